"""The user's pages hold together: README.md at most 250 lines, every markdown link in README, CHANGELOG and docs/
resolves (anchors included), docs/index.md lists every page of docs/, and no code cites a file outside the
repository (the design notes live in docs/architecture.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]


def _anchors(page: Path) -> set[str]:
    """GitHub's anchors of a page's headings."""
    return {
        re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-")
        for h in re.findall(r"^#+ (.*)$", page.read_text(), re.M)
    }


def _broken_links(page: Path) -> list[str]:
    broken = []
    for match in re.finditer(r"\]\(([^)\s]+)\)", page.read_text()):
        target = match.group(1)
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        if not resolved.exists():
            broken.append(target)
        elif anchor and resolved.suffix == ".md" and anchor not in _anchors(resolved):
            broken.append(target)
    return broken


def test_readme_is_a_page_not_a_notebook() -> None:
    assert len((ROOT / "README.md").read_text().splitlines()) <= 250


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_resolves(page: Path) -> None:
    assert page.exists()
    assert not _broken_links(page)


def test_the_link_check_sees_a_broken_link(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("# Title\n[ok](page.md) [anchor](#title) [gone](missing.md) [bad anchor](#nope)\n")
    assert _broken_links(page) == ["missing.md", "#nope"]


def test_docs_index_lists_every_page() -> None:
    index = (ROOT / "docs" / "index.md").read_text()
    pages = sorted((ROOT / "docs").glob("*.md"))
    missing = [p.name for p in pages if p.name != "index.md" and f"({p.name})" not in index]
    assert not missing


def test_no_code_cites_a_file_outside_the_repository() -> None:
    citing = [
        str(p.relative_to(ROOT))
        for p in sorted((ROOT / "redundancy_gym").rglob("*.py"))
        if "DESIGN.md" in p.read_text()
    ]
    assert not citing
