"""The project's mutation run: plant one plausible bug at a time and see whether the tests notice.

Each entry of :data:`MUTANTS` is a single-point bug of the kind a tired developer makes in the
physics and reading code (a sign, a transposed rotation, a swapped index, an off-by-one, a dropped
term, a wrong unit or default, a gear multiplied instead of divided, an angle left unwrapped): the
file, an exact snippet of it (found exactly once), what replaces it, the bug in words, and the
test files that ought to catch it.

For every mutant the script copies the repository's ``src/`` and ``tests/`` (with ``robots/``,
``examples/``, ``scripts/`` and ``pyproject.toml``, which the tests read) to a fresh temporary folder, applies
the one replacement there, and runs that mutant's tests with pytest in a subprocess (``-x -q``,
``PYTHONPATH`` on the copy's ``src/``, a time limit per mutant). The working tree is never
written to, even when the run is interrupted. A mutant is *caught* when a test fails and
*survived* when every test passes; a survivor is a finding (a bug the tests would let through),
not something to delete from the list.

Run it from anywhere, with the project's Python::

    python scripts/mutants.py --check          # every snippet found exactly once (no tests run)
    python scripts/mutants.py --list           # the mutants, one per line
    python scripts/mutants.py                  # the whole run (tens of minutes)
    python scripts/mutants.py --only F01 T04   # some of them
    python scripts/mutants.py --baseline       # their tests on an unmutated copy: all must pass

A run prints one line per mutant and ends with "N of M caught"; its exit status is 0 whatever it
finds (it reports). ``--check`` exits with 1 when a snippet is missing, repeated, or its mutant
would not compile. It is not part of CI (tests/test_mutants_script.py keeps the list in step with
the code); the last run's table is in docs/testing.md.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

#: The repository this script belongs to.
ROOT = Path(__file__).resolve().parents[1]

#: What the tests need besides themselves and the code: copied beside them.
COPIED = ("src", "tests", "robots", "examples", "scripts", "pyproject.toml")

#: Where each area's mutants may be planted (paths from the repository's root; a folder ends in /).
AREAS: dict[str, tuple[str, ...]] = {
    "floor": (
        "src/mobmanip/terms/constraints/floor.py",
        "src/mobmanip/terms/constraints/floor_wrench.py",
        "src/mobmanip/robot/support.py",
        "src/mobmanip/motion/carry_floor.py",
        "src/mobmanip/motion/ground.py",
    ),
    "descriptions": ("src/mobmanip/descriptions/", "src/mobmanip/platforms/wheels.py"),
    "recordings": ("src/mobmanip/motion/recordings.py",),
    "teams": ("src/mobmanip/coordination/", "src/mobmanip/team/"),
    "placement": ("src/mobmanip/placement/",),
}

#: Seconds one mutant's tests may take before the run gives up on them.
TIMEOUT = 360.0


@dataclass(frozen=True)
class Mutant:
    """One planted bug.

    Attributes:
        id: a short name (the area's letter and a number).
        area: one of :data:`AREAS`.
        file: the file, from the repository's root.
        original: a snippet that occurs exactly once in the file.
        replacement: what it becomes.
        description: the bug, in words.
        tests: the tests to run, from the repository's root (a file, or ``file::test``).
    """

    id: str
    area: str
    file: str
    original: str
    replacement: str
    description: str
    tests: tuple[str, ...]


FLOOR = "src/mobmanip/terms/constraints/floor.py"
SUPPORT = "src/mobmanip/robot/support.py"
CARRY_FLOOR = "src/mobmanip/motion/carry_floor.py"
FLOOR_WRENCH = "src/mobmanip/terms/constraints/floor_wrench.py"
GROUND = "src/mobmanip/motion/ground.py"
URDF = "src/mobmanip/descriptions/urdf.py"
MJCF = "src/mobmanip/descriptions/mjcf.py"
FLAWS = "src/mobmanip/descriptions/flaws.py"
XACRO = "src/mobmanip/descriptions/xacro.py"
MJCF_BUILDER = "src/mobmanip/descriptions/mjcf_builder.py"
WHEELS = "src/mobmanip/platforms/wheels.py"
RECORDINGS = "src/mobmanip/motion/recordings.py"
MEMBERS = "src/mobmanip/team/members.py"
TEAM_ANALYSIS = "src/mobmanip/team/analysis.py"
CAPACITY = "src/mobmanip/coordination/capacity.py"
PLATFORM_TASK = "src/mobmanip/coordination/platform_task.py"
TEAM_CARRY = "src/mobmanip/coordination/carry.py"
TEAM_EFFORT = "src/mobmanip/coordination/effort.py"
GRID = "src/mobmanip/placement/grid.py"
OPTIMIZE = "src/mobmanip/placement/optimize.py"
MAPS = "src/mobmanip/placement/maps.py"
SITE = "src/mobmanip/placement/site.py"
GROUNDED = "src/mobmanip/placement/grounded.py"


def _m(id: str, area: str, file: str, original: str, replacement: str, description: str, *tests: str) -> Mutant:
    return Mutant(id, area, file, original, replacement, description, tests)


MUTANTS: tuple[Mutant, ...] = (
    # ----- the floor: the constraint, the support, carry's floor rows, the floor along a motion
    _m(
        "F01", "floor", FLOOR,
        "wrench = np.vstack([np.eye(3), skew(p - c)])",
        "wrench = np.vstack([np.eye(3), skew(c - p)])",
        "the lever arm's cross-product is reversed: every contact force's moment about the centre of "
        "mass changes sign",
        "tests/test_floor.py",
    ),
    _m(
        "F02", "floor", FLOOR,
        "-math.sin(s) * math.cos(u), -math.sin(s) * math.sin(u), -math.cos(s)",
        "-math.sin(s) * math.sin(u), -math.sin(s) * math.cos(u), -math.cos(s)",
        "on a ramp, the uphill direction is measured from +y instead of +x (gravity's downhill part turned)",
        "tests/test_floor_slope.py::test_on_a_ramp_the_reaches_equal_the_independent_lp",
        "tests/test_floor_task.py::test_a_ramp_leans_gravity_as_written_here",
    ),
    _m(
        "F03", "floor", FLOOR,
        "tilt = mu * math.cos(math.pi / faces) * (1.0 - self.reserve)",
        "tilt = mu * (1.0 - self.reserve)",
        "the friction pyramid's cos(pi / faces) is dropped: its faces touch the cone from outside, not inside",
        "tests/test_floor.py",
    ),
    _m(
        "F04", "floor", FLOOR,
        "angles = heading + 2.0 * math.pi * np.arange(faces) / faces",
        "angles = 2.0 * math.pi * np.arange(faces) / faces",
        "the friction pyramid stays fixed in the world instead of turning with the platform's heading",
        "tests/test_floor.py", "tests/test_floor_task.py",
    ),
    _m(
        "F05", "floor", FLOOR,
        "rows = deflections / k[None, :]  # d = f / k",
        "rows = deflections * k[None, :]  # d = f / k",
        "the compliant sharing multiplies by each contact's stiffness where it should divide (d = f / k)",
        "tests/test_floor_stiffness.py",
    ),
    _m(
        "F06", "floor", FLOOR,
        "lateral = (-math.sin(heading), math.cos(heading))",
        "lateral = (math.cos(heading), math.sin(heading))",
        "the tyres' sideways sharing is written along the wheels' rolling direction instead of across it",
        "tests/test_floor.py",
    ),
    _m(
        "F07", "floor", FLOOR,
        "block[i, a : a + 2] = (math.cos(yaw) * fx - math.sin(yaw) * fy, math.sin(yaw) * fx + math.cos(yaw) * fy)",
        "block[i, a : a + 2] = (math.cos(yaw) * fx + math.sin(yaw) * fy, -math.sin(yaw) * fx + math.cos(yaw) * fy)",
        "a roller's free direction is turned to the world by the transposed rotation (minus the heading)",
        "tests/test_floor_kinds.py", "tests/test_floor_task.py",
    ),
    _m(
        "F08", "floor", SUPPORT,
        'contacts.append(ContactPoint(joint, center - np.array([0.0, 0.0, radius]), True, "wheel"))',
        'contacts.append(ContactPoint(joint, center + np.array([0.0, 0.0, radius]), True, "wheel"))',
        "a driven wheel touches the floor a radius above its centre instead of below it",
        "tests/test_floor_reference.py", "tests/test_floor.py",
    ),
    _m(
        "F09", "floor", SUPPORT,
        "R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])",
        "R = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])",
        "the contact points are turned to the world by the transposed rotation (a turned robot's support mirrored)",
        "tests/test_floor.py", "tests/test_floor_task.py",
    ),
    _m(
        "F10", "floor", SUPPORT,
        'return float(np.min(np.einsum("ij,ij->i", normals, P) - normals @ np.asarray(point, dtype=float)[:2]))',
        'return float(np.max(np.einsum("ij,ij->i", normals, P) - normals @ np.asarray(point, dtype=float)[:2]))',
        "the stability margin is the distance to the farthest edge of the support polygon, not the nearest",
        "tests/test_floor.py", "tests/test_floor_reference.py", "tests/test_ground_along.py",
    ),
    _m(
        "F11", "floor", SUPPORT,
        "free = (math.cos(angle), math.sin(angle))",
        "free = (math.sin(angle), math.cos(angle))",
        "a wheel's roller angle ([support] rollers) is measured from the platform's y axis instead of its x axis",
        "tests/test_floor_rollers.py", "tests/test_floor_kinds.py", "tests/test_retime_kinds.py",
    ),
    _m(
        "F12", "floor", FLOOR_WRENCH,
        "T[3:, :3] = -turn @ origin",
        "T[3:, :3] = turn @ origin",
        "carry's floor rows move the moment from the world origin to the platform with p x F's sign dropped",
        "tests/test_carry_floor.py",
    ),
    _m(
        "F13", "floor", FLOOR_WRENCH,
        "B[:, k] = direction[0], direction[1], x * direction[1] - y * direction[0]",
        "B[:, k] = direction[0], direction[1], y * direction[0] - x * direction[1]",
        "a wheel's moment about the vertical enters the split of the traction among the wheels with the wrong sign",
        "tests/test_retime_kinds.py", "tests/test_carry_floor.py",
    ),
    _m(
        "F14", "floor", GROUND,
        "zmp[i] = ((z_floor * force[0] - moment[1]) / force[2], (moment[0] + z_floor * force[1]) / force[2])",
        "zmp[i] = ((z_floor * force[0] + moment[1]) / force[2], (moment[0] + z_floor * force[1]) / force[2])",
        "the zero-moment point's x takes the pitch moment with the wrong sign",
        "tests/test_ground_along.py",
    ),
    _m(
        "F15", "floor", GROUND,
        "offset[:3] = rate0[:3] + object_mass * a0[:3] - (mass + object_mass) * g",
        "offset[:3] = rate0[:3] + object_mass * a0[:3] - mass * g",
        "the floor's resultant force along a motion leaves out the held object's weight",
        "tests/test_ground_along.py",
    ),
    _m(
        "F16", "floor", GROUND,
        "linear[3:] = rate1[3:] + skew(c) @ rate1[:3] + object_mass * skew(c_o) @ a1[:3]",
        "linear[3:] = rate1[3:] + object_mass * skew(c_o) @ a1[:3]",
        "the rate of the robot's momentum is not moved from its centre of mass to the world origin (c x p dropped)",
        "tests/test_ground_along.py",
    ),
    _m(
        "F17", "floor", FLOOR,
        "-math.sin(s) * math.cos(u), -math.sin(s) * math.sin(u), -math.cos(s)",
        "math.sin(s) * math.cos(u), math.sin(s) * math.sin(u), -math.cos(s)",
        "on a ramp, gravity's part along the floor points uphill instead of downhill",
        "tests/test_floor_slope.py", "tests/test_brake.py",
    ),
    # ----- robot descriptions: URDF, MJCF, vendor flaws, xacro
    _m(
        "D01", "descriptions", URDF,
        'return " ".join(arguments[1:])',
        'return " ".join(arguments[2:])',
        "a $(optenv NAME DEFAULT) left in a URDF loses the default's first word (off by one)",
        "tests/test_spec_and_urdf.py",
    ),
    _m(
        "D02", "descriptions", URDF,
        'line = text.count("\\n", 0, start) + 1',
        'line = text.count("\\n", 0, start)',
        "the line named for an unexpanded substitution is counted from 0 (one too small)",
        "tests/test_spec_and_urdf.py",
    ),
    _m(
        "D03", "descriptions", URDF,
        '(entry["ixz"], entry["iyz"], entry["izz"]),',
        '(entry["ixy"], entry["iyz"], entry["izz"]),',
        "the inertia tensor's third row takes ixy where ixz belongs (a swapped index)",
        "tests/test_vendor_flaws.py", "tests/test_description_formats.py",
    ),
    _m(
        "D04", "descriptions", MJCF,
        "w, x, y, z = np.asarray(list(q), dtype=float) / np.linalg.norm(list(q))",
        "x, y, z, w = np.asarray(list(q), dtype=float) / np.linalg.norm(list(q))",
        "MJCF quaternions read as (x, y, z, w); MuJoCo writes w first",
        "tests/test_mjcf.py", "tests/test_mjcf_mesh_mass.py",
    ),
    _m(
        "D05", "descriptions", MJCF,
        "R = R @ turn if axis.islower() else turn @ R  # lower case: moving axes",
        "R = turn @ R if axis.islower() else R @ turn  # lower case: moving axes",
        "Euler angles composed about fixed axes where MuJoCo's lower-case sequence means moving ones",
        "tests/test_mjcf_mesh_mass.py", "tests/test_mjcf.py",
    ),
    _m(
        "D06", "descriptions", MJCF,
        "return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K",
        "return np.eye(3) - math.sin(angle) * K + (1 - math.cos(angle)) * K @ K",
        "Rodrigues' formula with the sine term's sign flipped: every axis-angle and Euler rotation transposed",
        "tests/test_mjcf_mesh_mass.py", "tests/test_mjcf.py",
    ),
    _m(
        "D07", "descriptions", MJCF,
        'lower, upper = (r.angle(v) if kind == "hinge" else v for v in range_)',
        "lower, upper = (v for v in range_)",
        "a hinge's range is left in degrees when the compiler's angle is degree (a wrong unit)",
        "tests/test_mjcf.py",
    ),
    _m(
        "D08", "descriptions", MJCF,
        "max(abs(ctrl[0]), abs(ctrl[1])) / gear)",
        "max(abs(ctrl[0]), abs(ctrl[1])) * gear)",
        "a velocity actuator's gear multiplies its command range instead of dividing it",
        "tests/test_mjcf.py",
    ),
    _m(
        "D09", "descriptions", MJCF,
        'entry["effort"] = max(entry.get("effort", 0.0), gear * max(abs(force[0]), abs(force[1])))',
        'entry["effort"] = max(entry.get("effort", 0.0), max(abs(force[0]), abs(force[1])) / gear)',
        "an actuator's gear divides its force range instead of multiplying it",
        "tests/test_mjcf.py",
    ),
    _m(
        "D10", "descriptions", MJCF,
        'xx, yy, zz, xy, xz, yz = _floats(attrs["fullinertia"]',
        'xx, yy, zz, xy, yz, xz = _floats(attrs["fullinertia"]',
        "fullinertia's last two products of inertia (xz, yz) read in swapped order",
        "tests/test_mjcf.py",
    ),
    _m(
        "D11", "descriptions", MJCF,
        "a, b, c = (2 * s for s in size[:3])",
        "a, b, c = (s for s in size[:3])",
        "a box geom's half-sizes taken as its side lengths in its mass properties",
        "tests/test_mjcf_mesh_mass.py", "tests/test_mjcf.py",
    ),
    _m(
        "D12", "descriptions", FLAWS,
        "mean = max((a + b + c) / 3.0, 0.0)",
        "mean = max((a + b + c) / 2.0, 0.0)",
        "the balanced principal moment is the moments' sum over two, not their mean",
        "tests/test_vendor_flaws.py",
    ),
    _m(
        "D13", "descriptions", FLAWS,
        "parameters[4:] += (change[0, 0], change[0, 1], change[1, 1], change[0, 2], change[1, 2], change[2, 2])",
        "parameters[4:] += (change[0, 0], change[0, 1], change[0, 2], change[1, 1], change[1, 2], change[2, 2])",
        "the repair is added in URDF's order (ixx ixy ixz iyy ...) to parameters in Pinocchio's (Ixx Ixy Iyy Ixz ...)",
        "tests/test_vendor_flaws.py",
    ),
    _m(
        "D14", "descriptions", FLAWS,
        "change = rotation @ flaw.delta @ rotation.T",
        "change = rotation.T @ flaw.delta @ rotation",
        "the repair is turned into the joint's frame by the transposed rotation",
        "tests/test_vendor_flaws.py",
    ),
    _m(
        "D15", "descriptions", FLAWS,
        "tolerance = INERTIA_SLACK * scale",
        "tolerance = INERTIA_SLACK",
        "the rounding slack of the inertia check is absolute (kg m^2) instead of relative to the tensor",
        "tests/test_vendor_flaws.py",
    ),
    _m(
        "D16", "descriptions", XACRO,
        "[folder.parent for folder in found]",
        "[folder for folder in found]",
        "package:// meshes are looked for inside a found package's folder instead of beside it (one level off)",
        "tests/test_xacro.py",
    ),
    _m(
        "D17", "descriptions", XACRO,
        "known |= set(_DECLARED.findall(text)) | set(_USED.findall(text))",
        "known |= set(_DECLARED.findall(text))",
        "an argument the files use but do not declare is refused as unknown",
        "tests/test_xacro.py",
    ),
    _m(
        "D18", "descriptions", MJCF,
        "out.append((element, 7, 0.0))",
        "out.append((element, 6, 0.0))",
        "a keyframe's qpos gives a free joint six numbers (its velocities' count) where its quaternion makes seven",
        "tests/test_mjcf_keyframes.py",
    ),
    _m(
        "D19", "descriptions", MJCF,
        'first.set("pos", " ".join(repr(float(v)) for v in offsets[1] - axis))',
        'first.set("pos", " ".join(repr(float(v)) for v in offsets[1] + axis))',
        "the body below a nested planar base's root is moved by its yaw axis's offset, not by the opposite: the "
        "platform turns about another point than MuJoCo's hinge",
        "tests/test_mjcf_planar_base.py",
    ),
    _m(
        "D20", "descriptions", WHEELS,
        "return float(np.linalg.norm(d - float(d @ axis) * axis))",
        "return float(np.linalg.norm(d))",
        "a wheel's offset from its steering joint is measured from the joint's origin, not its axis: a steered drive "
        "unit steered from above its wheel is taken for a caster",
        "tests/test_mjcf_steered_drive.py",
    ),
    _m(
        "D21", "descriptions", MJCF,
        'joints[role] = self.joint(jname, kind, attrs, chain[k][1], chain[k][1], Origin())\n'
        '            self.base_armature[role] = _float(attrs.get("armature", 0.0))',
        'joints[role] = self.joint(jname, kind, attrs, chain[k][1], chain[k][1], Origin())\n'
        '            self.base_armature[role] = _float(element.get("armature", 0.0))',
        "a nested planar base's armature is read from the joint's own attributes, its class's default ignored",
        "tests/test_mjcf_planar_base.py",
    ),
    _m(
        "D22", "descriptions", MJCF_BUILDER,
        "armature[root.idx_v : root.idx_v + 3] = (0.0, 0.0, yaw)\n"
        "            model.armature = armature\n"
        "            model.inertias[1] = model.inertias[1] + pin.Inertia(along, np.zeros(3), np.zeros((3, 3)))",
        "armature[root.idx_v : root.idx_v + 3] = (along, along, yaw)\n"
        "            model.armature = armature",
        "the planar base's slide armature is put on the platform joint's diagonal instead of as a point mass on the "
        "yaw axis: the same mass matrix, but the bias loses its omega x a v",
        "tests/test_mjcf_planar_base.py",
    ),
    # ----- ROS recordings
    _m(
        "R01", "recordings", RECORDINGS,
        "return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))",
        "return math.atan2(1.0 - 2.0 * (y * y + z * z), 2.0 * (w * z + x * y))",
        "the odometry's yaw takes atan2's arguments transposed",
        "tests/test_recordings.py",
    ),
    _m(
        "R02", "recordings", RECORDINGS,
        "ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)",
        "ns = int(stamp.sec) * 1_000_000 + int(stamp.nanosec)",
        "a stamp's seconds are turned into nanoseconds with 1e6 (a wrong unit)",
        "tests/test_recordings.py",
    ),
    _m(
        "R03", "recordings", RECORDINGS,
        "pose[:, 2] = np.unwrap(pose[:, 2])",
        "pose[:, 2] = pose[:, 2]",
        "the odometry's yaw is interpolated without unwrapping it",
        "tests/test_recordings.py",
    ),
    _m(
        "R04", "recordings", RECORDINGS,
        "if keep_s and s <= keep_s[-1]:",
        "if keep_s and s < keep_s[-1]:",
        "a message stamped the same instant as the one before is kept (a repeated stamp is no clock jump)",
        "tests/test_recordings.py", "tests/test_hostile_recordings.py",
    ),
    _m(
        "R05", "recordings", RECORDINGS,
        "high = None if end is None else origin + int(round(_within_years(end) * 1e9)) + 1",
        "high = None if end is None else origin + int(round(_within_years(end) * 1e9))",
        "--end cuts before its own instant: the message stamped at --end is lost (off by one)",
        "tests/test_recordings.py",
    ),
    _m(
        "R06", "recordings", RECORDINGS,
        "t = (base - base[0]).astype(float) * 1e-9",
        "t = (base - base[0]).astype(float) * 1e-6",
        "the time base is converted from nanoseconds with 1e-6 (a wrong unit)",
        "tests/test_recordings.py",
    ),
    _m(
        "R07", "recordings", RECORDINGS,
        "base = base[(base >= o_stamps[0]) & (base <= o_stamps[-1])]",
        "base = base[base <= o_stamps[-1]]",
        "joint states before the first odometry message are kept: the pose is extrapolated there",
        "tests/test_recordings.py",
    ),
    _m(
        "R08", "recordings", RECORDINGS,
        "o_t = (odom[0] - base[0]).astype(float)",
        "o_t = (odom[0] - odom[0][0]).astype(float)",
        "odometry times are counted from its own first message, not from the joint states' time base",
        "tests/test_recordings.py",
    ),
    # ----- teams and their coordination
    _m(
        "T01", "teams", MEMBERS,
        "points.append(center + R @ point)",
        "points.append(center + R.T @ point)",
        "a grasp point is turned from the object's frame to the world by the transposed rotation",
        "tests/test_team_spec.py",
    ),
    _m(
        "T02", "teams", MEMBERS,
        "return mass / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])",
        "return mass / 12.0 * np.array([a * a + b * b, a * a + c * c, b * b + c * c])",
        "a box's principal moments come out in reversed axis order",
        "tests/test_team_spec.py",
    ),
    _m(
        "T03", "teams", MEMBERS,
        'yaw = math.radians(_number(entry.get("yaw_deg", 0.0), f"{here} yaw_deg"))',
        'yaw = _number(entry.get("yaw_deg", 0.0), f"{here} yaw_deg")',
        "a robot's yaw_deg is used as radians (a wrong unit)",
        "tests/test_team_spec.py", "tests/test_team_carry.py",
    ),
    _m(
        "T04", "teams", MEMBERS,
        "return 0.4 * mass * radius2 * np.eye(3)",
        "return 2.0 / 3.0 * mass * radius2 * np.eye(3)",
        "the default object's inertia is a hollow sphere's (2/3 m r^2) instead of a solid one's (2/5 m r^2)",
        "tests/test_team.py",
    ),
    _m(
        "T05", "teams", TEAM_ANALYSIS,
        "        hand += k\n",
        "        hand += 1\n",
        "the next robot's blocks of the grasp matrix start one hand on, not after all of this robot's hands",
        "tests/test_team.py",
    ),
    _m(
        "T06", "teams", TEAM_ANALYSIS,
        "b = -Qinv @ terms.xi",
        "b = Qinv @ terms.xi",
        "the load sharing takes the robots' gravity bias with the wrong sign",
        "tests/test_team.py",
    ),
    _m(
        "T07", "teams", TEAM_ANALYSIS,
        "down = np.log(r0[ok] / r_down[ok]) / -math.log1p(-step)",
        "down = np.log(r0[ok] / r_down[ok]) / math.log1p(-step)",
        "a robot's share of the team's reach loses the sign of its downward step",
        "tests/test_team.py",
    ),
    _m(
        "T08", "teams", CAPACITY,
        "(2.0 * GRADIENT_STEP))\n        return np.array(grad)",
        "(GRADIENT_STEP))\n        return np.array(grad)",
        "the team's fast kinematic gradient divides its central difference by one step instead of two",
        "tests/test_team_carry.py::test_the_fast_kinematic_gradient_matches_the_stacked_terms_and_differences",
    ),
    _m(
        "T09", "teams", PLATFORM_TASK,
        "J = np.array([[ch, -sh], [sh, ch]]) @ local",
        "J = np.array([[ch, sh], [-sh, ch]]) @ local",
        "a platform's control-point velocity is turned to the world by the transposed heading rotation",
        "tests/test_team_carry.py",
    ),
    _m(
        "T10", "teams", TEAM_CARRY,
        "across = -np.sin(mid) * step[:, 0] + np.cos(mid) * step[:, 1]",
        "across = np.cos(mid) * step[:, 0] + np.sin(mid) * step[:, 1]",
        "a platform's slip is measured along its heading instead of across it",
        "tests/test_team_carry.py",
    ),
    _m(
        "T11", "teams", TEAM_CARRY,
        "shift = shift @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])",
        "shift = shift @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])",
        "a path given in the object's frame is turned to the world by the transposed rotation",
        "tests/test_team_carry.py",
    ),
    _m(
        "T12", "teams", TEAM_EFFORT,
        "A = np.linalg.solve(Q_t, P_t + J_u.T @ loads) / dt",
        "A = np.linalg.solve(Q_t, P_t) / dt",
        "the team's efforts leave out the object's inertia reflected through the grasp (a dropped term)",
        "tests/test_team_carry.py",
    ),
    _m(
        "T13", "teams", TEAM_EFFORT,
        "    bound = EFFORT_SHARE * limits\n",
        "    bound = limits\n",
        "the team's efforts are held to their whole limits: the 1 % reserve is dropped",
        "tests/test_team_carry.py",
    ),
    # ----- base placement
    _m(
        "P01", "placement", GRID,
        "return np.where(ellipsoids.empty, -np.inf, ellipsoids.center @ d + np.sqrt(np.sum((s * along) ** 2, axis=1)))",
        "return np.where(ellipsoids.empty, -np.inf, np.sqrt(np.sum((s * along) ** 2, axis=1)))",
        "an ellipsoid's capacity along a direction leaves out its centre (gravity's offset: a dropped term)",
        "tests/test_placement.py",
    ),
    _m(
        "P02", "placement", OPTIMIZE,
        "turned = self.hold.offsets @ Rz.T  # (k, 3)",
        "turned = self.hold.offsets @ Rz  # (k, 3)",
        "the hold's grasp offsets are turned by psi with the transposed rotation",
        "tests/test_placement_map.py",
    ),
    _m(
        "P03", "placement", OPTIMIZE,
        "d_psi[:, 0], d_psi[:, 1] = turned[:, 1], -turned[:, 0]",
        "d_psi[:, 0], d_psi[:, 1] = -turned[:, 1], turned[:, 0]",
        "the hold constraints' derivative in the hold's turn psi has the wrong sign",
        "tests/test_placement_map.py",
    ),
    _m(
        "P04", "placement", OPTIMIZE,
        "out[:, 0] = c * tangent_rows[:, 0] - s * tangent_rows[:, 1]\n"
        "        out[:, 1] = s * tangent_rows[:, 0] + c * tangent_rows[:, 1]",
        "out[:, 0] = c * tangent_rows[:, 0] + s * tangent_rows[:, 1]\n"
        "        out[:, 1] = -s * tangent_rows[:, 0] + c * tangent_rows[:, 1]",
        "constraint rows are moved from the platform's frame to the world's by the transposed heading rotation",
        "tests/test_placement_map.py",
    ),
    _m(
        "P05", "placement", OPTIMIZE,
        "R_t = Rz @ self.hold.rotations[i]",
        "R_t = self.hold.rotations[i] @ Rz",
        "a hand's held orientation is turned by psi about its own axis instead of the world's vertical",
        "tests/test_placement_map.py",
    ),
    _m(
        "P06", "placement", MAPS,
        "bound = max(bound, total + float(np.linalg.norm(hold.offsets[i])))",
        "bound = max(bound, total)",
        "the map's reach bound leaves out the grasp offset from the hand to the object's centre",
        "tests/test_placement_map.py",
    ),
    _m(
        "P07", "placement", MAPS,
        "heading[index] = math.atan2(math.sin(z[2]), math.cos(z[2]))",
        "heading[index] = z[2]",
        "a map cell's heading is kept as the optimiser left it, not wrapped into (-pi, pi]",
        "tests/test_placement_map.py",
    ),
    _m(
        "P08", "placement", SITE,
        'e[task.labels.index(label)] = 1.0 if site.direction[0] == "+" else -1.0',
        'e[task.labels.index(label)] = -1.0 if site.direction[0] == "+" else 1.0',
        "a site's grounded direction is read with its sign the wrong way round",
        "tests/test_site_grounded.py",
    ),
    _m(
        "P09", "placement", GROUNDED,
        "return 1e6 if value == -math.inf else -value",
        "return 1e6 if value == -math.inf else value",
        "the polytope placement's derivative-free search minimises the reading instead of maximising it",
        "tests/test_place_polytope.py",
    ),
)  # fmt: skip


# ----------------------------------------------------------------------------------------------
# checking the list


def problems(mutants: tuple[Mutant, ...] = MUTANTS, root: Path = ROOT) -> list[str]:
    """What is wrong with the list, one line each (empty when nothing is): an unknown area, a
    file outside its area or missing, a snippet not found exactly once, a replacement equal to
    it or that would not compile, a test file that does not exist, an id used twice."""
    out: list[str] = []
    seen: set[str] = set()
    for m in mutants:
        if m.id in seen:
            out.append(f"{m.id}: id used twice")
        seen.add(m.id)
        if m.area not in AREAS:
            out.append(f"{m.id}: unknown area {m.area!r}")
        elif not any(m.file == p or (p.endswith("/") and m.file.startswith(p)) for p in AREAS[m.area]):
            out.append(f"{m.id}: {m.file} is not in the {m.area} area")
        path = root / m.file
        if not path.is_file():
            out.append(f"{m.id}: no file {m.file}")
            continue
        text = path.read_text(encoding="utf-8")
        count = text.count(m.original)
        if count != 1:
            out.append(f"{m.id}: the original snippet occurs {count} times in {m.file}: {m.original!r}")
        elif m.replacement == m.original:
            out.append(f"{m.id}: the replacement is the original")
        else:
            try:
                compile(text.replace(m.original, m.replacement), m.file, "exec")
            except SyntaxError as exc:
                out.append(f"{m.id}: the mutated {m.file} does not compile ({exc.msg}, line {exc.lineno})")
        if not m.tests:
            out.append(f"{m.id}: no tests to run")
        for test in m.tests:
            if not (root / test.split("::")[0]).is_file():
                out.append(f"{m.id}: no test file {test.split('::')[0]}")
        if not m.description.strip():
            out.append(f"{m.id}: no description")
    return out


# ----------------------------------------------------------------------------------------------
# running


@dataclass(frozen=True)
class Outcome:
    """One mutant's run: ``caught``, ``survived``, ``timeout`` or ``error`` (pytest could not run
    the tests, e.g. a file failed to import for a reason other than a failing test), its seconds
    and the last lines pytest printed."""

    mutant: Mutant
    status: str
    seconds: float
    tail: str


def _copy_tree(root: Path, folder: Path) -> None:
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache", "*.egg-info")
    for name in COPIED:
        source = root / name
        if source.is_dir():
            shutil.copytree(source, folder / name, ignore=ignore, symlinks=True)
        elif source.is_file():
            shutil.copy2(source, folder / name)


def run_mutant(mutant: Mutant, root: Path = ROOT, timeout: float = TIMEOUT, *, apply: bool = True) -> Outcome:
    """Apply ``mutant`` in a temporary copy of the repository and run its tests there (without
    ``apply``, the tests on the unmutated copy)."""
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix=f"mobmanip-mutant-{mutant.id}-") as temporary:
        folder = Path(temporary)
        _copy_tree(root, folder)
        target = folder / mutant.file
        text = target.read_text(encoding="utf-8")
        if text.count(mutant.original) != 1:
            return Outcome(mutant, "error", 0.0, "the original snippet is not found exactly once")
        if apply:
            target.write_text(text.replace(mutant.original, mutant.replacement), encoding="utf-8")
        env = dict(os.environ)
        env["PYTHONPATH"] = str(folder / "src")
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        env.pop("PYTEST_ADDOPTS", None)
        command = [sys.executable, "-m", "pytest", "-n", "0", "-x", "-q", "-p", "no:cacheprovider", *mutant.tests]
        # a session of its own, so that a timeout or an interruption ends pytest and whatever it started
        run = subprocess.Popen(command, cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, start_new_session=True)  # fmt: skip
        try:
            output, _ = run.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            _stop(run)
            output, _ = run.communicate()
            return Outcome(mutant, "timeout", time.monotonic() - started, _tail(output))
        except BaseException:
            _stop(run)
            run.communicate()
            raise
        status = {0: "survived", 1: "caught"}.get(run.returncode, "error")
        return Outcome(mutant, status, time.monotonic() - started, _tail(output))


def _stop(run: subprocess.Popen) -> None:
    """End the process group of ``run`` (pytest and the processes its tests started)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(run.pid, signal.SIGKILL)


