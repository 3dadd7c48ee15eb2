"""The CPG inside the environment (Cho et al. 2019; the paper's Fig. 2b baseline).

At every control step the policy's action is a set of CPG parameters; this wrapper steps the
same Hopf network as the CPG-Actor (:func:`cpg_actor.cpg.hopf_step`, eq. 1-2) with them, with
no feedback (xi = kappa = 0) and no gradients, and sends ``nominal pose + x`` to the hopper as
desired joint positions. The CPG state lives here and is reset with each env's episode.

Action, float32 ``(5,)`` in ``[-1, 1]`` (finite values outside are clipped; NaN/inf raise),
mapped affinely onto the parameter ranges of :data:`PARAMETER_RANGES`:

==== ============================ ================= ==========================================
 #   parameter                    range             why
==== ============================ ================= ==========================================
 0   nu_HFE, Hz                   0.2 .. 4          hopping rhythms of a 3.4 kg leg: ~1-3 Hz;
 1   nu_KFE, Hz                   0.2 .. 4          coupled, each may sit below the rhythm
 2   rho_HFE, rad                 0.02 .. 0.6       positive; within the joint stops
 3   rho_KFE, rad                 0.02 .. 0.8       the knee swings farther than the hip
 4   phi_HFE,KFE, rad             -pi .. pi         hip-knee coordination (phi_KFE,HFE = -phi)
==== ============================ ================= ==========================================

Frequency and amplitude per oscillator are what Cho et al. adapt; the phase bias is added
because on a two-joint leg the hip-knee phase lag decides whether the motion is a hop at all.
The convergence rate ``a`` and the coupling weight ``w`` stay at the hopper preset's values:
they shape transients, not the gait, and leaving them out keeps the action small.

Observation, float32 ``(16,)``: the hopper's 8 observations (``OBS_NAMES``), then the CPG state
the environment now owns: ``cos(theta)`` (2), ``sin(theta)`` (2), ``r`` (2), ``r_dot`` (2).

``action_set="paper", observe_cpg=False`` is the baseline as the paper describes it: the
actions are the first four parameters (frequency and amplitude; ranges
:data:`PAPER_PARAMETER_RANGES`), the phase bias stays at the hopper preset's pi, and the
observation is the hopper's 8 values only.
``info`` adds ``cpg_parameters`` (N, 5, physical units), ``theta_dot``, ``r_ddot``,
``cpg_position`` (x) and ``desired_velocity`` (x_dot), each (N, 2).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from cpg_actor.cpg import CPGState, OscillatorParameters, hopf_step
from cpg_actor.robots.common.checks import check_real_tensor, real_actions
from cpg_actor.robots.common.torch_env import EnvStep, TensorEnv
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.cpg import hopper_cpg
from cpg_actor.robots.hopper.task import OBS_BOUND, OBS_NAMES
from cpg_actor.robots.hopper.vector import make_vector_env

PARAMETER_NAMES = ("nu_HFE", "nu_KFE", "rho_HFE", "rho_KFE", "phi_HFE_KFE")
PARAMETER_RANGES = np.array(
    [[0.2, 4.0], [0.2, 4.0], [0.02, 0.6], [0.02, 0.8], [-math.pi, math.pi]], dtype=np.float64
)
CPG_OBS_NAMES = (
    "cos_theta_HFE", "cos_theta_KFE", "sin_theta_HFE", "sin_theta_KFE",
    "r_HFE", "r_KFE", "r_dot_HFE", "r_dot_KFE",
)  # fmt: skip


# The paper's action set for Cho et al. (``action_set="paper"``): frequency and amplitude per
# oscillator only (the phase bias stays at the hopper preset's pi). Its frequency range
# reaches down to 0.2 Hz so that the Ijspeert et al. 2007 warm-start target (0.6 Hz, see
# cpg_actor.robots.hopper.agents) lies well inside it.
PAPER_PARAMETER_RANGES = np.array(
    [[0.2, 4.0], [0.2, 4.0], [0.02, 0.6], [0.02, 0.8]], dtype=np.float64
)
ACTION_SETS = {
    "extended": (PARAMETER_NAMES, PARAMETER_RANGES),
    "paper": (PARAMETER_NAMES[:4], PAPER_PARAMETER_RANGES),
}


def action_to_parameters(action: np.ndarray, ranges: np.ndarray = PARAMETER_RANGES) -> np.ndarray:
    """Map actions in [-1, 1] (clipped) to physical CPG parameters, ``(..., P)`` for the
    ``(P, 2)`` ``ranges`` of an action set (default the extended set's)."""
    unit = (np.clip(action, -1.0, 1.0) + 1.0) / 2.0
    low, high = ranges[:, 0], ranges[:, 1]
    return low + unit * (high - low)


def parameters_to_action(
    parameters: np.ndarray, ranges: np.ndarray = PARAMETER_RANGES
) -> np.ndarray:
    """Inverse of :func:`action_to_parameters` (inside the ranges)."""
    parameters = np.asarray(parameters, dtype=np.float64)
    low, high = ranges[:, 0], ranges[:, 1]
    if np.any(parameters < low) or np.any(parameters > high):
        names = PARAMETER_NAMES[: len(ranges)]
        raise ValueError(
            f"CPG parameters {parameters.tolist()} are outside the ranges "
            f"{dict(zip(names, ranges.tolist(), strict=True))}"
        )
    return 2.0 * (parameters - low) / (high - low) - 1.0


class CPGParameterVectorEnv(VectorEnv):
    """N hoppers driven by N CPGs whose parameters are the actions (SAME_STEP autoreset).

    A wrapper: ``CPGParameterVectorEnv(env)`` puts the CPGs in front of an existing
    :class:`HopperVectorEnv` (what the ``cho2019`` agents declare they need);
    ``CPGParameterVectorEnv(N, config)`` builds that hopper env first. The CPGs run in torch
    on the hopper env's device; around an env with a tensor face (MJX) the wrapper offers one
    too (``reset_tensors`` / ``step_tensors``), with the numbers of its numpy face.

    Args:
        env_or_num_envs: a hopper vector env to wrap (:func:`make_vector_env`: any simulator), or N.
        config: with N, the hopper's :class:`HopperConfig` (or dict); the CPG runs at its
            control rate.
        num_threads: with N, passed to :func:`make_vector_env`.
        action_set: ``"extended"`` (5 actions, the phase bias included) or ``"paper"`` (4:
            frequency and amplitude; the phase bias fixed at the preset's).
        observe_cpg: append the CPG state to the observation (16 values; False: 8).
        cpg_initial: overrides of the hopper CPG preset (:func:`hopper_cpg`): the convergence
            rate and coupling weight the actions do not set.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(
        self,
        env_or_num_envs: VectorEnv | int,
        config: HopperConfig | dict | None = None,
        num_threads: int | None = None,
        action_set: str = "extended",
        observe_cpg: bool = True,
        cpg_initial: dict | None = None,
    ) -> None:
        if action_set not in ACTION_SETS:
            raise ValueError(f"action_set must be one of {sorted(ACTION_SETS)}, got {action_set!r}")
        self.action_set = action_set
        self.parameter_names, self.parameter_ranges = ACTION_SETS[action_set]
        self.observe_cpg = observe_cpg
        if isinstance(env_or_num_envs, VectorEnv):  # a hopper vector env (any simulator)
            if config is not None or num_threads is not None:
                raise ValueError("config and num_threads belong to the wrapped env, not here")
            self.env = env_or_num_envs
        else:
            self.env = make_vector_env(env_or_num_envs, config=config, num_threads=num_threads)
        if self.env.config.normalized_actions:
            self.env.close()
            raise ValueError(
                "the Cho et al. env drives the hopper with desired positions in rad: "
                "normalized_actions must be false"
            )
        self.config = self.env.config
        self.num_envs = self.env.num_envs
        # the CPGs run in torch (float64) where the hopper runs: the CPU for the numpy
        # simulators, JAX's device for MJX (whose tensor face this wrapper then offers too)
        self.device = torch.device(getattr(self.env, "device", "cpu"))
        # The hopper preset supplies a, w, the topology and the initial phases (``cpg_initial``
        # overrides them: a start gait's a and w); its trainable vector is never used for
        # gradients here.
        self.cpg = hopper_cpg(self.config.control_dt, initial=cpg_initial, dtype=torch.float64).to(
            self.device
        )
        values = self.cpg.parametrisation.values()
        self._convergence = values["convergence"].detach()
        self._coupling_weight = values["coupling_weight"].detach()
        self._coupling = self.cpg.parametrisation.coupling
        self._phase_bias = float(values["phase_bias"][0, 1].detach())  # when not an action
        ranges = torch.as_tensor(self.parameter_ranges, dtype=torch.float64, device=self.device)
        self._low, self._high = ranges[:, 0], ranges[:, 1]
        self.robot = self.env.robot  # the hopper it drives (the actions are CPG parameters)
        self._offset = torch.as_tensor(
            self.robot.nominal_pose, dtype=torch.float64, device=self.device
        )
        obs_dim = len(OBS_NAMES) + (len(CPG_OBS_NAMES) if observe_cpg else 0)
        bound = np.full(obs_dim, OBS_BOUND, dtype=np.float32)
        self.single_observation_space = spaces.Box(-bound, bound, dtype=np.float32)
        self.action_dim = len(self.parameter_names)
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(self.action_dim,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.metadata = {**self.metadata, "render_fps": self.env.metadata["render_fps"]}
        self.state = self._initial_state(self.num_envs)
        if isinstance(self.env, TensorEnv):  # a device env: tensors in and out, no host copy
            self.reset_tensors, self.step_tensors = self._reset_tensors, self._step_tensors

    # -- CPG (torch, on self.device) -------------------------------------------------------------
    def _initial_state(self, count: int) -> CPGState:
        return self.cpg.initial_state(count)

    def parameters(self, actions: torch.Tensor) -> torch.Tensor:
        """Actions ``(N, P)`` in [-1, 1] (clipped) -> all five physical parameters ``(N, 5)``
        (:func:`action_to_parameters`; the phase bias fixed at the preset's when it is not an
        action), float64 on ``self.device``."""
        unit = (actions.to(self.device, torch.float64).clamp(-1.0, 1.0) + 1.0) / 2.0
        parameters = self._low + unit * (self._high - self._low)
        if parameters.shape[-1] == len(PARAMETER_NAMES):
            return parameters
        fixed = parameters.new_full((*parameters.shape[:-1], 1), self._phase_bias)
        return torch.cat([parameters, fixed], dim=-1)

    def oscillator_parameters(self, parameters: torch.Tensor) -> OscillatorParameters:
        """Physical parameters ``(N, 5)`` -> the :class:`OscillatorParameters` of eq. 1."""
        p = parameters
        phase_bias = p.new_zeros(p.shape[0], 2, 2)
        phase_bias[:, 0, 1] = p[:, 4]
        phase_bias[:, 1, 0] = -p[:, 4]
        return OscillatorParameters(
            frequency=p[:, 0:2],
            amplitude=p[:, 2:4],
            convergence=self._convergence,
            coupling_weight=self._coupling_weight,
            phase_bias=phase_bias,
        )

    @torch.no_grad()
    def _cpg_step(self, actions: torch.Tensor):
        """The CPG step of eq. 1-2 from actions: ``(parameters, output, next_state)``."""
        parameters = self.parameters(actions)
        output, next_state = hopf_step(
            self.oscillator_parameters(parameters), self.state, self._coupling,
            self.config.control_dt,
        )  # fmt: skip
        return parameters, output, next_state

    def _observation(self, env_obs: torch.Tensor, state: CPGState) -> torch.Tensor:
        """The hopper's observation, with the CPG state's features unless ``observe_cpg`` is
        off, clipped to the bound: float32 on ``self.device``."""
        env_obs = torch.as_tensor(env_obs, device=self.device)
        if not self.observe_cpg:
            return env_obs.clamp(-OBS_BOUND, OBS_BOUND).to(torch.float32)
        features = [torch.cos(state.phase), torch.sin(state.phase), state.amplitude,
                    state.amplitude_velocity]  # fmt: skip
        obs = torch.cat([env_obs.to(torch.float64), *features], dim=-1)
        return obs.clamp(-OBS_BOUND, OBS_BOUND).to(torch.float32)

    def _end_episodes(self, done: torch.Tensor, state: CPGState) -> CPGState:
        """``state`` with the rows of the envs that ended restarted."""
        rows = done.to(self.device).reshape(-1, 1)
        fresh = self._initial_state(self.num_envs)
        return CPGState(
            *(torch.where(rows, new, old) for old, new in zip(state, fresh, strict=True))
        )

    def _check_open(self, what: str) -> None:
        if getattr(self, "env", None) is None:
            raise gym.error.ClosedEnvironmentError(
                f"{what}() on a closed environment; make a new one"
            )

    def _check_actions(self, actions: torch.Tensor, check_finite: bool = True) -> None:
        check_real_tensor(actions)
        if tuple(actions.shape) != (self.num_envs, self.action_dim):
            raise ValueError(
                f"actions must have shape ({self.num_envs}, {self.action_dim}) (CPG parameters "
                f"{', '.join(self.parameter_names)} in [-1, 1]), got {tuple(actions.shape)}"
            )
        if check_finite and not bool(torch.isfinite(actions).all()):
            raise ValueError("actions contain NaN or inf; CPG parameters must be finite")

    def _cpg_info(self, parameters, output, next_state) -> dict[str, torch.Tensor]:
        return {
            "cpg_parameters": parameters,
            "theta_dot": next_state.phase_velocity.clone(),
            "r_ddot": next_state.amplitude_acceleration.clone(),
            "cpg_position": output.position.clone(),
            "desired_velocity": output.velocity.clone(),
        }

    # -- VectorEnv API (numpy) -------------------------------------------------------------------
    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        self._check_open("reset")
        env_obs, info = self.env.reset(seed=seed, options=options)
        self.state = self._initial_state(self.num_envs)
        return self._observation(env_obs, self.state).cpu().numpy(), info

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        self._check_open("step")
        array = real_actions(actions, f"of shape ({self.num_envs}, {self.action_dim})")
        self._check_actions(torch.from_numpy(array))
        parameters, output, next_state = self._cpg_step(torch.from_numpy(array))
        desired = (output.position + self._offset).cpu().numpy()
        env_obs, reward, terminated, truncated, info = self.env.step(desired)
        done = torch.as_tensor(terminated | truncated)
        info = dict(info)
        info["final_obs"] = self._observation(info["final_obs"], next_state).cpu().numpy()
        self.state = self._end_episodes(done, next_state)
        info.update(
            {k: v.cpu().numpy() for k, v in self._cpg_info(parameters, output, next_state).items()}
        )
        obs = self._observation(env_obs, self.state).cpu().numpy()
        return obs, reward, terminated, truncated, info

    # -- the trainer's tensor face (only when the hopper env has one: MJX) ----------------------
    def _reset_tensors(self, seed: int | list[int] | None = None):
        self._check_open("reset")
        env_obs, info = self.env.reset_tensors(seed)
        self.state = self._initial_state(self.num_envs)
        return self._observation(env_obs, self.state), info

    def _step_tensors(self, actions: torch.Tensor, check_finite: bool = True) -> EnvStep:
        # check_finite: the MJX hopper's (False: no wait for the device); the CPG's output is
        # finite for finite parameters, and the hopper's own check would be a second wait
        self._check_open("step")
        self._check_actions(actions, check_finite)
        parameters, output, next_state = self._cpg_step(actions)
        out = self.env.step_tensors(
            (output.position + self._offset).to(torch.float32), check_finite=False
        )
        final_obs = self._observation(out.final_obs, next_state)
        self.state = self._end_episodes(out.terminated | out.truncated, next_state)
        info = {**out.info, "final_obs": final_obs}
        info.update(self._cpg_info(parameters, output, next_state))
        obs = self._observation(out.obs, self.state)
        return out._replace(obs=obs, final_obs=final_obs, info=info)

    def get_state(self) -> dict[str, Any]:
        """The hopper's state (:meth:`HopperVectorEnv.get_state`) and the CPG state."""
        self._check_open("get_state")
        return {"hopper": self.env.get_state(), "cpg": self.state.as_tensor().cpu().clone()}

    def set_state(self, state: dict[str, Any]) -> None:
        self._check_open("set_state")
        self.env.set_state(state["hopper"])
        self.state = CPGState.from_tensor(state["cpg"].to(self.device, torch.float64).clone())

    def render_frame(self, index: int = 0) -> np.ndarray:
        """An RGB frame of env ``index`` (see :meth:`HopperVectorEnv.render_frame`)."""
        return self.env.render_frame(index)

    def close_extras(self, **kwargs: Any) -> None:
        if getattr(self, "env", None) is not None:
            self.env.close()
            self.env = None
