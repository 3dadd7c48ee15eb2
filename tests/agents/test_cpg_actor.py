"""The CPG-Actor's state handling (paper III-B) and end-to-end gradient flow."""

import pytest
import torch

from cpg_actor.agents import AgentConfig, CPGActorAgent, MLPAgent, get_agent_spec
from cpg_actor.config import TrainConfig
from cpg_actor.cpg import CPGState
from cpg_actor.ppo import PPOConfig
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.env import robot_spec
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.runner import Runner

# tests/ppo/fake_env.py: pytest puts tests/ on sys.path (tests/ is not a package)
from ppo.fake_env import FakeConfig, FakeHopperVectorEnv, fake_robot, registered  # noqa: I001

HOPPER = robot_spec(HopperConfig())  # the robot the CPG-Actor is built for
ROBOT = get_robot("hopper")  # its registry entry: the CPG layouts and the start gait


def make_runner(agent="cpg-actor", num_envs=6, num_steps=32, seed=0, **env_kwargs):
    env_config = FakeConfig(**env_kwargs)
    config = TrainConfig(
        agent=agent,
        seed=seed,
        num_envs=num_envs,
        total_steps=num_envs * num_steps * 2,
        ppo=PPOConfig(num_steps=num_steps, num_epochs=2, num_minibatches=2),
        env=env_config,
        eval_interval=0,
    )
    return Runner(config, env=FakeHopperVectorEnv(num_envs, env_config))


@pytest.mark.parametrize("agent", ["cpg-actor", "cpg-actor-open-loop", "mlp"])
def test_replaying_stored_state_reproduces_rollout_log_probs(agent):
    runner = make_runner(agent)
    runner.start_episodes()
    runner.collect()
    s = runner.storage
    with torch.no_grad():
        for t in range(s.num_steps):  # same batch as during the rollout: bit-exact
            log_prob, _, value, mean, _ = runner.agent.evaluate(
                s.observations[t], s.states[t], s.actions[t]
            )
            assert torch.equal(log_prob, s.log_probs[t])
            assert torch.equal(value, s.values[t])
            assert torch.equal(mean, s.action_mean[t])
        # the update's flattened minibatches agree to float32 rounding of the log-probabilities'
        # magnitude (another batch shape, another summation order)
        log_prob, *_ = runner.agent.evaluate(
            s.observations.flatten(0, 1), s.states.flatten(0, 1), s.actions.flatten(0, 1)
        )
    scale = s.log_probs.abs().max().item()
    torch.testing.assert_close(log_prob, s.log_probs.flatten(), rtol=1e-5, atol=1e-5 * scale)


def test_cpg_state_is_reset_for_the_env_that_ended_only():
    runner = make_runner("cpg-actor", num_envs=6, episode_steps=7, fall_probability=0.05)
    runner.start_episodes()
    runner.collect()
    s = runner.storage
    agent = runner.agent
    initial = agent.initial_state(1)[0]
    done = torch.maximum(s.terminated, s.truncated).bool()
    seen_mixed = False
    with torch.no_grad():
        for t in range(s.num_steps - 1):
            stepped = agent.actor(s.observations[t], s.states[t]).next_state
            for i in range(s.num_envs):
                if done[t, i]:
                    assert torch.equal(s.states[t + 1, i], initial)
                else:
                    assert torch.equal(s.states[t + 1, i], stepped[i])
                    assert not torch.equal(s.states[t + 1, i], initial)
            seen_mixed |= bool(done[t].any() and not done[t].all())
    assert seen_mixed, "the test needs steps where some envs end and others continue"
    assert torch.equal(s.states[0], agent.initial_state(s.num_envs))


