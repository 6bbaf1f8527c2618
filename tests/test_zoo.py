"""The robot zoo (issue 25, item 4): every robot with an arm in example-robot-data and in
pybullet's data, and the Menagerie models this project ships as fixtures, goes through
``init-spec`` and ``analyze`` with no hand edits, or stops with one message naming exactly what is
missing and the flag that supplies it. The table in ``docs/howto/robot-zoo.md`` lists each robot's
platform kind, what was repaired and what the user must supply; this test checks it row by row
(run ``python tests/test_zoo.py`` to print the rows measured).

Left out, having no arm: the quadrupeds and humanoids' legs-only files (a1, go1, go2, b1, solo,
hyq, laikago, anymal, bolt, alexander lower body), hands (allegro), drones and flying arms (iris,
hector, borinot, hextilt), pendulums and toys (double_pendulum, asr_twodof, finger_edu, quadruped,
human, simple_humanoid), husky (a base); ``ur3.urdf`` (an empty wrapper of ``ur3_robot.urdf``).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "tests") not in sys.path:  # run as a script
    sys.path.insert(0, str(ROOT / "tests"))

from hostile_util import run_cli  # noqa: E402

TABLE = ROOT / "docs" / "howto" / "robot-zoo.md"

#: Per source, (robot, file under the source, end effectors).
SOURCES = {
    "example-robot-data": [
        ("panda", "panda_description/urdf/panda.urdf", ["panda_hand_tcp"]),
        ("ur3", "ur_description/urdf/ur3_robot.urdf", ["tool0"]),
        ("ur5", "ur_description/urdf/ur5_robot.urdf", ["tool0"]),
        ("ur10", "ur_description/urdf/ur10_robot.urdf", ["tool0"]),
        ("kinova", "kinova_description/robots/kinova.urdf", ["j2s6s200_end_effector"]),
        ("xarm7", "xarm_description/urdf/xarm7.urdf", ["link_eef"]),
        ("z1", "z1_description/urdf/z1.urdf", ["gripperStator"]),
        ("so100", "so_arm_description/urdf/so100.urdf", ["gripper"]),
        ("so101", "so_arm_description/urdf/so101.urdf", ["gripper_frame_link"]),
        ("tiago", "tiago_description/robots/tiago.urdf", ["hand_tool_link"]),
        ("tiago_no_hand", "tiago_description/robots/tiago_no_hand.urdf", ["arm_tool_link"]),
        ("tiago_dual", "tiago_description/robots/tiago_dual.urdf", ["arm_right_tool_link", "arm_left_tool_link"]),
        ("tiago_pro", "tiago_pro_description/robots/tiago_pro.urdf", ["arm_right_tool_link", "arm_left_tool_link"]),
        ("pr2", "pr2_description/urdf/pr2.urdf", ["r_gripper_tool_frame", "l_gripper_tool_frame"]),
        ("romeo", "romeo_description/urdf/romeo.urdf", ["r_gripper", "l_gripper"]),
        ("romeo_small", "romeo_description/urdf/romeo_small.urdf", ["r_gripper", "l_gripper"]),
        ("talos_left_arm", "talos_data/robots/talos_left_arm.urdf", ["wrist_left_ft_tool_link"]),
        ("talos", "talos_data/robots/talos_reduced.urdf", ["wrist_right_ft_tool_link", "wrist_left_ft_tool_link"]),
        ("baxter", "baxter_description/urdf/baxter.urdf", ["right_gripper", "left_gripper"]),
        ("b1_z1", "b1_description/urdf/b1-z1.urdf", ["gripperStator"]),
        ("anymal_kinova", "anymal_b_simple_description/robots/anymal-kinova.urdf", ["j2s6s200_end_effector"]),
        ("alex_nub_hands", "alex_description/urdf/alex_nub_hands.urdf", ["rightNub", "leftNub"]),
        ("alex_psyonic_hands", "alex_description/urdf/alex_psyonic_hands.urdf",
         ["RightWristYawIMULink", "LeftWristYawIMULink"]),
        ("centauro", "centauro_description/urdf/centauro.urdf", ["arm1_8", "arm2_8"]),
        ("g1", "g1_description/urdf/g1_29dof_rev_1_0.urdf", ["right_rubber_hand", "left_rubber_hand"]),
        ("icub", "icub_description/robots/icub_reduced.urdf", ["r_gripper", "l_gripper"]),
    ],
    "pybullet_data": [
        ("franka_panda", "franka_panda/panda.urdf", ["panda_grasptarget"]),
        ("kuka_iiwa", "kuka_iiwa/model.urdf", ["lbr_iiwa_link_7"]),
        ("xarm6", "xarm/xarm6_robot.urdf", ["link6"]),
        ("xarm6_with_gripper", "xarm/xarm6_with_gripper.urdf", ["xarm_gripper_base_link"]),
    ],
    "mujoco_menagerie": [
        ("tiago_dual (MJCF)", "menagerie_tiago_dual/tiago_dual.xml", ["arm_right_7_link", "arm_left_7_link"]),
        ("tidybot (MJCF)", "menagerie_stanford_tidybot/tidybot.xml", ["pinch_site"]),
        ("fr3_duo (MJCF)", "menagerie_franka_mobile_fr3_duo/mobile_fr3_duo.xml",
         ["left_attachment_site", "right_attachment_site"]),
        ("stretch_3 (MJCF)", "menagerie_hello_robot_stretch_3/stretch.xml", ["link_grasp_center"]),
    ],
}  # fmt: skip
#: (robot, source, file under the source, end effectors).
ZOO = [(name, source, relative, ends) for source, rows in SOURCES.items() for name, relative, ends in rows]


def robot_file(source: str, relative: str) -> Path:
    if source == "example-robot-data":
        from mobmanip.descriptions.resources import example_robot_data_share

        return example_robot_data_share() / "example-robot-data" / "robots" / relative
    if source == "pybullet_data":
        import pybullet_data

        return Path(pybullet_data.getDataPath()) / relative
    return ROOT / "tests" / "data" / relative


def outcome(capfd, folder: Path, name: str, source: str, relative: str, ends: list[str]) -> dict:
    """What init-spec and analyze say of one robot: its platform, the links repaired, and what the
    user must supply (the flags init-spec names), or "nothing"."""
    path = robot_file(source, relative)
    spec = folder / (re.sub(r"\W+", "_", name) + ".toml")
    code, _, err = run_cli(capfd, "init-spec", path, *[a for end in ends for a in ("--ee", end)], "--out", spec)
    assert code == 0, err
    platform = re.search(r'^platform = "(\w+)"', spec.read_text(), re.M).group(1)
    supply = sorted(set(re.findall(r"\((--[\w-]+)[^)]*\)", err))) if err else []
    assert (not err) or err.count("\n") == 1 and err.startswith("warning: ") and supply, err
    code, out, err = run_cli(capfd, "analyze", spec)
    repaired = sorted(re.findall(r"^warning: link '([^']+)': inertia", err, re.M))
    if supply:
        # the spec is incomplete: analyze stops with one line naming a missing limit and where it goes
        lines = [line for line in err.splitlines() if not line.startswith("warning: ")]
        assert code == 2 and len(lines) == 1 and lines[0].startswith("mobmanip: error: ") and "[limits." in lines[0], (
            err
        )
    else:
        assert code == 0, err
        assert "kinematic ellipsoid" in out
    return {"platform": platform, "repaired": len(repaired), "supply": " ".join(supply) or "nothing"}


def documented() -> dict[str, dict]:
    """The rows of the docs table: robot -> platform, repaired links, what to supply."""
    rows = {}
    for line in TABLE.read_text().splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) != 6 or cells[0] in ("robot", "") or set(cells[0]) <= {"-", ":"}:
            continue
        name = cells[0].strip("`")
        supply = " ".join(sorted(re.findall(r"--[\w-]+", cells[5]))) or "nothing"
        rows[name] = {"platform": cells[3].strip("`"), "repaired": int(cells[4].split()[0]), "supply": supply}
    return rows


@pytest.mark.parametrize(("name", "source", "relative", "ends"), ZOO, ids=[row[0] for row in ZOO])
def test_every_robot_of_the_zoo_goes_through_init_spec_and_analyze(tmp_path, capfd, name, source, relative, ends):
    assert documented()[name] == outcome(capfd, tmp_path, name, source, relative, ends)


def test_the_table_lists_exactly_the_zoo():
    assert sorted(documented()) == sorted(row[0] for row in ZOO)


if __name__ == "__main__":  # print the measured rows for the docs table
    import tempfile

    class _Capture:
        def readouterr(self):
            return "", ""

    import contextlib
    import io

    from mobmanip.cli import main

    def run(*argv):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main([str(a) for a in argv])
            except SystemExit as exc:
                code = exc.code
        return code, out.getvalue(), err.getvalue()

    globals()["run_cli"] = lambda capfd, *argv: run(*argv)
    with tempfile.TemporaryDirectory() as folder:
        for name, source, relative, ends in ZOO:
            found = outcome(None, Path(folder), name, source, relative, ends)
            print(f"| `{name}` | {source} | {', '.join(f'`{e}`' for e in ends)} | `{found['platform']}` | "
                  f"{found['repaired']} | {found['supply']} |")  # fmt: skip
