"""`QuadrupedVectorEnv`: N quadrupeds on MuJoCo, a Gymnasium ``VectorEnv`` (SAME_STEP autoreset),
the locomotion task of :mod:`cpg_actor.tasks.velocity`. A robot's env is a subclass that names
its :class:`~cpg_actor.robots.common.quadruped.model.QuadrupedModel` (``quadruped``), e.g.
:class:`cpg_actor.robots.anymal.vector.AnymalVectorEnv`.

The task's step (:func:`cpg_actor.tasks.velocity.step`) is the MJX env's too: only the physics
differs. As the hopper's MuJoCo env: the robots are rows of one state array and a control step is
``mujoco.rollout`` of ``decimation`` substeps over chunks of them, on the calling thread and
a helper per further core (``ThreadedRollout``), the ``dcmotor`` actuators running the
actuator law inside MuJoCo. Actions are desired joint positions (12,
rad; in [-1, 1] with ``normalized_actions``), clipped to the joint ranges.

Per episode: a forward-speed command uniform in ``command_range`` (lateral and yaw speed
commands uniform in ``lateral_range`` and ``yaw_range``, 0 by default; zero with probability
``standing_share``; under legged_gym's heading command, ``heading_gain``, a heading instead
of the yaw rate, which follows it after every step), drawn again every
``command_resample_seconds`` where that is not 0 (the observation after the step that draws
it carries the new one), a start in the nominal pose (scaled per joint with
``reset_joint_scale``) with uniform joint noise, the feet on the ground, at rest (the base's
velocities uniform with ``reset_base_velocity``) (on rough
ground, ``config.terrain``: on the env's tile, heights read over the ground and a curriculum
over its levels, :mod:`cpg_actor.robots.common.quadruped.ground`). An episode ends
when the base falls (``task.fallen``) or touches the ground (terminated), or after
``episode_seconds`` (truncated). ``info["episode_metrics"]`` (NaN for envs still running):
``speed_error`` (mean |forward speed - command| over the episode, m/s), ``forward_speed`` (mean,
m/s), ``fell`` (1 or 0), ``episode_seconds``, ``cost_of_transport`` (the joints' mechanical
work, sum of |torque x joint speed| dt, over m g times the distance walked forward; NaN under
0.1 m), ``foot_slip`` (the planted feet's mean sliding speed, m/s: ``task.planted_slip``
over every foot and step it applies to; NaN if no foot was planted), ``lin_vel_error`` (mean
|v_xy - command_xy| in the base frame, m/s), ``yaw_rate_error`` (mean |yaw rate - command|,
rad/s), their offsets ``lin_vel_offset`` and ``yaw_rate_offset`` (the error of the mean: the
gait's sway averaged out), ``duty_factor`` (the share of steps a foot is on the ground, mean
over the feet) and ``planar_cost_of_transport`` (as ``cost_of_transport``, over the length of
the base's path in the plane).

``info`` of a step also has, per env: ``command`` (the one the step ran under, also on the step
that ends an episode), ``contact`` (4 bool, the feet in the robot's leg order (``foot_names``)
within 5 mm of the ground), ``forward_speed`` (the base's, m/s), ``base_height``,
``desired_position`` and ``measured_position``.

Seeding: ``reset(seed=s)`` seeds env i with ``s + i``; every random draw (noise, commands)
comes from env i's own generator.

Rendering: :meth:`QuadrupedVectorEnv.render_frame` draws one robot with MuJoCo's offscreen
renderer (needs an OpenGL backend, as the hopper's), a camera following the base over the
checkered ground.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv

from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.checks import real_actions
from cpg_actor.robots.common.mujoco_runtime import (
    CONTROL_SPEC,
    PUSH_SPEC,
    STATE_SPEC,
    add_mass,
    default_threads,
    mujoco,
    offscreen_renderer,
)
from cpg_actor.robots.common.perturbation import (
    CommandDelay,
    EpisodeDraws,
    Randomization,
    push_force,
)
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.common.quadruped.ground import Ground, terrain_model
from cpg_actor.robots.common.quadruped.model import SENSORS, QuadrupedModel
from cpg_actor.robots.common.seeding import env_seeds
from cpg_actor.robots.common.threaded_rollout import ThreadedRollout
from cpg_actor.robots.spec import RobotSpec
from cpg_actor.tasks import velocity as task

# the task's episode fields a saved state holds (the feet's positions are its sensors')
SAVED_FIELDS = tuple(name for name in task.Episode._fields if name != "feet_xy")
# zero in states saved before they existed
ADDED_FIELDS = ("slip_sum", "planted_steps", "lin_vel_error_sum", "yaw_rate_error_sum",
                "contact_steps", "path_length", "velocity_offset_sum", "swing_peak")  # fmt: skip
SHAPES = {"velocity_offset_sum": (3,), "swing_peak": (4,)}  # per env, of the added fields
COUNTS = ("planted_steps", "contact_steps")  # the integer ones


# the robot's models as compiled from its MJCF, by (MJCF generator, actuator, torque control),
# with a scratch MjData of their sizes: randomised training loads a model per episode, and
# copying a compiled one is much cheaper than generating and compiling the MJCF again; the
# copy holds the same numbers (tests/training/test_same_numbers.py)
_COMPILED: dict[tuple, tuple[mujoco.MjModel, mujoco.MjData]] = {}
_KEPT = 4  # compiled models kept (randomised motor strengths make a new one per episode)


def compiled_model(quadruped: QuadrupedModel, actuator: Actuator | None,
                   torque_control: bool) -> tuple[mujoco.MjModel, mujoco.MjData]:  # fmt: skip
    """A copy of the robot's model compiled from its MJCF with ``actuator`` (plain motors
    with ``torque_control``), and a scratch MjData of its sizes (shared: for computing its
    constants, never for stepping)."""
    key = (quadruped.mjcf_text, repr(actuator), torque_control)
    if key not in _COMPILED:
        model = mujoco.MjModel.from_xml_string(
            quadruped.mjcf_text(actuator, torque_control=torque_control))  # fmt: skip
        if len(_COMPILED) >= _KEPT:
            _COMPILED.pop(next(iter(_COMPILED)))
        _COMPILED[key] = (model, mujoco.MjData(model))
    model, scratch = _COMPILED[key]
    return copy.copy(model), scratch


def load_model(quadruped: QuadrupedModel, config: QuadrupedConfig,
               torque_control: bool = False) -> mujoco.MjModel:  # fmt: skip
    """The robot's MjModel under ``config``: its actuators (plain motors with
    ``torque_control``), timestep and foot-ground friction, and its perturbation's motor
    strength, ground friction and payload (on the base)."""
    perturbation = config.perturbation
    actuator = None if torque_control else perturbation.actuator(Actuator.from_config(config))
    scratch = None
    if config.terrain.active:  # the ground a height field (docs/quadruped.md, "Terrain")
        text = quadruped.mjcf_text(actuator, torque_control=torque_control)
        model = terrain_model(text, config.terrain)
    else:
        model, scratch = compiled_model(quadruped, actuator, torque_control)
    model.opt.timestep = config.physics_dt
    friction = perturbation.ground_friction(config.foot_friction)
    for leg in quadruped.legs:
        model.geom_friction[model.geom(f"{leg}_foot").id, 0] = friction
    model.geom_friction[model.geom("ground").id, 0] = friction
    if config.feet_only:
        floor_feet_only(model, quadruped.legs)
    if perturbation.payload:
        add_mass(model, quadruped.base_body, perturbation.payload, scratch)
    if not perturbation.model_nominal:  # the joints' and the contact's (randomised training)
        model_terms(model, quadruped, perturbation)
    return model


def floor_feet_only(model: mujoco.MjModel, legs) -> None:
    """Take every geom of the robot but its feet (``<leg>_foot``) out of collisions
    (``QuadrupedConfig.floor_contacts``): the robot's geoms collide with the floor alone."""
    feet = {model.geom(f"{leg}_foot").id for leg in legs}
    for geom in range(model.ngeom):
        if model.geom_bodyid[geom] != 0 and geom not in feet:  # body 0: the world's floor
            model.geom_contype[geom] = model.geom_conaffinity[geom] = 0


