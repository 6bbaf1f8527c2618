"""Hostile recordings: ``trajectory --bag`` honours ``--max-work`` (the joint-state messages are
counted from the bag's index, or in the part --start/--end keep, before any is decoded), and NaN
or infinite positions are never dropped without a word: a stream of nothing but NaN says so, one
inf is a warning naming the joint, the value and when."""

from __future__ import annotations

import time

import numpy as np
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.errors import ArgumentError, RecordingError
from mobmanip.motion import recordings
from mobmanip.motion.recordings import read_recording
from mobmanip.support.work import WorkBound
from test_recordings import ARM, ROBOT, T0, WHEELS, motion, motion_records, write_bag


@pytest.fixture(scope="module")
def robot():
    return mobmanip.load_robot(ROBOT)


@pytest.fixture(scope="module")
def long_bags(tmp_path_factory):
    """400 joint states (and odometry) at 50 Hz in each storage format."""
    folder = tmp_path_factory.mktemp("bags")
    t = np.arange(400) * 0.02
    values = motion(t)
    return {
        kind: write_bag(folder / kind, kind, motion_records(kind, t, values)[0]) for kind in ("ros1", "mcap", "db3")
    }


@pytest.mark.parametrize("kind", ["ros1", "mcap", "db3"])
def test_max_work_bounds_a_recording_before_any_message_is_decoded(capfd, monkeypatch, long_bags, kind):
    decoded = []
    original = recordings._deserialize
    monkeypatch.setattr(recordings, "_deserialize", lambda *a: decoded.append(1) or original(*a))
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", long_bags[kind], "--max-work", "100")
    assert_one_line_error(code, err, "400 samples", "joint-state messages on '/joint_states'",
                          long_bags[kind].name, "more than the 100 samples", "--max-work N")  # fmt: skip
    assert decoded == [] and out == ""


def test_the_default_bound_holds_for_recordings(capfd, monkeypatch, long_bags):
    """The default (MAX_SAMPLES) applies to a bag as to a CSV file: lowered here so that a small
    bag crosses it."""
    from mobmanip.commands import trajectory

    monkeypatch.setattr(trajectory, "MAX_SAMPLES", 399)
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", long_bags["mcap"])
    assert_one_line_error(code, err, "400 samples", "more than the 399 samples", "--max-work N")
    monkeypatch.setattr(trajectory, "MAX_SAMPLES", 400)
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", long_bags["mcap"], "--odom", "none")
    assert code == 0, err
    assert "400 samples on the joint states' time base" in out


def test_a_cut_is_counted_in_the_part_read_and_stops_past_the_bound(robot, long_bags, monkeypatch, capfd):
    """With --start/--end the index's total does not apply: the part read is counted (2.0 .. 5.0 s
    at 50 Hz: 151 messages), and counting stops one past the bound."""
    bag = long_bags["ros1"]
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag, "--start", "2", "--end", "5",
                             "--max-work", "150")  # fmt: skip
    assert_one_line_error(code, err, "151 samples", "between --start and --end", "more than the 150 samples")
    counted = []
    original = recordings._count_messages
    monkeypatch.setattr(recordings, "_count_messages", lambda *a: counted.append(original(*a)) or counted[-1])
    with pytest.raises(ArgumentError, match=r"11 samples .*counted up to one past the bound"):
        read_recording(robot, bag, start=2.0, end=5.0, work=WorkBound("trajectory", "samples", 0.003, 10))
    assert counted == [(11, False)]
    recording = read_recording(robot, bag, start=2.0, end=5.0, work=WorkBound("trajectory", "samples", 0.003, 151))
    assert recording.report.samples == 151


def test_an_index_that_declares_too_few_messages_is_caught_while_reading(robot, long_bags, monkeypatch):
    monkeypatch.setattr(recordings, "_count_messages", lambda *a: (5, True))
    with pytest.raises(ArgumentError, match=r"101 samples .*more than its index declares.*more than the 100"):
        read_recording(robot, long_bags["db3"], work=WorkBound("trajectory", "samples", 0.003, 100))


def test_a_large_recording_is_refused_in_time(capfd, tmp_path):
    """20,000 joint states (no odometry): refused from the index in well under a second of
    reading (decoding and resampling them all took minutes at 300,000)."""
    m_records, _ = motion_records("mcap", np.arange(3) * 0.02, motion(np.arange(3) * 0.02))
    template = m_records[0][2]
    from test_recordings import Messages

    m = Messages(2)
    records = [("/joint_states", T0 * 1_000_000_000 + k * 1_000_000, m.joint_state(T0 * 1_000_000_000 + k * 1_000_000,
                template.name, template.position)) for k in range(20_000)]  # fmt: skip
    bag = write_bag(tmp_path / "big", "mcap", records)
    started = time.perf_counter()
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag, "--odom", "none", "--max-work", "1000")
    seconds = time.perf_counter() - started
    assert_one_line_error(code, err, "20,000 samples", "more than the 1,000 samples")
    assert seconds < 3.0, seconds


