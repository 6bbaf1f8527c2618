"""Small defects a hostile pass found (issue 25, item 6): joint names TOML can hold round-trip
through init-spec (the rest are refused with a message); a URDF with a DTD is refused, because
Pinocchio's parser and Python's read its entities differently; a ``sweep -o`` that cannot be its
output folder is refused before any work."""

from __future__ import annotations

import time
from xml.sax.saxutils import quoteattr

import numpy as np
import pytest

import mobmanip
from conftest import PAPER_URDF
from hostile_util import assert_one_line_error, run_cli
from mobmanip.errors import ArgumentError
from mobmanip.robot.spec import load_spec
from mobmanip.support.toml import toml_key, toml_string

#: Joint names a URDF may give (XML 1.0 characters) that a JSON-style TOML writer got wrong or that
#: are hard for TOML: an emoji (beyond U+FFFF), DEL, the control characters XML 1.0 allows (as character
#: references, quotes, backslashes, TOML's own syntax, a combining mark, right-to-left text, spaces.
HOSTILE_NAMES = {
    "arm_right_1_joint": "arm\U0001f600right\x7f1",
    "arm_right_2_joint": 'r2 "quoted" \\ back\\slash # not a comment = [table]',
    "arm_right_3_joint": "r3\nsecond line\ttab\rreturn",
    "arm_left_1_joint": "l1 e\u0301 \u05d0\u05d1 \u00a0nbsp",
    "arm_left_2_joint": "'single' '''triple''' \"\"\"",
    "wheel_right_joint": "wheel \U0001f6de right",
}


def _xml_attribute(name: str) -> str:
    """``name`` as an XML attribute value: control characters as character references (a bare
    newline in an attribute would be read back as a space)."""
    quoted = quoteattr(name)
    return "".join(f"&#{ord(c)};" if ord(c) < 0x20 or ord(c) == 0x7F else c for c in quoted)


def _renamed_urdf(tmp_path):
    text = PAPER_URDF.read_text()
    for old, new in HOSTILE_NAMES.items():
        assert text.count(f'"{old}"') == 1, old
        text = text.replace(f'"{old}"', _xml_attribute(new))
    path = tmp_path / "hostile.urdf"
    path.write_text(text, encoding="utf-8")
    return path


def test_init_spec_round_trips_every_joint_name_toml_allows(tmp_path, capfd):
    urdf = _renamed_urdf(tmp_path)
    spec = tmp_path / "hostile.toml"
    argv = ["init-spec", urdf, "--ee", "arm_right_tool_link", "--ee", "arm_left_tool_link", "--out", spec]
    code, _, err = run_cli(capfd, *argv)
    assert code == 0, err
    loaded = load_spec(spec)
    assert loaded.wheels.right == HOSTILE_NAMES["wheel_right_joint"]
    assert loaded.arms[0].joints == tuple(HOSTILE_NAMES[f"arm_right_{k}_joint"] for k in (1, 2, 3))
    assert loaded.arms[1].joints[:2] == (HOSTILE_NAMES["arm_left_1_joint"], HOSTILE_NAMES["arm_left_2_joint"])
    # the commented notes name the joints too: none may break out of its comment line
    for line in spec.read_text(encoding="utf-8").splitlines():
        assert "\n" not in line and "\r" not in line
    robot = mobmanip.load_robot(loaded)
    paper = mobmanip.load_robot("planar_dual_arm")
    np.testing.assert_array_equal(robot.velocity_limits, paper.velocity_limits)
    # (urdfdom orders a link's children by name, so the tangent order may differ: compare results)
    ours, theirs = (mobmanip.analyze(r, r.neutral(), object_mass=2.0) for r in (robot, paper))
    np.testing.assert_allclose(ours.unified_jacobian, theirs.unified_jacobian, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours.dynamic.semi_axes, theirs.dynamic.semi_axes, rtol=1e-12)
    code, out, err = run_cli(capfd, "analyze", spec)
    assert code == 0, err


@pytest.mark.parametrize("name", [*HOSTILE_NAMES.values(), "", "plain_name", "\x00", "\U0010ffff"])
def test_toml_strings_and_keys_read_back(name):
    import tomllib

    assert tomllib.loads(f"{toml_key(name)} = {toml_string(name)}") == {name: name}


def test_a_name_toml_cannot_hold_is_refused_with_a_message():
    with pytest.raises(ArgumentError, match="lone surrogate.*U\\+D800.*rename it"):
        toml_string("arm\ud800joint")


def test_a_urdf_with_a_dtd_is_refused(tmp_path, capfd):
    """An internal entity in a link name: Python's parser expands it, urdfdom (Pinocchio) does
    not, so the two would read different robots. Refused, naming the DTD and what to do."""
    text = PAPER_URDF.read_text()
    start = text.index("<robot")
    dtd = '<!DOCTYPE robot [<!ENTITY tool "arm_right_tool_link">]>\n'
    entity = text[:start] + dtd + text[start:].replace('"arm_right_tool_link"', '"&tool;"')
    plain = text[:start] + '<!DOCTYPE robot SYSTEM "robot.dtd">\n' + text[start:]
    for name, content in (("entity.urdf", entity), ("doctype.urdf", plain)):
        path = tmp_path / name
        path.write_text(content)
        code, out, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", "arm_right_tool_link")
        assert_one_line_error(code, err, name, "DOCTYPE", "entities")
        code, _, err = run_cli(capfd, "init-spec", path, "--list-frames")
        assert_one_line_error(code, err, "DOCTYPE")


def test_a_sweep_output_that_cannot_be_its_folder_is_refused_before_any_work(tmp_path, capfd, monkeypatch):
    """``sweep -o`` names a folder (issue 39), as ``site -o`` and ``carry --out`` do. Refused in one
    line before anything is loaded: a name ending in a file suffix (the old prefix habit, naming the
    folder to give instead), a file where the folder would be, a folder whose sweep.csv is a directory."""
    import mobmanip.sweep.runner as runner

    def no_work(*args, **kwargs):
        raise AssertionError("the sweep ran before its output was checked")

    monkeypatch.setattr(runner, "run_sweep", no_work)
    monkeypatch.setattr(mobmanip.robot.model, "load_robot", no_work)
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "sweep.csv").mkdir()  # a file the folder would hold is a directory
    (tmp_path / "plain").write_text("a file, not a folder")
    for target, needles in (
        (tmp_path / "run.npz", ["-o", "run.npz", "folder", f"give -o {tmp_path / 'run'}"]),
        (tmp_path / "fig.PNG", ["fig.PNG", "folder", f"give -o {tmp_path / 'fig'}"]),
        (tmp_path / "plain", ["plain", "a file of that name exists", "folder"]),
        (tmp_path / "taken", ["sweep.csv", "directory"]),
    ):
        started = time.perf_counter()
        code, out, err = run_cli(capfd, "sweep", "planar_dual_arm", "--angle", "0:90:3", "-o", target, "--no-progress")
        assert_one_line_error(code, err, *needles)
        assert out == "" and time.perf_counter() - started < 5.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plain", "taken"]
    assert [p.name for p in (tmp_path / "taken").iterdir()] == ["sweep.csv"]