def draw_command(rng: np.random.Generator, config: QuadrupedConfig) -> np.ndarray:
    """One command (3,): forward and lateral speed (m/s), yaw rate (rad/s), each uniform in its
    range, or zero with probability ``standing_share``; under a heading command
    (``heading_gain``) the yaw rate is 0, not drawn (the env sets it from the heading,
    :func:`draw_heading`), and a (vx, vy) of norm at most ``min_command_speed`` is zeroed
    (legged_gym's). Only the draws a config needs are taken (the lateral and yaw ones where
    the range is not a point, the standing one where the share is not 0), so that the
    forward task's random streams stay as they were."""
    command = np.zeros(3)
    command[0] = rng.uniform(*config.command_range)
    names = ((1, "lateral_range"),) if config.heading_gain else ((1, "lateral_range"),
                                                                 (2, "yaw_range"))  # fmt: skip
    for column, name in names:
        low, high = getattr(config, name)
        command[column] = rng.uniform(low, high) if high > low else low
    if config.min_command_speed and np.hypot(*command[:2]) <= config.min_command_speed:
        command[:2] = 0.0
    if config.standing_share > 0 and rng.uniform() < config.standing_share:
        command[:] = 0.0
    return command


def draw_heading(rng: np.random.Generator, config: QuadrupedConfig) -> float:
    """The heading (rad) a heading command turns the base to, uniform in ``heading_range``,
    drawn after each command's :func:`draw_command`."""
    low, high = config.heading_range
    return float(rng.uniform(low, high)) if high > low else low


