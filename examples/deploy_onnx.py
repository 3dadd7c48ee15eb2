"""Run a policy exported by ``cpg-actor export`` on its robot in MuJoCo, with nothing of the
project: numpy, onnxruntime and mujoco only.

    cpg-actor export runs/my-run                      # runs/my-run/export/policy.onnx
    python examples/deploy_onnx.py runs/my-run/export/policy.onnx --seed 1000

Everything comes from the policy file's metadata and the MJCF the export wrote next to it
(``policy.onnx.robot.xml``, whose ``dcmotor`` actuators run the actuator law at every physics
substep): the control period, the joints, how each observation entry is read from MuJoCo's
data (``observation_sources``), the initial CPG state, the episode's settings
(``env_config``). One control step is what the project's MuJoCo env does: the solver's warm
start cleared, the desired joint positions held for ``decimation`` substeps of ``mj_step``,
then the observation read from the state (and the sensors) the last substep left.

The printed return is that of ``cpg-actor eval RUN --episodes 1 --seed SEED`` (episode i of
``--seed S`` is this script's ``--seed S+i``): the start is drawn as the env draws it and
the reward is the env's, written out below for the two tasks of the project: the hopper's
(eq. 4 with its default ``hop_reward``) and the quadrupeds' (ANYmal B, the Go1, any robot whose
observation has the velocity command: legged_gym's terms, the feet those of the MJCF's
``<leg>_foot_pos`` sensors). The library's
evaluation acting with this same file scores it to float64 rounding; ``cpg-actor eval``'s
PyTorch policy rounds float32 differently from ONNX Runtime, which moves a legged robot's
return a little (``docs/training.md``, "Export"). On a real robot, ``Simulation`` is the
robot's driver and the reward goes; the loop stays as it is.

A run of the field's recipes (``--preset playground`` on the Go1, ``legged_gym`` on ANYmal B)
runs as well: its observation ends with the base's linear velocity, read from the MJCF's
velocimeter (on a robot a state estimator's, the metadata's ``on_robot``). This example
writes out the project's own velocity task, not those recipes' starts, commands and clipped
rewards, so for such a run the printed return is not ``cpg-actor eval``'s.

Another model of the robot (``--mjcf OTHER.xml``, a quadruped's policy): its joints are found
by name (one line naming those it lacks), its actuators switched off and the metadata's
actuator law applied as joint torques at every substep of its own timestep; the sites, sensors
and ground the observation and the reward read are added where it lacks them (the metadata's
``model_interface``). ``--command VX [VY YAW]`` holds a command for the episode and prints the
tracking::

    python examples/deploy_onnx.py runs/my-run --mjcf OTHER.xml --command 0.5

A non-finite observation (a failed sensor) is refused before the model sees it: the model
would replace it by the normaliser's mean (its metadata's ``nonfinite_observations``), a
fallback a robot should not run on.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

# nothing is rendered here: without a display, keep mujoco from looking for an OpenGL library
if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import onnxruntime as ort  # noqa: E402

TEXT_KEYS = ("cpg_actor_version", "robot", "robot_model", "agent", "simulator", "mjcf_file",
             "nonfinite_observations", "state_usage")  # fmt: skip
# what this example reads of the metadata (``model_interface`` only for --mjcf)
NEEDED_KEYS = ("agent", "robot_model", "mjcf_file", "observation_names", "observation_sources",
               "initial_state", "joint_names", "default_joint_positions", "action_low",
               "action_high", "actuator", "decimation", "control_dt", "env_config")  # fmt: skip
# the most physics substeps one control step may take on another model's timestep: legged
# robots' models step 0.5 to 5 ms under a 10 to 50 ms control period (a few to 100 substeps);
# 10,000 is far beyond any of them and still ends (a 20 ms period at 2 us), where a
# mistyped timestep (1e-9 s) would step 20 million times per action and never finish
MAX_SUBSTEPS = 10_000


def read_metadata(session: ort.InferenceSession, path: Path) -> dict:
    """The exported policy's metadata, JSON values decoded; ValueError without it."""
    raw = session.get_modelmeta().custom_metadata_map
    try:
        meta = {key: value if key in TEXT_KEYS else json.loads(value) for key, value in raw.items()}
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: its metadata is not cpg-actor's ({error})") from None
    if not {"mjcf_file", "observation_names"} <= set(meta):
        raise ValueError(f"{path} has no cpg-actor metadata; export it with cpg-actor export")
    missing = [key for key in NEEDED_KEYS if key not in meta]
    if missing:
        raise ValueError(f"{path}: its metadata lacks {', '.join(missing)}; export it again "
                         "with cpg-actor export")  # fmt: skip
    joints = meta["joint_names"]
    if not (isinstance(joints, list) and joints and all(isinstance(j, str) for j in joints)):
        raise ValueError(f"{path}: its metadata's joint_names is not a list of joint names")
    for key in ("default_joint_positions", "action_low", "action_high"):
        if np.shape(meta[key]) != (len(joints),):
            raise ValueError(f"{path}: its metadata's {key} is not one number per joint "
                             f"({len(joints)} joints)")  # fmt: skip
    control_dt = meta["control_dt"]
    if not (isinstance(control_dt, int | float) and 0 < control_dt < float("inf")):
        raise ValueError(f"{path}: its metadata's control_dt {control_dt!r} is not a positive "
                         "number of seconds")  # fmt: skip
    return meta


