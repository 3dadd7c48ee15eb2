"""The CPG-Actor (paper section III, Fig. 2): feedback MLP -> (xi, kappa) -> one CPG step.

The CPG state is an input of the actor and its next state an output (section III-B): the
runner carries it between control steps, the rollout storage keeps the state *before* each
step, and the PPO update replays one CPG step from it, so the gradient reaches the CPG
parameters V and the feedback MLP together with no backpropagation through time.
"""

from __future__ import annotations

import inspect
import math
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
    gaussian_sample,
    mlp,
    tanh,
)
from cpg_actor.agents.start_gait import start_parameters
from cpg_actor.cpg import CPGNetwork, CPGState, JointMap
from cpg_actor.cpg.hopf import STATE_FIELDS
from cpg_actor.robots.plugin import Robot
from cpg_actor.robots.spec import RobotSpec


def output_bounds(
    robot: RobotSpec,
    joints: Sequence[int] | None,
    config: AgentConfig,
    dt: float,
) -> dict[str, tuple]:
    """``agent_config.output_bound``'s bounds: per oscillator, the amplitude rho in ``(0,
    h - kappa_bound)``, h the half-range of its joint around the nominal pose (the nearer
    stop), and the convergence a in ``convergence_bounds``, capped at ``1 / dt``."""
    joints = range(robot.num_joints) if joints is None else joints
    pose, low, high_stop = robot.nominal_pose, robot.action_low, robot.action_high
    half = [min(high_stop[j] - pose[j], pose[j] - low[j]) for j in joints]
    high = [h - config.kappa_bound for h in half]
    if min(high) <= 0:
        raise ValueError(
            f"agent_config.kappa_bound {config.kappa_bound} rad leaves no amplitude inside the "
            f"joint half-ranges {[round(h, 3) for h in half]}: lower it"
        )
    low_a, high_a = config.convergence_bounds
    high_a = min(high_a, 1.0 / dt)
    if not low_a < high_a:
        raise ValueError(
            f"agent_config.convergence_bounds {list(config.convergence_bounds)}: the lower bound "
            f"must be below 1 / dt = {1.0 / dt:g}"
        )
    return {"amplitude": (0.0, high), "convergence": (low_a, high_a)}


