"""A trained policy as one self-contained file for a robot's control loop: TorchScript or ONNX.

The exported function is the deterministic control step of
:class:`cpg_actor.training.policy.Policy`:

    (observation, state) -> (action, next_state)

* ``observation``: ``(B, obs_dim)`` float32, the raw observation the actor reads (for the
  hopper, in the order of ``cpg_actor.robots.hopper.task.OBS_NAMES``: measured HFE, KFE
  positions (rad) and velocities (rad/s), the desired positions being tracked (rad), hip
  height (m), hip velocity (m/s)): the env's, less the critic's privileged entries where the
  run has them (``env.privileged_observation``: ``Policy.actor_obs_dim`` entries). Every
  transform of it is inside: the observation normaliser and the agent's fixed observation
  scales (``agent_config.observation_scales``), both described in the metadata; feed it raw.
  A non-finite entry (NaN, +-inf) is replaced by the normaliser's mean (0 where the run does
  not normalise) before anything else, so the policy acts as if that sensor read its
  average; the action stays finite. A deployment should not rely on it: it should refuse a
  non-finite observation before the call (as ``examples/deploy_onnx.py`` does), the model's
  replacement being the fallback.
* ``state``: ``(B, *state_shape)`` float32, the agent's recurrent state: for the CPG-Actor the
  CPG state ``(B, 5, N)`` (rows: phase theta, theta_dot, amplitude r, r_dot, r_ddot; columns:
  oscillators; on a robot with a drive, the quadruped, a sixth row: the drive d, set from the
  observation inside the step), for the MLP an empty ``(B, 0)``. Start from
  :func:`initial_state` (saved next to the policy as ``*.initial_state.npy``, and in the
  metadata) and feed ``next_state`` back at the next step; restart it when an episode
  restarts.
* ``action``: ``(B, A)`` float32, desired joint positions (rad), the mean of the Gaussian,
  clipped to the joint limits.

The feedback network, the CPG step (eq. 1-2) and the joint map are inside; the batch size is
fixed at export (``batch``, default 1: one robot).

Next to the policy file ``PATH``: ``PATH.initial_state.npy`` and ``PATH.robot.xml``, the MJCF of
the model the run's MuJoCo env simulates (actuators, timestep and friction as configured).
The file carries :func:`export_metadata` (what a robot's control loop needs to run it: joints,
nominal pose, control period, observation layout, action bounds, actuator law, state layout;
``docs/training.md``, "Export"): as the ONNX model's ``metadata_props``, and in the TorchScript
archive as the extra file ``metadata.json`` (the same mapping, one JSON object). Values are
strings; lists, mappings and numbers JSON-encoded (``METADATA_TEXT_KEYS`` are plain text).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import logging
import os
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from cpg_actor.files import naming, new_temporary
from cpg_actor.training.policy import Policy

FORMATS = ("torchscript", "onnx")
SUFFIXES = {"torchscript": ".pt", "onnx": ".onnx"}
INPUT_NAMES = ["observation", "state"]
OUTPUT_NAMES = ["action", "next_state"]
EXPORTABLE = (
    "mlp",
    "mlp-warm",
    "cpg-actor",
    "cpg-actor-paper",
    "cpg-actor-open-loop",
    "open-loop-es",
)
TORCHSCRIPT_METADATA = "metadata.json"  # the extra file of a TorchScript export
# where an observation entry comes from in the MuJoCo data of the exported MJCF, after a
# control step (each entry of the metadata's observation_sources names one, with "index" and
# an optional "offset" added to the value):
OBSERVATION_SOURCES = {
    "qpos": "data.qpos[index]",
    "qvel": "data.qvel[index]",
    "sensor": "data.sensordata at the named sensor's address + index, as the control step's "
    "last mj_step left it",
    "projected_gravity": "component index of the world's unit gravity (0, 0, -1) in the base "
    "frame, from the unit quaternion (w, x, y, z) at data.qpos[quaternion:quaternion + 4]",
    "desired": "the desired joint positions being tracked: the last action as clipped, "
    "the env's reset value before the first",
    "command": "the episode's velocity command (forward, lateral m/s, yaw rad/s)",
}
# an entry read from the simulation that a robot has no sensor for carries "on_robot": what
# stands for it there (the base's linear velocity: a state estimator's)
NONFINITE_OBSERVATIONS = (
    "replaced inside the model by observation_normalization.mean (0 when not normalising): a "
    "fallback; refuse non-finite observations before the call (examples/deploy_onnx.py does)"
)
METADATA_TEXT_KEYS = ("cpg_actor_version", "robot", "robot_model", "agent", "simulator",
                      "mjcf_file", "nonfinite_observations", "state_usage")  # fmt: skip


class ControlStep(nn.Module):
    """``(observation, state) -> (action, next_state)``: replace non-finite observation
    entries, normalise, act (mean), clip."""

    def __init__(self, policy: Policy) -> None:
        super().__init__()
        # a frozen copy: the exported step needs no gradients (outputs without requires_grad)
        self.agent = copy.deepcopy(policy.agent).requires_grad_(False)
        normalizer, size = policy.normalizer, policy.actor_obs_dim  # the actor's entries
        self.normalize = policy.normalize_observations
        self.register_buffer("mean", normalizer.mean[:size].to(torch.float32))
        std = torch.sqrt(normalizer.var[:size] + normalizer.epsilon)
        self.register_buffer("std", std.float())
        # what a non-finite entry becomes: the mean, normalised to 0
        fill = self.mean if self.normalize else torch.zeros_like(self.mean)
        self.register_buffer("fill", fill.clone())
        self.clip = float(normalizer.clip)
        self.register_buffer("low", torch.as_tensor(policy.action_low, dtype=torch.float32))
        self.register_buffer("high", torch.as_tensor(policy.action_high, dtype=torch.float32))

    def forward(self, observation: Tensor, state: Tensor) -> tuple[Tensor, Tensor]:
        observation = torch.where(torch.isfinite(observation), observation, self.fill)
        state = self.agent.observe(observation, state)  # e.g. the CPG's drive (raw obs)
        if self.normalize:
            observation = ((observation - self.mean) / self.std).clamp(-self.clip, self.clip)
        out = self.agent.actor(observation, state)
        action = torch.minimum(torch.maximum(out.mean, self.low), self.high)
        return action, out.next_state


def initial_state(policy: Policy, batch: int = 1) -> np.ndarray:
    """The recurrent state an episode starts from, ``(batch, *state_shape)`` float32."""
    return policy.agent.initial_state(batch).cpu().numpy().astype(np.float32)


def sidecar_paths(path: Path) -> dict[str, Path]:
    """The files written next to the policy file ``path``."""
    return {
        "initial_state": path.with_name(path.name + ".initial_state.npy"),
        "mjcf": path.with_name(path.name + ".robot.xml"),
    }


def export_metadata(policy: Policy, batch: int = 1, mjcf_file: str = "") -> dict[str, str]:
    """What a control loop needs to run the exported step of ``policy`` (one loaded by
    :func:`cpg_actor.deploy.load_policy`, which knows its run and robot), key -> string
    (``docs/training.md``, "Export", has the table)."""
    from cpg_actor import __version__
    from cpg_actor.agents.base import observation_scale
    from cpg_actor.deploy.interface import model_interface, named_sources
    from cpg_actor.robots.common.actuator import Actuator
    from cpg_actor.robots.registry import get_robot

    config, robot = policy.config, policy.robot
    if config is None or robot is None:
        raise ValueError(
            "the policy knows no run or robot; load it with cpg_actor.deploy.load_policy"
        )
    env = config.env
    actuator = Actuator.from_config(env)
    normalizer, size = policy.normalizer, policy.actor_obs_dim
    names = list(robot.observation_names[:size])  # the actor's: no privileged entries
    std = torch.sqrt(normalizer.var[:size] + normalizer.epsilon)
    factors = [1.0] * size  # the agent's fixed scales, as configured (inside: in float32)
    if getattr(policy.agent, "input_scale", None) is not None:
        factors = observation_scale(names, config.agent_config.observation_scales)
    state = initial_state(policy, batch)
    plugin = get_robot(config.robot)
    mjcf = plugin.mjcf(env)  # the model the policy trained on: its joints, sites, sensors
    sources = named_sources(mjcf, [dict(source) for source in plugin.observation_sources(env)])
    if len(sources) != size:  # an env option the robot's deploy interface does not know
        first = f", from {names[len(sources)]} on" if len(sources) < size else ""
        raise ValueError(
            f"the policy's actor reads {size} observation entries and the {config.robot} "
            f"robot's deploy interface (observation_sources) describes {len(sources)}{first}: "
            "this run cannot be exported"
        )
    values: dict[str, Any] = {
        "cpg_actor_version": __version__,
        "robot": config.robot,
        "robot_model": robot.name,
        "agent": config.agent,
        "simulator": env.sim,
        "input_names": INPUT_NAMES,
        "output_names": OUTPUT_NAMES,
        "batch": batch,
        "joint_names": list(robot.joint_names),
        "default_joint_positions": [float(v) for v in robot.nominal_pose],
        "action_low": [float(v) for v in robot.action_low],
        "action_high": [float(v) for v in robot.action_high],
        "control_dt": float(robot.control_dt),
        "physics_dt": float(env.physics_dt),
        "decimation": int(env.decimation),
        "observation_names": names,
        "observation_sources": [
            {"name": name, **source} for name, source in zip(names, sources, strict=True)
        ],  # fmt: skip
        "observation_normalization": {
            "inside": bool(policy.normalize_observations),
            "mean": normalizer.mean[:size].double().cpu().tolist(),
            "std": std.double().cpu().tolist(),
            "clip": float(normalizer.clip),
        },
        "observation_scales": {"inside": True, "factors": factors},
        "nonfinite_observations": NONFINITE_OBSERVATIONS,
        "drive_observation": robot.drive_observation,
        "state_shape": list(state.shape),
        "state_rows": list(policy.agent.state_rows),
        "initial_state": state.astype(np.float64).tolist(),
        "state_usage": "feed next_state back as state at the next step; start every episode "
        "from initial_state",
        "actuator": {
            "law": actuator.law,
            "kp": actuator.kp,
            "kd": actuator.kd,
            "torque_limit": actuator.torque_limit,
            "velocity_limit": actuator.velocity_limit,
            "saturation_torque": actuator.saturation_torque,
        },
        "mjcf_file": mjcf_file,
        "model_interface": model_interface(mjcf),
        "env_config": dataclasses.asdict(env),
    }
    return {
        key: value if key in METADATA_TEXT_KEYS else json.dumps(value, allow_nan=False)
        for key, value in values.items()
    }


@contextlib.contextmanager
def quiet_export() -> Iterator[None]:
    """Silence what the exporters print about themselves (and nothing else, nowhere else):
    the tracer's warnings about the agents' shape checks (constant at a fixed batch), torch's
    deprecation of a pytree class its ONNX exporter still uses and of TorchScript itself
    (shown only where deprecation warnings are; ``docs/training.md`` says it), and the ONNX
    optimiser's notes on the operators it leaves unfolded."""
    loggers = [logging.getLogger(name) for name in
               ("torch.onnx", "onnxscript.optimizer._constant_folding")]  # fmt: skip
    levels = [logger.level for logger in loggers]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", torch.jit.TracerWarning)
        warnings.filterwarnings("ignore", r".*isinstance\(treespec, LeafSpec\)", FutureWarning)
        warnings.filterwarnings("ignore", r"`torch\.jit\.\w+` is deprecated", DeprecationWarning)
        for logger in loggers:
            logger.setLevel(logging.ERROR)
        try:
            yield
        finally:
            for logger, level in zip(loggers, levels, strict=True):
                logger.setLevel(level)


