"""Hostile input, round 2 (class 6): every command whose work grows with its input estimates it
before starting and refuses more than a stated bound, naming the estimate and ``--max-work``
that raises it; a raised bound lets the run go."""

from __future__ import annotations

import re
import time

import pytest

from hostile_util import ROOT, assert_one_line_error, run_cli
from mobmanip.errors import ArgumentError
from mobmanip.support.work import WorkEstimate, check_work, duration

TEAM_TEXT = (ROOT / "examples" / "beam_team.toml").read_text()
PLACE = ("place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x")


def _refused_quickly(capfd, *argv) -> str:
    started = time.monotonic()
    code, out, err = run_cli(capfd, *argv)
    line = assert_one_line_error(code, err, "--max-work", "about")
    assert out == ""
    assert time.monotonic() - started < 15, line
    return line


@pytest.mark.parametrize(
    ("duration_s", "step", "prepare"),
    [("1e5", "0.02", "0"), ("1000", "0.001", "0"), ("10", "0.02", "1e9"), ("4000", "0.02", "30")],
)
def test_carry_estimates_and_bounds_its_steps(tmp_path, capfd, duration_s, step, prepare):
    path = tmp_path / "p.csv"
    path.write_text(f"t,x,y\n0,0,0\n{duration_s},0.1,0\n")
    line = _refused_quickly(capfd, "carry", "planar_dual_arm", "--path", path, "--step", step, "--prepare", prepare)
    assert "QP steps" in line and re.search(r"\d{3},\d{3}", line)


def test_carry_max_work_raises_and_lowers_the_bound(tmp_path, capfd):
    path = tmp_path / "p.csv"
    path.write_text("t,x,y\n0,0,0\n0.5,0.01,0\n")
    argv = ("carry", "planar_dual_arm", "--path", path, "--prepare", "0", "--step", "0.05")
    _refused_quickly(capfd, *argv, "--max-work", "5")
    code, _, err = run_cli(capfd, *argv, "--max-work", "20")
    assert code == 0, err
    code, _, err = run_cli(capfd, *argv, "--max-work", "0")
    assert_one_line_error(code, err, "--max-work")


@pytest.mark.parametrize("samples", [200_001, 1_000_000])
def test_trajectory_counts_samples_before_parsing(tmp_path, capfd, samples):
    path = tmp_path / "m.csv"
    path.write_text("t,platform_x,platform_y,platform_yaw\n" + "".join(f"{i},0,0,0\n" for i in range(samples)))
    line = _refused_quickly(capfd, "trajectory", "planar_dual_arm", path)
    assert f"{samples:,} samples" in line


@pytest.mark.parametrize(("extra", "needle"), [(("--map-cells", "400", "--map", "maps"), "160,000 map cells"),
                                               (("--map-cells", "101", "--map", "maps"), "10,201 map cells"),
                                               (("--starts", "1000000"), "1,000,000 starts"),
                                               (("--starts", "1001"), "1,001 starts")])  # fmt: skip
def test_place_bounds_starts_and_map_cells(tmp_path, capfd, extra, needle):
    extra = tuple(str(tmp_path / e) if e == "maps" else e for e in extra)
    line = _refused_quickly(capfd, *PLACE, *extra)
    assert needle in line
    assert not (tmp_path / "maps").exists()


def test_place_max_work_lets_more_starts_run(capfd):
    code, _, err = run_cli(capfd, *PLACE, "--starts", "3", "--max-work", "3")
    assert code == 0, err
    _refused_quickly(capfd, *PLACE, "--starts", "3", "--max-work", "2")


@pytest.mark.parametrize("robots", [65, 200])
def test_team_bounds_its_robots(tmp_path, capfd, robots):
    head, first = TEAM_TEXT.split("[[robots]]", 1)
    entry = "[[robots]]" + first.split("[[robots]]")[0]
    text = head + "".join(entry.replace('name = "south"', f'name = "r{k}"') for k in range(robots))
    team = tmp_path / "team.toml"
    team.write_text(text)
    line = _refused_quickly(capfd, "team", team)
    assert f"{robots} robots" in line


@pytest.mark.parametrize("grid", ["0:10:1000000", "0:360:50001", "-1e6:1e6:1000000"])
def test_team_bounds_its_heading_sweep(capfd, grid):
    line = _refused_quickly(capfd, "team", ROOT / "examples" / "beam_team.toml", f"--sweep-heading={grid}")
    assert "robot-headings" in line


def test_estimates_read_for_people():
    assert duration(30) == "30.0 s" and duration(600) == "10 min" and duration(7200) == "2.0 h"
    assert "days" in duration(1e9) and duration(float("inf")) == "forever"
    estimate = WorkEstimate("carry", "QP steps", 5e6, 2.5e-3, "path 1e5 s")
    with pytest.raises(ArgumentError, match=r"5,000,000 QP steps \(path 1e5 s\), about 3.5 h"):
        check_work(estimate, 200_000)
    assert check_work(estimate, 10**7) is estimate


def test_a_grounded_placement_search_is_announced_only_when_long(capfd):
    """A polytope objective's search: 300 evaluations (the default) take a few seconds, so nothing
    is announced; more than the bound is refused naming the estimate (it once announced 'about
    75 s' for a search that took 4 s)."""
    argv = ("place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "dynamic_polytope:reach:+x",
            "--ground", "--no-progress")  # fmt: skip
    code, _, err = run_cli(capfd, *argv)
    assert code == 0, err
    assert "about" not in err
    line = _refused_quickly(capfd, *argv, "--budget", "20001")
    assert "20,001 search evaluations, about 7 min" in line
