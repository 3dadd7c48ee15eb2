"""The trainable vector V of the paper's eq. 3 and its map to nu, rho, a, W and Phi.

Eq. 3 writes every oscillator parameter as a function of one vector V in R^M (``A V``,
``W V``, ``Phi V``, ``C_nu(V, D)``, ``P(V, D)``). Here each entry of each parameter field is
either

* **trainable**: ``transform(sign * V[k])`` for an index ``k`` (entries that share ``k`` are
  tied: symmetric or shared parameters), or
* **frozen**: a fixed physical value that never changes.

Fields and their transforms (positivity is built in, so nu, rho and a stay positive):

=================== ======= ============ =========================================
field               shape   transform    meaning
=================== ======= ============ =========================================
``frequency``       (N,)    exp          c_nu0, intrinsic frequency at zero drive, Hz
``frequency_gain``  (N,)    exp          c_nu1, Hz per unit drive (>= 0)
``amplitude``       (N,)    exp          c_R0, intrinsic amplitude at zero drive
``amplitude_gain``  (N,)    exp          c_R1, amplitude per unit drive (>= 0)
``convergence``     (N,)    exp          a, amplitude convergence rate, 1/s
``coupling_weight`` (N, N)  identity     w_ij
``phase_bias``      (N, N)  identity     phi_ij, rad
=================== ======= ============ =========================================

With the drive law of Ijspeert et al. 2007, ``nu(d) = c_nu1 d + c_nu0`` and
``rho(d) = c_R1 d + c_R0``, and a drive ``d >= 0`` (checked), nu and rho are positive.
A gain of exactly 0 cannot be written as ``exp(v)``: freeze it (the default), or start it
above 0 to train it. Coupling entries outside the topology are always frozen at 0.

**Bounded fields** (beyond the paper). ``bounds={field: (low, high)}`` replaces a field's
transform by ``low + (high - low) sigmoid(V[k])``, so the value stays strictly inside
``(low, high)`` whatever the optimiser does to V: the CPG-Actor bounds the amplitude rho so
that the joint command stays inside the joint range, and the convergence rate a so that eq. 2
stays stable and the feedback's effect on the amplitude stays known. ``low`` and ``high`` are
scalars or have the field's shape.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import torch
from torch import Tensor, nn

from cpg_actor.cpg.hopf import OscillatorParameters
from cpg_actor.cpg.topology import Topology

POSITIVE_FIELDS = ("frequency", "frequency_gain", "amplitude", "amplitude_gain", "convergence")
MATRIX_FIELDS = ("coupling_weight", "phase_bias")
FIELDS = POSITIVE_FIELDS + MATRIX_FIELDS

# A tie: entries (field, index) that share one entry of V, each with a sign (+1 or -1).
Entry = tuple[str, tuple[int, ...], float]


def _field_shape(field: str, n: int) -> tuple[int, ...]:
    return (n, n) if field in MATRIX_FIELDS else (n,)


class Parametrisation(nn.Module):
    """Holds V (``self.vector``) and maps it to the oscillator parameters of eq. 1.

    Args:
        topology: the coupling graph (Lambda).
        initial: physical initial values per field; a scalar is broadcast to the field's shape.
            Missing fields default to 0 for gains, weights and phase biases; ``frequency``,
            ``amplitude`` and ``convergence`` are required.
        frozen: per field, ``True`` (freeze all entries) or a boolean mask of the field's shape.
            Gains are frozen by default; pass ``frozen={"frequency_gain": False}`` to train them.
        dtype: floating dtype of V and the buffers (default: torch's default dtype).
        ties: groups of entries that share one trainable value, each entry
            ``(field, index, sign)``; the sign may be -1 only for identity-transformed fields
            (e.g. ``phi_ji = -phi_ij``). The first entry's initial value is used; the others must
            agree with it.
    """

    def __init__(
        self,
        topology: Topology,
        initial: Mapping[str, float | Sequence | Tensor],
        frozen: Mapping[str, bool | Sequence | Tensor] | None = None,
        ties: Iterable[Sequence[Entry]] = (),
        dtype: torch.dtype | None = None,
        bounds: Mapping[str, tuple[float | Sequence | Tensor, float | Sequence | Tensor]]
        | None = None,
    ) -> None:
        super().__init__()
        self.topology = topology
        n = topology.num_oscillators
        unknown = set(initial) - set(FIELDS)
        if unknown:
            raise ValueError(f"unknown CPG parameter fields {sorted(unknown)}; accepted: {FIELDS}")
        for required in ("frequency", "amplitude", "convergence"):
            if required not in initial:
                raise ValueError(f"an initial value for '{required}' is required")
        frozen = {"frequency_gain": True, "amplitude_gain": True, **(frozen or {})}
        unknown = set(frozen) - set(FIELDS)
        if unknown:
            raise ValueError(f"unknown fields in frozen: {sorted(unknown)}; accepted: {FIELDS}")

        adjacency = topology.adjacency(torch.float64).bool()
        values: dict[str, Tensor] = {}
        masks: dict[str, Tensor] = {}
        for field in FIELDS:
            shape = _field_shape(field, n)
            value = torch.as_tensor(initial.get(field, 0.0), dtype=torch.float64)
            try:
                value = value.expand(shape).clone()
            except RuntimeError:
                raise ValueError(
                    f"'{field}' must be a scalar or have shape {shape}, got {tuple(value.shape)}"
                ) from None
            if not torch.isfinite(value).all():
                raise ValueError(f"'{field}' has non-finite initial values: {value.tolist()}")
            mask = torch.as_tensor(frozen.get(field, False), dtype=torch.bool)
            try:
                mask = mask.expand(shape).clone()
            except RuntimeError:
                raise ValueError(
                    f"frozen['{field}'] must be a bool or a mask of shape {shape}"
                ) from None
            if field in MATRIX_FIELDS:
                mask |= ~adjacency  # no coupling where Lambda is 0
                value = torch.where(adjacency, value, torch.zeros_like(value))
            values[field], masks[field] = value, mask
        self._check_positive(values, masks)
        lows, highs = self._bounds(bounds or {}, values, n)
        dtype = dtype or torch.get_default_dtype()
        # a bounded entry's V is the logit of its place in (low, low + span) as the transform
        # will compute it: with low and span rounded to V's dtype, so that the physical values
        # of a V (e.g. a gait file) give that V back
        spans = {f: (highs[f] - lows[f]).to(dtype).double() for f in FIELDS}
        lows = {f: lows[f].to(dtype).double() for f in FIELDS}

        # Assign an index of V to every trainable entry; ties share one index.
        index = {f: torch.full(_field_shape(f, n), -1, dtype=torch.long) for f in FIELDS}
        sign = {f: torch.ones(_field_shape(f, n), dtype=torch.float64) for f in FIELDS}
        raw: list[float] = []
        for group in ties:
            group = list(group)
            if not group:
                continue
            k = len(raw)
            first_field, first_idx, first_sign = self._check_entry(group[0], n, masks)
            raw.append(
                self._to_raw(
                    first_field,
                    first_sign * values[first_field][first_idx],
                    lows[first_field][first_idx],
                    spans[first_field][first_idx],
                )
            )
            for entry in group:
                field, idx, s = self._check_entry(entry, n, masks)
                if index[field][idx] >= 0:
                    raise ValueError(f"entry {field}{list(idx)} appears in more than one tie")
                expected = s * first_sign * values[first_field][first_idx]
                if not torch.isclose(values[field][idx], expected, rtol=1e-6, atol=1e-9):
                    raise ValueError(
                        f"tied entries disagree: {field}{list(idx)} = {values[field][idx].item()}"
                        f" but the tie implies {expected.item()}"
                    )
                index[field][idx] = k
                sign[field][idx] = s
        for field in FIELDS:
            for idx in zip(*torch.nonzero(~masks[field], as_tuple=True), strict=True):
                idx = tuple(int(i) for i in idx)
                if index[field][idx] < 0:
                    index[field][idx] = len(raw)
                    raw.append(
                        self._to_raw(field, values[field][idx], lows[field][idx], spans[field][idx])
                    )

        # Created in ``dtype`` (default: torch's default dtype, float32 unless changed). Pass
        # dtype=torch.float64 to keep the initial values exact in float64: .double() afterwards
        # converts values already rounded to float32.
        self.vector = nn.Parameter(torch.tensor(raw, dtype=dtype))
        # All fields flattened into one row, so that the map V -> parameters is one gather,
        # one exp and one select for every field at once (a few operators per CPG step).
        self.shapes = {field: _field_shape(field, n) for field in FIELDS}
        names = ("index", "sign", "fixed", "trainable", "positive", "bounded", "low", "span")
        flat = {name: [] for name in names}
        for field in FIELDS:
            flat["index"].append(index[field].flatten().clamp(min=0))
            flat["trainable"].append(index[field].flatten() >= 0)
            flat["sign"].append(sign[field].flatten())
            flat["fixed"].append(values[field].flatten())
            bounded = torch.isfinite(lows[field]).flatten()
            flat["bounded"].append(bounded)
            flat["positive"].append(
                torch.full((index[field].numel(),), field in POSITIVE_FIELDS, dtype=torch.bool)
                & ~bounded
            )
            flat["low"].append(torch.where(bounded, lows[field].flatten(), 0.0))
            flat["span"].append(torch.where(bounded, spans[field].flatten(), 0.0))
        for name, parts in flat.items():
            value = torch.cat(parts)
            if value.is_floating_point():
                value = value.to(dtype)
            self.register_buffer(f"flat_{name}", value, persistent=False)
        self.register_buffer("coupling", adjacency.to(dtype), persistent=False)

    # -- construction helpers -------------------------------------------------------------
    @staticmethod
    def _to_raw(field: str, value: Tensor, low: Tensor, span: Tensor) -> float:
        if torch.isfinite(low):  # bounded: the logit of the value's place in (low, low + span)
            unit = (float(value) - float(low)) / float(span)
            return math.log(unit / (1.0 - unit))
        return math.log(float(value)) if field in POSITIVE_FIELDS else float(value)

    @staticmethod
    def _bounds(
        bounds: Mapping, values: dict[str, Tensor], n: int
    ) -> tuple[dict[str, Tensor], dict[str, Tensor]]:
        """Per field, the lower and upper bound of each entry (-inf, inf: unbounded), checked:
        low < high, low >= 0 for positive fields, the initial value strictly inside."""
        unknown = set(bounds) - set(FIELDS)
        if unknown:
            raise ValueError(f"unknown fields in bounds: {sorted(unknown)}; accepted: {FIELDS}")
        lows, highs = {}, {}
        for field in FIELDS:
            shape = _field_shape(field, n)
            if field not in bounds:
                lows[field] = torch.full(shape, -math.inf, dtype=torch.float64)
                highs[field] = torch.full(shape, math.inf, dtype=torch.float64)
                continue
            try:
                low, high = bounds[field]
                low = torch.as_tensor(low, dtype=torch.float64).expand(shape).clone()
                high = torch.as_tensor(high, dtype=torch.float64).expand(shape).clone()
            except (TypeError, ValueError, RuntimeError):
                raise ValueError(
                    f"bounds['{field}'] must be (low, high), each a scalar or of shape {shape}"
                ) from None
            if not (torch.isfinite(low).all() and torch.isfinite(high).all()):
                raise ValueError(f"bounds['{field}'] must be finite, got {low.tolist()}, "
                                 f"{high.tolist()}")  # fmt: skip
            if not (low < high).all() or (field in POSITIVE_FIELDS and (low < 0).any()):
                need = "0 <= low < high" if field in POSITIVE_FIELDS else "low < high"
                raise ValueError(f"bounds['{field}'] need {need}, got {low.tolist()}, "
                                 f"{high.tolist()}")  # fmt: skip
            value = values[field]
            if not ((low < value) & (value < high)).all():
                raise ValueError(
                    f"the initial '{field}' {value.tolist()} must lie strictly inside its bounds "
                    f"({low.tolist()}, {high.tolist()})"
                )
            lows[field], highs[field] = low, high
        return lows, highs

    @staticmethod
    def _check_positive(values: dict[str, Tensor], masks: dict[str, Tensor]) -> None:
        for field in POSITIVE_FIELDS:
            value, mask = values[field], masks[field]
            strictly = field in ("frequency", "amplitude", "convergence")
            bad = (value <= 0) if strictly else ((value < 0) | ((value <= 0) & ~mask))
            if bad.any():
                need = "> 0" if strictly else ">= 0 (and > 0 when trainable: freeze a zero gain)"
                raise ValueError(f"'{field}' must be {need}, got {value.tolist()}")

    @staticmethod
    def _check_entry(entry: Entry, n: int, masks: dict[str, Tensor]) -> Entry:
        try:
            field, idx, s = entry
        except (TypeError, ValueError):
            raise ValueError(f"a tie entry must be (field, index, sign), got {entry!r}") from None
        if field not in FIELDS:
            raise ValueError(f"unknown field '{field}' in tie; accepted: {FIELDS}")
        idx = tuple(int(i) for i in (idx if isinstance(idx, Sequence) else (idx,)))
        shape = _field_shape(field, n)
        if len(idx) != len(shape) or any(not 0 <= i < d for i, d in zip(idx, shape, strict=True)):
            raise ValueError(f"index {list(idx)} is out of range for '{field}' of shape {shape}")
        if s not in (1, -1, 1.0, -1.0):
            raise ValueError(f"tie sign must be +1 or -1, got {s!r}")
        if s < 0 and field in POSITIVE_FIELDS:
            raise ValueError(f"'{field}' is positive; a tie with sign -1 is not possible")
        if masks[field][idx]:
            raise ValueError(f"{field}{list(idx)} is frozen (or outside the topology); cannot tie")
        return field, idx, float(s)

    # -- the map V -> parameters ------------------------------------------------------------
    @property
    def num_parameters(self) -> int:
        """M, the number of trainable CPG parameters."""
        return self.vector.numel()

    def field(self, name: str) -> Tensor:
        """The physical value of one field, differentiable in V."""
        if name not in FIELDS:
            raise ValueError(f"unknown field '{name}'; accepted: {FIELDS}")
        return self.values()[name]

    def indices(self, name: str) -> Tensor:
        """The entry of V behind each entry of field ``name`` (its shape), -1 where frozen."""
        if name not in FIELDS:
            raise ValueError(f"unknown field '{name}'; accepted: {FIELDS}")
        start = sum(math.prod(self.shapes[field]) for field in FIELDS[: FIELDS.index(name)])
        rows = slice(start, start + math.prod(self.shapes[name]))
        index = torch.where(self.flat_trainable[rows], self.flat_index[rows], -1)
        return index.reshape(self.shapes[name])

    def values(self, vector: Tensor | None = None) -> dict[str, Tensor]:
        """All fields, physical values, differentiable in V (one gather for all of them).

        ``vector``: a V to use instead of :attr:`vector`, ``(M,)`` or a batch ``(B, M)`` (one
        V per row: the fields then get a leading batch dimension)."""
        vector = self.vector if vector is None else vector
        batch = tuple(vector.shape[:-1])
        if vector.shape[-1] == 0:
            flat = self.flat_fixed.to(vector.dtype).expand(*batch, -1)
        else:
            raw = self.flat_sign * vector[..., self.flat_index]
            # exp and sigmoid only where the field uses them (exp of a large weight would be
            # inf, and where() would turn its zero gradient into NaN)
            zeros = torch.zeros_like(raw)
            positive = torch.exp(torch.where(self.flat_positive, raw, zeros))
            bounded = self.flat_low + self.flat_span * torch.sigmoid(raw)
            value = torch.where(self.flat_positive, positive, raw)
            value = torch.where(self.flat_bounded, bounded, value)
            flat = torch.where(self.flat_trainable, value, self.flat_fixed.to(value.dtype))
        sizes = [math.prod(self.shapes[field]) for field in FIELDS]
        return {
            field: part.reshape(*batch, *self.shapes[field])
            for field, part in zip(FIELDS, flat.split(sizes, dim=-1), strict=True)
        }

    def oscillator_parameters(
        self, drive: Tensor | float = 0.0, vector: Tensor | None = None
    ) -> OscillatorParameters:
        """nu(d) = c_nu1 d + c_nu0, rho(d) = c_R1 d + c_R0 (Ijspeert et al. 2007), a, W, Phi.

        ``drive`` is a scalar, ``(N,)`` or ``(B, N)`` and must be >= 0; ``vector`` as in
        :meth:`values`.
        """
        values = self.values(vector)
        if isinstance(drive, (int, float)) and drive == 0:  # the hopper: no drive term to add
            frequency, amplitude = values["frequency"], values["amplitude"]
        else:
            frequency = values["frequency_gain"] * drive + values["frequency"]
            amplitude = values["amplitude_gain"] * drive + values["amplitude"]
        return OscillatorParameters(
            frequency=frequency,
            amplitude=amplitude,
            convergence=values["convergence"],
            coupling_weight=values["coupling_weight"],
            phase_bias=values["phase_bias"],
        )


def symmetric_coupling_ties(
    topology: Topology, frozen: Mapping[str, bool | Sequence | Tensor] | None = None
) -> list[list[Entry]]:
    """Ties making w_ij = w_ji and phi_ji = -phi_ij for every pair coupled both ways.

    A pair whose two entries are both ``frozen`` (same format as :class:`Parametrisation`) is
    left out: frozen entries keep their fixed values and cannot be tied. A pair with only one
    frozen side is a contradiction and raises ``ValueError``.
    """
    n = topology.num_oscillators
    frozen_masks: dict[str, Tensor] = {}
    for field in MATRIX_FIELDS:
        try:
            mask = torch.as_tensor((frozen or {}).get(field, False), dtype=torch.bool)
            frozen_masks[field] = mask.expand(n, n)
        except (RuntimeError, TypeError, ValueError):
            frozen_masks[field] = torch.zeros(n, n, dtype=torch.bool)  # Parametrisation complains
    edges = set(topology.edges)
    ties: list[list[Entry]] = []
    for i, j in sorted(edges):
        if i < j and (j, i) in edges:
            for field, sign in (("coupling_weight", 1.0), ("phase_bias", -1.0)):
                frozen_ij, frozen_ji = (
                    bool(frozen_masks[field][i, j]),
                    bool(frozen_masks[field][j, i]),
                )
                if frozen_ij and frozen_ji:
                    continue
                if frozen_ij or frozen_ji:
                    raise ValueError(
                        f"{field}[{i}, {j}] and {field}[{j}, {i}] are tied by symmetric coupling "
                        "but only one of them is frozen: freeze both, or disable symmetric coupling"
                    )
                ties.append([(field, (i, j), 1.0), (field, (j, i), sign)])
    return ties
