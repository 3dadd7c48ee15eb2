"""The paper's test bed: one ANYmal leg hopping on a vertical rail (``docs/hopper.md``)."""
