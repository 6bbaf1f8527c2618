"""Hostile site files: the number of object positions is counted from the file and refused
before any position is made (a grid of a billion is not a 24 GB array), naming the key, the
count and the bound; ``--max-work`` raises the bound up to the ceiling no site passes."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from hostile_util import assert_one_line_error, run_cli
from mobmanip.commands.site import MAX_SITE_POSITIONS
from mobmanip.errors import SpecError
from mobmanip.placement.site import MAX_POSITIONS, Site

HEAD = 'robot = "planar_dual_arm"\nobjective = "kinematic:capacity:+x"\n'


def _site(tmp_path: Path, body: str, name: str = "site.toml") -> Path:
    path = tmp_path / name
    path.write_text(HEAD + body)
    return path


@pytest.mark.parametrize(
    ("grid", "count"),
    [
        ("x = [0, 1, 10000000000000]\ny = 0.5\nz = 0.35", 10**13),
        ("x = [0, 1, 100000]\ny = [0, 1, 100000]\nz = [0, 1, 100000]", 10**15),
        ("x = 0.0\ny = 0.5\nz = [0.1, 0.9, 9223372036854775807]", 9223372036854775807),
    ],
)
def test_a_grid_beyond_the_ceiling_is_refused_before_it_is_made(capfd, tmp_path, grid, count):
    """In this process: counts whose arrays could not even be asked for (a regression fails at
    once with "out of memory", never by filling this machine's memory; the billion of the
    report is run in a capped child below)."""
    site = _site(tmp_path, f"[grid]\n{grid}\n")
    started = time.perf_counter()
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out")
    seconds = time.perf_counter() - started
    line = assert_one_line_error(code, err, "[grid]", site.name, f"{count:,} object positions", f"{MAX_POSITIONS:,}")
    assert seconds < 5, seconds
    assert "out of memory" not in line
    assert out == "" and not (tmp_path / "out").exists()


def test_a_billion_positions_cost_no_memory(tmp_path):
    """In a process whose address space is capped at 1 GiB (a billion positions would need
    24 GB, and a MemoryError would end the child with a traceback): the refusal comes from
    counting."""
    site = _site(tmp_path, "[grid]\nx = [0, 1, 1000000000]\ny = 0.5\nz = 0.35\n")
    code = (
        "import resource, sys\n"
        "resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))\n"
        "from mobmanip.placement.site import Site\n"
        "from mobmanip.errors import SpecError\n"
        "try:\n"
        f"    Site.read({str(site)!r})\n"
        "except SpecError as exc:\n"
        "    print(exc)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30)
    assert done.returncode == 0, done.stderr
    assert "1,000,000,000 object positions" in done.stdout and "x 1,000,000,000 by y 1 by z 1" in done.stdout


@pytest.mark.parametrize(
    ("body", "count", "shape"),
    [
        ("[grid]\nx = [0, 1, 200]\ny = [0, 1, 100]\nz = 0.35\n", 20_000, "x 200 by y 100 by z 1"),
        ("[grid]\nx = [0, 3, 11]\ny = [0, 1, 11]\nz = [0.1, 0.9, 100]\n", 12_100, "x 11 by y 11 by z 100"),
    ],
)
def test_a_grid_above_the_work_bound_names_the_option_and_the_bound(capfd, tmp_path, body, count, shape):
    site = _site(tmp_path, body)
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out")
    assert_one_line_error(
        code, err, f"{count:,} object positions", shape, site.name, f"{MAX_SITE_POSITIONS:,}", "--max-work N"
    )
    assert out == ""


def test_a_list_of_positions_is_counted_too(capfd, tmp_path):
    positions = ", ".join("[1.0, 0.5, 0.35]" for _ in range(12))
    site = _site(tmp_path, f"positions = [{positions}]\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--max-work", "10")
    assert_one_line_error(code, err, "12 object positions", "'positions'", site.name, "more than the 10", "--max-work")


def test_max_work_raises_the_bound_but_not_the_ceiling(capfd, tmp_path):
    site = _site(tmp_path, "[grid]\nx = [0, 1, 2000]\ny = [0, 1, 1000]\nz = 0.35\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--max-work", "10000000")
    assert_one_line_error(code, err, "2,000,000 object positions", f"more than the {MAX_POSITIONS:,} any site may hold")


def test_the_bound_counts_before_the_grid_is_made():
    """The library: the check sees the count and how it follows from the file, and refuses
    before anything is allocated; a site within it is made as before (x fastest)."""
    seen = []

    def refuse(count, detail):
        seen.append((count, detail))
        raise SpecError("refused")

    document = {"robot": "planar_dual_arm", "objective": "kinematic:capacity:+x",
                "grid": {"x": [0.0, 1.0, 10**9], "y": [0.0, 1.0, 2], "z": 0.35}}  # fmt: skip
    with pytest.raises(SpecError, match="2,000,000,000 object positions"):
        Site.from_document(document, where="here.toml", check_count=refuse)
    assert seen == []  # beyond the ceiling: refused before the check is asked
    document["grid"]["x"] = [0.0, 1.0, 3]
    with pytest.raises(SpecError, match="refused"):
        Site.from_document(document, where="here.toml", check_count=refuse)
    assert seen == [(6, "[grid] in here.toml: x 3 by y 2 by z 1")]
    site = Site.from_document(document, where="here.toml", check_count=lambda count, detail: None)
    assert site.grid_shape == (3, 2, 1)
    assert site.positions.tolist() == [[0.0, 0.0, 0.35], [0.5, 0.0, 0.35], [1.0, 0.0, 0.35],
                                       [0.0, 1.0, 0.35], [0.5, 1.0, 0.35], [1.0, 1.0, 0.35]]  # fmt: skip


@pytest.mark.parametrize("axis", ["[-1e308, 1e308, 3]", "[1.7e308, -1.7e308, 5]"])
def test_a_grid_whose_step_overflows_is_one_line(capfd, tmp_path, axis):
    site = _site(tmp_path, f"[grid]\nx = {axis}\ny = 0.0\nz = 0.35\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out")
    assert_one_line_error(code, err, site.name, "[grid] x from", "goes beyond +-1e+06 m")
