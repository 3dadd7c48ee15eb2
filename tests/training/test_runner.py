"""Runner: reproducibility, exact resume, checkpoint validation, NaN handling (fake env)."""

import json

import pytest
import torch

from cpg_actor.config import TrainConfig
from cpg_actor.ppo import PPO, PPOConfig
from cpg_actor.training.checkpoint import load_checkpoint
from cpg_actor.training.runner import Runner, TrainingDiverged
from cpg_actor.training.threads import update_threads
from ppo.fake_env import FakeConfig, FakeHopperVectorEnv

NUM_ENVS, NUM_STEPS = 4, 16


def config(iterations, agent="cpg-actor", seed=3, interval=2, eval_interval=0, **ppo):
    return TrainConfig(
        agent=agent,
        seed=seed,
        num_envs=NUM_ENVS,
        total_steps=iterations * NUM_ENVS * NUM_STEPS,
        checkpoint_interval=interval,
        eval_interval=eval_interval,
        eval_episodes=3,
        ppo=PPOConfig(num_steps=NUM_STEPS, num_epochs=2, num_minibatches=2, **ppo),
        env=FakeConfig(episode_steps=11, fall_probability=0.05),
    )


def runner(cfg, run_dir=None, env=None):
    return Runner(
        cfg,
        run_dir,
        env=env or FakeHopperVectorEnv(cfg.num_envs, cfg.env),
        eval_env=FakeHopperVectorEnv(cfg.eval_episodes, cfg.env),
        tensorboard=False,
    )


def params(r):
    return {k: v.clone() for k, v in {**r.agent.state_dict(), **r.normalizer.state_dict()}.items()}


def assert_same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        assert torch.equal(a[k], b[k]), k


def test_same_seed_gives_identical_numbers_and_other_seed_differs():
    runs = []
    for seed in (3, 3, 4):
        r = runner(config(3, seed=seed))
        r.learn()
        runs.append((params(r), r.last_row))
    assert_same(runs[0][0], runs[1][0])
    assert runs[0][1]["losses/policy_loss"] == runs[1][1]["losses/policy_loss"]
    assert not torch.equal(runs[0][0]["log_std"], runs[2][0]["log_std"])


@pytest.mark.slow
def test_update_on_several_threads_is_reproducible():
    """Large minibatches update on every usable core (the simulator is idle then), compiled:
    the same seed still gives the same numbers, and the rollout is back on torch_threads."""
    runs = []
    for _ in range(2):
        cfg = TrainConfig(
            agent="cpg-actor", seed=5, num_envs=8, total_steps=2 * 8 * 256, eval_interval=0,
            ppo=PPOConfig(num_steps=256, num_epochs=2, num_minibatches=2, compile=True),
            env=FakeConfig(episode_steps=40, fall_probability=0.02), update_threads=2,
        )  # fmt: skip
        r = runner(cfg)
        assert update_threads(r.config) == 2
        r.learn()
        assert torch.get_num_threads() == cfg.torch_threads
        runs.append(params(r))
    assert_same(runs[0], runs[1])
    auto = config(1)  # minibatches of 32 samples: the update stays on torch_threads
    assert update_threads(auto) == auto.torch_threads
    with pytest.raises(ValueError, match=r"update_threads \(or null: automatic\) must be"):
        TrainConfig(update_threads=0).validate()


def test_compiled_calls_skip_their_guard_checks_once_built_and_train_the_same(tmp_path):
    """ppo.skip_guard_checks: after a runner's first iteration its compiled calls (policy
    step, reward scaling, gradient step, output check) no longer check dynamo's guards. The
    same compiled code runs, so a run trains the same numbers as one that checks them, with
    episodes ending, evaluations and checkpoints in between. A new compiled PPO in the
    process (dynamo forgets every compiled function) makes the runner build and check them
    again for one iteration; forgotten behind its back, the next call is a clear error."""
    fast = runner(config(4, eval_interval=2, compile=True), tmp_path / "fast")
    assert not fast.compile_stance.skips_guard_checks  # nothing built yet
    fast.learn()
    assert fast.compile_stance.skips_guard_checks
    fast_params, fast_row = params(fast), fast.last_row

    checked = runner(config(4, eval_interval=2, compile=True, skip_guard_checks=False),
                     tmp_path / "checked")  # fmt: skip
    assert not fast.compile_stance.skips_guard_checks  # its compiled functions were forgotten
    checked.learn()
    assert not checked.compile_stance.skips_guard_checks
    assert_same(fast_params, params(checked))
    assert fast_row["losses/policy_loss"] == checked.last_row["losses/policy_loss"]

    fast.collect()  # built again, guards checked
    fast.update()
    assert fast.compile_stance.skips_guard_checks
    torch.compiler.reset()  # behind the runner's back: its next call finds nothing built
    with pytest.raises(RuntimeError, match="train with --set ppo.skip_guard_checks=false"):
        fast.collect()
    PPO(fast.agent, PPOConfig(compile=True))
    assert not fast.compile_stance.skips_guard_checks
    eager = runner(config(1))
    eager.learn()
    assert not eager.compile_stance.skips_guard_checks  # nothing compiled


