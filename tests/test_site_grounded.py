"""``mobmanip site`` with ``[grounded]``: the straight-line reach on the floor at each position's
placement, checked against the independent whole-robot LP (tests/floor_reference.py); where the
robot cannot stand on its floor the value is left out and the reason says why; a bad ``mu``,
direction or objective is one error before any work or output."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest

import mobmanip
from floor_reference import PAPER_CASTERS, build_problem, straight_line

HEAD = 'robot = "planar_dual_arm"\nstarts = 2\npositions = [[1.0, 0.5, 0.35], [0.8, 0.0, 0.35]]\n'


def _site(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(HEAD + text)
    run = subprocess.run([sys.executable, "-m", "mobmanip", "site", str(path), "--output", str(tmp_path / "o"),
                          "--no-progress"], capture_output=True, text=True)  # fmt: skip
    rows = list(csv.DictReader((tmp_path / "o" / "site.csv").open())) if run.returncode == 0 else []
    return run, rows


def test_the_grounded_reach_at_each_placement_is_the_independent_lps(tmp_path):
    run, rows = _site(tmp_path, 'objective = "dynamic:capacity:+x"\n[grounded]\nmu = 0.5\ndirection = "+x"\n')
    assert run.returncode == 0, run.stderr
    robot = mobmanip.load_robot("planar_dual_arm")
    header = (tmp_path / "o" / "site.csv").read_text().splitlines()[0].split(",")
    assert len(header) == len(set(header))  # every column once: the placement's platform_x and q's apart
    assert "q_0" not in rows[0] and {"q.platform_cos_yaw", "q.arm_right_1_joint", "platform_x"} <= set(rows[0])
    for row in rows:
        q = np.array([float(row[f"q.{name}"]) for name in robot.coordinate_names])
        held = mobmanip.analyze(robot, q, "planar", measures=("kinematic",)).held_object
        problem = build_problem(robot, q, "planar", held, casters=PAPER_CASTERS)
        ref = straight_line(problem, np.array([1.0, 0.0]), mode="friction", mu=0.5, springs=True).value
        assert ref > 1.0 and row["reason"] == ""
        assert float(row["grounded_reach"]) == pytest.approx(ref, rel=1e-6)


def test_a_grounded_direction_keeps_its_sign():
    """Along -y the grounded reach at the placement is the independent LP's along (0, -1), written
    here, and not its reach along +y. The placement turns the platform to face -y with the object
    at its side, so world y is the platform's fore and aft, where the arms' folded postures are not
    symmetric: on the floor the two reaches differ (21.5 and 23.9 m/s^2). Along +-x they agree to
    rounding there, and a direction's sign read the wrong way could not be seen."""
    from mobmanip.placement.site import Site, run_site

    document = {"robot": "planar_dual_arm", "starts": 2, "positions": [[0.8, 0.0, 0.35]],
                "objective": "dynamic:capacity:+x", "grounded": {"mu": 0.5, "direction": "-y"}}  # fmt: skip
    result = run_site(Site.from_document(document))
    assert result.reasons == ("",)
    robot = mobmanip.load_robot("planar_dual_arm")
    row = result.table[0]
    q = np.array([row[result.columns.index(f"q.{name}")] for name in robot.coordinate_names])
    held = mobmanip.analyze(robot, q, "planar", measures=("kinematic",)).held_object
    problem = build_problem(robot, q, "planar", held, casters=PAPER_CASTERS)
    down = straight_line(problem, np.array([0.0, -1.0]), mode="friction", mu=0.5, springs=True).value
    up = straight_line(problem, np.array([0.0, 1.0]), mode="friction", mu=0.5, springs=True).value
    assert abs(up - down) > 0.05 * down > 0.5  # the sign shows
    assert row[result.columns.index("grounded_reach")] == pytest.approx(down, rel=1e-6)


def test_where_the_robot_cannot_stand_the_reason_says_why(tmp_path):
    """The kinematic capacity along +x stretches the arms: the centre of mass (robot and 2 kg held
    level) leaves the core of the six equally stiff contacts, so the set on the floor is empty. It
    was reported as a reach of 0 with no reason."""
    run, rows = _site(tmp_path, 'objective = "kinematic:capacity:+x"\n[grounded]\nmu = 0.5\nlevel = true\n')
    assert run.returncode == 0, run.stderr
    for row in rows:
        assert row["grounded_reach"] == "" and float(row["value"]) > 0.0
        assert row["reason"].startswith("grounded capacity: dynamic_polytope on the floor is empty")
        assert "would unload wheel_" in row["reason"]


@pytest.mark.parametrize(
    "body, message",
    [
        ('objective = "dynamic:capacity:+x"\n[grounded]\nmu = 50\ndirection = "+x"', "[grounded] mu 50 is above 10"),
        ('objective = "dynamic:capacity:+x"\n[grounded]\nmu = 0.5\ndirection = "+q"',
         "[grounded] direction '+q': the planar task's axes are +x, -x, +y, -y"),
        ('objective = "dynamic_polytope:bogus:+x"', "the reading must be one of reach, support"),
        ('objective = "kinematic:capacity:+q"', "+q"),
    ],
    ids=["mu", "direction", "reading", "axis"],
)  # fmt: skip
def test_a_bad_site_is_one_error_before_any_work_or_output(tmp_path, body, message):
    """Nothing is printed before the error: not even the site's header line."""
    run, _ = _site(tmp_path, body + "\n")
    assert run.returncode == 2 and run.stderr.count("\n") == 1 and message in run.stderr, run.stderr
    assert run.stderr.startswith("mobmanip: error: ") and run.stdout == "", run.stdout
    assert not (tmp_path / "o").exists()
