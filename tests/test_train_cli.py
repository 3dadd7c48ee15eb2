"""`cpg-actor train` / `cpg-actor eval`: config handling, run directory safety, resume, traces."""

import argparse
import json
import os

import numpy as np
import pytest
import torch

from cpg_actor.cli import main
from cpg_actor.config import TrainConfig, apply_dict, compose_config, parse_override, parse_steps
from cpg_actor.robots.registry import ROBOTS
from cpg_actor.training.checkpoint import load_checkpoint

# tiny runs: 2 envs x 8 steps per iteration, eager (compiling costs seconds per run; the
# compiled path: test_train_resume_equals_straight_run_and_eval_writes_traces)
TINY = [
    "--set",
    "ppo.compile=false",
    "--num-envs",
    "2",
    "--set",
    "ppo.num_steps=8",
    "--set",
    "ppo.num_minibatches=2",
    "--set",
    "ppo.num_epochs=1",
    "--set",
    "checkpoint_interval=1",
    "--no-progress",
]


def test_step_counts_accept_suffixes_and_reject_bad_values():
    assert parse_steps("20M") == 20_000_000
    assert parse_steps("500k") == 500_000
    assert parse_steps("1e6") == 1_000_000
    assert parse_steps("1_000") == 1000
    for bad in ("-5", "0", "abc", "1.5", "2.5k3"):
        with pytest.raises(ValueError):
            parse_steps(bad)
    config = TrainConfig()  # --set and config files take the same suffixes as --total-steps
    apply_dict(config, parse_override("total_steps=2M"), "")
    assert config.total_steps == 2_000_000
    with pytest.raises(ValueError, match="500k or 20M"):
        apply_dict(config, parse_override("total_steps=many"), "")


def test_overrides_are_typed_and_unknown_keys_list_valid_ones():
    config = TrainConfig()
    apply_dict(config, parse_override("ppo.learning_rate=1e-4"), "")
    apply_dict(config, parse_override("agent_config.actor_hidden=[32, 16]"), "")
    apply_dict(config, parse_override("ppo.target_kl=null"), "")
    apply_dict(config, parse_override("env.sim=pybullet"), "")
    assert config.ppo.learning_rate == 1e-4
    assert config.agent_config.actor_hidden == (32, 16)
    assert config.ppo.target_kl is None
    assert config.env.sim == "pybullet"
    with pytest.raises(ValueError, match="valid keys here: .*learning_rate"):
        apply_dict(config, parse_override("ppo.learning_rat=1"), "")
    with pytest.raises(ValueError, match="must be an integer"):
        apply_dict(config, parse_override("num_envs=2.5"), "")
    with pytest.raises(ValueError, match="env"):
        apply_dict(config, parse_override("env.no_such_key=1"), "")
    with pytest.raises(ValueError, match="KEY=VALUE"):
        parse_override("ppo.learning_rate")


def test_config_round_trips_through_yaml(tmp_path):
    config = TrainConfig(agent="mlp", seed=7)
    config.ppo.lr_schedule = "linear"
    config.save(tmp_path / "c.yaml")
    loaded = TrainConfig.load(tmp_path / "c.yaml")
    assert loaded.to_dict() == config.to_dict()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--agent", "nope"], "unknown agent 'nope'"),
        (["--total-steps", "-100"], "positive integer"),
        (["--set", "ppo.gamma=2"], "ppo.gamma"),
        (["--set", "bogus=1"], "unknown config key 'bogus'"),
        (["--total-steps", "1e30"], "above the largest accepted"),
        (["--config", "."], "is a directory; give a YAML file"),
    ],
)
def test_bad_input_is_a_clear_error_and_creates_nothing(tmp_path, capsys, argv, message):
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), *argv]) == 2
    assert message in capsys.readouterr().err
    assert not run_dir.exists()


