"""The Python example in docs/cpg.md runs as written."""

from __future__ import annotations

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[2] / "docs" / "cpg.md"


def test_docs_python_example_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) == 1, "docs/cpg.md should hold exactly one Python example"
    exec(compile(blocks[0], str(DOC), "exec"), {"__name__": "docs_example"})
    printed = capsys.readouterr().out
    assert "torch.Size([8]) torch.Size([4, 2])" in printed
    assert "tensor([2., 2.]" in printed