def policy_file(path: Path) -> Path:
    """The ONNX file ``path`` names: the file itself, or ``policy.onnx`` in an export directory
    or in a run directory's ``export/``."""
    if not path.is_dir():
        if not path.is_file():
            raise ValueError(f"{path} does not exist (an ONNX file from cpg-actor export)")
        return path
    for candidate in (path / "policy.onnx", path / "export" / "policy.onnx"):
        if candidate.is_file():
            return candidate
    raise ValueError(f"{path} is a directory without policy.onnx or export/policy.onnx; give the "
                     "ONNX file from cpg-actor export, or its run or export directory")  # fmt: skip


class Policy:
    """The exported control step, its recurrent (CPG) state kept here."""

    def __init__(self, path: Path) -> None:
        try:
            self.session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        except Exception as error:  # onnxruntime's own errors (a truncated or foreign file)
            reason = (str(error).strip() or type(error).__name__).splitlines()[0]
            raise ValueError(f"{path} is not an ONNX model onnxruntime loads: {reason}") from None
        self.meta = read_metadata(self.session, path)
        self.names = self.meta["observation_names"]
        self.reset()

    def reset(self) -> None:
        """An episode starts: the state goes back to the initial one."""
        self.state = np.asarray(self.meta["initial_state"], dtype=np.float32)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        """Desired joint positions (rad) for one observation (float64 or float32)."""
        bad = [name for name, value in zip(self.names, observation, strict=True)
               if not np.isfinite(value)]  # fmt: skip
        if bad:
            raise ValueError(f"non-finite observation entries {bad}: refused (check the sensors)")
        obs = np.asarray(observation, dtype=np.float32)[None]
        action, self.state = self.session.run(None, {"observation": obs, "state": self.state})
        return action[0].astype(np.float64)


def actuator_torque(law: dict, desired, position, velocity) -> np.ndarray:
    """The actuator law of the metadata's ``actuator``: PD on the desired position, clipped to
    what the motor gives at this speed (its torque-speed line), and to the torque limit. The
    MJCF's ``dcmotor`` actuators compute the ``dc-motor`` law inside MuJoCo; this is run where
    the MJCF has them switched off, for ``coast`` (no torque along the motion beyond the
    speed limit, never braking). A constant is one number, or one per joint of a leg
    (repeated leg after leg), or one per joint."""
    n = len(desired)
    kp, kd, limit, stall, speed = (
        np.resize(np.asarray(law[name], dtype=np.float64), n)
        for name in ("kp", "kd", "torque_limit", "saturation_torque", "velocity_limit")
    )
    torque = kp * (desired - position) - kd * velocity
    drop = velocity * (stall / speed)
    floor, ceiling = (0.0, 0.0) if law["law"] == "coast" else (-limit, limit)
    upper = np.minimum(np.maximum(stall - drop, floor), limit)
    lower = np.maximum(np.minimum(-stall - drop, ceiling), -limit)
    return np.minimum(np.maximum(torque, lower), upper)


def projected_gravity(quat: np.ndarray) -> np.ndarray:
    """The world's unit gravity (0, 0, -1) in the frame of the unit quaternion (w, x, y, z)."""
    w, x, y, z = quat
    return -np.array([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])