def test_existing_run_dir_is_never_overwritten_without_overwrite(tmp_path, capsys):
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / "config.yaml").write_text("precious: true\n")
    assert main(["train", "--run-dir", str(run_dir), *TINY]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (run_dir / "config.yaml").read_text() == "precious: true\n"
    other = tmp_path / "not_a_run"
    other.mkdir()
    (other / "notes.txt").write_text("keep")
    assert main(["train", "--run-dir", str(other), "--overwrite", *TINY]) == 2
    assert "refusing to delete" in capsys.readouterr().err
    assert (other / "notes.txt").read_text() == "keep"


@pytest.mark.slow
def test_train_resume_equals_straight_run_and_eval_writes_traces(tmp_path, capsys):
    """Extending a run (--resume with a larger --total-steps) equals training that long in
    one go under a fixed learning rate (a linear schedule is stretched by an extension).
    The paper preset compiles the loss (ppo.compile), so this checks that compiled updates
    are reproducible from one process to the next too."""
    straight, split = tmp_path / "straight", tmp_path / "split"
    fixed = ["--set", "ppo.lr_schedule=fixed", "--set", "ppo.compile=true"]
    assert main(["train", "--run-dir", str(straight), "--total-steps", "64", *TINY, *fixed]) == 0
    assert main(["train", "--run-dir", str(split), "--total-steps", "32", *TINY, *fixed]) == 0
    assert main(["train", "--run-dir", str(split), "--resume", "--seed", "3"]) == 2
    assert "only --total-steps may change" in capsys.readouterr().err
    assert (
        main(["train", "--run-dir", str(split), "--resume", "--total-steps", "64", "--no-progress"])
        == 0
    )
    assert TrainConfig.load(split / "config.yaml").ppo.compile  # the compiled path
    a = load_checkpoint(straight / "checkpoints" / "last.pt")
    b = load_checkpoint(split / "checkpoints" / "last.pt")
    assert a["iteration"] == b["iteration"] == 4
    for key, value in a["agent_state"].items():
        assert torch.equal(value, b["agent_state"][key]), key
    for key in ("config.yaml", "metrics.jsonl", "tensorboard", "checkpoints/iter_000002.pt"):
        assert (split / key).exists(), key
    rows = [json.loads(line) for line in (split / "metrics.jsonl").read_text().splitlines()]
    assert [row["iteration"] for row in rows] == [0, 1, 2, 3, 4]  # 0: the untrained agent's eval
    assert "eval/return" in rows[0] and "eval/return" in rows[-1]

    assert main(["eval", str(split), "--episodes", "2"]) == 0
    traces = np.load(split / "eval" / "traces.npz")
    for key in (
        "desired_position",
        "measured_position",
        "desired_velocity",
        "theta_dot",
        "r_ddot",
        "xi",
        "kappa",
        "hip_height",
        "foot_height",
        "episode_return",
        "hop_height",
        "length",
    ):
        assert key in traces, key
    assert traces["desired_position"].shape[1:] == (2, 2)
    # RUN/eval/ holds eval's own outputs: a second evaluation replaces them; a file the user
    # named is replaced only with --overwrite
    traces_file = split / "eval" / "traces.npz"
    traces_file.write_bytes(b"stale")
    assert main(["eval", str(split), "--episodes", "2"]) == 0
    assert np.load(traces_file)["episode_return"].shape == (2,)
    named = tmp_path / "mine.npz"
    named.write_bytes(b"mine")
    capsys.readouterr()
    assert main(["eval", str(split), "--episodes", "2", "--output", str(named)]) == 2
    assert "--overwrite" in capsys.readouterr().err and named.read_bytes() == b"mine"

    # a checkpoint of another agent is rejected by eval
    assert (
        main(
            [
                "train",
                "--run-dir",
                str(tmp_path / "mlp"),
                "--agent",
                "mlp",
                "--total-steps",
                "16",
                *TINY,
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "eval",
                str(split),
                "--checkpoint",
                str(tmp_path / "mlp" / "checkpoints" / "last.pt"),
                "--output",
                str(tmp_path / "x.npz"),
            ]
        )
        == 2
    )
    assert "agent 'mlp'" in capsys.readouterr().err


def test_nan_loss_exits_with_status_1_and_keeps_the_last_good_checkpoint(tmp_path, capsys):
    from ppo.fake_env import FakeHopperVectorEnv, fake_robot, registered  # tests/ppo

    def make_env(num_envs, env_config, num_threads=None):
        env = FakeHopperVectorEnv(num_envs, env_config)
        env.nan_at_step = 2 * 8 + 3  # in the third iteration's rollout
        return env

    with registered(fake_robot("test-nan", make_env)):  # an env whose rewards turn NaN
        run_dir = tmp_path / "run"
        argv = ["train", "--agent", "mlp", "--robot", "test-nan", "--run-dir", str(run_dir),
                "--total-steps", "96"]  # fmt: skip
        assert main([*argv, *TINY]) == 1
    err = capsys.readouterr().err
    assert "training stopped" in err and "non-finite" in err and "last.pt" in err
    assert load_checkpoint(run_dir / "checkpoints" / "last.pt")["iteration"] == 2


def test_resume_from_a_corrupt_checkpoint_is_a_clear_error_and_changes_nothing(tmp_path, capsys):
    """Every checkpoint unreadable: exit 2 naming each one, nothing written."""
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "32", *TINY]) == 0
    for path in (run_dir / "checkpoints").glob("*.pt"):
        path.write_bytes(path.read_bytes()[:200])
    files = [p for p in run_dir.rglob("*") if p.is_file() and p.name != ".lock"]  # lock: who
    before = {p.name: p.read_bytes() for p in files}
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 2
    err = capsys.readouterr().err
    assert "no usable checkpoint" in err and "last.pt" in err and "iter_000002.pt" in err
    after = {
        p.name: p.read_bytes() for p in run_dir.rglob("*") if p.is_file() and p.name != ".lock"
    }
    assert before == after