def test_update_changes_cpg_parameters_and_feedback_output_layer():
    runner = make_runner("cpg-actor")
    agent = runner.agent
    cpg_before = agent.cpg.parametrisation.vector.detach().clone()
    values_before = {k: v.detach().clone() for k, v in agent.cpg.parametrisation.values().items()}
    out_w = agent.feedback[-1].weight.detach().clone()
    out_b = agent.feedback[-1].bias.detach().clone()
    runner.start_episodes()
    runner.collect()
    normalizer = {k: v.clone() for k, v in runner.normalizer.state_dict().items()}
    runner.ppo.update(runner.storage)
    for key, value in runner.normalizer.state_dict().items():  # frozen during the update
        assert torch.equal(value, normalizer[key])
    assert not torch.equal(agent.cpg.parametrisation.vector.detach(), cpg_before)
    after = agent.cpg.parametrisation.values()
    for field in ("frequency", "amplitude", "convergence"):  # every oscillator's nu, rho, a
        assert (after[field].detach() - values_before[field]).abs().min() > 0, field
    assert not torch.equal(agent.feedback[-1].weight.detach(), out_w)
    assert not torch.equal(agent.feedback[-1].bias.detach(), out_b)


def test_gradient_reaches_cpg_and_feedback_from_one_replayed_step():
    agent = CPGActorAgent(8, [0.9, 0.9], AgentConfig(), HOPPER, ROBOT)
    state = agent.cpg.initial_state(4, amplitude=0.2).as_tensor()
    obs = torch.randn(4, 8)
    log_prob, *_ = agent.evaluate(obs, state, torch.zeros(4, 2))
    log_prob.sum().backward()
    assert agent.cpg.parametrisation.vector.grad.abs().sum() > 0
    assert agent.feedback[-1].weight.grad.abs().sum() > 0
    assert agent.feedback[0].weight.grad.abs().sum() > 0


def test_open_loop_agent_has_no_feedback_and_trains_only_cpg_and_log_std():
    agent = CPGActorAgent(8, [0.9, 0.9], AgentConfig(), HOPPER, ROBOT, feedback=False)
    actor_params = {n for n, _ in agent.named_parameters() if not n.startswith("critic")}
    assert actor_params == {"log_std", "cpg.parametrisation.vector"}
    out = agent.actor(torch.randn(3, 8), agent.initial_state(3))
    assert torch.equal(out.extras["xi"], torch.zeros(3, 2))


def test_initial_feedback_is_small_and_mean_starts_at_nominal_pose():
    agent = CPGActorAgent(8, [0.9, 0.9], AgentConfig(), HOPPER, ROBOT)
    out = agent.actor(torch.randn(16, 8), agent.initial_state(16))
    assert out.extras["xi"].abs().max() < 0.5  # rad/s, vs 2 pi nu = 12.6
    state = CPGState.from_tensor(out.next_state)
    assert state.amplitude.abs().max() < 0.05  # starts at rest, amplitude 0
    torch.testing.assert_close(
        out.mean, torch.tensor([[0.4, -0.8]]).expand(16, 2), atol=0.05, rtol=0
    )


def test_mlp_agent_is_stateless_and_starts_at_nominal_pose():
    agent = MLPAgent(8, [0.9, 0.9], AgentConfig(), nominal_pose=(0.4, -0.8))
    state = agent.initial_state(5)
    assert state.shape == (5, 0)
    out = agent.actor(torch.randn(5, 8), state)
    assert out.next_state.shape == (5, 0)
    torch.testing.assert_close(
        out.mean, torch.tensor([[0.4, -0.8]]).expand(5, 2), atol=0.05, rtol=0
    )


def test_unknown_agent_name_lists_the_registered_ones():
    with pytest.raises(ValueError, match="cpg-actor-open-loop"):
        get_agent_spec("cpg-actr")


def test_a_new_agent_on_a_new_robot_is_one_registry_entry_each():
    """How a later baseline plugs in, on a robot of its own (the robot builds the env, the
    agent is built for it): no runner change."""
    from cpg_actor.agents import AGENTS, AgentSpec, register_agent
    from cpg_actor.agents.registry import env_shapes

    made = []

    def make_env(num_envs, env_config, num_threads=None):
        made.append(num_envs)
        return FakeHopperVectorEnv(num_envs, env_config)

    register_agent(
        AgentSpec(
            "test-agent",
            "MLP on a stand-in env",
            lambda cfg, env, robot: MLPAgent(*env_shapes(env), cfg, (0.4, -0.8)),
        )
    )
    try:
        with pytest.raises(ValueError, match="already registered"):
            register_agent(AGENTS["test-agent"])
        with registered(fake_robot("test-robot", make_env)):
            config = TrainConfig(
                agent="test-agent",
                robot="test-robot",
                num_envs=3,
                total_steps=3 * 8,
                ppo=PPOConfig(num_steps=8, num_minibatches=2),
                env=FakeConfig(),
            )
            runner = Runner(config)
            runner.learn()
        assert made == [3, 5] and runner.iteration == 1  # training envs, eval envs
    finally:
        del AGENTS["test-agent"]


