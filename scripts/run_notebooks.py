"""Execute the notebooks in examples/ headless, or check that none is committed with outputs.

    python scripts/run_notebooks.py                 # run every notebook; fails on the first error
    python scripts/run_notebooks.py examples/sweep.ipynb
    python scripts/run_notebooks.py --check-clean   # no outputs, execution counts or widget state
    python scripts/run_notebooks.py --strip         # remove them (before committing)

Notebooks run with the current interpreter's kernel, in a temporary directory (whatever they
write is thrown away), and are never written back: the repository keeps them without outputs.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def notebooks(paths: list[str]) -> list[Path]:
    found = [Path(p).resolve() for p in paths] if paths else sorted(EXAMPLES.glob("*.ipynb"))
    if not found:
        raise SystemExit(f"no notebooks in {EXAMPLES}")
    return found


def dirty_cells(book: nbformat.NotebookNode) -> list[str]:
    """What a committed notebook must not carry: outputs, execution counts, widget state."""
    problems = []
    for k, cell in enumerate(book.cells):
        if cell.cell_type != "code":
            continue
        if cell.get("outputs"):
            problems.append(f"cell {k} has outputs")
        if cell.get("execution_count") is not None:
            problems.append(f"cell {k} has an execution count")
    if "widgets" in book.metadata:
        problems.append("the notebook carries widget state")
    return problems


def strip(book: nbformat.NotebookNode) -> nbformat.NotebookNode:
    for cell in book.cells:
        if cell.cell_type == "code":
            cell.outputs = []
            cell.execution_count = None
        cell.metadata.pop("execution", None)
    book.metadata.pop("widgets", None)
    return book


def execute(path: Path, timeout: int) -> float:
    """Run every cell of the notebook at ``path`` in a fresh kernel; raise on the first error."""
    from nbclient import NotebookClient

    book = nbformat.read(path, as_version=4)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as work:
        client = NotebookClient(
            book,
            timeout=timeout,
            kernel_name="python3",
            resources={"metadata": {"path": work}},
        )
        client.execute()
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="*", help="notebooks to run (default: examples/*.ipynb)")
    parser.add_argument("--check-clean", action="store_true", help="fail if a notebook carries outputs")
    parser.add_argument("--strip", action="store_true", help="remove outputs and execution counts in place")
    parser.add_argument("--timeout", type=int, default=900, help="seconds per cell (default 900)")
    args = parser.parse_args(argv)
    paths = notebooks(args.notebooks)

    if args.strip:
        for path in paths:
            nbformat.write(strip(nbformat.read(path, as_version=4)), path)
        return 0
    if args.check_clean:
        bad = {path: dirty_cells(nbformat.read(path, as_version=4)) for path in paths}
        bad = {path: problems for path, problems in bad.items() if problems}
        for path, problems in bad.items():
            print(f"{path.relative_to(ROOT)}: {'; '.join(problems)} (run scripts/run_notebooks.py --strip)")
        return 1 if bad else 0

    os.environ.pop("MPLBACKEND", None)  # the kernel's inline backend renders figures into the outputs, headless
    failed = 0
    for path in paths:
        name = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
        try:
            seconds = execute(path, args.timeout)
        except Exception as exc:  # a cell raised, timed out, or the kernel died
            failed += 1
            print(f"FAILED {name}:\n{exc}", file=sys.stderr)
        else:
            print(f"ok {name} ({seconds:.1f} s)")
    print(f"{len(paths) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
