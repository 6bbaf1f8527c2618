"""scripts/mutants.py, the mutation run kept on demand outside CI: its list stays in step with the
code. Every original snippet occurs exactly once in its file (an edit that moves or changes it
would silently retire the mutant), every mutant compiles, every test it names exists, and the
list keeps its breadth: at least 44 mutants, at least 6 in each area. No mutant is run here."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "mutants.py"


@pytest.fixture(scope="module")
def mutants():
    spec = importlib.util.spec_from_file_location("mutants_script", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules[spec.name]
    return module


def test_every_snippet_is_found_once_and_every_test_file_exists(mutants):
    assert mutants.problems() == []


def test_the_list_is_broad_enough(mutants):
    listed = mutants.MUTANTS
    assert len(listed) >= 44
    assert len({m.id for m in listed}) == len(listed)
    for area in mutants.AREAS:
        assert sum(m.area == area for m in listed) >= 6, area
    for m in listed:
        assert m.tests and all(t.startswith("tests/test_") for t in m.tests), m.id


def test_check_reports_a_snippet_that_is_gone(mutants, tmp_path):
    """--check's logic on a copy where one snippet was edited away: it names the mutant and the count."""
    first = mutants.MUTANTS[0]
    copy = tmp_path / first.file
    copy.parent.mkdir(parents=True)
    copy.write_text((mutants.ROOT / first.file).read_text().replace(first.original, "pass"))
    for test in first.tests:
        path = tmp_path / test.split("::")[0]
        path.parent.mkdir(parents=True, exist_ok=True)
        path.touch()
    found = mutants.problems((first,), root=tmp_path)
    assert found == [f"{first.id}: the original snippet occurs 0 times in {first.file}: {first.original!r}"]
