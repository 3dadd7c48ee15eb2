"""The CPG-Actor beyond the paper: exploration in the CPG's terms (``exploration="cpg"``),
the command inside the joint range (``output_bound``), its start gait, and the per-agent
defaults that make these the ``cpg-actor`` agent's settings."""

import math

import pytest
import torch

from cpg_actor.agents import AgentConfig, CPGActorAgent
from cpg_actor.agents.start_gait import read_gait, start_parameters
from cpg_actor.config import compose_config
from cpg_actor.cpg import CPGState
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import robot_spec
from cpg_actor.robots.registry import get_robot

HOPPER = robot_spec(HopperConfig())
ROBOT = get_robot("hopper")
SCALE = [0.9, 0.9]


def agent(**fields) -> CPGActorAgent:
    torch.manual_seed(0)
    return CPGActorAgent(8, SCALE, AgentConfig(**fields), HOPPER, ROBOT)


def test_cpg_exploration_scores_exactly_the_sampled_feedback_and_vector():
    """log pi = sum log N(u; MLP(obs), s_u) + sum log N(V_t; V, s_V), by hand with
    torch.distributions; the command is the CPG's output for the sample, not sampled."""
    a = agent(exploration="cpg", feedback_std=0.4, cpg_noise=0.05, std_floor=0.1)
    obs, state = torch.randn(5, 8), a.initial_state(5)
    step = a.act(obs, state)
    n, m = 2, a.cpg.parametrisation.num_parameters
    assert step.action.shape == (5, 2 + 2 * n + m) == (5, a.sample_dim)
    u, v = step.action[:, 2 : 2 + 2 * n], step.action[:, 2 + 2 * n :]
    with torch.no_grad():
        expected = torch.distributions.Normal(a.feedback(obs), 0.4).log_prob(u).sum(
            -1
        ) + torch.distributions.Normal(a.cpg.parametrisation.vector, 0.05).log_prob(v).sum(-1)
        torch.testing.assert_close(step.log_prob, expected)
        # the command: the CPG stepped with the sampled feedback and parameters
        xi = 4.0 * torch.tanh(u[:, :n])
        kappa = 25.0 * torch.tanh(u[:, n:])  # kappa_scale: no output bound here
        output, _ = a.cpg(CPGState.from_tensor(state), 0.0, xi, kappa, v)
        torch.testing.assert_close(step.action[:, :2], a.joint_map(output.position))
        # the PPO update's replay scores the stored sample the same way
        log_prob, entropy, _, mean, std = a.evaluate(obs, state, step.action)
    torch.testing.assert_close(log_prob, step.log_prob)
    torch.testing.assert_close(mean, step.mean)
    # the command's entries carry N(0, 1) in every step: no KL from what is not sampled
    assert torch.equal(step.mean[:, :2], torch.zeros(5, 2))
    assert torch.equal(step.std[:, :2], torch.ones(5, 2))
    hand_entropy = 2 * n * (0.5 + 0.5 * math.log(2 * math.pi) + math.log(0.4)) + m * (
        0.5 + 0.5 * math.log(2 * math.pi) + math.log(0.05)
    )
    torch.testing.assert_close(entropy, torch.full((5,), hand_entropy))


def test_cpg_exploration_gives_the_cpg_vector_and_the_feedback_a_likelihood_gradient():
    a = agent(exploration="cpg")
    obs, state = torch.randn(6, 8), a.initial_state(6)
    step = a.act(obs, state)
    log_prob = a.evaluate(obs, state, step.action)[0]
    log_prob.sum().backward()
    assert a.cpg.parametrisation.vector.grad.abs().sum() > 0
    assert a.feedback[-1].weight.grad.abs().sum() > 0
    assert a.log_std.grad is None  # the command is not sampled: its std is unused


def test_deterministic_cpg_exploration_is_the_mean_and_the_std_has_a_floor():
    a = agent(exploration="cpg", feedback_std=0.5, cpg_noise=0.05, std_floor=0.1)
    obs, state = torch.randn(3, 8), a.initial_state(3)
    step = a.act(obs, state, deterministic=True)
    torch.testing.assert_close(step.action[:, :2], a.actor(obs, state).mean)
    with torch.no_grad():
        a.latent_log_std.fill_(-50.0)
        a.vector_log_std.fill_(-50.0)
    latent, vector = a.exploration_stds()
    torch.testing.assert_close(latent, torch.full((4,), 0.05))
    torch.testing.assert_close(vector, torch.full((vector.numel(),), 0.005))