class CPGActorAgent(Agent):
    """Gaussian policy whose mean is ``JointMap(x)``, x the CPG output of eq. 1 (or, in the
    quadruped's ``leg`` layout, ``FootSpaceMap(theta, r)`` of the CPG's next state).

    Built for the env's robot ``robot`` (its joints, pose and control period) from the run's
    robot entry ``plugin`` (its CPG layout ``agent_config.cpg_layout`` and start gait).

    * ``feedback=True`` (``cpg-actor``): ``[xi, kappa] = scale * MLP(obs)`` per oscillator, or
      ``scale * tanh(MLP(obs))`` with ``feedback_tanh`` (bounded feedback).
    * ``feedback=False`` (``cpg-actor-open-loop``): ``xi = kappa = 0``; only the CPG vector V
      and the log-std are trained.
    * ``agent_config.feedback_noise > 0`` (beyond the paper): the feedback is sampled,
      ``[xi, kappa] ~ N(MLP output, sigma_f^2)``, the CPG steps with the sample and the action
      is drawn around its output. The sample is kept after the action in
      :attr:`ActStep.action` (``sample_dim = 2N + 2N``) and the log-probability is that of
      both draws, so PPO's ratio moves the feedback MLP through its own likelihood.

    * ``exploration="cpg"`` (beyond the paper): the joint command is the CPG's output,
      deterministic. At each step the feedback MLP's pre-bound output ``u`` and the CPG vector
      V are sampled, ``u ~ N(MLP(obs), s_u^2)`` and ``V_t ~ N(V, s_V^2)``, and the CPG steps
      with ``[xi, kappa]`` from ``u`` and its parameters from ``V_t``: noise the CPG filters
      into a smooth motion. :attr:`ActStep.action` is ``[command, u, V_t]`` (``sample_dim =
      A + 2N + M``) and the log-probability is that of ``u`` and ``V_t`` alone, so PPO's ratio
      moves the feedback MLP and V through their own likelihoods. The command's entries of
      :attr:`ActStep.mean` and :attr:`ActStep.std` are 0 and 1 in every step (no KL): it is
      not sampled. Each std is ``floor + exp(log_std)``, never below ``std_floor`` of its
      initial value.
    * ``output_bound`` (beyond the paper): rho_i in ``(0, h_i - kappa_bound)``, h_i the
      half-range of oscillator i's joint around the nominal pose, and a in
      ``convergence_bounds`` (sigmoid transforms of V, :class:`Parametrisation`); kappa is
      ``kappa_bound a^2 / 4`` times the bounded feedback, so its steady-state change of the
      amplitude, ``4 kappa / a^2``, is at most ``kappa_bound`` rad. The amplitude equation of
      eq. 1 is critically damped (its impulse response is positive), so r stays between the
      lowest and highest ``rho + 4 kappa / a^2`` it has been driven toward, and the command
      ``nominal + r cos(theta)`` inside the joint range.

    The critic sees the observation and the CPG state as ``cos(phase), sin(phase), amplitude``.
    The CPG state is reset to :meth:`CPGNetwork.initial_state` (rest, amplitude 0, the preset
    phases) at each episode start.

    **Drive** (paper eq. 3, ``nu(d) = c_nu1 d + c_nu0``, ``rho(d) = c_R1 d + c_R0``): when the
    robot names a drive observation (:attr:`RobotSpec.drive_observation`, the quadruped's
    forward-speed command) and ``agent_config.cpg_drive`` is on, d is that observation as the
    env gives it (before normalisation), clipped at 0. It is part of the recurrent state, a
    sixth row ``(B, 6, N)`` written by :meth:`observe` before each step, so the rollout storage
    keeps it and the PPO update replays the step with the drive it was taken with. With
    ``agent_config.cpg_planar_steps`` (a layout with a planar drive: the quadruped's ``leg``),
    each leg's d is its foot's commanded planar speed and a seventh row holds its step's
    direction, which the pattern takes
    (:mod:`cpg_actor.robots.common.quadruped.planar_drive`).
    """

    def __init__(
        self,
        obs_dim: int,
        action_scale: Sequence[float],
        config: AgentConfig,
        robot: RobotSpec,
        plugin: Robot,
        feedback: bool = True,
    ) -> None:
        layout, cpg = plugin.cpg_layout(config.cpg_layout)  # the run's robot's CPG layouts
        preset, joints, pattern, planar = cpg.preset, cpg.joints, cpg.pattern, cpg.planar_drive
        options = {"gait": config.cpg_gait} if config.cpg_gait else {}
        if options and not cpg.gaits:
            raise ValueError(
                f"agent_config.cpg_gait: the CPG preset of robot '{robot.name}' has no gaits; "
                "leave it empty"
            )
        initial = {**start_parameters(config.start_gait, plugin), **config.cpg_initial}
        if config.output_bound:
            if pattern is not None:
                raise ValueError(
                    f"agent_config.output_bound needs oscillators that drive joints; the "
                    f"'{layout}' layout's amplitude is a foot step: set it to false"
                )
            if "bounds" not in inspect.signature(preset).parameters:
                raise ValueError(
                    f"agent_config.output_bound: the CPG preset of robot '{robot.name}' takes "
                    "no bounds; set it to false"
                )
            options["bounds"] = output_bounds(robot, joints, config, robot.control_dt)
        cpg = preset(robot.control_dt, initial=initial or None, check_inputs=False, **options)
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
        # planar steps: each leg's drive and step direction from the whole command
        self.planar_drive = None
        if config.cpg_planar_steps:
            if self.drive_index is None:
                raise ValueError("agent_config.cpg_planar_steps needs agent_config.cpg_drive "
                                 f"and a robot with a drive (robot '{robot.name}')")  # fmt: skip
            if planar is None or not robot.command_observations:
                raise ValueError(f"agent_config.cpg_planar_steps needs a CPG layout with planar "
                                 f"steps (the quadrupeds' 'leg'); the '{layout}' layout of robot "
                                 f"'{robot.name}' has none: set it to false")  # fmt: skip
            self.planar_drive = planar()
            names = robot.observation_names
            self.command_index = [names.index(name) for name in robot.command_observations]
        drive_rows = () if self.drive_index is None else ("drive",)
        drive_rows += () if self.planar_drive is None else ("direction",)
        self.state_rows = STATE_FIELDS + drive_rows
        self.state_shape = (len(self.state_rows), n)
        self.xi_scale = config.xi_scale
        self.kappa_scale = config.kappa_scale
        self.kappa_bound = config.kappa_bound if config.output_bound else None
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
        # exploration "cpg": the stds of the sampled feedback u and vector V, floor + exp(.)
        self.cpg_exploration = config.exploration == "cpg"
        self.latent_log_std: torch.nn.Parameter | None = None
        self.vector_log_std: torch.nn.Parameter | None = None
        if self.cpg_exploration:
            m = self.cpg.parametrisation.num_parameters
            floor = config.std_floor
            self.vector_floor = floor * config.cpg_noise
            self.vector_log_std = torch.nn.Parameter(
                torch.full((m,), math.log(config.cpg_noise - self.vector_floor))
            )
            latent = 0
            if self.feedback is not None:
                latent = 2 * n
                self.latent_floor = floor * config.feedback_std
                self.latent_log_std = torch.nn.Parameter(
                    torch.full((latent,), math.log(config.feedback_std - self.latent_floor))
                )
            self.sample_dim = self.action_dim + latent + m

    def initial_state(self, batch_size: int) -> Tensor:
        state = self.cpg.initial_state(batch_size).as_tensor()
        if self.drive_index is None:
            return state
        extra = state.new_zeros(batch_size, self.state_shape[0] - 5, state.shape[2])
        return torch.cat([state, extra], dim=1)  # drive (and direction) 0 until observed

    def cpg_parameters(self) -> list[torch.nn.Parameter]:
        """The CPG vector V (eq. 1-3's parameters) and the feedback MLP: what acts on the
        action through the CPG state, so that one step shows little of its change."""
        feedback = [] if self.feedback is None else list(self.feedback.parameters())
        return list(self.cpg.parameters()) + feedback

    def exploration_stds(self) -> tuple[Tensor | None, Tensor]:
        """Exploration ``"cpg"``: the stds of the sampled feedback ``u`` ``(2N,)`` (None
        without feedback) and of V ``(M,)``, each ``floor + exp(log_std)``."""
        latent = None
        if self.latent_log_std is not None:
            latent = self.latent_floor + self.latent_log_std.exp()
        return latent, self.vector_floor + self.vector_log_std.exp()

    def observe(self, obs: Tensor, state: Tensor) -> Tensor:
        """The state with the drive row set from the raw observation (class docstring)."""
        if self.drive_index is None:
            return state
        if self.planar_drive is not None:
            drive, direction = self.planar_drive(obs[:, self.command_index].to(state.dtype))
            return torch.cat([state[:, :5], drive[:, None], direction[:, None]], dim=1)
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
        # the joint command's log-std only where it is sampled
        row = {} if self.cpg_exploration else super().log_scalars()
        names = self.cpg.topology.names
        if self.feedback_log_std is not None:
            stds = self.feedback_log_std.detach().exp().tolist()
            for i, name in enumerate(names):
                row[f"feedback/xi_std_{name}"] = stds[i]
                row[f"feedback/kappa_std_{name}"] = stds[len(names) + i]
        if self.cpg_exploration:
            latent, vector = (t if t is None else t.detach() for t in self.exploration_stds())
            if latent is not None:
                for i, name in enumerate(names):
                    row[f"feedback/xi_std_{name}"] = float(latent[i])
                    row[f"feedback/kappa_std_{name}"] = float(latent[len(names) + i])
            row["cpg/vector_std_mean"] = float(vector.mean())
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

    def feedback_latent(self, obs: Tensor) -> Tensor:
        """The feedback MLP's output before its bound and scale, ``(B, 2N)`` (zeros without
        feedback)."""
        n = self.cpg.num_oscillators
        if self.feedback is None:
            return torch.zeros(obs.shape[0], 2 * n, dtype=obs.dtype, device=obs.device)
        return self.feedback(obs)

    def feedback_from_latent(
        self, latent: Tensor, drive: Tensor | float = 0.0, vector: Tensor | None = None
    ) -> Tensor:
        """``[xi, kappa]`` ``(B, 2N)`` from the MLP's output: ``xi_scale tanh(u)`` and
        ``kappa_scale tanh(u)`` (``feedback_tanh``; else unbounded ``scale u``), or with
        ``output_bound`` ``kappa = kappa_bound a^2 / 4 tanh(u)``, a the convergence rate the
        step uses (``vector``: a sampled V)."""
        n = self.cpg.num_oscillators
        out = tanh(latent) if self.feedback_tanh else latent
        xi = self.xi_scale * out[:, :n]
        if self.kappa_bound is None:
            kappa = self.kappa_scale * out[:, n:]
        else:
            a = self.cpg.oscillator_parameters(drive, vector).convergence
            kappa = self.kappa_bound * a * a / 4.0 * out[:, n:]
        return torch.cat([xi, kappa], dim=-1)

    def feedback_mean(self, obs: Tensor, state: Tensor | None = None) -> Tensor:
        """``[xi, kappa]`` of the feedback MLP, ``(B, 2N)`` (zeros without feedback);
        ``state`` gives the drive where the bound on kappa needs the convergence rate."""
        n = self.cpg.num_oscillators
        if self.feedback is None:
            return torch.zeros(obs.shape[0], 2 * n, dtype=obs.dtype, device=obs.device)
        drive = 0.0 if state is None else self._split(state)[1]
        return self.feedback_from_latent(self.feedback(obs), drive)

    def actor(
        self,
        obs: Tensor,
        state: Tensor,
        feedback: Tensor | None = None,
        vector: Tensor | None = None,
    ) -> ActorOutput:
        """One CPG step from ``state`` with ``feedback`` ``[xi, kappa]`` (default: the MLP's
        output, the mean when the feedback is sampled) and the CPG vector ``vector``
        (default: V; ``(B, M)``, a sampled V per row)."""
        n = self.cpg.num_oscillators
        cpg_state, drive = self._split(state)
        if feedback is None:
            feedback = self.feedback_from_latent(self.feedback_latent(obs), drive, vector)
        xi, kappa = feedback[:, :n], feedback[:, n:]
        output, next_cpg_state = self.cpg(cpg_state, drive, xi, kappa, vector)
        next_state = next_cpg_state.as_tensor()
        if self.drive_index is not None:  # the drive is held until the next observation
            next_state = torch.cat([next_state, state[:, 5:]], dim=1)
        if self.planar_drive is not None:  # the step along each leg's direction
            mean = self.pattern(next_cpg_state.phase, next_cpg_state.amplitude, state[:, 6])
        elif self.pattern is not None:
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

    # -- exploration "cpg": sampled feedback u and CPG vector V, deterministic command --------
    def _cpg_distribution(self, obs: Tensor) -> tuple[Tensor, Tensor]:
        """Mean and std ``(B, 2N + M)`` of the sampled ``[u, V_t]``."""
        latent_std, vector_std = self.exploration_stds()
        batch = obs.shape[0]
        vector = self.cpg.parametrisation.vector
        means = [vector.expand(batch, -1)]
        stds = [vector_std.expand(batch, -1)]
        if latent_std is not None:
            means.insert(0, self.feedback_latent(obs))
            stds.insert(0, latent_std.expand(batch, -1))
        return torch.cat(means, dim=-1), torch.cat(stds, dim=-1)

    def _cpg_step(self, obs: Tensor, state: Tensor, sampled: Tensor) -> ActorOutput:
        """The CPG step with a sampled ``[u, V_t]``."""
        m = self.cpg.parametrisation.num_parameters
        latent, vector = sampled[:, : sampled.shape[1] - m], sampled[:, sampled.shape[1] - m :]
        feedback = None
        if self.feedback is not None:
            feedback = self.feedback_from_latent(latent, self._split(state)[1], vector)
        return self.actor(obs, state, feedback, vector)

    def _with_command(self, out: ActorOutput, mean: Tensor, std: Tensor):
        """``(mean, std)`` of the whole sample: the command's entries 0 and 1 (not sampled)."""
        return (
            torch.cat([torch.zeros_like(out.mean), mean], dim=-1),
            torch.cat([torch.ones_like(out.mean), std], dim=-1),
        )

    def _act_cpg(self, obs: Tensor, state: Tensor, deterministic: bool) -> ActStep:
        mean, std = self._cpg_distribution(obs)
        with torch.no_grad():
            sampled = mean if deterministic else gaussian_sample(mean, std)
        out = self._cpg_step(obs, state, sampled)
        log_prob = gaussian_log_prob(sampled, mean, std).sum(-1)
        sample = torch.cat([out.mean, sampled], dim=-1)
        full_mean, full_std = self._with_command(out, mean, std)
        value = self.value(obs, state)
        return ActStep(sample, log_prob, value, full_mean, full_std, out.next_state, out.extras)

    # -- sampled feedback (feedback_noise > 0) -----------------------------------------------
    def act(self, obs: Tensor, state: Tensor, deterministic: bool = False) -> ActStep:
        if self.cpg_exploration:
            return self._act_cpg(obs, state, deterministic)
        if self.feedback_log_std is None:
            return super().act(obs, state, deterministic)
        feedback_mean = self.feedback_mean(obs, state)
        feedback_std = self.feedback_log_std.exp().expand_as(feedback_mean)
        with torch.no_grad():
            feedback = (
                feedback_mean if deterministic else gaussian_sample(feedback_mean, feedback_std)
            )
        out = self.actor(obs, state, feedback)
        with torch.no_grad():
            action = (
                out.mean
                if deterministic
                else gaussian_sample(out.mean.expand(out.std.shape), out.std)
            )
        sample = torch.cat([action, feedback], dim=-1)
        mean = torch.cat([out.mean, feedback_mean], dim=-1)
        std = torch.cat([out.std, feedback_std], dim=-1)
        log_prob = gaussian_log_prob(sample, mean, std).sum(-1)
        value = self.value(obs, state)
        return ActStep(sample, log_prob, value, mean, std, out.next_state, out.extras)

    def _sampled(self, obs: Tensor, state: Tensor, sample: Tensor) -> tuple[ActorOutput, ...]:
        feedback = sample[:, self.action_dim :]
        return self.actor(obs, state, feedback), self.feedback_mean(obs, state)

    def replay_state(self, obs: Tensor, state: Tensor, sample: Tensor) -> Tensor:
        if self.cpg_exploration:
            return self._cpg_step(obs, state, sample[:, self.action_dim :]).next_state
        if self.feedback_log_std is None:
            return super().replay_state(obs, state, sample)
        return self._sampled(obs, state, sample)[0].next_state

    def evaluate(self, obs: Tensor, state: Tensor, actions: Tensor) -> tuple[Tensor, ...]:
        if self.cpg_exploration:
            sampled = actions[:, self.action_dim :]
            mean, std = self._cpg_distribution(obs)
            out = self._cpg_step(obs, state, sampled)
            full_mean, full_std = self._with_command(out, mean, std)
            return (
                gaussian_log_prob(sampled, mean, std).sum(-1),
                gaussian_entropy(std).sum(-1),
                self.value(obs, state),
                full_mean,
                full_std,
            )
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
