"""examples/deploy_onnx.py: the exported ONNX policy run on its robot in MuJoCo with numpy,
onnxruntime and mujoco alone (no torch, no cpg_actor) scores `cpg-actor eval`'s return, on
the hopper and the quadrupeds (ANYmal B, the Go1).

Two comparisons per robot: against the library's deterministic evaluation acting with the
same ONNX file (the example's simulation, observation and reward mirror the env's: equal to
float64 rounding), and against `cpg-actor eval`'s own PyTorch policy (within 1 %: ONNX Runtime
and PyTorch round float32 differently, by up to a few 1e-6 rad per action, and a legged
robot's contacts carry such differences into the return; the library's own evaluation changes
as much with the number of episodes run in one batch)."""

import re
import runpy
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from cpg_actor.config import TrainConfig
from cpg_actor.deploy import load_policy
from cpg_actor.deploy.export import export_policy
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.build import make_env
from cpg_actor.training.evaluation import evaluate, evaluate_policy
from tiny import trained_run  # tests/tiny.py

ort = pytest.importorskip("onnxruntime")
pytest.importorskip("onnxscript")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "deploy_onnx.py"
SEED = 1000


def exported_run(path: Path, agent: str, robot: str, **changes) -> tuple[TrainConfig, Path]:
    """A tiny training run (its config.yaml as `cpg-actor train` writes it), exported."""
    config = TrainConfig.load(trained_run(path, agent, robot, **changes) / "config.yaml")
    policy = load_policy(path, run_config=config)
    return config, export_policy(policy, path / "export" / "policy.onnx", "onnx")


def run_example(policy: Path, seed: int) -> tuple[float, int, str]:
    """The example in a fresh interpreter: (return, steps, how it ended); it must import
    neither torch nor cpg_actor."""
    code = "\n".join([
        "import runpy, sys",
        f"sys.argv = ['deploy_onnx.py', {str(policy)!r}, '--seed', '{seed}']",
        f"code = runpy.run_path({str(EXAMPLE)!r})['main']()",
        "loaded = sorted({n.split('.')[0] for n in sys.modules} & {'torch', 'cpg_actor'})",
        "print('imported:', loaded)",
        "sys.exit(code)",
    ])  # fmt: skip
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "imported: []" in result.stdout, result.stdout
    found = re.search(r"return (\S+) over (\d+) steps \((\w+)\)", result.stdout)
    assert found, result.stdout
    return float(found[1]), int(found[2]), found[3]


class OnnxPolicy:
    """The exported file behind the library's evaluation (``reset``, ``act``)."""

    def __init__(self, path: Path) -> None:
        self.session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        self.initial = np.load(path.with_name(path.name + ".initial_state.npy"))

    def reset(self, num_envs: int) -> None:
        self.state = self.initial.copy()

    def act(self, obs, deterministic: bool = True):
        obs = np.asarray(obs, dtype=np.float32)
        action, self.state = self.session.run(None, {"observation": obs, "state": self.state})
        return SimpleNamespace(action=action)


@pytest.mark.parametrize(
    ("robot", "agent", "changes", "against_pytorch"),
    [
        ("hopper", "cpg-actor", {}, True),
        # ONNX Runtime's float32 rounding differs from PyTorch's by about 1e-6 rad; the
        # quadruped's contacts carry that into an untrained CPG-Actor's small return (a few
        # %), so only its agreement with the library's evaluation of the same file is exact
        ("anymal", "cpg-actor", {}, False),
        ("anymal", "mlp", {}, True),
        ("go1", "mlp", {}, True),  # any quadruped: its feet from the MJCF
        # the stateless MLP, and the actuator law run in numpy (the MJCF's actuators off)
        ("hopper", "mlp", {"env": {"actuator_law": "coast"}}, True),
    ],
)
def test_the_example_scores_the_evaluations_return(
    tmp_path, robot, agent, changes, against_pytorch
):
    config, policy_path = exported_run(tmp_path / "run", agent, robot, **changes)
    total, steps, ended = run_example(policy_path, SEED)

    env = make_env(config, get_robot(config.robot), 1, 1)
    try:
        same_file = evaluate(OnnxPolicy(policy_path), env, seed=SEED,
                             control_dt=float(config.env.control_dt),
                             max_steps=int(config.env.episode_steps), traces=False)  # fmt: skip
    finally:
        env.close()
    assert steps == same_file["length"][0]
    assert ended == ("truncated" if steps == config.env.episode_steps else "terminated")
    expected = same_file["episode_return"][0]
    assert total == pytest.approx(expected, rel=1e-6, abs=1e-9 * steps)

    if not against_pytorch:
        return
    # `cpg-actor eval RUN --episodes 1 --seed SEED`, the PyTorch policy
    policy = load_policy(policy_path.parents[1], run_config=config)
    pytorch = evaluate_policy(policy, config, 1, seed=SEED)["episode_return"][0]
    assert total == pytest.approx(pytorch, rel=1e-2)