def test_agents_supply_their_own_scalars_and_histograms():
    agent = CPGActorAgent(8, [0.9, 0.9], AgentConfig(), HOPPER, ROBOT)
    scalars = agent.log_scalars()
    assert {"policy/log_std_0", "cpg/nu_HFE", "cpg/rho_KFE", "cpg/a_HFE"} <= set(scalars)
    assert scalars["cpg/phi_HFE_KFE"] == pytest.approx(-scalars["cpg/phi_KFE_HFE"])
    histograms = agent.log_histograms()
    assert histograms["cpg/vector_V"].shape == (8,)
    assert set(histograms) == {
        "cpg/parameters",
        "cpg/vector_V",
        "feedback/output_weight",
        "feedback/output_bias",
    }
    open_loop = CPGActorAgent(8, [0.9, 0.9], AgentConfig(), HOPPER, ROBOT, feedback=False)
    assert "feedback/output_weight" not in open_loop.log_histograms()
    mlp = MLPAgent(8, [0.9, 0.9], AgentConfig(), nominal_pose=(0.4, -0.8))
    assert set(mlp.log_scalars()) == {"policy/log_std_0", "policy/log_std_1"}
    assert mlp.log_histograms()["actor/output_weight"].shape == (2, 64)


def test_agents_are_built_from_the_env_robot():
    """The nominal pose and the CPG's time step come from the env's RobotSpec, defined once."""
    from cpg_actor.agents.registry import build_cpg_actor, build_mlp
    from cpg_actor.robots.hopper import description
    from cpg_actor.robots.spec import RobotSpec

    env = FakeHopperVectorEnv(2, FakeConfig(control_dt=0.02))
    assert env.robot.nominal_pose == tuple(description.NOMINAL_POSE) == HOPPER.nominal_pose
    agent = build_cpg_actor(AgentConfig(), env, ROBOT)
    assert agent.cpg.dt == 0.02
    assert torch.equal(agent.joint_map.offset, torch.tensor([0.4, -0.8]))
    assert torch.equal(build_mlp(AgentConfig(), env).nominal_pose, torch.tensor([0.4, -0.8]))
    # its CPG layouts and start gait are the run's robot's, whatever the env's model is called
    env.robot = RobotSpec("a-biped", ("HFE", "KFE"), (0.4, -0.8), (-1, -2), (1, 0), 0.01, ())
    agent = build_cpg_actor(AgentConfig(start_gait="search"), env, ROBOT)
    assert agent.cpg.num_oscillators == 2
    with pytest.raises(ValueError, match="robot 'hopper' has the CPG layouts joint"):
        build_cpg_actor(AgentConfig(cpg_layout="leg"), env, ROBOT)
    with pytest.raises(ValueError, match=r"traced_observations \['hip'\] are not observed"):
        RobotSpec("x", ("HFE", "KFE"), (0.4, -0.8), (-1, -2), (1, 0), 0.01, ("q",),
                  traced_observations=("hip",))  # fmt: skip
    with pytest.raises(ValueError, match="nominal_pose needs 2 entries"):
        RobotSpec("x", ("HFE", "KFE"), (0.4,), (-1, -2), (1, 0), 0.01, ())
    with pytest.raises(ValueError, match="drive_observation 'speed' is not one of"):
        RobotSpec("x", ("HFE", "KFE"), (0.4, -0.8), (-1, -2), (1, 0), 0.01, ("q",), "speed")
    assert agent.state_shape == (5, 2)  # the hopper has no drive: the paper's CPG state