def test_the_position_noise_std_has_a_floor_only_when_asked():
    """action_std_floor: std = floor + exp(log_std), the floor a fraction of init_std in the
    action's units; starting at init_std either way, and scored with that std."""
    floored, plain = agent(init_std=0.3, action_std_floor=0.1), agent(init_std=0.3)
    scale = torch.tensor(SCALE)
    for a in (floored, plain):
        torch.testing.assert_close(a.std(1)[0], 0.3 * scale)
    with torch.no_grad():
        floored.log_std.fill_(-50.0)
        plain.log_std.fill_(-50.0)
    torch.testing.assert_close(floored.std(2), (0.03 * scale).expand(2, 2))
    assert float(plain.std(1).detach().max()) < 1e-20
    logged = floored.log_scalars()
    assert logged["policy/log_std_0"] == pytest.approx(math.log(0.03 * 0.9), rel=1e-5)
    obs, state = torch.randn(4, 8), floored.initial_state(4)
    step = floored.act(obs, state)
    expected = torch.distributions.Normal(step.mean, 0.03 * scale).log_prob(step.action).sum(-1)
    torch.testing.assert_close(step.log_prob, expected)
    with pytest.raises(ValueError, match="action_std_floor must be in"):
        AgentConfig(action_std_floor=1.0).validate()


def test_the_bounded_command_stays_inside_the_joint_range_whatever_v_and_the_feedback():
    """output_bound: rho < half-range - kappa_bound, a bounded, kappa in radians of
    amplitude: 2,000 steps with V pushed to extremes and the feedback at its bounds
    (switching every step, the worst case for the amplitude's dynamics) never leave the
    joint range; the unbounded (paper) CPG-Actor does."""
    low = torch.tensor(HOPPER.action_low)
    high = torch.tensor(HOPPER.action_high)

    def worst_command(bound: bool) -> float:
        a = agent(output_bound=bound)
        with torch.no_grad():
            vector = a.cpg.parametrisation.vector
            vector.copy_(torch.where(torch.arange(vector.numel()) % 2 == 0, 8.0, -8.0))
            for field in ("amplitude", "convergence"):
                vector[a.cpg.parametrisation.indices(field)] = 8.0
            state = a.initial_state(4)
            excess = 0.0
            for t in range(2000):
                sign = 1.0 if t % 2 == 0 else -1.0
                latent = torch.full((4, 4), 20.0 * sign)
                feedback = a.feedback_from_latent(latent)
                out = a.actor(torch.zeros(4, 8), state, feedback)
                state = out.next_state
                excess = max(excess, float((out.mean - high).max()), float((low - out.mean).max()))
        return excess

    assert worst_command(True) <= 0.0
    assert worst_command(False) > 0.1


def test_kappa_is_bounded_in_radians_of_amplitude_change():
    """The steady state of the amplitude under a constant kappa is rho + 4 kappa / a^2:
    with the bound, a saturated feedback moves it by kappa_bound rad, whatever a is."""
    for convergence in (5.0, 20.0, 60.0):
        a = agent(output_bound=True, kappa_bound=0.15, cpg_initial={"convergence": convergence})
        with torch.no_grad():
            state = a.initial_state(1)
            latent = torch.tensor([[0.0, 0.0, 30.0, 30.0]])  # kappa at its bound
            for _ in range(3000):
                state = a.actor(torch.zeros(1, 8), state, a.feedback_from_latent(latent)).next_state
            rho = a.cpg.parametrisation.values()["amplitude"]
        torch.testing.assert_close(state[0, 2], rho + 0.15, rtol=2e-3, atol=0)


def test_the_packaged_start_gait_is_where_the_cpg_starts(tmp_path):
    gait = start_parameters("search", ROBOT)
    a = agent(start_gait="search", output_bound=True)
    values = a.cpg.parametrisation.values()
    torch.testing.assert_close(
        values["frequency"].detach(), torch.tensor(gait["frequency"], dtype=torch.float32)
    )
    torch.testing.assert_close(
        values["amplitude"].detach(), torch.tensor(gait["amplitude"], dtype=torch.float32)
    )
    # a gait file of the user's, overridden entry by entry by cpg_initial
    path = tmp_path / "gait.yaml"
    path.write_text(
        "robot: hopper\nfitness: 1.0\nsteps: 0\nseed: 0\n"
        "cpg_initial:\n  frequency: [1.2, 1.2]\n  amplitude: [0.3, 0.4]\n  convergence: 20.0\n"
    )
    b = agent(start_gait=str(path), cpg_initial={"amplitude": [0.2, 0.25]})
    values = b.cpg.parametrisation.values()
    assert values["frequency"].tolist() == pytest.approx([1.2, 1.2])
    assert values["amplitude"].tolist() == pytest.approx([0.2, 0.25])


