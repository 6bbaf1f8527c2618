"""Hostile input, round 2: robot files (URDF, xacro, MJCF and the files they include), recordings
(ROS bags, MCAP files, ROS 2 bag folders) and configurations go through the bounded reader. A FIFO
or ``/dev/zero`` is refused at once in one line, never opened; a file over the bound is refused
with its size and the bound, never read.

The bounds are the documented ones, written here independently of the code: a robot file and
its includes 64 MiB together, a recording 64 GiB. Oversized files are sparse (``truncate``), so
they cost no disk.
"""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import pytest

from hostile_util import PAPER_URDF_TEXT, assert_one_line_error, run_cli, write_robot

ROBOT_BOUND = 64 * 1024 * 1024
RECORDING_BOUND = 64 * 1024**3
NOT_REGULAR = "not a regular file"


@pytest.fixture
def fifo(tmp_path):
    """A FIFO factory. Should a reader open one, a writer opens and closes it after 20 s, so the
    reader sees its end and the test fails on time instead of hanging."""
    made: list[Path] = []

    def make(name: str) -> Path:
        path = tmp_path / name
        os.mkfifo(path)
        made.append(path)
        return path

    done = threading.Event()

    def unblock():
        if not done.wait(20):
            for path in made:
                fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK) if _has_reader(path) else None
                if fd is not None:
                    os.close(fd)

    thread = threading.Thread(target=unblock, daemon=True)
    thread.start()
    yield make
    done.set()


def _has_reader(path: Path) -> bool:
    try:
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        return True
    except OSError:  # ENXIO: nobody has it open for reading
        return False


def _refused_at_once(capfd, *argv, needles=()) -> str:
    start = time.monotonic()
    code, out, err = run_cli(capfd, *argv)
    assert time.monotonic() - start < 10, "took as long as the guard: the file was opened"
    assert out == ""
    return assert_one_line_error(code, err, *needles)


def _zero_link(tmp_path: Path, name: str) -> Path:
    link = tmp_path / name
    link.symlink_to("/dev/zero")
    return link


def _sparse(tmp_path: Path, name: str, size: int) -> Path:
    path = tmp_path / name
    with open(path, "wb") as handle:
        handle.truncate(size)
    return path


@pytest.mark.parametrize("name", ["robot.urdf", "robot.urdf.xacro", "robot.xml"])
def test_a_fifo_or_dev_zero_as_the_robot_file_is_refused_at_once(tmp_path, capfd, fifo, name):
    for path in (fifo(name), _zero_link(tmp_path / "..", f"{tmp_path.name}-zero-{name}")):
        _refused_at_once(capfd, "analyze", "--urdf", path, "--ee", "tool", needles=(path.name, NOT_REGULAR))


@pytest.mark.parametrize("name", ["robot.urdf", "robot.urdf.xacro", "robot.xml"])
def test_an_oversized_robot_file_is_refused_with_its_size_and_the_bound(tmp_path, capfd, name):
    path = _sparse(tmp_path, name, ROBOT_BOUND + 1)
    _refused_at_once(
        capfd, "analyze", "--urdf", path, "--ee", "tool", needles=(name, str(ROBOT_BOUND + 1), str(ROBOT_BOUND))
    )


def test_a_robot_file_at_the_bound_is_read(tmp_path, capfd):
    """The bound is inclusive and content, not size, decides below it: the paper robot padded with
    blanks to exactly 64 MiB is analysed."""
    text = PAPER_URDF_TEXT.encode()
    path = tmp_path / "padded.urdf"
    path.write_bytes(text + b" " * (ROBOT_BOUND - len(text)))
    assert path.stat().st_size == ROBOT_BOUND
    spec = write_robot(tmp_path)
    spec.write_text(spec.read_text().replace("robot.urdf", "padded.urdf"))
    code, _, err = run_cli(capfd, "analyze", spec)
    assert code == 0, err


def test_a_spec_naming_a_fifo_as_its_urdf_is_refused_at_once(tmp_path, capfd, fifo):
    spec = write_robot(tmp_path)
    (tmp_path / "robot.urdf").unlink()
    fifo("robot.urdf")
    _refused_at_once(capfd, "analyze", spec, needles=("robot.urdf", NOT_REGULAR))


XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="x">
  <xacro:include filename="{include}"/>
  <link name="base_link"/>
