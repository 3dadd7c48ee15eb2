"""The package's layers: no module imports from a layer above its own (the CLI above the
experiments, above deployment, above training, above the configuration, above the agents
and PPO, above the robots' registry, above the robots, above their tasks and shared
machinery (and the parts they share), above the CPG; small shared utilities at the bottom),
and the folders of one layer import each other one way only (no cycle).

The longest dotted prefix in ``LAYERS`` decides a module's layer, so a robot's subfolder can sit
above its robot: the hopper's own commands (``robots.hopper.commands``) and Cho et al.'s
agents (``robots.hopper.agents``) sit at the layer of what they plug into, and generic code
reaches them only through the robot's registry entry (its ``Robot`` names them by string)."""

import ast
from pathlib import Path

import cpg_actor

PACKAGE = Path(cpg_actor.__file__).parent
# module or folder of cpg_actor (its dotted name; the longest that names a module counts)
# -> its layer (0: shared utilities)
LAYERS = {
    "errors": 0, "files": 0, "machine": 0, "device": 0, "host_reads": 0,
    "limits": 0, "safe_yaml": 0, "inputs": 0,  # bounds, bounded YAML, reading study inputs
    "cpg": 1,  # knows no robot
    "robots.spec": 2, "robots.plugin": 2, "robots.common": 2,  # what robots share; no robot
    "tasks": 3,  # a task (command, reward, observation); knows no robot
    "terrain": 3,  # the ground a task runs on (height maps, curriculum); knows no robot
    "robots.common.quadruped": 4,  # the quadrupeds' machinery, on the velocity task
    "robots.anymal_leg": 4,  # the leg the hopper and ANYmal B are built of
    "robots": 5,  # a folder per robot (hopper, anymal, go1)
    # the one place the robots are named; the package registers their Gymnasium ids
    "robots.registry": 6, "robots.assets": 6, "robots.__main__": 6, "__init__": 6,
    "agents": 7, "ppo": 7,
    "config": 8,
    "training": 9,
    "deploy": 10,
    "experiments": 11, "plots": 11, "robustness": 11,
    "cli": 12, "commands": 12,
    "robots.hopper.commands": 12,  # the hopper's own commands (Robot.commands)
    "robots.hopper.agents": 7,  # Cho et al.'s agents, which the hopper brings (Robot.agents)
}  # fmt: skip
# the imports allowed upward: the package's re-export of load_policy, imported on first use
# (cpg_actor.load_policy; `import cpg_actor` does not import it)
FACADE = {("", "deploy")}


def layer_of(name: str) -> int:
    parts = (name or "__init__").split(".")
    for end in range(len(parts), 0, -1):
        if ".".join(parts[:end]) in LAYERS:
            return LAYERS[".".join(parts[:end])]
    raise AssertionError(f"cpg_actor.{parts[0]} has no layer: add it to LAYERS")


def imported(tree: ast.AST) -> set[str]:
    """Every ``cpg_actor.X`` imported anywhere in a module (in functions too), as ``X``."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("cpg_actor"):
            if node.module == "cpg_actor":
                names |= {a.name for a in node.names if a.name != "__version__"}
            else:
                names.add(node.module.removeprefix("cpg_actor").lstrip("."))
        elif isinstance(node, ast.Import):
            names |= {a.name.removeprefix("cpg_actor.") for a in node.names
                      if a.name.startswith("cpg_actor.")}  # fmt: skip
    return names


def test_no_module_imports_from_a_layer_above_its_own():
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        module = module.removesuffix(".__init__").removesuffix("__init__")
        for name in imported(ast.parse(path.read_text(encoding="utf-8"))):
            if layer_of(name) > layer_of(module) and (module, name) not in FACADE:
                upward.append(f"cpg_actor.{module} imports cpg_actor.{name}")
    assert upward == [], "\n".join(upward)


def folder_of(name: str) -> str:
    """The folder a module belongs to, for the cycle check: its entry of ``LAYERS`` (the
    longest that names it), a robot's own folder under ``robots``."""
    parts = (name or "__init__").split(".")
    key = next(".".join(parts[:end]) for end in range(len(parts), 0, -1)
               if ".".join(parts[:end]) in LAYERS)  # fmt: skip
    return f"robots.{parts[1]}" if key == "robots" and len(parts) > 1 else key


def import_cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The cycles of the directed graph ``edges`` (node -> the nodes it imports), each once,
    as the list of its nodes from the smallest."""
    cycles: set[tuple[str, ...]] = set()

    def walk(path: list[str]) -> None:
        for nxt in sorted(edges.get(path[-1], ())):
            if nxt == path[0]:
                cycles.add(tuple(path))
            elif nxt not in path and nxt > path[0]:  # each cycle found from its smallest node
                walk([*path, nxt])

    for node in sorted(edges):
        walk([node])
    return sorted(list(cycle) for cycle in cycles)


def folder_imports() -> dict[str, set[str]]:
    """Folder -> the other folders its modules import."""
    edges: dict[str, set[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        module = module.removesuffix(".__init__").removesuffix("__init__")
        source = folder_of(module)
        for name in imported(ast.parse(path.read_text(encoding="utf-8"))):
            if folder_of(name) != source:
                edges.setdefault(source, set()).add(folder_of(name))
    return edges


def test_no_two_folders_import_each_other():
    """Folders of one layer (agents and ppo, experiments and robustness, the robots) import
    each other one way only; the check finds a cycle through any number of folders."""
    assert import_cycles(folder_imports()) == []
    assert import_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_library_never_imports_the_command_line():
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if module.split(".")[0] in ("cli", "commands"):
            continue
        names = imported(ast.parse(path.read_text(encoding="utf-8")))
        assert not {n for n in names if n.split(".")[0] in ("cli", "commands")}, module


def test_the_agents_never_look_a_robot_up():
    """A run resolves its robot once, where it is built (``TrainConfig.robot``), and hands the
    entry down: the agents and PPO never import the registry to find one again."""
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if module.split(".")[0] in ("agents", "ppo"):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            if module == "agents.registry":  # the robots' table, for the agents they bring
                assert registry_names(tree) <= {"ROBOTS"}, module
            else:
                assert "robots.registry" not in imported(tree), module


def registry_names(tree: ast.AST) -> set[str]:
    """The names a module imports from ``cpg_actor.robots.registry``."""
    return {alias.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
            and node.module == "cpg_actor.robots.registry" for alias in node.names}  # fmt: skip


def robot_folders() -> set[str]:
    """The robots' folders under ``robots`` (those with a ``plugin.py``)."""
    return {path.parent.name for path in (PACKAGE / "robots").glob("*/plugin.py")}


def outside_imports() -> dict[str, str]:
    """Module outside ``robots/<name>/`` -> the robot ``<name>`` it imports (the registry,
    the one place the robots are named, aside)."""
    robots, found = robot_folders(), {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        module = module.removesuffix(".__init__").removesuffix("__init__")
        own = module.split(".")[1] if module.startswith("robots.") else ""
        if module == "robots.registry" or own in robots:
            continue
        for name in imported(ast.parse(path.read_text(encoding="utf-8"))):
            parts = name.split(".")
            if parts[0] == "robots" and len(parts) > 1 and parts[1] in robots:
                found[module] = parts[1]
    return found


def test_nothing_outside_a_robots_folder_imports_it():
    """A robot is its folder plus its registry line: generic code gets what it needs from the
    robot's registry entry, never by importing the robot's modules."""
    assert outside_imports() == {}
