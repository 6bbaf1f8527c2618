"""The notebooks in examples/ are committed without outputs (CI executes them separately with
``scripts/run_notebooks.py``), and the check that says so catches a notebook that has them."""

from __future__ import annotations

import importlib.util

import pytest

from conftest import ROOT

nbformat = pytest.importorskip("nbformat")
_spec = importlib.util.spec_from_file_location("run_notebooks", ROOT / "scripts" / "run_notebooks.py")
run_notebooks = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(run_notebooks)

NOTEBOOKS = sorted((ROOT / "examples").glob("*.ipynb"))


def test_the_four_example_notebooks_exist():
    assert {p.stem for p in NOTEBOOKS} >= {"case_study", "real_robot", "sweep", "viewer"}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_committed_without_outputs(path):
    book = nbformat.read(path, as_version=4)
    assert run_notebooks.dirty_cells(book) == []
    assert book.metadata["kernelspec"]["name"] == "python3"


def test_the_check_sees_outputs_and_strip_removes_them():
    book = nbformat.read(NOTEBOOKS[0], as_version=4)
    code = next(cell for cell in book.cells if cell.cell_type == "code")
    code.outputs = [nbformat.v4.new_output("stream", name="stdout", text="hello\n")]
    code.execution_count = 3
    problems = run_notebooks.dirty_cells(book)
    assert any("outputs" in p for p in problems) and any("execution count" in p for p in problems)
    assert run_notebooks.dirty_cells(run_notebooks.strip(book)) == []
