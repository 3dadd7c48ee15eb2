"""The seed register (docs/results/SEEDS.md) lists every results folder with a link, and its
fresh report seeds have not been used by any folder or benchmark."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"
REGISTER = RESULTS / "SEEDS.md"
FRESH = range(10, 35)


def test_the_register_lists_every_results_folder():
    text = REGISTER.read_text(encoding="utf-8")
    folders = sorted(p.name for p in RESULTS.iterdir() if p.is_dir())
    missing = [name for name in folders if f"]({name}/" not in text]
    assert folders and not missing, f"SEEDS.md has no row linking to {missing}"


def fresh_folders(text: str) -> set[Path]:
    """The folders whose register row names their kind "fresh report"."""
    rows = re.finditer(r"^\| \[`([^`]+)/`\]\([^)]*\) \|[^|]*\| fresh report", text, re.M)
    return {RESULTS / row.group(1) for row in rows}


def test_the_fresh_report_seeds_are_unused():
    """No command in docs/ or benchmarks/ trains on the fresh seeds (`--seed 1X`, or
    `--first-seed 1X`) outside the folders the register lists as their users (each with a
    protocol committed before its runs): the others were never looked at."""
    pattern = re.compile(r"--(?:first-)?seed[ =](\d+)\b")
    allowed = fresh_folders(REGISTER.read_text(encoding="utf-8"))
    assert all((folder / "PROTOCOL.md").is_file() for folder in allowed), allowed
    used = []
    for path in [*(ROOT / "docs").rglob("*.md"), *(ROOT / "benchmarks").rglob("*.md")]:
        if any(folder in path.parents for folder in allowed):
            continue
        for match in pattern.finditer(path.read_text(encoding="utf-8")):
            if int(match.group(1)) in FRESH:
                used.append(f"{path.relative_to(ROOT)}: {match.group(0)}")
    assert not used, used
    assert "**10-19**" in REGISTER.read_text(encoding="utf-8")
