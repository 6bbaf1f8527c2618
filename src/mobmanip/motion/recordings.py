"""ROS recordings: a whole-body trajectory from the joint states and the odometry of a bag.

:func:`read_recording` reads a ROS 1 bag (``.bag``) or a ROS 2 bag (a ``.mcap`` or ``.db3``
file, or the bag's folder with its ``metadata.yaml``) with ``rosbags`` (no ROS install needed):

- the joint states (``sensor_msgs/msg/JointState``) give each joint's position, the odometry
  (``nav_msgs/msg/Odometry``) the platform's pose: ``pose.pose.position`` x, y and the yaw of
  ``pose.pose.orientation``, taken as the pose of the robot's root link in the world (the
  odometry's ``child_frame_id`` should be that link; a different one is reported);
- time is each message's ``header.stamp`` (the bag's receive time where a stamp is zero), in
  seconds from the first kept sample; ``start`` and ``end`` (seconds from the recording's first
  message) cut the recording first;
- **one time base**: the stamps of the joint-state messages inside the span every stream covers
  (never extrapolated); each joint and the platform pose are interpolated linearly onto it (yaw
  and continuous joints unwrapped first). A joint-state message that carries only some joints (a
  gripper published apart) adds samples to those joints only;
- **gaps**: an interval between two messages of a stream longer than :data:`GAP_FACTOR` times the
  stream's median period; **clock jumps**: a stamp earlier than (or equal to) the one before it
  (the message is dropped), or a stamp interval that differs from the recording's receive-time
  interval by more than :data:`CLOCK_JUMP` seconds (a clock reset or a simulation restart). Both
  are reported, never silently smoothed over: finite differences across a gap are chords;
- joint names: a name that is no joint of the robot file is an error naming it (with the
  closest); joints of the file the spec locks are ignored (reported), moving joints the recording
  lacks stay at home, and wheels the recording lacks turn as the platform's motion needs (as for a
  CSV file);
- **NaN and infinite values**: a joint's non-finite position, or an odometry pose with one, is
  dropped and reported as a warning (the stream is interpolated across it); a joint with no finite
  position stays at home (warned); a stream with none at all is an error saying so.

The result is the same :class:`~mobmanip.motion.trajectory.Trajectory` a CSV file gives
(:func:`mobmanip.motion.trajectory.trajectory_from_samples`), so the analysis is the CSV's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, JointNotFoundError, RecordingError
from ..robot.model import Robot, description_of
from ..support.reading import MAX_RECORDING_BYTES, file_refusal
from ..support.work import WorkBound
from .trajectory import Trajectory, trajectory_from_samples

#: A stream's interval longer than this many times its median period is a gap.
GAP_FACTOR = 3.0

#: A stamp interval that differs from the receive-time interval by more than this (s) is a clock jump.
CLOCK_JUMP = 0.5

#: The message types read, as rosbags names them (ROS 1 and ROS 2 alike).
JOINT_STATE = "sensor_msgs/msg/JointState"
ODOMETRY = "nav_msgs/msg/Odometry"
#: A topic left for the recording to say: the conventional name if the recording has it, else its
#: one topic of the message type (named in the report).
BY_TYPE = "auto"
#: The conventional names :data:`BY_TYPE` looks for first.
DEFAULT_TOPICS = {JOINT_STATE: "/joint_states", ODOMETRY: "/odom"}

#: Suffixes of the files read (a ROS 2 bag's folder is read too).
BAG_SUFFIXES = (".bag", ".mcap", ".db3")


@dataclass(frozen=True)
class Stream:
    """One topic's samples, as read: stamps (ns since the epoch), receive times (ns), kept in order."""

    topic: str
    stamps: np.ndarray
    received: np.ndarray


