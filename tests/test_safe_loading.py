"""No pickle where a user's file can reach: every Python file of the repository (the library,
the benchmarks, the examples, the results folders' scripts, the tests) is read as a syntax
tree and may not unpickle, load YAML with a loader that builds objects, or load tensors or
arrays with pickling allowed."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("src", "benchmarks", "examples", "docs", "tests")

# module.attribute that read a pickle (or run code from a file) whatever their arguments
FORBIDDEN = {
    ("pickle", "load"), ("pickle", "loads"), ("pickle", "Unpickler"), ("pickle", "_Unpickler"),
    ("pickle", "_load"), ("pickle", "_loads"), ("_pickle", "load"), ("_pickle", "loads"),
    ("cloudpickle", "load"), ("cloudpickle", "loads"), ("dill", "load"), ("dill", "loads"),
    ("joblib", "load"), ("shelve", "open"), ("marshal", "load"), ("marshal", "loads"),
    ("pd", "read_pickle"), ("pandas", "read_pickle"),
    ("yaml", "unsafe_load"), ("yaml", "unsafe_load_all"), ("yaml", "full_load"),
    ("yaml", "full_load_all"), ("yaml", "Loader"), ("yaml", "UnsafeLoader"),
    ("yaml", "FullLoader"), ("yaml", "CLoader"), ("yaml", "CUnsafeLoader"),
    ("yaml", "CFullLoader"),
}  # fmt: skip
FORBIDDEN_NAMES = {"Unpickler", "_Unpickler", "UnsafeLoader", "FullLoader", "unsafe_load"}
SAFE_YAML_BASES = {"SafeLoader", "CSafeLoader", "BaseLoader", "CBaseLoader"}


def python_files() -> list[Path]:
    files = []
    for folder in FOLDERS:
        files += sorted(p for p in (ROOT / folder).rglob("*.py") if ".venv" not in p.parts)
    return files


def _dotted(node: ast.AST) -> tuple[str, str] | None:
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return node.value.id, node.attr
    return None


def _keyword(call: ast.Call, name: str) -> ast.AST | None:
    return next((k.value for k in call.keywords if k.arg == name), None)


def _is_constant(node: ast.AST | None, value: object) -> bool:
    return isinstance(node, ast.Constant) and node.value is value


def _safe_loader_classes(tree: ast.Module) -> set[str]:
    """Classes of the module that derive (through the module's own classes) from a YAML loader
    that builds no objects."""
    safe: set[str] = set()
    changed = True
    while changed:
        changed = False
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef) and node.name not in safe and node.bases:
                names = [
                    b.attr if isinstance(b, ast.Attribute) else getattr(b, "id", "")
                    for b in node.bases
                ]
                if all(n in SAFE_YAML_BASES or n in safe for n in names):
                    safe.add(node.name)
                    changed = True
    return safe


def problems(source: str, name: str) -> list[str]:
    """Each unsafe load in ``source``, as 'file:line: what'."""
    tree = ast.parse(source)
    safe_loaders = _safe_loader_classes(tree) | SAFE_YAML_BASES
    found = []

    def report(node: ast.AST, what: str) -> None:
        found.append(f"{name}:{node.lineno}: {what}")

    for node in ast.walk(tree):
        if _dotted(node) in FORBIDDEN:
            report(node, ".".join(_dotted(node)))
        elif isinstance(node, ast.Name) and node.id in FORBIDDEN_NAMES:
            report(node, node.id)
        elif isinstance(node, ast.ImportFrom) and node.module in {"pickle", "dill", "joblib"}:
            if any(a.name in {"load", "loads", "Unpickler", "_Unpickler"} for a in node.names):
                report(node, f"from {node.module} import a loader")
        if not isinstance(node, ast.Call):
            continue
        callee = _dotted(node.func)
        if callee in {("torch", "load")} and not _is_constant(_keyword(node, "weights_only"), True):
            report(node, "torch.load without weights_only=True")
        if callee in {("np", "load"), ("numpy", "load")}:
            if not _is_constant(_keyword(node, "allow_pickle"), False) and _keyword(
                node, "allow_pickle"
            ):
                report(node, "np.load with allow_pickle not False")
        if callee in {("yaml", "load"), ("yaml", "load_all")}:
            loader = _keyword(node, "Loader") or (node.args[1] if len(node.args) > 1 else None)
            loader_name = (
                loader.attr if isinstance(loader, ast.Attribute) else getattr(loader, "id", None)
            )
            if loader_name not in safe_loaders:
                report(node, f"yaml.load with loader {loader_name}")
    return found


def test_no_file_of_the_repository_unpickles_or_builds_objects_from_yaml():
    files = python_files()
    assert len(files) > 100  # the tree was found
    found = [
        line for path in files for line in problems(path.read_text(), str(path.relative_to(ROOT)))
    ]
    assert found == []


@pytest.mark.parametrize(
    "source",
    [
        "import pickle\npickle.load(f)",
        "import pickle\nclass U(pickle._Unpickler): pass",
        "from pickle import Unpickler",
        "import torch\ntorch.load(p)",
        "import torch\ntorch.load(p, weights_only=False)",
        "import numpy as np\nnp.load(p, allow_pickle=True)",
        "import yaml\nyaml.load(s, yaml.Loader)",
        "import yaml\nyaml.unsafe_load(s)",
        "import yaml\nyaml.load(s, Loader=yaml.FullLoader)",
        "import yaml\nclass L(yaml.UnsafeLoader): pass\nyaml.load(s, L)",
        "import yaml\nclass L(yaml.Loader): pass\nyaml.load(s, L)",
    ],
)
def test_the_scan_finds_each_unsafe_load(source):
    assert problems(source, "x.py")


@pytest.mark.parametrize(
    "source",
    [
        "import torch\ntorch.load(p, map_location='cpu', weights_only=True)",
        "import numpy as np\nnp.load(p)\nnp.load(p, allow_pickle=False)",
        "import yaml\nyaml.safe_load(s)",
        "import yaml\nclass L(yaml.SafeLoader): pass\nclass M(L): pass\nyaml.load(s, M)",
        "import pickle\npickle.dumps(x)\npickle.SHORT_BINUNICODE",
    ],
)
def test_the_scan_passes_safe_loads(source):
    assert problems(source, "x.py") == []
