"""ROS recordings (issue 25, item 5): ``mobmanip trajectory ROBOT --bag RUN --joint-states TOPIC
--odom TOPIC`` reads joint states and odometry with rosbags (no ROS). The tests write real bags
with rosbags' writers (ROS 1 ``.bag``, ROS 2 ``.mcap`` and ``.db3``) and read them back: the
analysis equals that of the same motion written as the project's CSV to 1e-9; the two streams are
resampled onto the joint states' time base; gaps and clock jumps are reported; a missing topic,
another message type or joint names the robot lacks are one clear error."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.motion.recordings import GAP_FACTOR, read_recording
from mobmanip.motion.trajectory import read_trajectory
from mobmanip.motion.trajectory_analysis import analyze_trajectory

ROBOT = "planar_dual_arm"
ARM = [f"arm_{side}_{k}_joint" for side in ("right", "left") for k in (1, 2, 3)]
WHEELS = ["wheel_right_joint", "wheel_left_joint"]
WHEEL_RADIUS, HALF_TRACK = 0.075, 0.171
T0 = 1_700_000_000  # the stamps' epoch second: a real clock, far from zero


def motion(t: np.ndarray) -> dict[str, np.ndarray]:
    """A smooth whole-body motion: the platform drives a curve without slipping (its wheels turn
    as it needs), the arms swing."""
    speed, yaw_rate = 0.3 + 0.1 * np.sin(t), 0.4 * np.cos(0.7 * t)
    yaw = 0.4 / 0.7 * np.sin(0.7 * t)
    # the pose integrates (speed, yaw rate) exactly enough on a fine grid
    fine = np.linspace(0.0, t[-1], 20001)
    f_speed, f_yaw = 0.3 + 0.1 * np.sin(fine), 0.4 / 0.7 * np.sin(0.7 * fine)
    x = np.interp(t, fine, np.concatenate([[0.0], np.cumsum(np.diff(fine) * (f_speed * np.cos(f_yaw))[1:])]))
    y = np.interp(t, fine, np.concatenate([[0.0], np.cumsum(np.diff(fine) * (f_speed * np.sin(f_yaw))[1:])]))
    wheel_right = (0.3 * t + 0.1 * (1 - np.cos(t)) + HALF_TRACK * yaw) / WHEEL_RADIUS
    wheel_left = (0.3 * t + 0.1 * (1 - np.cos(t)) - HALF_TRACK * yaw) / WHEEL_RADIUS
    out = {"platform_x": x, "platform_y": y, "platform_yaw": yaw, "wheel_right_joint": wheel_right,
           "wheel_left_joint": wheel_left}  # fmt: skip
    for k, name in enumerate(ARM):
        out[name] = 0.3 * np.sin(0.8 * t + k) + (0.6 if name.endswith("2_joint") else 0.0)
    del speed, yaw_rate
    return out


def write_csv(path, t, values, joints=WHEELS + ARM):
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["t", "platform_x", "platform_y", "platform_yaw", *joints])
        for i in range(t.shape[0]):
            writer.writerow([repr(float(t[i]))] + [repr(float(values[c][i])) for c in
                            ("platform_x", "platform_y", "platform_yaw", *joints)])  # fmt: skip


class Messages:
    """JointState and Odometry messages of one ROS version, and their serialisation."""

    def __init__(self, ros: int):
        self.ros = ros
        self.store = get_typestore(Stores.ROS1_NOETIC if ros == 1 else Stores.ROS2_HUMBLE)
        self.types = self.store.types

    def header(self, ns: int, frame: str = ""):
        Header, Time = self.types["std_msgs/msg/Header"], self.types["builtin_interfaces/msg/Time"]
        stamp = Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        return Header(seq=0, stamp=stamp, frame_id=frame) if self.ros == 1 else Header(stamp=stamp, frame_id=frame)

    def joint_state(self, ns: int, names, positions):
        JointState = self.types["sensor_msgs/msg/JointState"]
        empty = np.zeros(0)
        return JointState(header=self.header(ns), name=list(names), position=np.asarray(positions, dtype=float),
                          velocity=empty, effort=empty)  # fmt: skip

    def odometry(self, ns: int, x: float, y: float, yaw: float, child: str = "base_link"):
        t = self.types
        pose = t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
        )
        zero = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
        twist = t["geometry_msgs/msg/Twist"](linear=zero, angular=zero)
        return t["nav_msgs/msg/Odometry"](
            header=self.header(ns, "odom"),
            child_frame_id=child,
            pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
            twist=t["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
        )

    def string(self, text: str):
        return self.types["std_msgs/msg/String"](data=text)

    def serialize(self, message):
        kind = message.__msgtype__
        return self.store.serialize_ros1(message, kind) if self.ros == 1 else self.store.serialize_cdr(message, kind)


def write_bag(path, kind: str, records):
    """A bag of ``records``: ``(topic, receive time ns, message)``, written with rosbags' writer.
    ``kind`` is "ros1", "mcap" or "db3"; returns the path to give --bag (the storage file)."""
    messages = Messages(1 if kind == "ros1" else 2)
    if kind == "ros1":
        writer = Writer1(path.with_suffix(".bag"))
    else:
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    connections = {}
    with writer:
        for topic, received, message in sorted(records, key=lambda r: r[1]):
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, message.__msgtype__, typestore=messages.store)
            writer.write(connections[topic], received, messages.serialize(message))
    if kind == "ros1":
        return path.with_suffix(".bag")
    return path / f"{path.name}.{kind}"


def motion_records(kind, t, values, joints=WHEELS + ARM, odom_t=None, odom_values=None, delay_ns=0):
    """Joint states at ``t`` and odometry at ``odom_t`` (default ``t``), stamped T0 + t."""
    m = Messages(1 if kind == "ros1" else 2)
    records = []
    for i, ti in enumerate(t):
        ns = T0 * 1_000_000_000 + int(round(ti * 1e9))
        records.append(("/joint_states", ns + delay_ns, m.joint_state(ns, joints, [values[j][i] for j in joints])))
    odom_t = t if odom_t is None else odom_t
    odom_values = values if odom_values is None else odom_values
    for i, ti in enumerate(odom_t):
        ns = T0 * 1_000_000_000 + int(round(ti * 1e9))
        pose = (odom_values["platform_x"][i], odom_values["platform_y"][i], odom_values["platform_yaw"][i])
        records.append(("/odom", ns + delay_ns, m.odometry(ns, *pose)))
    return records, m


@pytest.fixture(scope="module")
def robot():
    return mobmanip.load_robot(ROBOT)


def _same_analysis(robot, a, b):
    """Two trajectories give the same analysis, to 1e-9."""
    assert len(a) == len(b)
    np.testing.assert_allclose(a.t - a.t[0], b.t - b.t[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-9)
    ra, rb = (analyze_trajectory(robot, tr, "planar") for tr in (a, b))
    for field in ("velocity_use", "effort_use", "velocity_capacity", "acceleration_capacity"):
        x, y = getattr(ra, field), getattr(rb, field)
        np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-9 * max(1.0, float(np.abs(y).max())), err_msg=field)
    assert ra.scaling.k_max == pytest.approx(rb.scaling.k_max, rel=1e-9)


@pytest.mark.parametrize("kind", ["ros1", "mcap", "db3"])
def test_a_bag_gives_the_analysis_of_the_same_motion_as_csv(robot, tmp_path, capfd, kind):
    t = np.arange(80) * 0.025
    values = motion(t)
    csv_path = tmp_path / "motion.csv"
    write_csv(csv_path, t + 12.5, values)  # the CSV's clock starts elsewhere: only differences matter
    records, _ = motion_records(kind, t, values)
    bag = write_bag(tmp_path / "run", kind, records)
    recording = read_recording(robot, bag, "/joint_states", "/odom")
    assert recording.report.samples == 80 and recording.report.gaps == () and recording.report.clock_jumps == ()
    _same_analysis(robot, recording.trajectory, read_trajectory(robot, csv_path))
    # the command line: the same summary as for the CSV file
    code, from_bag, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag, "--joint-states", "/joint_states",
                                  "--odom", "/odom")  # fmt: skip
    assert code == 0, err
    code, from_csv, err = run_cli(capfd, "trajectory", ROBOT, csv_path)
    assert code == 0, err
    summary = [line for line in from_bag.splitlines() if not line.startswith(("recording ", "  "))]
    assert summary == from_csv.splitlines()
    assert f"recording {bag}" in from_bag and "80 samples" in from_bag


def test_streams_at_different_rates_are_resampled_onto_the_joint_states(robot, tmp_path):
    """Odometry at 20 Hz, offset from the joint states at 40 Hz; the platform drives straight at
    constant speed (its pose is linear in time, so interpolating it is exact) while the arms swing:
    the analysis is that of the motion sampled at the joint states' stamps, to 1e-9."""
    t = 0.1 + np.arange(81) * 0.025
    values = motion(t)
    straight = {"platform_x": 0.4 * t, "platform_y": 0.05 + 0.0 * t, "platform_yaw": 0.3 + 0.0 * t}
    values.update(straight)
    for name in WHEELS:
        values[name] = 0.4 * t / WHEEL_RADIUS
    odom_t = np.arange(35) * 0.05 + 0.313
    odom_values = {"platform_x": 0.4 * odom_t, "platform_y": 0.05 + 0.0 * odom_t, "platform_yaw": 0.3 + 0.0 * odom_t}
    records, _ = motion_records("mcap", t, values, odom_t=odom_t, odom_values=odom_values)
    recording = read_recording(robot, write_bag(tmp_path / "run", "mcap", records))
    inside = t[(t >= odom_t[0]) & (t <= odom_t[-1])]
    assert recording.report.samples == inside.shape[0] < t.shape[0]  # never extrapolated
    csv_path = tmp_path / "motion.csv"
    write_csv(csv_path, inside, {k: v[(t >= odom_t[0]) & (t <= odom_t[-1])] for k, v in values.items()})
    _same_analysis(robot, recording.trajectory, read_trajectory(robot, csv_path))


