"""The package's layers: no module imports from a layer above its own (the CLI above the
experiments, above deployment, above training, above the configuration, above the agents
and PPO, above the envs, above the CPG; small shared utilities at the bottom)."""

import ast
from pathlib import Path

import cpg_actor

PACKAGE = Path(cpg_actor.__file__).parent
# top-level module or folder of cpg_actor -> its layer (0: shared utilities)
LAYERS = {
    "__init__": 0, "errors": 0, "files": 0, "machine": 0, "device": 0, "robot": 0,
    "registration": 0, "host_reads": 0, "plots": 0,
    "cpg": 1,
    "envs": 2,
    "agents": 3, "ppo": 3,
    "config": 4,
    "training": 5,
    "deploy": 6,
    "experiments": 7,
    "cli": 8, "commands": 8,
}  # fmt: skip
# imports that still go up, each with the change that removes it
KNOWN = {
    ("cpg.foot_space", "envs.robot"),  # ANYmal's leg kinematics: moves to the robot's folder
}


def layer_of(name: str) -> int:
    top = name.split(".")[0] if name else "__init__"
    assert top in LAYERS, f"cpg_actor.{top} has no layer: add it to LAYERS"
    return LAYERS[top]


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
            if layer_of(name) > layer_of(module) and (module, name) not in KNOWN:
                upward.append(f"cpg_actor.{module} imports cpg_actor.{name}")
    assert upward == [], "\n".join(upward)


def test_the_library_never_imports_the_command_line():
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if module.split(".")[0] in ("cli", "commands"):
            continue
        names = imported(ast.parse(path.read_text(encoding="utf-8")))
        assert not {n for n in names if n.split(".")[0] in ("cli", "commands")}, module
