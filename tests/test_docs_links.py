"""Every relative Markdown link in README.md, docs/ and benchmarks/ points at a file or folder
that exists. Links into the git-ignored outputs at the repository's top (results/, runs/) and
links to web pages are not checked; neither are anchors (only the file before the `#`)."""

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
IGNORED_OUTPUTS = ("results", "runs")  # top-level folders a user's commands write (.gitignore)

FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
INLINE_CODE = re.compile(r"(`+)(?!`).*?(?<!`)\1(?!`)", re.S)
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE_LINK = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s|$)", re.M)


def markdown_files():
    files = [ROOT / "README.md", ROOT / "CHANGELOG.md", ROOT / "benchmarks" / "README.md"]
    files += sorted((ROOT / "docs").rglob("*.md"))
    files += sorted((ROOT / "benchmarks" / "results").rglob("*.md"))
    return [f for f in files if f.is_file()]


def relative_targets(text):
    """The link targets of a Markdown text that are paths (no scheme, not a bare anchor)."""
    text = INLINE_CODE.sub("", FENCE.sub("", text))
    targets = INLINE_LINK.findall(text) + REFERENCE_LINK.findall(text)
    for target in targets:
        if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith("#"):
            continue  # http:, https:, mailto:, an anchor in the same page
        yield target


def broken_links(path):
    broken = []
    for target in relative_targets(path.read_text(encoding="utf-8")):
        file_part = target.split("#", 1)[0].split("?", 1)[0]
        if not file_part:
            continue
        resolved = (path.parent / file_part).resolve()
        try:
            top = resolved.relative_to(ROOT).parts[0]
        except (ValueError, IndexError):
            broken.append(f"{target} (outside the repository)")
            continue
        if top in IGNORED_OUTPUTS:
            continue
        if not resolved.exists():
            broken.append(target)
    return broken


def _param(path):
    return pytest.param(path, id=path.relative_to(ROOT).as_posix())


@pytest.mark.parametrize("path", [_param(p) for p in markdown_files()])
def test_relative_links_resolve(path):
    assert broken_links(path) == [], f"{path.relative_to(ROOT)}: broken relative links"


def test_the_link_finder_sees_links_and_skips_code():
    text = (
        "[a](docs/x.md) ![b](fig.png#top) [c](https://example.org) [d](#anchor)\n"
        "`[e](not/a/link.md)`\n```\n[f](also/not.md)\n```\n[g]: ref/target.md\n"
    )
    assert list(relative_targets(text)) == ["docs/x.md", "fig.png#top", "ref/target.md"]


def test_a_missing_target_is_reported(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "docs").mkdir()
    page = tmp_path / "docs" / "page.md"
    (tmp_path / "docs" / "there.md").write_text("")
    page.write_text("[ok](there.md) [gone](gone.md) [out](../results/run/report.md)")
    assert broken_links(page) == ["gone.md"]
