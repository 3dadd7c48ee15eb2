"""Safe by construction: every count and size a config or a flag sets has an upper bound,
checked before anything is built or written; an error message quotes what was given in a
bounded text; YAML is read within bounds (size, aliases expanded, depth). Each refusal is one
line, and is refused before any work, so these tests are quick."""

import dataclasses
import tracemalloc
import typing
from pathlib import Path

import pytest

from cpg_actor.agents.base import AgentConfig
from cpg_actor.agents.open_loop_es import ESConfig
from cpg_actor.agents.warm_start import WarmStartConfig
from cpg_actor.cli import main
from cpg_actor.config import TrainConfig, compose_config, parse_override, read_config_file
from cpg_actor.limits import MAX_BRIEF, brief
from cpg_actor.ppo.config import PPOConfig
from cpg_actor.robots.common.quadruped.config import QuadrupedConfig
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.safe_yaml import parse_yaml
from cpg_actor.terrain.config import Terrain

HUGE = 10**20  # above every bound (the largest, a seed's, is 2**63 - 1)
ROOT = Path(__file__).resolve().parents[1]


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def int_fields(cls: type, prefix: str) -> list[tuple[str, bool]]:
    """(dotted key, is a list of ints) of every integer field of the dataclass ``cls``."""
    hints = typing.get_type_hints(cls)
    found = []
    for field in dataclasses.fields(cls):
        hint = hints[field.name]
        args = typing.get_args(hint)
        if hint is int or (int in args and typing.get_origin(hint) is not tuple):
            found.append((prefix + field.name, False))
        elif typing.get_origin(hint) is tuple and args[:1] == (int,):
            found.append((prefix + field.name, True))
    return found


# every integer field a training config has: the run's, its sections', each robot's env's
FIELDS = [
    *((key, listed, []) for key, listed in int_fields(TrainConfig, "")),
    *((key, listed, []) for key, listed in int_fields(AgentConfig, "agent_config.")),
    *((key, listed, []) for key, listed in int_fields(PPOConfig, "ppo.")),
    *((key, listed, []) for key, listed in int_fields(WarmStartConfig, "warm_start.")),
    *((key, listed, []) for key, listed in int_fields(ESConfig, "es.")),
    *((key, listed, []) for key, listed in int_fields(HopperConfig, "env.")),
    *((key, listed, ["robot=anymal"]) for key, listed in int_fields(QuadrupedConfig, "env.")),
    *((key, listed, ["robot=go1"]) for key, listed in int_fields(Terrain, "env.terrain.")),
]


def test_the_sweep_finds_the_fields_it_should():
    keys = {key for key, _, _ in FIELDS}
    assert {"num_envs", "eval_episodes", "update_threads", "env_threads", "ppo.num_epochs",
            "agent_config.actor_hidden", "agent_config.critic_hidden", "es.popsize",
            "env.decimation", "env.terrain.levels", "env.terrain.seed"} <= keys  # fmt: skip
    assert len(FIELDS) >= 35


@pytest.mark.parametrize(("key", "listed", "robot"), FIELDS, ids=[key for key, *_ in FIELDS])
@pytest.mark.parametrize("value", [HUGE, "1e309"], ids=["huge", "inf"])
def test_every_integer_field_is_bounded_and_refused_in_one_line(key, listed, robot, value):
    text = f"[{value}]" if listed else str(value)
    with pytest.raises(ValueError) as error:
        compose_config(overrides=[*robot, f"{key}={text}"])
    message = str(error.value)
    assert "\n" not in message and len(message) < 1000, message
    assert key.rsplit(".", 1)[-1] in message, message


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["ppo.num_epochs=1e9"], "ppo.num_epochs must be an integer from 1 to 10,000"),
        (["num_envs=100000000"], "num_envs must be an integer from 1 to 262,144"),
        (["eval_episodes=1e9"], "eval_episodes must be an integer from 1 to 1,000"),
        (["agent_config.actor_hidden=[1000000,1000000]"], "from 1 to 65,536, got 1000000"),
        (["agent_config.critic_hidden=[60000,60000]"], "above the 268,435,456 accepted"),
        (["agent_config.actor_hidden=[" + ",".join(["8"] * 100) + "]"], "1 to 64 layer sizes"),
        (["num_envs=65536", "ppo.num_steps=65536"], "samples, above the 16,777,216 accepted"),
        (["robot=anymal", "env.terrain.kinds=all", "env.terrain.levels=100000"],
         "terrain.levels must be an integer from 1 to 1,000"),
        (["robot=anymal", "env.terrain.kinds=all", "env.terrain.resolution=1e-4"],
         "height map of 600,001,600,001 samples"),
        (["robot=anymal", "env.physics_dt=1e-320"], "episodes of inf control steps"),
        (["robot=anymal", "env.command_resample_seconds=1e300"], "at most 100,000 control steps"),
        (["agent_config.init_std=1e309"], "agent_config.init_std must be a finite number > 0"),
        (["es.popsize=1000", "es.episodes=1000", "agent=open-loop-es"], "envs are above"),
    ],
)  # fmt: skip
def test_sizes_that_would_hang_or_exhaust_memory_are_refused(overrides, message):
    with pytest.raises(ValueError, match=None) as error:
        compose_config(overrides=overrides)
    assert message in str(error.value) and "\n" not in str(error.value), str(error.value)


