"""Sweeps: grid syntax, postures at a reach, agreement with analyze, files, executors."""

from __future__ import annotations

import csv
import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.analysis import analyze
from mobmanip.casestudy import ArmPosture, arm_measure, configuration_at
from mobmanip.cli import main
from mobmanip.errors import SpecError
from mobmanip.sweep import SweepGrid, SweepSpec, parse_grid, run_sweep
from mobmanip.sweep.runner import GridError, planar_arm, posture_at_reach

# ----- grid syntax -----


def test_parse_grid_forms():
    np.testing.assert_allclose(parse_grid("0:360:37"), np.arange(0.0, 361.0, 10.0))
    np.testing.assert_allclose(parse_grid("0.6:1.4:9"), np.linspace(0.6, 1.4, 9))
    np.testing.assert_allclose(parse_grid("0,45,90"), [0.0, 45.0, 90.0])
    np.testing.assert_allclose(parse_grid("1.5"), [1.5])
    np.testing.assert_allclose(parse_grid("2:2:1"), [2.0])


@pytest.mark.parametrize(
    "text, message",
    [
        ("0:360", "START:STOP:COUNT"),
        ("0:360:0", "positive integer"),
        ("0:360:2.5", "positive integer"),
        ("a:1:3", "not a number"),
        ("1,,2", "not a number"),
        ("0:1:1", "COUNT >= 2"),
        ("nan", "finite"),
    ],
)
def test_parse_grid_errors(text, message):
    with pytest.raises(GridError, match=message):
        parse_grid(text, "--angle")


def test_positive_axes_rejected():
    with pytest.raises(GridError, match="--distance: values must be positive"):
        SweepGrid.parse("0", "-1:1:3")
    with pytest.raises(GridError, match="positive"):
        SweepGrid(angle_deg=[0.0], distance=[1.0], wheel_effort_scale=[0.0])


@pytest.mark.parametrize(
    "args",
    [
        ["--angle", "0:360"],
        ["--distance", "0.6:1.4:x"],
        ["--wheel-velocity-scale", "-1"],
        ["--heading", "0:90:0"],
        ["--direction", "north"],
        ["--index", "kinematic.colour", "--plot"],
    ],
)
def test_cli_bad_grid_is_one_line_exit_2(args, tmp_path, capsys):
    code = main(["sweep", "planar_dual_arm", "--no-progress", "--workers", "1", "-o", str(tmp_path / "s"), *args])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("mobmanip: error: ") and err.count("\n") == 1, err