@dataclass(frozen=True)
class RecordingReport:
    """What reading a recording found.

    Attributes:
        path: the bag.
        topics: ``{topic: (message type, messages)}`` of the topics read.
        samples: samples of the common time base.
        span: ``(first, last)`` of the time base, seconds from the recording's first message.
        gaps: one line per gap found.
        clock_jumps: one line per clock jump found.
        dropped: one line per joint (and for the odometry) whose NaN or infinite values were dropped.
        notes: other remarks (joints ignored or missing, the odometry's frame).
    """

    path: Path
    topics: dict[str, tuple[str, int]]
    samples: int
    span: tuple[float, float]
    gaps: tuple[str, ...] = ()
    clock_jumps: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    dropped: tuple[str, ...] = ()

    @property
    def warnings(self) -> tuple[str, ...]:
        """Gaps, clock jumps and values dropped as NaN or infinite: what makes the trajectory doubtful."""
        return self.gaps + self.clock_jumps + self.dropped

    def lines(self) -> list[str]:
        """The report for the console."""
        out = [f"recording {self.path}:"]
        for topic, (kind, count) in self.topics.items():
            out.append(f"  {topic}: {count} messages of {kind}")
        out.append(
            f"  {self.samples} samples on the joint states' time base, {self.span[0]:.3f} .. {self.span[1]:.3f} s "
            "from the recording's start"
        )
        out += [f"  {line}" for line in self.notes]
        return out


@dataclass(frozen=True)
class Recording:
    """A recording read: its trajectory and the report of how it was read."""

    trajectory: Trajectory
    report: RecordingReport
    joints: tuple[str, ...] = field(default=())


def _within_years(seconds: float) -> float:
    """``seconds`` clipped to +-1e9 s (about 30 years)."""
    return min(max(seconds, -1e9), 1e9)


def _seconds(ns: int | float) -> float:
    return float(ns) * 1e-9


#: The first bytes of each kind of recording file, and the suffix its reader needs.
_SIGNATURES = (
    (b"#ROSBAG V2.0", "a ROS 1 bag", ".bag"),
    (b"\x89MCAP", "an MCAP file", ".mcap"),
    (b"SQLite format 3\x00", "a ROS 2 SQLite bag", ".db3"),
)


def recording_kind(path: str | Path) -> str | None:
    """What ``path`` is by its first bytes when it is a ROS recording (``"a ROS 1 bag"``, ``"an
    MCAP file"``, ``"a ROS 2 SQLite bag"``, ``"a ROS 2 bag folder"``), else ``None``: a file
    named as a trajectory that holds a recording is read as one. Only a regular file is opened
    (a FIFO or a device is never read here).

    Raises:
        RecordingError: a recording whose suffix its reader cannot take (named, with the suffix to
            give it), or a file that cannot be read.
    """
    path = Path(path)
    if path.is_dir():
        return "a ROS 2 bag folder" if (path / "metadata.yaml").is_file() else None
    if not path.is_file():
        return None
    try:
        with open(path, "rb") as handle:
            head = handle.read(16)
    except OSError as exc:  # unreadable: named, not an internal error
        raise RecordingError(str(path), f"cannot read its first bytes: {exc.strerror or exc}") from None
    for signature, kind, suffix in _SIGNATURES:
        if head.startswith(signature):
            if path.suffix.lower() != suffix:
                raise RecordingError(str(path), f"it is {kind} by its first bytes: name it with the suffix {suffix}")
            return kind
    return None


def _check_recording_files(path: Path) -> None:
    """A recording is a regular file, or a ROS 2 bag folder of regular files, of at most
    :data:`~mobmanip.support.reading.MAX_RECORDING_BYTES` (together): a FIFO or a device is
    refused at once, never opened.

    Raises:
        RecordingError: naming the file and why.
    """
    if not path.is_dir():
        reason = file_refusal(path, limit=MAX_RECORDING_BYTES)
        if reason is not None:
            raise RecordingError(str(path), "not found" if reason == "file not found" else reason)
        return
    total = 0
    for entry in sorted(path.iterdir()):
        if entry.is_dir():
            continue  # not part of the bag: rosbags reads the files its metadata names
        reason = file_refusal(entry, limit=MAX_RECORDING_BYTES)
        if reason is not None:
            raise RecordingError(str(path), f"{entry.name}: {reason}")
        total += entry.stat().st_size
        if total > MAX_RECORDING_BYTES:
            raise RecordingError(
                str(path), f"its files come to more than the {MAX_RECORDING_BYTES} bytes this reads (at {entry.name})"
            )