</robot>
"""


def test_xacro_includes_count_against_the_bound_together(tmp_path, capfd):
    """Two includes of 40 MiB each are each under the bound, together over it (the first is valid
    xacro padded with blanks, so that the second is reached)."""
    part = b'<robot xmlns:xacro="http://www.ros.org/wiki/xacro"/>'
    (tmp_path / "a.xacro").write_bytes(part + b" " * (40 * 1024 * 1024 - len(part)))
    _sparse(tmp_path, "b.xacro", 40 * 1024 * 1024)
    robot = tmp_path / "robot.urdf.xacro"
    robot.write_text(XACRO.format(include="a.xacro").replace("<link", '<xacro:include filename="b.xacro"/><link'))
    _refused_at_once(capfd, "analyze", "--urdf", robot, "--ee", "tool", needles=("b.xacro", str(ROBOT_BOUND)))


MJCF = """<mujoco model="m">
  <include file="{include}"/>
  <worldbody><body name="base"><geom type="box" size="0.1 0.1 0.1"/></body></worldbody>
</mujoco>
"""


#: Per language that includes files: the robot file, the template of its text, the included
#: file's name and what the message says of a huge one (the MJCF reader also names its size).
INCLUDING = {
    "xacro": ("robot.urdf.xacro", XACRO, "part.xacro", (str(ROBOT_BOUND),)),
    "mjcf": ("robot.xml", MJCF, "part.xml", (str(ROBOT_BOUND + 1), str(ROBOT_BOUND))),
}


@pytest.mark.parametrize("language", INCLUDING)
@pytest.mark.parametrize("kind", ["fifo", "zero", "huge"])
def test_a_file_a_robot_file_includes_is_refused_as_a_fifo_dev_zero_or_huge(tmp_path, capfd, fifo, language, kind):
    name, template, part, huge = INCLUDING[language]
    include = {
        "fifo": lambda: fifo(part),
        "zero": lambda: _zero_link(tmp_path, part),
        "huge": lambda: _sparse(tmp_path, part, ROBOT_BOUND + 1),
    }[kind]()
    robot = tmp_path / name
    robot.write_text(template.format(include=include.name))
    needles = (part, *huge) if kind == "huge" else (part, NOT_REGULAR)
    _refused_at_once(capfd, "analyze", "--urdf", robot, "--ee", "tool", needles=needles)


@pytest.mark.parametrize("name", ["run.bag", "run.mcap", "run.db3"])
def test_a_fifo_or_dev_zero_as_a_recording_is_refused_at_once(tmp_path, capfd, fifo, name):
    for path in (fifo(name), _zero_link(tmp_path, f"zero-{name}"), Path("/dev/zero")):
        _refused_at_once(capfd, "trajectory", "planar_dual_arm", "--bag", path, needles=(str(path), NOT_REGULAR))


@pytest.mark.parametrize("name", ["run.bag", "run.mcap"])
def test_an_oversized_recording_is_refused_with_its_size_and_the_bound(tmp_path, capfd, name):
    path = _sparse(tmp_path, name, RECORDING_BOUND + 1)
    _refused_at_once(
        capfd,
        "trajectory",
        "planar_dual_arm",
        "--bag",
        path,
        needles=(name, str(RECORDING_BOUND + 1), str(RECORDING_BOUND)),
    )


def test_a_bag_folder_holding_a_fifo_or_too_much_is_refused(tmp_path, capfd, fifo):
    folder = tmp_path / "bag"
    folder.mkdir()
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    os.mkfifo(folder / "bag_0.db3")
    _refused_at_once(capfd, "trajectory", "planar_dual_arm", "--bag", folder, needles=("bag_0.db3", NOT_REGULAR))
    (folder / "bag_0.db3").unlink()
    for k in range(2):
        _sparse(folder, f"bag_{k}.mcap", RECORDING_BOUND // 2 + 1)
    _refused_at_once(
        capfd, "trajectory", "planar_dual_arm", "--bag", folder, needles=("bag_1.mcap", str(RECORDING_BOUND))
    )


def test_a_fifo_or_dev_zero_as_a_configuration_is_refused_at_once(tmp_path, capfd, fifo):
    for path in (fifo("q.json"), Path("/dev/zero")):
        _refused_at_once(capfd, "analyze", "planar_dual_arm", "--q", path, needles=(str(path), NOT_REGULAR))
