"""Another faithful model of the Go1, for running a policy on a model it was not trained on
(``examples/deploy_onnx.py --mjcf``, ``docs/go1.md``, "On another model of the Go1").

The same robot (bodies, masses, inertias, joints, collision shapes: this project's Go1 MJCF),
with the passive dynamics and the contact that mjlab gives its Go1 (``mujocolab/mjlab``,
Apache-2.0, ``asset_zoo/robots/unitree_go1/go1_constants.py`` and ``xmls/go1.xml``; numbers
only, no file of it is included) instead of Menagerie's, which this project's model uses:

================  ======================================  =====================================
                  this project (Menagerie's ``go1.xml``)  the variant (mjlab's Go1)
================  ======================================  =====================================
joint damping     1 (abduction), 2 (hip, knee) N m s/rad  0 (passive; mjlab's damping is its PD's)
armature          0.01 kg m^2                             the rotor's 1.11842e-4 kg m^2 reflected
                                                          through the gearbox: x 6^2 = 0.00403
                                                          (abduction, hip), x 9^2 = 0.00906 (knee)
friction loss     0.2 N m                                 0
foot contact      condim 6, solimp 0.015 1 0.031,         condim 3, solimp 0.9 0.95 0.023,
                  solref 0.02 1                           solref 0.02 1 (MuJoCo's default)
foot and ground   0.8                                     0.6
sliding friction
================  ======================================  =====================================

The file is written as another tool would write it: the legs in legged_gym's order (FL, FR,
RL, RR: other joint indices, the same names), an IMU site where mjlab puts it (on the Go1's
board, off the trunk's origin), and none of this project's actuators, sensors or other sites:
a control loop finds the joints by name, applies its own actuator law and adds the sensors it
needs. The timestep and the solver options are this project's (the comparison is about the
robot's model, not the integrator).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from cpg_actor.robots.common.notice import generated_comment
from cpg_actor.robots.go1 import description as robot

VARIANT_PATH = Path(__file__).resolve().parent / "assets" / "go1_mjlab_physics.xml"
SOURCES = ("cpg_actor/robots/go1/description.py", "cpg_actor/robots/go1/variant.py")
ROTOR_INERTIA = 0.000111842  # kg m^2 (Unitree's URDF, as mjlab reads it)
GEAR_RATIO = {"hip": 6.0, "thigh": 6.0, "calf": 9.0}  # the knee's gearbox 1.5 x the hip's
ARMATURE = {kind: ROTOR_INERTIA * ratio**2 for kind, ratio in GEAR_RATIO.items()}
DAMPING = 0.0
FRICTION_LOSS = 0.0
FOOT_CONTACT = {"condim": "3", "solimp": "0.9 0.95 0.023", "solref": "0.02 1"}
FRICTION = 0.6
LEG_ORDER = ("FL", "FR", "RL", "RR")  # legged_gym's (its URDF's alphabetical order)
IMU_SITE = (-0.01592, -0.06659, -0.00617)  # m, in the trunk frame


# the variant's differences from this project's model, each of which ``only`` can name alone
TERMS = ("damping", "armature", "friction_loss", "contact", "friction")


def variant_mjcf(only: str | None = None) -> str:
    """The variant's MJCF text, generated from this project's Go1 MJCF; ``only`` (one of
    :data:`TERMS`): the project's model written the variant's way (legs reordered, no
    actuators or sensors) with that one difference alone (what each difference does)."""
    from cpg_actor.robots.go1.mjcf import mjcf_text

    if only is not None and only not in TERMS:
        raise ValueError(f"unknown variant term {only!r}; accepted: {', '.join(TERMS)}")

    def changed(term: str) -> bool:
        return only is None or only == term

    root = ET.fromstring(mjcf_text(foot_friction=FRICTION if changed("friction")
                                   else robot.FOOT_FRICTION))  # fmt: skip
    for name in ("actuator", "sensor", "keyframe"):
        for element in root.findall(name):
            root.remove(element)
    trunk = root.find("worldbody/body")
    for parent in [trunk, *trunk.iter("body")]:
        for site in parent.findall("site"):
            parent.remove(site)
    ET.SubElement(trunk, "site", name="imu", pos=" ".join(f"{v:g}" for v in IMU_SITE),
                  size="0.01")  # fmt: skip
    legs = {body.get("name").split("_")[0]: body for body in trunk.findall("body")}
    for body in legs.values():
        trunk.remove(body)
    for leg in LEG_ORDER:
        trunk.append(legs[leg])
    for joint in trunk.iter("joint"):
        kind = joint.get("name").split("_")[1]
        if changed("damping"):
            joint.set("damping", f"{DAMPING:g}")
        if changed("armature"):
            joint.set("armature", f"{ARMATURE[kind]:.6g}")
        if changed("friction_loss"):
            joint.set("frictionloss", f"{FRICTION_LOSS:g}")
    for geom in root.iter("geom"):
        if geom.get("name", "").endswith("_foot"):
            if changed("contact"):
                geom.attrib.update(FOOT_CONTACT)
            if changed("friction"):
                spin_roll = geom.get("friction").split()[1:]
                geom.set("friction", " ".join([f"{FRICTION:g}", *spin_roll]))
    ET.indent(root, space="  ")
    comment = generated_comment(SOURCES, robot.LICENSE_NOTICE)
    return "\n".join([*comment, ET.tostring(root, encoding="unicode"), ""])


def variant_assets() -> dict[Path, str]:
    """The shipped variant file and its text (``python -m cpg_actor.robots`` writes it)."""
    return {VARIANT_PATH: variant_mjcf()}
