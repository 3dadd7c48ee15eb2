"""The map V -> (nu, rho, a, W, Phi) of eq. 3: ties, frozen entries, positivity, drive law."""

from __future__ import annotations

import math

import pytest
import torch

from cpg_actor.cpg import CPGNetwork, Parametrisation, Topology
from cpg_actor.robots.hopper.cpg import hopper_cpg

BASE = {"frequency": (1.0, 2.0), "amplitude": (0.3, 0.6), "convergence": (10.0, 20.0)}


def _step(module: torch.nn.Module, loss_fn, lr: float = 0.1) -> None:
    optimizer = torch.optim.SGD(module.parameters(), lr=lr)
    optimizer.zero_grad()
    loss_fn().backward()
    optimizer.step()


def test_hopper_has_eight_parameters_with_symmetric_w_and_antisymmetric_phi():
    p = hopper_cpg(0.01).parametrisation
    assert p.num_parameters == 8  # nu, rho, a per oscillator + one w + one phi
    assert p.indices("coupling_weight")[0, 1] == p.indices("coupling_weight")[1, 0]
    assert p.indices("phase_bias")[0, 1] == p.indices("phase_bias")[1, 0]
    phi = p.field("phase_bias")
    assert phi[0, 1] == -phi[1, 0] != 0


def test_ties_really_share_one_value_through_training():
    topology = Topology.all_to_all(2)
    initial = {**BASE, "frequency": 1.5, "coupling_weight": 2.0, "phase_bias": 0.0}
    initial["phase_bias"] = torch.tensor([[0.0, 0.4], [-0.4, 0.0]])
    ties = [[("frequency", (0,), 1.0), ("frequency", (1,), 1.0)]]
    p = Parametrisation(topology, initial, ties=ties + _symmetric(topology))
    assert p.num_parameters == 1 + 2 + 2 + 1 + 1

    # a loss on ONE side of each tie moves both sides together
    _step(p, lambda: p.field("coupling_weight")[0, 1] + 3 * p.field("phase_bias")[1, 0])
    w, phi = p.field("coupling_weight"), p.field("phase_bias")
    assert w[0, 1] != 2.0 and w[0, 1] == w[1, 0]
    assert phi[0, 1] != 0.4 and phi[1, 0] == -phi[0, 1]
    assert w[0, 0] == 0 and phi[1, 1] == 0  # the diagonal is outside the topology

    # both tied frequencies receive the gradient of both uses: d(nu_0 + nu_1)/dV = 2 nu
    p.zero_grad()
    p.field("frequency").sum().backward()
    k = int(p.indices("frequency")[0])
    assert p.vector.grad[k].item() == pytest.approx(2 * 1.5)
    _step(p, lambda: p.field("frequency")[1])
    nu = p.field("frequency")
    assert nu[0] == nu[1] and nu[0] != 1.5


def _symmetric(topology):
    from cpg_actor.cpg import symmetric_coupling_ties

    return symmetric_coupling_ties(topology)


def test_frozen_entries_get_no_gradient_and_stay_fixed():
    topology = Topology.chain(3)
    initial = {
        "frequency": 1.0,
        "amplitude": 0.5,
        "convergence": (10.0, 20.0, 30.0),
        "coupling_weight": 1.0,
        "phase_bias": torch.tensor([[0, 0.3, 0], [-0.3, 0, 0.2], [0, -0.2, 0]]),
    }
    frozen = {"convergence": (True, False, True), "amplitude": True}
    p = Parametrisation(topology, initial, frozen=frozen, ties=_symmetric(topology))
    assert p.num_parameters == 3 + 1 + 2 + 2  # nu x3, one a, two w, two phi
    assert (p.indices("convergence") >= 0).tolist() == [False, True, False]

    # a loss that depends only on frozen entries gives V a zero gradient
    p.field("convergence")[[0, 2]].sum().add(p.field("amplitude").sum()).backward()
    assert p.vector.grad is None or torch.count_nonzero(p.vector.grad) == 0

    before = {name: value.detach().clone() for name, value in p.values().items()}

    def everything():
        return sum((v**2).sum() for v in p.values().values())

    for _ in range(3):
        _step(p, everything, lr=0.01)
    after = p.values()
    assert torch.equal(after["amplitude"], before["amplitude"])
    assert after["convergence"][0] == before["convergence"][0] == 10.0
    assert after["convergence"][2] == before["convergence"][2] == 30.0
    assert after["convergence"][1] != before["convergence"][1]  # the trainable one moved
    assert not torch.equal(after["frequency"], before["frequency"])
    # coupling outside the topology (0 <-> 2, the diagonal) stays exactly 0
    assert after["coupling_weight"][0, 2] == 0 and after["coupling_weight"][2, 0] == 0
    assert after["coupling_weight"][1, 2] != 1.0