def test_resume_recovers_from_a_corrupt_last_checkpoint_and_a_missing_config(tmp_path, capsys):
    """A corrupt last.pt falls back to the newest readable iter_*.pt (saying so), a missing
    config.yaml is rebuilt from the checkpoint, and the result equals the straight run."""
    fixed = ["--set", "ppo.lr_schedule=fixed"]
    straight, run_dir = tmp_path / "straight", tmp_path / "run"
    assert main(["train", "--run-dir", str(straight), "--total-steps", "64", *TINY, *fixed]) == 0
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "32", *TINY, *fixed]) == 0
    last = run_dir / "checkpoints" / "last.pt"
    last.write_bytes(last.read_bytes()[:200])
    (run_dir / "config.yaml").unlink()
    capsys.readouterr()
    argv = ["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64", "--no-progress"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "skipped last.pt" in captured.err and "resuming from iter_000002.pt" in captured.err
    assert "was missing; rebuilt from iter_000002.pt" in captured.out
    a = load_checkpoint(straight / "checkpoints" / "last.pt")
    b = load_checkpoint(run_dir / "checkpoints" / "last.pt")
    for key, value in a["agent_state"].items():
        assert torch.equal(value, b["agent_state"][key]), key


def test_resume_refuses_a_config_edited_since_the_checkpoint(tmp_path, capsys):
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "32", *TINY]) == 0
    path = run_dir / "config.yaml"
    path.write_text(path.read_text().replace("num_epochs: 1", "num_epochs: 4"))
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 2
    err = capsys.readouterr().err
    assert "differs from the config the run was trained with" in err and "ppo.num_epochs" in err


