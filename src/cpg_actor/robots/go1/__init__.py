"""The Unitree Go1 quadruped (floating base, four legs of abduction, hip and knee) walking at a
commanded velocity, on MuJoCo and MJX: the quadruped machinery of ``robots/common/quadruped``
on the Go1's description (``docs/go1.md``)."""
