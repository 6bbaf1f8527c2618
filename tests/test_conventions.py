"""Conventions of the ecosystem: ``python -m mobmanip``, ``--version`` from one place, logging
through :mod:`logging` (quiet by default, ``-v`` for more), readable results in a notebook."""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import tomllib
from html.parser import HTMLParser
from importlib.metadata import version

import numpy as np
import pytest

import mobmanip
from conftest import ROOT
from mobmanip.cli import main


def _run_module(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    return subprocess.run(
        [sys.executable, "-m", "mobmanip", *args], capture_output=True, text=True, env=env, timeout=300
    )


def test_version_has_one_source():
    """pyproject.toml is the only place the version is written: the package and the command
    report the installed distribution's version, which is pyproject's."""
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert version("mobmanip") == declared
    assert mobmanip.__version__ == declared
    done = _run_module("--version")
    assert done.returncode == 0
    assert done.stdout.strip() == f"mobmanip {declared}"


def test_python_dash_m_runs_the_command(tmp_path):
    """``python -m mobmanip`` is the command: same JSON as ``main`` in this process."""
    out = tmp_path / "a.json"
    done = _run_module("analyze", "planar_dual_arm", "--json", str(out))
    assert done.returncode == 0, done.stderr
    doc = json.loads(out.read_text())
    robot = mobmanip.load_robot("planar_dual_arm")
    expected = mobmanip.analyze(robot, robot.neutral())
    np.testing.assert_allclose(doc["kinematic_ellipsoid"]["semi_axes"], expected.kinematic.semi_axes, rtol=1e-12)


def test_quiet_by_default_and_verbose_on_request(capsys):
    """Without -v nothing but the result is printed; -v adds INFO records naming what was loaded,
    on standard error only (standard output stays the same)."""
    assert main(["analyze", "planar_dual_arm"]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == ""
    assert main(["-v", "analyze", "planar_dual_arm"]) == 0
    verbose = capsys.readouterr()
    assert verbose.out == quiet.out
    lines = verbose.err.splitlines()
    assert lines and all(line.startswith("mobmanip: ") for line in lines)
    assert any("INFO" in line and "planar_dual_arm" in line and "nx = 8" in line for line in lines)
    # -v twice is DEBUG, and repeated runs do not stack handlers (one line per record).
    assert main(["-vv", "analyze", "planar_dual_arm"]) == 0
    again = capsys.readouterr().err.splitlines()
    assert sum("loaded planar_dual_arm" in line for line in again) == 1
    assert logging.getLogger("mobmanip").level == logging.DEBUG


def test_library_logs_nothing_unless_configured(caplog):
    """The library only emits records; whether they are shown is the application's choice."""
    with caplog.at_level(logging.INFO, logger="mobmanip"):
        mobmanip.load_robot("planar_dual_arm")
    assert any(r.name == "mobmanip.robot.model" and r.levelno == logging.INFO for r in caplog.records)


@pytest.fixture(scope="module")
def analysis():
    robot = mobmanip.load_robot("planar_dual_arm")
    return mobmanip.analyze(robot, robot.neutral(), measures=("kinematic", "dynamic", "kinematic_polytope"))


def test_robot_repr_is_one_short_line():
    robot = mobmanip.load_robot("planar_dual_arm")
    text = repr(robot)
    assert "\n" not in text and len(text) < 120
    assert text == "Robot('planar_dual_arm', platform='differential_drive', arms=(right, left), nq=14, nx=8)"
    assert "platform='fixed'" in repr(robot.with_platform("fixed")) and "nx=6" in repr(robot.with_platform("fixed"))


def test_analysis_repr_carries_the_sets(analysis):
    """The one-line repr gives each set's semi-axes, volume and isotropy, which are the sets' own."""
    text = repr(analysis)
    assert "\n" not in text and len(text) < 400
    for value in analysis.kinematic.semi_axes:
        assert f"{value:.4g}" in text
    assert f"volume {analysis.measure('kinematic_polytope').volume:.4g}" in text
    assert text.startswith("Analysis(robot='planar_dual_arm', task='planar'")


class _Cells(HTMLParser):
    def __init__(self):
        super().__init__()
        self.rows: list[list[str]] = []

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])

    def handle_data(self, data):
        if self.rows:
            self.rows[-1].append(data)


def test_analysis_html_is_a_table_of_its_measures(analysis):
    cells = _Cells()
    cells.feed(analysis._repr_html_())
    header, *rows = cells.rows
    assert header == ["measure", "units", "set"]
    assert [row[0] for row in rows] == list(analysis.measures)
    assert rows[1][1] == "m/s^2"  # the planar task: linear rows only


def test_sweep_and_case_study_reprs_are_summaries():
    """A sweep's repr counts what it holds (grid shape, reachable points) from its own arrays."""
    from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep

    result = run_sweep(SweepSpec("planar_dual_arm"), SweepGrid(angle_deg=[0, 90], distance=[0.8, 5.0]), workers=1)
    text = repr(result)
    assert "\n" not in text and "grid 2 x 2 x 1 x 1 x 1" in text
    assert f"reachable {int(result.reachable.sum())}/4" in text and "reachable 2/4" in text  # 5 m is out of reach
    assert "measures kinematic, dynamic" in text
