"""What a control loop needs to find in *another* MJCF of the robot to run an exported policy
on it (the export metadata's ``model_interface``), read from the model the policy trained on.

A policy moved to another simulator's model of the same robot (another file, other passive
dynamics, joints in another order) finds its joints there by name, not by index. So the
metadata says, for each observation entry read from ``qpos`` / ``qvel``, which joint it is
(``observation_sources``' ``joint`` and ``element``: the coordinate within that joint), and
everything the observation and the reward read besides the joints: the free base, the sites
and the sensors, written as MuJoCo names them (``mjtSensor``, ``mjtObj``, ``mjtGeom``), so
that ``examples/deploy_onnx.py --mjcf OTHER.xml`` adds those the other file lacks, and the
ground (its sliding friction) when it has none.
"""

from __future__ import annotations

from typing import Any

import mujoco


def _name(model: mujoco.MjModel, kind: mujoco.mjtObj, index: int) -> str:
    return mujoco.mj_id2name(model, kind, int(index)) or ""


def model_interface(mjcf: str) -> dict[str, Any]:
    """The free base, the sites, the sensors on sites and the ground of the MJCF text
    ``mjcf`` (the exported policy's own model), as plain JSON values."""
    model = mujoco.MjModel.from_xml_string(mjcf)
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    body = mujoco.mjtObj.mjOBJ_BODY
    sites = [
        {
            "name": _name(model, mujoco.mjtObj.mjOBJ_SITE, i),
            "body": _name(model, body, model.site_bodyid[i]),
            "type": mujoco.mjtGeom(model.site_type[i]).name,
            "pos": model.site_pos[i].tolist(),
            "quat": model.site_quat[i].tolist(),
            "size": model.site_size[i].tolist(),
        }
        for i in range(model.nsite)
    ]
    sensors = []
    for i in range(model.nsensor):
        objtype = mujoco.mjtObj(model.sensor_objtype[i])
        if objtype != mujoco.mjtObj.mjOBJ_SITE:  # e.g. actuator forces: the law gives those
            continue
        sensors.append({
            "name": _name(model, mujoco.mjtObj.mjOBJ_SENSOR, i),
            "type": mujoco.mjtSensor(model.sensor_type[i]).name,
            "objtype": objtype.name,
            "objname": _name(model, objtype, model.sensor_objid[i]),
        })  # fmt: skip
    planes = [g for g in range(model.ngeom) if model.geom_bodyid[g] == 0
              and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE]  # fmt: skip
    return {
        "free_joint": _name(model, mujoco.mjtObj.mjOBJ_JOINT, free[0]) if free else "",
        "base_body": _name(model, body, model.jnt_bodyid[free[0]]) if free else "",
        "sites": sites,
        "sensors": sensors,
        "ground_friction": model.geom_friction[planes[0]].tolist() if planes else None,
    }


def named_sources(mjcf: str, sources: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``sources`` (the observation's, :data:`cpg_actor.deploy.export.OBSERVATION_SOURCES`)
    with each ``qpos`` / ``qvel`` entry's joint name and element (the index within that
    joint's coordinates) added, for the model of the MJCF text ``mjcf``; the entries
    reading the base's quaternion get the free joint's name."""
    model = mujoco.MjModel.from_xml_string(mjcf)
    joints = mujoco.mjtObj.mjOBJ_JOINT

    def owner(index: int, kind: str) -> tuple[str, int]:
        start = model.jnt_qposadr if kind == "qpos" else model.jnt_dofadr
        j = max(j for j in range(model.njnt) if start[j] <= index)
        return _name(model, joints, j), int(index - start[j])

    named = []
    for entry in sources:
        entry = dict(entry)
        if entry["source"] in ("qpos", "qvel"):
            entry["joint"], entry["element"] = owner(entry["index"], entry["source"])
        elif entry["source"] == "projected_gravity":
            entry["joint"], entry["element"] = owner(entry["quaternion"], "qpos")
        named.append(entry)
    return named
