"""The CPG-Actor (paper section III, Fig. 2): feedback MLP -> (xi, kappa) -> one CPG step.

The CPG state is an input of the actor and its next state an output (section III-B): the
runner carries it between control steps, the rollout storage keeps the state *before* each
step, and the PPO update replays one CPG step from it, so the gradient reaches the CPG
parameters V and the feedback MLP together with no backpropagation through time.
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence

import torch
from torch import Tensor

from cpg_actor.agents.base import (
    ActorOutput,
    ActStep,
    Agent,
    AgentConfig,
    gaussian_entropy,
    gaussian_log_prob,
    mlp,
    tanh,
)
from cpg_actor.cpg import CPGNetwork, CPGState, JointMap, hopper_cpg
from cpg_actor.cpg.foot_space import FootSpaceMap
from cpg_actor.cpg.gaits import OSCILLATOR_JOINTS, quadruped_cpg, quadruped_leg_cpg
from cpg_actor.robot import RobotSpec

# robot name -> its CPG layouts (``agent_config.cpg_layout``; the first is the default), each
# the CPG, ``preset(dt, initial=..., check_inputs=..., gait=...)``, and how it drives the
# joints: a tuple of the joint (index in the robot's joint order) each oscillator drives
# (None: one oscillator per joint, in the joint order; the joints no oscillator drives are held
# at the nominal pose), or a pattern module built from the nominal pose that maps the
# oscillators' phase and amplitude to all joints (the quadruped's foot-space legs)
CPG_PRESETS = {
    "anymal-hopper": {"joint": (hopper_cpg, None)},
    "anymal-b": {
        "joint": (quadruped_cpg, OSCILLATOR_JOINTS),
        "leg": (quadruped_leg_cpg, FootSpaceMap),
    },
}


class CPGActorAgent(Agent):
    """Gaussian policy whose mean is ``JointMap(x)``, x the CPG output of eq. 1 (or, in the
    quadruped's ``leg`` layout, ``FootSpaceMap(theta, r)`` of the CPG's next state).

    * ``feedback=True`` (``cpg-actor``): ``[xi, kappa] = scale * MLP(obs)`` per oscillator, or
      ``scale * tanh(MLP(obs))`` with ``feedback_tanh`` (bounded feedback).
    * ``feedback=False`` (``cpg-actor-open-loop``): ``xi = kappa = 0``; only the CPG vector V
      and the log-std are trained.
    * ``agent_config.feedback_noise > 0`` (beyond the paper): the feedback is sampled,
      ``[xi, kappa] ~ N(MLP output, sigma_f^2)``, the CPG steps with the sample and the action
      is drawn around its output. The sample is kept after the action in
      :attr:`ActStep.action` (``sample_dim = 2N + 2N``) and the log-probability is that of
      both draws, so PPO's ratio moves the feedback MLP through its own likelihood.

    The critic sees the observation and the CPG state as ``cos(phase), sin(phase), amplitude``.
    The CPG state is reset to :meth:`CPGNetwork.initial_state` (rest, amplitude 0, the preset
    phases) at each episode start.

    **Drive** (paper eq. 3, ``nu(d) = c_nu1 d + c_nu0``, ``rho(d) = c_R1 d + c_R0``): when the
    robot names a drive observation (:attr:`RobotSpec.drive_observation`, the quadruped's
    forward-speed command) and ``agent_config.cpg_drive`` is on, d is that observation as the
    env gives it (before normalisation), clipped at 0. It is part of the recurrent state, a
    sixth row ``(B, 6, N)`` written by :meth:`observe` before each step, so the rollout storage
    keeps it and the PPO update replays the step with the drive it was taken with.
    """

    def __init__(
        self,
        obs_dim: int,
        action_scale: Sequence[float],
        config: AgentConfig,
        robot: RobotSpec,
        feedback: bool = True,
    ) -> None:
        if robot.name not in CPG_PRESETS:
            raise ValueError(
                f"no CPG preset for robot '{robot.name}'; add one to "
                f"cpg_actor.agents.cpg_actor.CPG_PRESETS (known: {', '.join(CPG_PRESETS)})"
            )
        layouts = CPG_PRESETS[robot.name]
        layout = config.cpg_layout or next(iter(layouts))
        if layout not in layouts:
            raise ValueError(
                f"agent_config.cpg_layout {layout!r}: robot '{robot.name}' has the CPG "
                f"layouts {', '.join(layouts)}"
            )
        preset, joints = layouts[layout]
        pattern = None if joints is None or isinstance(joints, tuple) else joints
        if pattern is not None:
            joints = None
        options = {"gait": config.cpg_gait} if config.cpg_gait else {}
        if options and "gait" not in inspect.signature(preset).parameters:
            raise ValueError(
                f"agent_config.cpg_gait: the CPG preset of robot '{robot.name}' has no gaits; "
                "leave it empty"
            )
        cpg = preset(
            robot.control_dt, initial=config.cpg_initial or None, check_inputs=False, **options
        )
        n = cpg.num_oscillators
        driven = n if joints is None else len(joints)
        if (
            driven != n
            or len(action_scale) != robot.num_joints
            or (joints is None and pattern is None and n != robot.num_joints)
        ):
            raise ValueError(
                f"the CPG has {n} oscillators driving {driven} joints, but the robot has "
                f"{robot.num_joints} joints and the action {len(action_scale)} entries"
            )
        super().__init__(obs_dim, action_scale, config, critic_state_features=3 * n)
        self.cpg: CPGNetwork = cpg
        self.layout = layout
        # the joints from the oscillators: x through the joint map (around the standing pose),
        # or phase and amplitude through the layout's pattern (FootSpaceMap)
        self.joint_map = JointMap(robot.nominal_pose, joints=joints) if pattern is None else None
        self.pattern = None if pattern is None else pattern(robot.nominal_pose)
        # the observation that sets the drive d (None: d = 0)
        self.drive_index = robot.drive_index if config.cpg_drive else None
        self.state_shape = (5, n) if self.drive_index is None else (6, n)
        self.xi_scale = config.xi_scale
        self.kappa_scale = config.kappa_scale
        self.feedback_tanh = config.feedback_tanh
        self.feedback = (
            mlp([obs_dim, *config.actor_hidden, 2 * n], config.activation, config.output_gain)
            if feedback
            else None
        )
        self.feedback_log_std: torch.nn.Parameter | None = None
        if config.feedback_noise > 0:
            if not feedback:
                raise ValueError(
                    "agent_config.feedback_noise needs an agent with feedback (cpg-actor); "
                    "the open-loop CPG-Actor has none: set it to 0"
                )
            scales = torch.tensor([config.xi_scale] * n + [config.kappa_scale] * n)
            self.feedback_log_std = torch.nn.Parameter(torch.log(config.feedback_noise * scales))
            self.sample_dim = self.action_dim + 2 * n

    def initial_state(self, batch_size: int) -> Tensor:
        state = self.cpg.initial_state(batch_size).as_tensor()
        if self.drive_index is None:
            return state
        return torch.cat([state, torch.zeros_like(state[:, :1])], dim=1)  # drive 0 until observed

    def cpg_parameters(self) -> list[torch.nn.Parameter]:
        """The CPG vector V (eq. 1-3's parameters) and the feedback MLP: what acts on the
        action through the CPG state, so that one step shows little of its change."""
        feedback = [] if self.feedback is None else list(self.feedback.parameters())
        return list(self.cpg.parameters()) + feedback

    def observe(self, obs: Tensor, state: Tensor) -> Tensor:
        """The state with the drive row set from the raw observation (class docstring)."""
        if self.drive_index is None:
            return state
        drive = obs[:, self.drive_index].clamp(min=0.0).to(state.dtype)
        return torch.cat([state[:, :5], drive[:, None, None].expand_as(state[:, 5:])], dim=1)

    def keep_observed(self, stepped: Tensor, stored: Tensor) -> Tensor:
        """The replayed CPG state with the stored step's drive."""
        if self.drive_index is None:
            return stepped
        return torch.cat([stepped[:, :5], stored[:, 5:]], dim=1)

    def _split(self, state: Tensor) -> tuple[CPGState, Tensor | float]:
        """The CPG state and the drive ``(B, N)`` (0.0 without one) of a packed state."""
        if self.drive_index is None:
            return CPGState.from_tensor(state), 0.0
        return CPGState.from_tensor(state[:, :5]), state[:, 5]

    def state_features(self, state: Tensor) -> Tensor:
        cpg_state = self._split(state)[0]
        phase = cpg_state.phase
        return torch.cat([torch.cos(phase), torch.sin(phase), cpg_state.amplitude], dim=-1)

    def log_scalars(self) -> dict[str, float]:
        """The log-std and the CPG's physical parameters: nu, rho, a per oscillator, w and phi
        per edge of the topology."""
        row = super().log_scalars()
        names = self.cpg.topology.names
        if self.feedback_log_std is not None:
            stds = self.feedback_log_std.detach().exp().tolist()
            for i, name in enumerate(names):
                row[f"feedback/xi_std_{name}"] = stds[i]
                row[f"feedback/kappa_std_{name}"] = stds[len(names) + i]
        values = {k: v.detach() for k, v in self.cpg.parametrisation.values().items()}
        values["convergence"] = values["convergence"].clamp(max=self.cpg.max_convergence)
        fields = [("frequency", "nu"), ("amplitude", "rho"), ("convergence", "a")]
        if self.drive_index is not None:  # eq. 3's gains: c_nu1 (Hz per unit d), c_R1
            fields += [("frequency_gain", "nu_gain"), ("amplitude_gain", "rho_gain")]
        for field, short in fields:
            for i, name in enumerate(names):
                row[f"cpg/{short}_{name}"] = float(values[field][i])
        for i, j in self.cpg.topology.edges:
            row[f"cpg/w_{names[i]}_{names[j]}"] = float(values["coupling_weight"][i, j])
            row[f"cpg/phi_{names[i]}_{names[j]}"] = float(values["phase_bias"][i, j])
        return row

    def log_histograms(self) -> dict[str, Tensor]:
        """Paper Fig. 5: the CPG parameters, V, and the feedback network's output layer."""
        parametrisation = self.cpg.parametrisation
        values = parametrisation.values().values()
        out = {
            "cpg/parameters": torch.cat([v.detach().flatten() for v in values]),
            "cpg/vector_V": parametrisation.vector.detach(),
        }
        if self.feedback is not None:
            last = self.feedback[-1]
            out["feedback/output_weight"] = last.weight.detach()
            out["feedback/output_bias"] = last.bias.detach()
        return out

    def feedback_mean(self, obs: Tensor) -> Tensor:
        """``[xi, kappa]`` of the feedback MLP, ``(B, 2N)`` (zeros without feedback)."""
        n = self.cpg.num_oscillators
        if self.feedback is None:
            return torch.zeros(obs.shape[0], 2 * n, dtype=obs.dtype, device=obs.device)
        out = self.feedback(obs)
        if self.feedback_tanh:
            out = tanh(out)
        return torch.cat([self.xi_scale * out[:, :n], self.kappa_scale * out[:, n:]], dim=-1)

    def actor(self, obs: Tensor, state: Tensor, feedback: Tensor | None = None) -> ActorOutput:
        """One CPG step from ``state`` with ``feedback`` ``[xi, kappa]`` (default: the MLP's
        output, the mean when the feedback is sampled)."""
        n = self.cpg.num_oscillators
        if feedback is None:
            feedback = self.feedback_mean(obs)
        xi, kappa = feedback[:, :n], feedback[:, n:]
        cpg_state, drive = self._split(state)
        output, next_cpg_state = self.cpg(cpg_state, drive, xi, kappa)
        next_state = next_cpg_state.as_tensor()
        if self.drive_index is not None:  # the drive is held until the next observation
            next_state = torch.cat([next_state, state[:, 5:]], dim=1)
        if self.pattern is not None:
            mean = self.pattern(next_cpg_state.phase, next_cpg_state.amplitude)
        else:
            mean = self.joint_map(output.position)
        extras = {
            "xi": xi,
            "kappa": kappa,
            "theta_dot": next_cpg_state.phase_velocity,
            "r_ddot": next_cpg_state.amplitude_acceleration,
            "desired_velocity": output.velocity,
            "cpg_position": output.position,
        }
        return ActorOutput(mean, self.std(obs.shape[0]), next_state, extras)

    # -- sampled feedback (feedback_noise > 0) -----------------------------------------------
    def act(self, obs: Tensor, state: Tensor, deterministic: bool = False) -> ActStep:
        if self.feedback_log_std is None:
            return super().act(obs, state, deterministic)
        feedback_mean = self.feedback_mean(obs)
        feedback_std = self.feedback_log_std.exp().expand_as(feedback_mean)
        with torch.no_grad():
            feedback = feedback_mean if deterministic else torch.normal(feedback_mean, feedback_std)
        out = self.actor(obs, state, feedback)
        with torch.no_grad():
            action = (
                out.mean if deterministic else torch.normal(out.mean.expand(out.std.shape), out.std)
            )
        sample = torch.cat([action, feedback], dim=-1)
        mean = torch.cat([out.mean, feedback_mean], dim=-1)
        std = torch.cat([out.std, feedback_std], dim=-1)
        log_prob = gaussian_log_prob(sample, mean, std).sum(-1)
        value = self.value(obs, state)
        return ActStep(sample, log_prob, value, mean, std, out.next_state, out.extras)

    def _sampled(self, obs: Tensor, state: Tensor, sample: Tensor) -> tuple[ActorOutput, ...]:
        feedback = sample[:, self.action_dim :]
        return self.actor(obs, state, feedback), self.feedback_mean(obs)

    def replay_state(self, obs: Tensor, state: Tensor, sample: Tensor) -> Tensor:
        if self.feedback_log_std is None:
            return super().replay_state(obs, state, sample)
        return self._sampled(obs, state, sample)[0].next_state

    def evaluate(self, obs: Tensor, state: Tensor, actions: Tensor) -> tuple[Tensor, ...]:
        if self.feedback_log_std is None:
            return super().evaluate(obs, state, actions)
        out, feedback_mean = self._sampled(obs, state, actions)
        mean = torch.cat([out.mean, feedback_mean], dim=-1)
        std = torch.cat([out.std, self.feedback_log_std.exp().expand_as(feedback_mean)], dim=-1)
        return (
            gaussian_log_prob(actions, mean, std).sum(-1),
            gaussian_entropy(std).sum(-1),
            self.value(obs, state),
            mean,
            std,
        )
