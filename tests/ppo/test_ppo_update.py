"""PPO update options: learning-rate schedules, target-KL early stop, loss pieces."""

import pytest
import torch

from cpg_actor.ppo import PPO, PPOConfig, gaussian_kl
from cpg_actor.ppo.algorithm import cpp_compiler

from .fake_env import fake_runner


def collected_runner(**ppo):
    runner = fake_runner("mlp", **ppo)
    runner.collect()
    return runner


def test_adaptive_schedule_moves_the_learning_rate_against_the_kl():
    low = collected_runner(lr_schedule="adaptive", desired_kl=1e-12, min_learning_rate=1e-5)
    low.ppo.update(low.storage)
    assert low.ppo.learning_rate < 3e-4  # KL far above the target: lr / 1.5 per minibatch
    high = collected_runner(lr_schedule="adaptive", desired_kl=10.0, max_learning_rate=1e-2)
    high.ppo.update(high.storage)
    assert high.ppo.learning_rate > 3e-4
    assert high.ppo.optimizer.param_groups[0]["lr"] == high.ppo.learning_rate


def test_the_cpg_learning_rate_stays_fixed_while_the_schedule_moves_the_others():
    """ppo.cpg_learning_rate: the CPG vector V and the feedback MLP in their own Adam group at
    a fixed rate, out of the adaptive (and linear) schedule; the others follow the schedule."""
    runner = fake_runner(
        "cpg-actor", lr_schedule="adaptive", desired_kl=10.0, cpg_learning_rate=1e-4
    )
    runner.collect()
    ppo, vector = runner.ppo, runner.agent.cpg.parametrisation.vector
    others, cpg = ppo.optimizer.param_groups
    feedback = list(runner.agent.feedback.parameters())
    assert cpg["params"] == [vector, *feedback]
    assert not {id(p) for p in others["params"]} & {id(p) for p in cpg["params"]}
    assert len(others["params"]) + len(cpg["params"]) == len(list(runner.agent.parameters()))
    before = vector.detach().clone()
    ppo.update(runner.storage)
    assert ppo.learning_rate > 3e-4 and others["lr"] == ppo.learning_rate  # KL far below
    assert cpg["lr"] == 1e-4
    # Adam moves each entry by about the learning rate per step at most: 6 steps
    assert 0 < (vector - before).abs().max() <= 6 * 1e-4 * 1.01
    ppo.schedule(5, 10)
    assert cpg["lr"] == 1e-4
    runner.close()
    with pytest.raises(ValueError, match="cpg_learning_rate must be a number in"):
        PPOConfig(cpg_learning_rate=0.0).validate()


def test_a_following_cpg_learning_rate_falls_with_the_others_and_never_rises_above_its_own():
    """ppo.cpg_lr_schedule="follow": the CPG group's rate is cpg_learning_rate times
    min(1, lr / learning_rate), after every minibatch of the adaptive rule and at the linear
    schedule's steps."""
    falling = fake_runner(
        "cpg-actor", lr_schedule="adaptive", desired_kl=1e-12, learning_rate=1e-3,
        cpg_learning_rate=1e-4, cpg_lr_schedule="follow",
    )  # fmt: skip
    falling.collect()
    falling.ppo.update(falling.storage)
    others, cpg = falling.ppo.optimizer.param_groups
    assert others["lr"] < 1e-3 / 1.5**5  # KL far above the target at each of the 6 steps
    assert cpg["lr"] == pytest.approx(1e-4 * others["lr"] / 1e-3, rel=1e-12)
    falling.close()
    rising = fake_runner(
        "cpg-actor", lr_schedule="adaptive", desired_kl=10.0, learning_rate=1e-3,
        cpg_learning_rate=1e-4, cpg_lr_schedule="follow",
    )  # fmt: skip
    rising.collect()
    rising.ppo.update(rising.storage)
    others, cpg = rising.ppo.optimizer.param_groups
    assert others["lr"] > 1e-3 and cpg["lr"] == 1e-4
    rising.close()
    linear = fake_runner(
        "cpg-actor", lr_schedule="linear", learning_rate=1e-3, cpg_learning_rate=1e-4,
        cpg_lr_schedule="follow",
    )  # fmt: skip
    linear.ppo.schedule(3, 4)
    assert linear.ppo.optimizer.param_groups[1]["lr"] == pytest.approx(2.5e-5, rel=1e-12)
    linear.close()
    with pytest.raises(ValueError, match="cpg_lr_schedule=follow needs ppo.cpg_learning_rate"):
        PPOConfig(cpg_lr_schedule="follow").validate()
    with pytest.raises(ValueError, match="cpg_lr_schedule must be one of"):
        PPOConfig(cpg_learning_rate=1e-4, cpg_lr_schedule="decay").validate()


def test_linear_schedule_decays_to_zero_and_fixed_stays():
    ppo = PPO(torch.nn.Linear(2, 2), PPOConfig(lr_schedule="linear", learning_rate=1e-3))
    ppo.schedule(5, 10)
    assert ppo.learning_rate == pytest.approx(5e-4)
    fixed = PPO(torch.nn.Linear(2, 2), PPOConfig(lr_schedule="fixed", learning_rate=1e-3))
    fixed.schedule(5, 10)
    assert fixed.learning_rate == 1e-3


