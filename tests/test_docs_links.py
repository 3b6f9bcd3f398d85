"""The docs hold together: every relative markdown link in README.md and docs/**/*.md points at
a file that exists (and, into a markdown page, at a heading that exists), and the README stays a
first page (at most 120 lines, both commands in its first 40 lines)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs").rglob("*.md"))]

# [text](target) and ![alt](target), with an optional "title"; fenced code blocks and inline
# code are removed first, so that link-like text inside code is not taken for a link
LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
INLINE_CODE = re.compile(r"`[^`\n]*`")
SCHEME = re.compile(r"^[a-z][a-z0-9+.-]*:", re.I)

SETUP = "python3 -m venv .venv && .venv/bin/pip install -e '.[dev]'"
MAIN_COMMAND = f"{SETUP} && .venv/bin/vgs reproduce --profile quick --out runs/quick"
TEST_COMMAND = f"{SETUP} && .venv/bin/python -m pytest -q"


def _prose(text: str) -> str:
    return INLINE_CODE.sub("", FENCE.sub("", text))


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    seen: dict[str, int] = {}
    anchors = set()
    for line in FENCE.sub("", page.read_text()).splitlines():
        match = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if match:
            slug = _slug(match.group(1))
            count = seen.get(slug, 0)
            seen[slug] = count + 1
            anchors.add(slug if count == 0 else f"{slug}-{count}")
    return anchors


def _links(page: Path) -> list[str]:
    return [m.group(1) for m in LINK.finditer(_prose(page.read_text()))
            if not SCHEME.match(m.group(1))]


def test_pages_are_found() -> None:
    names = {p.relative_to(ROOT).as_posix() for p in PAGES}
    assert {"README.md", "docs/results.md", "docs/architecture.md"} <= names


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_resolve(page: Path) -> None:
    broken = []
    for target in _links(page):
        path, _, fragment = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        if not resolved.exists():
            broken.append(f"{target} (no such file)")
        elif fragment and resolved.suffix == ".md" and fragment not in _anchors(resolved):
            broken.append(f"{target} (no such heading)")
    assert not broken, f"{page.relative_to(ROOT)}: " + ", ".join(broken)


def test_every_docs_page_is_in_the_readme_index() -> None:
    linked = {(ROOT / t.partition("#")[0]).resolve() for t in _links(README)}
    missing = [p.name for p in sorted((ROOT / "docs").glob("*.md")) if p.resolve() not in linked]
    assert not missing, f"README.md does not link {missing}"


def test_readme_is_a_first_page() -> None:
    lines = README.read_text().splitlines()
    assert len(lines) <= 120, f"README.md has {len(lines)} lines (at most 120)"
    first_screen = "\n".join(lines[:40])
    assert MAIN_COMMAND in first_screen
    assert TEST_COMMAND in first_screen


def _table_lines(section: str) -> list[str]:
    return [line for line in section.splitlines() if line.startswith("|")]


def test_the_readme_headline_is_the_published_seeds_summary() -> None:
    """The README's headline table is, line for line, the summary of the seeds table it links
    (written by `vgs seeds`), so the headline cannot drift from the published result set."""
    headline = README.read_text().split("## Headline result")[1].split("\n## ")[0]
    linked = re.findall(r"\((docs/results/[^)]+/seeds\.md)\)", headline)
    assert len(linked) == 1, "the headline links one seeds table"
    seeds = (ROOT / linked[0]).read_text()
    summary = seeds.split("## Summary")[1].split("\n## ")[0]
    assert _table_lines(headline) == _table_lines(summary)


def test_the_docs_pages_stay_a_manual() -> None:
    """docs/*.md describe the system as it is, in at most 2,000 lines together (history goes
    to CHANGELOG.md)."""
    total = sum(len(p.read_text().splitlines()) for p in (ROOT / "docs").glob("*.md"))
    assert total <= 2000, f"docs/*.md hold {total} lines (at most 2000)"


def test_ci_runs_the_readme_test_command() -> None:
    """.ci/run runs exactly the README's test command."""
    ci = ROOT / ".ci" / "run"
    if not ci.exists():
        pytest.skip("no .ci/run in this checkout")
    assert TEST_COMMAND in ci.read_text()
