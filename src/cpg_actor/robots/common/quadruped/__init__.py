"""The machinery every quadruped shares: the velocity task's config
(:class:`~cpg_actor.robots.common.quadruped.config.QuadrupedConfig`), its env on MuJoCo
(``vector``), on MJX (``mjx``) and as one Gymnasium env (``env``), the gait CPGs (``gaits``), the
foot-space pattern (``foot_space``), the MJCF document (``mjcf``) and the registry entry
(``plugin``). A robot's folder gives its description, a
:class:`~cpg_actor.robots.common.quadruped.model.QuadrupedModel` (its facts and its MJCF), its
:class:`~cpg_actor.robots.common.quadruped.gaits.GaitCPGs`, and binds these to it in a few
lines (``robots/anymal``, ``robots/go1``)."""