def hold_command(previous, fresh, hold, nonzero):
    """MuJoCo Playground's command resampling (``go1/joystick.py``, ``sample_command``) given
    its draws: each entry of ``previous`` (3,) is kept where ``hold`` (3, bool), else it
    becomes ``fresh`` (uniform in its range) where ``nonzero`` (3, bool), else 0."""
    return np.where(hold, previous, np.where(nonzero, fresh, 0.0))


def resample_command(rng: np.random.Generator, previous: np.ndarray,
                     config: QuadrupedConfig) -> np.ndarray:  # fmt: skip
    """A command drawn again within an episode: :func:`draw_command`, or with
    ``command_nonzero`` Playground's process (:func:`hold_command`)."""
    if config.command_nonzero is None:
        return draw_command(rng, config)
    low, high = np.array([config.command_range, config.lateral_range, config.yaw_range]).T
    fresh = rng.uniform(low, high)
    hold = rng.uniform(size=3) < config.command_hold
    nonzero = rng.uniform(size=3) < np.asarray(config.command_nonzero)
    return hold_command(previous, fresh, hold, nonzero)


def steps_to_next_command(rng: np.random.Generator, config: QuadrupedConfig) -> int:
    """Control steps until the next resampling: ``resample_steps``, or with ``command_interval``
    "exponential" an exponential time of mean ``command_resample_seconds`` (Playground's),
    at least one step."""
    if config.command_interval != "exponential":
        return config.resample_steps
    seconds = rng.exponential(config.command_resample_seconds)
    return max(1, round(seconds / config.control_dt))


def action_bounds(quadruped: QuadrupedModel, config: QuadrupedConfig):
    """``(low, high)`` (J,) of the actions (rad): the robot's action limits, within the
    nominal pose +- ``action_scale`` where that is set."""
    low, high = quadruped.low, quadruped.high
    if config.action_scale:
        nominal = np.asarray(quadruped.nominal_pose)
        low = np.maximum(low, nominal - config.action_scale)
        high = np.minimum(high, nominal + config.action_scale)
    return low, high


def model_terms(model: mujoco.MjModel, quadruped: QuadrupedModel, perturbation) -> None:
    """The perturbation's factors on the joints' passive damping and armature (every dof but
    the free base's six) and on the contact time constant (solref's first number) of the
    feet and the ground, written into ``model``."""
    model.dof_damping[6:] *= perturbation.joint_damping
    model.dof_armature[6:] *= perturbation.armature
    for geom in [*(f"{leg}_foot" for leg in quadruped.legs), "ground"]:
        model.geom_solref[model.geom(geom).id, 0] *= perturbation.contact_softness


def resolve_config(
    config: QuadrupedConfig | dict | None, config_class: type = QuadrupedConfig
) -> QuadrupedConfig:
    """``config`` (a ``config_class``, a variant of it, or a dict of its fields; defaults if
    None), validated."""
    name = config_class.__name__
    if config is None:
        config = config_class()
    elif isinstance(config, dict):
        config = config_class.from_dict(config)
    # a subclass for another body (the Go1's of ANYmal's) is not this robot's; a variant is
    elif not (isinstance(config, config_class) and config.body == config_class.body):
        raise ValueError(f"config must be a {name} or a dict of its fields, got "
                         f"{type(config).__name__}")  # fmt: skip
    return config.validate()


SIMULATOR_NAMES = {"mujoco": "MuJoCo", "mjx": "MJX"}