def test_cli_planar_postures_need_planar_arms(tmp_path, capsys):
    """The closed form on request only; other robots get inverse kinematics (test_sweep_general.py)."""
    args = ["sweep", "tiago_dual", "--postures", "planar", "--angle", "0", "--distance", "0.5"]
    code = main([*args, "--no-progress", "-o", str(tmp_path / "t")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "planar" in err


# ----- postures -----


def test_posture_at_optimal_reach_is_the_case_study_posture(robot, posture):
    found = posture_at_reach(planar_arm(robot, 0), posture.reach)
    assert found.manipulability == pytest.approx(posture.manipulability, rel=1e-12)
    np.testing.assert_allclose(found.q, posture.q, atol=1e-6)  # the case study's grid search resolution
    assert found.bearing == pytest.approx(posture.bearing, abs=1e-6)


@pytest.mark.parametrize("reach", [0.35, 0.8, 1.3, 1.49])
def test_posture_at_reach_against_pinocchio(robot, reach):
    """Reach and manipulability checked with Pinocchio; no neighbour on the family does better."""
    arm = robot.arms[0]
    found = posture_at_reach(planar_arm(robot, 0), reach)
    w, tip, base = arm_measure(robot, arm, found.q[1], found.q[2])
    assert np.hypot(*(tip - base)[:2]) == pytest.approx(reach, abs=1e-12)
    assert w == pytest.approx(found.manipulability, rel=1e-10)
    assert found.bearing > 0.0  # arm 1 bends to the right

    def family_member(q3):
        """q2 keeping the reach, by bisection on Pinocchio's forward kinematics (same elbow)."""

        def err(q2):
            _, t, b = arm_measure(robot, arm, q2, q3)
            return np.hypot(*(t - b)[:2]) - reach

        lo, hi = found.q[1] - 0.2, found.q[1] + 0.2
        assert err(lo) * err(hi) < 0
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if err(lo) * err(mid) > 0 else (lo, mid)
        return arm_measure(robot, arm, 0.5 * (lo + hi), q3)[0]

    for dq3 in (-1e-3, 1e-3):
        assert family_member(found.q[2] + dq3) <= found.manipulability + 1e-12


def test_out_of_reach(robot):
    arm = planar_arm(robot, 0)
    assert posture_at_reach(arm, arm.max_reach * 1.01) is None
    assert posture_at_reach(arm, 0.0) is None


def test_non_planar_arms_rejected():
    with pytest.raises(SpecError, match="3-joint planar arms; arm .right. has 7"):
        planar_arm(mobmanip.load_robot("tiago_dual"), 0)


# ----- sweep results against analyze -----


def test_sweep_matches_analyze(robot):
    """Grid points checked against analyze at configurations built independently
    (casestudy.configuration_at from the sweep's arm posture at each distance) and on variant
    robots for the limit scales."""
    grid = SweepGrid(
        angle_deg=[0.0, 45.0, 90.0, 200.0],
        distance=[0.7, 1.2],
        heading_deg=[0.0, 30.0],
        wheel_velocity_scale=[0.001, 0.5, 1.0],
        wheel_effort_scale=[1.0, 0.05],
    )
    spec = SweepSpec("planar_dual_arm", decoupled=True)
    result = run_sweep(spec, grid, workers=1)
    assert result.reachable.all()
    v0, e0 = robot.velocity_limits[0], robot.effort_limits[0]
    for idist, distance in enumerate(grid.distance):
        q2, q3, bearing = result.postures.right[idist]
        np.testing.assert_allclose(result.postures.left[idist], [-q2, -q3, -bearing])
        posture = ArmPosture((0.0, q2, q3), 0.0, distance, bearing)
        for ia, angle in enumerate(grid.angle_deg):
            for ih, heading in enumerate(grid.heading_deg):
                q = configuration_at(robot, posture, angle, heading=math.radians(heading))
                phi = math.radians(angle + heading)
                radial = np.array([math.cos(phi), math.sin(phi)])
                pin.framesForwardKinematics(robot.model, robot.data, q)
                for arm in robot.arms:  # both tips on the object
                    tip = robot.data.oMf[arm.frame_id].translation[:2]
                    np.testing.assert_allclose(tip, distance * radial, atol=1e-12)
                for iv, vs in enumerate(grid.wheel_velocity_scale):
                    for ie, es in enumerate(grid.wheel_effort_scale):
                        variant = robot.with_wheel_limits(velocity=vs * v0, effort=es * e0)
                        single = analyze(variant, q, "planar", decoupled=True)
                        at = (ia, idist, ih, iv, ie)
                        for kind, e in (("kinematic", single.kinematic), ("dynamic", single.dynamic)):
                            scale = e.semi_axes[0]
                            got = result.indices[f"{kind}_semi_axes"][at]
                            np.testing.assert_allclose(got, e.semi_axes, rtol=0, atol=1e-10 * scale)
                            assert result.index(f"{kind}.semi_axis_2")[at] == got[1]
                            assert result.index(f"{kind}.volume")[at] == pytest.approx(e.volume, rel=1e-9)
                            assert result.index(f"{kind}.isotropy")[at] == pytest.approx(e.isotropy, rel=1e-9)
                            capacity = result.index(f"{kind}.capacity")[at]
                            assert capacity == pytest.approx(e.support(radial), abs=1e-10 * scale)


def test_unreachable_points_are_nan(robot):
    grid = SweepGrid(angle_deg=[0.0, 90.0], distance=[1.0, 2.0])
    result = run_sweep(SweepSpec("planar_dual_arm"), grid, workers=1)
    np.testing.assert_array_equal(result.reachable[:, :, 0], [[True, False], [True, False]])
    assert np.isnan(result.index("kinematic.volume")[:, 1]).all()
    assert np.isfinite(result.index("dynamic.volume")[:, 0]).all()


def test_fixed_platform_and_fixed_direction(robot, posture):
    grid = SweepGrid(angle_deg=[0.0, 90.0], distance=[posture.reach])
    result = run_sweep(SweepSpec("planar_dual_arm", platform="fixed", direction=(0.0, 1.0)), grid, workers=1)
    q2, q3, bearing = result.postures.right[0]
    at_reach = ArmPosture((0.0, q2, q3), 0.0, posture.reach, bearing)
    locked = robot.with_platform("fixed")
    for ia, angle in enumerate(grid.angle_deg):
        single = analyze(locked, configuration_at(robot, at_reach, angle), "planar")
        got = result.index("kinematic.capacity")[ia, 0, 0, 0, 0]
        assert got == pytest.approx(single.kinematic.support([0.0, 1.0]), abs=1e-10 * single.kinematic.semi_axes[0])


# ----- files -----


def test_cli_writes_npz_csv_and_plot(tmp_path, capsys):
    out = tmp_path / "run" / "fig"  # a folder, created with its parent
    code = main(
        [
            "sweep",
            "planar_dual_arm",
            "--angle",
            "0:90:4",
            "--distance",
            "0.8,1.0,1.6",
            "--wheel-velocity-scale",
            "0.5,1",
            "--workers",
            "1",
            "--no-progress",
            "--plot",
            "--index",
            "dynamic.semi_axis_1",
            "-o",
            str(out),
        ]
    )
    assert code == 0, capsys.readouterr().err
    data = np.load(out / "sweep.npz")
    np.testing.assert_allclose(data["angle_deg"], [0.0, 30.0, 60.0, 90.0])
    np.testing.assert_allclose(data["distance"], [0.8, 1.0, 1.6])
    np.testing.assert_allclose(data["wheel_velocity_scale"], [0.5, 1.0])
    shape = (4, 3, 1, 2, 1)
    for kind in ("kinematic", "dynamic"):
        for name in ("volume", "isotropy", "capacity", "degenerate", "empty"):
            assert data[f"{kind}_{name}"].shape == shape
        assert data[f"{kind}_semi_axes"].shape == shape + (2,)
    assert str(data["meta_robot"]) == "planar_dual_arm" and str(data["meta_task"]) == "planar"
    assert not data["reachable"][:, 2].any() and data["reachable"][:, :2].all()
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == int(np.prod(shape))
    assert set(rows[0]) >= {"angle_deg", "distance", "kinematic_volume", "dynamic_semi_axis_2", "reachable"}
    row = next(
        r
        for r in rows
        if float(r["angle_deg"]) == 60.0 and float(r["distance"]) == 1.0 and r["wheel_velocity_scale"] == "1"
    )
    assert float(row["kinematic_volume"]) == pytest.approx(data["kinematic_volume"][2, 1, 0, 1, 0], rel=1e-11)
    assert float(row["dynamic_isotropy"]) == pytest.approx(data["dynamic_isotropy"][2, 1, 0, 1, 0], rel=1e-11)
    assert (out / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_output_is_a_folder_and_an_old_prefix_gets_one_line(tmp_path, capfd):
    """``-o OUT`` writes OUT/sweep.npz and OUT/sweep.csv (issue 39: it was a prefix, OUT.npz). Beside
    an earlier run's OUT.csv, a folder OUT that does not exist yet gets one warning line naming where
    the files go and the old file, which is left alone; once the folder exists nothing is said."""
    from hostile_util import run_cli

    old = tmp_path / "fig.csv"
    old.write_text("an earlier run's table")
    argv = ["sweep", "planar_dual_arm", "--angle", "0,90", "--distance", "1.0", "--workers", "1", "--no-progress"]
    code, out, err = run_cli(capfd, *argv, "-o", tmp_path / "fig")
    assert code == 0, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: -o ") and "is a folder now" in lines[0]
    assert str(tmp_path / "fig" / "sweep.npz") in lines[0] and str(old) in lines[0]
    assert old.read_text() == "an earlier run's table"
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == ["sweep.csv", "sweep.npz"]
    assert f"wrote {tmp_path / 'fig' / 'sweep.npz'}" in out
    with np.load(tmp_path / "fig" / "sweep.npz") as data:
        np.testing.assert_allclose(data["angle_deg"], [0.0, 90.0])
    code, _, err = run_cli(capfd, *argv, "-o", tmp_path / "fig")
    assert code == 0 and err.strip() == ""


# ----- executors -----


SMALL = SweepGrid(angle_deg=np.linspace(0, 180, 7), distance=[0.7, 1.0, 1.3], heading_deg=[0.0, 45.0],
                  wheel_effort_scale=[1.0, 0.1])  # fmt: skip


def assert_same_result(a, b):
    assert a.indices.keys() == b.indices.keys()
    for key in a.indices:
        np.testing.assert_array_equal(a.indices[key], b.indices[key], err_msg=key)
    np.testing.assert_array_equal(a.reachable, b.reachable)


def test_process_pool_equals_serial():
    spec = SweepSpec("planar_dual_arm")
    serial = run_sweep(spec, SMALL, workers=1, chunk_size=5)
    parallel = run_sweep(spec, SMALL, workers=2, chunk_size=5)
    assert_same_result(serial, parallel)


def test_dask_cluster_equals_serial():
    distributed = pytest.importorskip("dask.distributed")
    spec = SweepSpec("planar_dual_arm", decoupled=True)
    serial = run_sweep(spec, SMALL, workers=1, chunk_size=8)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            result = run_sweep(spec, SMALL, executor=client.get_executor(), chunk_size=8)
            workers = client.run(lambda: __import__("mobmanip.sweep.runner").sweep.runner._WORKER_CACHE.__len__())
    assert_same_result(serial, result)
    assert len(workers) == 2


def test_saving_to_a_missing_directory_is_an_output_error(tmp_path):
    """From Python as from the CLI: one MobmanipError naming the path, no partial file."""
    from mobmanip.commands.outputs import write_sweep_csv, write_sweep_npz
    from mobmanip.support.files import OutputError

    result = run_sweep(SweepSpec("planar_dual_arm"), SweepGrid(angle_deg=[0.0], distance=[1.0]), workers=1)
    for save, name in ((write_sweep_npz, "x.npz"), (write_sweep_csv, "x.csv")):
        with pytest.raises(OutputError, match=name):
            save(result, tmp_path / "missing" / name)
    assert not (tmp_path / "missing").exists()


def test_posture_table_is_the_same_spread_over_workers():
    """run_sweep spreads the posture search over its executor in slices of distances: every
    distance's posture is searched on its own, so the table is identical."""
    import concurrent.futures as cf

    from mobmanip.sweep.runner import posture_table

    robot = mobmanip.load_robot("planar_dual_arm")
    distances = np.linspace(0.2, 1.6, 37)  # some out of reach
    alone = posture_table(robot, distances)
    with cf.ProcessPoolExecutor(max_workers=2) as pool:
        spread = posture_table(robot, distances, pool.map)
    np.testing.assert_array_equal(spread.reachable, alone.reachable)
    np.testing.assert_array_equal(spread.right, alone.right)
    np.testing.assert_array_equal(spread.left, alone.left)
    assert 0 < alone.reachable.sum() < len(distances)
