"""Messages that say what is true (issue 28, item 10): ``init-spec --list-frames`` on a file with
no candidate end effector says so and what to do, instead of a header over an empty list;
``view --duration N`` says how long it serves, not that it waits for Ctrl-C."""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest

from hostile_util import run_cli

#: A base with two continuous wheels and a sensor mast on a fixed joint: nothing beyond the
#: wheels moves, so no link can be an end effector.
BASE_ONLY = """<robot name="cart">
  <link name="base_link"/>
  <link name="wheel_l"/><link name="wheel_r"/><link name="mast"/><link name="camera"/>
  <joint name="wheel_l_joint" type="continuous"><parent link="base_link"/><child link="wheel_l"/>
    <origin xyz="0 0.2 0.1" rpy="-1.5708 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="wheel_r_joint" type="continuous"><parent link="base_link"/><child link="wheel_r"/>
    <origin xyz="0 -0.2 0.1" rpy="-1.5708 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="mast_joint" type="fixed"><parent link="base_link"/><child link="mast"/></joint>
  <joint name="camera_joint" type="fixed"><parent link="mast"/><child link="camera"/></joint>
</robot>
"""


def _bases(tmp_path) -> list[Path]:
    cart = tmp_path / "cart.urdf"
    cart.write_text(BASE_ONLY)
    bases = [cart]
    try:
        import pybullet_data
    except ImportError:
        return bases
    return [*bases, Path(pybullet_data.getDataPath()) / "husky" / "husky.urdf"]


def test_list_frames_without_candidates_says_so_and_what_to_do(tmp_path, capfd):
    for base in _bases(tmp_path):
        code, out, err = run_cli(capfd, "init-spec", base, "--list-frames")
        assert code == 0, err
        assert not re.search(r"^\d+ candidate", out, re.M), out  # no count over an empty list
        assert out.startswith(f"no candidate end-effector frames in {base}:"), out
        assert "no arm" in out and "actuated joint" in out, out
        assert f"mobmanip init-spec --mount ARM.urdf --on {base} --at X,Y,Z,YAW" in out, out  # what to do


def test_list_frames_counts_one_candidate_in_the_singular(tmp_path, capfd):
    one_joint = BASE_ONLY.replace(
        '<joint name="camera_joint" type="fixed">',
        '<joint name="camera_joint" type="revolute"><limit lower="-1" upper="1" velocity="1" effort="1"/>',
    )
    path = tmp_path / "pan.urdf"
    path.write_text(one_joint)
    code, out, err = run_cli(capfd, "init-spec", path, "--list-frames")
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == f"1 candidate end-effector frame of {path} (for --ee), the most likely first:", out
    assert [line.split()[0] for line in lines[1:]] == ["camera"], out


@pytest.mark.parametrize("duration", [0.5, 2])
def test_view_with_a_duration_says_how_long_it_serves(capfd, duration):
    started = time.monotonic()
    code, out, err = run_cli(capfd, "view", "planar_dual_arm", "--no-locked", "--duration", duration)
    elapsed = time.monotonic() - started
    assert code == 0, err
    line = next(x for x in out.splitlines() if x.startswith("meshcat viewer:"))
    assert f"serving for {duration:g} s" in line, line
    assert "Ctrl-C to stop" not in line, line
    assert elapsed >= duration  # it did serve that long, as it said
    assert "stopped the meshcat server" in err