def standing_hip_height(model: mujoco.MjModel, joints: np.ndarray) -> float:
    """The hopper's hip height at which its foot sphere touches the ground in the pose
    ``joints`` (HFE, KFE), worked out along its planar chain (hip, thigh, shank, adapter,
    foot; rotations about y) as the env does it, to the last bit: the foot starts at
    distance 0 from the ground, where the last bit decides whether MuJoCo counts a contact
    at the first substep (mj_kinematics' own arithmetic differs there for 2 seeds in 5)."""
    hfe, knee = model.body("thigh").pos, model.body("shank").pos
    adapter, foot = model.body("adapter").pos, model.site("foot").pos
    kx, kz = knee[0], knee[2]
    fx, fz = adapter[0] + foot[0], adapter[2] + foot[2]
    q = np.asarray(joints, dtype=np.float64)[None]  # a batch of one, as the env's
    thigh, shank = q[:, 0], q[:, 0] + q[:, 1]
    knee_z = hfe[2] + (-kx * np.sin(thigh) + kz * np.cos(thigh))
    foot_z = knee_z + (-fx * np.sin(shank) + fz * np.cos(shank))
    return float((model.geom("foot").size[0] - foot_z)[0])


# -- another model of the robot (--mjcf) -----------------------------------------------------
def other_model(meta: dict, mjcf: Path) -> mujoco.MjModel:
    """Another MJCF of the policy's robot, made ready for it: its joints found by name (a
    ValueError naming those missing), the sites and sensors the observation and the reward
    read added where it lacks them (``model_interface``: where they sit on which body), a
    ground plane when it has none, and its actuators switched off: the metadata's actuator
    law is applied as joint torques at every substep (:func:`actuator_torque`)."""
    interface = meta.get("model_interface")
    if interface is None or not interface.get("free_joint"):
        raise ValueError("--mjcf with another model takes a quadruped policy exported with its "
                         "model_interface (cpg-actor export of this version)")  # fmt: skip
    try:
        spec = mujoco.MjSpec.from_file(str(mjcf))
        spec.compile()
    except Exception as error:  # MuJoCo's own parse and compile errors
        reason = (str(error).strip() or type(error).__name__).splitlines()[0]
        raise ValueError(f"{mjcf} is not an MJCF MuJoCo loads: {reason}") from None
    have = {joint.name for joint in spec.joints}
    missing = [name for name in meta["joint_names"] if name not in have]
    if missing:
        raise ValueError(f"{mjcf} lacks the policy's joints {', '.join(missing)} (it has: "
                         f"{', '.join(sorted(n for n in have if n)) or 'none'})")  # fmt: skip
    frees = [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_FREE]
    if len(frees) != 1:
        raise ValueError(f"{mjcf} has {len(frees)} free joints; the robot's base is the one "
                         "free body of the file")  # fmt: skip
    frees[0].name = frees[0].name or interface["free_joint"]
    bodies = {body.name: body for body in spec.bodies}
    bodies[interface["base_body"]] = bodies.get(interface["base_body"], frees[0].parent)
    sites = {site.name for site in spec.sites}
    sensors = {sensor.name for sensor in spec.sensors}
    for sensor in interface["sensors"]:
        if sensor["name"] in sensors:
            continue
        site = next(s for s in interface["sites"] if s["name"] == sensor["objname"])
        if site["name"] not in sites:
            body = bodies.get(site["body"])
            if body is None:
                raise ValueError(
                    f"{mjcf} lacks the body {site['body']!r} that carries the "
                    f"site {site['name']!r} of the sensor {sensor['name']!r}"
                )
            body.add_site(
                name=site["name"],
                pos=site["pos"],
                quat=site["quat"],
                size=site["size"],
                type=getattr(mujoco.mjtGeom, site["type"]),
            )
            sites.add(site["name"])
        spec.add_sensor(name=sensor["name"], type=getattr(mujoco.mjtSensor, sensor["type"]),
                        objtype=getattr(mujoco.mjtObj, sensor["objtype"]),
                        objname=sensor["objname"])  # fmt: skip
    planes = [
        g
        for g in spec.worldbody.geoms
        if g.type in (mujoco.mjtGeom.mjGEOM_PLANE, mujoco.mjtGeom.mjGEOM_HFIELD)
    ]
    if not planes:  # the ground the policy trained on
        friction = interface.get("ground_friction") or [1.0, 0.005, 0.0001]
        spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE,
                                size=[50, 50, 0.05], friction=friction,
                                contype=1, conaffinity=1)  # fmt: skip
    model = spec.compile()
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION.value
    return model


