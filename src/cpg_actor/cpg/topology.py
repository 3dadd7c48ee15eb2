"""Which oscillator couples to which: the Lambda of the paper's eq. 3."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import torch


@dataclass(frozen=True)
class Topology:
    """A directed coupling graph over ``num_oscillators`` oscillators.

    ``edges`` holds pairs ``(i, j)``: oscillator ``i`` receives the coupling term of ``j``
    (``Lambda_ij = 1`` in eq. 1/3). ``names`` label the oscillators (e.g. the joints they drive).
    """

    num_oscillators: int
    edges: tuple[tuple[int, int], ...] = ()
    names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = self.num_oscillators
        if not isinstance(n, int) or n < 1:
            raise ValueError(f"num_oscillators must be a positive integer, got {n!r}")
        edges = tuple((int(i), int(j)) for i, j in self.edges)
        for i, j in edges:
            if not (0 <= i < n and 0 <= j < n):
                raise ValueError(f"edge ({i}, {j}) is outside 0..{n - 1}")
            if i == j:
                raise ValueError(f"edge ({i}, {j}) couples an oscillator to itself; not allowed")
        if len(set(edges)) != len(edges):
            raise ValueError(f"duplicate edges in {edges}")
        names = tuple(self.names) or tuple(f"osc{i}" for i in range(n))
        if len(names) != n:
            raise ValueError(f"{len(names)} names given for {n} oscillators")
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "names", names)

    @classmethod
    def all_to_all(cls, num_oscillators: int, names: Sequence[str] = ()) -> Topology:
        """Every oscillator receives every other one's coupling."""
        n = num_oscillators
        edges = [(i, j) for i in range(n) for j in range(n) if i != j]
        return cls(n, tuple(edges), tuple(names))

    @classmethod
    def chain(cls, num_oscillators: int, names: Iterable[str] = ()) -> Topology:
        """Nearest neighbours, both directions (a salamander-like chain)."""
        n = num_oscillators
        edges = [(i, i + 1) for i in range(n - 1)] + [(i + 1, i) for i in range(n - 1)]
        return cls(n, tuple(edges), tuple(names))

    def adjacency(self, dtype: torch.dtype = torch.float32) -> torch.Tensor:
        """Lambda as an ``(N, N)`` 0/1 matrix, entry ``[i, j]`` = 1 when ``i`` receives ``j``."""
        matrix = torch.zeros(self.num_oscillators, self.num_oscillators, dtype=dtype)
        for i, j in self.edges:
            matrix[i, j] = 1.0
        return matrix