def _tail(text: str, lines: int = 3) -> str:
    kept = [line for line in text.splitlines() if line.strip()]
    return "\n".join(kept[-lines:])


def _select(ids: list[str] | None) -> tuple[Mutant, ...]:
    if not ids:
        return MUTANTS
    known = {m.id: m for m in MUTANTS}
    unknown = [i for i in ids if i not in known]
    if unknown:
        raise SystemExit(f"mutants.py: unknown mutant id(s): {', '.join(unknown)} (see --list)")
    return tuple(known[i] for i in ids)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Plant one bug at a time and see whether the tests catch it.")
    parser.add_argument("--only", nargs="+", metavar="ID", help="run these mutants only")
    parser.add_argument("--list", action="store_true", help="print the mutants and stop")
    parser.add_argument("--check", action="store_true", help="check every snippet is found once; run no tests")
    parser.add_argument("--baseline", action="store_true", help="run the chosen mutants' tests, unmutated (must pass)")
    parser.add_argument("--timeout", type=float, default=TIMEOUT, help=f"seconds per mutant (default {TIMEOUT:g})")
    args = parser.parse_args(argv)
    chosen = _select(args.only)
    if args.list:
        for m in chosen:
            print(f"{m.id}  {m.area:<12}  {m.file.removeprefix('src/mobmanip/')}: {m.description}")
            print(f"      tests: {' '.join(m.tests)}")
        return 0
    if args.check:
        found = problems(chosen)
        for line in found:
            print(line)
        counts = {area: sum(m.area == area for m in chosen) for area in AREAS}
        print(f"{len(chosen)} mutants ({', '.join(f'{a} {n}' for a, n in counts.items())}): "
              + ("every snippet found exactly once" if not found else f"{len(found)} problem(s)"))  # fmt: skip
        return 1 if found else 0
    if args.baseline:
        tests = tuple(dict.fromkeys(t for m in chosen for t in m.tests))
        plain = Mutant("baseline", "", chosen[0].file, chosen[0].original, chosen[0].original, "no bug", tests)
        outcome = run_mutant(plain, timeout=args.timeout * len(chosen), apply=False)
        print(f"baseline: {len(tests)} test files or tests, {outcome.seconds:.0f} s: "
              + ("every test passes" if outcome.status == "survived" else outcome.status))  # fmt: skip
        if outcome.status != "survived":
            print(outcome.tail)
        return 0 if outcome.status == "survived" else 1
    outcomes = []
    started = time.monotonic()
    for m in chosen:
        outcome = run_mutant(m, timeout=args.timeout)
        outcomes.append(outcome)
        print(f"{outcome.status:<9} {m.id}  {m.area:<12} {outcome.seconds:6.1f} s  {m.description}", flush=True)
        if outcome.status in ("error", "timeout"):
            print("          " + outcome.tail.replace("\n", "\n          "), flush=True)
    caught = sum(o.status == "caught" for o in outcomes)
    print(f"{caught} of {len(outcomes)} caught in {time.monotonic() - started:.0f} s")
    for status in ("survived", "timeout", "error"):
        ids = [o.mutant.id for o in outcomes if o.status == status]
        if ids:
            print(f"{status}: {', '.join(ids)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
