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

The rows over the wrench are built once, for every motion, by
:class:`mobmanip.terms.constraints.floor_wrench.FloorRows` (:meth:`CarryFloor.rows`); here they
are written over the step's (x, s): :func:`floor_rows` gives them with a label per row naming what
it keeps (the zero-moment point, a support, a wheel's traction) for the diagnosis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, SpecError
from ..platforms import a_platform
from ..robot.model import Robot
from ..robot.support import Support, check_faces, check_mu, check_reserve, deepest_margin, robot_support
from ..robot.tasks import TaskSpace
from ..terms.constraints.floor import check_ramp, friction_of, ramp_gravity
from ..terms.constraints.floor_wrench import NO_TURN, FloorRows, traction_components, turning_row
from ..terms.grasp import object_mass_of
from .ground import floor_wrench

__all__ = [
    "DEFAULT_ZMP_MARGIN",
    "NO_TURN",
    "CarryFloor",
    "FloorRows",
    "floor_binding",
    "floor_rows",
    "solve_with_floor",
    "traction_components",
    "turning_row",
    "wrench_rows",
]

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
        check_reserve(self.reserve)
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
        return (support, *friction_of(support, self.mu, self.faces))

    def rows(
        self, robot: Robot, object_mass: float, resolved: tuple[Support, float | None, int] | None = None
    ) -> FloorRows:
        """This floor's rows for ``robot`` holding ``object_mass`` kg
        (:class:`mobmanip.terms.constraints.floor_wrench.FloorRows`): the reserve is a share of
        the weight's normal part, robot and object."""
        support, mu, faces = self.resolve(robot) if resolved is None else resolved
        weight = (robot_mass(robot) + float(object_mass)) * float(-self.gravity()[2])
        return FloorRows.build(
            robot, support, mu, faces, zmp_margin=self.zmp_margin, reserve=self.reserve, weight=weight
        )

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


def wrench_rows(
    robot: Robot,
    q: np.ndarray,
    object_mass: float,
    floor: CarryFloor,
    resolved: tuple[Support, float | None, int],
) -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    """The floor's rows at ``q``: (R (r, 6), r (r,), labels, kinds) over the floor's wrench as
    :func:`mobmanip.motion.ground.floor_wrench` gives it (world axes, moment about the world origin)."""
    rows = floor.rows(robot, object_mass, resolved)
    R, r = rows.at(q)
    return R, r, list(rows.labels), list(rows.kinds)


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
