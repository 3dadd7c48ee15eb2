"""Every benchmark script runs: its smallest real configuration, on the CPU, its table written
to a temporary file (a script that breaks says so here, not on the next measurement). Those
whose smallest run compiles (``torch.compile``, MJX's JIT) or trains for seconds are slow."""

import importlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from cpg_actor.ppo.algorithm import cpp_compiler
from extras import MJX  # noqa: I001 (tests/ is on sys.path)

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
# the package of this tree, wherever the script runs from
PYTHONPATH = os.pathsep.join([str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])])
SLOW = pytest.mark.slow
COMPILER = pytest.mark.skipif(cpp_compiler() is None, reason="torch.compile needs a C++ compiler")

# script (and a variant's name after a space) -> (its smallest run's arguments, the flag of
# its output file)
RUNS = {
    "activation.py": (["--batch-sizes", "8", "--min-run-time", "0.01"], "--output"),
    "cpg_step.py": (["--batch-sizes", "1", "--min-run-time", "0.01"], "--out"),
    "env_throughput.py": (["--quick", "--max-n", "1", "--sims", "mujoco", "--repeats", "1"],
                          "--out"),
    "gpu_throughput.py": (["--envs", "4", "--agents", "mlp", "--iterations", "1", "--repeats",
                           "1", "--device", "cpu", "--seeds", "2"], "--output"),
    # a quadruped on MJX, two seeds in one process: gpu_check.sh's qbench part
    "gpu_throughput.py go1": (["--robot", "go1", "--envs", "2", "--agents", "cpg-actor",
                               "--iterations", "1", "--repeats", "1", "--device", "cpu",
                               "--seeds", "2"], "--output"),
    "guard_checks.py": (["--agent", "mlp", "--preset", "paper", "--pairs", "1", "--iterations",
                         "1"], "--output"),
    "learning_curves.py": (["--reference-src", str(ROOT / "src"), "--agents", "mlp", "--seeds",
                            "1", "--total-steps", "4096"], "--output"),
    "mjx_agreement.py": ([], "--output"),
    "mjx_eval.py": (["--agent", "mlp", "--episodes", "1", "--steps", "5", "--rounds", "1"],
                    "--output"),
    "mjx_solver_iterations.py": (["--caps", "4/15", "--rounds", "1", "--batch", "1"],
                                 "--output"),
    "planar_prior.py": (["--robot", "go1", "--seconds", "0.1", "--robots", "1"], "--output"),
    # GO1POLICY: a tiny trained Go1 run the test makes, exported; episodes of 5 steps
    "other_model.py": (["GO1POLICY", "--seeds", "1000", "--commands", "0.5", "--steps", "5",
                        "--ablation"], "--output"),
    "policy_latency.py": (["--steps", "20", "--agents", "mlp"], "--output"),
    "profile_collect.py": (["--num-envs", "4", "--agent", "mlp", "--device", "cpu"], "--output"),
    "quadruped_physics_settings.py": (["--robot", "go1", "--envs", "2", "--rounds", "1",
                                       "--seconds", "0.04", "--trot-robots", "1",
                                       "--trot-seconds", "0.1"], "--output"),
    "quadruped_physics_training.py": (["--robot", "go1", "--settings", "default", "4x5",
                                       "--seeds", "100", "--total-steps", "256", "--commands",
                                       "0.5", "--episodes", "1", "--set", "num_envs=2", "--set",
                                       "ppo.compile=false", "--eval-set",
                                       "env.episode_seconds=0.2"], "--output"),
    "quadruped_throughput.py": (["--envs", "2", "--seconds", "0.2"], "--output"),
    "quadruped_train_throughput.py": (["--case", "go1/playground/mlp", "go1/-/cpg-actor",
                                       "--iterations", "1", "--num-envs", "2", "--no-compile"],
                                      "--output"),
    # REPRODUCTION: a tiny trained reproduction the test makes (its runs' episodes 250 steps)
    "robustness_suite.py": (["REPRODUCTION", "--variants", "mlp", "--seeds", "1", "--episodes",
                             "1"], "--output"),
    "rollout_threads.py": (["--agent", "mlp", "--num-envs", "2", "--iterations", "1",
                            "--repeats", "1"], "--output"),
    "shared_device.py": (["--runs", "1", "--preset", "paper", "--agent", "mlp", "--seconds", "10",
                          "--train-args=--num-envs 2 --set ppo.compile=false"], "--output"),
    "terrain_trot.py": (["--robots", "1", "--seconds", "0.1", "--levels", "1"], "--output"),
    "time_to_hop.py": (["--seeds", "1", "--agents", "mlp", "--presets", "paper", "--no-sb3",
                        "--no-search", "--budget", "mlp=256", "--set", "ppo.compile=false",
                        "--set", "num_envs=2", "--ceiling-steps", "2000"], "--output"),
    # one search of one generation (16 episodes of 50 steps) charged to mlp-warm, which is
    # also charged its cloning; open-loop-es is its own search
    "time_to_quality.py": (["--seeds", "1", "--first-seed", "4", "--agents",
                            "mlp-warm,open-loop-es", "--budget", "800", "--search-budgets",
                            "800", "--no-sb3", "--set",
                            "ppo.compile=false", "--set", "num_envs=2", "--set",
                            "env.episode_steps=50", "--ceiling-steps", "1000"], "--output"),
    # a tiny budget: it may not reach the target; mlp-warm's cloning is charged
    "time_to_walk.py": (["--agents", "cpg-actor,mlp-warm", "--max-steps", "128",
                         "--eval-interval", "64", "--eval-episodes", "1", "--set",
                         "ppo.compile=false", "--set", "num_envs=2", "--set",
                         "env.episode_seconds=0.5", "--ceiling-seconds", "0.1"], "--output"),
    # --grid: the omni task, evaluated on the protocol's 12 commands, episodes of 10 steps
    "time_to_walk.py grid": (["--grid", "--agents", "cpg-actor,mlp-warm", "--max-steps", "128",
                              "--eval-interval", "64", "--grid-episode-seconds", "0.2", "--set",
                              "ppo.compile=false", "--set", "num_envs=2", "--set",
                              "env.episode_seconds=0.5", "--ceiling-seconds", "0.1"], "--output"),
    "train_scaling.py": (["--cores", "1", "--num-envs", "2", "--iterations", "1", "--agent",
                          "mlp"], "--output"),
    "train_throughput.py": (["--presets", "paper", "--agents", "mlp", "--iterations", "1",
                             "--num-envs", "2"], "--output"),
}  # fmt: skip
# longer than ~20 s: a compile, MJX's JIT, or seconds of training
MARKS = {
    "activation.py": [COMPILER],
    "gpu_throughput.py": [SLOW, MJX],
    "gpu_throughput.py go1": [SLOW, MJX],
    "guard_checks.py": [SLOW, COMPILER],
    "learning_curves.py": [SLOW],
    "quadruped_physics_training.py": [SLOW],
    "mjx_agreement.py": [SLOW, MJX],
    "mjx_eval.py": [SLOW, MJX],
    "mjx_solver_iterations.py": [SLOW, MJX],
    "profile_collect.py": [SLOW, MJX],
    "robustness_suite.py": [SLOW],
    "rollout_threads.py": [SLOW],
    "shared_device.py": [SLOW],
    "time_to_quality.py": [SLOW],
    "train_scaling.py": [COMPILER],
}