def test_presets_set_values_under_config_flags_and_set_and_are_recorded(tmp_path, capsys):
    from cpg_actor.commands.train import add_arguments, build_config, simulator

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    paper = build_config(parser.parse_args([]))
    assert paper.preset == "paper" and paper.num_envs * paper.ppo.num_steps == 2048
    assert (paper.ppo.num_epochs, paper.ppo.num_minibatches, paper.ppo.max_grad_norm) == (
        10,
        32,
        0.5,
    )
    assert paper.ppo.lr_schedule == "linear" and paper.ppo.normalize_rewards
    # the paper's own init_std, 1 action half-range; the default agent's tuned one is 0.3
    assert (
        build_config(parser.parse_args(["--agent", "cpg-actor-paper"])).agent_config.init_std == 1.0
    )
    assert paper.agent_config.init_std == 0.3
    fast = build_config(parser.parse_args(["--preset", "throughput"]))
    assert fast.preset == "throughput" and fast.num_envs == 256 and fast.ppo.num_minibatches == 4
    gpu = build_config(parser.parse_args(["--preset", "gpu"]))
    assert (gpu.env.sim, gpu.device, gpu.num_envs * gpu.ppo.num_steps) == ("mjx", "auto", 98_304)
    # the CPG at the anymal preset's fixed rate, outside the adaptive schedule
    assert (gpu.ppo.lr_schedule, gpu.ppo.cpg_learning_rate) == ("adaptive", 3e-4)
    assert (fast.ppo.lr_schedule, fast.ppo.learning_rate) == ("adaptive", 1e-3)
    assert fast.ppo.cpg_learning_rate == gpu.ppo.cpg_learning_rate  # the CPG outside it too
    # "anymal", the old name of the quadruped's recipe: the throughput recipe plus the CPG-Actor
    # settings of its results, as its saved runs have it
    anymal = build_config(parser.parse_args(["--preset", "anymal"]))
    spelled = build_config(parser.parse_args(
        ["--preset", "throughput", "--robot", "anymal", "--set", "agent_config.cpg_layout=leg",
         "--set", "agent_config.init_std=0.1",
         "--set", "agent_config.feedback_noise=0.2"]))  # fmt: skip
    assert anymal.robot == "anymal" and type(anymal.env).__name__ == "QuadrupedConfig"
    assert {**anymal.to_dict(), "preset": "throughput"} == spelled.to_dict()
    assert anymal.ppo.cpg_learning_rate == gpu.ppo.cpg_learning_rate
    # --sim: the robot entry's simulators (the quadrupeds have no PyBullet)
    go1 = build_config(parser.parse_args(["--robot", "go1", "--sim", "mjx"]))
    assert go1.env.sim == "mjx" and simulator(go1) == "go1-mjx"
    with pytest.raises(ValueError, match="--sim pybullet: the go1 runs on mujoco, mjx"):
        build_config(parser.parse_args(["--robot", "go1", "--sim", "pybullet"]))
    fast.save(tmp_path / "fast.yaml")
    # the flags and --set win over the preset; a config file brings its preset along
    mixed = build_config(
        parser.parse_args(
            [
                "--config",
                str(tmp_path / "fast.yaml"),
                "--num-envs",
                "8",
                "--set",
                "ppo.num_epochs=3",
            ]
        )
    )
    assert (mixed.preset, mixed.num_envs, mixed.ppo.num_epochs) == ("throughput", 8, 3)
    assert mixed.ppo.num_minibatches == 4
    run_dir = tmp_path / "run"
    argv = ["train", "--run-dir", str(run_dir), "--preset", "throughput", "--total-steps", "32"]
    assert main([*argv, *TINY]) == 0
    assert "throughput preset" in capsys.readouterr().out
    assert TrainConfig.load(run_dir / "config.yaml").preset == "throughput"
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--preset", "paper"]) == 2
    with pytest.raises(SystemExit):
        parser.parse_args(["--preset", "fastest"])
    with pytest.raises(ValueError, match="unknown preset 'fastest'; the recipes are paper, thr"):
        TrainConfig(preset="fastest").validate()


def test_a_robot_alone_trains_with_its_recipe_and_its_agents_tuned_settings():
    """``--robot NAME`` alone: the robot's recipe (``Robot.recipe``) under each agent's tuned
    settings on it (``Robot.agent_defaults``), for every robot of the registry; a recipe
    named on the command line wins over the robot's."""
    from cpg_actor.commands.train import add_arguments, build_config
    from cpg_actor.config.presets import PRESETS

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    go1 = build_config(parser.parse_args(["--robot", "go1"]))  # the Go1's results' settings
    assert (go1.preset, go1.num_envs, go1.ppo.lr_schedule) == ("throughput", 256, "adaptive")
    agent = go1.agent_config
    assert (agent.cpg_layout, agent.init_std, agent.feedback_noise) == ("leg", 0.1, 0.2)
    for name, robot in ROBOTS.items():
        for agent in dict.fromkeys((TrainConfig.agent, "mlp", *robot.agent_defaults)):
            expected = TrainConfig()
            for values in (robot.agent_defaults.get(agent, {}), PRESETS[robot.recipe],
                           {"robot": name, "agent": agent, "preset": robot.recipe}):  # fmt: skip
                apply_dict(expected, dict(values), prefix="")
            argv = ["--robot", name, "--agent", agent, "--set", "ppo.compile=false"]
            expected.ppo.compile = False  # as with no C++ compiler
            assert build_config(parser.parse_args(argv)).to_dict() == expected.to_dict(), name
        paper = build_config(parser.parse_args(["--robot", name, "--preset", "paper"]))
        assert (paper.preset, paper.num_envs) == ("paper", TrainConfig.num_envs)


