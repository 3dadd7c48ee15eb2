"""The machinery every quadruped shares: the velocity task's config
(:class:`~cpg_actor.robots.common.quadruped.config.QuadrupedConfig`), its env on MuJoCo
(``vector``), on MJX (``mjx``) and as one Gymnasium env (``env``), the gait CPGs (``gaits``) and
the foot-space pattern (``foot_space``). A robot's folder gives a
:class:`~cpg_actor.robots.common.quadruped.model.QuadrupedModel` (its facts and its MJCF) and
binds these to it in a few lines (``robots/anymal``, ``robots/go1``)."""