def test_start_and_end_cut_the_recording(robot, tmp_path):
    t = np.arange(100) * 0.02
    records, _ = motion_records("ros1", t, motion(t))
    bag = write_bag(tmp_path / "run", "ros1", records)
    recording = read_recording(robot, bag, start=0.5, end=1.5)
    assert recording.report.samples == 51
    assert recording.report.span == pytest.approx((0.5, 1.5), abs=1e-9)


def test_gaps_and_clock_jumps_are_reported(robot, tmp_path, capfd):
    t = np.arange(100) * 0.02
    values = motion(t)
    records, m = motion_records("mcap", t, values)
    # a gap: the joint states of 0.80 .. 1.20 s were lost
    records = [r for r in records if not (r[0] == "/joint_states" and 0.79 < (r[1] / 1e9 - T0) < 1.21)]
    # a clock jump: one joint state stamped 5 s in the past (a clock reset), received in order
    late = T0 * 1_000_000_000 + int(1.5e9)
    stale = m.joint_state(late - 5_000_000_000, WHEELS + ARM, [values[j][75] for j in WHEELS + ARM])
    records.append(("/joint_states", late + 1_000_000, stale))
    bag = write_bag(tmp_path / "run", "mcap", records)
    report = read_recording(robot, bag).report
    # 0.80 .. 1.20 s lost: 0.44 s from the message at 0.78 s to the one at 1.22 s, 22 median periods
    assert 0.44 > GAP_FACTOR * 0.02
    assert len(report.gaps) == 1 and "/joint_states: 0.440 s without a message after 0.780 s" in report.gaps[0]
    assert len(report.clock_jumps) == 1 and "5.000 s earlier" in report.clock_jumps[0]
    code, out, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag)
    assert code == 0, err
    assert err.count("warning: gap in /joint_states") == 1 and err.count("warning: clock jump in /joint_states") == 1