def test_every_script_is_run_here():
    """A new benchmark script gets its smallest run in RUNS (bench_report.py and
    time_to_target.py are their modules)."""
    modules = {"bench_report.py", "time_to_target.py"}
    scripts = {path.name for path in BENCHMARKS.glob("*.py")} - modules
    assert scripts == {name.split()[0] for name in RUNS}


@pytest.mark.parametrize(
    "script", [pytest.param(name, marks=MARKS.get(name, [])) for name in sorted(RUNS)]
)
def test_the_script_runs_its_smallest_configuration(script, tmp_path):
    arguments, output_flag = RUNS[script]
    if "REPRODUCTION" in arguments:
        from tiny import trained_run  # tests/tiny.py

        reproduction = tmp_path / "repro"
        trained_run(reproduction / "runs" / "mlp" / "seed0", "mlp", env={"episode_steps": 250})
        arguments = [str(reproduction) if a == "REPRODUCTION" else a for a in arguments]
    if "GO1POLICY" in arguments:
        from cpg_actor.config import TrainConfig
        from cpg_actor.deploy import load_policy
        from cpg_actor.deploy.export import export_policy
        from tiny import trained_run  # tests/tiny.py

        run = trained_run(tmp_path / "go1", "cpg-actor", "go1")
        policy = load_policy(run, run_config=TrainConfig.load(run / "config.yaml"))
        onnx = export_policy(policy, run / "export" / "policy.onnx", "onnx")
        arguments = [str(onnx) if a == "GO1POLICY" else a for a in arguments]
    output = tmp_path / "result.md"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / script.split()[0]), *arguments, output_flag, str(output)],
        cwd=tmp_path,  # nothing written into the tree
        env={**os.environ, "CUDA_VISIBLE_DEVICES": "", "PYTHONPATH": PYTHONPATH},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert output.is_file() and output.stat().st_size > 0
    if "--first-seed" in arguments:  # its runs take the seeds asked for
        assert f"seed {arguments[arguments.index('--first-seed') + 1]} " in result.stdout
    if script.startswith("time_to_walk"):  # every run's result beside the report
        runs = json.loads(output.with_suffix(".json").read_text())
        assert [(r["agent"], r["seed"]) for r in runs] == [("cpg-actor", 100), ("mlp-warm", 100)]
        assert all(r["history"] and "reached" in r for r in runs)