# -- bounded error messages -----------------------------------------------------------------
@pytest.mark.parametrize(
    "value",
    [list(range(10**6)), "x" * 10**6, 10**5000, {str(i): i for i in range(10**5)}],
    ids=["list", "string", "integer", "mapping"],
)
def test_brief_is_bounded(value):
    assert len(brief(value)) <= MAX_BRIEF


def test_brief_of_a_deep_structure_is_bounded():
    deep: list = []
    for _ in range(10_000):
        deep = [deep]
    assert len(brief(deep)) <= MAX_BRIEF


@pytest.mark.parametrize(
    "override",
    [
        "agent_config.activation=" + "x" * 100_000,
        "ppo.lr_schedule=[" + ",".join(["1"] * 50_000) + "]",
        "seed=" + "9" * 5_000,
        "agent_config.actor_hidden=[" + ",".join(["0"] * 50_000) + "]",
        "env.sim={" + ",".join(f"k{i}: 1" for i in range(20_000)) + "}",
    ],
    ids=["string", "list", "integer", "layers", "mapping"],
)
def test_an_error_quoting_a_huge_value_is_one_short_line(override):
    with pytest.raises(ValueError) as error:
        compose_config(overrides=[override])
    assert "\n" not in str(error.value) and len(str(error.value)) < 1000, str(error.value)[:2000]