def test_a_missing_topic_is_one_error_listing_the_topics(robot, tmp_path, capfd):
    t = np.arange(20) * 0.02
    records, _ = motion_records("ros1", t, motion(t))
    bag = write_bag(tmp_path / "run", "ros1", records)
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag, "--odom", "/odometry/filtered")
    assert_one_line_error(code, err, "'/odometry/filtered'", "--odom", "/odom (nav_msgs/msg/Odometry)",
                          "/joint_states (sensor_msgs/msg/JointState)")  # fmt: skip


def test_another_message_type_is_one_error(robot, tmp_path, capfd):
    t = np.arange(20) * 0.02
    records, m = motion_records("mcap", t, motion(t))
    records += [("/chatter", T0 * 1_000_000_000 + k, m.string("hello")) for k in range(3)]
    bag = write_bag(tmp_path / "run", "mcap", records)
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag, "--joint-states", "/chatter")
    assert_one_line_error(code, err, "'/chatter'", "std_msgs/msg/String", "sensor_msgs/msg/JointState")


def test_joint_names_the_robot_lacks_are_one_error(robot, tmp_path, capfd):
    t = np.arange(20) * 0.02
    values = motion(t)
    values["arm_right_4_joint"] = values["arm_right_3_joint"]
    records, _ = motion_records("db3", t, values, joints=WHEELS + ARM + ["arm_right_4_joint"])
    bag = write_bag(tmp_path / "run", "db3", records)
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag)
    assert_one_line_error(code, err, "'arm_right_4_joint'", "arm_right_3_joint")