def test_frozen_field_of_a_network_is_not_in_v_and_unchanged_by_training():
    net = hopper_cpg(0.01, frozen={"phase_bias": True})
    assert net.parametrisation.num_parameters == 7
    state = net.initial_state(4, amplitude=0.2)
    _step(net, lambda: net(state)[0].position.pow(2).sum() + net(state)[1].phase.sum())
    phi = net.parametrisation.field("phase_bias")
    assert phi[0, 1].item() == pytest.approx(math.pi) and phi[1, 0].item() == pytest.approx(
        -math.pi
    )


@pytest.mark.parametrize(("dtype", "bound"), [(torch.float32, 80.0), (torch.float64, 700.0)])
def test_positive_fields_stay_positive_for_any_vector(dtype, bound):
    initial = {**BASE, "frequency_gain": 0.2, "amplitude_gain": 0.1}
    frozen = {"frequency_gain": False, "amplitude_gain": False}
    p = Parametrisation(Topology.all_to_all(2), initial, frozen=frozen).to(dtype)
    g = torch.Generator().manual_seed(0)
    with torch.no_grad():
        for _ in range(50):
            p.vector.copy_((torch.rand(p.num_parameters, generator=g) * 2 - 1) * bound)
            for name in (
                "frequency",
                "frequency_gain",
                "amplitude",
                "amplitude_gain",
                "convergence",
            ):
                assert (p.field(name) > 0).all(), (name, p.vector)
            params = p.oscillator_parameters(torch.rand(2, generator=g).to(dtype) * 3)
            assert (params.frequency > 0).all() and (params.amplitude > 0).all()
            assert (params.convergence > 0).all()
        # the extreme ends of the range too
        for value in (-bound, bound):
            p.vector.fill_(value)
            assert all((p.field(n) > 0).all() for n in ("frequency", "amplitude", "convergence"))


def test_drive_law_nu_is_c1_d_plus_c0():
    c0, c1 = torch.tensor([1.0, 2.0]), torch.tensor([0.5, 0.25])
    r0, r1 = torch.tensor([0.3, 0.6]), torch.tensor([0.1, 0.2])
    initial = {**BASE, "frequency": c0, "frequency_gain": c1, "amplitude": r0, "amplitude_gain": r1}
    frozen = {"frequency_gain": False, "amplitude_gain": False}
    net = CPGNetwork(Topology.all_to_all(2), 0.01, initial, frozen=frozen).double()
    c0, c1, r0, r1 = (t.double() for t in (c0, c1, r0, r1))
    drives = [0.0, 1.7, torch.tensor([0.5, 2.0]), torch.tensor([[0.0, 1.0], [3.0, 0.5]])]
    for drive in drives:
        params = net.oscillator_parameters(torch.as_tensor(drive, dtype=torch.float64))
        torch.testing.assert_close(params.frequency, c1 * drive + c0)
        torch.testing.assert_close(params.amplitude, r1 * drive + r0)
        torch.testing.assert_close(params.convergence, torch.tensor([10.0, 20.0]).double())
    # by default the gains are frozen at 0: the drive changes nothing
    default = CPGNetwork(Topology.all_to_all(2), 0.01, BASE)
    assert default.parametrisation.num_parameters == 6 + 2
    torch.testing.assert_close(
        default.oscillator_parameters(5.0).frequency, torch.tensor([1.0, 2.0])
    )


def test_initial_values_are_reproduced_exactly():
    net = hopper_cpg(0.01)
    values = net.parametrisation.values()
    torch.testing.assert_close(values["frequency"], torch.tensor([2.0, 2.0]))
    torch.testing.assert_close(values["amplitude"], torch.tensor([0.15, 0.3]))
    torch.testing.assert_close(values["convergence"], torch.tensor([20.0, 20.0]))
    torch.testing.assert_close(values["coupling_weight"], torch.tensor([[0.0, 10.0], [10.0, 0.0]]))
    torch.testing.assert_close(
        values["phase_bias"], torch.tensor([[0.0, math.pi], [-math.pi, 0.0]])
    )
