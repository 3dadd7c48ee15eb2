"""The README's Python example runs as written and prints what it says."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) == 1, "the README should hold exactly one Python example"
    exec(compile(blocks[0], str(README), "exec"), {"__name__": "readme_example"})
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == "torch.Size([4, 2])"
    assert printed[1] == "(8,) (2,)"  # the hopper's observation and action


def test_load_policy_is_imported_where_the_readme_shows_it():
    import cpg_actor
    from cpg_actor.deploy import load_policy

    text = README.read_text(encoding="utf-8")
    assert "load_policy(" in text and "`from cpg_actor import load_policy`" in text
    assert text.index("`from cpg_actor import load_policy`") < text.index("load_policy(")
    assert cpg_actor.load_policy is load_policy  # what the README's import gives


def test_readme_is_a_first_page():
    """At most 170 lines, none over 400 characters: findings go to docs/results/."""
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 170
    assert [n for n, line in enumerate(lines, 1) if len(line) > 400] == []