def substeps(timestep: float, control_dt: float, mjcf: Path) -> int:
    """Physics steps per control step at ``timestep``; ValueError unless a whole number, and
    at most :data:`MAX_SUBSTEPS`."""
    if not 0 < timestep < float("inf"):
        raise ValueError(f"{mjcf}: timestep {timestep} s is not a positive number of seconds")
    if control_dt / timestep > MAX_SUBSTEPS + 0.5:
        raise ValueError(f"{mjcf}: timestep {timestep} s takes more than {MAX_SUBSTEPS:,} "
                         f"substeps per control period of {control_dt} s; give a timestep "
                         f"of at least {control_dt / MAX_SUBSTEPS:g} s")  # fmt: skip
    n = round(control_dt / timestep)
    if n < 1 or abs(n * timestep - control_dt) > 1e-9:
        raise ValueError(f"{mjcf}: timestep {timestep} s does not divide the policy's control "
                         f"period {control_dt} s")  # fmt: skip
    return n


def free_joint(model: mujoco.MjModel, name: str):
    """The free joint ``name``, or the model's only free joint."""
    try:
        return model.joint(name)
    except KeyError:
        free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
        return model.joint(free[0])


def located(model: mujoco.MjModel, entry: dict) -> dict:
    """An observation source with its index in ``model``: a joint's coordinate found by the
    joint's name (the metadata's ``joint`` and ``element``), as is without them."""
    if "joint" not in entry:
        return entry
    entry = dict(entry)
    joint = model.joint(entry["joint"]) if entry["joint"] else None
    if entry["source"] == "projected_gravity":
        joint = free_joint(model, entry["joint"])
        entry["quaternion"] = int(joint.qposadr[0]) + entry["element"]
    elif entry["source"] == "qpos":
        entry["index"] = int(joint.qposadr[0]) + entry["element"]
    else:
        entry["index"] = int(joint.dofadr[0]) + entry["element"]
    return entry


def check_model(model: mujoco.MjModel, meta: dict, mjcf: Path, other: bool) -> None:
    """ValueError, in one line, where ``model`` is not what the policy drives and reads: its
    joints hinges (one angle each: the action and the observation's joint entries are
    angles), the other joints and the sensors the observation names; in the policy's own
    model (its actuators on), a position actuator on each joint and its torque sensor; for
    the velocity task, the base's and feet's sensors the reward reads."""
    joints = {model.joint(j).name: j for j in range(model.njnt)}
    sensors = {model.sensor(i).name for i in range(model.nsensor)}
    missing = [name for name in meta["joint_names"] if name not in joints]
    if missing:
        raise ValueError(f"{mjcf} lacks the policy's joints {', '.join(missing)}")
    kinds = ("free", "ball", "slide", "hinge")  # mjtJoint's values, in order
    wrong = [f"{name} ({kinds[int(model.jnt_type[joints[name]])]})"
             for name in meta["joint_names"]
             if model.jnt_type[joints[name]] != mujoco.mjtJoint.mjJNT_HINGE]  # fmt: skip
    if wrong:
        raise ValueError(f"{mjcf}: the policy's joints must be hinges; {', '.join(wrong)} "
                         f"{'is' if len(wrong) == 1 else 'are'} not")  # fmt: skip
    for entry in meta["observation_sources"]:
        free = other and entry["source"] == "projected_gravity"  # the one free joint, found
        if entry.get("joint") and entry["joint"] not in joints and not free:
            raise ValueError(f"{mjcf} lacks the joint {entry['joint']!r} the observation's "
                             f"{entry['name']!r} reads")  # fmt: skip
        if entry["source"] == "sensor" and entry["sensor"] not in sensors:
            raise ValueError(f"{mjcf} lacks the sensor {entry['sensor']!r} the observation's "
                             f"{entry['name']!r} reads")  # fmt: skip
    if not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_ACTUATION.value:
        actuated = {int(model.actuator_trnid[a, 0]): model.actuator(a).name
                    for a in range(model.nu)
                    if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT}  # fmt: skip
        for name in meta["joint_names"]:
            if actuated.get(joints[name]) != name:
                raise ValueError(f"{mjcf} has no actuator {name!r} on the joint {name!r} (the "
                                 "policy's own model has one per joint)")  # fmt: skip
            if f"{name}_torque" not in sensors:
                raise ValueError(f"{mjcf} lacks the sensor '{name}_torque' (the policy's own "
                                 "model has one per joint)")  # fmt: skip
    if meta["robot_model"] != "anymal-hopper":
        needed = ["base_lin_vel", "base_ang_vel", "base_touch"]
        lacking = [name for name in needed if name not in sensors]
        if not any(name.endswith("_foot_pos") for name in sensors):
            lacking.append("LEG_foot_pos")
        if lacking:
            raise ValueError(f"{mjcf} lacks the sensors {', '.join(lacking)} the velocity "
                             "task's reward reads")  # fmt: skip