def _open(path: Path):
    """An open rosbags AnyReader for the bag (a ROS 2 bag without type definitions gets the
    standard ROS 2 types)."""
    try:
        from rosbags.highlevel import AnyReader, AnyReaderError
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:  # pragma: no cover - rosbags is a dependency
        raise RecordingError(str(path), "reading ROS bags needs rosbags (pip install rosbags)") from exc
    _check_recording_files(path)
    if path.is_file() and path.suffix.lower() not in BAG_SUFFIXES:
        raise RecordingError(
            str(path), f"suffix {path.suffix!r}: a ROS bag is a .bag (ROS 1), .mcap or .db3 file or a ROS 2 bag folder"
        )
    try:
        reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except (AnyReaderError, Exception) as exc:  # rosbags raises its own and OS errors alike
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise RecordingError(str(path), f"cannot read it as a ROS bag: {reason}{_repair_hint(path)}") from None
    return reader


def _repair_hint(path: Path) -> str:
    """How to repair a recording its reader refuses (a recorder stopped without writing its index,
    a file cut short by a full disk or a copy), by its kind."""
    suffix = path.suffix.lower()
    if suffix == ".bag":
        return (
            "; a ROS 1 bag cut short or left without its index is repaired by `rosbag reindex` "
            "(it rebuilds the index from the chunks that are whole), then read again"
        )
    if suffix == ".mcap":
        return "; an MCAP file cut short is repaired by `mcap recover IN.mcap -o OUT.mcap`, then read again"
    return ""


def _chosen_topic(reader, path: Path, topic: str, kind: str, option: str) -> tuple[str, str | None]:
    """``topic``, or for :data:`BY_TYPE` the recording's conventional one, else its one topic of
    ``kind``: (the topic, a note saying which was taken where it was not the conventional name).

    Raises:
        RecordingError: :data:`BY_TYPE` and the recording has no topic of ``kind``, or several
            (listed, with the option that names one).
    """
    if topic != BY_TYPE:
        return topic, None
    conventional = DEFAULT_TOPICS[kind]
    if any(c.topic == conventional for c in reader.connections):
        return conventional, None
    typed = sorted({c.topic for c in reader.connections if c.msgtype == kind})
    if len(typed) == 1:
        return typed[0], f"no topic {conventional!r}: read {typed[0]!r}, the recording's one {kind} topic"
    listed = ", ".join(f"{c.topic} ({c.msgtype})" for c in sorted(reader.connections, key=lambda c: c.topic))
    which = f"{len(typed)} topics carry {kind}" if typed else f"no topic carries {kind}"
    raise RecordingError(
        str(path), f"no topic {conventional!r}, and {which}: name one with {option} (the bag has: {listed or 'none'})"
    )


def _connections(reader, path: Path, topic: str, kind: str, option: str):
    found = [c for c in reader.connections if c.topic == topic]
    if not found:
        listed = ", ".join(f"{c.topic} ({c.msgtype})" for c in sorted(reader.connections, key=lambda c: c.topic))
        raise RecordingError(
            str(path), f"no topic {topic!r} (give another with {option}; the bag has: {listed or 'no topics'})"
        )
    types = {c.msgtype for c in found}
    if types != {kind}:
        raise RecordingError(
            str(path),
            f"topic {topic!r} carries {', '.join(sorted(types))}, not {kind} (the message type {option} reads)",
        )
    return found


def _stamp(message, received: int) -> int:
    stamp = message.header.stamp
    ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
    return ns if ns > 0 else int(received)


def _deserialize(reader, path: Path, connection, raw):
    try:
        return reader.deserialize(raw, connection.msgtype)
    except Exception as exc:  # an unknown or mismatched message definition
        raise RecordingError(
            str(path),
            f"cannot decode a {connection.msgtype} message on {connection.topic!r}: {' '.join(str(exc).split())}",
        ) from None


def _yaw(orientation) -> float:
    x, y, z, w = (float(orientation.x), float(orientation.y), float(orientation.z), float(orientation.w))
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _clean(stream_name: str, stamps: list[int], received: list[int], values: list, jumps: list[str], origin: int):
    """Drop samples whose stamp does not increase (a clock jump backwards), report forward jumps."""
    keep_s: list[int] = []
    keep_r: list[int] = []
    keep_v: list = []
    for s, r, v in zip(stamps, received, values):
        if keep_s and s <= keep_s[-1]:
            jumps.append(
                f"clock jump in {stream_name}: a stamp {_seconds(keep_s[-1] - s):.3f} s earlier than the one "
                f"before, at {_seconds(r - origin):.3f} s of the recording (message dropped)"
            )
            continue
        if keep_s:
            stamp_step, receive_step = s - keep_s[-1], r - keep_r[-1]
            if abs(_seconds(stamp_step - receive_step)) > CLOCK_JUMP:
                jumps.append(
                    f"clock jump in {stream_name}: the stamps advance {_seconds(stamp_step):.3f} s where the recording "
                    f"advances {_seconds(receive_step):.3f} s, at {_seconds(r - origin):.3f} s of the recording"
                )
        keep_s.append(s)
        keep_r.append(r)
        keep_v.append(v)
    return np.array(keep_s, dtype=np.int64), np.array(keep_r, dtype=np.int64), keep_v


