"""The paper's arm postures for planar dual-arm robots: the globally most manipulable one (the
case study's) and the closed form at a given reach (sweeps).

Both are for robots with two 3-joint planar arms with vertical axes (like ``planar_dual_arm``).

The case study's posture (:func:`optimal_posture`): each arm's (q2, q3) maximise its own
kinematic manipulability sqrt(det(J J^T)) of its 2 x 3 horizontal translational Jacobian, found
numerically on the model's own Jacobian; the arms mirror each other about the line from P_o to
the object, and q1 of each arm points its end effector at the object
(:func:`configuration_at`; :func:`optimal_configuration` with the object straight ahead is
``mobmanip carry``'s start for such a robot without a hold posture).

The closed form at a reach (the arms' first joints sharing their position; the reference point
is that joint, P_o): at a given reach, each arm's posture family is one-dimensional (q3 free, q2
from the reach, two elbow branches); the posture taken maximises the arm's own manipulability
along that family (dense sampling of q3 with zooming refinement, see
:func:`postures_at_reaches`). At the reach of the globally optimal posture this is the paper's
posture (:func:`optimal_posture`). Arm 1 (right) bends to the right and arm 2 takes the mirror
image about the line from the base to the object; q1 of each arm points its end effector at the
object. :mod:`mobmanip.sweep` uses these as its ``planar`` postures.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import SpecError
from ..robot.model import Arm, Robot


@dataclass(frozen=True)
class ArmPosture:
    """The globally optimal posture of one arm.

    Attributes:
        q: joint angles (q1 = 0, q2, q3) (rad).
        manipulability: sqrt(det(J J^T)) of the arm's horizontal translational Jacobian (m^2).
        reach: horizontal distance from the arm's first joint to its end effector (m).
        bearing: direction of the end effector seen from the first joint at q1 = 0 (rad).
    """

    q: tuple[float, ...]
    manipulability: float
    reach: float
    bearing: float


def _check_two_arms(robot: Robot, axes: bool = False) -> None:
    """The posture is the arms' own: any platform carries it (the paper's differential drive, the
    omnidirectional base it is compared with, a locked one). ``axes``: also that their joints
    turn about vertical axes (it runs the model's kinematics, on ``robot.data``)."""
    joints = [len(arm.joint_names) for arm in robot.arms]
    if joints != [3, 3]:
        shape = " and ".join(str(n) for n in joints) or "no"
        raise SpecError(f"the case study's posture needs two 3-joint arms; {robot.name!r} has arms of {shape} joints")
    for arm in robot.arms if axes else ():
        for name, axis in _joint_axes(robot, arm):
            if abs(axis[2]) < math.cos(POSTURE_AXIS_TILT):
                raise SpecError(
                    f"the case study's posture needs vertical arm joints; {name!r} turns about "
                    f"{np.round(axis, 3).tolist()}"
                )


#: How far an arm joint's axis may lean from the vertical for the case study's posture (rad). The
#: posture is searched on the model's own Jacobian, so a file that writes pi/2 as 1.57 (a lean of
#: 8e-4) still gives its robot the posture; the sweeps' closed form (:func:`planar_arm`) asks for
#: vertical axes to 1e-9.
POSTURE_AXIS_TILT = 0.01


def _joint_axes(robot: Robot, arm: Arm) -> list[tuple[str, np.ndarray]]:
    """Each joint of ``arm`` and its axis in the world at the home configuration (on ``robot.data``)."""
    model, data = robot.model, robot.data
    pin.computeJointJacobians(model, data, robot.configuration(joints=dict.fromkeys(arm.joint_names, 0.0)))
    pin.updateFramePlacements(model, data)
    out = []
    for name in arm.joint_names:
        jid = model.getJointId(name)
        out.append((name, pin.getJointJacobian(model, data, jid, pin.WORLD)[3:, model.joints[jid].idx_v].copy()))
    return out


def arm_measure(robot: Robot, arm: Arm, q2: float, q3: float) -> tuple[float, np.ndarray, np.ndarray]:
    """An arm's own manipulability sqrt(det(J J^T)) of its planar 2 x 3 translational Jacobian,
    its end-effector position and its first joint's position (m), at joints (0, q2, q3) (rad)."""
    model, data = robot.model, robot.data
    q = robot.configuration(joints=dict(zip(arm.joint_names, (0.0, q2, q3))))
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[:2, list(arm.v_indices)]
    w = math.sqrt(max(np.linalg.det(J @ J.T), 0.0))
    base = data.oMi[model.getJointId(arm.joint_names[0])].translation
    return w, data.oMf[arm.frame_id].translation.copy(), base.copy()


def optimal_posture(robot: Robot, arm_index: int = 0, grid: int = 73, refinements: int = 6) -> ArmPosture:
    """Maximise an arm's own manipulability over (q2, q3) by grid search with zooming.

    The search starts on a ``grid`` x ``grid`` lattice over [-pi, pi]^2 and zooms in around the
    best point ``refinements`` times (each time to a cell of the previous lattice); the result is
    accurate to about 2 pi / grid / (grid / 4)^refinements rad. Among the two mirror-image optima
    (q2, q3) and (-q2, -q3), the one that bends to the right (positive bearing) is returned.

    Raises:
        SpecError: not two 3-joint arms with vertical axes (as the paper's robot has).
    """
    _check_two_arms(robot, axes=True)
    arm = robot.arms[arm_index]
    center, half = np.zeros(2), math.pi
    best = (-1.0, 0.0, 0.0)
    for _ in range(refinements + 1):
        values = np.linspace(-half, half, grid)
        for dq2 in values:
            for dq3 in values:
                q2, q3 = center[0] + dq2, center[1] + dq3
                w = arm_measure(robot, arm, q2, q3)[0]
                if w > best[0]:
                    best = (w, q2, q3)
        center = np.array(best[1:])
        half = 2.0 * half / (grid - 1)
    w, q2, q3 = best
    _, tip, base = arm_measure(robot, arm, q2, q3)
    bearing = math.atan2(tip[1] - base[1], tip[0] - base[0])
    if bearing < 0:  # take the mirror image so that the arm's elbow is on its right
        q2, q3 = -q2, -q3
        _, tip, base = arm_measure(robot, arm, q2, q3)
        bearing = math.atan2(tip[1] - base[1], tip[0] - base[0])
    reach = float(np.hypot(*(tip - base)[:2]))
    return ArmPosture((0.0, float(q2), float(q3)), float(w), reach, float(bearing))


def configuration_at(robot: Robot, posture: ArmPosture, angle_deg: float, heading: float = 0.0) -> np.ndarray:
    """q with both arms in the mirrored optimal posture pointing at an object at ``angle_deg``.

    Arm 1 (right) takes (q2, q3) and arm 2 (left) the mirror image (-q2, -q3); each q1 turns its
    end effector onto the direction alpha from the platform heading. ``heading`` rotates the
    whole robot (rad).

    Raises:
        SpecError: not two 3-joint arms with vertical axes (as the paper's robot has).
    """
    _check_two_arms(robot)
    alpha = math.radians(angle_deg)
    _, q2, q3 = posture.q
    right, left = robot.arms
    joints = dict(zip(right.joint_names, (alpha - posture.bearing, q2, q3)))
    joints.update(zip(left.joint_names, (alpha + posture.bearing, -q2, -q3)))
    return robot.configuration((0.0, 0.0, heading), joints)


def optimal_configuration(robot: Robot, angle_deg: float = 0.0, heading: float = 0.0) -> np.ndarray:
    """The paper's posture as a configuration: both arms at their own optimum
    (:func:`optimal_posture`), mirrored, pointed at an object at ``angle_deg`` from the platform
    heading (default straight ahead); ``heading`` rotates the whole robot (rad).

    Raises:
        SpecError: not two 3-joint arms with vertical axes (as the paper's robot has).
    """
    return configuration_at(robot, optimal_posture(robot), angle_deg, heading)


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
        raise SpecError(f"the paper's postures need 3-joint planar arms; arm {arm.name!r} has {len(arm.joint_names)}")
    model, data = robot.model, robot.data
    points, signs = [], []
    for name, axis in _joint_axes(robot, arm):  # the placements below are the home configuration's
        jid = model.getJointId(name)
        if abs(abs(axis[2]) - 1.0) > 1e-9:
            raise SpecError(
                f"the paper's postures need vertical arm joints; {name!r} turns about {np.round(axis, 3).tolist()}"
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
            effector, as :func:`optimal_posture`), -1 for its mirror image
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


def posture_at_reach(arm: PlanarArm, reach: float, bend: int = 1, **search: int) -> ReachPosture | None:
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


def posture_table(
    robot: Robot, distances: Sequence[float] | np.ndarray, map_fn: Callable[..., Iterable[np.ndarray]] = map
) -> PostureTable:
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