def test_target_kl_stops_the_epochs_early():
    runner = collected_runner(target_kl=1e-12)
    stats = runner.ppo.update(runner.storage)
    assert stats["early_stop"] == 1.0
    assert stats["num_minibatch_updates"] < 3 * 2
    runner = collected_runner()
    assert runner.ppo.update(runner.storage)["num_minibatch_updates"] == 3 * 2


def test_gaussian_kl_matches_torch():
    mu0, s0, mu1, s1 = (
        torch.randn(5, 2),
        torch.rand(5, 2) + 0.1,
        torch.randn(5, 2),
        torch.rand(5, 2) + 0.1,
    )
    expected = torch.distributions.kl_divergence(
        torch.distributions.Normal(mu0, s0), torch.distributions.Normal(mu1, s1)
    ).sum(-1)
    torch.testing.assert_close(gaussian_kl(mu0, s0, mu1, s1), expected)


def test_invalid_ppo_values_are_rejected():
    for bad in ({"gamma": 1.5}, {"num_epochs": 0}, {"lr_schedule": "cosine"}, {"clip_ratio": 0}):
        with pytest.raises(ValueError, match="ppo"):
            PPOConfig(**bad).validate()


def test_an_update_that_breaks_the_policy_is_undone_and_raises():
    """A finite loss with a huge learning rate (1e6) makes the policy non-finite: the update
    raises and every parameter is back to its value before the update, all finite."""
    from cpg_actor.ppo import NonFiniteLossError

    runner = collected_runner(learning_rate=1e6)
    before = {k: v.clone() for k, v in runner.agent.state_dict().items()}
    with pytest.raises(NonFiniteLossError, match="non-finite.*undone"):
        runner.ppo.update(runner.storage)
    for key, value in runner.agent.state_dict().items():
        assert torch.equal(value, before[key]), key
        assert torch.isfinite(value).all(), key


@pytest.mark.parametrize("key", ["learning_rate", "max_grad_norm", "gamma", "entropy_coef"])
def test_non_finite_numbers_are_refused(key):
    from cpg_actor.ppo import PPOConfig

    with pytest.raises(ValueError, match=f"ppo.{key} must be finite"):
        PPOConfig(**{key: float("inf")}).validate()
    with pytest.raises(ValueError, match=f"ppo.{key} must be"):
        PPOConfig(**{key: float("nan")}).validate()


def test_gaussian_formulas_match_torch_distributions():
    from cpg_actor.agents.base import gaussian_entropy, gaussian_log_prob

    mean, std, value = torch.randn(6, 2), torch.rand(6, 2) + 0.1, torch.randn(6, 2)
    normal = torch.distributions.Normal(mean, std)
    assert torch.allclose(gaussian_log_prob(value, mean, std), normal.log_prob(value))
    assert torch.allclose(gaussian_entropy(std), normal.entropy())


@pytest.mark.skipif(
    cpp_compiler() is None,
    reason="torch.compile's CPU backend needs a C++ compiler",
)
def test_compiled_loss_equals_the_eager_loss_and_its_gradients():
    from cpg_actor.ppo.algorithm import ppo_loss

    runner = fake_runner("cpg-actor", num_epochs=1)
    config = runner.config
    runner.collect()
    batch = next(runner.storage.minibatches(2))
    compiled = torch.compile(ppo_loss)
    results = []
    for loss_fn in (ppo_loss, compiled):
        runner.agent.zero_grad()
        loss, stats = loss_fn(runner.agent, batch, config.ppo)
        loss.backward()
        grads = [p.grad.clone() for p in runner.agent.parameters() if p.grad is not None]
        results.append((loss.detach(), stats, grads))
    (loss0, stats0, grads0), (loss1, stats1, grads1) = results
    assert len(grads0) == len(grads1) > 0
    assert torch.allclose(loss0, loss1, rtol=1e-5, atol=1e-6)
    assert torch.allclose(stats0, stats1, rtol=1e-4, atol=1e-6)
    for g0, g1 in zip(grads0, grads1, strict=True):
        assert torch.allclose(g0, g1, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize(
    "compile",
    [
        False,
        pytest.param(
            True,
            marks=pytest.mark.skipif(
                cpp_compiler() is None,
                reason="torch.compile's CPU backend needs a C++ compiler",
            ),
        ),
    ],
)
def test_the_output_check_after_an_update_finds_a_single_bad_row(compile):
    """``ppo.compile`` compiles the check too: it still sees one non-finite row among many."""
    runner = fake_runner("cpg-actor", num_epochs=1, compile=compile)
    runner.collect()
    storage, ppo = runner.storage, runner.ppo
    assert ppo._outputs_are_finite(storage)
    for field in ("observations", "states"):
        stored = getattr(storage, field)
        good = stored[7, 2].clone()
        stored[7, 2] = float("nan")
        assert not ppo._outputs_are_finite(storage), field
        stored[7, 2] = good
        assert ppo._outputs_are_finite(storage)
