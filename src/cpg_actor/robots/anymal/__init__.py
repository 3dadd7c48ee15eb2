"""Beyond the paper: the ANYmal B quadruped (floating base, four legs of HAA, HFE and KFE)
walking at a commanded velocity, on MuJoCo and MJX (``docs/quadruped.md``)."""