class Simulation:
    """The robot of the MJCF, stepped as the project's MuJoCo env steps it."""

    def __init__(self, meta: dict, mjcf: Path, other: bool = False) -> None:
        self.meta, self.env = meta, meta["env_config"]
        if other:  # another model of the robot: adapted to the policy by name
            self.model = other_model(meta, mjcf)
        else:
            self.model = mujoco.MjModel.from_xml_path(str(mjcf))
        self.data = mujoco.MjData(self.model)
        self.query = mujoco.MjData(self.model)  # for what the reward reads between steps
        self.decimation = int(meta["decimation"])
        if other:  # its own timestep: the control period in as many substeps as it takes
            self.decimation = substeps(self.model.opt.timestep, meta["control_dt"], mjcf)
        elif abs(self.model.opt.timestep * self.decimation - meta["control_dt"]) > 1e-12:
            raise ValueError(f"{mjcf}: timestep {self.model.opt.timestep} s x "
                             f"{self.decimation} is not the control period "
                             f"{meta['control_dt']} s")  # fmt: skip
        check_model(self.model, meta, mjcf, other)
        joints = [self.model.joint(name) for name in meta["joint_names"]]
        self.qpos_index = np.array([j.qposadr[0] for j in joints])
        self.dof_index = np.array([j.dofadr[0] for j in joints])
        # the free base's coordinates (0 in the policy's own model, the hopper has none)
        base = meta.get("model_interface", {}).get("free_joint") if other else None
        self.base_qpos = int(free_joint(self.model, base).qposadr[0]) if base else 0
        self.base_dof = int(free_joint(self.model, base).dofadr[0]) if base else 0
        self.sources = [located(self.model, entry) for entry in meta["observation_sources"]]
        self.low = np.asarray(meta["action_low"])
        self.high = np.asarray(meta["action_high"])
        self.nominal = np.asarray(meta["default_joint_positions"])
        self.law = meta["actuator"]
        # the MJCF's actuators switched off (the coast law, another model): the law is
        # applied here, as torques
        actuation_off = mujoco.mjtDisableBit.mjDSBL_ACTUATION.value
        self.torque_law = bool(self.model.opt.disableflags & actuation_off)
        if not self.torque_law:
            self.ctrl_index = np.array([self.model.actuator(n).id for n in meta["joint_names"]])
            self.torque_sensors = [self.sensor_slice(f"{n}_torque") for n in meta["joint_names"]]
        self.hopper = meta["robot_model"] == "anymal-hopper"
        if self.hopper and self.env["hop_reward"] != "hip-velocity":
            raise ValueError(f"hop_reward {self.env['hop_reward']!r}: this example computes "
                             "the hopper's default reward only, 'hip-velocity'")  # fmt: skip
        sources = {entry["source"] for entry in meta["observation_sources"]}
        if not self.hopper and "command" not in sources:
            raise ValueError(f"robot {meta['robot_model']!r}: this example knows the reset and "
                             "reward of the hopper and of the velocity task")  # fmt: skip
        # the quadruped's feet, in the order of its foot sensors (the env's leg order)
        sensors = [self.model.sensor(i).name for i in range(self.model.nsensor)]
        self.legs = [name.removesuffix("_foot_pos") for name in sensors
                     if name.endswith("_foot_pos")]  # fmt: skip
        self.fixed_command = None  # --command: held instead of the drawn one
        self.forward_speeds: list[float] = []  # the base's forward speed at each step

    def sensor_slice(self, name: str) -> slice:
        sensor = self.model.sensor(name)
        return slice(sensor.adr[0], sensor.adr[0] + sensor.dim[0])

    # -- an episode ------------------------------------------------------------------------
    def reset(self, seed: int) -> None:
        """The env's start for seed ``seed``: the nominal pose plus uniform joint noise (and
        the quadruped's command), feet on the ground, at rest."""
        model, data, env = self.model, self.data, self.env
        rng = np.random.default_rng(seed)
        mujoco.mj_resetData(model, data)
        if self.hopper:
            joints = self.nominal + rng.uniform(-env["reset_noise"], env["reset_noise"], 2)
            data.qpos[self.qpos_index] = joints
            data.qpos[0] = standing_hip_height(model, joints) + env["reset_clearance"]
            self.desired = self.nominal.copy()
            self.command = np.zeros(3)
            data.time = 1000.0  # MuJoCo restarts a diverging simulation at time 0
        else:
            noise = rng.uniform(-env["reset_noise"], env["reset_noise"], len(self.nominal))
            joints = np.clip(self.nominal + noise, self.low, self.high)
            self.command = np.array([rng.uniform(*env["command_range"]), 0.0, 0.0])
            for column, name in ((1, "lateral_range"), (2, "yaw_range")):
                low, high = env[name]
                self.command[column] = rng.uniform(low, high) if high > low else low
            if self.fixed_command is not None:
                self.command = np.array(self.fixed_command, dtype=np.float64)
            data.qpos[self.qpos_index] = joints
            mujoco.mj_kinematics(model, data)
            lowest = min(data.site(f"{leg}_foot").xpos[2] for leg in self.legs)
            data.qpos[self.base_qpos + 2] += self.foot_radius() - lowest
            self.forward_speeds = []
            self.desired = joints.copy()  # the env's last action at a start
            self.joint_vel_before = np.zeros(len(joints))
            self.air_time = np.zeros(len(self.legs))
            self.in_contact = np.ones(len(self.legs), dtype=bool)
        mujoco.mj_forward(model, data)  # the sensors of the start
        self.steps = 0

    def observation(self) -> np.ndarray:
        """The observation, built entry by entry from the metadata's ``observation_sources``."""
        data, values = self.data, []
        for entry in self.sources:
            source, index = entry["source"], entry["index"]
            if source == "qpos":
                value = data.qpos[index]
            elif source == "qvel":
                value = data.qvel[index]
            elif source == "sensor":
                value = data.sensordata[self.sensor_slice(entry["sensor"])][index]
            elif source == "projected_gravity":
                start = entry["quaternion"]
                value = projected_gravity(data.qpos[start : start + 4])[index]
            elif source == "desired":
                value = self.desired[index]
            elif source == "command":
                value = self.command[index]
            else:
                raise ValueError(f"observation source {source!r} unknown to this example")
            values.append(value + entry.get("offset", 0.0))
        return np.array(values)

    def step(self, action: np.ndarray) -> tuple[float, bool, bool]:
        """Hold ``action`` for one control step; ``(reward, terminated, truncated)``."""
        model, data = self.model, self.data
        desired = np.clip(action, self.low, self.high)
        last_desired, feet_before = self.desired, None if self.hopper else self.feet()[:, :2]
        self.desired = desired
        torque_sum = np.zeros(len(desired))
        if not self.torque_law:
            data.ctrl[:] = 0.0
            data.ctrl[self.ctrl_index] = desired
        data.qacc_warmstart[:] = 0.0  # each control step starts the solver afresh, as the env
        for _ in range(self.decimation):
            if self.torque_law:  # the law in numpy at every substep, as joint torques
                torque = actuator_torque(self.law, desired, data.qpos[self.qpos_index],
                                         data.qvel[self.dof_index])  # fmt: skip
                data.qfrc_applied[self.dof_index] = torque
                data.qacc_warmstart[:] = 0.0  # the env steps this law one substep per call
                mujoco.mj_step(model, data)
            else:
                mujoco.mj_step(model, data)
                torque = np.array([data.sensordata[s][0] for s in self.torque_sensors])
            torque_sum += torque
        self.steps += 1
        if self.hopper:  # its torque penalty: the mean over the substeps
            reward, terminated = self.hopper_reward(desired, torque_sum / self.decimation)
        else:  # the last substep's torques
            reward, terminated = self.quadruped_reward(desired, last_desired, torque, feet_before)
        if self.hopper:
            episode_steps = self.env["episode_steps"]
        else:
            episode_steps = round(self.env["episode_seconds"] / self.meta["control_dt"])
        return reward, terminated, bool(self.steps >= episode_steps and not terminated)

    def feet(self) -> np.ndarray:
        """(legs, 3) the quadruped's feet (world, m), as the last substep's sensors read them."""
        data = self.data
        return np.stack([data.sensordata[self.sensor_slice(f"{leg}_foot_pos")]
                         for leg in self.legs])  # fmt: skip

    def foot_radius(self) -> float:
        """The quadruped's foot sphere's radius (m): the first foot's geom, or in another
        model the sphere nearest the foot's site on the site's body."""
        model, leg = self.model, self.legs[0]
        try:
            return float(model.geom(f"{leg}_foot").size[0])
        except KeyError:
            site = model.site(f"{leg}_foot")
        spheres = [g for g in range(model.ngeom) if model.geom_bodyid[g] == site.bodyid[0]
                   and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE]  # fmt: skip
        if not spheres:
            raise ValueError(f"the body of the site {leg}_foot has no sphere geom: no foot")
        nearest = min(spheres, key=lambda g: np.linalg.norm(model.geom_pos[g] - site.pos))
        return float(model.geom_size[nearest][0])

    # -- the reward (the env's) --------------------------------------------------------------
    def hopper_reward(self, desired, torque) -> tuple[float, bool]:
        """Paper eq. 4: hop (upward hip speed), track, and spare the joints and the foot."""
        env, qpos, qvel = self.env, self.data.qpos, self.data.qvel
        joint_vel = qvel[self.dof_index]
        terminated = bool(
            not (np.isfinite(qpos).all() and np.isfinite(qvel).all())
            or np.abs(joint_vel).max() > env["blowup_joint_velocity"]
            or abs(qvel[0]) > env["blowup_hip_velocity"]
            or self.data.time < 1000.0  # MuJoCo found it unstable and restarted it
        )
        if terminated:
            return 0.0, True
        query = self.query
        query.qpos[:], query.qvel[:] = qpos, qvel
        mujoco.mj_forward(self.model, query)
        velocity = np.zeros(6)  # the foot's (angular, linear), world frame
        site = self.model.site("foot").id
        mujoco.mj_objectVelocity(self.model, query, mujoco.mjtObj.mjOBJ_SITE, site, velocity, 0)
        terms = (
            (env["c1"] * max(qvel[0], 0.0)) ** 2,
            env["c2"] * np.sum((desired - qpos[self.qpos_index]) ** 2),
            env["c3"] * np.sum(joint_vel**2),
            env["c4"] * np.sum(torque**2),
            env["c5"] * abs(velocity[3]),  # the foot slides along x only (the rail holds y)
        )
        return float(sum(terms)), False

    def quadruped_reward(self, desired, last_desired, torque, feet_xy_before):
        """legged_gym's terms, each times its scale and the control period."""
        env, data, dt = self.env, self.data, self.meta["control_dt"]
        lin_vel = data.sensordata[self.sensor_slice("base_lin_vel")]
        ang_vel = data.sensordata[self.sensor_slice("base_ang_vel")]
        base = self.base_qpos
        gravity = projected_gravity(data.qpos[base + 3 : base + 7])
        height = data.qpos[base + 2]
        self.forward_speeds.append(float(lin_vel[0]))
        joint_vel = data.qvel[self.dof_index].copy()
        feet = self.feet()
        contact = feet[:, 2] < self.foot_radius() + 0.005
        planted = contact & self.in_contact
        speed = np.sqrt(np.sum((feet[:, :2] - feet_xy_before) ** 2, axis=-1)) / dt
        slip = np.where(planted, speed, 0.0)
        touchdown = contact & ~self.in_contact
        self.air_time += dt
        moving = np.linalg.norm(self.command[:2]) > 0.1
        air_paid = np.sum((self.air_time - 0.5) * touchdown) * moving
        self.air_time[contact] = 0.0
        self.in_contact = contact
        command, sigma = self.command, env["tracking_sigma"]
        terms = {
            "tracking_lin_vel": np.exp(-np.sum((command[:2] - lin_vel[:2]) ** 2) / sigma),
            "tracking_ang_vel": np.exp(-((command[2] - ang_vel[2]) ** 2) / sigma),
            "lin_vel_z": lin_vel[2] ** 2,
            "ang_vel_xy": np.sum(ang_vel[:2] ** 2),
            "orientation": np.sum(gravity[:2] ** 2),
            "base_height": (height - env["base_height_target"]) ** 2,
            "torques": np.sum(torque**2),
            "joint_acc": np.sum(((joint_vel - self.joint_vel_before) / dt) ** 2),
            "action_rate": np.sum((desired - last_desired) ** 2),
            "feet_air_time": air_paid,
            "feet_slip": np.sum(slip**2),
        }
        reward = sum(value * env["reward_scales"][name] * dt for name, value in terms.items())
        self.joint_vel_before = joint_vel
        tilt = np.arccos(np.clip(-gravity[2], -1.0, 1.0))
        terminated = bool(
            height < env["fall_height"]
            or tilt > env["fall_tilt"]
            or data.sensordata[self.sensor_slice("base_touch")][0] > 0
            or not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all())
        )
        return float(reward), terminated


