"""ANYmal B's leg: the link facts and planar kinematics shared by the hopper and ANYmal B."""
