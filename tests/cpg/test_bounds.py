"""Bounded fields of the CPG vector V (``Parametrisation(bounds=...)``): a sigmoid transform
that keeps a parameter inside (low, high) whatever V becomes."""

import math

import pytest
import torch

from cpg_actor.cpg.parametrisation import Parametrisation
from cpg_actor.cpg.topology import Topology
from cpg_actor.robots.hopper.cpg import hopper_cpg

INITIAL = {"frequency": 2.0, "amplitude": (0.15, 0.3), "convergence": 20.0}


def bounded(**bounds):
    return Parametrisation(Topology.all_to_all(2), INITIAL, bounds=bounds, dtype=torch.float64)


def test_bounded_fields_start_at_their_initial_values_and_stay_inside_for_any_vector():
    p = bounded(amplitude=(0.0, (0.5, 0.7)), convergence=(2.0, 100.0))
    values = p.values()
    torch.testing.assert_close(values["amplitude"], torch.tensor([0.15, 0.3], dtype=torch.float64))
    torch.testing.assert_close(
        values["convergence"], torch.tensor([20.0, 20.0], dtype=torch.float64)
    )
    amplitude_index = p.indices("amplitude")
    with torch.no_grad():
        p.vector[amplitude_index] = torch.tensor([30.0, -30.0], dtype=torch.float64)
        p.vector[p.indices("convergence")] = torch.tensor([1e3, -1e3], dtype=torch.float64)
    values = p.values()
    assert 0.0 <= values["amplitude"][1] < 1e-9 and values["amplitude"][0] <= 0.5
    torch.testing.assert_close(values["amplitude"][0], torch.tensor(0.5, dtype=torch.float64))
    assert values["convergence"].tolist() == [100.0, 2.0]
    # the frequency keeps its exp transform
    assert p.values()["frequency"].tolist() == pytest.approx([2.0, 2.0])


def test_the_bounded_transform_is_low_plus_span_times_sigmoid():
    p = bounded(amplitude=(0.1, 0.9))
    k = int(p.indices("amplitude")[0])
    with torch.no_grad():
        p.vector[k] = 0.3
    expected = 0.1 + 0.8 / (1.0 + math.exp(-0.3))
    assert float(p.values()["amplitude"][0].detach()) == pytest.approx(expected, rel=1e-12)


def test_a_batch_of_vectors_gives_a_batch_of_parameters():
    cpg = hopper_cpg(0.01, bounds={"amplitude": (0.0, 0.7)}, dtype=torch.float64)
    p = cpg.parametrisation
    vectors = p.vector.detach() + torch.randn(4, p.num_parameters, dtype=torch.float64)
    batch = p.values(vectors)
    for row in range(4):
        with torch.no_grad():
            single = Parametrisation.values(p, vectors[row])
        for field, value in single.items():
            torch.testing.assert_close(batch[field][row], value)
    params = cpg.oscillator_parameters(0.0, vectors)
    assert params.frequency.shape == (4, 2) and params.phase_bias.shape == (4, 2, 2)


@pytest.mark.parametrize(
    ("bounds", "message"),
    [
        ({"amplitude": (0.5, 0.4)}, "low < high"),
        ({"amplitude": (-0.1, 0.4)}, "0 <= low"),
        ({"amplitude": (0.2, 0.4)}, "strictly inside"),
        ({"amplitude": (0.0, math.inf)}, "finite"),
        ({"speed": (0.0, 1.0)}, "unknown fields in bounds"),
        ({"amplitude": (0.0,)}, "must be \\(low, high\\)"),
    ],
)
def test_bad_bounds_are_refused_with_one_clear_line(bounds, message):
    with pytest.raises(ValueError, match=message):
        bounded(**bounds)