def test_a_bag_and_a_csv_together_or_neither_is_a_usage_error(tmp_path, capfd):
    code, _, err = run_cli(capfd, "trajectory", ROBOT)
    assert_one_line_error(code, err, "TRAJ.csv", "--bag")
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "x.csv", "--bag", "x.bag")
    assert_one_line_error(code, err, "TRAJ.csv", "--bag")
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", tmp_path / "none.mcap")
    assert_one_line_error(code, err, "none.mcap", "not found")


def test_a_heading_that_crosses_pi_is_interpolated_across_it(robot, tmp_path):
    """The platform turns at a constant rate through +-pi (odometry's quaternions give yaw in
    (-pi, pi], so it jumps by 2 pi there), odometry at 20 Hz offset from the joint states at 40 Hz:
    the heading at every joint-state stamp is the true one to 1e-9 (a yaw interpolated without
    unwrapping it passes through 0: 3.14 rad off between the two messages astride the jump)."""
    t = 0.1 + np.arange(81) * 0.025
    rate, start = 0.8, math.pi - 0.6  # crosses pi at t = 0.75 s
    values = motion(t)
    values.update({"platform_x": 0.0 * t, "platform_y": 0.0 * t, "platform_yaw": start + rate * t})
    values["wheel_right_joint"] = HALF_TRACK * rate * t / WHEEL_RADIUS
    values["wheel_left_joint"] = -HALF_TRACK * rate * t / WHEEL_RADIUS
    odom_t = np.arange(35) * 0.05 + 0.313
    wrapped = np.angle(np.exp(1j * (start + rate * odom_t)))
    odom_values = {"platform_x": 0.0 * odom_t, "platform_y": 0.0 * odom_t, "platform_yaw": wrapped}
    assert np.abs(np.diff(wrapped)).max() > 6.0  # the messages jump by 2 pi
    records, _ = motion_records("mcap", t, values, odom_t=odom_t, odom_values=odom_values)
    trajectory = read_recording(robot, write_bag(tmp_path / "run", "mcap", records)).trajectory
    stamps = trajectory.t - trajectory.t[0] + t[t >= odom_t[0]][0]
    truth = start + rate * stamps
    np.testing.assert_allclose(trajectory.q[:, 2], np.cos(truth), atol=1e-9)
    np.testing.assert_allclose(trajectory.q[:, 3], np.sin(truth), atol=1e-9)


def test_retime_reads_a_recording_as_it_reads_the_same_motion_from_a_file(robot, tmp_path, capfd):
    """``retime --bag``: the recorded path's fastest timing is the CSV's, printed the same way; the
    cut and the source are checked as ``trajectory`` checks them."""
    t = np.arange(80) * 0.025
    values = motion(t)
    csv_path = tmp_path / "motion.csv"
    write_csv(csv_path, t, values)
    records, _ = motion_records("mcap", t, values)
    bag = write_bag(tmp_path / "run", "mcap", records)
    code, from_bag, err = run_cli(capfd, "retime", ROBOT, "--bag", bag, "--out", tmp_path / "bag")
    assert code == 0, err
    code, from_csv, err = run_cli(capfd, "retime", ROBOT, csv_path, "--out", tmp_path / "csv")
    assert code == 0, err
    assert f"recording {bag}" in from_bag
    summary = [line for line in from_bag.splitlines() if not line.startswith(("recording ", "  "))]
    assert [line.replace("bag/", "csv/") for line in summary] == from_csv.splitlines()
    assert "fastest timing from rest to rest" in from_csv
    code, _, err = run_cli(capfd, "retime", ROBOT, csv_path, "--bag", bag)
    assert_one_line_error(code, err, "either TRAJ.csv or --bag")
    code, _, err = run_cli(capfd, "retime", ROBOT, csv_path, "--start", "0.5")
    assert_one_line_error(code, err, "--start and --end cut a --bag recording")