def export_policy(
    policy: Policy, path: str | os.PathLike, fmt: str, batch: int = 1, overwrite: bool = False
) -> Path:
    """Write ``policy``'s control step to ``path`` in ``fmt`` (torchscript | onnx) with its
    metadata (:func:`export_metadata`), and next to it the initial state
    (``PATH.initial_state.npy``) and the robot's MJCF (``PATH.robot.xml``). Atomic; refuses
    to replace an existing file unless ``overwrite``. Returns the path."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; accepted: {', '.join(FORMATS)}")
    agent_name = getattr(policy.config, "agent", None)
    if agent_name is not None and agent_name not in EXPORTABLE:
        raise ValueError(
            f"agent '{agent_name}' acts on CPG parameters of a CPG inside its environment; "
            f"only agents that output joint positions can be exported: {', '.join(EXPORTABLE)}"
        )
    if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
        raise ValueError(f"batch must be a positive integer, got {batch!r}")
    alpha = getattr(getattr(policy.config, "env", None), "command_filter", 1.0)
    if alpha != 1.0:
        raise ValueError(
            f"the run trained with env.command_filter={alpha}, a low-pass the exported step "
            "does not contain; only runs without it (1.0) can be exported"
        )
    from cpg_actor.robots.registry import get_robot

    path = Path(path)
    sidecars = sidecar_paths(path)
    for target in (path, *sidecars.values()):
        if target.is_dir():  # not replaced even with --overwrite: a directory is no export
            raise FileExistsError(
                f"{target} is a directory; give the export a file name (e.g. "
                f"{target / ('policy' + SUFFIXES[fmt])})"
            )
        if target.exists() and not overwrite:
            raise FileExistsError(f"{target} exists; pass --overwrite to replace it")
    existed = {target for target in sidecars.values() if target.exists()}
    metadata = export_metadata(policy, batch, sidecars["mjcf"].name)
    mjcf = get_robot(policy.config.robot).mjcf(policy.config.env)
    module = ControlStep(policy).cpu().eval()  # exported for the CPU, wherever it trained
    obs_dim = policy.actor_obs_dim  # the actor's observation: no privileged entries
    example = (torch.zeros(batch, obs_dim), torch.as_tensor(initial_state(policy, batch)))
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = {target: new_temporary(target) for target in (path, *sidecars.values())}
    try:
        with torch.no_grad(), quiet_export(), naming(path):
            if fmt == "torchscript":
                torch.jit.save(
                    torch.jit.trace(module, example),
                    str(temporary[path]),
                    _extra_files={TORCHSCRIPT_METADATA: json.dumps(metadata, indent=1)},
                )
            else:
                program = torch.onnx.export(
                    module,
                    example,
                    input_names=INPUT_NAMES,
                    output_names=OUTPUT_NAMES,
                    dynamo=True,
                    verbose=False,
                )
                program.model.metadata_props.update(metadata)
                program.model.doc_string = (
                    f"cpg-actor {metadata['agent']} policy for {metadata['robot_model']}: "
                    "(observation, state) -> (action, next_state); see metadata_props"
                )
                program.save(str(temporary[path]))
        state = sidecars["initial_state"]
        with naming(state), open(temporary[state], "wb") as f:
            np.save(f, initial_state(policy, batch))
        with naming(sidecars["mjcf"]):
            temporary[sidecars["mjcf"]].write_text(mjcf)
        try:
            for target in (*sidecars.values(), path):  # the policy last: complete when there
                os.replace(temporary[target], target)
        except BaseException:  # no sidecar left behind without its policy
            for target in sidecars.values():
                if target not in existed:
                    target.unlink(missing_ok=True)
            raise
    finally:
        for tmp in temporary.values():
            tmp.unlink(missing_ok=True)
    return path


def _torchscript_extra(path: Path, name: str, limit: int = 1 << 20) -> str | None:
    """The extra file ``name`` of a TorchScript archive (``ARCHIVE/extra/NAME`` in its zip),
    None if it has none; ValueError (one line) if the file is no TorchScript archive or the
    extra file is over ``limit`` bytes."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            found = [
                info for info in archive.infolist()
                if info.filename.count("/") == 2 and info.filename.endswith(f"/extra/{name}")
            ]  # fmt: skip
            if not found:
                return None
            if found[0].file_size > limit:
                raise ValueError(f"{path}: its {name} is over {limit:,} bytes")
            return archive.read(found[0]).decode("utf-8")
    except (zipfile.BadZipFile, UnicodeDecodeError, OSError) as error:
        raise ValueError(f"{path} is not a TorchScript export ({type(error).__name__})") from None


def read_metadata(path: str | os.PathLike) -> dict[str, Any]:
    """The metadata of an exported policy file (ONNX or TorchScript), JSON values decoded."""
    path = Path(path)
    if path.suffix == ".onnx":
        import onnx

        raw = {p.key: p.value for p in onnx.load(str(path), load_external_data=False)
               .metadata_props}  # fmt: skip
    else:  # read from the archive as a zip: loading the TorchScript would unpickle its data
        raw = json.loads(_torchscript_extra(path, TORCHSCRIPT_METADATA) or "{}")
    return {key: value if key in METADATA_TEXT_KEYS else json.loads(value)
            for key, value in raw.items()}  # fmt: skip
