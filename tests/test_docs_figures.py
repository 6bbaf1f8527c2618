"""The documentation's pictures are made by the project's own commands when the docs are built
(``docs/figures.py``, issue 28, item 10), never committed; every picture a page shows is one the
build makes, and every one the build makes is shown. The README shows one of them."""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _figures_module():
    spec = importlib.util.spec_from_file_location("docs_figures", DOCS / "figures.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _shown() -> dict[str, list[str]]:
    """Picture name in _generated -> the pages that show it."""
    shown: dict[str, list[str]] = {}
    for page in DOCS.rglob("*.md"):
        for target in re.findall(r"```\{figure\}\s+(\S+)", page.read_text()):
            path = (page.parent / target).resolve()
            assert path.parent == (DOCS / "_generated").resolve(), (page, target)
            shown.setdefault(path.name, []).append(page.relative_to(DOCS).as_posix())
    return shown


def test_every_picture_shown_is_made_and_every_one_made_is_shown():
    figures = _figures_module()
    made = set(figures.FIGURES) | set(figures.SCREENSHOTS)
    shown = _shown()
    assert set(shown) == made
    for pages in ("getting-started.md", "howto/sweep.md", "howto/place.md", "howto/motion.md", "howto/team.md",
                  "howto/view-export.md", "howto/floor.md"):  # fmt: skip
        assert any(pages in p for p in shown.values()), pages
    for name, (arguments, produced) in figures.FIGURES.items():
        assert Path(produced).suffix == Path(name).suffix == ".png"
        assert arguments[0] in {"paper", "sweep", "place", "site", "carry", "team"}


def test_the_readme_shows_pictures_the_build_makes():
    """The README's pictures are the docs build's (it commits none of its own)."""
    figures = _figures_module()
    made = set(figures.FIGURES) | set(figures.SCREENSHOTS)
    shown = re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", (ROOT / "README.md").read_text())
    assert shown, "the README shows a first result"
    for target in shown:
        path = (ROOT / target).resolve()
        assert path.parent == (DOCS / "_generated").resolve() and path.name in made, target


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_the_generated_pictures_are_never_committed():
    tracked = subprocess.run(["git", "ls-files", "docs/_generated"], cwd=ROOT, capture_output=True, text=True)
    if tracked.returncode != 0:
        pytest.skip("not a git checkout")
    assert tracked.stdout == ""
    ignored = subprocess.run(["git", "check-ignore", "-q", "docs/_generated/sweep.png"], cwd=ROOT)
    assert ignored.returncode == 0