def test_presets_compile_the_loss_unless_no_cpp_compiler_is_found(monkeypatch, capsys):
    from cpg_actor.commands import train as train_command
    from cpg_actor.ppo import PPO, PPOConfig

    parser = argparse.ArgumentParser()
    train_command.add_arguments(parser)
    assert train_command.build_config(parser.parse_args([])).ppo.compile
    assert not train_command.build_config(
        parser.parse_args(["--set", "ppo.compile=false"])
    ).ppo.compile
    monkeypatch.setattr("cpg_actor.config.train_config.cpp_compiler", lambda: None)
    assert not train_command.build_config(parser.parse_args([])).ppo.compile
    assert "no C++ compiler found" in capsys.readouterr().err
    monkeypatch.setattr("cpg_actor.ppo.algorithm.cpp_compiler", lambda: None)
    with pytest.raises(ValueError, match="needs a C.. compiler .* --set ppo.compile=false"):
        PPO(torch.nn.Linear(2, 2), PPOConfig(compile=True))


def test_init_std_is_in_units_of_the_action_half_range():
    from cpg_actor.agents import AgentConfig, MLPAgent

    agent = MLPAgent(8, [0.9, 0.45], AgentConfig(init_std=1.0), nominal_pose=(0.4, -0.8))
    assert torch.allclose(agent.std(1)[0], torch.tensor([0.9, 0.45]))
    with pytest.raises(ValueError, match="action_scale must be positive"):
        MLPAgent(8, [0.9, 0.0], AgentConfig(), nominal_pose=(0.4, -0.8))


def test_a_second_writer_is_refused_naming_the_holder_and_a_dead_holder_leaves_no_lock(
    tmp_path, capsys
):
    import subprocess
    import sys

    from cpg_actor.training.run_lock import RunLock

    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "32", *TINY]) == 0
    with RunLock(run_dir):  # as if another `cpg-actor train` were writing this run
        assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 2
        err = capsys.readouterr().err
        assert "is in use by process" in err and str(os.getpid()) in err
        assert main(["train", "--run-dir", str(run_dir), "--overwrite", *TINY]) == 2
        assert "is in use" in capsys.readouterr().err
        assert (run_dir / "checkpoints" / "last.pt").is_file()  # --overwrite deleted nothing
    # a holder killed without any clean-up: the operating system drops its lock
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from cpg_actor.training.run_lock import RunLock; "
         f"lock = RunLock({str(run_dir)!r}).acquire(); print('held', flush=True); time.sleep(60)"],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert holder.stdout.readline().strip() == "held"
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 2
    holder.kill()
    holder.wait()
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"]) == 0


def test_a_config_file_accepts_exponents_without_a_dot(tmp_path):
    """YAML 1.1 reads `1e-4` as a string; `--config` takes it as the number it means."""
    path = tmp_path / "c.yaml"
    path.write_text("ppo:\n  learning_rate: 1e-4\n  max_grad_norm: 5E-1\n")
    config = TrainConfig.load(path)
    assert config.ppo.learning_rate == 1e-4 and config.ppo.max_grad_norm == 0.5
    path.write_text("ppo:\n  learning_rate: fast\n")
    with pytest.raises(ValueError, match="ppo.learning_rate must be a number"):
        TrainConfig.load(path)