def _dropped(stream_name: str, joint: str, bad: list[tuple[int, float]], all_bad: bool, origin: int) -> str:
    """The warning for a joint's NaN or infinite positions, dropped."""
    stamp, value = bad[0]
    where = f"first {value!r} at {_seconds(stamp - origin):.3f} s of the recording"
    if all_bad:
        return (f"every position of {joint} on {stream_name!r} is NaN or infinite ({len(bad)}, {where}): "
                "it stays at home")  # fmt: skip
    return f"{len(bad)} non-finite position(s) of {joint} on {stream_name!r} dropped ({where}): interpolated across"


def _gaps(stream_name: str, stamps: np.ndarray, origin: int) -> list[str]:
    if stamps.shape[0] < 3:
        return []
    steps = np.diff(stamps)
    period = float(np.median(steps))
    out = []
    for k in np.flatnonzero(steps > GAP_FACTOR * period):
        out.append(
            f"gap in {stream_name}: {_seconds(steps[k]):.3f} s without a message after "
            f"{_seconds(stamps[k] - origin):.3f} s (median period {_seconds(period):.4f} s): rates across it are chords"
        )
    return out


def _count_messages(reader, connections, low: int | None, high: int | None, limit: int) -> tuple[int, bool]:
    """How many messages ``connections`` hold in ``[low, high)``: the bag's index count for the
    whole recording, else counted without decoding, stopping one past ``limit``. Returns the
    count and whether it is exact."""
    declared = [int(getattr(c, "msgcount", 0) or 0) for c in connections]
    if low is None and high is None and all(declared):
        return sum(declared), True
    count = 0
    for _ in reader.messages(connections=connections, start=low, stop=high):
        count += 1
        if count > limit:
            return count, False
    return count, True