def init_spaces(
    env: VectorEnv,
    num_envs: int,
    config: QuadrupedConfig | dict | None,
    max_episode_steps: int | None,
    sim: str,
) -> None:
    """``env.config`` (validated), ``num_envs``, ``env.robot`` and the observation and action
    spaces of a quadruped vector env on the simulator ``sim`` (MuJoCo's and MJX's alike):
    ValueError for a config of another simulator. ``max_episode_steps`` is what
    ``gymnasium.make_vec`` passes from the registered spec: it must equal the config's
    ``episode_steps`` (the env truncates its episodes itself)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
    quadruped = env.quadruped
    config = resolve_config(config, quadruped.config_class)
    if config.sim != sim:
        other = " (sim='mjx': the robot's MJX env)" if sim == "mujoco" else ""
        raise ValueError(f"{type(env).__name__} simulates with {SIMULATOR_NAMES[sim]}, got "
                         f"sim={config.sim!r}{other}")  # fmt: skip
    if max_episode_steps is not None and max_episode_steps != config.episode_steps:
        raise ValueError(
            f"max_episode_steps={max_episode_steps} differs from the config's episode_steps="
            f"{config.episode_steps} (episode_seconds / control_dt); give both the same value"
        )
    env.config = config
    env.num_envs = num_envs
    names = observation_names(quadruped, config)
    n_obs, n_act = len(names), len(quadruped.joint_names)
    env.single_observation_space = gym.spaces.Box(-np.inf, np.inf, (n_obs,), np.float32)
    if config.normalized_actions:
        env.single_action_space = gym.spaces.Box(-1.0, 1.0, (n_act,), np.float32)
    else:
        low, high = (bound.astype(np.float32) for bound in action_bounds(quadruped, config))
        env.single_action_space = gym.spaces.Box(low, high)
    env.observation_space = gym.vector.utils.batch_space(env.single_observation_space, num_envs)
    env.action_space = gym.vector.utils.batch_space(env.single_action_space, num_envs)
    env.robot = robot_spec(quadruped, config)


def observation_names(quadruped: QuadrupedModel, config: QuadrupedConfig) -> tuple[str, ...]:
    """The observation's entries under ``config`` (the recipe's options add some)."""
    return task.observation_names(quadruped.joint_names, config.observe_lin_vel,
                                  config.privileged_observation)  # fmt: skip


def robot_spec(quadruped: QuadrupedModel, config: QuadrupedConfig) -> RobotSpec:
    low, high = action_bounds(quadruped, config)
    return RobotSpec(
        name=quadruped.name,
        joint_names=quadruped.joint_names,
        nominal_pose=quadruped.nominal_pose,
        action_low=tuple(low),
        action_high=tuple(high),
        control_dt=config.control_dt,
        observation_names=observation_names(quadruped, config),
        drive_observation="command_vx",  # the commanded forward speed (m/s) drives the CPG
        command_observations=("command_vx", "command_vy", "command_yaw"),  # planar steps'
    )


class QuadrupedVectorEnv(VectorEnv):
    """N quadrupeds (``quadruped``, set by a robot's subclass) walking on flat ground (module
    docstring).

    Args:
        num_envs: N.
        config: the robot's config (``quadruped.config_class``) or a dict of its fields;
            defaults if None.
        num_threads: MuJoCo stepping threads; None: the usable cores (>= 8 robots each).
        max_episode_steps: what ``gymnasium.make_vec`` passes from the registered spec; must
            equal the config's ``episode_steps`` (the env truncates its episodes itself).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    quadruped: QuadrupedModel  # the robot (a subclass sets it)

    @property
    def foot_names(self) -> tuple[str, ...]:
        """The columns of ``info["contact"]``."""
        return self.quadruped.legs

    def __init__(
        self,
        num_envs: int,
        config: QuadrupedConfig | dict | None = None,
        num_threads: int | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        init_spaces(self, num_envs, config, max_episode_steps, sim="mujoco")
        config, quadruped = self.config, self.quadruped
        self.model = load_model(quadruped, config)
        self._low, self._high = action_bounds(quadruped, config)
        # the soft joint limits of the dof_pos_limits term (the MJCF's ranges, scaled)
        ranges = np.array([self.model.joint(name).range for name in quadruped.joint_names])
        self._soft_range = tuple(ranges.T * config.soft_joint_limit_factor)
        # the recipe's uniform observation noise: its half-width per actor entry
        self._noise = task.noise_half_widths(config.observation_noise, len(quadruped.joint_names),
                                             config.observe_lin_vel)  # fmt: skip
        self._unit_draws = np.empty((num_envs, len(self._noise)))  # its draws, per env
        self._next_draw = np.zeros(num_envs, dtype=np.int64)  # the step of each next command
        self._heading = np.zeros(num_envs)  # each env's heading target (config.heading_gain)
        self._nominal = np.asarray(quadruped.nominal_pose)
        threads = default_threads(num_envs) if num_threads is None else int(num_threads)
        self.num_threads = max(1, min(threads, num_envs))
        self.stepper = ThreadedRollout(self.model, num_envs, self.num_threads)  # its threads
        self._data = mujoco.MjData(self.model)  # for resets and queries between control steps
        nstate = mujoco.mj_stateSize(self.model, STATE_SPEC)
        self._state = np.zeros((num_envs, nstate))
        self._next = np.zeros((num_envs, config.decimation, nstate))
        self._control = np.zeros((num_envs, config.decimation, self.model.nu))
        self._sensors = np.zeros((num_envs, config.decimation, self.model.nsensordata))
        self._power = np.zeros((num_envs, config.decimation, self.model.nu))  # |torque x speed|
        nq, nv = self.model.nq, self.model.nv
        self.qpos = self._state[:, 1 : 1 + nq]
        self.qvel = self._state[:, 1 + nq : 1 + nq + nv]
        offsets, start = {}, self.model.nu
        for name, size in SENSORS:
            offsets[name] = slice(start, start + size)
            start += size
        self._offsets = offsets
        perturbation, randomize = config.perturbation, config.randomize
        latency = perturbation.substeps(config.decimation)
        longest = round(randomize.latency[1] * config.decimation)
        self.delay = None  # the perturbation's latency, sensor noise and push
        if latency or longest:
            self.delay = CommandDelay(latency, config.decimation, num_envs, self.model.nu,
                                      longest)  # fmt: skip
        self.draws = EpisodeDraws(config, num_envs, task.sensor_noise(len(quadruped.joint_names)))
        self._push = push_force(perturbation, config.control_dt)  # N, in the heading frame
        self._payload = np.full(num_envs, perturbation.payload)  # per env (randomised)
        self._base = self.model.body(quadruped.base_body).id
        self.ground = None  # rough ground: each env's tile and level (None: flat)
        if config.terrain.active:
            self.ground = Ground(config.terrain, num_envs, config.episode_seconds)
        self._rngs: list[np.random.Generator] | None = None
        self.episode: task.Episode | None = None  # the task's bookkeeping
        self._needs_reset = True
        self._renderer: mujoco.Renderer | None = None
        self._camera: mujoco.MjvCamera | None = None
        self._render_model: mujoco.MjModel | None = None
        self._render_data: mujoco.MjData | None = None

    @property
    def env_rngs(self) -> list[np.random.Generator] | None:
        """Each env's random generator (reset noise, commands); None before the first reset.
        Assigning a list of ``num_envs`` generators makes the next draws come from them (the
        single-robot env hands its ``np_random`` over this way)."""
        return self._rngs

    @env_rngs.setter
    def env_rngs(self, rngs: list[np.random.Generator]) -> None:
        if not (
            isinstance(rngs, list | tuple)
            and len(rngs) == self.num_envs
            and all(isinstance(rng, np.random.Generator) for rng in rngs)
        ):
            raise ValueError(
                f"env_rngs must be a list of {self.num_envs} numpy Generators, got {rngs!r}"
            )
        self._rngs = list(rngs)

    @property
    def command(self) -> np.ndarray:
        """(N, 3) each env's command: forward, lateral (m/s), yaw (rad/s)."""
        return self.episode.command

    # -- episodes ------------------------------------------------------------------------------
    def _start(self, done: np.ndarray) -> None:
        """New episodes for the envs where ``done`` (N,) is set: pose, command, the task's
        bookkeeping."""
        index = np.flatnonzero(done)
        command, joints = np.zeros((self.num_envs, 3)), np.zeros((self.num_envs, 12))
        cfg = self.config
        for i in index:
            rng = self._rngs[i]
            noise = rng.uniform(-cfg.reset_noise, cfg.reset_noise, 12)
            pose = self._nominal
            if cfg.reset_joint_scale is not None:  # legged_gym's nominal x U(0.5, 1.5)
                pose = pose * rng.uniform(*cfg.reset_joint_scale, 12)
            joints[i] = np.clip(pose + noise, self._low, self._high)
            command[i] = draw_command(rng, cfg)
            if cfg.heading_gain:
                self._heading[i] = draw_heading(rng, cfg)
            if cfg.command_interval == "exponential":
                self._next_draw[i] = steps_to_next_command(rng, cfg)
            data = self._data
            mujoco.mj_resetData(self.model, data)
            data.qpos[7:] = joints[i]
            if self.ground is not None:  # on its tile, drawn after the flat task's draws
                self.ground.place(self.model, data, i, rng, self.quadruped)
            else:
                mujoco.mj_kinematics(self.model, data)
                lowest = min(data.site(f"{leg}_foot").xpos[2] for leg in self.quadruped.legs)
                data.qpos[2] += self.quadruped.foot_radius - lowest  # feet on the ground
            if cfg.reset_base_velocity:  # linear (world) and angular: the base starts level
                speed = cfg.reset_base_velocity
                data.qvel[:6] = rng.uniform(-speed, speed, 6)
            mujoco.mj_getState(self.model, data, self._state[i], STATE_SPEC)
        if cfg.heading_gain:  # the yaw rate toward each new heading, from the start's yaw
            command[index, 2] = self._heading_yaw_rate(index)
        self._refresh_sensors(index)
        fresh = task.new_episode(command, joints, self.qpos[:, 0].copy(),
                                 self._feet()[:, :, :2].copy())  # fmt: skip
        self.episode = fresh if self.episode is None else task.restart(self.episode, done, fresh)
        self.draws.start(index)
        if self.config.randomize.active:  # each env's episode perturbation
            self._perturb(index)
        if self.delay is not None:  # the drives hold the start pose until the first command
            self.delay.reset(index, joints[index])

    def _heading_yaw_rate(self, index=slice(None)) -> np.ndarray:
        """The heading command's yaw rate of the envs ``index`` now (``config.heading_gain``)."""
        cfg = self.config
        return task.heading_yaw_rate(self.qpos[index, 3:7], self._heading[index],
                                     cfg.heading_gain, *cfg.yaw_range)  # fmt: skip

    def _perturb(self, index: np.ndarray) -> None:
        """The envs ``index`` simulated under their episode perturbations (randomised
        training): a model of their own (payload, friction, motor strength), their latency."""
        for i in index:
            episode = self.draws.episodes[i]
            config = dataclasses.replace(self.config, perturbation=episode,
                                         randomize=Randomization())  # fmt: skip
            self.stepper.set_model(int(i), load_model(self.quadruped, config))
            self._payload[i] = episode.payload
            if self.delay is not None:
                self.delay.set_latency(i, episode.substeps(self.config.decimation))

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every env. ``seed``: an int s (env i gets s + i), a list of N ints, or None."""
        self._check_open("reset")
        if seed is not None or self._rngs is None:
            seeds = env_seeds(seed, self.num_envs) if seed is not None else [None] * self.num_envs
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
            self.draws.seed(seeds)
        self._sensors[:] = 0.0
        self.episode = None
        if self.ground is not None:  # every env back on its first level
            self.ground.restart()
        self._start(np.ones(self.num_envs, dtype=bool))
        self._needs_reset = False
        return self._observe(), {"command": self.command.copy()}

    def _refresh_sensors(self, index: np.ndarray) -> None:
        """Sensor values of freshly reset robots (no step has written them yet)."""
        data = self._data
        for i in index:
            mujoco.mj_setState(self.model, data, self._state[i], STATE_SPEC)
            mujoco.mj_forward(self.model, data)
            self._sensors[i, -1] = data.sensordata

    def _sensor(self, name: str) -> np.ndarray:
        return self._sensors[:, -1, self._offsets[name]]

    def _feet(self) -> np.ndarray:
        """(N, 4, 3) the feet's positions (world, m), in ``foot_names`` order."""
        return self._sensor("feet").reshape(-1, 4, 3)

    def _observe(self, index=None) -> np.ndarray:
        """The observation of robots at rest as the sensors read it (a perturbation's noise on
        rows ``index``, default all; the recipe's noise on those rows too)."""
        episode, config = self.episode, self.config
        lin_vel, privileged = self._sensor("velocimeter"), None
        if config.privileged_observation:  # at rest: no torque, feet planted
            gyro, n = self._sensor("gyro"), self.num_envs
            joints = self.qpos[:, 7:]
            privileged = task.privileged_observation(
                gyro, task.projected_gravity(self.qpos[:, 3:7]), lin_vel, joints - self._nominal,
                self.qvel[:, 6:], np.zeros_like(joints), episode.in_contact, np.zeros((n, 4, 2)),
                np.zeros((n, 4)))  # fmt: skip
        obs = task.observe(self.qpos, self.qvel, self._sensor("gyro"), episode.command,
                           episode.last_action, self._nominal,
                           lin_vel if config.observe_lin_vel else None, privileged)  # fmt: skip
        return self._recipe_noise(self.draws.observe(obs, index), index)

    def _recipe_noise(self, obs: np.ndarray, index=None) -> np.ndarray:
        """``obs`` with the recipe's uniform noise (``observation_noise``) on the actor's entries
        of rows ``index`` (default all), each row's from its env's generator, in place."""
        if not self._noise.any():
            return obs
        rows = np.arange(self.num_envs) if index is None else np.atleast_1d(index)
        width = len(self._noise)
        # each row's draws from its env's generator, the arithmetic on all rows at once:
        # uniform(-1, 1) is -1 + 2 u of the same u, exactly (2 u and the sum round nothing)
        draws = self._unit_draws[: len(rows)]
        for k, i in enumerate(rows):
            self._rngs[i].random(out=draws[k])
        np.multiply(draws, 2.0, out=draws)
        np.subtract(draws, 1.0, out=draws)
        noise = task.uniform_noise(draws, self._noise).astype(obs.dtype)
        if index is None:
            obs[:, :width] += noise
        else:
            obs[rows, :width] += noise
        return obs

    def _control_with_push(self, control: np.ndarray, pushed: np.ndarray) -> tuple[np.ndarray, int]:
        """``control`` and its ``mujoco.rollout`` spec, with the perturbation's push on the
        bases of the envs ``pushed`` (N,) bool, whose push comes in this step (their heading
        turns its direction)."""
        if not pushed.any():
            return control, CONTROL_SPEC
        forces = np.zeros((self.num_envs, self.config.decimation, self.model.nbody, 6))
        for i in np.flatnonzero(pushed):
            w, x, y, z = self.qpos[i, 3:7]
            yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
            c, s = np.cos(yaw), np.sin(yaw)
            fx, fy, fz = self._push
            forces[i, :, self._base, :3] = (c * fx - s * fy, s * fx + c * fy, fz)
        flat = forces.reshape(self.num_envs, self.config.decimation, -1)
        return np.ascontiguousarray(np.concatenate([control, flat], axis=2)), (
            CONTROL_SPEC | PUSH_SPEC)  # fmt: skip

    # -- stepping ------------------------------------------------------------------------------
    def step(self, actions: Any):
        self._check_open("step")
        if self._needs_reset:
            raise RuntimeError("call reset() before step()")
        actions = real_actions(actions, f"of shape {(self.num_envs, 12)}")
        if actions.shape != (self.num_envs, 12):
            raise ValueError(f"actions must have shape {(self.num_envs, 12)} (desired joint "
                             f"positions, rad, joints {self.quadruped.joint_names}), got "
                             f"{actions.shape}")  # fmt: skip
        if not np.isfinite(actions).all():
            raise ValueError("actions must be finite, got NaN or inf")
        desired = task.desired_positions(actions, self._low, self._high,
                                         self.config.normalized_actions)  # fmt: skip
        cfg, model = self.config, self.model
        # the drives track the command sent `latency` steps ago (the task keeps the one sent)
        self._control[:] = desired[:, None, :] if self.delay is None else self.delay.schedule(
            desired)  # fmt: skip
        pushed = self.draws.pushed(self.episode.elapsed)  # before the step's clock moves
        kicks = self.draws.kicks(self.episode.elapsed)  # randomised training's pushes
        if kicks is not None:  # the bases' horizontal velocity (world frame) kicked
            self.qvel[:, :2] += kicks
        control, spec = self._control_with_push(self._control, pushed)
        self.stepper.rollout(self._state, control, self._next, self._sensors, spec, cfg.decimation)
        np.copyto(self._state, self._next[:, -1])
        torque = self._sensors[:, :, : model.nu]  # every substep's
        joint_speed = self._next[:, :, 1 + model.nq + 6 : 1 + model.nq + model.nv]
        power = np.multiply(torque, joint_speed, out=self._power)  # no new array per step
        np.abs(power, out=power)
        # copies: the autoreset below rewrites the state and sensors of the robots it resets
        reading = task.Reading(
            qpos=self.qpos.copy(), qvel=self.qvel.copy(),
            lin_vel=self._sensor("velocimeter").copy(), ang_vel=self._sensor("gyro").copy(),
            feet=self._feet().copy(), torque=torque[:, -1].copy(),
            work=power.sum(axis=(1, 2)) * cfg.physics_dt,
            base_touch=self._sensor("base_touch")[:, 0] > 0,
            unstable=~np.isfinite(self._state).all(axis=1),
        )  # fmt: skip
        if self.ground is not None:  # heights over the ground under the robot
            reading = self.ground.relative(reading)
        weight = (self.quadruped.total_mass + self._payload) * self.quadruped.gravity
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # blown up: masked
            self.episode, out = task.step(cfg, self.episode, reading, desired, self._nominal,
                                          self.quadruped.foot_radius, weight,
                                          self._soft_range)  # fmt: skip
        done = out["terminated"] | out["truncated"]
        if cfg.resample_steps:  # a new command where one is due (the next step runs under it)
            elapsed = self.episode.elapsed
            if cfg.command_interval == "exponential":
                due = (elapsed >= self._next_draw) & ~done
            else:
                due = (elapsed % cfg.resample_steps == 0) & ~done
            command = self.episode.command.copy()
            for i in np.flatnonzero(due):
                command[i] = resample_command(self._rngs[i], command[i], cfg)
                if cfg.heading_gain:
                    self._heading[i] = draw_heading(self._rngs[i], cfg)
                if cfg.command_interval == "exponential":
                    self._next_draw[i] = elapsed[i] + steps_to_next_command(self._rngs[i], cfg)
            self.episode, out["obs"] = task.resample(self.episode, out["obs"], command, due)
        if cfg.heading_gain:  # the yaw rate toward each heading, from the yaw the step reached
            command = self.episode.command.copy()
            command[:, 2] = self._heading_yaw_rate()
            self.episode, out["obs"] = task.resample(self.episode, out["obs"], command, ~done)
        final_obs = self._recipe_noise(self.draws.observe(out["obs"]))
        obs = final_obs.copy()
        if self.ground is not None:  # the curriculum, before the next episodes start
            out["episode_metrics"]["terrain_level"] = self.ground.end_episodes(
                done, self.qpos, out["info"]["command"], self._rngs)  # fmt: skip
        if done.any():  # SAME_STEP autoreset
            self._start(done)
            obs = task.rows(done, self._observe(np.flatnonzero(done)), obs)
        info = {
            **out["info"],
            "command": out["info"]["command"].copy(),  # this step's (not the next episode's)
            "reward_terms": out["reward_terms"],
            "final_obs": final_obs,
            "_final_obs": done,
            "episode_metrics": out["episode_metrics"],
        }
        if cfg.perturbation.push:  # the envs a perturbation's push came in this step
            info["pushed"] = pushed
        return obs, out["reward"], out["terminated"], out["truncated"], info

    # -- state ---------------------------------------------------------------------------------
    def get_state(self) -> dict[str, Any]:
        """Everything the next step depends on: the physics state, the episode fields, each
        env's generator and the last sensor values, as tensors and plain Python values
        (``torch.save``-able with ``weights_only``)."""
        if self._needs_reset:
            raise RuntimeError("call reset() before get_state()")
        arrays = {"physics": self._state, "sensors": self._sensors[:, -1]}
        if self.config.command_interval == "exponential":
            arrays["next_draw"] = self._next_draw
        if self.config.heading_gain:
            arrays["heading"] = self._heading
        arrays.update({name: getattr(self.episode, name) for name in SAVED_FIELDS})
        extra = {}  # a perturbation's commands on their way, push steps and generators
        if self.delay is not None:
            arrays["delayed"] = self.delay.get_state()
        if self.ground is not None:  # each env's level and where its episode started
            arrays.update(self.ground.get_state())
        if self.draws.active:
            arrays["push_step"] = self.draws.push_step
            extra["perturbation"] = self.draws.get_state()
        return {
            self.quadruped.state_key: {
                **{name: torch.from_numpy(np.array(value)) for name, value in arrays.items()},
                "rngs": [rng.bit_generator.state for rng in self._rngs],
                **extra,
            }
        }

    def set_state(self, state: dict[str, Any]) -> None:
        key = self.quadruped.state_key
        if not isinstance(state, dict) or key not in state:
            raise ValueError(f"not a state of {type(self).__name__} (get_state() makes one)")
        state = {name: value.numpy() if isinstance(value, torch.Tensor) else value
                 for name, value in state[key].items()}  # fmt: skip
        if np.shape(state["physics"]) != self._state.shape:
            raise ValueError(f"the state has {len(state['physics'])} envs, this env "
                             f"{self.num_envs}")  # fmt: skip
        np.copyto(self._state, np.asarray(state["physics"]))
        self._sensors[:, -1] = np.asarray(state["sensors"])
        fields = {}
        for name in SAVED_FIELDS:
            if name not in state and name in ADDED_FIELDS:
                dtype = np.int64 if name in COUNTS else np.float64
                fields[name] = np.zeros((self.num_envs, *SHAPES.get(name, ())), dtype=dtype)
                continue
            fields[name] = np.array(state[name])
        self.episode = task.Episode(**fields, feet_xy=self._feet()[:, :, :2].copy())
        if "next_draw" in state:
            np.copyto(self._next_draw, np.asarray(state["next_draw"]))
        if "heading" in state:
            np.copyto(self._heading, np.asarray(state["heading"]))
        self._rngs = []
        for saved in state["rngs"]:
            rng = np.random.default_rng()
            rng.bit_generator.state = saved
            self._rngs.append(rng)
        if self.ground is not None:
            self.ground.set_state(state)
        if self.delay is not None and "delayed" in state:
            self.delay.set_state(state["delayed"])
        if "perturbation" in state:
            self.draws.set_state(state["perturbation"], state["push_step"])
            if self.config.randomize.active:
                self._perturb(np.arange(self.num_envs))
        self._needs_reset = False

    # -- rendering -----------------------------------------------------------------------------
    def render_frame(self, index: int = 0) -> np.ndarray:
        """An RGB frame ``(H, W, 3)`` uint8 of env ``index`` in its current state: MuJoCo's
        offscreen renderer, a camera tracking the base (``quadruped.camera``), the
        checkered ground showing the forward motion. The config's ``render_width`` by
        ``render_height`` pixels. Raises
        :class:`~cpg_actor.robots.common.video.RenderingUnavailable` without an OpenGL backend."""
        self._check_open("render_frame")
        if self._needs_reset:
            raise RuntimeError("call reset() before render_frame()")
        if not 0 <= index < self.num_envs:
            raise ValueError(f"index must be in 0..{self.num_envs - 1}, got {index}")
        return self.render_pose(self.qpos[index])

    def render_pose(self, qpos: np.ndarray) -> np.ndarray:
        """:meth:`render_frame` of a robot at the configuration ``qpos`` (``nq`` numbers: base
        position, quaternion, 12 joints), e.g. one the MJX env simulated."""
        self._check_open("render_pose")
        qpos = np.asarray(qpos, dtype=np.float64)
        if qpos.shape != (self.model.nq,):
            raise ValueError(f"qpos must have {self.model.nq} entries, got {qpos.shape}")
        if self._renderer is None:
            # the renderer's own copy of the model, its light following the robot (the world's
            # centre of mass: the robot's) as the camera does: a robot walking 10 m away from
            # the light would be in the dark
            model = copy.copy(self.model)
            model.light_mode[:] = mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM
            width, height = int(self.config.render_width), int(self.config.render_height)
            self._renderer = offscreen_renderer(model, width, height)
            camera = mujoco.MjvCamera()
            camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
            camera.trackbodyid = model.body(self.quadruped.base_body).id
            for name, value in self.quadruped.camera.items():
                setattr(camera, name, value)
            self._camera = camera
            self._render_model, self._render_data = model, mujoco.MjData(model)
        model, data = self._render_model, self._render_data
        data.qpos[:] = qpos
        mujoco.mj_forward(model, data)  # the camera tracks the subtree's centre of mass
        self._renderer.update_scene(data, camera=self._camera)
        return self._renderer.render().copy()

    def _check_open(self, what: str) -> None:
        if getattr(self, "stepper", None) is None:
            raise gym.error.ClosedEnvironmentError(f"{what}() on a closed environment")

    def close(self, **kwargs: Any) -> None:
        if getattr(self, "_renderer", None) is not None:
            self._renderer.close()
            self._renderer = None
        if getattr(self, "stepper", None) is not None:
            self.stepper.close()
            self.stepper = None