def test_the_gpu_check_script_parses():
    """gpu_check.sh runs on a lent GPU machine only: here, its syntax."""
    subprocess.run(["bash", "-n", str(BENCHMARKS / "gpu_check.sh")], check=True)


@pytest.mark.parametrize("preset", ["paper", "throughput"])
def test_time_to_hop_trains_each_agent_with_the_config_cpg_actor_train_gives_it(preset):
    """The benchmark composes its runs' configs itself (it also runs older trees): on this tree
    every agent's, its tuned settings on the hopper included, is the one ``cpg-actor train``
    composes. (Its runs once lost the tuned settings when they moved to the robot.)"""
    from cpg_actor.agents import AGENTS
    from cpg_actor.config import compose_config

    sys.path.insert(0, str(BENCHMARKS))
    try:
        import time_to_hop
    finally:
        sys.path.remove(str(BENCHMARKS))
    values = [{"num_envs": 8}]
    for agent in AGENTS:
        expected = compose_config(preset, None, {"agent": agent, "num_envs": 8})
        composed = time_to_hop.compose(agent, preset, values)
        composed.preset = expected.preset  # the benchmark names the preset in its report
        assert composed == expected, agent


def benchmark(name: str):
    """The benchmark script ``name`` as a module (its folder on the path while it imports)."""
    sys.path.insert(0, str(BENCHMARKS))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(BENCHMARKS))


def evaluation(steps: int, error: float, fell: float = 0.0) -> dict:
    """One recorded evaluation of time_to_walk: at ``steps`` env steps, ``steps / 1000`` s."""
    return {"steps": steps, "wall": steps / 1000, "eval/speed_error": error, "eval/fell": fell,
            "eval/forward_speed": 0.5, "eval/return": 10.0}  # fmt: skip


def test_time_to_walk_target_is_a_low_speed_error_without_a_fall():
    walk = benchmark("time_to_walk")
    assert walk.reached(evaluation(0, 0.1), 0.1)
    assert walk.reached(evaluation(0, 0.02), 0.1)
    assert not walk.reached(evaluation(0, 0.1001), 0.1)
    assert not walk.reached(evaluation(0, 0.05, fell=0.1), 0.1)  # one episode of ten fell
    assert not walk.reached(evaluation(0, math.nan), 0.1)
    assert not walk.reached(evaluation(0, 0.05, fell=math.nan), 0.1)
    assert walk.reached(evaluation(0, 0.14), 0.15)


def test_time_to_walk_times_the_first_evaluation_at_the_target_and_charges_the_start():
    walk = benchmark("time_to_walk")
    history = [evaluation(0, 0.5), evaluation(100, 0.2), evaluation(200, 0.08, fell=0.1),
               evaluation(300, 0.09), evaluation(400, 0.05)]  # fmt: skip
    run = walk.summarize(history, 0.1, start_steps=1000, start_wall=2.0)
    assert run["reached"] and (run["steps"], run["wall"]) == (300, 0.3)
    assert walk.total_steps(run) == 1300 and walk.total_wall(run) == pytest.approx(2.3)
    assert run["first"]["eval/speed_error"] == 0.5 and run["best"]["steps"] == 400
    run.update(sps=1000.0, ceiling=[2000.0, 2000.0], stolen=0.0)
    row = walk.run_row("mlp-warm", 100, run, 400)
    assert "1,000 + 300 = **1,300**" in row and "2 s + 0 s = **2 s**" in row
    assert "| 1 s |" in row  # physics alone: 1,300 steps at 2,000 per second