def _bag_with(tmp_path, kind, change):
    """A 60-sample bag whose joint-state positions pass through ``change(i, name, value)``."""
    t = np.arange(60) * 0.02
    values = motion(t)
    for name in WHEELS + ARM:
        values[name] = np.array([change(i, name, v) for i, v in enumerate(values[name])])
    return write_bag(tmp_path / "run", kind, motion_records(kind, t, values)[0])


@pytest.mark.parametrize("kind", ["ros1", "mcap", "db3"])
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_a_recording_of_nothing_but_nan_says_so(capfd, tmp_path, kind, bad):
    bag = _bag_with(tmp_path, kind, lambda i, name, v: bad)
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag)
    line = assert_one_line_error(code, err, str(bag), "every position on '/joint_states'", "NaN or infinite",
                                 "480 values", "wheel_right_joint", "arm_left_3_joint")  # fmt: skip
    assert "name none" not in line


@pytest.mark.parametrize(("value", "shown"), [(float("inf"), "inf"), (float("nan"), "nan"), (-float("inf"), "-inf")])
def test_one_non_finite_position_is_a_warning_naming_it(robot, capfd, tmp_path, value, shown):
    bag = _bag_with(tmp_path, "mcap", lambda i, name, v: value if (i, name) == (17, "arm_right_2_joint") else v)
    report = read_recording(robot, bag).report
    assert report.dropped == (
        f"1 non-finite position(s) of arm_right_2_joint on '/joint_states' dropped (first {shown} at 0.340 s of the "
        "recording): interpolated across",
    )
    assert report.dropped[0] in report.warnings
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag)
    assert code == 0, err
    assert err.count("arm_right_2_joint") == 1 and "0.340 s" in err and shown in err
    assert "60 samples" in out  # the sample stays: the joint is interpolated there


def test_a_joint_with_no_finite_position_is_warned_to_stay_at_home(robot, tmp_path):
    bag = _bag_with(tmp_path, "ros1", lambda i, name, v: float("nan") if name == "arm_left_1_joint" else v)
    recording = read_recording(robot, bag)
    assert recording.report.dropped == (
        "every position of arm_left_1_joint on '/joint_states' is NaN or infinite (60, first nan at 0.000 s of the "
        "recording): it stays at home",
    )
    assert "arm_left_1_joint" not in recording.joints and recording.report.samples == 60
    k = robot.model.joints[robot.model.getJointId("arm_left_1_joint")].idx_q
    home = robot.configuration((0.0, 0.0, 0.0), {})[k]
    assert np.all(recording.trajectory.q[:, k] == home)
    moved = robot.model.joints[robot.model.getJointId("arm_left_2_joint")].idx_q
    assert np.ptp(recording.trajectory.q[:, moved]) > 0.05  # the others are read (0.073 over 1.2 s)


def test_non_finite_odometry_is_dropped_with_a_warning_or_refused(robot, tmp_path, capfd):
    t = np.arange(60) * 0.02
    values = motion(t)
    odom = {k: values[k].copy() for k in ("platform_x", "platform_y", "platform_yaw")}
    odom["platform_x"][30] = float("inf")
    records, _ = motion_records("mcap", t, values, odom_t=t, odom_values=odom)
    report = read_recording(robot, write_bag(tmp_path / "one", "mcap", records)).report
    assert len(report.dropped) == 1 and report.dropped[0].startswith(
        "1 non-finite pose(s) on '/odom' dropped (first (inf,"
    )
    assert "0.600 s" in report.dropped[0]
    odom["platform_y"][:] = float("nan")
    records, _ = motion_records("mcap", t, values, odom_t=t, odom_values=odom)
    bag = write_bag(tmp_path / "all", "mcap", records)
    with pytest.raises(RecordingError, match=r"every pose on '/odom' is NaN or infinite \(60 messages\)"):
        read_recording(robot, bag)


@pytest.mark.parametrize(
    ("argv", "needles"),
    [
        (["--start", "nan"], ("--start must be a finite number of seconds", "got nan")),
        (["--start", "inf"], ("--start must be a finite number of seconds", "got inf")),
        (["--end=-inf"], ("--end must be a finite number of seconds", "got -inf")),
        (["--start", "1e300"], ("no joint-state messages on '/joint_states' in the part read",)),
        (["--end=-1e300"], ("no joint-state messages on '/joint_states' in the part read",)),
    ],
)
def test_a_cut_that_is_not_finite_or_far_off_is_one_line(capfd, long_bags, argv, needles):
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", long_bags["ros1"], *argv)
    assert_one_line_error(code, err, *needles)
