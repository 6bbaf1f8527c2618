"""Hostile and broken input (4): bounded work. Sweep grids beyond a stated size are refused up
front with an estimate, grid values and scaled limits are checked before anything runs, worker
processes end with their parent, and loading and detection stay near-linear in the model size."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.errors import GridError, RangeError, SpecError
from mobmanip.robot.detect import detect_spec
from mobmanip.support.ranges import MAX_MODEL_DOF
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
from mobmanip.sweep.budget import BYTES_PER_POINT, MAX_GRID_POINTS, estimate

SRC = Path(mobmanip.__file__).resolve().parents[1]


@pytest.mark.parametrize("angle", ["0:360:1000000000", "0:360:10000000000", "0:360:100000"])
def test_huge_grids_are_refused_at_once_with_an_estimate(capfd, angle):
    start = time.perf_counter()
    code, out, err = run_cli(capfd, "sweep", "planar_dual_arm", "--angle", angle, "--distance", "0.6:1.4:1000")
    line = assert_one_line_error(code, err)
    assert time.perf_counter() - start < 5.0
    assert "10,000,000" in line  # the stated limit
    if angle.endswith("100000"):
        assert "100,000,000 grid points" in line and "GB of memory" in line  # the estimate


def test_the_limit_can_be_raised_or_lowered():
    grid = SweepGrid(angle_deg=[0.0, 90.0], distance=[0.8, 1.0])
    with pytest.raises(GridError, match="more than the limit of 3 points"):
        run_sweep(SweepSpec("planar_dual_arm"), grid, workers=1, max_points=3)
    result = run_sweep(SweepSpec("planar_dual_arm"), grid, workers=1, max_points=None)
    assert result.reachable.shape[:2] == (2, 2)


def test_estimate_scales_with_the_grid():
    small, large = estimate((10, 10, 1, 1, 1)), estimate((100, 100, 2, 1, 1))
    assert large.points == 200 * small.points and large.bytes == 200 * small.bytes
    assert large.bytes == 20_000 * BYTES_PER_POINT
    assert estimate((10, 10, 1, 1, 1), workers=2).seconds == pytest.approx(small.seconds / 2)
    assert MAX_GRID_POINTS == 10_000_000


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--distance", "1e308"),
        ("--angle", "1e308"),
        ("--heading", "-1e300"),
        ("--wheel-velocity-scale", "1e-300"),
        ("--wheel-effort-scale", "1e12"),
        ("--wheel-velocity-scale", "1e5"),  # within the scale range, but the wheel limit leaves its own
    ],
)
def test_extreme_grid_values_are_refused_before_the_sweep(capfd, option, value):
    argv = ["sweep", "planar_dual_arm", "--angle", "0,90", "--distance", "1.0", "--workers", "1", f"{option}={value}"]
    code, out, err = run_cli(capfd, *argv)
    assert_one_line_error(code, err, "outside the supported range")


def test_scaled_wheel_limits_are_checked_in_the_library():
    grid = SweepGrid(angle_deg=[0.0], distance=[1.0], wheel_velocity_scale=[1.0, 1e5])
    with pytest.raises(RangeError, match="scale 100000"):
        run_sweep(SweepSpec("planar_dual_arm"), grid, workers=1)


# ----- process hygiene


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out += [int(p) for p in (task / "children").read_text().split()]
        except OSError:
            continue
    return out


def _alive(pid: int) -> bool:
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    state = next(line for line in status.splitlines() if line.startswith("State:"))
    return "Z" not in state.split()[1]  # a zombie has exited


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
def test_workers_exit_when_the_sweep_process_is_killed(tmp_path):
    script = tmp_path / "sweep.py"
    script.write_text(
        textwrap.dedent(
            """
            import numpy as np
            from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
            # one configuration per task: slow enough to be killed midway
            grid = SweepGrid(angle_deg=np.linspace(0, 360, 200), distance=np.linspace(0.6, 1.4, 100))
            run_sweep(SweepSpec("planar_dual_arm"), grid, workers=2, chunk_size=1)
            """
        )
    )
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    parent = subprocess.Popen([sys.executable, str(script)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len(workers) < 2:
            assert parent.poll() is None, parent.stderr.read().decode()
            workers = _children(parent.pid)
            time.sleep(0.1)
        assert len(workers) >= 2, "the pool did not start"
        time.sleep(1.0)  # the workers are busy
        assert all(_alive(w) for w in workers)
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and any(_alive(w) for w in workers):
            time.sleep(0.1)
        assert not any(_alive(w) for w in workers), "orphaned workers"
    finally:
        if parent.poll() is None:
            parent.kill()
        for worker in workers:  # left over only if the test failed
            if _alive(worker):
                os.kill(worker, signal.SIGKILL)


# ----- model size


def _chain(n: int, fixed: bool) -> str:
    inertial = (
        '<inertial><mass value="0.1"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial>'
    )
    limit = '<limit lower="-3" upper="3" effort="10" velocity="2"/>'
    parts = ['<robot name="chain">', f'<link name="base">{inertial}</link>']
    parent = "base"
    for i in range(n):
        kind = "fixed" if fixed else "revolute"
        parts.append(
            f'<joint name="j{i}" type="{kind}"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="0 0 0.01"/><axis xyz="0 0 1"/>{"" if fixed else limit}</joint>'
            f'<link name="l{i}">{inertial}</link>'
        )
        parent = f"l{i}"
    parts.append(
        f'<joint name="arm" type="revolute"><parent link="{parent}"/><child link="tool"/><axis xyz="0 0 1"/>{limit}'
        f'</joint><link name="tool">{inertial}</link></robot>'
    )
    return "\n".join(parts)


def _seconds(function) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def test_detection_of_long_chains_is_near_linear(tmp_path):
    paths = {}
    for n in (1000, 4000):
        paths[n] = tmp_path / f"chain{n}.urdf"
        paths[n].write_text(_chain(n, fixed=False))
    detect_spec(paths[1000], ["tool"], None, None)  # warm up imports
    small = min(_seconds(lambda: detect_spec(paths[1000], ["tool"], None, None)) for _ in range(2))
    large = _seconds(lambda: detect_spec(paths[4000], ["tool"], None, None))
    assert large < 10.0 * small + 0.5  # 4x the joints: 16x if quadratic


def test_five_thousand_fixed_links_load_and_analyse(tmp_path, capfd):
    path = tmp_path / "fixed5000.urdf"
    path.write_text(_chain(5000, fixed=True))
    start = time.perf_counter()
    code, out, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", "tool", "--task", "planar")
    assert code == 0, err
    assert time.perf_counter() - start < 30.0
    assert "kinematic ellipsoid" in out


def test_five_thousand_moving_joints_are_refused_with_the_reason(tmp_path, capfd):
    path = tmp_path / "chain5000.urdf"
    path.write_text(_chain(5000, fixed=False))
    code, out, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", "tool")
    assert_one_line_error(code, err, "5,001 moving joints", f"at most {MAX_MODEL_DOF}")
    with pytest.raises(SpecError):
        mobmanip.load_robot(detect_spec(path, ["tool"], None, None).spec)


def test_the_grid_axes_are_numbers(capfd):
    assert np.isfinite(MAX_GRID_POINTS)