def test_time_to_walk_says_not_reached_and_ends_at_the_cap():
    walk = benchmark("time_to_walk")
    history = [evaluation(0, 0.5), evaluation(100, 0.2), evaluation(200, 0.11)]
    run = walk.summarize(history, 0.1)
    assert not run["reached"] and run["steps"] == 200 and run["best"]["steps"] == 200
    falling = walk.summarize([*history, evaluation(300, 0.05, fell=0.5)], 0.1)
    assert falling["best"]["steps"] == 200 and falling["lowest"]["steps"] == 300
    assert walk.summarize([evaluation(0, 0.3, fell=1.0)], 0.1)["best"] is None
    run.update(sps=1000.0, ceiling=[2000.0, 2000.0], stolen=0.0)
    assert "not reached by 3,000k |" in walk.run_row("mlp", 100, run, 3_000_000)
    run["stopped"] = True  # cut short by SIGTERM: not reached by its last evaluation
    assert "not reached by 200 (stopped there by hand)" in walk.run_row("mlp", 100, run, 3_000_000)
    assert walk.summarize([evaluation(0, 0.1)], 0.1)["steps"] == 0  # walks before training


def test_the_evaluation_recorder_stops_after_the_first_evaluation_at_the_target():
    recorder = benchmark("time_to_target").evaluation_recorder(lambda e: e["x"] <= 1)
    runner = SimpleNamespace(last_evaluation={"x": 3}, global_step=0, train_wall=0.0)
    recorder.start(runner, True)
    stops = []
    for step, x in ((10, None), (20, 2), (30, None), (40, 1), (50, 0)):
        runner.global_step, runner.train_wall = step, step / 10
        it = SimpleNamespace(evaluation=None if x is None else {"x": x}, stop=False)
        recorder.iteration(runner, it)
        stops.append(it.stop)
    assert stops == [False, False, False, True, True]
    assert [(s, w, e["x"]) for s, w, e in recorder.history] == [
        (0, 0.0, 3), (20, 2.0, 2), (40, 4.0, 1), (50, 5.0, 0)]  # fmt: skip
    first = benchmark("time_to_target").evaluation_recorder(lambda e: e["x"] <= 1)
    runner.last_evaluation = {"x": 0}  # at the target before training: stop at once
    first.start(runner, True)
    it = SimpleNamespace(evaluation=None, stop=False)
    first.iteration(runner, it)
    assert it.stop


def test_the_time_to_a_target_is_the_first_evaluation_at_it_else_the_runs_end(capsys):
    """time_to_target: a run's time is its first evaluation at the target, its start charged
    on top; a run that never got there is censored at its last evaluation. Over seeds: the
    medians of the seeds that reached it, and the median wall time with the censored seeds
    counted as later than their whole run (a lower bound where that median is one of them)."""
    shared = benchmark("time_to_target")

    def met(entry: dict) -> bool:
        return entry["x"] <= 1

    history = [{"steps": 0, "wall": 0.0, "x": 3}, {"steps": 100, "wall": 1.5, "x": 1},
               {"steps": 200, "wall": 3.0, "x": 0}]  # fmt: skip
    assert shared.first_at_target(history, met) is history[1]
    assert shared.to_target(history, met) == {"reached": True, "steps": 100, "wall": 1.5}
    never = [history[0], {"steps": 300, "wall": 4.0, "x": 2}]
    assert shared.first_at_target(never, met) is None
    assert shared.to_target(never, met) == {"reached": False, "steps": 300, "wall": 4.0}
    assert shared.to_target([], met) == {"reached": False, "steps": 0, "wall": 0.0}
    assert shared.charged(history, 1000, 10.0)[1] == {"steps": 1100, "wall": 11.5, "x": 1}
    start = {"start_steps": 1000, "start_wall": 10.0}
    runs = [{**shared.to_target(history, met), **start},  # 1,100 steps, 11.5 s
            {"reached": True, "steps": 300, "wall": 2.5, **start},  # 1,300 steps, 12.5 s
            {**shared.to_target(never, met), **start}]  # censored: 1,300 steps, 14 s  # fmt: skip
    assert (shared.total_steps(runs[2]), shared.total_wall(runs[2])) == (1300, 14.0)
    assert shared.total_steps({"steps": 5, "wall": 1.0}) == 5  # nothing charged
    assert shared.over_seeds(runs) == (2, 1200.0, 12.0)
    assert shared.over_seeds(runs[2:]) == (0, None, None)
    assert shared.censored_median_wall(runs) == (12.5, False)
    assert shared.censored_median_wall(runs[1:]) == (13.25, True)  # 12.5 s and >= 14 s
    assert shared.split(1300, 1000, str) == "1000 + 300 = **1300**"
    assert shared.split(300, 0, str) == "300"
    # a run's spec travels to a fresh process as JSON, its result comes back as JSON
    twice = {"--one-run": (dict, lambda given: {"twice": 2 * given["x"]})}
    assert not shared.answer(["--seeds", "3"], twice)
    assert shared.answer(["--one-run", json.dumps({"x": 2})], twice)
    assert json.loads(capsys.readouterr().out) == {"twice": 4}


