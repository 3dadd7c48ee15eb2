"""The agent interface shared by every actor-critic, stateful (CPG) or not.

An agent maps a *normalised* observation and its recurrent state to a Gaussian over actions
(desired joint positions for the hopper) and a value. The recurrent state is an explicit
input and output, packed as one tensor ``(B, *state_shape)``: ``(B, 5, N)`` for a CPG of N
oscillators (:meth:`CPGState.as_tensor`), ``(B, 0)`` for stateless agents, so the runner and
the rollout storage treat every agent the same way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from typing import Any, NamedTuple

import torch
from torch import Tensor, nn

from cpg_actor.limits import (
    MAX_LAYER_WEIGHTS,
    MAX_LAYER_WIDTH,
    MAX_LAYERS,
    brief,
    check_int,
)


@dataclass
class AgentConfig:
    """Network sizes and initialisation; used by every registered agent (unused parts ignored).

    ``activation`` applies to the hidden layers of the actor MLP, the feedback MLP and the
    critic. The feedback MLP's outputs are bounded and scaled: ``xi = xi_scale * tanh(out[:N])``
    (rad/s) and ``kappa = kappa_scale * tanh(out[N:])`` (rad/s^2) (``feedback_tanh=False``:
    ``scale * out``, unbounded), and its last layer is initialised orthogonally with gain
    ``output_gain`` so that the CPG-Actor starts as the open-loop CPG.
    """

    actor_hidden: tuple[int, ...] = (64, 64)
    critic_hidden: tuple[int, ...] = (64, 64)
    activation: str = "tanh"  # tanh | elu
    # initial action std in units of the action's half-range (high - low) / 2, as Baselines'
    # log-std 0 on an env whose actions span [-1, 1]: 1.0 is 0.9 rad on the hopper's joints
    init_std: float = 1.0
    output_gain: float = 0.01  # orthogonal gain of the actor's / feedback's last layer
    # The feedback is bounded: xi = xi_scale * tanh(out[:N]) (rad/s), kappa = kappa_scale *
    # tanh(out[N:]) (rad/s^2). Unbounded feedback (feedback_tanh=False: scale * out) can learn
    # a period-2 chatter of theta_dot through the observation loop, and unstable returns.
    xi_scale: float = 4.0
    kappa_scale: float = 25.0
    feedback_tanh: bool = True
    # exploration in feedback space (beyond the paper): xi and kappa are sampled around the
    # feedback MLP's output with a trained std, initially feedback_noise x (xi_scale,
    # kappa_scale); the policy gradient then reaches the MLP through the feedback's own
    # likelihood instead of the one-step lever dx/dxi. 0 (the paper): deterministic feedback.
    feedback_noise: float = 0.0
    cpg_initial: dict = field(default_factory=dict)  # overrides of the robot's CPG preset
    # the gait the robot's CPG starts in (its CPGLayout.gaits, e.g. the quadruped's trot, pace,
    # bound, pronk, walk); empty: the preset's. The hopper has none.
    cpg_gait: str = ""
    # how the robot's CPG drives its joints, one of its CPG layouts (Robot.cpg_layouts, e.g.
    # the quadruped's "joint": one oscillator per HFE and KFE joint, or "leg": one per leg, a
    # foot-space pattern); empty: the robot's first. The hopper has "joint" only.
    cpg_layout: str = ""
    # the CPG's drive d (eq. 3) follows the robot's drive observation (the quadruped's
    # forward-speed command; RobotSpec.drive_observation). False, or a robot without one: d = 0
    cpg_drive: bool = True
    # the CPG's drive follows the whole velocity command (forward, lateral, yaw rate): each
    # leg's drive is its foot's commanded planar speed and its step points along that velocity
    # (the layout's planar drive: the quadruped's "leg" layout). False: d is the drive
    # observation alone (the forward command) on every oscillator. Needs cpg_drive
    cpg_planar_steps: bool = False
    # -- beyond the paper: the CPG-Actor's start, exploration and output bound --------------
    # where the CPG starts: "" the robot's CPG preset (the paper's start), "search" the gait
    # the open-loop search (agent open-loop-es) found for the robot, shipped with the package,
    # or the path of a gait file (a run's gait.yaml); cpg_initial overrides it. cho2019-warm
    # and mlp-warm are warm-started toward the same gait
    start_gait: str = ""
    # where the CPG-Actor explores: "position" (the paper: Gaussian noise on the desired joint
    # positions, std init_std) or "cpg" (the joint command is the CPG's output, deterministic;
    # at each step the feedback MLP's pre-bound output and the CPG vector V are sampled, with
    # initial stds feedback_std and cpg_noise, and the log-probability is theirs)
    exploration: str = "position"
    feedback_std: float = 0.5  # "cpg": initial std of the feedback's pre-tanh values
    cpg_noise: float = 0.05  # "cpg": initial std of each entry of V (V's own units)
    # "cpg": no sampled std falls below this fraction of its initial value
    # (std = floor + exp(log_std)), so exploration cannot collapse to nothing
    std_floor: float = 0.1
    # the Gaussian noise on the env's action (position exploration, the MLP, Cho et al.'s CPG
    # parameters): no std falls below this fraction of its initial init_std (std = floor +
    # exp(log_std)); 0, the paper's and the default, lets it shrink toward nothing
    action_std_floor: float = 0.0
    # the command inside the joint range: the amplitude rho of each oscillator bounded to
    # (0, joint half-range - kappa_bound), the convergence a to convergence_bounds (and 1/dt),
    # and kappa = kappa_bound a^2 / 4 tanh(out), whose steady-state change of the amplitude
    # (4 kappa / a^2) is at most kappa_bound rad
    output_bound: bool = False
    kappa_bound: float = 0.2  # rad
    convergence_bounds: tuple[float, float] = (2.0, 100.0)  # 1/s
    # fixed factors on the observation's entries before the actor and the critic read them,
    # by entry-name pattern (fnmatch: "base_ang_vel_*"; the first pattern an entry matches
    # gives its factor, 1 where none does): rsl_rl v1's input, legged_gym's scaled
    # observation, where no running normalisation is (the legged_gym recipe). The agents
    # whose spec says so (AgentSpec.observation_scales: the MLP's) take it; empty: none
    observation_scales: dict = field(default_factory=dict)

    def validate(self) -> None:
        if self.activation not in ACTIVATIONS:
            raise ValueError(
                f"agent_config.activation must be one of {sorted(ACTIVATIONS)}, "
                f"got {brief(self.activation)}"
            )
        for name in ("actor_hidden", "critic_hidden"):
            check_hidden(getattr(self, name), f"agent_config.{name}")
        for name in ("init_std", "output_gain", "xi_scale", "kappa_scale"):
            value = getattr(self, name)
            if not 0 < value < math.inf:
                raise ValueError(f"agent_config.{name} must be a finite number > 0, "
                                 f"got {brief(value)}")  # fmt: skip
        if not 0 <= self.feedback_noise < math.inf:
            raise ValueError(
                "agent_config.feedback_noise must be a finite number >= 0, "
                f"got {brief(self.feedback_noise)}"
            )
        if self.exploration not in EXPLORATIONS:
            raise ValueError(
                f"agent_config.exploration must be one of {', '.join(EXPLORATIONS)}, "
                f"got {brief(self.exploration)}"
            )
        for name in ("feedback_std", "cpg_noise", "kappa_bound"):
            value = getattr(self, name)
            if not 0 < value < math.inf:
                raise ValueError(f"agent_config.{name} must be a finite number > 0, "
                                 f"got {brief(value)}")  # fmt: skip
        for name in ("std_floor", "action_std_floor"):
            if not 0 <= getattr(self, name) < 1:
                raise ValueError(f"agent_config.{name} must be in [0, 1) (a fraction of the "
                                 f"initial std), got {brief(getattr(self, name))}")  # fmt: skip
        low, high = (tuple(self.convergence_bounds) + (None, None))[:2]
        if len(self.convergence_bounds) != 2 or not 0 < low < high < math.inf:
            raise ValueError(
                "agent_config.convergence_bounds must be [low, high] with 0 < low < high (1/s), "
                f"got {brief(self.convergence_bounds)}"
            )
        scales = self.observation_scales
        if not isinstance(scales, dict) or not all(
            isinstance(k, str) and not isinstance(v, bool) and isinstance(v, int | float)
            and 0 < v < math.inf for k, v in scales.items()
        ):  # fmt: skip
            raise ValueError(f"agent_config.observation_scales must map observation-name "
                             f"patterns to finite factors > 0, got {brief(scales)}")  # fmt: skip
        if self.exploration == "cpg" and self.feedback_noise > 0:
            raise ValueError(
                "agent_config.feedback_noise samples the feedback under position noise; with "
                "exploration 'cpg' the feedback is sampled already (feedback_std): set it to 0"
            )


EXPLORATIONS = ("position", "cpg")


def check_hidden(sizes: Any, name: str) -> None:
    """ValueError (one line) unless ``sizes`` are hidden layer sizes within the bounds of
    :mod:`cpg_actor.limits`: 1 to MAX_LAYERS layers of 1 to MAX_LAYER_WIDTH units, and at most
    MAX_LAYER_WEIGHTS weights between two of them (checked before a network is built)."""
    if not isinstance(sizes, (list, tuple)) or not 1 <= len(sizes) <= MAX_LAYERS:
        raise ValueError(f"{name} must be 1 to {MAX_LAYERS} layer sizes, got {brief(sizes)}")
    for size in sizes:
        check_int(size, f"each layer size of {name}", 1, MAX_LAYER_WIDTH)
    for first, second in zip(sizes[:-1], sizes[1:], strict=True):
        if first * second > MAX_LAYER_WEIGHTS:
            raise ValueError(
                f"{name}: layers of {first:,} and {second:,} units have {first * second:,} "
                f"weights between them, above the {MAX_LAYER_WEIGHTS:,} accepted"
            )


def observation_scale(names: Sequence[str], scales: dict[str, float]) -> list[float]:
    """Each observation entry's factor (``agent_config.observation_scales``): that of the first
    pattern (fnmatch, case-sensitive) its name matches, 1 where none does. A pattern that
    matches no entry (a misspelling would scale nothing): ValueError naming the entries."""
    unmatched = [p for p in scales if not any(fnmatchcase(name, p) for name in names)]
    if unmatched:
        raise ValueError(f"agent_config.observation_scales: {brief(unmatched)} match no entry of "
                         f"the observation; its entries are {brief(list(names))}")  # fmt: skip
    return [next((float(f) for pattern, f in scales.items() if fnmatchcase(name, pattern)), 1.0)
            for name in names]  # fmt: skip


def tanh(x: Tensor) -> Tensor:
    """tanh(x), computed as ``2 sigmoid(2x) - 1`` (the same function; within 2e-7 of
    ``torch.tanh`` in float32): on the CPU torch's float32 ``tanh`` is much slower than its
    ``sigmoid`` (``benchmarks/activation.py`` compares them)."""
    return torch.sigmoid(2.0 * x) * 2.0 - 1.0


class Tanh(nn.Module):
    """``nn.Tanh`` through :func:`tanh`; it has no parameters, so checkpoints are unchanged."""

    def forward(self, x: Tensor) -> Tensor:
        return tanh(x)


ACTIVATIONS = {"tanh": Tanh, "elu": nn.ELU}


def mlp(sizes: list[int], activation: str, output_gain: float) -> nn.Sequential:
    """Linear layers with ``activation`` between them; orthogonal init (CleanRL)."""
    layers: list[nn.Module] = []
    for i in range(len(sizes) - 1):
        last = i == len(sizes) - 2
        layer = nn.Linear(sizes[i], sizes[i + 1])
        nn.init.orthogonal_(layer.weight, output_gain if last else 2**0.5)
        nn.init.zeros_(layer.bias)
        layers.append(layer)
        if not last:
            layers.append(ACTIVATIONS[activation]())
    return nn.Sequential(*layers)


LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


def gaussian_log_prob(value: Tensor, mean: Tensor, std: Tensor) -> Tensor:
    """Elementwise log N(value; mean, std^2) (the formula of ``torch.distributions.Normal``)."""
    return -((value - mean) ** 2) / (2.0 * std**2) - torch.log(std) - LOG_SQRT_2PI


def gaussian_sample(mean: Tensor, std: Tensor) -> Tensor:
    """One draw of N(mean, std^2): the numbers of ``torch.normal(mean, std)`` from the same
    draw of the RNG. On the CPU it is ``torch.normal``; elsewhere it is computed the way
    ``torch.normal`` computes it (:func:`scaled_noise`), without ``torch.normal``'s check
    that std >= 0, which reads std's minimum on the host: on a GPU, a wait for the device at
    every control step."""
    if mean.device.type == "cpu":
        return torch.normal(mean, std)
    return scaled_noise(mean, std)


def scaled_noise(mean: Tensor, std: Tensor) -> Tensor:
    """N(0, 1) drawn in the broadcast shape, times ``std``, plus ``mean``: what
    ``torch.normal(mean, std)`` computes, bit for bit (tested), with no look at the values."""
    noise = torch.randn(
        torch.broadcast_shapes(mean.shape, std.shape), dtype=mean.dtype, device=mean.device
    )
    return noise.mul_(std).add_(mean)


def gaussian_entropy(std: Tensor) -> Tensor:
    """Elementwise entropy of N(., std^2): 1/2 + log(sqrt(2 pi) std)."""
    return 0.5 + LOG_SQRT_2PI + torch.log(std)


class ActorOutput(NamedTuple):
    """Gaussian over actions for a batch, the next recurrent state and diagnostics."""

    mean: Tensor  # (B, A)
    std: Tensor  # (B, A)
    next_state: Tensor  # (B, *state_shape)
    extras: dict[str, Tensor]  # e.g. xi, kappa, theta_dot, r_ddot, desired_velocity


class ActStep(NamedTuple):
    action: Tensor
    log_prob: Tensor
    value: Tensor
    mean: Tensor
    std: Tensor
    next_state: Tensor
    extras: dict[str, Tensor]


class Agent(nn.Module):
    """Base class: subclasses implement :meth:`actor`, :meth:`critic_features` and
    :meth:`initial_state`, and set ``state_shape``."""

    state_shape: tuple[int, ...] = (0,)
    # what the first axis of the state holds, one name per row (the exported policy's
    # metadata, cpg_actor.deploy.export); none for a stateless agent
    state_rows: tuple[str, ...] = ()

    def __init__(
        self,
        obs_dim: int,
        action_scale: Sequence[float],
        config: AgentConfig,
        critic_state_features: int = 0,
    ) -> None:
        super().__init__()
        scale = torch.as_tensor(action_scale, dtype=torch.float32).reshape(-1)
        if not bool((scale > 0).all()) or not bool(torch.isfinite(scale).all()):
            raise ValueError(f"action_scale must be positive and finite, got {scale.tolist()}")
        self.obs_dim = obs_dim
        # the leading observation entries the actor reads: all here; fewer where the entries
        # after them are the critic's alone (the MLP's privileged critic)
        self.actor_obs = obs_dim
        self.action_dim = int(scale.shape[0])
        # entries of a sampled ActStep.action: the env's action first, then any other random
        # choice the agent makes and the storage keeps (the CPG-Actor's noisy feedback)
        self.sample_dim = self.action_dim
        # (high - low) / 2 of the action space: the unit of init_std (and of the MLP's mean)
        self.register_buffer("action_scale", scale)
        # std = floor + exp(log_std), the floor in action_scale units (a fraction of init_std);
        # without one, exp(log_std) alone, as in the paper
        self.action_floor = float(config.action_std_floor * config.init_std)
        self.log_std = nn.Parameter(torch.log((config.init_std - self.action_floor) * scale))
        critic_in = obs_dim + critic_state_features
        self.critic = mlp([critic_in, *config.critic_hidden, 1], config.activation, 1.0)

    # -- to implement ---------------------------------------------------------------------
    def initial_state(self, batch_size: int) -> Tensor:
        return torch.zeros(batch_size, *self.state_shape, device=self.log_std.device)

    def actor(self, obs: Tensor, state: Tensor) -> ActorOutput:
        raise NotImplementedError

    def cpg_parameters(self) -> list[nn.Parameter]:
        """The parameters that act through a CPG (``ppo.cpg_learning_rate`` applies to them);
        none here."""
        return []

    def keep_observed(self, stepped: Tensor, stored: Tensor) -> Tensor:
        """A replayed state (``stepped``, from the previous step) with what :meth:`observe`
        wrote into the ``stored`` state of the same step put back: replays over several
        steps (``ppo.bptt_steps``) then act from each step's own observation. Default:
        ``stepped``."""
        return stepped

    def observe(self, obs: Tensor, state: Tensor) -> Tensor:
        """The state to act from, given the *raw* (unnormalised) observation ``obs``: called
        before each step (by :class:`cpg_actor.training.policy.Policy` and the exported control
        step), so that the rollout storage keeps it. Default: the state as it is. The CPG-Actor
        writes its drive d here."""
        return state

    def state_features(self, state: Tensor) -> Tensor:
        """What the critic sees of the recurrent state, ``(B, critic_state_features)``."""
        return state.reshape(state.shape[0], 0)

    # -- shared ------------------------------------------------------------------------------
    def value(self, obs: Tensor, state: Tensor) -> Tensor:
        features = torch.cat([obs, self.state_features(state)], dim=-1)
        return self.critic(features).squeeze(-1)

    def act(self, obs: Tensor, state: Tensor, deterministic: bool = False) -> ActStep:
        """Sample (or take the mean) action for a batch; no gradients needed by callers.
        ``obs``: ``(B, obs_dim)``, or the actor's entries alone ``(B, actor_obs)`` (a robot's
        observation, without the critic's privileged entries: the value is then NaN)."""
        out = self.actor(obs, state)
        if deterministic:
            action = out.mean
        else:  # as torch.distributions.Normal.sample: mean + std * N(0, 1), one RNG draw
            with torch.no_grad():
                action = gaussian_sample(out.mean.expand(out.std.shape), out.std)
        log_prob = gaussian_log_prob(action, out.mean, out.std).sum(-1)
        if obs.shape[-1] == self.obs_dim:
            value = self.value(obs, state)
        else:  # the critic's entries are not there
            value = torch.full_like(log_prob, float("nan"))
        return ActStep(action, log_prob, value, out.mean, out.std, out.next_state, out.extras)

    def replay_state(self, obs: Tensor, state: Tensor, sample: Tensor) -> Tensor:
        """The state after the step from ``(obs, state)`` that drew ``sample`` (a stored
        :attr:`ActStep.action`), with gradients: used to replay several steps
        (``ppo.bptt_steps``). Here the sample does not change the state."""
        return self.actor(obs, state).next_state

    def evaluate(self, obs: Tensor, state: Tensor, actions: Tensor) -> tuple[Tensor, ...]:
        """Replay one step from stored (obs, state): ``(log_prob, entropy, value, mean, std)``."""
        out = self.actor(obs, state)
        return (
            gaussian_log_prob(actions, out.mean, out.std).sum(-1),
            gaussian_entropy(out.std).sum(-1),
            self.value(obs, state),
            out.mean,
            out.std,
        )

    def action_std(self) -> Tensor:
        """The std of the Gaussian noise on each action entry, ``(A,)``: ``exp(log_std)``, plus
        ``agent_config.action_std_floor`` of the initial std when there is one."""
        if self.action_floor == 0.0:
            return self.log_std.exp()
        return self.action_floor * self.action_scale + self.log_std.exp()

    def std(self, batch_size: int) -> Tensor:
        return self.action_std().expand(batch_size, self.action_dim)

    # -- logging (the runner writes what the agent gives) -----------------------------------
    def log_scalars(self) -> dict[str, float]:
        """Scalars for TensorBoard and ``metrics.jsonl`` at every logged iteration: the log of
        each action std (the floor included)."""
        logs = self.log_std if self.action_floor == 0.0 else self.action_std().log()
        logs = logs.detach().tolist()
        return {f"policy/log_std_{i}": v for i, v in enumerate(logs)}

    def log_histograms(self) -> dict[str, Tensor]:
        """Histograms for TensorBoard every ``histogram_interval`` iterations."""
        return {}