@pytest.mark.parametrize("kind", ["ros1", "db3"])
def test_a_recording_given_as_the_trajectory_is_read_as_one(robot, tmp_path, capfd, kind):
    """A recording passed where TRAJ.csv goes is known by its first bytes (not its name) and read
    as --bag would read it; the same bytes under a suffix its reader cannot take are one line
    naming the suffix to give it."""
    import shutil

    t = np.arange(60) * 0.025
    records, _ = motion_records(kind, t, motion(t))
    bag = write_bag(tmp_path / "run", kind, records)
    code, as_bag, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag)
    assert code == 0, err
    code, as_file, err = run_cli(capfd, "trajectory", ROBOT, bag)
    assert code == 0, err
    assert (
        as_file.splitlines()[0]
        == f"{bag} is {'a ROS 1 bag' if kind == 'ros1' else 'a ROS 2 SQLite bag'}: read as --bag {bag}"
    )
    assert as_file.splitlines()[1:] == as_bag.splitlines()
    renamed = tmp_path / "looks_like.csv"
    shutil.copy(bag, renamed)
    code, _, err = run_cli(capfd, "retime", ROBOT, renamed)
    assert_one_line_error(code, err, "looks_like.csv", "by its first bytes", ".bag" if kind == "ros1" else ".db3")


@pytest.mark.parametrize("kind, share", [("ros1", 0.6), ("ros1", 0.95), ("mcap", 0.6)])
def test_a_bag_cut_short_is_one_line_that_says_how_to_repair_it(robot, tmp_path, capfd, kind, share):
    """A recorder stopped mid-chunk (at 60 % and at 95 % of the file: this bag's messages fill one
    chunk, its index the last 1 %): one line naming the file, why, and the tool that repairs it.
    A bag whose chunks are whole but whose index is missing is the next test's."""
    t = np.arange(200) * 0.025
    records, _ = motion_records(kind, t, motion(t))
    bag = write_bag(tmp_path / "run", kind, records)
    cut = tmp_path / f"cut{bag.suffix}"
    whole = bag.read_bytes()
    cut.write_bytes(whole[: int(len(whole) * share)])
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", cut)
    repair = "rosbag reindex" if kind == "ros1" else "mcap recover"
    assert_one_line_error(code, err, str(cut), "cannot read it as a ROS bag", repair)


def _ros1_header_fields(data: bytes) -> dict[bytes, tuple[int, int]]:
    """The ROS 1 bag's header record (after the 13-byte ``#ROSBAG V2.0`` line), as the format
    writes it: each field a 4-byte little-endian length, then ``name=value``. Returns name ->
    (offset of the value in the file, its length)."""
    import struct

    length = struct.unpack_from("<I", data, 13)[0]
    fields, i = {}, 17
    while i < 17 + length:
        size = struct.unpack_from("<I", data, i)[0]
        name = data[i + 4 : i + 4 + size].split(b"=", 1)[0]
        fields[name] = (i + 4 + len(name) + 1, size - len(name) - 1)
        i += 4 + size
    return fields


@pytest.mark.parametrize("header", ["kept", "zeroed"])
def test_a_ros1_bag_without_its_index_is_one_line_that_says_how_to_repair_it(robot, tmp_path, capfd, header):
    """Every chunk whole, the index records after them gone: cut where the header says the index
    starts, the header kept (a copy that stopped there) or zeroed (index_pos, conn_count and
    chunk_count 0: what a recorder killed before closing its bag leaves). One line naming the file
    and the tool that rebuilds the index."""
    import struct

    t = np.arange(200) * 0.025
    records, _ = motion_records("ros1", t, motion(t))
    whole = bytearray(write_bag(tmp_path / "run", "ros1", records).read_bytes())
    fields = _ros1_header_fields(bytes(whole))
    at, size = fields[b"index_pos"]
    index_pos = struct.unpack_from("<Q", whole, at)[0]
    assert size == 8 and 0 < index_pos < len(whole)
    cut = whole[:index_pos]
    if header == "zeroed":
        struct.pack_into("<Q", cut, at, 0)
        for name in (b"conn_count", b"chunk_count"):
            struct.pack_into("<I", cut, fields[name][0], 0)
    bag = tmp_path / "unindexed.bag"
    bag.write_bytes(bytes(cut))
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", bag)
    assert_one_line_error(code, err, str(bag), "cannot read it as a ROS bag", "rosbag reindex")


