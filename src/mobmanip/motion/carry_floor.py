"""The floor in ``carry``'s QP: rows that keep each step's zero-moment point inside the support
polygon with a margin, every support loaded and the driven wheels within friction.

At a step from reduced velocity x_prev to x over h seconds, xdot = (x - x_prev) / h and the
floor's resultant wrench (:func:`mobmanip.motion.ground.floor_wrench`, the velocity terms at
x_prev as the effort rows take them; the object's acceleration from the hands, as
:meth:`mobmanip.motion.MotionTerms.object_acceleration`) is affine in x: force F(x), moment
M(x) about the world origin. With the floor at height z_f, F_z times the zero-moment point is
N(x) = (z_f F_x - M_y, M_x + z_f F_y), also affine. So, exactly for that wrench:

- zero-moment point: for each edge of the support polygon (outward normal n_e through the
  vertex p_e), n_e . N(x) <= (n_e . p_e - margin) F_z(x): the point at least ``margin`` inside;
- no support unloads: the compliant normal forces (equally stiff contacts under a rigid platform,
  as the floor constraint's :func:`~mobmanip.terms.constraints.floor.compliant_sharing`) are a
  linear map of (F_z, N), each >= the reserve's share of the weight;
- traction: the casters are frictionless, so the driven wheels carry (F_x, F_y, M_z). Each
  wheel pushes along the floor where its mechanism lets it (:func:`traction_components`): a
  wheel with a motor both ways (along its rolling direction its torque's force, across it a
  constraint force), a mecanum wheel only across its rollers, a free-rolling wheel (a tricycle's
  rear wheels) only across its rolling direction. The wheels share the force as equally stiff
  tyres under a rigid platform do: the least-norm split t = P (F_x, F_y, M_z), P the
  pseudo-inverse (a differential drive's two wheels: half the lateral force each; the QP keeps a
  split variable s for the rows' shape, which nothing moves). A wheel pushing both ways keeps its
  force in the pyramid with ``faces`` faces inscribed in its cone, one pushing one way within
  its cone (a segment), each scaled by 1 - reserve;
- a skid-steer turns only by sliding its wheels sideways, so on the floor it keeps its heading
  (:data:`NO_TURN`: two rows hold its turn rate at zero).

On a ramp (``CarryFloor(slope=, uphill=)``) the world's axes are the ramp's, as for the floor at
rest (:class:`mobmanip.terms.constraints.floor.Floor`): the platform moves in the ramp's plane
(z = z_f), z is its normal and gravity leans downhill (:meth:`CarryFloor.gravity`). The rows
above then hold unchanged on the ramp: F_z is the normal load, N the moment about the ramp's
plane (the zero-moment point is the ramp's), the traction is (F_x, F_y, M_z) in its plane; the
weights' lean enters through the wrench (and the efforts), and the reserve is a share of the
weight's normal part, (m + m_o) g cos s.

Every platform that rolls on wheels is covered (differential drive, skid-steer, steered,
omnidirectional on ``[support] wheels``); a fixed base is refused.

The rows are over (x, s); :func:`floor_rows` gives them with a label per row naming what it
keeps (the zero-moment point, a support, a wheel's traction) for the diagnosis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, SpecError
from ..platforms import a_platform
from ..platforms.base import BASE_V
from ..robot.model import Robot
from ..robot.support import Support, check_faces, check_mu, deepest_margin, robot_support
from ..robot.tasks import TaskSpace
from ..terms.constraints.floor import check_ramp, compliant_sharing, pyramid_faces, ramp_gravity
from ..terms.grasp import object_mass_of
from .ground import floor_wrench

#: Default distance (m) the carry keeps its zero-moment point inside the support polygon.
DEFAULT_ZMP_MARGIN = 0.02


@dataclass(frozen=True)
class CarryFloor:
    """The floor a carry keeps (see the module's docstring).

    Attributes:
        mu: the driven wheels' friction coefficient; ``None``: no traction rows (tip-over only);
            ``"spec"``: the support's own.
        zmp_margin: how far (m) the zero-moment point stays inside the support polygon.
        reserve: a fraction in [0, 1): each support keeps this share of its equal part of the
            weight, each wheel uses at most 1 - reserve of its friction pyramid.
        faces: faces of the friction pyramid (default: the support's).
        support: the contacts (default: the robot's own).
        slope: the floor's inclination (deg, 0 to 30): a ramp, with the conventions and checks of
            :class:`mobmanip.terms.constraints.floor.Floor`'s. The platform's plane is the ramp's,
            so the world's x, y and z are the ramp's own axes (z its normal) and gravity leans
            (:meth:`gravity`): the zero-moment point is taken on the ramp's plane, the supports'
            loads along its normal, the wheels' traction in its plane, and the efforts hold the
            leaning weights.
        uphill: the direction (deg, in the floor's x, y) in which the ramp rises; 0: along +x.
    """

    mu: float | str | None = "spec"
    zmp_margin: float = DEFAULT_ZMP_MARGIN
    reserve: float = 0.0
    faces: int | None = None
    support: Support | None = None
    slope: float = 0.0
    uphill: float = 0.0

    def __post_init__(self):
        if self.mu != "spec":
            check_mu(self.mu, "the carry floor's mu")
        if self.faces is not None:
            check_faces(self.faces, "the carry floor's faces")
        margin = self.zmp_margin
        if (
            isinstance(margin, bool)
            or not isinstance(margin, (int, float))
            or not (math.isfinite(margin) and margin >= 0)
        ):
            raise ArgumentError(f"the zero-moment point's margin must be a finite distance >= 0 m, got {margin!r}")
        if not (isinstance(self.reserve, (int, float)) and 0.0 <= self.reserve < 1.0):
            raise ArgumentError(f"the floor's reserve must be a fraction in [0, 1), got {self.reserve!r}")
        check_ramp(self.slope, self.uphill, "the carry floor")

    def gravity(self) -> np.ndarray:
        """Gravity in the floor's axes (m/s^2), (3,): straight down on a level floor, leaning
        downhill on a ramp (:func:`mobmanip.terms.constraints.floor.ramp_gravity`)."""
        return ramp_gravity(self.slope, self.uphill)

    def resolve(self, robot: Robot) -> tuple[Support, float | None, int]:
        """The support, friction coefficient and faces for ``robot``."""
        if robot.wheel_platform is None:
            raise SpecError(
                f"the floor needs a platform that moves on wheels; {robot.name!r} has {a_platform(robot.platform.kind)}"
            )
        support = self.support if self.support is not None else robot_support(robot)
        deepest = deepest_margin(support.polygon((0.0, 0.0, 0.0)))
        if self.zmp_margin >= deepest:
            raise ArgumentError(
                f"the zero-moment point's margin {self.zmp_margin:g} m is more than {robot.name}'s support polygon "
                f"gives (no point of it is farther than {deepest:.4g} m from its edges; contacts "
                f"{', '.join(support.names)})"
            )
        mu = support.mu if self.mu == "spec" else self.mu
        faces = support.faces if self.faces is None else self.faces
        return support, (None if mu is None else float(mu)), int(faces)

    def describe(self) -> dict:
        out = {"mu": self.mu, "zmp_margin": self.zmp_margin, "reserve": self.reserve, "load": "compliant"}
        if self.slope:
            out |= {"slope": self.slope, "uphill": self.uphill, "gravity": self.gravity().tolist()}
        return out


def floor_rows(
    robot: Robot,
    q: np.ndarray,
    x_prev: np.ndarray,
    h: float,
    task: TaskSpace,
    object_mass: float | None,
    floor: CarryFloor,
    resolved: tuple[Support, float | None, int] | None = None,
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The step's floor rows G [x; s] <= g (see the module's docstring).

    Returns:
        (G (r, nx + 1), g (r,), one label per row).
    """
    from .in_motion import motion_terms

    resolved = floor.resolve(robot) if resolved is None else resolved
    mass_o = object_mass_of(robot, object_mass)
    terms = motion_terms(robot, q, x_prev, task, object_mass=mass_o)
    to_object = np.linalg.pinv(terms.W.T)  # a_o = (W^T)^+ (J_u xdot + drift - grasp drift)
    rows = list(task.rows)
    a0, a1 = np.zeros(6), np.zeros((6, robot.nx))
    a0[rows] = to_object @ (terms.drift - terms.grasp_drift)
    a1[rows] = to_object @ terms.J_u
    offset, linear = floor_wrench(robot, q, x_prev, mass_o, a0, a1, gravity=floor.gravity())
    # over x: wrench = w0 + w1 x (xdot = (x - x_prev) / h)
    w1 = linear / h
    w0 = offset - w1 @ x_prev
    R, r, labels, _ = wrench_rows(robot, q, mass_o, floor, resolved)
    # over (x, s): the lateral split s is the compliant floor's own, half per tyre; no row moves it
    G = np.hstack([R @ w1, np.zeros((len(R), 1))])
    g = r - R @ w0
    turn = turning_row(robot, q)
    if turn is not None:  # a skid-steer keeps its heading: both senses of the turn rate at zero
        G = np.vstack([G, np.r_[turn, 0.0], np.r_[-turn, 0.0]])
        g = np.r_[g, 0.0, 0.0]
        labels = [*labels, *[NO_TURN] * 2]
    return G, g, labels


@dataclass(frozen=True)
class FloorRows:
    """The floor's rows over its resultant wrench on the robot and its object, ``R @ wrench <= r``:
    the zero-moment point ``floor.zmp_margin`` inside the support polygon, every support loaded
    (its compliant share at least the reserve's part of the weight) and each driven wheel's
    traction within its friction pyramid scaled by 1 - reserve.

    Built once per robot and floor (:meth:`build`) in the platform's frame, where the contacts do
    not move; :meth:`at` turns them to the world at a configuration.

    Attributes:
        R: (r, 6) over the wrench in the platform's axes, its moment about the platform's origin.
        r: (r,).
        labels: what each row keeps, (r,).
        kinds: ``"tip-over"``, ``"contact"`` or ``"traction"`` per row, (r,).
    """

    R: np.ndarray
    r: np.ndarray
    labels: tuple[str, ...]
    kinds: tuple[str, ...]

    @classmethod
    def build(
        cls, robot: Robot, object_mass: float, floor: CarryFloor, resolved: tuple[Support, float | None, int]
    ) -> FloorRows:
        return cls(*_platform_rows(robot, object_mass, floor, resolved))

    def at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R, r) over the wrench as :func:`mobmanip.motion.ground.floor_wrench` gives it: force
        then moment about the world origin, world axes, for the platform at ``q``."""
        c, s = float(q[2]), float(q[3])
        norm = math.hypot(c, s)
        c, s = c / norm, s / norm
        x, y = float(q[0]), float(q[1])
        turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # world to platform axes
        origin = np.array([[0.0, 0.0, y], [0.0, 0.0, -x], [-y, x, 0.0]])  # M_p = M_O - p x F
        T = np.zeros((6, 6))
        T[:3, :3] = turn
        T[3:, 3:] = turn
        T[3:, :3] = -turn @ origin
        return self.R @ T, self.r


def wrench_rows(
    robot: Robot,
    q: np.ndarray,
    object_mass: float,
    floor: CarryFloor,
    resolved: tuple[Support, float | None, int],
) -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    """:class:`FloorRows` at ``q``: (R (r, 6), r (r,), labels, kinds) over the floor's wrench as
    :func:`mobmanip.motion.ground.floor_wrench` gives it (world axes, moment about the world origin)."""
    rows = FloorRows.build(robot, object_mass, floor, resolved)
    R, r = rows.at(q)
    return R, r, list(rows.labels), list(rows.kinds)


def _platform_rows(
    robot: Robot, object_mass: float, floor: CarryFloor, resolved: tuple[Support, float | None, int]
) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], tuple[str, ...]]:
    """:class:`FloorRows`' rows in the platform's frame (the platform at the world's origin)."""
    support, mu, faces = resolved
    z = support.floor_z
    # the moment about the floor point under the origin, times F_z: N = (z F_x - M_y, M_x + z F_y)
    N = np.zeros((2, 6))
    N[0, 0], N[0, 4] = z, -1.0
    N[1, 3], N[1, 1] = 1.0, z
    Fz = np.zeros(6)
    Fz[2] = 1.0

    pose = (0.0, 0.0, 0.0)
    points = support.world_points(pose)[:, :2]
    R_rows, r_rows, labels, kinds = [], [], [], []
    polygon = support.polygon(pose)
    edges = np.roll(polygon, -1, axis=0) - polygon
    normals = np.c_[edges[:, 1], -edges[:, 0]] / np.linalg.norm(edges, axis=1)[:, None]
    for n_e, p_e in zip(normals, polygon):
        # n_e . N <= (n_e . p_e - margin) F_z
        reach = float(n_e @ p_e) - floor.zmp_margin
        R_rows.append(n_e @ N - reach * Fz)
        r_rows.append(0.0)
        labels.append(f"the zero-moment point {floor.zmp_margin:g} m inside the support polygon")
        kinds.append("tip-over")

    # compliant normal forces: [balance; sharing] fn = [F_z, N_x, N_y, 0...]
    n = len(points)
    system = np.vstack([np.ones(n), points.T, compliant_sharing(points, support.stiffness)])
    fn = np.linalg.inv(system)[:, :3] @ np.vstack([Fz, N])  # fn = fn @ wrench
    # the weight's share along the floor's normal (on a ramp: m g cos s), as the floor at rest keeps it
    least = floor.reserve * (float(robot_mass(robot)) + object_mass) * float(-floor.gravity()[2]) / n
    for c, contact in enumerate(support.contacts):
        R_rows.append(-fn[c])
        r_rows.append(-least)
        labels.append(f"support {contact.name} loaded")
        kinds.append("contact")

    if mu is not None:
        components = traction_components(robot, support)
        B = np.zeros((3, len(components)))
        for k, (c, direction) in enumerate(components):
            x, y = points[c]
            B[:, k] = direction[0], direction[1], x * direction[1] - y * direction[0]
        if np.linalg.matrix_rank(B) < 3:
            raise SpecError(
                f"{robot.name}'s wheels cannot hold the floor's sideways force and turning moment together "
                f"(contacts {', '.join(support.contacts[c].name for c, _ in components)})"
            )
        H = np.zeros((3, 6))
        H[0, 0], H[1, 1], H[2, 5] = 1.0, 1.0, 1.0
        traction = np.linalg.pinv(B) @ H  # equally stiff tyres: the minimum-norm split
        for c in dict.fromkeys(c for c, _ in components):
            mine = [k for k, (owner, _) in enumerate(components) if owner == c]
            label = f"traction of {support.contacts[c].name} within friction (mu = {mu:g})"
            if len(mine) == 2:  # along the floor both ways: the pyramid inscribed in the cone
                tilt = mu * math.cos(math.pi / faces) * (1.0 - floor.reserve)
                rows = [u @ traction[mine] - tilt * fn[c] for u in pyramid_faces(faces, pose[2])]
            else:  # one way only (rollers, or a wheel rolling free): the cone is a segment
                reach = mu * (1.0 - floor.reserve)
                rows = [traction[mine[0]] - reach * fn[c], -traction[mine[0]] - reach * fn[c]]
            R_rows += rows
            r_rows += [0.0] * len(rows)
            labels += [label] * len(rows)
            kinds += ["traction"] * len(rows)
    return np.array(R_rows), np.array(r_rows, dtype=float), tuple(labels), tuple(kinds)


#: Why a base whose wheels scrub as it turns keeps its heading on the floor.
NO_TURN = "no turn: a skid-steer turns only by sliding its wheels sideways, and on the floor no wheel slides"


def turning_row(robot: Robot, q: np.ndarray) -> np.ndarray | None:
    """The base's turn rate as a row over the reduced velocities (rad/s per unit of x), (nx,),
    for a platform whose wheels scrub as it turns (a skid-steer's); ``None`` for the others, which
    turn on rolling wheels."""
    if not robot.platform.scrubs:
        return None
    return np.asarray(robot.null_space(q)[BASE_V[2]], dtype=float).copy()


def traction_components(robot: Robot, support: Support) -> list[tuple[int, np.ndarray]]:
    """The floor's tangential force components the contacts take, as (contact index, unit
    direction in the platform frame): both axes for a wheel the floor may push any way along the
    floor (a driven wheel's rolling force is its torque's, its sideways one a constraint force);
    only the direction across a free direction for a mecanum wheel's rollers (``[support]
    rollers``) or a wheel rolling free (:meth:`~mobmanip.platforms.base.Platform.free_rolling`,
    a steered base's rear wheels); none for a caster."""
    rolling = robot.platform.free_rolling()
    out = []
    for c, contact in enumerate(support.contacts):
        if not contact.driven:
            continue
        free = contact.free if contact.free is not None else rolling.get(contact.name)
        if free is None:
            out += [(c, np.array([1.0, 0.0])), (c, np.array([0.0, 1.0]))]
        else:
            out.append((c, np.array([-free[1], free[0]]) / math.hypot(free[0], free[1])))
    return out


def robot_mass(robot: Robot) -> float:
    import pinocchio as pin

    return float(pin.computeTotalMass(robot.model))


#: Bound on the lateral split variable s (N): far beyond any floor force the rows allow.
SPLIT_BOUND = 1e7
#: The QP's weight on s (it is otherwise free; the rows decide it).
SPLIT_WEIGHT = 1e-10


def solve_with_floor(solve, H, c, J_u, b, lo, hi, G, g, floor_G, floor_g) -> np.ndarray | None:
    """The step's QP over (x, s) with the floor's rows; x, or ``None`` when it has no solution.
    ``solve`` is the QP solver ``solve(H, c, A, b, lo, hi, G, g)``."""
    nx = len(c)
    H2 = np.zeros((nx + 1, nx + 1))
    H2[:nx, :nx] = H
    H2[nx, nx] = SPLIT_WEIGHT
    G2 = np.vstack([np.hstack([G, np.zeros((len(G), 1))]), floor_G]) if G is not None else floor_G
    g2 = np.concatenate([g, floor_g]) if g is not None else floor_g
    sol = solve(H2, np.r_[c, 0.0], np.hstack([J_u, np.zeros((len(J_u), 1))]), b, np.r_[lo, -SPLIT_BOUND],
                np.r_[hi, SPLIT_BOUND], G2, g2)  # fmt: skip
    return None if sol is None else sol[:nx]


def floor_binding(solve, H, c, J_u, b, lo, hi, G, g, floor_G, floor_g, labels) -> str | None:
    """Which of the floor's rows make the step infeasible: ``None`` when the step has no solution
    without them either (a joint limit binds); else the label of the first group of rows whose
    removal alone makes it feasible, or ``"the floor's rows together"``."""
    if solve(H, c, J_u, b, lo, hi, G, g) is None:
        return None
    labels = np.asarray(labels)
    for label in dict.fromkeys(labels.tolist()):
        keep = labels != label
        if solve_with_floor(solve, H, c, J_u, b, lo, hi, G, g, floor_G[keep], floor_g[keep]) is not None:
            return str(label)
    return "the floor's rows together"