def run_episode(policy: Policy, sim: Simulation, seed: int, max_steps: int | None):
    """One episode from the env's start for ``seed``: ``(return, steps, how it ended)``."""
    sim.reset(seed)
    policy.reset()
    total, steps, ended = 0.0, 0, "step limit"
    while max_steps is None or steps < max_steps:
        action = policy(sim.observation())
        reward, terminated, truncated = sim.step(action)
        total += reward
        steps += 1
        if terminated or truncated:
            ended = "terminated" if terminated else "truncated"
            break
    return total, steps, ended


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("policy", type=Path, help="an ONNX file written by `cpg-actor export`, "
                        "or its export or run directory")  # fmt: skip
    parser.add_argument("--mjcf", type=Path, default=None,
                        help="the robot's MJCF (default: the one the export wrote next to the "
                        "policy); for a quadruped, any MJCF of the robot: joints found by "
                        "name, the actuator law applied as torques, the ground and sensors "
                        "added where it lacks them")  # fmt: skip
    parser.add_argument("--command", type=float, nargs="+", default=None,
                        metavar="VX [VY YAW]",
                        help="a quadruped's velocity command (m/s, m/s, rad/s), held for the "
                        "episode instead of the drawn one")  # fmt: skip
    parser.add_argument("--seed", type=int, default=1000, help="the start's seed (default 1000)")
    parser.add_argument("--steps", type=int, default=None, help="stop after this many steps")
    args = parser.parse_args(argv)
    try:
        path = policy_file(args.policy)
        policy = Policy(path)
        mjcf = args.mjcf or path.with_name(policy.meta["mjcf_file"])
        if not mjcf.is_file():
            raise ValueError(f"the robot's MJCF {mjcf} does not exist; pass --mjcf PATH")
        other = args.mjcf is not None and bool(
            policy.meta.get("model_interface", {}).get("free_joint")
        )  # a quadruped's
        sim = Simulation(policy.meta, mjcf, other=other)
        if args.command is not None:
            if sim.hopper or len(args.command) not in (1, 3):
                raise ValueError("--command takes VX or VX VY YAW, for a quadruped policy")
            sim.fixed_command = [*args.command, 0.0, 0.0][:3]
        total, steps, ended = run_episode(policy, sim, args.seed, args.steps)
    except ValueError as error:
        print(f"deploy_onnx.py: error: {error}", file=sys.stderr)
        return 2
    print(f"{policy.meta['agent']} on {policy.meta['robot_model']}, seed {args.seed}: "
          f"return {total:.10g} over {steps} steps ({ended})")  # fmt: skip
    if sim.forward_speeds:  # the velocity task's tracking, as the env's metrics measure it
        speeds = np.array(sim.forward_speeds)
        print(f"command {sim.command[0]:.3g} m/s: mean forward speed {speeds.mean():.4f} m/s, "
              f"speed error {np.abs(speeds - sim.command[0]).mean():.4f} m/s")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