def test_progress_goes_to_a_log_file_as_plain_lines(tmp_path):
    """With stdout not a terminal (nohup, cluster jobs) train prints a plain progress line
    every --progress-interval seconds and one at the end, not a progress bar at exit."""
    import subprocess
    import sys

    run_dir = tmp_path / "run"
    argv = ["train", "--run-dir", str(run_dir), "--total-steps", "48", "--progress-interval", "0"]
    argv += [a for a in TINY if a != "--no-progress"]
    result = subprocess.run(
        [sys.executable, "-m", "cpg_actor.cli", *argv], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if line.startswith("[train cpg-actor]")]
    assert len(lines) == 3  # one per iteration with interval 0, the last with the evaluation
    assert lines[0].startswith("[train cpg-actor] 16/48 steps (33.3%)")
    # the first iteration includes compiling: no ETA yet; no episode has ended: no return yet
    assert "ETA after warm-up" in lines[0] and "return -" in lines[0]
    assert "ETA after warm-up" not in lines[1] and "ETA 0 s" in lines[-1]
    assert not any("nan" in line for line in lines)
    assert "eval return" in lines[-1] and "48/48 steps (100.0%)" in lines[-1]
    # where the logs are, before training
    assert f"logs: {run_dir / 'metrics.jsonl'}; TensorBoard: tensorboard --logdir" in result.stdout


def test_file_system_errors_are_one_line_and_nothing_is_lost(tmp_path, capsys):
    afile = tmp_path / "notes.txt"
    afile.write_text("keep")
    for run_dir in (afile, afile / "run"):
        code = main(["train", "--run-dir", str(run_dir), "--total-steps", "32", *TINY])
        err = capsys.readouterr().err
        assert code in (1, 2) and err.count("\n") == 1 and "Traceback" not in err, err
    assert afile.read_text() == "keep"


def test_step_counts_not_a_whole_iteration_are_announced(tmp_path, capsys):
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "40", *TINY]) == 0
    out = capsys.readouterr().out
    assert "40 steps is not a whole number of iterations of 16; training 48" in out
    assert "no training episode finished" in out


def test_the_rounding_note_is_for_a_budget_the_user_asked_and_the_logs_are_named(
    tmp_path, capsys, monkeypatch
):
    """The default budget (500,000) is not a whole number of iterations either: it trains the
    same rounded-up steps without a note. The start names metrics.jsonl and TensorBoard."""
    from cpg_actor.training.runner import Runner

    monkeypatch.setattr(Runner, "learn", lambda self, stop_when=None: None)  # only the start
    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), *TINY]) == 0
    out = capsys.readouterr().out
    assert "note:" not in out
    assert "for 500,000 steps (31250 iterations of 16 steps)" in out  # 500,000 / 16: whole
    assert (
        f"logs: {run_dir / 'metrics.jsonl'}; TensorBoard: tensorboard --logdir "
        f"{run_dir / 'tensorboard'}" in out
    )
    other = ["--set", "ppo.num_steps=24"]  # 48 steps per iteration: 500,000 rounds up
    assert main(["train", "--run-dir", str(run_dir), "--overwrite", *TINY, *other]) == 0
    out = capsys.readouterr().out
    assert "note:" not in out and "(10417 iterations of 48 steps)" in out
    assert TrainConfig.load(run_dir / "config.yaml").num_iterations == 10417  # trained as before
    note = "note: 500,000 steps is not a whole number of iterations of 48; training 500,016"
    for asked in (["--set", "total_steps=500000"], ["--total-steps", "500k"]):
        argv = ["train", "--run-dir", str(run_dir), "--overwrite", *TINY, *other, *asked]
        assert main(argv) == 0
        assert note in capsys.readouterr().out


