"""Sweeps: the measures' indices over object direction, distance, platform heading and limits.

A sweep places the object at direction ``angle`` (deg, from the platform heading, 0 in front,
90 to the left) and horizontal ``distance`` (m) from the arms' reference point, turns the
platform to ``heading`` (deg), and scales the wheels' velocity and effort limits; at every grid
point it records, for each measure swept (by default the kinematic and the dynamic ellipsoid;
any measure of :mod:`mobmanip.measures` with a batch form), the volume, the isotropy, the
directional capacity (how far the set reaches along a direction: ``max d . p`` over it, for a
unit d), the empty and degenerate flags and the measure's per-axis arrays (the ellipsoids'
semi-axes).

The arms' postures depend on (angle, distance) only; they are found once, in the calling
process, before the grid's configurations are analysed. Two providers (``SweepSpec.postures``):

``planar`` -- the paper's closed form, for robots with two 3-joint planar arms with vertical
axes sharing their first joint (like ``planar_dual_arm``; the reference point is that joint,
P_o): at a given reach, each arm's posture family is one-dimensional (q3 free, q2 from the
reach, two elbow branches); the sweep takes the posture that maximises the arm's own
manipulability sqrt(det(J J^T)) of its 2 x 3 horizontal Jacobian along that family (dense
sampling of q3 with zooming refinement, see :func:`posture_at_reach`). At the reach of the
globally optimal posture this is the paper's posture (:func:`mobmanip.casestudy.optimal_posture`).
Arm 1 (right) bends to the right and arm 2 takes the mirror image about the line from the base
to the object; q1 of each arm points its end effector at the object. Both end effectors hold
the object at its centre. Distances beyond the reach of the arms are unreachable.

``ik`` -- any robot: inverse kinematics holds the object as a reference posture (by default
the spec's ``[hold]`` posture, else its home configuration) does, turned towards the object's direction, with the object
centre at the given distance from the horizontal centroid of the arms' first joints and at the
reference posture's height; :mod:`mobmanip.posture` defines this precisely. Grid points where
some end effector cannot be brought within :data:`mobmanip.posture.POSITION_TOLERANCE` of its
target are unreachable.

``auto`` (the default) takes ``planar`` where it applies and no reference posture is given,
else ``ik``. Unreachable grid points hold NaN indices; a grid with no reachable point at all is
an error (:class:`UnreachableGridError`).

Execution: the grid's configurations are cut into chunks that run through any
:class:`concurrent.futures.Executor` (a local process pool by default; a ``dask.distributed``
client's ``get_executor()`` runs the same sweep across machines). Each worker loads the robot
itself from the spec name or path; only small arrays travel. Results do not depend on the
executor or the number of workers: chunk boundaries are fixed by ``chunk_size``.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import csv
import functools
import math
import multiprocessing
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pinocchio as pin

from .batch import BatchSetup, check_configurations, default_chunk, iter_terms
from .errors import MobmanipError, SpecError, UsageError
from .io import atomic_output, save_figure
from .measure import TaskSetBatch
from .measures import BatchRequest, Measure, evaluate_batch, resolve_measures
from .model import Robot, load_robot
from .posture import POSITION_TOLERANCE, IKPostureTable, reference_configuration, solve_postures
from .tasks import get_task

#: Grid axes in order: the result arrays have this shape (one entry per value).
AXES = ("angle_deg", "distance", "heading_deg", "wheel_velocity_scale", "wheel_effort_scale")
#: Scalar indices recorded by a sweep for every measure.
SCALAR_INDICES = ("volume", "isotropy", "capacity")
#: Flags recorded by a sweep for every measure.
FLAGS = ("degenerate", "empty")
#: Where the arms' postures come from (see the module's docstring).
POSTURE_METHODS = ("auto", "planar", "ik")


class GridError(UsageError):
    """A grid specification that cannot be parsed or makes no sense."""


class UnreachableGridError(GridError):
    """No grid point is within the arms' reach: the message names the grid's distances and angles."""


def parse_grid(text: str, name: str = "grid", positive: bool = False) -> np.ndarray:
    """Values of one grid axis from ``START:STOP:COUNT``, ``V1,V2,...`` or a single value.

    ``START:STOP:COUNT`` gives COUNT evenly spaced values from START to STOP, both included
    (``0:360:37`` is every 10 degrees). Values must be finite; with ``positive``, above zero.

    Raises:
        GridError: the text does not parse, COUNT is not a positive integer, or a value is bad.
    """
    text = str(text).strip()
    hint = "use START:STOP:COUNT, V1,V2,... or V"
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise GridError(f"{name}: expected START:STOP:COUNT, got {text!r}")
        count_text = parts[2].strip()
        if not count_text.isdigit() or int(count_text) < 1:
            raise GridError(f"{name}: COUNT must be a positive integer, got {parts[2]!r} in {text!r}")
        try:
            start, stop = float(parts[0]), float(parts[1])
        except ValueError:
            raise GridError(f"{name}: not a number in {text!r} ({hint})") from None
        count = int(count_text)
        if count == 1 and start != stop:
            raise GridError(f"{name}: one value from {start:g} to {stop:g}? use COUNT >= 2 or a single value")
        values = np.linspace(start, stop, count)
    else:
        try:
            values = np.array([float(v) for v in text.split(",")])
        except ValueError:
            raise GridError(f"{name}: not a number in {text!r} ({hint})") from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise GridError(f"{name}: values must be finite numbers, got {text!r}")
    if positive and np.any(values <= 0.0):
        raise GridError(f"{name}: values must be positive, got {text!r}")
    return values


@dataclass(frozen=True)
class SweepGrid:
    """The grid of a sweep; every axis is a 1-D array of values.

    Attributes:
        angle_deg: object directions from the platform heading (deg).
        distance: horizontal distances of the object from the arms' reference point (m): their
            common first joint for the planar postures, the horizontal centroid of their first
            joints for the inverse-kinematics ones.
        heading_deg: platform headings in the world (deg).
        wheel_velocity_scale: factors on both wheels' velocity limit.
        wheel_effort_scale: factors on both wheels' effort limit.
    """

    angle_deg: np.ndarray
    distance: np.ndarray
    heading_deg: np.ndarray = field(default_factory=lambda: np.zeros(1))
    wheel_velocity_scale: np.ndarray = field(default_factory=lambda: np.ones(1))
    wheel_effort_scale: np.ndarray = field(default_factory=lambda: np.ones(1))

    def __post_init__(self):
        for name in AXES:
            values = np.atleast_1d(np.asarray(getattr(self, name), dtype=float))
            if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)):
                raise GridError(f"{name}: a non-empty list of finite numbers is needed")
            if name in ("distance", "wheel_velocity_scale", "wheel_effort_scale") and np.any(values <= 0.0):
                raise GridError(f"{name}: values must be positive")
            object.__setattr__(self, name, values)

    @classmethod
    def parse(
        cls,
        angle: str,
        distance: str,
        heading: str = "0",
        wheel_velocity_scale: str = "1",
        wheel_effort_scale: str = "1",
    ) -> SweepGrid:
        """Build a grid from the command line's texts (see :func:`parse_grid`)."""
        return cls(
            parse_grid(angle, "--angle"),
            parse_grid(distance, "--distance", positive=True),
            parse_grid(heading, "--heading"),
            parse_grid(wheel_velocity_scale, "--wheel-velocity-scale", positive=True),
            parse_grid(wheel_effort_scale, "--wheel-effort-scale", positive=True),
        )

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(getattr(self, name)) for name in AXES)

    @property
    def n_configurations(self) -> int:
        """Distinct configurations: angle x distance x heading (limits do not change q)."""
        a, d, h, _, _ = self.shape
        return a * d * h

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))


