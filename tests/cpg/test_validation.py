"""Bad input raises ValueError with a message that says what is wrong."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from cpg_actor.cpg import CPGNetwork, CPGState, Parametrisation, Topology
from cpg_actor.robots.hopper.cpg import hopper_cpg

NAN, INF = float("nan"), float("inf")
BASE = {"frequency": 1.0, "amplitude": 1.0, "convergence": 10.0}
PAIR = Topology.all_to_all(2)


@pytest.fixture
def net() -> CPGNetwork:
    return hopper_cpg(0.01)


@pytest.fixture
def state(net) -> CPGState:
    return net.initial_state(3, amplitude=0.1)


def _with(state: CPGState, **fields) -> CPGState:
    return state._replace(**fields)


@pytest.mark.parametrize(
    ("make_state", "message"),
    [
        (lambda s: tuple(s), "state must be a CPGState, got tuple"),
        (lambda s: CPGState(*(f[0] for f in s)), r"shape \(B, 2\), got \(2,\)"),
        (lambda s: CPGState(*(torch.zeros(3, 3) for _ in s)), r"shape \(B, 2\), got \(3, 3\)"),
        (lambda s: _with(s, amplitude=torch.zeros(4, 2)), r"state.amplitude has shape \(4, 2\)"),
        (lambda s: _with(s, amplitude_velocity=[0.0, 0.0]), "must be a torch.Tensor, got list"),
        (lambda s: _with(s, phase=s.phase.double()), "state.phase has dtype torch.float64"),
    ],
)
def test_wrong_state_raises(net, state, make_state, message):
    with pytest.raises(ValueError, match=message):
        net(make_state(state))


@pytest.mark.parametrize("field", CPGState._fields)
@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_non_finite_state_raises(net, state, field, bad):
    broken = getattr(state, field).clone()
    broken[1, 0] = bad
    with pytest.raises(ValueError, match=f"state.{field} contains NaN or inf"):
        net(_with(state, **{field: broken}))


@pytest.mark.parametrize("name", ["xi", "kappa", "drive"])
@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_non_finite_feedback_and_drive_raise(net, state, name, bad):
    with pytest.raises(ValueError, match=f"{name} is {bad}; a finite number is required"):
        net(state, **{name: bad})
    tensor = torch.zeros(3, 2)
    tensor[2, 1] = bad
    with pytest.raises(ValueError, match=f"{name} contains NaN or inf"):
        net(state, **{name: tensor})


@pytest.mark.parametrize("name", ["xi", "kappa", "drive"])
def test_feedback_of_wrong_shape_type_or_dtype_raises(net, state, name):
    with pytest.raises(
        ValueError, match=rf"{name} must be a scalar, \(2,\) or \(3, 2\), got \(3,\)"
    ):
        net(state, **{name: torch.zeros(3)})
    with pytest.raises(ValueError, match=f"{name} must be a real number or a torch.Tensor"):
        net(state, **{name: np.zeros(2)})
    with pytest.raises(ValueError, match=f"{name} has dtype torch.float64"):
        net(state, **{name: torch.zeros(2, dtype=torch.float64)})


def test_accepted_feedback_forms(net, state):
    for value in (0.5, 1, torch.tensor(0.5), torch.full((2,), 0.5), torch.full((3, 2), 0.5)):
        net(state, drive=value, xi=value, kappa=value)


@pytest.mark.parametrize("drive", [-1.0, torch.tensor([0.5, -0.1])])
def test_negative_drive_raises(net, state, drive):
    with pytest.raises(ValueError, match="drive must be >= 0"):
        net(state, drive=drive)


@pytest.mark.parametrize("dt", [0.0, -0.01, NAN, INF, "0.01", None, True, torch.tensor(0.01)])
def test_non_positive_or_non_numeric_dt_raises(dt):
    with pytest.raises(ValueError, match="dt must be a positive finite number of seconds"):
        hopper_cpg(dt)


def test_numpy_scalar_dt_is_accepted():
    assert hopper_cpg(np.float32(0.01)).dt == pytest.approx(0.01)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"initial": {**BASE, "freq": 1.0}}, r"unknown CPG parameter fields \['freq'\]"),
        ({"initial": BASE, "frozen": {"ampl": True}}, r"unknown fields in frozen: \['ampl'\]"),
        ({"initial": {"frequency": 1.0, "amplitude": 1.0}}, "'convergence' is required"),
        ({"initial": {**BASE, "frequency": -1.0}}, "'frequency' must be > 0"),
        ({"initial": {**BASE, "amplitude": 0.0}}, "'amplitude' must be > 0"),
        ({"initial": {**BASE, "convergence": NAN}}, "'convergence' has non-finite"),
        ({"initial": {**BASE, "frequency": (1.0, 2.0, 3.0)}}, r"shape \(2,\), got \(3,\)"),
        ({"initial": BASE, "frozen": {"amplitude": (True,) * 3}}, r"mask of shape \(2,\)"),
        (
            {"initial": {**BASE, "frequency_gain": 0.0}, "frozen": {"frequency_gain": False}},
            "freeze a zero gain",
        ),
    ],
)
def test_bad_parametrisation_raises(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Parametrisation(PAIR, **kwargs)


def test_unknown_field_lookup_raises(net):
    with pytest.raises(ValueError, match="unknown field 'nu'"):
        net.parametrisation.field("nu")


@pytest.mark.parametrize(
    ("ties", "message"),
    [
        ([[("nu", (0,), 1.0)]], "unknown field 'nu' in tie"),
        ([[("frequency", (2,), 1.0)]], r"index \[2\] is out of range for 'frequency'"),
        ([[("coupling_weight", (0,), 1.0)]], r"out of range for 'coupling_weight'"),
        ([[("frequency", (0,), 0.5)]], "tie sign must be \\+1 or -1, got 0.5"),
        ([[("frequency", (0,), 1), ("frequency", (1,), -1)]], "a tie with sign -1 is not possible"),
        ([["frequency"]], "a tie entry must be \\(field, index, sign\\)"),
        ([[("frequency", (0,), 1), ("frequency", (0,), 1)]], "appears in more than one tie"),
        (
            [[("amplitude", (0,), 1), ("amplitude", (1,), 1)], [("amplitude", (1,), 1)]],
            "appears in more than one tie",
        ),
        (
            [[("coupling_weight", (0, 1), 1), ("coupling_weight", (1, 0), 1)]],
            "appears in more than one tie",  # already tied by symmetric coupling
        ),
        ([[("convergence", (0,), 1)]], r"convergence\[0\] is frozen"),
    ],
)
def test_bad_ties_raise(ties, message):
    with pytest.raises(ValueError, match=message):
        CPGNetwork(PAIR, 0.01, BASE, frozen={"convergence": (True, False)}, ties=ties)


def test_tied_entries_with_different_initial_values_raise():
    initial = {**BASE, "frequency": (1.0, 2.0)}
    with pytest.raises(ValueError, match=r"tied entries disagree: frequency\[1\] = 2.0"):
        CPGNetwork(PAIR, 0.01, initial, ties=[[("frequency", (0,), 1), ("frequency", (1,), 1)]])
    with pytest.raises(ValueError, match=r"phase_bias\[1, 0\] = 1.0 but the tie implies -1.0"):
        CPGNetwork(PAIR, 0.01, {**BASE, "phase_bias": 1.0})  # symmetric ties need phi_ji = -phi_ij


def test_tie_outside_the_topology_raises():
    with pytest.raises(ValueError, match="outside the topology"):
        CPGNetwork(Topology(2), 0.01, BASE, ties=[[("coupling_weight", (0, 1), 1.0)]])


def test_half_frozen_symmetric_pair_raises():
    frozen = {"phase_bias": [[True, True], [False, False]]}
    with pytest.raises(ValueError, match="only one of them is frozen"):
        hopper_cpg(0.01, frozen=frozen)


@pytest.mark.parametrize("shape", [(5,), (2, 4, 2), (3, 2), (4, 2), (3, 2, 5)])
def test_from_tensor_with_wrong_shape_raises(shape):
    with pytest.raises(ValueError, match=r"must have shape \(\.\.\., 5, N\)"):
        CPGState.from_tensor(torch.zeros(shape))


def test_bad_topology_and_initial_phase_raise():
    with pytest.raises(ValueError, match="positive integer"):
        Topology(0)
    with pytest.raises(ValueError, match="couples an oscillator to itself"):
        Topology(2, ((0, 0),))
    with pytest.raises(ValueError, match=r"edge \(0, 2\) is outside 0..1"):
        Topology(2, ((0, 2),))
    with pytest.raises(ValueError, match="initial_phase must be a scalar or have 2 entries"):
        CPGNetwork(PAIR, 0.01, BASE, initial_phase=(0.0, 1.0, math.pi))


def test_validation_can_be_switched_off(state):
    fast = hopper_cpg(0.01, check_inputs=False)
    out, _ = fast(_with(state, phase=torch.full((3, 2), NAN)))
    assert torch.isnan(out.position).all()
