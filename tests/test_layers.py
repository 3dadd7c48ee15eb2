"""The package's layers: no module imports from a layer above its own (the CLI above the
experiments, above deployment, above training, above the configuration, above the agents
and PPO, above the robots' registry, above the robots, above their tasks and shared
machinery (and the parts they share), above the CPG; small shared utilities at the bottom)."""

import ast
from pathlib import Path

import cpg_actor

PACKAGE = Path(cpg_actor.__file__).parent
# module or folder of cpg_actor (its dotted name; the longest that names a module counts)
# -> its layer (0: shared utilities)
LAYERS = {
    "errors": 0, "files": 0, "machine": 0, "device": 0, "host_reads": 0,
    "cpg": 1,  # knows no robot
    "robots.spec": 2, "robots.plugin": 2, "robots.common": 2,  # what robots share; no robot
    "tasks": 3,  # a task (command, reward, observation); knows no robot
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


def test_the_library_never_imports_the_command_line():
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if module.split(".")[0] in ("cli", "commands"):
            continue
        names = imported(ast.parse(path.read_text(encoding="utf-8")))
        assert not {n for n in names if n.split(".")[0] in ("cli", "commands")}, module