# ----------------------------------------------------------------------------------------------
# arm postures at a given reach


@dataclass(frozen=True)
class PlanarArm:
    """A 3-joint arm whose joint axes are vertical: its geometry in the horizontal plane.

    Attributes:
        base: (x, y) of the first joint in the platform frame (m).
        links: link vectors a_1, a_2, a_3 (first joint to second, second to third, third to the
            end effector) at zero joint angles, (3, 2) (m).
        signs: +1 where a joint turns about +z, -1 about -z.
    """

    base: np.ndarray
    links: np.ndarray
    signs: np.ndarray

    def tip(self, theta: np.ndarray) -> np.ndarray:
        """End effector relative to the base for rotation angles theta = signs * q, (..., 2)."""
        theta = np.asarray(theta, dtype=float)
        phi1 = theta[..., 0]
        phi2 = phi1 + theta[..., 1]
        phi3 = phi2 + theta[..., 2]
        out = np.zeros(theta.shape[:-1] + (2,))
        for phi, a in zip((phi1, phi2, phi3), self.links):
            c, s = np.cos(phi), np.sin(phi)
            out[..., 0] += c * a[0] - s * a[1]
            out[..., 1] += s * a[0] + c * a[1]
        return out

    @property
    def max_reach(self) -> float:
        return float(np.sum(np.linalg.norm(self.links, axis=1)))


def planar_arm(robot: Robot, arm_index: int) -> PlanarArm:
    """The horizontal geometry of a 3-joint arm with vertical axes, read from the model.

    Raises:
        SpecError: the arm does not have 3 joints with vertical axes, or its motion is not the
            planar chain this reads (checked against Pinocchio at random angles).
    """
    arm = robot.arms[arm_index]
    if len(arm.joint_names) != 3:
        raise SpecError(f"sweep postures need 3-joint planar arms; arm {arm.name!r} has {len(arm.joint_names)}")
    model, data = robot.model, robot.data
    q0 = robot.configuration(joints=dict.fromkeys(arm.joint_names, 0.0))
    pin.computeJointJacobians(model, data, q0)
    pin.updateFramePlacements(model, data)
    points, signs = [], []
    for name in arm.joint_names:
        jid = model.getJointId(name)
        axis = pin.getJointJacobian(model, data, jid, pin.WORLD)[3:, model.joints[jid].idx_v]
        if abs(abs(axis[2]) - 1.0) > 1e-9:
            raise SpecError(
                f"sweep postures need vertical arm joints; {name!r} turns about {np.round(axis, 3).tolist()}"
            )
        signs.append(1.0 if axis[2] > 0 else -1.0)
        points.append(data.oMi[jid].translation[:2].copy())
    points.append(data.oMf[arm.frame_id].translation[:2].copy())
    points = np.array(points)
    result = PlanarArm(points[0].copy(), np.diff(points, axis=0), np.array(signs))
    rng = np.random.default_rng(0)
    for _ in range(3):
        q = rng.uniform(-math.pi, math.pi, 3)
        qa = robot.configuration(joints=dict(zip(arm.joint_names, q)))
        pin.framesForwardKinematics(model, data, qa)
        actual = data.oMf[arm.frame_id].translation[:2] - result.base
        if np.max(np.abs(actual - result.tip(result.signs * q))) > 1e-9:
            raise SpecError(f"arm {arm.name!r} of {robot.name!r} is not a planar chain with vertical axes")
    return result


def _manipulability(arm: PlanarArm, theta2: np.ndarray, theta3: np.ndarray) -> np.ndarray:
    """sqrt(det(J J^T)) of the 2 x 3 horizontal Jacobian at q1 = 0 (it does not depend on q1).

    Column i of J is +-e_z x (tip - p_i); by Cauchy-Binet det(J J^T) is the sum of the squared
    2 x 2 minors, i.e. of the squared cross products of the vectors tip - p_i.
    """
    a1, a2, a3 = arm.links
    c2, s2 = np.cos(theta2), np.sin(theta2)
    phi = theta2 + theta3
    c3, s3 = np.cos(phi), np.sin(phi)
    last = np.stack([c3 * a3[0] - s3 * a3[1], s3 * a3[0] + c3 * a3[1]], axis=-1)  # tip - p_3
    middle = np.stack([c2 * a2[0] - s2 * a2[1], s2 * a2[0] + c2 * a2[1]], axis=-1) + last  # tip - p_2
    cols = (a1 + middle, middle, last)  # tip - p_1 (arm.tip at q1 = 0), tip - p_2, tip - p_3
    det = np.zeros_like(theta2)
    for i in range(3):
        for j in range(i + 1, 3):
            det += (cols[i][..., 0] * cols[j][..., 1] - cols[i][..., 1] * cols[j][..., 0]) ** 2
    return np.sqrt(det)


def _theta2_for(arm: PlanarArm, theta3: np.ndarray, reach, branch: int) -> np.ndarray:
    """theta2 putting the end effector at ``reach`` from the base (NaN where impossible);
    ``theta3`` and ``reach`` broadcast."""
    a1 = arm.links[0]
    c3, s3 = np.cos(theta3), np.sin(theta3)
    bx = arm.links[1][0] + c3 * arm.links[2][0] - s3 * arm.links[2][1]
    by = arm.links[1][1] + s3 * arm.links[2][0] + c3 * arm.links[2][1]
    nb = np.hypot(bx, by)
    na = float(np.linalg.norm(a1))
    with np.errstate(invalid="ignore", divide="ignore"):
        cos_ = (np.asarray(reach) ** 2 - na**2 - nb**2) / (2.0 * na * nb)
        cos_ = np.where(np.abs(cos_) <= 1.0 + 1e-12, np.clip(cos_, -1.0, 1.0), np.nan)  # rounding at full reach
        angle = np.arccos(cos_)
    return math.atan2(a1[1], a1[0]) - np.arctan2(by, bx) + branch * angle


@dataclass(frozen=True)
class ReachPosture:
    """The most manipulable posture of one arm at a given reach.

    Attributes:
        q: joint angles (q1, q2, q3) with q1 = 0 (rad).
        manipulability: sqrt(det(J J^T)) of the arm's horizontal Jacobian (m^2).
        bearing: direction of the end effector from the first joint at q1 = 0 (rad).
    """

    q: tuple[float, float, float]
    manipulability: float
    bearing: float


