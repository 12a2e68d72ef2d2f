"""The documentation cannot rot: the MkDocs site builds with `--strict` (every page in the nav,
every link and anchor between pages found), and every relative link in README.md points to a
file of the repository, each `docs/` link to a page the site builds."""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.cli_fixtures import ROOT

README = ROOT / "README.md"
DOCS = ROOT / "docs"
README_MAX_LINES = 200

# [text](target) outside code spans; images too. Targets with a scheme are external.
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def readme_links() -> list[str]:
    text = re.sub(r"```.*?```", "", README.read_text(encoding="utf-8"), flags=re.S)
    text = re.sub(r"`[^`\n]*`", "", text)
    return [t for t in LINK.findall(text) if not re.match(r"[a-z][a-z0-9+.-]*:", t)]


def link_problem(target: str) -> str | None:
    path = target.split("#", 1)[0]
    if not path:
        return None
    file = (ROOT / path).resolve()
    if not file.is_relative_to(ROOT):
        return f"{target} leaves the repository"
    if not file.exists():
        return f"{target} does not exist"
    if file.is_relative_to(DOCS) and file.suffix != ".md":
        return f"{target} is not a documentation page"
    return None


def test_the_readme_is_short_and_starts_with_the_two_commands() -> None:
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines"
    first_screen = "\n".join(lines[:30])
    assert "./dev smoke" in first_screen and "./dev test" in first_screen


def test_every_relative_link_in_the_readme_points_to_a_page() -> None:
    links = readme_links()
    assert any(t.startswith("docs/") for t in links), "README.md links no docs page"
    problems = [p for t in links if (p := link_problem(t)) is not None]
    assert problems == []


def test_the_link_check_catches_a_broken_link() -> None:
    assert link_problem("docs/no-such-page.md") == "docs/no-such-page.md does not exist"
    assert link_problem("../outside.md") == "../outside.md leaves the repository"
    assert link_problem("docs/index.md#anchor") is None


needs_mkdocs = pytest.mark.skipif(
    importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("material") is None,
    reason="mkdocs-material is not installed (pip install -e '.[dev]' installs it)")


def mkdocs_build(root: Path, site: Path) -> subprocess.CompletedProcess[str]:
    # Never --quiet: it hides the warnings that --strict counts, so a broken link would pass.
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict",
         "--config-file", str(root / "mkdocs.yml"), "--site-dir", str(site)],
        cwd=root, capture_output=True, text=True, timeout=300,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})


@needs_mkdocs
@pytest.mark.slow
def test_the_documentation_site_builds_strictly(tmp_path: Path) -> None:
    built = mkdocs_build(ROOT, tmp_path / "site")
    assert built.returncode == 0, built.stdout + built.stderr
    for page in DOCS.rglob("*.md"):
        relative = page.relative_to(DOCS).with_suffix("")
        folder = relative.parent if relative.name == "index" else relative
        assert (tmp_path / "site" / folder / "index.html").is_file(), f"{page} was not built"


@needs_mkdocs
@pytest.mark.slow
def test_the_strict_build_refuses_a_broken_link_and_a_page_outside_the_nav(
        tmp_path: Path) -> None:
    copy = tmp_path / "repo"
    shutil.copytree(DOCS, copy / "docs")
    shutil.copy(ROOT / "mkdocs.yml", copy / "mkdocs.yml")
    page = copy / "docs" / "getting-started.md"
    page.write_text(page.read_text(encoding="utf-8") + "\n[gone](no-such-page.md)\n")
    broken = mkdocs_build(copy, tmp_path / "site1")
    assert broken.returncode != 0 and "no-such-page.md" in broken.stdout + broken.stderr
    page.write_text((DOCS / "getting-started.md").read_text(encoding="utf-8"))
    (copy / "docs" / "orphan.md").write_text("# Orphan\n")
    orphan = mkdocs_build(copy, tmp_path / "site2")
    assert orphan.returncode != 0 and "orphan.md" in orphan.stdout + orphan.stderr