def test_a_resumed_run_leaves_no_step_twice_in_tensorboard(tmp_path, capsys):
    """A run interrupted after logging past its last checkpoint: the resumed run logs those
    steps again; TensorBoard drops the interrupted run's events from there (purge_step), as
    metrics.jsonl is cut back."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run_dir = tmp_path / "run"
    argv = ["train", "--run-dir", str(run_dir), "--total-steps", "64", *TINY]
    assert main([*argv, "--set", "checkpoint_interval=2", "--set", "histogram_interval=1"]) == 0
    checkpoints = run_dir / "checkpoints"
    # the crash: iterations 3 and 4 logged, their checkpoint never written
    os.replace(checkpoints / "iter_000002.pt", checkpoints / "last.pt")
    (checkpoints / "iter_000004.pt").unlink()
    assert main(["train", "--run-dir", str(run_dir), "--resume", "--no-progress"]) == 0
    assert "resuming" in capsys.readouterr().out
    events = EventAccumulator(
        str(run_dir / "tensorboard"), size_guidance={"scalars": 0, "histograms": 0}
    )
    events.Reload()
    tags = events.Tags()["scalars"]
    assert "charts/SPS" in tags and "eval/return" in tags
    for tag in tags:
        steps = [event.step for event in events.Scalars(tag)]
        assert len(steps) == len(set(steps)), (tag, steps)
    assert [event.step for event in events.Scalars("charts/SPS")] == [16, 32, 48, 64]
    assert [event.step for event in events.Scalars("eval/return")] == [0, 64]
    assert [event.step for event in events.Histograms(events.Tags()["histograms"][0])] == [
        16, 32, 48, 64
    ]  # fmt: skip
    rows = [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]
    assert [row["global_step"] for row in rows] == [0, 16, 32, 48, 64]


def test_a_full_disk_or_a_read_only_run_is_one_line_and_keeps_what_was_saved(
    tmp_path, capsys, monkeypatch
):
    """(As root, chmod cannot make a directory read-only: the file-system errors are raised
    where the writes happen.)"""
    import errno

    run_dir = tmp_path / "run"
    assert main(["train", "--run-dir", str(run_dir), "--total-steps", "32", *TINY]) == 0
    saved = load_checkpoint(run_dir / "checkpoints" / "last.pt")
    capsys.readouterr()

    def full_disk(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("cpg_actor.training.checkpoint.atomic_save", full_disk)
    code = main(["train", "--run-dir", str(run_dir), "--resume", "--total-steps", "64"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "no space left on device" in err, err
    kept = load_checkpoint(run_dir / "checkpoints" / "last.pt")
    assert kept["iteration"] == saved["iteration"] == 2

    def read_only(*args, **kwargs):
        raise PermissionError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(np, "savez", read_only)
    code = main(["eval", str(run_dir), "--episodes", "1"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "Read-only file system" in err, err


def test_compose_config_applies_each_layer_in_order(tmp_path):
    """defaults < preset < config file < values (the flags) < each --set, in that order."""
    path = tmp_path / "c.yaml"
    path.write_text("preset: throughput\nseed: 3\nnum_envs: 64\nppo:\n  num_epochs: 7\n")
    config = compose_config(
        config_file=path,
        values={"num_envs": 8, "env": {"sim": "pybullet"}},
        overrides=["ppo.num_epochs=2", "ppo.num_epochs=3"],
    )
    assert config.preset == "throughput" and config.ppo.num_minibatches == 4  # the file's preset
    assert (config.seed, config.num_envs, config.ppo.num_epochs) == (3, 8, 3)
    assert config.env.sim == "pybullet"
    assert compose_config(preset="paper", config_file=path).ppo.num_minibatches == 32
    assert compose_config().preset == "paper"
    with pytest.raises(ValueError, match="unknown config key 'ppo.epochs'"):
        compose_config(overrides=["ppo.epochs=3"])
    with pytest.raises(FileNotFoundError, match="does not exist"):
        compose_config(config_file=tmp_path / "missing.yaml")


def test_compose_config_takes_a_robots_env_keys_before_the_robot():
    """A quadruped's env key given before ``robot=`` (as a variant's settings come before the
    user's): the robot picks the env's config first, whatever the order."""
    config = compose_config(
        "omni", overrides=["env.tracking_sigma=0.25", "robot=go1", "env.tracking_sigma=0.3"]
    )
    assert (config.robot, config.env.tracking_sigma) == ("go1", 0.3)
    with pytest.raises(ValueError, match=r"unknown HopperConfig key\(s\): tracking_sigma"):
        compose_config(overrides=["env.tracking_sigma=0.25"])  # the hopper has no such key


@pytest.mark.parametrize("robot", ["go1", "anymal"])
def test_a_recipe_sets_the_env_of_the_robot_the_flags_name(robot):
    """`--preset gpu --robot go1` trains the Go1 on MJX: the recipe's env values land on the
    named robot's config, not on the default robot's that the robot flag then replaces."""
    config = compose_config("gpu", values={"robot": robot})
    assert (config.robot, config.env.sim, config.num_envs) == (robot, "mjx", 4096)
    assert compose_config("gpu", values={"robot": robot, "env": {"sim": "mujoco"}}).env.sim == (
        "mujoco"  # the flags still come after the recipe
    )


def test_a_config_saved_before_a_field_existed_keeps_what_it_trained_with():
    """Runs saved before ``env.actuator_law`` and ``update_threads`` resume with the drive law
    and update threads they trained with; a new config gets today's defaults."""
    saved = TrainConfig().to_dict()
    del saved["env"]["actuator_law"], saved["update_threads"]
    old = TrainConfig.from_dict(saved)
    assert old.env.actuator_law == "coast" and old.update_threads == old.torch_threads
    new = TrainConfig.from_dict(TrainConfig().to_dict())
    assert new.env.actuator_law == "dc-motor" and new.update_threads is None
    assert compose_config().env.actuator_law == "dc-motor"