def postures_at_reaches(
    arm: PlanarArm, reaches: Sequence[float], bend: int = 1, samples: int = 721, refinements: int = 8
) -> np.ndarray:
    """Maximise an arm's own manipulability over its postures at each reach (vectorised).

    The family at a reach is parametrised by theta3 in [-pi, pi] and the elbow branch; theta2
    follows from the reach. The search samples theta3 on ``samples`` points on both branches,
    then zooms ``refinements`` times around the best sample (41 samples over +-2 previous steps
    each time), to about (4 pi / samples) / 10^refinements rad in theta3 -- below the flatness
    of the maximum in double precision (about 1e-8 rad).

    Args:
        arm: the arm's planar geometry.
        reaches: distances from the first joint to the end effector (m), (D,).
        bend: +1 for the posture with positive bearing (the end effector counterclockwise from
            the first link at q1 = 0: the elbow to the right of the line from base to end
            effector, as :func:`mobmanip.casestudy.optimal_posture`), -1 for its mirror image
            (-q2, -q3) (exact when the links are collinear at zero angles, as in the paper's arm).

    Returns:
        (D, 4): q2, q3 (rad), manipulability (m^2), bearing (rad); NaN rows where no posture
        reaches that far (or that close).
    """
    reaches = np.asarray(reaches, dtype=float).reshape(-1)
    D = reaches.size
    theta3 = np.linspace(-math.pi, math.pi, samples)
    step = theta3[1] - theta3[0]
    offsets = np.linspace(-1.0, 1.0, 41)
    best = np.full((D, 3), np.nan)  # value, theta2, theta3
    rho = reaches[:, None]
    for branch in (1, -1):
        w = _manipulability(arm, _theta2_for(arm, theta3[None, :], rho, branch), np.broadcast_to(theta3, (D, samples)))
        found = ~np.all(np.isnan(w), axis=1)
        i = np.argmax(np.where(np.isnan(w), -np.inf, w), axis=1)
        center, width = theta3[i], np.full(D, 2.0 * step)
        for _ in range(refinements):
            t3 = center[:, None] + width[:, None] * offsets[None, :]
            w = _manipulability(arm, _theta2_for(arm, t3, rho, branch), t3)
            ok = ~np.all(np.isnan(w), axis=1)
            j = np.argmax(np.where(np.isnan(w), -np.inf, w), axis=1)
            center = np.where(ok, t3[np.arange(D), j], center)
            width = width / 20.0
        t2 = _theta2_for(arm, center, reaches, branch)
        value = _manipulability(arm, t2, center)
        better = found & np.isfinite(value) & ~(value <= best[:, 0] + 1e-15)
        best[better] = np.stack([value, t2, center], axis=1)[better]
    value, t2, t3 = best.T
    tip = arm.tip(np.stack([np.zeros(D), t2, t3], axis=1))
    bearing = np.arctan2(tip[:, 1], tip[:, 0])
    mirror = bend * bearing < 0
    t2, t3 = np.where(mirror, -t2, t2), np.where(mirror, -t3, t3)
    tip = arm.tip(np.stack([np.zeros(D), t2, t3], axis=1))
    bearing = np.arctan2(tip[:, 1], tip[:, 0])
    out = np.stack([t2 * arm.signs[1], t3 * arm.signs[2], value, bearing], axis=1)
    out[~(reaches > 0.0)] = np.nan
    return out


def posture_at_reach(arm: PlanarArm, reach: float, bend: int = 1, **search) -> ReachPosture | None:
    """The most manipulable posture at one reach (see :func:`postures_at_reaches`), or ``None``."""
    q2, q3, value, bearing = postures_at_reaches(arm, [reach], bend, **search)[0]
    if math.isnan(value):
        return None
    return ReachPosture((0.0, float(q2), float(q3)), float(value), float(bearing))


