"""The one YAML reader of the project: every YAML file or value it reads (a config file, a
run's config.yaml, ``--set KEY=VALUE``, a gait file, a results directory's settings) goes
through :func:`parse_yaml` or :func:`read_yaml`.

It is YAML's safe loader (no tags that build objects) with bounds, so that a hostile file
is refused in one line before it can hang or exhaust the memory: the text's size
(:data:`~cpg_actor.limits.MAX_YAML_BYTES`), the nodes it holds with every alias expanded (a
"billion laughs" file, a few lines of aliases of aliases, expands into billions:
:data:`~cpg_actor.limits.MAX_YAML_NODES`), how deep it nests (the composer recurses:
:data:`~cpg_actor.limits.MAX_YAML_DEPTH`), and a key given twice in one mapping (PyYAML would
keep the last silently).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from cpg_actor.limits import MAX_YAML_BYTES, MAX_YAML_DEPTH, MAX_YAML_NODES, brief, shorten


class YAMLRefused(ValueError):
    """YAML beyond the reader's bounds (its text, its expanded nodes, its depth), or an alias
    inside the node it names (a structure that holds itself)."""


class BoundedLoader(yaml.SafeLoader):
    """The safe loader, counting each node as it is composed: its size with every alias
    expanded (memoised per node, so counting costs one pass over the text's nodes) and its
    depth; a node beyond :data:`MAX_YAML_NODES` or :data:`MAX_YAML_DEPTH`, or an alias inside
    the node it names, stops the load before anything is constructed. A key twice in one
    mapping is refused."""

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._depth = 0
        self._sizes: dict[int, int] = {}  # id(node) -> its nodes, aliases expanded

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise YAMLRefused(
                    f"nests deeper than {MAX_YAML_DEPTH} levels (at line "
                    f"{self.peek_event().start_mark.line + 1})"
                )
            alias = self.check_event(yaml.AliasEvent)
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        key = id(node)
        if alias and key not in self._sizes:  # the node it names is still being composed
            raise YAMLRefused(
                f"has an alias inside the node it names (at line {node.start_mark.line + 1}): "
                "a structure holding itself"
            )
        if key not in self._sizes:  # an alias's node was counted where it was anchored
            if isinstance(node, yaml.SequenceNode):
                children = node.value
            elif isinstance(node, yaml.MappingNode):
                children = [item for pair in node.value for item in pair]
            else:
                children = []
            size = 1 + sum(self._sizes.get(id(child), 1) for child in children)
            if size > MAX_YAML_NODES:
                raise YAMLRefused(
                    f"holds more than {MAX_YAML_NODES:,} values with its aliases expanded "
                    f"(at line {node.start_mark.line + 1})"
                )
            self._sizes[key] = size
        return node

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                duplicate = key in seen
                seen.add(key)
            except TypeError:  # an unhashable key: the safe loader's own error names it
                break
            if duplicate:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {brief(key)} (give each key once)",
                    key_node.start_mark,
                )  # fmt: skip
        return super().construct_mapping(node, deep)


def parse_yaml(text: str) -> Any:
    """The value of the YAML ``text`` (one document). ``yaml.YAMLError`` where it is not
    valid YAML; :class:`YAMLRefused` (a ValueError, one line) beyond the bounds."""
    if len(text) > MAX_YAML_BYTES:
        raise YAMLRefused(f"has {len(text):,} characters, above the {MAX_YAML_BYTES:,} accepted")
    loader = BoundedLoader(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def read_yaml(path: Path, what: str = "") -> Any:
    """The value of the YAML file ``path``; ValueError in one line where it is too large, not
    UTF-8 text or not valid YAML (the problem and where). ``what``: how the message names it
    (default: the path)."""
    path = Path(path)
    name = what or str(path)
    if path.is_file() and path.stat().st_size > MAX_YAML_BYTES:  # refused before reading it
        raise ValueError(
            f"{name} has {path.stat().st_size:,} bytes, above the {MAX_YAML_BYTES:,} accepted "
            "for a YAML file"
        )
    try:
        return parse_yaml(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as error:  # a binary file: a checkpoint, an image, ...
        raise ValueError(
            f"{name} is not a YAML text file (byte {error.start} is not UTF-8 text)"
        ) from None
    except YAMLRefused as error:
        raise ValueError(f"{name} is refused: the YAML {error}") from None
    except yaml.YAMLError as error:
        raise ValueError(f"{name} is not valid YAML{yaml_error_text(error)}") from None
    except ValueError as error:  # an integer of too many digits, ...
        raise ValueError(f"{name} is not valid YAML: {shorten(str(error))}") from None


def yaml_error_text(error: yaml.YAMLError) -> str:
    """``" at line L, column C: PROBLEM"`` for a YAML error, in one bounded line."""
    mark = getattr(error, "problem_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
    problem = getattr(error, "problem", None) or str(error)
    return f"{where}: {shorten(' '.join(str(problem).split()))}"
