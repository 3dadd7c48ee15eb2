"""The tree's docs/ stays small: under a size budget and free of run files. Runs, checkpoints,
traces and archives go to the git-ignored results/ (docs/results/README.md); the raw runs of
the studies in docs/results/ are in git history."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from cpg_actor.files import MARKER
from cpg_actor_studies.reproduction.execute import MARKER as REPRODUCE_RUN

ROOT = Path(__file__).resolve().parents[1]
BUDGET_MB = 15
RUN_FILES = (MARKER, REPRODUCE_RUN, "metrics.jsonl")  # the markers and log of a run directory
RUN_SUFFIXES = (".pt", ".npz", ".tar.gz", ".tgz", ".zip")  # checkpoints, traces, archives


def _git(root: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)


def docs_files(root: Path) -> list[Path]:
    """The files under root/docs: the tracked ones where root is a git checkout's top (what a
    clone carries), else every file there (an unpacked source archive)."""
    if shutil.which("git"):
        top = _git(root, "rev-parse", "--show-toplevel")
        if top.returncode == 0 and Path(top.stdout.strip()).resolve() == root.resolve():
            listed = _git(root, "ls-files", "-z", "--", "docs").stdout.split("\0")
            files = [root / name for name in listed if name]
            return [f for f in files if f.is_symlink() or f.exists()]  # not a deletion to commit
    return [Path(d) / name for d, _, names in os.walk(root / "docs") for name in names]


def run_files(files: list[Path]) -> list[Path]:
    return [f for f in files if f.name in RUN_FILES or f.name.endswith(RUN_SUFFIXES)]


def size_mb(files: list[Path]) -> float:
    return sum(f.lstat().st_size for f in files) / 1e6


def test_docs_stay_under_their_budget():
    files = docs_files(ROOT)
    largest = sorted(files, key=lambda f: f.lstat().st_size, reverse=True)[:5]
    named = ", ".join(f"{f.relative_to(ROOT)} ({size_mb([f]):.1f} MB)" for f in largest)
    assert size_mb(files) <= BUDGET_MB, (
        f"docs/ holds {size_mb(files):.1f} MB, over its {BUDGET_MB} MB budget (largest: {named}); "
        "keep run folders, traces, videos and archives in the git-ignored results/"
    )


def test_docs_hold_no_run_files():
    found = [str(f.relative_to(ROOT)) for f in run_files(docs_files(ROOT))]
    assert found == [], (
        f"run files under docs/: {found}; a study keeps its README, summary.json and small "
        "figures there, its runs go to the git-ignored results/"
    )


def test_a_run_marker_and_the_size_are_seen_outside_git(tmp_path):
    run = tmp_path / "docs" / "results" / "study" / "runs"
    run.mkdir(parents=True)
    (run / MARKER).write_text("{}")
    (run / "seed0.tar.gz").write_bytes(b"x" * 1000)
    (tmp_path / "docs" / "README.md").write_text("# notes\n")
    files = docs_files(tmp_path)
    assert sorted(f.name for f in run_files(files)) == sorted([MARKER, "seed0.tar.gz"])
    assert size_mb(files) == pytest.approx((2 + 1000 + 8) / 1e6, rel=1e-9)


@pytest.mark.skipif(shutil.which("git") is None, reason="needs the git command")
def test_in_a_checkout_only_tracked_files_count(tmp_path):
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "page.md").write_text("tracked\n")
    (docs / "scratch.bin").write_bytes(b"x" * 5000)  # a user's file, not in git
    subprocess.run(["git", "init", "-q", str(tmp_path)], check=True)
    subprocess.run(["git", "-C", str(tmp_path), "add", "docs/page.md"], check=True)
    assert [f.name for f in docs_files(tmp_path)] == ["page.md"]


LARGE_MB = 1.0  # a tracked file over this is run data, but for the figures listed
LARGE_ALLOWED = {"docs/img/anymal.gif"}  # the README's picture


def tracked_files(root: Path) -> list[Path] | None:
    """Every file git tracks in the checkout at ``root``; None outside a checkout."""
    if not shutil.which("git"):
        return None
    top = _git(root, "rev-parse", "--show-toplevel")
    if top.returncode != 0 or Path(top.stdout.strip()).resolve() != root.resolve():
        return None
    files = [root / n for n in _git(root, "ls-files", "-z").stdout.split("\0") if n]
    return [f for f in files if f.is_file() and not f.is_symlink()]


def test_no_run_data_is_tracked_anywhere():
    """No run archive, checkpoint or trace anywhere in the tree git tracks, and
    no file over 1 MB but the README's figures: every clone carries what is committed."""
    files = tracked_files(ROOT)
    if files is None:
        pytest.skip("not a git checkout: nothing is tracked")
    archives = [str(f.relative_to(ROOT)) for f in run_files(files) if f.name != "metrics.jsonl"]
    large = [
        f"{f.relative_to(ROOT)} ({size_mb([f]):.1f} MB)"
        for f in files
        if size_mb([f]) > LARGE_MB and str(f.relative_to(ROOT)) not in LARGE_ALLOWED
    ]
    assert archives == [] and large == [], (archives, large)