def test_a_missing_or_bad_gait_file_is_refused_with_one_clear_line(tmp_path):
    with pytest.raises(ValueError, match="does not exist .agent_config.start_gait"):
        read_gait(tmp_path / "gait.yaml")
    (tmp_path / "gait.yaml").write_text("robot: hopper\n")
    with pytest.raises(ValueError, match="lacks fitness"):
        read_gait(tmp_path / "gait.yaml")


def test_cpg_actor_trains_with_its_tuned_defaults_and_cpg_actor_paper_as_the_paper():
    best = compose_config(values={"agent": "cpg-actor"})
    paper = compose_config(values={"agent": "cpg-actor-paper"})
    assert best.agent_config.output_bound and best.agent_config.start_gait == "search"
    assert (best.agent_config.exploration, best.agent_config.init_std) == ("position", 0.3)
    assert best.agent_config.action_std_floor == 0.1 and paper.agent_config.action_std_floor == 0
    assert best.ppo.bptt_steps == 8
    mlp = compose_config(values={"agent": "mlp"})
    assert (mlp.agent_config.init_std, mlp.agent_config.action_std_floor) == (0.3, 0.1)
    assert paper.agent_config.exploration == "position" and not paper.agent_config.output_bound
    assert paper.agent_config.start_gait == "" and paper.ppo.bptt_steps == 1
    # the command line wins over an agent's defaults, and the quadruped gets none of them
    mine = compose_config(values={"agent": "cpg-actor"}, overrides=["ppo.bptt_steps=1"])
    assert mine.ppo.bptt_steps == 1
    quadruped = compose_config(preset="anymal", values={"agent": "cpg-actor"})
    assert quadruped.agent_config.start_gait == "" and not quadruped.agent_config.output_bound


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"exploration": "joint"}, "exploration must be one of"),
        ({"std_floor": 1.0}, "std_floor must be in"),
        ({"convergence_bounds": (5.0, 2.0)}, "convergence_bounds must be"),
        ({"exploration": "cpg", "feedback_noise": 0.1}, "set it to 0"),
        ({"kappa_bound": 0.0}, "kappa_bound must be a finite number > 0"),
    ],
)
def test_bad_exploration_and_bound_settings_are_refused(fields, message):
    with pytest.raises(ValueError, match=message):
        AgentConfig(**fields).validate()


def test_a_kappa_bound_wider_than_the_joint_range_is_refused():
    with pytest.raises(ValueError, match="leaves no amplitude"):
        agent(output_bound=True, kappa_bound=1.0)


def test_the_k_step_gradient_matches_finite_differences():
    """d/dV of a function of the state after k replayed CPG steps (float64), against central
    differences: the gradient ppo.bptt_steps gives is the true one of the k-step map."""
    torch.manual_seed(0)
    a = CPGActorAgent(8, SCALE, AgentConfig(), HOPPER, ROBOT).double()
    obs = torch.randn(6, 3, 8, dtype=torch.float64)
    state0 = a.initial_state(3).double()
    with torch.no_grad():  # a state in mid-gait
        for t in range(40):
            state0 = a.actor(obs[t % 6], state0).next_state

    def objective() -> torch.Tensor:
        state = state0
        for t in range(6):
            state = a.actor(obs[t], state).next_state
        return (torch.sin(state[:, 0]) * state[:, 2]).sum() + a.actor(obs[0], state).mean.sum()

    vector = a.cpg.parametrisation.vector
    (grad,) = torch.autograd.grad(objective(), vector)
    numeric = torch.zeros_like(grad)
    h = 1e-6
    for k in range(vector.numel()):
        with torch.no_grad():
            vector[k] += h
            up = objective()
            vector[k] -= 2 * h
            down = objective()
            vector[k] += h
        numeric[k] = (up - down) / (2 * h)
    torch.testing.assert_close(grad, numeric, rtol=1e-5, atol=1e-7 * float(numeric.abs().max()))