def test_time_to_hop_censors_a_run_below_the_threshold_at_its_end_with_its_best_return():
    hop = benchmark("time_to_hop")
    evaluations = [(0, 0.0, 300.0, 0.30), (100, 1.0, 700.0, 0.44), (200, 2.0, 600.0, 0.46),
                   (300, 3.0, 650.0, 0.40)]  # fmt: skip
    history = [hop.point(s, w, {"eval/return": r, "eval/hop_height": h})
               for s, w, r, h in evaluations]  # fmt: skip
    run = hop.summarize(history, (None, 0.45))
    assert run["reached"] and (run["steps"], run["wall"], run["hop"]) == (200, 2.0, 0.46)
    assert run["best"]["steps"] == 200 and run["near_best"]["steps"] == 100  # 0.44 >= 0.437
    missed = hop.summarize(history, (800.0, 0.45))
    assert not missed["reached"] and (missed["steps"], missed["wall"]) == (300, 3.0)
    assert (missed["return"], missed["hop"]) == (700.0, 0.44)  # the best return and its hop
    assert hop.fmt_runs([missed]) == ("0/1", "not reached", "-")
    run["start_steps"], run["start_wall"] = 1000, 10.0
    assert hop.fmt_runs([run, missed]) == ("1/2", "1k + 0k = **1k**", "10 s + 2 s = **12 s**")
    assert hop.wall_ratio([missed, missed], [run, run]) == ">= 3 s / 12 s = **>= 0.25x**"


def test_time_to_walk_trains_as_a_run_without_its_evaluations():
    """The benchmark's run (its config, the trainer's evaluations, its recorder) trains the
    same parameters as the same run with no evaluation: the evaluations draw nothing from
    the training's random numbers."""
    import torch

    from cpg_actor.training.runner import Runner

    walk = benchmark("time_to_walk")
    tiny = ["ppo.compile=false", "num_envs=2", "env.episode_seconds=0.5"]
    spec = walk.RunSpec("go1", "cpg-actor", 100, 192, 64, 1, 0.1, tiny, 0.1)
    parameters = []
    for evaluated in (True, False):
        config = walk.run_config(spec)
        recorder = benchmark("time_to_target").evaluation_recorder()
        if not evaluated:
            config.eval_interval = 0
        runner = Runner(config, run_dir=None, tensorboard=False, hooks=[recorder])
        runner.learn()
        runner.close()
        assert len(recorder.history) == (4 if evaluated else 0)  # before, then every iteration
        parameters.append(runner.agent.state_dict())
    for key, value in parameters[0].items():
        assert torch.equal(value, parameters[1][key]), key


def grid_evaluation(error: float, fell: float = 0.0) -> dict:
    """One grid evaluation of time_to_walk --grid: its mean linear-velocity error over the
    commands and the share of its episodes that fell (no forward speed error in it)."""
    return {"eval/lin_vel_error": error, "eval/fell": fell, "eval/return": 10.0}


def test_time_to_walk_grid_target_is_a_low_grid_error_without_a_fall_on_any_command():
    walk = benchmark("time_to_walk")
    assert walk.reached_grid(grid_evaluation(0.15), 0.15)
    assert walk.reached_grid(grid_evaluation(0.03), 0.15)
    assert not walk.reached_grid(grid_evaluation(0.1501), 0.15)
    assert not walk.reached_grid(grid_evaluation(0.05, fell=1 / 12), 0.15)  # one command fell
    assert not walk.reached_grid(grid_evaluation(math.nan), 0.15)
    assert not walk.reached_grid(grid_evaluation(0.05, fell=math.nan), 0.15)
    # the grid's error, not the forward task's: a low speed error alone is no hit
    assert not walk.reached_grid({**grid_evaluation(0.3), "eval/speed_error": 0.01}, 0.15)
    history = [{"steps": 0, "wall": 0.0, **grid_evaluation(0.3)},
               {"steps": 100, "wall": 0.1, **grid_evaluation(0.1, fell=0.5)},
               {"steps": 200, "wall": 0.2, **grid_evaluation(0.14)}]  # fmt: skip
    run = walk.summarize(history, 0.15, error=walk.ERRORS["grid"])
    assert run["reached"] and run["steps"] == 200 and run["lowest"]["steps"] == 100
    run.update(sps=1000.0, ceiling=[2000.0, 2000.0], stolen=0.0, mode="grid", eval_seconds=3.0)
    row = walk.run_row("cpg-actor", 100, run, 400)
    assert "| grid |" in row and "0.300 m/s (at 0)" in row and "| 3.0 s |" in row