def test_the_example_refuses_a_nonfinite_observation_and_a_missing_file(tmp_path, capsys):
    _, policy_path = exported_run(tmp_path / "run", "cpg-actor", "hopper")
    example = runpy.run_path(str(EXAMPLE))
    policy = example["Policy"](policy_path)
    observation = np.array([0.4, -0.8, 0.0, 0.0, 0.4, -0.8, 0.47, 0.0])
    assert np.isfinite(policy(observation)).all()
    observation[[1, 6]] = [np.nan, np.inf]
    with pytest.raises(ValueError, match=r"non-finite observation entries \['p_m_KFE', "
                                         r"'hip_height'\]: refused"):  # fmt: skip
        policy(observation)
    assert example["main"]([str(tmp_path / "missing.onnx")]) == 2
    err = capsys.readouterr().err
    assert "missing.onnx does not exist" in err and len(err.splitlines()) == 1
    (policy_path.with_name("policy.onnx.robot.xml")).rename(tmp_path / "robot.xml")
    assert example["main"]([str(policy_path)]) == 2
    assert "pass --mjcf PATH" in capsys.readouterr().err
    assert example["main"]([str(policy_path), "--mjcf", str(tmp_path / "robot.xml"),
                            "--steps", "3"]) == 0  # fmt: skip
    assert "over 3 steps (step limit)" in capsys.readouterr().out


def test_the_example_takes_a_run_or_export_directory_and_refuses_a_damaged_file(tmp_path, capsys):
    import onnx

    _, policy_path = exported_run(tmp_path / "run", "cpg-actor", "hopper")
    example = runpy.run_path(str(EXAMPLE))
    for directory in (tmp_path / "run", tmp_path / "run" / "export"):
        assert example["main"]([str(directory), "--steps", "3"]) == 0
        assert "over 3 steps (step limit)" in capsys.readouterr().out
    assert example["main"]([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "is a directory without policy.onnx or export/policy.onnx" in err
    assert len(err.splitlines()) == 1
    truncated = tmp_path / "truncated.onnx"
    truncated.write_bytes(policy_path.read_bytes()[:1000])
    bare = tmp_path / "bare.onnx"
    model = onnx.load(policy_path)
    del model.metadata_props[:]
    onnx.save(model, bare)
    for path, message in ((truncated, "is not an ONNX model onnxruntime loads"),
                          (bare, "has no cpg-actor metadata")):  # fmt: skip
        assert example["main"]([str(path)]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.splitlines()) == 1, err


def test_the_example_refuses_a_model_or_metadata_it_cannot_run_in_one_line(tmp_path, capsys):
    import onnx

    example = runpy.run_path(str(EXAMPLE))

    def refused(*args: str) -> str:
        assert example["main"]([*args, "--steps", "2"]) == 2
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1, err
        return err

    _, quadruped = exported_run(tmp_path / "anymal", "mlp", "anymal")
    _, hopper = exported_run(tmp_path / "hopper", "mlp", "hopper")
    own = quadruped.with_name("policy.onnx.robot.xml").read_text()
    hopper_xml = hopper.with_name("policy.onnx.robot.xml").read_text()

    def model(name: str, text: str) -> str:
        (tmp_path / name).write_text(text)
        return str(tmp_path / name)

    # another model's timestep: none, or so fine a control step would never end
    for timestep, message in (
        ("0", "is not a positive number of seconds"),
        ("1e-9", "takes more than 10,000 substeps per control period"),
    ):
        text = own.replace('timestep="0.002"', f'timestep="{timestep}"')
        assert text != own
        assert message in refused(str(quadruped), "--mjcf", model(f"t{timestep}.xml", text))
    # the policy's joints by name, of another type
    knee = '<joint name="LF_KFE" type="hinge" axis="0 1 0" range="-1.7 0.1"/>'
    assert knee in own
    for kind, joint in (("slide", knee.replace("hinge", "slide")),
                        ("ball", '<joint name="LF_KFE" type="ball"/>')):  # fmt: skip
        err = refused(str(quadruped), "--mjcf", model(f"{kind}.xml", own.replace(knee, joint)))
        assert f"must be hinges; LF_KFE ({kind}) is not" in err
    err = refused(str(hopper), "--mjcf", model("h.xml", hopper_xml.replace(
        'name="HFE" type="hinge"', 'name="HFE" type="slide"')))  # fmt: skip
    assert "HFE (slide) is not" in err
    # the policy's own model: an actuator on each of its joints, the joints it observes
    moved = hopper_xml.replace('<dcmotor name="HFE" joint="HFE"', '<dcmotor name="HFE" joint="KFE"')
    assert "no actuator 'HFE' on the joint 'HFE'" in refused(str(hopper), "--mjcf",
                                                             model("a.xml", moved))  # fmt: skip
    no_rail = "\n".join(line for line in hopper_xml.splitlines() if 'name="rail"' not in line)
    assert "lacks the joint 'rail' the observation's 'hip_height' reads" in refused(
        str(hopper), "--mjcf", model("r.xml", no_rail)
    )
    # metadata without the joints
    bare = tmp_path / "export" / "policy.onnx"
    bare.parent.mkdir()
    onnx_model = onnx.load(quadruped)
    kept = [p for p in onnx_model.metadata_props if p.key != "joint_names"]
    del onnx_model.metadata_props[:]
    onnx_model.metadata_props.extend(kept)
    onnx.save(onnx_model, bare)
    bare.with_name("policy.onnx.robot.xml").write_text(own)
    assert "its metadata lacks joint_names" in refused(str(bare))
