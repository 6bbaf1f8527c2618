"""Issue 38's small ones for MJCF files: ``init-spec --list-frames`` puts a site named like a
pinch or tool point (TidyBot's ``pinch_site``) above the gripper's deeper links, and the spec's
comments and notes name the file's format, not "the URDF"."""

from __future__ import annotations

from hostile_util import run_cli
from mjcf_util import mjcf_text
from mobmanip.descriptions import read_description
from mobmanip.robot.detect import spec_to_toml
from mobmanip.robot.detect_report import candidate_frames

#: An arm ending in a bracelet with a pinch site, and a two-finger gripper below it whose links
#: are leaves further from the root (more actuated joints) than the site, as in TidyBot.
GRIPPER = mjcf_text("pincher")


def test_a_pinch_site_ranks_above_the_grippers_links(tmp_path, capfd):
    path = tmp_path / "pincher.xml"
    path.write_text(GRIPPER)
    rows = candidate_frames(read_description(path))
    names = [row[0] for row in rows]
    # a leaf named like a hand (left_finger_pad) and plain leaves are deeper, the site comes first
    assert names[0] == "pinch_site" and set(names[1:]) == {"left_finger_pad", "right_coupler"}
    code, out, err = run_cli(capfd, "init-spec", path, "--list-frames")
    assert code == 0, err
    assert out.splitlines()[1].split()[0] == "pinch_site"


def test_the_spec_names_the_files_format(tmp_path, capfd):
    path = tmp_path / "pincher.xml"
    path.write_text(GRIPPER)
    spec = tmp_path / "pincher.toml"
    code, out, err = run_cli(capfd, "init-spec", path, "--ee", "pinch_site", "--out", spec)
    assert code == 0, err
    text = spec.read_text()
    assert "REQUIRED: the MJCF file gives none" in text and "the MJCF file's value is used" in text
    assert "URDF gives none" not in text and "the URDF's value" not in text
    # the default, for a program that writes a URDF robot's spec by hand, is unchanged
    assert "the URDF's value is used" in spec_to_toml(_spec_of(spec))


def _spec_of(path):
    from mobmanip.robot.spec import load_spec

    return load_spec(path)


def test_the_platform_limits_note_names_the_files_format(tmp_path):
    from mobmanip.robot.detect import detect_spec

    path = tmp_path / "mobile.xml"
    planar = (
        '<joint name="x" type="slide" axis="1 0 0"/><joint name="y" type="slide" axis="0 1 0"/>'
        '<joint name="th" axis="0 0 1"/>\n      <inertial pos="0 0 0.1"'
    )
    path.write_text(GRIPPER.replace('<inertial pos="0 0 0.1"', planar, 1))
    found = detect_spec(path, ["pinch_site"])
    assert found.spec.platform == "omnidirectional" and found.source_format == "MJCF"
    note = next(n for n in found.notes if "needs limits for base_x" in n)
    assert note.endswith("(the MJCF file gives none)")


def test_a_missing_joint_limit_is_said_in_mjcfs_terms(tmp_path):
    import pytest

    import mobmanip
    from mobmanip.errors import MissingLimitError
    from mobmanip.robot.detect import detect_spec

    path = tmp_path / "pincher.xml"
    path.write_text(GRIPPER)
    spec = detect_spec(path, ["pinch_site"]).spec
    with pytest.raises(MissingLimitError, match="joint_1.*MJCF has no velocity limit; a velocity actuator") as caught:
        mobmanip.load_robot(spec)
    assert "URDF" not in str(caught.value).split("(with")[0]