def test_sim_mjx_without_jax_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    from cpg_actor.robots.common import mjx_runtime as runtime

    def missing():
        raise runtime.MjxUnavailable(f"{runtime.INSTALL_HINT} (No module named 'jax')")

    monkeypatch.setattr(runtime, "load", missing)
    run_dir = tmp_path / "run"
    argv = ["train", "--sim", "mjx", "--run-dir", str(run_dir), "--total-steps", "64"]
    assert main(argv) == 2
    assert 'pip install -e ".[mjx]"' in capsys.readouterr().err
    # nothing half-made is left to refuse the next try
    assert not run_dir.exists() or not any(run_dir.iterdir())


SPIN_COUNT_AT_TORCH_IMPORT = """
import os, sys
seen = []
class Watch:  # notes GOMP_SPINCOUNT when torch (and with it libgomp) is first imported
    def find_spec(self, name, path=None, target=None):
        if name == "torch" and not seen:
            seen.append(os.environ.get("GOMP_SPINCOUNT"))
sys.meta_path.insert(0, Watch())
import cpg_actor.cli  # (imports no torch: a command's module does, after it)
import torch
print(seen[0] if seen else "torch not imported")
"""


@pytest.mark.parametrize(("given", "expected"), [(None, "2000"), ("50", "50")])
def test_the_cli_shortens_openmp_spinning_before_torch_loads_unless_the_user_set_it(
    given, expected
):
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "GOMP_SPINCOUNT"}
    if given is not None:
        env["GOMP_SPINCOUNT"] = given
    result = subprocess.run(
        [sys.executable, "-c", SPIN_COUNT_AT_TORCH_IMPORT],
        capture_output=True, text=True, env=env, check=True, timeout=120,
    )  # fmt: skip
    assert result.stdout.strip() == expected


def test_sigterm_stops_training_as_ctrl_c_does_and_the_run_resumes(tmp_path, capsys, monkeypatch):
    """A run started in the background by a script ignores SIGINT; SIGTERM stops it the same
    way (the resume hint, exit 143), the run resumes to its end, and the process's own SIGTERM
    handler is back afterwards."""
    import signal

    from cpg_actor.training.runner import Runner

    run = tmp_path / "run"
    args = ["train", "--run-dir", str(run), "--total-steps", "64", *TINY]
    collect = Runner.collect

    def terminated_at_the_third(self):
        if self.iteration == 2:
            os.kill(os.getpid(), signal.SIGTERM)
        return collect(self)

    def ignored(signum, frame):  # the test's own: a missing handler fails, never kills pytest
        pass

    previous = signal.signal(signal.SIGTERM, ignored)
    try:
        monkeypatch.setattr(Runner, "collect", terminated_at_the_third)
        assert main(args) == 143
        assert "--resume" in capsys.readouterr().err
        assert signal.getsignal(signal.SIGTERM) is ignored
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert load_checkpoint(run / "checkpoints" / "last.pt")["iteration"] == 2
    monkeypatch.setattr(Runner, "collect", collect)
    assert main(["train", "--run-dir", str(run), "--resume", "--no-progress"]) == 0
    assert load_checkpoint(run / "checkpoints" / "last.pt")["iteration"] == 4