def test_the_grid_evaluation_is_the_protocols_grid_on_flat_ground():
    """The grid evaluation holds each of the protocol's commands for its episodes, on the
    nominal robot on flat ground, with the episode length asked for."""
    from cpg_actor.config import compose_config
    from cpg_actor.robots.registry import get_robot
    from cpg_actor.robustness.grid_evaluation import GridEvaluation
    from cpg_actor.robustness.protocol import GRID

    config = compose_config("omni", None, {"robot": "go1"}, ["env.terrain.kinds=all"])
    assert config.env.terrain.active  # trained on rough ground: evaluated on flat
    grid = GridEvaluation(config, get_robot("go1"), 1, 0.2)
    assert len(grid.env_configs) == len(GRID) and grid.episode_seconds == 0.2
    for command, env in zip(GRID, grid.env_configs, strict=True):
        assert (env.command_range[0], env.lateral_range[0], env.yaw_range[0]) == command.values
        assert env.command_resample_seconds == 0 and env.standing_share == 0
        assert not env.terrain.active
    with pytest.raises(ValueError, match="velocity task"):
        GridEvaluation(compose_config(None, None, {"robot": "hopper"}), get_robot("hopper"))


def test_time_to_walk_times_a_named_variant_the_fields_mlp_recipe(capsys):
    """--agents takes reproduce's named variants: mlp-field is the MLP with the field's
    network and PPO weights on the omni task; an unknown name lists both kinds."""
    walk = benchmark("time_to_walk")
    spec = walk.RunSpec("go1", "mlp-field", 100, 128, 64, 1, 0.15, ["num_envs=2"], 0.1, True)
    config = walk.run_config(spec)
    assert (config.agent, config.preset) == ("mlp", "omni")
    assert config.agent_config.actor_hidden == (512, 256, 128) and config.ppo.entropy_coef == 0.01
    with pytest.raises(SystemExit):
        walk.main(["--grid", "--agents", "cpg-actor,mlp-fast", "--max-steps", "128"])
    error = capsys.readouterr().err
    assert "unknown mlp-fast" in error and "mlp-field" in error


def test_time_to_walk_grid_trains_as_a_run_without_its_evaluations():
    """With --grid, the runs trained with the grid evaluations give the same parameters as
    the same runs with no evaluation: the grid draws nothing from the training's random
    numbers."""
    import torch

    from cpg_actor.robots.registry import get_robot
    from cpg_actor.robustness.grid_evaluation import GridEvaluation
    from cpg_actor.training.runner import Runner

    walk = benchmark("time_to_walk")
    tiny = ["ppo.compile=false", "num_envs=2", "env.episode_seconds=0.5"]
    spec = walk.RunSpec("go1", "mlp-warm", 100, 128, 64, 1, 0.15, tiny, 0.1, True, 0.1)
    parameters = []
    for evaluated in (True, False):
        config = walk.run_config(spec)
        assert config.preset == "omni" and config.env.lateral_range != (0.0, 0.0)
        recorder = benchmark("time_to_target").evaluation_recorder()
        if not evaluated:
            config.eval_interval = 0
        runner = Runner(config, run_dir=None, tensorboard=False, hooks=[recorder])
        runner.evaluation.evaluator = GridEvaluation(config, get_robot("go1"), 1, 0.1)
        runner.learn()
        runner.close()
        assert len(recorder.history) == (3 if evaluated else 0)  # before, then every iteration
        if evaluated:
            assert all("eval/lin_vel_error" in e and "eval/speed_error" not in e
                       for _, _, e in recorder.history)  # fmt: skip
        parameters.append(runner.agent.state_dict())
    for key, value in parameters[0].items():
        assert torch.equal(value, parameters[1][key]), key


def quality(steps: int, ret: float, apex: float) -> dict:
    """One evaluation of time_to_quality: at ``steps`` env steps, ``steps / 1000`` s."""
    return {"steps": steps, "wall": steps / 1000, "return": ret, "apex": apex, "hop": apex}


def test_time_to_quality_target_needs_the_return_and_the_apex_in_one_evaluation():
    ttq = benchmark("time_to_quality")
    target = ttq.Target(850.0, 0.5)
    assert target.met(quality(0, 850.0, 0.5)) and target.met(quality(0, 900.0, 0.6))
    assert not target.met(quality(0, 849.9, 0.6))  # the apex alone
    assert not target.met(quality(0, 1000.0, 0.499))  # the return alone
    assert not target.met(quality(0, math.nan, 0.6)) and not target.met(quality(0, 900, math.nan))
    # the best return and the best apex in different evaluations are no hit
    history = [quality(0, 900.0, 0.3), quality(100, 700.0, 0.6), quality(200, 860.0, 0.55)]
    assert ttq.first_at_target(history[:2], target) is None
    assert ttq.first_at_target(history, target)["steps"] == 200
    assert "return >= 850" in target.describe() and "apex >= 0.5 m" in target.describe()