def read_recording(
    robot: Robot,
    path: str | Path,
    joint_states: str = BY_TYPE,
    odometry: str | None = BY_TYPE,
    *,
    start: float | None = None,
    end: float | None = None,
    work: WorkBound | None = None,
) -> Recording:
    """The trajectory a ROS bag records (see the module docstring).

    Args:
        robot: the loaded robot.
        path: the bag: ``.bag`` (ROS 1), ``.mcap`` / ``.db3`` (ROS 2), or a ROS 2 bag's folder.
        joint_states: the ``sensor_msgs/msg/JointState`` topic; :data:`BY_TYPE` (default):
            ``/joint_states`` if the recording has it, else its one topic of that type (said in
            the report's notes).
        odometry: the ``nav_msgs/msg/Odometry`` topic (:data:`BY_TYPE`: ``/odom``, else the one
            of that type); ``None`` for a robot whose platform does not move (the platform stays
            at the origin).
        start, end: seconds from the recording's first message; only what lies between is read.
        work: the bound on the samples (joint-state messages in the part read), checked before
            any message is decoded (from the bag's index, or by counting the part read up to
            one past the bound) and again as they are read.

    Raises:
        RecordingError: the bag cannot be read, a topic is missing or of another message type,
            a message cannot be decoded, or too little of the recording is left.
        JointNotFoundError: a joint-state name that is no joint of the robot file.
        ArgumentError: ``start`` not before ``end``, or more samples than ``work`` allows.
    """
    path = Path(path)
    for option, value in (("--start", start), ("--end", end)):
        if value is not None and not math.isfinite(value):
            raise ArgumentError(
                f"{option} must be a finite number of seconds from the recording's start, got {value!r}"
            )
    if start is not None and end is not None and not start < end:
        raise ArgumentError(f"--start {start:g} must come before --end {end:g}")
    reader = _open(path)
    chosen = []
    try:
        joint_states, note = _chosen_topic(reader, path, joint_states, JOINT_STATE, "--joint-states")
        chosen.append(note)
        if odometry is not None:
            odometry, note = _chosen_topic(reader, path, odometry, ODOMETRY, "--odom")
            chosen.append(note)
        js_connections = _connections(reader, path, joint_states, JOINT_STATE, "--joint-states")
        odom_connections = [] if odometry is None else _connections(reader, path, odometry, ODOMETRY, "--odom")
        origin = int(reader.start_time)
        # a cut further than 30 years from the start cuts as the 30 years do (and stays in int64 ns)
        low = None if start is None else origin + int(round(_within_years(start) * 1e9))
        high = None if end is None else origin + int(round(_within_years(end) * 1e9)) + 1
        joints_raw: list = []
        odom_raw: list = []
        frames: set[str] = set()
        what = f"joint-state messages on {joint_states!r} of {path.name}" + (
            "" if low is None and high is None else " between --start and --end"
        )
        if work is not None:
            count, exact = _count_messages(reader, js_connections, low, high, work.limit)
            work.check(count, what if exact else f"{what}, counted up to one past the bound")
        for connection, received, raw in reader.messages(
            connections=js_connections + odom_connections, start=low, stop=high
        ):
            if connection.msgtype == JOINT_STATE and work is not None and len(joints_raw) >= work.limit:
                work.check(len(joints_raw) + 1, f"{what}, more than its index declares")  # the index was wrong
            message = _deserialize(reader, path, connection, raw)
            stamp = _stamp(message, received)
            if connection.msgtype == JOINT_STATE:
                joints_raw.append((stamp, int(received), list(message.name), np.asarray(message.position, dtype=float)))
            else:
                pose = message.pose.pose
                frames.add(str(message.child_frame_id))
                odom_raw.append(
                    (stamp, int(received), (float(pose.position.x), float(pose.position.y), _yaw(pose.orientation)))
                )
        topics = {joint_states: (JOINT_STATE, len(joints_raw))}
        if odometry is not None:
            topics[odometry] = (ODOMETRY, len(odom_raw))
    finally:
        reader.close()
    found = _resample(robot, path, joints_raw, odom_raw, frames, topics, origin, joint_states, odometry)
    said = tuple(note for note in chosen if note is not None)
    return replace(found, report=replace(found.report, notes=said + found.report.notes)) if said else found


