"""Hostile input, round 2 (classes 4, 7 and 8): one bounded reader for the user's files. Devices,
huge files and huge fields are refused quickly in one line; paths inside a file resolve against
that file; numbers are checked with the file, line and column named, and no message shows an
internal array or a bare ``nan``."""

from __future__ import annotations

import os
import re
import time
from pathlib import Path

import pytest

from hostile_util import ROOT, assert_one_line_error, run_cli, write_robot
from mobmanip.errors import ArgumentError
from mobmanip.support.reading import read_csv_rows, read_user_text, resolve_beside

TEAM_TEXT = (ROOT / "examples" / "beam_team.toml").read_text()
ARRAY_TEXT = re.compile(r"array\(|np\.float64|\bnan\b", re.IGNORECASE)


def _team(directory: Path, robot: str, name: str = "team.toml", **edits) -> Path:
    text = TEAM_TEXT.replace('robot = "planar_dual_arm"', f'robot = "{robot}"')
    for old, new in edits.items():
        assert old in text
        text = text.replace(old, new, 1)
    path = directory / name
    path.write_text(text)
    return path


def _no_internals(line: str) -> None:
    assert not ARRAY_TEXT.search(line), line


def test_a_team_robot_path_resolves_against_the_team_file(tmp_path, capfd, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write_robot(tmp_path, name="r")  # ./r.toml exists in the current folder ...
    sub = tmp_path / "sub"
    sub.mkdir()
    team = _team(sub, "r.toml")  # ... but sub/team.toml names sub/r.toml, which does not
    code, out, err = run_cli(capfd, "team", team)
    assert_one_line_error(code, err, str(sub / "r.toml"))
    assert out == ""
    for reference in ("./r.toml", "../sub/r.toml", "nested/r.toml"):
        code, _, err = run_cli(capfd, "team", _team(sub, reference))
        assert_one_line_error(code, err, "r.toml")
    write_robot(sub, name="r")  # now it exists beside the team file: used
    code, out, err = run_cli(capfd, "team", _team(sub, "r.toml"))
    assert code == 0, err
    code, out, err = run_cli(capfd, "team", _team(sub, str(tmp_path / "r.toml")))  # absolute: as given
    assert code == 0, err
    assert resolve_beside("x/y.toml", "/a/b/team.toml") == Path("/a/b/x/y.toml")


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom", "fifo", "directory"])
def test_devices_fifos_and_directories_as_robot_files_are_refused_at_once(tmp_path, capfd, device):
    special = {"fifo": tmp_path / "f.toml", "directory": tmp_path / "d.toml"}.get(device, Path(device))
    if device == "fifo":
        os.mkfifo(special)
    elif device == "directory":
        special.mkdir()
    started = time.monotonic()
    code, _, err = run_cli(capfd, "team", _team(tmp_path, str(special)))
    assert_one_line_error(code, err)
    assert time.monotonic() - started < 10
    for argv in (("analyze", special), ("team", special)):
        code, _, err = run_cli(capfd, *argv)
        assert_one_line_error(code, err)
    assert time.monotonic() - started < 20


@pytest.mark.parametrize("kind", ["carry", "trajectory"])
@pytest.mark.parametrize("size", [2_000, 131_072, 1_000_000])
def test_huge_csv_fields_are_one_clear_line(tmp_path, capfd, kind, size):
    path = tmp_path / "p.csv"
    if kind == "carry":
        path.write_text("t,x,y\n0,0,0\n1,0," + "1" * size + "\n")
        argv = ("carry", "planar_dual_arm", "--path", path)
    else:
        path.write_text("t,platform_x,platform_y,platform_yaw\n0,0,0,0\n1,0,0," + "2" * size + "\n")
        argv = ("trajectory", "planar_dual_arm", path)
    code, _, err = run_cli(capfd, *argv)
    assert_one_line_error(code, err, "line 3", "longer than")
    quoted = tmp_path / "q.csv"
    quoted.write_text('t,x,y\n0,0,"' + "a\n" * size)  # an unterminated quoted field
    with pytest.raises(ArgumentError, match="line"):
        read_csv_rows(quoted, "object path")


def test_file_size_is_bounded(tmp_path):
    path = tmp_path / "big.csv"
    path.write_bytes(b"t,x,y\n" + b"0,0,0\n" * 1000)
    with pytest.raises(ArgumentError, match="more than the 100 this reads"):
        read_user_text(path, "object path", limit=100)


@pytest.mark.parametrize(
    ("rows", "needles"),
    [
        ("0,0,0\n1,1e308,0\n", ["line 3", "'x'", "1e308"]),
        ("0,0,0\n1,0,-1e308\n", ["line 3", "'y'", "-1e308"]),
        ("0,0,0\n1,0,inf\n", ["line 3", "'y'", "inf"]),
        ("0,0,0\n1e-200,0.1,0\n", ["line 3", "'t'", "1e-200"]),
        ("0,0,0\n1e17,0.1,0\n", ["line 3", "'t'", "1e17"]),
        ("0,0,0\n1," + "9" * 400 + ",0\n", ["line 3", "'x'"]),
        ("0,0,0\n1,0.1,0\n1,0.2,0\n", ["line 4", "'t'"]),
    ],
)
def test_bad_numbers_in_a_path_name_file_line_and_column(tmp_path, capfd, rows, needles):
    path = tmp_path / "p.csv"
    path.write_text("t,x,y\n" + rows)
    code, _, err = run_cli(capfd, "carry", "planar_dual_arm", "--path", path)
    line = assert_one_line_error(code, err, str(path), *needles)
    _no_internals(line)


@pytest.mark.parametrize(
    ("cell", "column"),
    [("1e308", "platform_x"), ("-1e308", "platform_y"), ("1e300", "arm_right_1_joint"), ("9" * 400, "platform_x")],
)
def test_bad_numbers_in_a_trajectory_name_file_line_and_column(tmp_path, capfd, cell, column):
    header = ["t", "platform_x", "platform_y", "platform_yaw", "arm_right_1_joint"]
    values = {name: "0" for name in header}
    path = tmp_path / "m.csv"
    second = {**values, "t": "1", column: cell}
    path.write_text(",".join(header) + "\n" + ",".join(values.values()) + "\n" + ",".join(second.values()) + "\n")
    code, _, err = run_cli(capfd, "trajectory", "planar_dual_arm", path)
    line = assert_one_line_error(code, err, str(path), "line 3", repr(column))
    _no_internals(line)


@pytest.mark.parametrize(
    ("old", "new", "needle"),
    [
        ("mass = 4.0 ", "mass = " + "9" * 400 + " ", "400 digits"),
        ("size = [1.5, 0.08, 0.08]", "size = [1e200, 0.08, 0.08]", "size"),
        ("size = [1.5, 0.08, 0.08]", "size = [1.5, " + "8" * 300 + ", 0.08]", "300 digits"),
        ("yaw_deg = 90.0 ", "yaw_deg = " + "1" * 30 + " ", "yaw_deg"),
    ],
)
def test_huge_numbers_in_a_team_file_are_named(tmp_path, capfd, old, new, needle):
    code, _, err = run_cli(capfd, "team", _team(tmp_path, "planar_dual_arm", **{old: new}))
    line = assert_one_line_error(code, err, needle)
    _no_internals(line)


def test_a_400_digit_mass_in_a_spec_is_named(tmp_path, capfd):
    spec = write_robot(tmp_path, spec_edits=[("mass = 2.0", "mass = " + "9" * 400)])
    code, _, err = run_cli(capfd, "analyze", spec)
    assert_one_line_error(code, err, "400 digits", "mass")


@pytest.mark.parametrize("option", ["--figure", "--plot"])
@pytest.mark.parametrize("suffix", ["xyz", "PNG2", "html"])
def test_unknown_figure_extensions_name_the_formats(tmp_path, capfd, option, suffix):
    target = tmp_path / f"out.{suffix}"
    if option == "--figure":
        argv = ("place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x")
    else:
        argv = ("team", ROOT / "examples" / "beam_team.toml")
    code, out, err = run_cli(capfd, *argv, option, target)
    assert_one_line_error(code, err, option, "png", "svg")
    assert out == "" and not target.exists()


@pytest.mark.parametrize(("step", "prepare"), [("1e-6", "30"), ("0", "30"), ("nan", "30"), ("0.02", "nan"),
                                               ("0.02", "-1"), ("2", "0")])  # fmt: skip
def test_carry_step_and_prepare_out_of_range_name_the_option(capfd, step, prepare):
    code, _, err = run_cli(capfd, "carry", "planar_dual_arm", "--path", ROOT / "examples" / "carry_line.csv",
                           "--step", step, "--prepare", prepare)  # fmt: skip
    line = assert_one_line_error(code, err)
    assert "--step" in line or "--prepare" in line, line


def test_a_file_larger_than_its_reported_size_is_refused_not_cut_short():
    """A regular file whose reported size is below the limit but whose content is above it (the
    kernel's own files report 0 bytes; a file may also grow between the check and the read): the
    bounded reader reads one byte past the limit and refuses the file, naming the limit, where
    reading only up to the limit would cut it short without a word."""
    import os
    import stat as stat_module

    from mobmanip.errors import ArgumentError
    from mobmanip.support.reading import read_bounded

    path = "/proc/self/status"
    if not os.path.exists(path) or not stat_module.S_ISREG(os.stat(path).st_mode) or os.stat(path).st_size != 0:
        pytest.skip("needs a regular file whose reported size is 0 (Linux procfs)")
    with pytest.raises(ArgumentError, match="grew to more than the 16 bytes"):
        read_bounded(path, limit=16, refuse=ArgumentError)
    assert len(read_bounded(path, limit=1 << 20, refuse=ArgumentError)) > 16  # within the limit: read whole


def test_a_file_that_grows_after_its_size_is_checked_is_refused_not_cut_short(tmp_path, monkeypatch):
    """Anywhere (not only where procfs reports 0 bytes): a file of exactly the limit passes the
    size check and then grows by four bytes before it is read. The reader refuses it, naming the
    limit, rather than returning its first 16 bytes; a file of exactly the limit that stays so is
    read whole."""
    from mobmanip.support import reading

    path = tmp_path / "growing.txt"
    path.write_bytes(b"0123456789abcdef")
    checked = reading.file_refusal

    def check_then_grow(where, *, limit):
        reason = checked(where, limit=limit)
        with open(where, "ab") as handle:
            handle.write(b"more")
        return reason

    assert reading.read_bounded(path, limit=16, refuse=ArgumentError) == b"0123456789abcdef"
    monkeypatch.setattr(reading, "file_refusal", check_then_grow)
    with pytest.raises(ArgumentError, match="grew to more than the 16 bytes"):
        reading.read_bounded(path, limit=16, refuse=ArgumentError)