@dataclass(frozen=True)
class PostureTable:
    """The two arms' postures at every distance of a grid (the planar closed form).

    Attributes:
        reachable: whether both arms reach each distance, (D,).
        right: (q2, q3, bearing) of arm 1 per distance, (D, 3) (NaN where unreachable).
        left: the same for arm 2, (D, 3).
        signs: axis signs of each arm's first joint, (2,).
        joint_names: the arm joints, arm 1's three then arm 2's.
    """

    reachable: np.ndarray
    right: np.ndarray
    left: np.ndarray
    signs: np.ndarray
    joint_names: tuple[str, ...] = ()

    method = "planar"

    def joint_values(self, alpha: np.ndarray, idist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Arm joint positions for object directions ``alpha`` (rad) at distance indices ``idist``.

        Returns:
            (N, 6) joint positions (zero where unreachable) and whether each row is reachable.
        """
        reachable = self.reachable[idist]
        columns = []
        for values, sign in zip((self.right, self.left), self.signs):
            q2, q3, bearing = (np.where(reachable, values[idist, c], 0.0) for c in range(3))
            q1 = np.where(reachable, sign * (alpha - bearing), 0.0)
            columns += [q1, q2, q3]
        return np.stack(columns, axis=1), reachable


def posture_table(robot: Robot, distances: Sequence[float], map_fn=map) -> PostureTable:
    """Postures of both arms (arm 1 bending right, arm 2 its mirror image) at each distance.

    ``map_fn`` (e.g. an executor's ``map``) runs the search on slices of the distances; each
    distance's posture is found independently, so the result does not depend on it.

    Raises:
        SpecError: not a robot with two planar 3-joint arms sharing their first joint's position.
    """
    if len(robot.arms) != 2:
        raise SpecError(
            f"sweeps need a robot with two arms (like planar_dual_arm); {robot.name!r} has {len(robot.arms)}"
        )
    arms = [planar_arm(robot, 0), planar_arm(robot, 1)]
    if np.max(np.abs(arms[0].base - arms[1].base)) > 1e-9:
        raise SpecError(f"sweeps need both arms of {robot.name!r} to share their first joint's (x, y) position")
    mirror = np.allclose(arms[0].links, arms[1].links, atol=1e-12) and np.array_equal(arms[0].signs, arms[1].signs)
    right_all = _postures_mapped(map_fn, arms[0], distances, 1)
    if mirror:
        left_all = right_all * np.array([-1.0, -1.0, 1.0, -1.0])
    else:
        left_all = _postures_mapped(map_fn, arms[1], distances, -1)
    reachable = np.isfinite(right_all[:, 2]) & np.isfinite(left_all[:, 2])
    right = np.where(reachable[:, None], right_all[:, [0, 1, 3]], np.nan)
    left = np.where(reachable[:, None], left_all[:, [0, 1, 3]], np.nan)
    names = tuple(name for arm in robot.arms for name in arm.joint_names)
    return PostureTable(reachable, right, left, np.array([arms[0].signs[0], arms[1].signs[0]]), names)


def _postures_mapped(map_fn, arm: PlanarArm, distances, bend: int, pieces: int = 8) -> np.ndarray:
    """:func:`postures_at_reaches` over ``pieces`` slices of the distances, through ``map_fn``."""
    parts = np.array_split(np.asarray(distances, dtype=float).reshape(-1), pieces)
    results = list(map_fn(functools.partial(postures_at_reaches, arm, bend=bend), parts))
    return np.concatenate(results, axis=0)


@dataclass(frozen=True)
class _PostureRows:
    """Inverse-kinematics postures of consecutive (angle, distance) pairs, for one chunk.

    Attributes:
        first: flat index (angle * D + distance) of the first row.
        joints: arm joint positions, (rows, n); NaN where unreachable.
        reachable: (rows,).
        joint_names: the arm joints.
    """

    first: int
    joints: np.ndarray
    reachable: np.ndarray
    joint_names: tuple[str, ...]


def _posture_rows(table: IKPostureTable, first: int = 0, stop: int | None = None) -> _PostureRows:
    n = table.joints.shape[-1]
    joints = table.joints.reshape(-1, n)[first:stop]
    return _PostureRows(first, joints, table.reachable.reshape(-1)[first:stop], table.joint_names)


def sweep_postures(
    robot: Robot, grid: SweepGrid, method: str = "auto", reference=None, map_fn=map
) -> PostureTable | IKPostureTable:
    """The arms' postures for a grid (see the module's docstring for the methods).

    Args:
        robot: the robot.
        grid: the grid (only its angles and distances matter).
        method: ``"auto"``, ``"planar"`` or ``"ik"``.
        reference: joint positions by name for the inverse kinematics' reference posture
            (joints not named stay at home); ``None``: the spec's hold posture
            (:meth:`mobmanip.model.Robot.hold_configuration`).
        map_fn: runs the planar posture search on slices of the distances (an executor's
            ``map`` spreads it over workers); the result does not depend on it.

    Raises:
        SpecError: ``"planar"`` on a robot without two planar 3-joint arms sharing their base.
        UsageError: an unknown method, or a reference posture with ``"planar"``.
        JointNotFoundError, ConfigurationError: a bad reference posture.
    """
    if method not in POSTURE_METHODS:
        raise UsageError(f"postures must be one of {', '.join(POSTURE_METHODS)}, got {method!r}")
    if method == "planar" and reference is not None:
        raise UsageError("the planar postures follow the paper's closed form; a reference posture needs postures 'ik'")
    if method != "ik" and reference is None:
        try:
            return posture_table(robot, grid.distance, map_fn)
        except SpecError:
            if method == "planar":
                raise
    q_ref = robot.hold_configuration() if reference is None else reference_configuration(robot, reference)
    return solve_postures(robot, grid.angle_deg, grid.distance, q_ref)


def sweep_configurations(
    robot: Robot, grid: SweepGrid, table: PostureTable | IKPostureTable | _PostureRows, flat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Configurations at flat indices into (angle, distance, heading), and which are reachable.

    Unreachable rows get the home posture (finite, but not meaningful).
    """
    ia, idist, ih = np.unravel_index(flat, grid.shape[:3])
    n = len(flat)
    qs = np.repeat(robot.neutral()[None, :], n, axis=0)
    heading = np.radians(grid.heading_deg[ih])
    qs[:, 0:2] = 0.0
    qs[:, 2], qs[:, 3] = np.cos(heading), np.sin(heading)
    if isinstance(table, PostureTable):
        values, reachable = table.joint_values(np.radians(grid.angle_deg[ia]), idist)
        names = tuple(name for arm in robot.arms for name in arm.joint_names)
        rows = np.arange(n)
    else:
        chunk = _posture_rows(table) if isinstance(table, IKPostureTable) else table
        pair = ia * grid.shape[1] + idist - chunk.first
        reachable = chunk.reachable[pair]
        rows = np.flatnonzero(reachable)
        values, names = chunk.joints[pair[rows]], chunk.joint_names
    model = robot.model
    for name, value in zip(names, values.T):
        joint = model.joints[model.getJointId(name)]
        if joint.nq == 2:
            qs[rows, joint.idx_q], qs[rows, joint.idx_q + 1] = np.cos(value), np.sin(value)
        else:
            qs[rows, joint.idx_q] = value
    return qs, reachable


# ----------------------------------------------------------------------------------------------
# the job and its chunks


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep, in a form any worker process or machine can rebuild the robot from.

    Attributes:
        robot: built-in robot name or spec path (workers load it themselves; for a cluster,
            the path must exist on every worker).
        task: task space; defaults to the spec's ``default_task``.
        platform: ``"own"`` or ``"fixed"`` (locked platform).
        object_mass: object mass (kg); defaults to the spec's.
        decoupled: decoupled dynamics (the paper's Sec. 4.3).
        wheel_velocity_limit: both wheels' qdot_max before scaling (rad/s); default: the spec's.
        wheel_effort_limit: both wheels' tau_max before scaling (N m); default: the spec's.
        direction: the capacity direction: ``"radial"`` (from the reference point towards the object,
            in the horizontal plane), ``"tangential"`` (90 deg to the left of it) or task
            coordinates, e.g. ``(1, 0)`` (world frame; normalised).
        postures: ``"auto"``, ``"planar"`` or ``"ik"`` (see the module's docstring).
        reference: the inverse kinematics' reference posture, joint positions by name (a
            mapping or (name, value) pairs; joints not named stay at home); ``None``: the spec's
            hold posture, else the home configuration. Stored as a tuple of pairs.
        measures: the measures to sweep, by name (each needs a batch form, see
            :mod:`mobmanip.measures`); ``None``: the default ones (``kinematic``, ``dynamic``).
            :func:`run_sweep` stores them resolved, in the registry's order.
    """

    robot: str
    task: str | None = None
    platform: str = "own"
    object_mass: float | None = None
    decoupled: bool = False
    wheel_velocity_limit: float | None = None
    wheel_effort_limit: float | None = None
    direction: str | tuple[float, ...] = "radial"
    postures: str = "auto"
    reference: tuple[tuple[str, float], ...] | None = None
    measures: tuple[str, ...] | None = None

    def __post_init__(self):
        if self.measures is not None:
            names = (self.measures,) if isinstance(self.measures, str) else self.measures
            try:
                object.__setattr__(self, "measures", tuple(names))
            except TypeError:
                raise UsageError(f"measures must be measure names, got {self.measures!r}") from None
        if self.reference is not None:
            pairs = self.reference.items() if isinstance(self.reference, Mapping) else self.reference
            try:
                pairs = tuple((str(name), value) for name, value in pairs)
            except (TypeError, ValueError):
                raise UsageError(f"reference must map joint names to positions, got {self.reference!r}") from None
            object.__setattr__(self, "reference", pairs)

    def load(self) -> Robot:
        """The robot with the platform and base wheel limits applied."""
        robot = load_robot(self.robot)
        if self.wheel_velocity_limit is not None or self.wheel_effort_limit is not None:
            robot = robot.with_wheel_limits(velocity=self.wheel_velocity_limit, effort=self.wheel_effort_limit)
        if self.platform in ("fixed", "locked"):
            robot = robot.with_platform("fixed")
        elif self.platform != "own":
            raise UsageError(f"platform must be 'own' or 'fixed', got {self.platform!r}")
        return robot


@dataclass(frozen=True)
class _Job:
    spec: SweepSpec
    grid: SweepGrid
    table: PostureTable | _PostureRows  # the planar table, or the chunk's own rows of an IK table
    start: int
    stop: int
    chunk_size: int


_WORKER_CACHE: dict = {}


def _worker_setup(spec: SweepSpec):
    """The robot and batch setup for a spec, loaded once per process."""
    key = spec
    if key not in _WORKER_CACHE:
        robot = spec.load()
        _WORKER_CACHE.clear()
        _WORKER_CACHE[key] = (robot, BatchSetup(robot, spec.task, spec.object_mass))
    return _WORKER_CACHE[key]


def _wheel_limits(robot: Robot, base: np.ndarray, scales: np.ndarray) -> list[np.ndarray]:
    """Limit vectors with both drive wheels' entries scaled (unchanged with a locked platform)."""
    n_eta = robot.platform.n_reduced if robot.platform.kind == "differential_drive" else 0
    out = []
    for s in scales:
        limits = np.array(base, dtype=float)
        limits[:n_eta] *= s
        out.append(limits)
    return out


def _directions(spec: SweepSpec, m: int, alpha_world: np.ndarray) -> np.ndarray:
    """Unit capacity directions per configuration, (n, m)."""
    d = np.zeros((len(alpha_world), m))
    if isinstance(spec.direction, str):
        phi = alpha_world + (math.pi / 2 if spec.direction == "tangential" else 0.0)
        d[:, 0], d[:, 1] = np.cos(phi), np.sin(phi)
    else:
        d[:] = np.asarray(spec.direction, dtype=float) / np.linalg.norm(spec.direction)
    return d


def _record(e: TaskSetBatch, measure: Measure, directions: np.ndarray, rows: np.ndarray, out: dict, col: int):
    """Store one measure's indices of a chunk's rows at limit column ``col``."""
    prefix = measure.name
    out[f"{prefix}_volume"][rows, col] = e.volume
    out[f"{prefix}_isotropy"][rows, col] = e.isotropy
    capacity = e.support(directions)
    out[f"{prefix}_capacity"][rows, col] = np.where(e.empty, np.nan, capacity)
    for attribute, _ in measure.axis_indices:
        out[f"{prefix}_{attribute}"][rows, col] = getattr(e, attribute)
    out[f"{prefix}_degenerate"][rows, col] = e.degenerate
    out[f"{prefix}_empty"][rows, col] = e.empty


def _empty_chunk(n: int, nv: int, ne: int, m: int, measures: tuple[Measure, ...]) -> dict:
    """NaN-filled (False for flags) result arrays of a chunk of n configurations: per measure,
    one column per value of its limit scale (nv velocity, ne effort scales)."""
    out = {"reachable": np.zeros(n, dtype=bool)}
    for measure in measures:
        prefix, count = measure.name, nv if measure.quantity.limits == "velocity" else ne
        for name in SCALAR_INDICES:
            out[f"{prefix}_{name}"] = np.full((n, count), np.nan)
        for attribute, _ in measure.axis_indices:
            out[f"{prefix}_{attribute}"] = np.full((n, count, m), np.nan)
        for flag in FLAGS:
            out[f"{prefix}_{flag}"] = np.zeros((n, count), dtype=bool)
    return out


def _run_job(job: _Job) -> tuple[int, dict]:
    """One chunk of a sweep: its configurations' indices at every limit scale (a worker task)."""
    robot, setup = _worker_setup(job.spec)
    grid = job.grid
    flat = np.arange(job.start, job.stop)
    qs, reachable = sweep_configurations(robot, grid, job.table, flat)
    nv, ne, m = len(grid.wheel_velocity_scale), len(grid.wheel_effort_scale), setup.m
    measures = resolve_measures(job.spec.measures, sweep=True)
    out = _empty_chunk(len(flat), nv, ne, m, measures)
    out["reachable"][:] = reachable
    rows = np.flatnonzero(reachable)
    if rows.size == 0:
        return job.start, out
    qs = check_configurations(robot, qs[rows])
    ia, _, ih = np.unravel_index(flat[rows], grid.shape[:3])
    alpha_world = np.radians(grid.angle_deg[ia] + grid.heading_deg[ih])
    directions = _directions(job.spec, m, alpha_world)
    vlims = _wheel_limits(robot, robot.velocity_limits, grid.wheel_velocity_scale)
    elims = _wheel_limits(robot, robot.effort_limits, grid.wheel_effort_scale)
    for start, t in iter_terms(setup, qs, min(job.chunk_size, default_chunk())):
        n = t.n
        sub = rows[start : start + n]
        dirs = directions[start : start + n]
        # one pass per scale, every measure that still has a scale left at once (measures that
        # share a batch form, like the two ellipsoids, in one call)
        for col in range(max(len(vlims), len(elims))):
            limits = {}
            for measure in measures:
                by_scale = vlims if measure.quantity.limits == "velocity" else elims
                if col < len(by_scale):
                    limits[measure.name] = by_scale[col]
            results = evaluate_batch(BatchRequest(setup, t, limits, job.spec.decoupled))
            for measure in measures:
                if measure.name in limits:
                    _record(results[measure.name], measure, dirs, sub, out, col)
    return job.start, out


# ----------------------------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class SweepResult:
    """Indices over a sweep grid.

    ``indices[name]`` has the grid's shape (angle, distance, heading, wheel velocity scale,
    wheel effort scale), with a trailing task axis for per-axis arrays (``*_semi_axes``). Names:
    ``<measure>_{volume,isotropy,capacity,degenerate,empty}`` for every measure swept, and its
    per-axis arrays (``<measure>_semi_axes`` for the ellipsoids), e.g. ``kinematic_volume``.
    Indices of velocities (kinematic) do not depend on the effort scale, nor those of
    accelerations (dynamic) on the velocity scale; both are repeated along that axis.
    Unreachable grid points hold NaN (and False flags).

    Attributes:
        spec: what was swept.
        grid: the grid.
        task: task-space name.
        task_axes: labels of the task coordinates.
        reachable: whether the arms reach each (angle, distance, heading), (A, D, H).
        indices: the arrays described above.
        postures: the arms' postures: a :class:`PostureTable` per distance (planar closed form)
            or a :class:`mobmanip.posture.IKPostureTable` per (angle, distance); see
            :meth:`joint_positions` for both as one array.
    """

    spec: SweepSpec
    grid: SweepGrid
    task: str
    task_axes: tuple[str, ...]
    reachable: np.ndarray
    indices: dict
    postures: PostureTable | IKPostureTable

    def joint_positions(self) -> tuple[tuple[str, ...], np.ndarray]:
        """The arm joints' names and positions (rad or m) at every (angle, distance), (A, D, n);
        NaN where unreachable. The platform heading turns the whole robot and does not change them."""
        table = self.postures
        if isinstance(table, IKPostureTable):
            return table.joint_names, table.joints
        a, d = self.grid.shape[:2]
        ia, idist = (i.ravel() for i in np.meshgrid(np.arange(a), np.arange(d), indexing="ij"))
        values, reachable = table.joint_values(np.radians(self.grid.angle_deg[ia]), idist)
        values[~reachable] = np.nan
        return table.joint_names, values.reshape(a, d, -1)

    @property
    def measures(self) -> tuple[Measure, ...]:
        """The definitions of the measures swept, in order."""
        return resolve_measures(self.spec.measures, sweep=True)

    def index(self, name: str) -> np.ndarray:
        """One index by name: ``kinematic.volume``, ``dynamic.semi_axis_1`` (largest), ...

        Raises:
            UsageError: an unknown name (the message lists the valid ones).
        """
        kind, what, k = check_index_name(name, len(self.task_axes), self.spec.measures)
        if k is None:
            return self.indices[f"{kind}_{what}"]
        return self.indices[f"{kind}_{what}"][..., k - 1]

    def save_npz(self, path: str | Path) -> Path:
        """Write the grid axes, the indices, the postures and the settings to a NumPy ``.npz`` file.

        Keys: the grid axes (:data:`AXES`), every index array, ``reachable`` (A, D, H),
        ``posture_joint_names`` and ``posture_joints`` (A, D, n) (:meth:`joint_positions`), and
        ``meta_*`` texts (``meta_postures`` is ``planar`` or ``ik``). Planar postures add
        ``posture_right`` / ``posture_left`` ((q2, q3, bearing) per distance); inverse-kinematics
        ones add ``posture_position_error`` and ``posture_rotation_error`` (A, D),
        ``posture_reference`` (the reference configuration) and the hold: ``hold_origin``,
        ``hold_height``, ``hold_offsets``, ``hold_rotations`` (see :class:`mobmanip.posture.Hold`).
        """
        path = Path(path)
        arrays = {name: getattr(self.grid, name) for name in AXES}
        arrays.update(self.indices)
        arrays["reachable"] = self.reachable
        table = self.postures
        names, joints = self.joint_positions()
        arrays["posture_joint_names"] = np.array(names, dtype=str)
        arrays["posture_joints"] = joints
        if isinstance(table, PostureTable):
            arrays["posture_right"] = table.right
            arrays["posture_left"] = table.left
        else:
            arrays["posture_position_error"] = table.position_error
            arrays["posture_rotation_error"] = table.rotation_error
            arrays["posture_reference"] = table.reference
            arrays["hold_origin"] = table.hold.origin
            arrays["hold_height"] = np.array(table.hold.height)
            arrays["hold_offsets"] = table.hold.offsets
            arrays["hold_rotations"] = table.hold.rotations
        meta = {
            "robot": str(self.spec.robot),
            "task": self.task,
            "task_axes": ",".join(self.task_axes),
            "platform": self.spec.platform,
            "decoupled": str(self.spec.decoupled),
            "object_mass": str(self.spec.object_mass),
            "direction": str(self.spec.direction),
            "axes": ",".join(AXES),
            "postures": table.method,
        }
        arrays.update({f"meta_{k}": np.array(v) for k, v in meta.items()})
        with atomic_output(path, "wb") as f:
            np.savez_compressed(f, **arrays)
        return path

    def save_csv(self, path: str | Path) -> Path:
        """Write one row per grid point: the axis values, reachability and every index."""
        path = Path(path)
        m = len(self.task_axes)
        grids = np.meshgrid(*(getattr(self.grid, name) for name in AXES), indexing="ij")
        reach = np.broadcast_to(self.reachable[..., None, None], self.grid.shape)
        columns, header = [g.ravel() for g in grids], list(AXES)
        columns.append(reach.ravel().astype(int))
        header.append("reachable")
        for measure in self.measures:
            kind = measure.name
            for name in SCALAR_INDICES:
                columns.append(self.indices[f"{kind}_{name}"].ravel())
                header.append(f"{kind}_{name}")
            for attribute, stem in measure.axis_indices:
                for k in range(m):
                    columns.append(self.indices[f"{kind}_{attribute}"][..., k].ravel())
                    header.append(f"{kind}_{stem}_{k + 1}")
            for flag in FLAGS:
                columns.append(self.indices[f"{kind}_{flag}"].ravel().astype(int))
                header.append(f"{kind}_{flag}")
        with atomic_output(path, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(header)
            table = np.column_stack(columns)
            step = 65536
            for start in range(0, table.shape[0], step):
                writer.writerows([f"{v:.12g}" for v in row] for row in table[start : start + step])
        return path


def check_index_name(name: str, m: int, measures=None) -> tuple[str, str, int | None]:
    """Split an index name into (measure, index or per-axis array, axis number or None):
    ``"kinematic.volume"`` gives ``("kinematic", "volume", None)``, ``"dynamic.semi_axis_2"``
    gives ``("dynamic", "semi_axes", 2)``.

    Args:
        name: ``<measure>.<index>``.
        m: task dimension.
        measures: the measures swept (names; ``None``: the default ones).

    Raises:
        UsageError: an unknown name (the message lists the valid ones for an m-dimensional task).
    """
    kind, _, what = str(name).replace("-", "_").partition(".")
    for measure in resolve_measures(measures, sweep=True):
        if kind != measure.name:
            continue
        if what in SCALAR_INDICES:
            return kind, what, None
        for attribute, stem in measure.axis_indices:
            number = what[len(stem) + 1 :] if what.startswith(f"{stem}_") else ""
            if number.isdigit() and 1 <= int(number) <= m:
                return kind, attribute, int(number)
    raise UsageError(f"unknown index {name!r}; expected one of {', '.join(index_names(m, measures))}")


def index_names(m: int, measures=None) -> list[str]:
    """Names accepted by :meth:`SweepResult.index` for an m-dimensional task and the measures
    swept (names; ``None``: the default ones)."""
    out = []
    for measure in resolve_measures(measures, sweep=True):
        out += [f"{measure.name}.{name}" for name in SCALAR_INDICES]
        for _, stem in measure.axis_indices:
            out += [f"{measure.name}.{stem}_{k}" for k in range(1, m + 1)]
    return out


# ----------------------------------------------------------------------------------------------
# running


def default_workers() -> int:
    """Worker processes by default: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def _local_pool(workers: int, mp_context: str | None) -> cf.ProcessPoolExecutor:
    """A process pool. By default "fork" where the platform has it (no ``__main__`` guard needed
    in user scripts; the workers still load the robot themselves: the parent never fills their
    cache), else "spawn"."""
    if mp_context is None:
        mp_context = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    return cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(mp_context))


def run_sweep(
    spec: SweepSpec,
    grid: SweepGrid,
    *,
    executor: cf.Executor | None = None,
    workers: int | None = None,
    chunk_size: int = 4096,
    progress: bool = False,
    mp_context: str | None = None,
) -> SweepResult:
    """Run a sweep, serially, on local processes, or on any ``concurrent.futures.Executor``.

    Args:
        spec: what to sweep (robot by name or spec path, task, platform, limits...).
        grid: the grid.
        executor: run the chunks here, e.g. ``dask.distributed.Client(...).get_executor()``;
            the caller owns it. Without one: a local process pool of ``workers`` processes, or
            in this process when ``workers == 1``.
        workers: local worker processes (default: the usable cores).
        chunk_size: configurations per task; memory per task is proportional to it, and the
            results do not depend on it only up to rounding (keep it fixed to compare runs).
        progress: show a tqdm progress bar on standard error.
        mp_context: start method of the local pool ("fork", "spawn", "forkserver"); default
            "fork" where available. With "spawn"/"forkserver", scripts need the usual
            ``if __name__ == "__main__":`` guard.

    Raises:
        SpecError: ``postures="planar"`` on a robot without planar 3-joint arms sharing their base.
        UnknownMeasureError, MeasureError: an unknown measure, or one without a batch form.
        UnreachableGridError: the arms reach no grid point.
        GridError, UsageError: bad grid or settings.
    """
    if not isinstance(chunk_size, int) or chunk_size < 1:
        raise UsageError(f"chunk size must be a positive integer, got {chunk_size!r}")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise UsageError(f"workers must be a positive integer, got {workers!r}")
    robot = spec.load()
    task = get_task(spec.task or robot.spec.default_task)
    measures = tuple(measure.name for measure in resolve_measures(spec.measures, sweep=True))
    spec = replace(spec, task=task.name, direction=_check_direction(spec.direction, task.dim), measures=measures)
    BatchSetup(robot, task.name, spec.object_mass)  # validate the object mass here, once
    n_workers = workers or default_workers()
    with contextlib.ExitStack() as stack:
        if executor is None and n_workers > 1:
            executor = stack.enter_context(_local_pool(n_workers, mp_context))
            window = 4 * n_workers
        else:
            window = 64
        return _run_sweep(spec, grid, robot, task, executor, window, chunk_size, progress)


def _run_sweep(spec, grid, robot, task, executor, window, chunk_size, progress) -> SweepResult:
    """run_sweep with its arguments checked: in this process (``executor`` None) or on one."""
    reference = None if spec.reference is None else dict(spec.reference)
    table = sweep_postures(robot, grid, spec.postures, reference, map if executor is None else executor.map)
    if not np.any(table.reachable):
        raise UnreachableGridError(_unreachable_message(robot, grid, table))
    if isinstance(table, PostureTable):
        _check_postures(robot, grid, table)
    else:
        _check_ik_postures(robot, grid, table)
    n = grid.n_configurations
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    jobs = [_Job(spec, grid, _chunk_table(grid, table, s, e), s, e, chunk_size) for s, e in bounds]
    nv, ne, m = len(grid.wheel_velocity_scale), len(grid.wheel_effort_scale), task.dim
    merged = _empty_chunk(n, nv, ne, m, resolve_measures(spec.measures, sweep=True))

    from tqdm import tqdm

    bar = tqdm(total=n, unit="cfg", disable=not progress, desc=f"sweep {robot.name}", leave=False)

    def store(start: int, out: dict) -> None:
        stop = start + len(out["reachable"])
        for key, value in out.items():
            merged[key][start:stop] = value
        bar.update(stop - start)

    try:
        if executor is None:
            for job in jobs:
                store(*_run_job(job))
        else:
            _drain(executor, jobs, store, window=window)
    finally:
        bar.close()
    return _assemble(spec, grid, task, merged, table)


def _drain(executor: cf.Executor, jobs: list, store, window: int) -> None:
    """Submit jobs with at most ``window`` in flight (bounded memory), store results as they come."""
    pending = set()
    queue = iter(jobs)
    for job in queue:
        pending.add(executor.submit(_run_job, job))
        if len(pending) >= window:
            done, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for future in done:
                store(*future.result())
    for future in cf.as_completed(pending):
        store(*future.result())


def _check_direction(direction, m: int):
    if isinstance(direction, str):
        if direction not in ("radial", "tangential"):
            raise UsageError(f"direction must be 'radial', 'tangential' or {m} numbers, got {direction!r}")
        return direction
    try:
        values = tuple(float(v) for v in direction)
    except (TypeError, ValueError):
        raise UsageError(f"direction must be 'radial', 'tangential' or {m} numbers, got {direction!r}") from None
    if len(values) != m or not all(math.isfinite(v) for v in values) or not any(values):
        raise UsageError(f"direction must have {m} finite numbers, not all zero, got {list(values)}")
    return values


def _check_postures(robot: Robot, grid: SweepGrid, table: PostureTable) -> None:
    """Both end effectors at the object for one configuration per reachable distance (FK check)."""
    model, data = robot.model, robot.data
    for i in np.flatnonzero(table.reachable):
        flat = np.ravel_multi_index((0, i, 0), grid.shape[:3])
        q = sweep_configurations(robot, grid, table, np.array([flat]))[0][0]
        pin.framesForwardKinematics(model, data, q)
        heading = math.radians(grid.angle_deg[0] + grid.heading_deg[0])
        target = grid.distance[i] * np.array([math.cos(heading), math.sin(heading)])
        for arm in robot.arms:
            base = data.oMi[model.getJointId(arm.joint_names[0])].translation[:2]
            tip = data.oMf[arm.frame_id].translation[:2]
            if np.max(np.abs(tip - base - target)) > 1e-9 * max(1.0, grid.distance[i]):
                raise MobmanipError(
                    f"posture check failed: {arm.end_effector} misses the object at distance {grid.distance[i]:g} m"
                )


def _chunk_table(grid: SweepGrid, table, start: int, stop: int):
    """What a chunk of flat configuration indices [start, stop) needs of the posture table."""
    if isinstance(table, PostureTable):
        return table
    h = grid.shape[2]
    return _posture_rows(table, start // h, (stop - 1) // h + 1)


def _check_ik_postures(robot: Robot, grid: SweepGrid, table: IKPostureTable) -> None:
    """Every end effector at its target, at the first heading, for every reachable (angle, distance)."""
    model, data = robot.model, robot.data
    d, h = grid.shape[1:3]
    pairs = np.flatnonzero(table.reachable.reshape(-1))
    qs, _ = sweep_configurations(robot, grid, table, pairs * h)
    alpha = np.radians(grid.angle_deg[pairs // d])
    targets, _ = table.hold.targets(alpha, grid.distance[pairs % d], alpha)
    yaw = math.radians(grid.heading_deg[0])
    turn = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    for q, target in zip(qs, targets @ turn.T):
        pin.framesForwardKinematics(model, data, q)
        for arm, point in zip(robot.arms, target):
            miss = float(np.linalg.norm(data.oMf[arm.frame_id].translation - point))
            if miss > POSITION_TOLERANCE + 1e-12:
                raise MobmanipError(f"posture check failed: {arm.end_effector} misses its target by {miss:.3g} m")


def _span(values: np.ndarray, unit: str) -> str:
    values = np.unique(values)
    if len(values) <= 4:
        return ", ".join(f"{v:g}" for v in values) + f" {unit}"
    return f"{values[0]:g} .. {values[-1]:g} {unit} ({len(values)} values)"


def _unreachable_message(robot: Robot, grid: SweepGrid, table) -> str:
    if isinstance(table, PostureTable):
        reach = min(planar_arm(robot, i).max_reach for i in range(len(robot.arms)))
        return (
            f"{robot.name}: no grid distance is within the arms' reach: distance {_span(grid.distance, 'm')} "
            f"from their first joint, and they reach {reach:g} m at most"
        )
    hold = table.hold
    held = ""
    if len(robot.arms) > 1:
        width = float(np.max(np.linalg.norm(hold.offsets[:, None] - hold.offsets[None], axis=2)))
        held = f", hands {width:.3g} m apart"
    return (
        f"{robot.name}: the arms reach none of the grid's points: distance {_span(grid.distance, 'm')}, "
        f"angle {_span(grid.angle_deg, 'deg')}, from the reference point ({hold.origin[0]:.3g}, "
        f"{hold.origin[1]:.3g}) m, holding the object as the reference posture does (at height "
        f"{hold.height:.3g} m{held}); the inverse kinematics came within {np.min(table.position_error):.3g} m "
        "at best; try other distances or another reference posture"
    )


def _assemble(spec: SweepSpec, grid: SweepGrid, task, merged: dict, table: PostureTable) -> SweepResult:
    a, d, h, nv, ne = grid.shape
    indices = {}
    for measure in resolve_measures(spec.measures, sweep=True):
        velocity = measure.quantity.limits == "velocity"
        count = nv if velocity else ne
        keys = [f"{measure.name}_{name}" for name in SCALAR_INDICES]
        keys += [f"{measure.name}_{attribute}" for attribute, _ in measure.axis_indices]
        keys += [f"{measure.name}_{flag}" for flag in FLAGS]
        for key in keys:
            value = merged[key]
            tail = value.shape[2:]
            arr = value.reshape((a, d, h, count) + tail)
            if velocity:
                arr = np.broadcast_to(arr[:, :, :, :, None], (a, d, h, nv, ne) + tail)
            else:
                arr = np.broadcast_to(arr[:, :, :, None, :], (a, d, h, nv, ne) + tail)
            indices[key] = np.ascontiguousarray(arr)
    return SweepResult(
        spec=spec,
        grid=grid,
        task=task.name,
        task_axes=task.labels,
        reachable=merged["reachable"].reshape(a, d, h),
        indices=indices,
        postures=table,
    )


# ----------------------------------------------------------------------------------------------
# plot

_AXIS_LABELS = {
    "angle_deg": "object direction (deg)",
    "distance": "object distance (m)",
    "heading_deg": "platform heading (deg)",
    "wheel_velocity_scale": "wheel velocity scale",
    "wheel_effort_scale": "wheel effort scale",
}


def plot_sweep(result: SweepResult, index: str, path: str | Path, max_panels: int = 6) -> Path:
    """Plot one index over the sweep's varying grid axes and save it (PNG, matplotlib Agg).

    Two varying axes: a heat map, polar when they are angle and distance (0 deg up, 90 deg to
    the left, like the robot seen from above facing up). A third varying axis gives one panel per
    value (up to ``max_panels``, evenly picked); further axes are taken at their first value.
    One varying axis: a line plot.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    values = result.index(index)
    grid = result.grid
    varying = [i for i, n in enumerate(grid.shape) if n > 1]
    if 0 in varying and 1 in varying:
        pair = [0, 1]
    else:
        pair = varying[:2]
    rest = [i for i in varying if i not in pair]
    panel_axis = rest[0] if rest and len(pair) == 2 else None
    n_panel = 1 if panel_axis is None else grid.shape[panel_axis]
    picks = np.unique(np.linspace(0, n_panel - 1, min(n_panel, max_panels)).round().astype(int))
    polar = pair == [0, 1]
    cols = min(len(picks), 3)
    rows = math.ceil(len(picks) / cols)
    fig = Figure(figsize=(4.2 * cols + 0.8, 4.0 * rows), layout="constrained")
    FigureCanvasAgg(fig)
    finite = values[np.isfinite(values)]
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    mesh = None
    for p, pick in enumerate(picks):
        ax = fig.add_subplot(rows, cols, p + 1, projection="polar" if polar else None)
        index_tuple = [0] * 5
        if panel_axis is not None:
            index_tuple[panel_axis] = pick
        sl = tuple(slice(None) if i in pair else index_tuple[i] for i in range(5))
        data = values[sl]
        if len(pair) == 2:
            x = getattr(grid, AXES[pair[0]])
            y = getattr(grid, AXES[pair[1]])
            if polar:
                ax.set_theta_zero_location("N")
                mesh = ax.pcolormesh(np.radians(x), y, data.T, shading="nearest", vmin=vmin, vmax=vmax)
                ax.set_rlim(0.0, float(y.max()) * 1.05)
            else:
                mesh = ax.pcolormesh(x, y, data.T, shading="nearest", vmin=vmin, vmax=vmax)
                ax.set_xlabel(_AXIS_LABELS[AXES[pair[0]]])
                ax.set_ylabel(_AXIS_LABELS[AXES[pair[1]]])
        elif len(pair) == 1:
            x = getattr(grid, AXES[pair[0]])
            ax.plot(x, data, marker=".")
            ax.set_xlabel(_AXIS_LABELS[AXES[pair[0]]])
            ax.set_ylabel(index)
        else:
            ax.bar([index], [float(data)])
        if panel_axis is not None:
            ax.set_title(f"{_AXIS_LABELS[AXES[panel_axis]]} = {getattr(grid, AXES[panel_axis])[pick]:g}", fontsize=9)
    if mesh is not None:
        fig.colorbar(mesh, ax=fig.axes, label=index, shrink=0.8)
    fixed = [
        f"{_AXIS_LABELS[AXES[i]]} {getattr(grid, AXES[i])[0]:g}"
        for i in range(5)
        if i not in pair and i != panel_axis and grid.shape[i] > 1
    ]
    title = f"{result.spec.robot}: {index} ({result.task} task)"
    if polar:
        title += "\nradius: object distance (m), angle: object direction (deg)"
    if fixed:
        title += "\nat " + ", ".join(fixed)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path, dpi=110)