def _resample(robot, path, joints_raw, odom_raw, frames, topics, origin, joint_states, odometry) -> Recording:
    description = description_of(robot)
    moving = set(robot.joint_names)
    unknown: list[str] = []
    locked: set[str] = set()
    per_joint: dict[str, tuple[list[int], list[float]]] = {}
    nonfinite: dict[str, list[tuple[int, float]]] = {}  # per joint: (stamp, value) of each NaN or inf position
    jumps: list[str] = []
    if not joints_raw:
        raise RecordingError(str(path), f"no joint-state messages on {joint_states!r} in the part read")
    js_stamps, js_received, js_values = _clean(joint_states, [s for s, _, _, _ in joints_raw],
                                               [r for _, r, _, _ in joints_raw], [(n, p) for _, _, n, p in joints_raw],
                                               jumps, origin)  # fmt: skip
    for stamp, (names, positions) in zip(js_stamps, js_values):
        if len(positions) != len(names):
            raise RecordingError(
                str(path),
                f"a joint-state message on {joint_states!r} has {len(names)} names but {len(positions)} positions",
            )
        for name, value in zip(names, positions):
            if name not in description.joints:
                unknown.append(name)
            elif name not in moving:
                locked.add(name)
            elif math.isfinite(value):
                per_joint.setdefault(name, ([], []))
                per_joint[name][0].append(int(stamp))
                per_joint[name][1].append(float(value))
            else:
                nonfinite.setdefault(name, []).append((int(stamp), float(value)))
    if unknown:
        first = unknown[0]
        where = f"robot {robot.name} (joint states of {path.name})"
        raise JointNotFoundError(first, description.joints, where=where)
    if not per_joint and nonfinite:
        count = sum(len(bad) for bad in nonfinite.values())
        raise RecordingError(
            str(path),
            f"every position on {joint_states!r} of the robot's moving joints is NaN or infinite ({count} values of "
            f"{', '.join(sorted(nonfinite, key=robot.joint_names.index))}): nothing to analyse",
        )
    if not per_joint:
        raise RecordingError(str(path), f"the joint states on {joint_states!r} name none of the robot's moving joints")
    dropped = [_dropped(joint_states, name, bad, name not in per_joint, origin) for name, bad in nonfinite.items()]
    gaps = _gaps(joint_states, js_stamps, origin)
    base = js_stamps
    odom = None
    notes = []
    if odometry is not None:
        if not odom_raw:
            raise RecordingError(str(path), f"no odometry messages on {odometry!r} in the part read")
        bad_poses = [(s, v) for s, _, v in odom_raw if not all(math.isfinite(c) for c in v)]
        if len(bad_poses) == len(odom_raw):
            raise RecordingError(
                str(path),
                f"every pose on {odometry!r} is NaN or infinite ({len(odom_raw)} messages): nothing to analyse",
            )
        if bad_poses:
            first_stamp, first_pose = bad_poses[0]
            shown = ", ".join(map(repr, first_pose))
            dropped.append(
                f"{len(bad_poses)} non-finite pose(s) on {odometry!r} dropped (first ({shown}) "
                f"at {_seconds(first_stamp - origin):.3f} s of the recording): the pose is interpolated across them"
            )
            odom_raw = [record for record in odom_raw if all(math.isfinite(c) for c in record[2])]
        o_stamps, _, o_values = _clean(odometry, [s for s, _, _ in odom_raw], [r for _, r, _ in odom_raw],
                                       [v for _, _, v in odom_raw], jumps, origin)  # fmt: skip
        gaps += _gaps(odometry, o_stamps, origin)
        pose = np.array(o_values, dtype=float)
        pose[:, 2] = np.unwrap(pose[:, 2])
        odom = (o_stamps, pose)
        root = description.root_link
        other = sorted(f for f in frames if f and f != root)
        if other:
            notes.append(
                f"the odometry's child_frame_id is {', '.join(repr(f) for f in other)}, not the robot's root link "
                f"{root!r}: its pose is taken as the root's"
            )
        base = base[(base >= o_stamps[0]) & (base <= o_stamps[-1])]
    elif not robot.platform_locked:
        notes.append("no odometry: the platform stays at the origin")
    for stamps, _ in per_joint.values():
        base = base[(base >= stamps[0]) & (base <= stamps[-1])]
    if base.shape[0] < 3:
        raise RecordingError(
            str(path),
            f"only {base.shape[0]} joint-state samples lie where every stream has data; at least 3 are needed",
        )
    t = (base - base[0]).astype(float) * 1e-9
    joints = sorted(per_joint, key=robot.joint_names.index)
    values = {}
    for name in joints:
        stamps, series = (np.asarray(a) for a in per_joint[name])
        series = np.asarray(series, dtype=float)
        if robot.model.joints[robot.model.getJointId(name)].nq == 2:
            series = np.unwrap(series)
        values[name] = np.interp((base - base[0]).astype(float), (stamps - base[0]).astype(float), series)
    if odom is not None:
        o_t = (odom[0] - base[0]).astype(float)
        platform = np.column_stack([np.interp((base - base[0]).astype(float), o_t, odom[1][:, k]) for k in range(3)])
    else:
        platform = np.zeros((base.shape[0], 3))
    if locked:
        notes.append(f"joints the spec locks are not read: {', '.join(sorted(locked))}")
    missing = [name for name in robot.joint_names if name not in per_joint]
    if missing:
        notes.append(f"joints the recording lacks stay at home (wheels follow the platform): {', '.join(missing)}")
    qs = np.array(
        [
            robot.configuration(tuple(platform[i]), {name: values[name][i] for name in joints})
            for i in range(base.shape[0])
        ]
    )
    trajectory = trajectory_from_samples(robot, t, qs, known_joints=joints)
    span = (_seconds(base[0] - origin), _seconds(base[-1] - origin))
    report = RecordingReport(
        path=path,
        topics=topics,
        samples=int(base.shape[0]),
        span=span,
        gaps=tuple(gaps),
        clock_jumps=tuple(dict.fromkeys(jumps)),
        notes=tuple(notes),
        dropped=tuple(dropped),
    )
    return Recording(trajectory=trajectory, report=report, joints=tuple(joints))
