"""Every benchmark script runs: its smallest real configuration, on the CPU, its table written
to a temporary file (a script that breaks says so here, not on the next measurement). Those
whose smallest run compiles (``torch.compile``, MJX's JIT) or trains for seconds are slow."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from cpg_actor.ppo.algorithm import cpp_compiler
from extras import MJX  # noqa: I001 (tests/ is on sys.path)

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
# the package of this tree, wherever the script runs from
PYTHONPATH = os.pathsep.join([str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])])
SLOW = pytest.mark.slow
COMPILER = pytest.mark.skipif(cpp_compiler() is None, reason="torch.compile needs a C++ compiler")

# script -> (its smallest run's arguments, the flag of its output file)
RUNS = {
    "activation.py": (["--batch-sizes", "8", "--min-run-time", "0.01"], "--output"),
    "cpg_step.py": (["--batch-sizes", "1", "--min-run-time", "0.01"], "--out"),
    "env_throughput.py": (["--quick", "--max-n", "1", "--sims", "mujoco", "--repeats", "1"],
                          "--out"),
    "gpu_throughput.py": (["--envs", "4", "--agents", "mlp", "--iterations", "1", "--repeats",
                           "1", "--device", "cpu", "--seeds", "2"], "--output"),
    "guard_checks.py": (["--agent", "mlp", "--preset", "paper", "--pairs", "1", "--iterations",
                         "1"], "--output"),
    "learning_curves.py": (["--reference-src", str(ROOT / "src"), "--agents", "mlp", "--seeds",
                            "1", "--total-steps", "4096"], "--output"),
    "mjx_agreement.py": ([], "--output"),
    "mjx_eval.py": (["--agent", "mlp", "--episodes", "1", "--steps", "5", "--rounds", "1"],
                    "--output"),
    "mjx_solver_iterations.py": (["--caps", "4/15", "--rounds", "1", "--batch", "1"],
                                 "--output"),
    "policy_latency.py": (["--steps", "20", "--agents", "mlp"], "--output"),
    "profile_collect.py": (["--num-envs", "4", "--agent", "mlp", "--device", "cpu"], "--output"),
    "quadruped_physics_settings.py": (["--robot", "go1", "--envs", "2", "--rounds", "1",
                                       "--seconds", "0.04", "--trot-robots", "1",
                                       "--trot-seconds", "0.1"], "--output"),
    "quadruped_throughput.py": (["--envs", "2", "--seconds", "0.2"], "--output"),
    "quadruped_train_throughput.py": (["--robot", "go1", "--iterations", "1", "--num-envs", "2",
                                       "--no-compile"], "--output"),
    # REPRODUCTION: a tiny trained reproduction the test makes (its runs' episodes 250 steps)
    "robustness_suite.py": (["REPRODUCTION", "--variants", "mlp", "--seeds", "1", "--episodes",
                             "1"], "--output"),
    "rollout_threads.py": (["--agent", "mlp", "--num-envs", "2", "--iterations", "1",
                            "--repeats", "1"], "--output"),
    "shared_device.py": (["--runs", "1", "--preset", "paper", "--agent", "mlp", "--seconds", "10",
                          "--train-args=--num-envs 2 --set ppo.compile=false"], "--output"),
    "time_to_hop.py": (["--seeds", "1", "--agents", "mlp", "--presets", "paper", "--no-sb3",
                        "--no-search", "--budget", "mlp=256", "--set", "ppo.compile=false",
                        "--set", "num_envs=2", "--ceiling-steps", "2000"], "--output"),
    "train_scaling.py": (["--cores", "1", "--num-envs", "2", "--iterations", "1", "--agent",
                          "mlp"], "--output"),
    "train_throughput.py": (["--presets", "paper", "--agents", "mlp", "--iterations", "1",
                             "--num-envs", "2"], "--output"),
}  # fmt: skip
# longer than ~20 s: a compile, MJX's JIT, or seconds of training
MARKS = {
    "activation.py": [COMPILER],
    "gpu_throughput.py": [SLOW, MJX],
    "guard_checks.py": [SLOW, COMPILER],
    "learning_curves.py": [SLOW],
    "mjx_agreement.py": [SLOW, MJX],
    "mjx_eval.py": [SLOW, MJX],
    "mjx_solver_iterations.py": [SLOW, MJX],
    "profile_collect.py": [SLOW, MJX],
    "robustness_suite.py": [SLOW],
    "rollout_threads.py": [SLOW],
    "shared_device.py": [SLOW],
    "train_scaling.py": [COMPILER],
}


def test_every_script_is_run_here():
    """A new benchmark script gets its smallest run in RUNS (bench_report.py is their module)."""
    scripts = {path.name for path in BENCHMARKS.glob("*.py")} - {"bench_report.py"}
    assert scripts == set(RUNS)


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
    output = tmp_path / "result.md"
    result = subprocess.run(
        [sys.executable, str(BENCHMARKS / script), *arguments, output_flag, str(output)],
        cwd=tmp_path,  # nothing written into the tree
        env={**os.environ, "CUDA_VISIBLE_DEVICES": "", "PYTHONPATH": PYTHONPATH},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert output.is_file() and output.stat().st_size > 0


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