# -- YAML within bounds ---------------------------------------------------------------------
def billion_laughs(key: str = "agent_config:\n  cpg_initial:\n    bomb: *i\n") -> str:
    """Nine levels of ten aliases each: 10**9 values once expanded, in a dozen lines."""
    lines = ["a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for first, second in zip("abcdefgh", "bcdefghi", strict=True):
        lines.append(f"{second}: &{second} [{', '.join([f'*{first}'] * 10)}]")
    return "_laughs:\n" + "".join(f"  {line}\n" for line in lines) + key


def test_a_billion_laughs_config_is_refused_quickly_in_bounded_memory(tmp_path):
    path = tmp_path / "bomb.yaml"
    path.write_text(billion_laughs())
    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match="holds more than 100,000 values with its aliases"):
            read_config_file(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 50 * 2**20


def test_a_billion_laughs_under_a_checked_key_is_one_line_from_the_cli(tmp_path, capsys):
    path = tmp_path / "bomb.yaml"
    path.write_text(billion_laughs("agent_config:\n  actor_hidden: *i\n"))
    run_dir = tmp_path / "run"
    assert main(["train", "--config", str(path), "--run-dir", str(run_dir)]) == 2
    assert "aliases expanded" in one_line(capsys)
    assert not run_dir.exists()


def test_a_billion_laughs_in_a_set_value_is_refused():
    flow = "{a: &a [1,1,1,1,1,1,1,1,1,1], " + ", ".join(
        f"{second}: &{second} [{', '.join([f'*{first}'] * 10)}]"
        for first, second in zip("abcdefgh", "bcdefghi", strict=True)
    ) + "}"  # fmt: skip
    with pytest.raises(ValueError, match="aliases expanded"):
        parse_override(f"agent_config.cpg_initial={flow}")


def test_deeply_nested_yaml_is_one_line_not_a_recursion_error(tmp_path, capsys):
    path = tmp_path / "deep.yaml"
    path.write_text("agent_config:\n  cpg_initial:\n    x: " + "[" * 10_000 + "]" * 10_000 + "\n")
    with pytest.raises(ValueError, match="nests deeper than 100 levels"):
        read_config_file(path)
    assert main(["train", "--config", str(path), "--run-dir", str(tmp_path / "run")]) == 2
    assert "nests deeper than 100 levels" in one_line(capsys)
    with pytest.raises(ValueError, match="nests deeper"):
        parse_override("agent_config.cpg_initial=" + "[" * 10_000 + "]" * 10_000)


def test_a_structure_holding_itself_is_refused(tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text("agent_config:\n  cpg_initial: &a\n    self: *a\n")
    with pytest.raises(ValueError, match="a structure holding itself"):
        read_config_file(path)


def test_a_config_file_too_large_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "large.yaml"
    path.write_text("seed: 1\n# " + "x" * 2**21 + "\n")
    with pytest.raises(ValueError, match="above the 1,048,576 accepted"):
        read_config_file(path)


def test_an_integer_of_too_many_digits_is_one_line(tmp_path):
    path = tmp_path / "digits.yaml"
    path.write_text("seed: " + "9" * 5_000 + "\n")
    with pytest.raises(ValueError, match="is not valid YAML") as error:
        read_config_file(path)
    assert len(str(error.value)) < 1000


def test_valid_yaml_reads_as_before():
    assert parse_yaml("a: &x [1, 2]\nb: *x\nc: {d: 1.5}\n") == {
        "a": [1, 2], "b": [1, 2], "c": {"d": 1.5}}  # fmt: skip


def test_every_yaml_reader_uses_the_bounded_loader():
    """No module, benchmark or results script reads YAML around :mod:`cpg_actor.safe_yaml`."""
    readers = ("yaml.safe_load(", "yaml.load(", "yaml.unsafe_load(", "yaml.full_load(",
               "yaml.safe_load_all(", "yaml.load_all(")  # fmt: skip
    found = [
        f"{path.relative_to(ROOT)}: {reader}"
        for folder in ("src", "benchmarks", "docs")
        for path in sorted((ROOT / folder).rglob("*.py"))
        for reader in readers
        if reader in path.read_text(encoding="utf-8") and path.name != "safe_yaml.py"
    ]
    assert not found


# -- the command line -----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["train", "--seeds", "1000000"], "--seeds must be an integer from 1 to 10,000"),
        (["train", "--seeds", "2000", "--num-envs", "200"], "envs are above the 262,144"),
        (["train", "--num-envs", "100000000"], "num_envs must be an integer from 1 to 262,144"),
        (["train", "--set", "eval_episodes=1e9"], "eval_episodes must be an integer from 1"),
        (["train", "--set", "ppo.num_epochs=1e309"], "ppo.num_epochs must be an integer, got inf"),
        (["train", "--resume", "--run-dir", ""], "--run-dir is empty"),
        (["train", "--run-dir", "", "--set", "bogus=1"], "--run-dir is empty"),
        (["eval", ""], "RUN_DIR is empty"),
        (["eval", "RUN", "--checkpoint", ""], "--checkpoint is empty"),
        (["export", ""], "RUN_DIR is empty"),
        (["export", "RUN", "--out", ""], "--out is empty"),
        # --set bogus=1: the old code refused that later, before training anything
        (["reproduce", "--out", "OUT", "--workers", "100000", "--set", "bogus=1"],
         "--workers must be an integer from 1 to 1,024"),
        (["reproduce", "--out", "OUT", "--seeds", "1000000", "--set", "bogus=1"],
         "--seeds must be an integer from 1 to 10,000"),
        (["reproduce", "--out", "OUT", "--eval-episodes", "1000000000", "--set", "bogus=1"],
         "--eval-episodes must be an integer from 1 to 1,000"),
        (["sweep", "--out", "OUT", "--workers", "100000", "--set", "bogus=1"],
         "--workers must be an integer from 1 to 1,024"),
        (["sweep", "--out", "OUT", "--seeds", "1000000", "--set", "bogus=1"],
         "--seeds must be an integer from 1 to 10,000"),
    ],
)  # fmt: skip
def test_a_count_flag_or_an_empty_path_is_one_line_and_writes_nothing(
    tmp_path, capsys, monkeypatch, argv, message
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "RUN").mkdir()
    (tmp_path / "RUN" / "config.yaml").write_text("seed: 0\n")
    (tmp_path / "RUN" / "checkpoints").mkdir()
    (tmp_path / "RUN" / "checkpoints" / "last.pt").write_bytes(b"")
    before = sorted(path.relative_to(tmp_path) for path in tmp_path.rglob("*"))
    assert main(argv) == 2
    assert message in one_line(capsys)
    assert sorted(path.relative_to(tmp_path) for path in tmp_path.rglob("*")) == before
