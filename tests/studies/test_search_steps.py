"""A start gait's search charged to the runs that start from it (``TrainConfig.search_steps``,
``cpg-actor reproduce --count-search-steps``)."""

import json

import pytest

from cpg_actor.agents.start_gait import search_steps
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.runner import Runner
from cpg_actor_studies.reproduction.plan import ReproduceSettings, build_tasks, resolve_config
from tiny import tiny_config


def test_a_run_that_counts_its_search_trains_the_rest_and_counts_from_the_search(tmp_path):
    config = tiny_config("cpg-actor", iterations=3)  # 3 x 16 = 48 steps
    config.search_steps = 20
    assert config.num_iterations == 2  # ceil((48 - 20) / 16)
    runner = Runner(config, tmp_path, tensorboard=False)
    assert runner.global_step == 20
    runner.learn()
    rows = [json.loads(line) for line in (tmp_path / "metrics.jsonl").read_text().splitlines()]
    assert [row["global_step"] for row in rows] == [36, 52]
    runner.close()


@pytest.mark.parametrize(("steps", "message"), [(-1, "from 0 to"), (48, "below total_steps")])
def test_bad_search_steps_are_refused(steps, message):
    config = tiny_config("cpg-actor", iterations=3)
    config.search_steps = steps
    with pytest.raises(ValueError, match=message):
        config.validate()


def test_reproduce_charges_the_search_to_the_agents_that_start_from_its_gait(tmp_path):
    gait = tmp_path / "gait.yaml"
    gait.write_text(
        "robot: hopper\nfitness: 500.0\nsteps: 100000\nsteps_searched: 123456\nseed: 100\n"
        "cpg_initial:\n  frequency: [1.5, 1.5]\n  amplitude: [0.5, 0.6]\n  convergence: 20.0\n"
    )
    assert search_steps(str(gait), get_robot("hopper")) == 123_456
    settings = ReproduceSettings(
        variants=["cpg-actor", "cho2019-warm", "mlp-warm", "mlp", "cho2019-paper"],
        seeds=1,
        total_steps=2_000_000,
        overrides=[f"agent_config.start_gait={gait}"],
        count_search_steps=True,
    )
    charged = {v: resolve_config(settings, v).search_steps for v in settings.variants}
    assert charged == {
        "cpg-actor": 123_456, "cho2019-warm": 123_456, "mlp-warm": 123_456,
        "mlp": 0, "cho2019-paper": 0,
    }  # fmt: skip
    tasks = {task.variant: task for task in build_tasks(settings, tmp_path, workers=1)}
    assert "search_steps=123456" in tasks["cpg-actor"].train_args
    assert not any("search_steps" in arg for arg in tasks["mlp"].train_args)
    assert settings.identity()["count_search_steps"] is True
    # not counted unless asked: the runs train their whole budget
    settings.count_search_steps = False
    assert resolve_config(settings, "cpg-actor").search_steps == 0
    # the packaged gait's own search
    packaged = search_steps("search", get_robot("hopper"))
    settings = ReproduceSettings(["cpg-actor"], 1, 2_000_000, count_search_steps=True)
    assert resolve_config(settings, "cpg-actor").search_steps == packaged