def test_time_to_quality_best_so_far_keeps_each_maximum_and_skips_nan():
    ttq = benchmark("time_to_quality")
    history = [quality(0, 500.0, math.nan), quality(10, 400.0, 0.3), quality(20, 600.0, 0.2),
               quality(30, math.nan, 0.4)]  # fmt: skip
    curve = ttq.best_so_far(history)
    assert [c["return"] for c in curve] == [500.0, 500.0, 600.0, 600.0]
    assert math.isnan(curve[0]["apex"]) and [c["apex"] for c in curve[1:]] == [0.3, 0.3, 0.4]
    assert [c["steps"] for c in curve] == [0, 10, 20, 30]
    assert ttq.best_so_far([]) == []


def test_time_to_quality_charges_the_search_and_the_warm_start():
    ttq = benchmark("time_to_quality")
    target = ttq.Target(850.0, 0.5)
    run = {"history": [quality(0, 700.0, 0.49), quality(1000, 900.0, 0.52)],
           "warm_steps": 8000, "warm_wall": 1.5, "num_envs": 16}  # fmt: skip
    search = {"steps": 496_000, "wall": 60.0}
    charged = ttq.summarize(run, search, target)
    assert (charged["start_steps"], charged["start_wall"]) == (504_000, pytest.approx(61.5))
    assert charged["hit"]["steps"] == 505_000 and charged["hit"]["wall"] == pytest.approx(62.5)
    assert charged["curve"][0]["steps"] == 504_000  # the curve begins where the start ends
    assert (charged["best_return"], charged["best_apex"]) == (900.0, 0.52)
    alone = ttq.summarize(run | {"warm_steps": 0, "warm_wall": 0.0}, None, target)
    assert alone["hit"]["steps"] == 1000 and alone["start_steps"] == 0
    missed = ttq.summarize(run, search, ttq.Target(950.0, 0.5))
    assert missed["hit"] is None
    row = ttq.method_row(
        ttq.Method("`cpg-actor`", "project", "cpg-actor", 16, None), [charged, missed]
    )
    assert "| 1/2 |" in row and "**505k**" in row and "504k, 62 s" in row


@pytest.mark.slow
def test_time_to_quality_resumes_a_cut_off_run_without_redoing_what_it_saved(tmp_path, capsys):
    """Cut off after its search and first run, the same command with --resume reruns neither
    (the gait file comes back from the progress file), runs the rest and ends with every seed;
    without --resume it refuses to start over that progress."""
    ttq = benchmark("time_to_quality")
    output = tmp_path / "ttq.md"
    argv = ["--seeds", "2", "--first-seed", "4", "--agents", "mlp-warm", "--budget", "800",
            "--search-budgets", "800", "--no-sb3", "--set", "ppo.compile=false", "--set",
            "num_envs=2", "--set", "env.episode_steps=50", "--ceiling-steps", "1000",
            "--output", str(output)]  # fmt: skip
    real, calls = ttq.in_fresh_process, []

    def cut_after_one_run(flag, spec):
        calls.append(flag)
        if calls.count("--one-run") == 2:
            raise KeyboardInterrupt  # the session ends here
        return real(flag, spec)

    ttq.in_fresh_process = cut_after_one_run
    try:
        with pytest.raises(KeyboardInterrupt):
            ttq.main(argv)
        partial = json.loads(output.with_suffix(".partial.json").read_text())
        assert [r["seed"] for r in partial["results"]["`mlp-warm` (search 1k)"]] == [4]
        with pytest.raises(SystemExit):
            ttq.main(argv)  # the progress is there: --resume or delete it
        assert "add --resume" in capsys.readouterr().err
        calls.clear()
        assert ttq.main([*argv, "--resume"]) == 0
    finally:
        ttq.in_fresh_process = real
    assert calls == ["--one-run"]  # seed 5 only: no search, no seed 4 again
    final = json.loads(output.with_suffix(".json").read_text())
    assert [r["seed"] for r in final["`mlp-warm` (search 1k)"]] == [4, 5]
    assert not output.with_suffix(".partial.json").exists()
    with pytest.raises(SystemExit):
        ttq.main([*argv[:3], "3", *argv[4:], "--resume"])  # other arguments, nothing to resume
    assert "--resume: no" in capsys.readouterr().err