def test_a_ros2_bag_with_several_topics_picks_joint_states_and_odometry_by_type(robot, tmp_path):
    """A ROS 2 (SQLite) bag with five topics: joint states and odometry under other names, beside
    three string topics: the JointState and Odometry topics are picked by their types, the report
    names them, and the motion is the one under the conventional names."""
    t = np.arange(60) * 0.025
    records, m = motion_records("db3", t, motion(t))
    renamed = {"/joint_states": "/arm_base/joint_states", "/odom": "/wheel/odometry"}
    noise = [(topic, T0 * 1_000_000_000 + k * 50_000_000, m.string(f"{topic} {k}"))
             for topic in ("/chatter", "/diagnostics_text", "/operator/notes") for k in range(20)]  # fmt: skip
    several = [(renamed[topic], received, message) for topic, received, message in records] + noise
    plain = read_recording(robot, write_bag(tmp_path / "plain", "db3", records))
    found = read_recording(robot, write_bag(tmp_path / "several", "db3", several))
    np.testing.assert_array_equal(found.trajectory.q, plain.trajectory.q)
    np.testing.assert_array_equal(found.trajectory.t, plain.trajectory.t)
    notes = " ".join(found.report.notes)
    assert "read '/arm_base/joint_states'" in notes and "read '/wheel/odometry'" in notes


def test_a_ros2_bag_with_other_topic_names_is_read_by_message_type(robot, tmp_path, capfd):
    """A ROS 2 bag whose joint states and odometry are on other names: each is found by its
    message type and the report says which was read; the same motion as under the conventional
    names. Two topics of one type leave the choice to the user."""
    t = np.arange(60) * 0.025
    records, _ = motion_records("mcap", t, motion(t))
    renamed = {"/joint_states": "/robot/joint_states", "/odom": "/robot/odom"}
    moved = [(renamed[topic], received, message) for topic, received, message in records]
    plain = read_recording(robot, write_bag(tmp_path / "plain", "mcap", records))
    found = read_recording(robot, write_bag(tmp_path / "named", "mcap", moved))
    np.testing.assert_array_equal(found.trajectory.q, plain.trajectory.q)
    assert (
        "no topic '/joint_states': read '/robot/joint_states', the recording's one sensor_msgs/msg/JointState topic"
        in found.report.notes
    )
    assert any("read '/robot/odom'" in note for note in found.report.notes)
    twice = write_bag(
        tmp_path / "twice",
        "mcap",
        moved + [("/robot/joint_states_raw", r, m) for tp, r, m in moved if tp == "/robot/joint_states"],
    )
    code, _, err = run_cli(capfd, "trajectory", ROBOT, "--bag", twice)
    assert_one_line_error(code, err, "2 topics carry sensor_msgs/msg/JointState", "--joint-states")


def test_a_message_repeated_with_the_same_stamp_is_dropped_and_said(robot, tmp_path):
    """A driver that publishes one joint state twice (the same header stamp, received 1 ms apart):
    the copy is dropped as a clock jump, said in the report, and the motion is the one without it
    (a repeated stamp would otherwise give a zero time step)."""
    t = np.arange(40) * 0.025
    records, _ = motion_records("ros1", t, motion(t))
    joint_states = [r for r in records if r[0] == "/joint_states"]
    topic, received, message = joint_states[17]
    repeated = records + [(topic, received + 1_000_000, message)]
    plain = read_recording(robot, write_bag(tmp_path / "plain", "ros1", records))
    found = read_recording(robot, write_bag(tmp_path / "repeated", "ros1", repeated))
    assert found.report.samples == plain.report.samples == 40
    assert len(found.report.clock_jumps) == 1 and "0.000 s earlier" in found.report.clock_jumps[0]
    np.testing.assert_array_equal(found.trajectory.q, plain.trajectory.q)


def test_a_trajectory_file_that_cannot_be_read_is_one_line(tmp_path, capfd, monkeypatch):
    """Looking at a trajectory file's first bytes (is it a recording?) on a file the system will
    not open: one line naming the file and why, not an internal error."""
    import mobmanip.motion.recordings as recordings

    path = tmp_path / "motion.csv"
    path.write_text("t\n0\n")

    def refused(*_args, **_kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(recordings, "open", refused, raising=False)
    code, _, err = run_cli(capfd, "trajectory", ROBOT, path)
    assert_one_line_error(code, err, "motion.csv", "cannot read its first bytes: Permission denied")