@pytest.mark.parametrize("agent", ["cpg-actor", "mlp"])
def test_resume_after_a_kill_equals_uninterrupted_run(tmp_path, agent):
    """Killed in iteration 4 (after the checkpoint at 2), resumed from that checkpoint: the
    same parameters, optimiser, learning rate (linear decay), reward and observation
    normalisers and evaluations as the run that was never interrupted."""
    straight = runner(config(6, agent=agent, eval_interval=2), tmp_path / "straight")
    straight.learn()

    env = FakeHopperVectorEnv(NUM_ENVS, config(6).env)
    env.interrupt_at_step = 3 * NUM_STEPS + 5
    killed = runner(config(6, agent=agent, eval_interval=2), tmp_path / "split", env=env)
    with pytest.raises(KeyboardInterrupt):
        killed.learn()
    resumed = runner(config(6, agent=agent, eval_interval=2), tmp_path / "split")
    resumed.load_checkpoint(tmp_path / "split" / "checkpoints" / "last.pt")
    assert resumed.iteration == 2
    resumed.learn()

    assert straight.config.ppo.lr_schedule == "linear"
    assert straight.config.ppo.normalize_rewards
    assert_same(params(straight), params(resumed))
    assert_same(straight.reward_normalizer.state_dict(), resumed.reward_normalizer.state_dict())
    assert straight.ppo.learning_rate == resumed.ppo.learning_rate
    assert straight.last_evaluation["eval/return"] == resumed.last_evaluation["eval/return"]
    opt_a = straight.ppo.optimizer.state_dict()["state"]
    opt_b = resumed.ppo.optimizer.state_dict()["state"]
    for k in opt_a:
        assert torch.equal(opt_a[k]["exp_avg"], opt_b[k]["exp_avg"])
    ckpt = load_checkpoint(tmp_path / "split" / "checkpoints" / "last.pt")
    assert ckpt["iteration"] == 6 and ckpt["global_step"] == 6 * NUM_ENVS * NUM_STEPS


def test_evaluation_during_training_changes_nothing_that_is_trained(tmp_path):
    """The same run with an evaluation after every iteration and with none: identical
    parameters, normalisers, losses and training returns."""
    with_eval = runner(config(4, eval_interval=1), tmp_path / "with")
    with_eval.learn()
    without = runner(config(4, eval_interval=0))
    without.learn()
    assert_same(params(with_eval), params(without))
    for key in ("losses/policy_loss", "charts/episode_return"):
        assert with_eval.last_row[key] == without.last_row[key]
    rows = [
        json.loads(line) for line in (tmp_path / "with" / "metrics.jsonl").read_text().splitlines()
    ]
    evaluated = [row["iteration"] for row in rows if "eval/return" in row]
    assert evaluated == [0, 1, 2, 3, 4]
    assert all(row["eval/hop_height"] >= 0 for row in rows if "eval/return" in row)
    assert "eval/return" not in without.last_row


def test_linear_schedule_decays_the_learning_rate_to_zero_over_the_run():
    r = runner(config(4))
    r.learn()
    lr = r.config.ppo.learning_rate
    assert r.last_row["charts/learning_rate"] == pytest.approx(lr / 4)  # the last iteration's
    fixed = runner(config(4, lr_schedule="fixed"))
    fixed.learn()
    assert fixed.last_row["charts/learning_rate"] == lr


def test_a_custom_env_without_eval_env_needs_evaluation_off():
    cfg = config(1, eval_interval=1)
    with pytest.raises(ValueError, match="eval_env"):
        Runner(cfg, env=FakeHopperVectorEnv(cfg.num_envs, cfg.env), tensorboard=False)


def test_checkpoint_from_another_agent_and_corrupt_files_are_rejected(tmp_path):
    r = runner(config(2, agent="mlp"), tmp_path / "mlp")
    r.learn()
    path = tmp_path / "mlp" / "checkpoints" / "last.pt"
    other = runner(config(2, agent="cpg-actor"))
    with pytest.raises(ValueError, match="agent 'mlp'"):
        other.load_checkpoint(path)
    corrupt = tmp_path / "corrupt.pt"
    corrupt.write_bytes(path.read_bytes()[:100])
    with pytest.raises(ValueError, match="corrupt"):
        load_checkpoint(corrupt)
    garbage = tmp_path / "garbage.pt"
    garbage.write_text("not a checkpoint")
    with pytest.raises(ValueError, match="corrupt or not"):
        load_checkpoint(garbage)
    with pytest.raises(FileNotFoundError):
        load_checkpoint(tmp_path / "missing.pt")
    wrong = tmp_path / "wrong.pt"
    torch.save({"weights": torch.zeros(2)}, wrong)
    with pytest.raises(ValueError, match="not a cpg-actor checkpoint"):
        load_checkpoint(wrong)


def test_nan_loss_stops_the_run_and_keeps_the_last_good_checkpoint(tmp_path):
    cfg = config(6, interval=2)
    env = FakeHopperVectorEnv(cfg.num_envs, cfg.env)
    env.nan_at_step = 3 * NUM_STEPS + 5  # during the 4th iteration's rollout
    r = runner(cfg, tmp_path / "run", env=env)
    with pytest.raises(TrainingDiverged, match="non-finite") as info:
        r.learn()
    assert "last.pt" in str(info.value)
    ckpt = load_checkpoint(tmp_path / "run" / "checkpoints" / "last.pt")
    assert ckpt["iteration"] == 2
    for value in ckpt["agent_state"].values():
        assert torch.isfinite(value).all()
    assert not (tmp_path / "run" / "checkpoints" / "iter_000004.pt").exists()


def test_metrics_are_written_per_iteration(tmp_path):
    r = runner(config(2), tmp_path / "run")
    r.learn()
    lines = (tmp_path / "run" / "metrics.jsonl").read_text().splitlines()
    assert len(lines) == 2

    row = json.loads(lines[-1])
    for key in (
        "charts/episode_return",
        "charts/hop_height",
        "losses/approx_kl",
        "losses/clipfrac",
        "losses/explained_variance",
        "cpg/nu_HFE",
        "cpg/phi_HFE_KFE",
        "reward_terms/r1",
        "time/simulation",
        "time/learning",
        "time/train_wall",
        "policy/log_std_0",
    ):
        assert key in row, key