def fake_trainer(run_dir: Path, rows: int, every: float) -> list[str]:
    """A process that logs ``rows`` training iterations to RUN_DIR/metrics.jsonl, one each
    ``every`` seconds, then sleeps (as a run that trains until it is stopped)."""
    code = (
        "import json, sys, time\n"
        "from pathlib import Path\n"
        "d = Path(sys.argv[1]); d.mkdir(parents=True)\n"
        "for i in range(int(sys.argv[2])):\n"
        "    time.sleep(float(sys.argv[3]))\n"
        "    with open(d / 'metrics.jsonl', 'a') as f:\n"
        "        f.write(json.dumps({'global_step': 100 * (i + 1), 'charts/SPS': 1}) + '\\n')\n"
        "time.sleep(60)\n"
    )
    return [sys.executable, "-c", code, str(run_dir), str(rows), str(every)]


def test_shared_device_waits_for_the_iterations_its_window_needs_on_a_slow_machine(tmp_path):
    shared = benchmark("shared_device")
    run_dir = tmp_path / "seed0"
    # a run slower than --seconds: its 3 iterations come after 1.5 s of a 1 s watch (10 s cap)
    stamps = shared.watch([fake_trainer(run_dir, 3, 0.5)], [run_dir], seconds=1.0)
    assert [step for _, step in stamps[0]] == [100, 200, 300]
    rates, window = shared.window_rates(stamps)
    assert window > 0 and rates[0] > 0
    # a run that never gets there: the watch ends at WAIT_FACTOR x --seconds and says so
    quiet = tmp_path / "seed1"
    stamps = shared.watch([fake_trainer(quiet, 1, 0.05)], [quiet], seconds=0.1)
    assert len(stamps[0]) == 1
    with pytest.raises(ValueError, match="did not finish 3 iterations"):
        shared.window_rates(stamps)


@pytest.mark.parametrize(
    "script, arguments, beside",
    [
        ("time_to_walk", ["--agents", "cpg-actor", "--seeds", "100"], (".json",)),
        ("time_to_quality", ["--agents", "mlp", "--seeds", "1"], (".png", ".json")),
        ("learning_curves", ["--reference-src", str(ROOT / "src")], (".png",)),
    ],
)
def test_a_benchmark_replaces_no_file_beside_a_named_output_without_overwrite(
    script, arguments, beside, tmp_path, monkeypatch, capsys
):
    """``--output X.md`` writes X.md and the files it documents beside it (X.json, X.png):
    one of those that exists may be the user's, and is refused before anything runs."""
    module = benchmark(script)
    output = tmp_path / "mine.md"
    for suffix in beside:
        path = output.with_suffix(suffix)
        path.write_text("my own")
        monkeypatch.setattr(sys, "argv", [script, *arguments, "--output", str(output)])
        with pytest.raises(SystemExit) as stopped:
            module.main() if script == "learning_curves" else module.main(sys.argv[1:])
        assert stopped.value.code == 2
        err = capsys.readouterr().err
        last = err.strip().splitlines()[-1]  # after argparse's usage: the one line that says
        assert last.startswith(f"{script}: error: --output {output}: {path} exists"), err
        assert "--overwrite" in last and "Traceback" not in err
        assert path.read_text() == "my own" and not output.exists()
        path.unlink()
    # the report's own suffix for its companion: refused too
    named = tmp_path / f"mine{beside[-1]}"
    monkeypatch.setattr(sys, "argv", [script, *arguments, "--output", str(named)])
    with pytest.raises(SystemExit):
        module.main() if script == "learning_curves" else module.main(sys.argv[1:])
    assert "give a report name ending in .md" in capsys.readouterr().err


@pytest.mark.parametrize("script", ["time_to_walk", "time_to_quality"])
def test_the_time_benchmarks_refuse_a_bad_set_in_one_line_before_any_run(script, tmp_path, capsys):
    """--set is read and checked as `cpg-actor train --set` reads it: an unknown key, a text
    without `=`, a value of the wrong type, each one line naming it, nothing written."""
    main = benchmark(script).main
    output = tmp_path / "report.md"
    for text, message in (("nokey=1", "unknown config key 'nokey'"),
                          ("garbage", "--set expects KEY=VALUE"),
                          ("ppo.learning_rate=abc", "ppo.learning_rate must be a number"),
                          ("num_envs=many", "num_envs must be an integer")):  # fmt: skip
        with pytest.raises(SystemExit) as exit_:
            main(["--set", text, "--output", str(output)])
        assert exit_.value.code == 2
        error = capsys.readouterr().err
        assert message in error and "Traceback" not in error, error
        assert ": error: " in error.splitlines()[-1] and message in error.splitlines()[-1]
    assert not any(tmp_path.iterdir())
