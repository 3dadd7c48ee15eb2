"""Many seeds in one process (cpg_actor.training.many_seeds): one env stepped for K runs."""

import pytest
import torch
from tests.tiny import tiny_config

from cpg_actor.training.many_seeds import SeedGroup
from cpg_actor.training.runner import Runner


def parameters(runner) -> torch.Tensor:
    return torch.cat([p.detach().flatten().clone() for p in runner.agent.parameters()])


def group_parameters(seeds, agent="cpg-actor", **fields) -> list[torch.Tensor]:
    group = SeedGroup(tiny_config(agent, **fields), seeds)
    try:
        group.learn()
        return [parameters(runner) for runner in group.runners]
    finally:
        group.close()


def test_one_seed_group_trains_as_a_run_of_its_own():
    """A group of one seed is the seed's run, number for number: the slice, the lock-step
    rollout and the split of the iteration change nothing."""
    runner = Runner(tiny_config("cpg-actor", seed=3), tensorboard=False)
    try:
        runner.learn()
        alone = parameters(runner)
    finally:
        runner.close()
    (grouped,) = group_parameters([3], seed=3)
    torch.testing.assert_close(grouped, alone, rtol=0, atol=0)


@pytest.mark.parametrize("agent", ["cpg-actor", "mlp"])
def test_seeds_of_a_group_are_runs_of_their_own_and_reproducible(agent):
    first = group_parameters([0, 1], agent)
    again = group_parameters([0, 1], agent)
    for a, b in zip(first, again, strict=True):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
    assert not torch.equal(first[0], first[1])  # each seed its own initialisation and data


def test_each_seed_logs_in_its_own_folder(tmp_path):
    group = SeedGroup(tiny_config("mlp"), [5, 6], run_dir=tmp_path)
    try:
        group.learn()
    finally:
        group.close()
    for seed in (5, 6):
        rows = (tmp_path / f"seed-{seed}" / "metrics.jsonl").read_text().splitlines()
        assert len(rows) == 2  # one row per iteration
        assert (tmp_path / f"seed-{seed}" / "checkpoints" / "last.pt").exists()


def test_a_group_refuses_what_it_cannot_run():
    with pytest.raises(ValueError, match="distinct seeds"):
        SeedGroup(tiny_config("mlp"), [1, 1])
    with pytest.raises(ValueError, match="warm start"):
        SeedGroup(tiny_config("mlp-warm"), [1, 2])
