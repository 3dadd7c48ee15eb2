"""The package's layers: no module imports from a layer above its own (the CLI above the
robustness suite, above deployment and the evaluation's metrics, above training, above the
configuration, above the agents and PPO, above the robots' registry, above the robots, above
their tasks and shared machinery (and the parts they share), above the CPG; small shared
utilities at the bottom),
and the folders of one layer import each other one way only (no cycle).

The longest dotted prefix in ``LAYERS`` decides a module's layer, so a robot's subfolder can sit
above its robot: the hopper's own commands (``robots.hopper.commands``) and Cho et al.'s
agents (``robots.hopper.agents``) sit at the layer of what they plug into, and generic code
reaches them only through the robot's registry entry (its ``Robot`` names them by string).

The studies (``cpg_actor_studies``, the analyses of ``docs/results``) sit above the library: it
never imports them, and they import its public API (``cpg_actor.api``, ``docs/api.md``); each
other library module they still import is named in ``INTERNAL_USES`` with its count. The
library's function-level and relative imports are counted and may not grow."""

import ast
from pathlib import Path

import cpg_actor
from cpg_actor import api

PACKAGE = Path(cpg_actor.__file__).parent
# module or folder of cpg_actor (its dotted name; the longest that names a module counts)
# -> its layer (0: shared utilities)
LAYERS = {
    "errors": 0, "files": 0, "machine": 0, "device": 0, "host_reads": 0,
    "limits": 0, "safe_yaml": 0, "inputs": 0,  # bounds, bounded YAML, reading study inputs
    "statistics": 0,  # intervals, tests and verdicts over seeds (numpy, scipy)
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
    "deploy": 10, "metrics": 10,  # what an evaluation's traces show
    "plots": 11, "robustness": 11,
    "cli": 12, "commands": 12, "api": 12,  # the public API names every layer
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
    """Folders of one layer (agents and ppo, plots and robustness, the robots) import
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


# -- the studies above the library, through its public API ---------------------------------------
ROOT = PACKAGE.parents[1]
STUDIES = [ROOT / "src" / "cpg_actor_studies", ROOT / "docs" / "results"]
# the public API: cpg_actor.api and the namespaces it declares (every public name in them)
PUBLIC = {"cpg_actor.api", *api.MODULES.values()}
# internal module -> how many study files import it: the coupling left, which may only go down
# (lower a number when an import goes; name a module here only to record a new one, and say why)
INTERNAL_USES = {
    "cpg_actor.files": 6,  # the output folders' safety: markers, clearing, links refused
    "cpg_actor.limits": 6,  # bounded arguments (check_int, MAX_*) and brief messages
    "cpg_actor.machine": 3,  # the machine and commit a run was made on, thread shares
    "cpg_actor.safe_yaml": 2,  # bounded YAML (reproduce.yaml)
    "cpg_actor.robustness.protocol": 2,  # the suite's grid, read by two analyses
    "cpg_actor.robustness.summary": 2,  # the suite's verdicts, judged again (rejudge)
    "cpg_actor.training.checkpoint": 1,  # atomic_save (the sitting's archives)
    "cpg_actor.training.run_lock": 1,  # a reproduction's run is locked as train locks it
    "cpg_actor.agents.start_gait": 1,  # the start gait's search steps, in a run's budget
    "cpg_actor.agents.open_loop_es": 1,  # the search's generations, in a run's budget
    # the truncated-gradient study replays PPO's loss on a rollout: PPO's own parts
    "cpg_actor.agents.base": 1,
    "cpg_actor.ppo.algorithm": 1,
    "cpg_actor.ppo.normalizer": 1,
    "cpg_actor.ppo.storage": 1,
    "cpg_actor.robots.common.torch_env": 1,
}


def study_files() -> list[Path]:
    return sorted(path for root in STUDIES for path in root.rglob("*.py"))


def is_submodule(module: str, name: str) -> bool:
    folder = PACKAGE.joinpath(*module.split(".")[1:], name)
    return folder.with_suffix(".py").is_file() or (folder / "__init__.py").is_file()


def library_imports(tree: ast.AST) -> list[tuple[str, list[str]]]:
    """Every ``cpg_actor`` module a file imports, anywhere in it, with the names imported from
    it (``from cpg_actor import statistics``: the module ``cpg_actor.statistics``)."""
    found = []
    for node in ast.walk(tree):
        module = (node.module or "") if isinstance(node, ast.ImportFrom) and not node.level else ""
        if module == "cpg_actor" or module.startswith("cpg_actor."):
            names = [alias.name for alias in node.names]
            found += [(f"{module}.{name}", []) for name in names if is_submodule(module, name)]
            names = [name for name in names if not is_submodule(module, name)]
            found += [(module, names)] if names else []
        elif isinstance(node, ast.Import):
            found += [(a.name, []) for a in node.names
                      if a.name == "cpg_actor" or a.name.startswith("cpg_actor.")]  # fmt: skip
    return found


def internal_uses() -> dict[str, int]:
    """Internal module -> the study files that import it."""
    uses: dict[str, set[Path]] = {}
    for path in study_files():
        for module, _ in library_imports(ast.parse(path.read_text(encoding="utf-8"))):
            if module not in PUBLIC:
                uses.setdefault(module, set()).add(path)
    return {module: len(paths) for module, paths in uses.items()}


def test_the_library_never_imports_the_studies():
    """The studies sit above the library: no library module imports them (the command line
    finds their commands by name, :data:`cpg_actor.cli.PLUGINS`, when they are installed)."""
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            modules = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module or ""] if isinstance(node, ast.ImportFrom) else [])  # fmt: skip
            assert not [m for m in modules if m.split(".")[0] == "cpg_actor_studies"], path


def test_the_studies_use_the_public_api_and_name_what_else_they_use():
    """A study (``cpg_actor_studies``, ``docs/results``) imports ``cpg_actor.api`` and the
    namespaces it declares; names from ``cpg_actor.api`` are in its ``__all__``; any other
    library module is one of :data:`INTERNAL_USES`, by exactly as many files."""
    for path in study_files():
        for module, names in library_imports(ast.parse(path.read_text(encoding="utf-8"))):
            if module == "cpg_actor.api":
                assert set(names) <= set(api.__all__), (path, set(names) - set(api.__all__))
    uses = internal_uses()
    assert uses == INTERNAL_USES, (
        "update INTERNAL_USES: a count that fell is lowered, a new module is named with why; "
        f"now {dict(sorted(uses.items()))}"
    )


def test_every_name_of_the_api_resolves_in_the_library_and_is_documented():
    doc = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    for name in api.__all__:
        value = getattr(api, name)
        module = getattr(value, "__name__", None) if name in api.MODULES else api.EXPORTS[name]
        assert module.split(".")[0] == "cpg_actor", name
        assert f"`{name}`" in doc, f"docs/api.md does not name {name}"


# function-level imports of the library's own modules (each hides a dependency from a reader of
# the module's top) and relative imports: at most these (210 and 1 before the studies left)
FUNCTION_LEVEL_IMPORTS = 141
RELATIVE_IMPORTS = 0


def import_counts() -> tuple[int, int]:
    """(imports of ``cpg_actor`` modules inside a function, relative imports) in the library."""
    inside, relative = set(), 0
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        relative += sum(isinstance(n, ast.ImportFrom) and n.level > 0 for n in ast.walk(tree))
        for function in ast.walk(tree):
            if isinstance(function, ast.FunctionDef | ast.AsyncFunctionDef):
                inside |= {(path, node.lineno) for node in ast.walk(function)
                           if isinstance(node, ast.Import | ast.ImportFrom)
                           and library_imports(node)}  # fmt: skip
    return len(inside), relative


def test_function_level_and_relative_imports_do_not_grow():
    inside, relative = import_counts()
    assert inside <= FUNCTION_LEVEL_IMPORTS, f"{inside} function-level imports"
    assert relative <= RELATIVE_IMPORTS, f"{relative} relative imports"
