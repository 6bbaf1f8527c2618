"""Hostile and broken input (2): outputs never replace inputs, keep an existing file's
permissions, refuse special files, and a command publishes all its files or none."""

from __future__ import annotations

import json
import os
import stat

import numpy as np
import pytest

from hostile_util import PAPER_URDF_TEXT, assert_one_line_error, run_cli, write_robot
from mobmanip.errors import OutputError
from mobmanip.support.files import atomic_output, protect_inputs, publish_together, write_json, write_text


def _snapshot(*paths):
    return {p: (p.read_bytes(), stat.S_IMODE(os.stat(p).st_mode)) for p in paths}


def test_init_spec_out_equal_to_its_urdf_is_refused(tmp_path, capfd):
    urdf = tmp_path / "r.urdf"
    urdf.write_text(PAPER_URDF_TEXT)
    before = _snapshot(urdf)
    code, _, err = run_cli(capfd, "init-spec", urdf, "--ee", "arm_right_tool_link", "--out", urdf)
    assert_one_line_error(code, err, "input", str(urdf))
    assert _snapshot(urdf) == before


@pytest.mark.parametrize("which", ["q", "spec", "urdf"])
def test_analyze_json_onto_any_of_its_inputs_is_refused(tmp_path, capfd, which):
    spec = write_robot(tmp_path)
    q = tmp_path / "q.json"
    q.write_text(json.dumps({"platform": [0, 0, 0], "joints": {"arm_right_2_joint": 0.5}}))
    target = {"q": q, "spec": spec, "urdf": spec.with_suffix(".urdf")}[which]
    link = tmp_path / "alias.json"
    link.symlink_to(target)  # the same file under another name
    before = _snapshot(q, spec, spec.with_suffix(".urdf"))
    for out in (target, link):
        code, _, err = run_cli(capfd, "analyze", spec, "--q", q, "--json", out)
        assert_one_line_error(code, err, "input")
    assert _snapshot(q, spec, spec.with_suffix(".urdf")) == before


def test_an_existing_file_keeps_its_permissions(tmp_path):
    for mode in (0o600, 0o640, 0o444 | 0o200):
        path = tmp_path / f"out{mode:o}.json"
        path.write_text("{}")
        os.chmod(path, mode)
        write_json(path, {"a": 1})
        assert stat.S_IMODE(os.stat(path).st_mode) == mode
        assert json.loads(path.read_text()) == {"a": 1}
    fresh = tmp_path / "fresh.json"
    write_json(fresh, {})
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(os.stat(fresh).st_mode) == 0o666 & ~umask


def test_a_symlink_to_a_regular_file_is_followed(tmp_path):
    target = tmp_path / "target.json"
    target.write_text("{}")
    os.chmod(target, 0o600)
    link = tmp_path / "link.json"
    link.symlink_to(target)
    write_json(link, [1, 2])
    assert link.is_symlink() and json.loads(target.read_text()) == [1, 2]
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o600


def test_special_files_are_refused_and_left_alone(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    to_fifo = tmp_path / "to_fifo"
    to_fifo.symlink_to(fifo)
    to_null = tmp_path / "to_null"
    to_null.symlink_to(os.devnull)
    for path, kind in ((fifo, "FIFO"), (to_fifo, "FIFO"), (to_null, "character device"), (tmp_path, "directory")):
        with pytest.raises(OutputError, match=kind):
            write_text(path, "x")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and stat.S_ISCHR(os.stat(os.devnull).st_mode)
    assert to_fifo.is_symlink() and to_null.is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "to_fifo", "to_null"]  # no temporaries


def test_dev_null_on_the_command_line_is_one_line(capfd):
    code, _, err = run_cli(capfd, "analyze", "planar_dual_arm", "--json", os.devnull)
    assert_one_line_error(code, err, os.devnull, "character device")
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode)


def test_publish_together_publishes_all_or_none(tmp_path):
    old = {"a.txt": "old a", "b.txt": "old b"}
    for name, text in old.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(OutputError):
        with publish_together():
            write_text(tmp_path / "a.txt", "new a")
            write_text(tmp_path / "c.txt", "new c")
            write_text(tmp_path / "missing" / "b.txt", "new b")  # unwritable: nothing is published
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == old
    with pytest.raises(RuntimeError):
        with publish_together():
            write_text(tmp_path / "a.txt", "new a")
            raise RuntimeError("fails midway")
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == old
    with publish_together():
        write_text(tmp_path / "a.txt", "new a")
        write_text(tmp_path / "c.txt", "new c")
        assert (tmp_path / "a.txt").read_text() == "old a"  # not yet
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"a.txt": "new a", "b.txt": "old b", "c.txt": "new c"}


def test_a_failed_rename_restores_what_was_published(tmp_path, monkeypatch):
    (tmp_path / "a.txt").write_text("old a")
    (tmp_path / "b.txt").write_text("old b")
    real_replace = os.replace

    def failing(src, dst):
        if str(dst).endswith("b.txt") and str(src).endswith(".tmp"):
            raise PermissionError(13, "Permission denied")
        return real_replace(src, dst)

    with pytest.raises(OutputError, match="no output was changed"):
        with publish_together():
            write_text(tmp_path / "a.txt", "new a")
            write_text(tmp_path / "b.txt", "new b")
            monkeypatch.setattr(os, "replace", failing)
    monkeypatch.undo()
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"a.txt": "old a", "b.txt": "old b"}


def test_a_sweep_with_one_unwritable_output_changes_no_output(tmp_path, capfd):
    npz = tmp_path / "sweep.npz"
    npz.write_bytes(b"previous result")
    csv = tmp_path / "sweep.csv"
    csv.mkdir()  # the CSV cannot be written: a directory is in the way
    code, _, err = run_cli(
        capfd, "sweep", "planar_dual_arm", "--angle", "0,90", "--distance", "1.0", "--workers", "1", "--no-progress",
        "-o", tmp_path,
    )  # fmt: skip
    assert_one_line_error(code, err, "sweep.csv", "directory")
    assert npz.read_bytes() == b"previous result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.csv", "sweep.npz"]


def test_outputs_outside_a_command_may_replace_files_read_before(tmp_path):
    # The protection covers the inputs of one command; a library user may rewrite a file.
    path = tmp_path / "q.json"
    path.write_text("{}")
    with protect_inputs():
        pass
    with atomic_output(path) as handle:
        handle.write("[]")
    assert np.array_equal(json.loads(path.read_text()), [])


def test_a_bad_output_file_is_refused_before_any_work(tmp_path, capsys):
    """Nothing is computed or printed when the output would replace an input or is a device."""
    from mobmanip.cli import main

    q = tmp_path / "q.json"
    q.write_text('{"platform": [0, 0, 0]}')
    for argv in (
        ["analyze", "planar_dual_arm", "--q", str(q), "--json", str(q)],
        ["analyze", "planar_dual_arm", "--json", "/dev/null"],
        ["analyze", "planar_dual_arm", "--json", str(tmp_path)],
    ):
        assert main(argv) == 2
        out, err = capsys.readouterr()
        assert out == ""
        assert err.startswith("mobmanip: error: ") and err.count("\n") == 1
    assert q.read_text() == '{"platform": [0, 0, 0]}'
