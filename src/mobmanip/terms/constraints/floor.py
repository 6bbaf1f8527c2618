"""The floor: the robot stands on its wheels and casters, must not tip over, and its driven wheels
must not slip.

At rest, the whole robot with a floating base restricted to the platform's S (no vertical, roll
or pitch motion) obeys the paper's reduced dynamics (the rows along S, where the contact forces
do no work: the wheels roll, the casters do not sink) and, across S, the Newton-Euler equations
of the whole robot, about its centre of mass c::

    A_G S xdot = m g + sum_c [lambda_c; (p_c - c) x lambda_c] - sum_i [f_i; (p_i - c) x f_i + n_i]

A_G is the centroidal momentum matrix (Pinocchio's ``computeCentroidalMap``; at rest the rate of
the momentum is A_G qdd), lambda_c the floor's force at contact c, (f_i, n_i) the wrench hand i
applies to the object. For a differential drive (one reduced velocity per wheel and joint) these
six rows and the reduced ones together are the whole floating-base dynamics. The unknowns the
floor adds: each wheel's contact force (world x, y, z) and each passive support's normal force.

Every platform kind that moves on the floor (:data:`FLOOR_KINDS`) stands on it; what each kind's
wheels add (:func:`_wheel_equations`):

- differential drive: nothing more; a wheel's force along its rolling direction is its torque
  over its radius less its spin, its sideways force a constraint force within friction;
- skid-steer: each side's wheels turn at one rate and share its torque equally; the second wheel
  of a side keeps its own row of the dynamics (its force along the floor is what its share
  leaves). It turns only by sliding its wheels sideways, and on the floor no wheel slides: at
  rest its base does not start a turn, and the sideways forces that hold it are constraint
  forces within friction (a difference of the sides' torques pushes against them). With every
  contact free to pull (``lift``: the ideal set) the turn is the kinematic model's, whose
  sideways forces do no net work along it;
- steered (tricycle): the drive wheel as a differential drive's, the free rear wheels' rows of
  the dynamics with no effort (they push along the floor only what their spin asks);
- omnidirectional (a planar joint driven by wheels the file does not model, ``[support] wheels``):
  the base's efforts are the floor's traction, ``S^T sum_c J_c^T lambda_c = tau_base``, each
  wheel's within friction, none along its rollers' free direction (``[support] rollers``).

The task is the user's. On the floor the hands apply exactly the wrench components of the task
analysed without the floor: a translational task's hands apply forces and no moments, a planar
task's object is moved in the plane and its weight is not the hands' (as in the ideal set, where
g_o has no vertical row). Holding the object level is a requirement the user names
(``Floor(level=True)``, ``--level``): the hands then also apply the wrench components the task
leaves out among the object's vertical force and its roll and pitch moments (:data:`LEVEL_ROWS`),
which balance its weight and tipping moments (the robot feels their reaction), and the hands'
accelerations on those rows stay within :data:`LEVEL_TOLERANCE` of zero. Two hands share that load
without squeezing the object on those rows (the minimum-norm share): a squeeze would pass to the
joints only through the tilt of their axes, so a file's 1e-6 rad of rounding would let an
unbounded squeeze lend them unbounded torque (reaches four times the true ones). A band, not an equation:
a robot file that rounds pi/2 to 1.5708 tilts a wrist axis by 4e-6 rad, and an equation would
freeze that joint outright where the band lets it move as far as its tilt stays inside (a result
that moves by the tilt's own order, not by half of a reach).

Inequalities: every normal force >= 0 (no contact pulls: the robot does not tip over); with a
friction coefficient mu, each driven wheel's tangential force lies in the pyramid with
``faces`` faces inscribed in its cone ``|f_t| <= mu f_n`` (conservative by 1 - cos(pi / faces)).
Passive supports are frictionless. With every contact force free, the set is the ideal one.

How the weight is shared (``load``). A robot on more than three contacts is statically
indeterminate: the six rows above fix the total normal force and its moments, not how the
contacts share them. The sharing does not matter for tip-over (every sharing with normals >= 0
puts the zero-moment point in the support polygon, and every such point has one), but it decides
how hard each wheel may push. ``"compliant"`` shares it as the floor and the tyres do: the
platform is rigid and every contact a spring (equally stiff unless the spec's
``[support.stiffness]`` says otherwise, e.g. for sprung casters), so each contact's deflection is
an affine function of its position on the floor and its normal force that deflection times its
stiffness, f_n,c = k_c (a + b x_c + c y_c) (n - 3 equations over the normals, none with three
contacts). With the normals >= 0 every support stays loaded: the
zero-moment point stays in the support's *core*, which is smaller than its polygon (for four
corners, the diamond through the edges' midpoints), so the no-tip-over limit is conservative;
and each wheel's traction is limited by the load the springs give it, not by the most
favourable load. ``"any"`` admits every sharing that balances the robot: the tip-over limit is
exact (the zero-moment point anywhere in the polygon) but the traction limit is optimistic
(it assumes the wheels carry as much as the balance allows; measured in MuJoCo, whose
contacts share by compliance, the wheels of TIAGo++ and the paper robot then slip on some axes).
The driven wheels' sideways forces are not shared by compliance: two wheels on one axle are
held sideways together (the axle is rigid), so while one of them holds, neither slides; a wheel
at its friction limit passes the rest to the other, and any split within the two pyramids is what
the floor can do (in MuJoCo, at the ideal +y maximum of TIAGo++, one wheel sits at its limit, the
other holds, and nothing slides). Only the normal forces have no such mechanism.
``"auto"`` (the default) is ``"compliant"`` with a traction limit and ``"any"`` without one.
Where the robot cannot even stand still with every support loaded (its centre of mass outside
the core, e.g. arms stretched far out), the compliant set is empty; the exact compliant model,
where lightly loaded supports may lift, is a union of such sets (one per set of lifted supports)
and is not built.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

from ...errors import ArgumentError, SpecError
from ...platforms import a_platform
from ...robot.model import platform_pose
from ...robot.support import Support, check_faces, check_mu, check_reserve, polygon_margin, robot_support
from ...robot.tasks import get_task
from ..grasp import GRAVITY, HeldObject, skew, wrench_shift

if TYPE_CHECKING:
    from ...robot.model import Robot
from .base import Constraint, ConstraintRows, Terms

_G = float(-GRAVITY[2])  # m/s^2, the magnitude of gravity (along world -z)
#: The steepest floor modelled (deg): a ramp, not a wall (wheelchair ramps are under 5 deg).
MAX_SLOPE = 30.0

#: Rows of a 6-D wrench (force, then moment; world axes) the object is balanced in, when it is held
#: level (``Floor(level=True)``), even where the task leaves them out: its vertical force and its
#: roll and pitch moments.
LEVEL_ROWS = (2, 3, 4)
#: How far from zero the hands' accelerations on the level rows a task leaves out may be when the
#: object is held level (m/s^2 vertically, rad/s^2 in roll and pitch): a tray tilting at this
#: rate turns by 0.3 deg in a quarter of a second from rest.
LEVEL_TOLERANCE = 0.01
#: How the contacts may share the weight (see the module's docstring).
LOADS = ("auto", "compliant", "any")
#: The platform kinds the floor covers (each with its contacts; see the module's docstring).
FLOOR_KINDS = ("differential_drive", "skid_steer", "steered", "omnidirectional")
#: The name of the contact force variable (world x, y, z per driven wheel; z per passive support).
CONTACT_FORCES = "contact_forces"
#: The name of the hands' wrench components on the level rows a task leaves out.
LEVEL_WRENCHES = "level_wrenches"


#: One group of equality rows: blocks by variable name, each (p, size of the variable), and the
#: right-hand side (p,).
_Equations = tuple[dict[str, np.ndarray], np.ndarray]


def check_ramp(slope, uphill, who: str) -> None:
    """Refuse a ramp the floor does not model: ``slope`` (deg) a finite angle from 0 to
    :data:`MAX_SLOPE`, ``uphill`` (deg) a finite angle; ``who`` names the floor in the message
    (``"the floor"``: "the floor's slope must be ...").

    Raises:
        ArgumentError: either angle not a finite number, or the slope out of range.
    """
    for value, what in ((slope, "slope"), (uphill, "uphill direction")):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ArgumentError(f"{who}'s {what} must be a finite angle in degrees, got {value!r}")
    if not 0.0 <= slope <= MAX_SLOPE:
        raise ArgumentError(f"{who}'s slope must be from 0 to {MAX_SLOPE:g} deg, got {slope!r}")


def ramp_gravity(slope: float, uphill: float) -> np.ndarray:
    """Gravity in a ramp's axes (m/s^2), (3,): the platform's plane is the ramp's (z its normal),
    the ramp rises ``slope`` deg towards ``uphill`` deg from its +x, so gravity leans downhill:
    g (-sin s cos u, -sin s sin u, -cos s); straight down on a level floor (slope 0). The one home
    of the lean for the floor at rest (:meth:`Floor.gravity`) and in motion
    (:meth:`mobmanip.motion.carry_floor.CarryFloor.gravity`)."""
    if slope == 0.0:
        return np.array([0.0, 0.0, -_G])
    s, u = math.radians(slope), math.radians(uphill)
    return _G * np.array([-math.sin(s) * math.cos(u), -math.sin(s) * math.sin(u), -math.cos(s)])


def weight_lean(robot: Robot, q: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """What a leaning ``gravity`` (the floor's axes, (3,) m/s^2; :func:`ramp_gravity`) adds to the
    robot's generalized gravity forces g(q) (Pinocchio's, gravity straight down), (nv,):
    g(q) = -m J_c^T g, so the lean adds -m J_c^T (gravity - g_level). Zeros on a level floor.
    Updates ``robot.data``'s centre of mass."""
    lean = np.asarray(gravity, dtype=float) - np.array([0.0, 0.0, -_G])
    if not lean.any():
        return np.zeros(robot.model.nv)
    J_c = pin.jacobianCenterOfMass(robot.model, robot.data, q)
    return -float(pin.computeTotalMass(robot.model)) * (J_c.T @ lean)


@dataclass(frozen=True)
class Floor(Constraint):
    """The robot on the floor (see the module's docstring).

    Args:
        mu: friction coefficient of the driven wheels; ``None``: no traction limit (only no
            tip-over); ``"spec"``: the support's own (the spec's ``[support] mu``, default 0.5).
        faces: faces of the inscribed friction pyramid (default: the support's).
        support: the contacts; default: :func:`mobmanip.robot.support.robot_support`.
        lift: allow contacts to pull (normal forces of any sign): the ideal set, with the floor's
            forces reported (where its zero-moment point would be). Off by default.
        load: how the contacts share the weight: ``"compliant"`` (contacts as springs of their
            stiffness, equal by default, under a rigid platform; every support stays loaded),
            ``"any"`` (every sharing that balances the robot) or ``"auto"``: compliant with a
            traction limit, any without one; see the module's docstring.
        reserve: a safety reserve, a fraction r in [0, 1): every support keeps at least r times
            its equal share of the weight (robot and object), and every driven wheel uses at most
            1 - r of its friction pyramid. 0 (the default): the exact limits. A replay from rest
            drifts from the instantaneous solution as the robot moves (in MuJoCo, within 20 ms at
            97 % of a maximum, a nearly unloaded caster lifts and the load leaves the wheels);
            a reserve keeps the maxima clear of that; :func:`mobmanip.motion.hold.held_reach`
            finds the reach that holds for a given time.
        slope: the floor's inclination (deg, 0 to :data:`MAX_SLOPE`): a ramp. The platform's
            plane is the floor's, so the world's x, y and z are the ramp's own axes (z its
            normal) and gravity leans: g (-sin s cos u, -sin s sin u, -cos s). The robot's and
            the object's weights change with it (in the reduced dynamics, the whole robot's
            rows, the object's equation and its level rows); the wheels' traction must hold the
            weight's share along the ramp.
        uphill: the direction (deg, in the floor's x, y) in which the ramp rises; 0: along +x.
        level: hold the object level (see the module's docstring): the hands also carry the
            object's weight and its roll and pitch moments where the task leaves those rows out,
            and keep their accelerations there within ``level_tolerance`` of zero. Off by default:
            the task is the one analysed without the floor.
        level_tolerance: the band of the level requirement (m/s^2 and rad/s^2, > 0).
    """

    mu: float | str | None = "spec"
    faces: int | None = None
    support: Support | None = None
    lift: bool = False
    load: str = "auto"
    reserve: float = 0.0
    slope: float = 0.0
    uphill: float = 0.0
    level: bool = False
    level_tolerance: float = LEVEL_TOLERANCE
    name: str = "floor"
    problem: str = "acceleration"

    def __post_init__(self):
        if self.mu != "spec":
            check_mu(self.mu, "the floor's mu")
        if self.faces is not None:
            check_faces(self.faces, "the floor's faces")
        check_reserve(self.reserve)
        if self.load not in LOADS:
            raise ArgumentError(f"the floor's load must be one of {', '.join(LOADS)}, got {self.load!r}")
        check_ramp(self.slope, self.uphill, "the floor")
        if not isinstance(self.level, bool):
            raise ArgumentError(f"the floor's level must be True or False, got {self.level!r}")
        tol = self.level_tolerance
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not (math.isfinite(tol) and tol > 0.0):
            raise ArgumentError(f"the floor's level tolerance must be a positive number (m/s^2, rad/s^2), got {tol!r}")

    def gravity(self) -> np.ndarray:
        """Gravity in the floor's axes (m/s^2), (3,): straight down on a level floor."""
        return ramp_gravity(self.slope, self.uphill)

    def resolve(self, robot: Robot) -> tuple[Support, float | None, int]:
        """The support, friction coefficient and faces this floor uses for ``robot``."""
        support = self.support if self.support is not None else _robot_support(robot)
        return (support, *friction_of(support, self.mu, self.faces))

    def sharing(self, mu: float | None) -> str | None:
        """The load sharing used with friction coefficient ``mu`` (``None``: no traction limit):
        ``"compliant"`` or ``"any"``; ``None`` when contacts may pull (``lift``)."""
        if self.lift:
            return None
        if self.load == "auto":
            return "any" if mu is None else "compliant"
        return self.load

    def describe(self) -> dict:
        out: dict = {"name": self.name, "model": "whole robot on the floor, at rest"}
        out["mu"] = self.mu
        out["tip_over"] = "allowed (contacts may pull)" if self.lift else "not allowed"
        if not self.lift:
            out["load"] = self.load if self.load != "auto" else "compliant with a traction limit, else any"
        if self.faces is not None:
            out["faces"] = self.faces
        if self.reserve:
            out["reserve"] = self.reserve
        if self.slope:
            out["slope"], out["uphill"] = self.slope, self.uphill
        if self.level:
            out["level"] = f"object held level (within {self.level_tolerance:g} m/s^2, rad/s^2)"
        return out

    def rows(self, terms: Terms) -> ConstraintRows:
        robot, q, held = _standing_robot(terms)
        support, mu, faces = self.resolve(robot)
        model, data = robot.model, robot.data
        S = robot.null_space(q)
        c = pin.centerOfMass(model, data, q).copy()
        mass = float(pin.computeTotalMass(model))
        A_G = pin.computeCentroidalMap(model, data, q).copy()  # momentum about c, world axes
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        pose = platform_pose(q)
        points = support.world_points(pose)
        columns = _contact_columns(support, points, c)
        n_forces, nx = columns.size, S.shape[1]
        rows = list(get_task(terms.task).rows)
        level = [r for r in LEVEL_ROWS if r not in rows] if self.level else []
        hands = _hand_rows(robot, S, c, np.asarray(held.center, dtype=float), rows, level)
        k, nl = len(robot.arms), len(level)
        gravity = self.gravity()

        # the whole robot's Newton-Euler rows (6)
        whole = {"xdot": A_G @ S, CONTACT_FORCES: -columns.wrench, "h": np.hstack(hands.task)}
        equations = [(whole, _weight(mass, gravity))]
        variables = {CONTACT_FORCES: (n_forces, -np.inf, np.inf)}
        couplings: dict[str, dict[str, np.ndarray]] = {}
        object_E: dict[str, np.ndarray] = {}
        object_e = np.zeros(0)
        if nl:
            variables[LEVEL_WRENCHES] = (k * nl, -np.inf, np.inf)
            whole[LEVEL_WRENCHES] = np.hstack(hands.level)
            object_E, object_e, couplings["dynamics"], squeeze = _level_hold(hands, level, held.mass, gravity)
            equations += squeeze
        wheels, turning = _wheel_equations(
            robot, q, S, support, points, columns.slices, n_forces, gravity, mass, rows, self.lift
        )
        equations += wheels
        if turning is not None:  # the sideways forces that hold a skid-steer from turning do work along S
            couplings.setdefault("dynamics", {})[CONTACT_FORCES] = turning
        equations += self._sharing_equations(robot, support, points, columns, mu, pose[2])
        sizes = {"xdot": nx, "tau": nx, CONTACT_FORCES: n_forces, "h": terms.W.shape[1], LEVEL_WRENCHES: k * nl}
        E, e = _stack(equations, sizes)
        shifts = self._slope_shifts(robot, q, S, mass, held.mass, gravity, rows)

        G, h, labels, kinds, scales = self._contact_inequalities(
            support, columns, mu, faces, mass + held.mass, gravity, pose[2]
        )
        if nl:  # the hands keep the object level: their accelerations on the level rows in the band
            G, h, labels = self._level_band(G, h, labels, hands.kinematics, robot.arms, level, pose[2], nx)
            added = len(h) - len(kinds)
            kinds, scales = kinds + ["level"] * added, scales + [self.level_tolerance] * added
        info = self._report(support, mu, faces, pose, points, columns.slices, gravity)
        return ConstraintRows(
            self.name, self.problem, variables=variables, G=G, h=h, E=E, e=e, couplings=couplings,
            object_E=object_E, object_e=object_e, shifts=shifts,
            labels=tuple(labels), info=info, kinds=tuple(kinds), scales=tuple(scales),
        )  # fmt: skip

    def _sharing_equations(
        self,
        robot: Robot,
        support: Support,
        points: np.ndarray,
        columns: _ContactColumns,
        mu: float | None,
        heading: float,
    ) -> list[_Equations]:
        """How the contacts share their forces, as equations over the contact forces: the normal
        forces as springs under a rigid platform (compliant sharing), then the sideways forces of
        wheels rolling along the platform's x as tyres share them.

        Args:
            robot: the robot on the floor.
            support: its contacts; ``points`` their world points, (n, 3) m.
            columns: where each contact's force is in the contact forces.
            mu: the friction coefficient in use (``None``: no traction limit).
            heading: the platform's heading (rad).

        Returns:
            ``(blocks, right-hand side)`` per group of rows, none when nothing is shared.
        """
        sharing_model, n_forces = self.sharing(mu), columns.size
        equations = []
        if sharing_model == "compliant":
            sharing = compliant_sharing(points, support.stiffness)
            if len(sharing):
                block = np.zeros((len(sharing), n_forces))
                block[:, columns.normals] = sharing
                equations.append(({CONTACT_FORCES: block}, np.zeros(len(sharing))))
        # the sideways forces as tyres share them: under the compliant sharing, and wherever
        # friction does not bound them (an axle's squeeze would be unbounded, and a file's 1e-8
        # tilt of a wheel axis would turn it into torque: reaches 3 % apart)
        if robot.platform.kind in PARALLEL_WHEELS and (sharing_model == "compliant" or (mu is None and not self.lift)):
            wheels = [i for i, ct in enumerate(support.contacts) if ct.driven and ct.source == "wheel"]
            sideways = lateral_sharing(support.root_points()[wheels, 0], support.stiffness[wheels])
            if len(sideways):
                lateral = (-math.sin(heading), math.cos(heading))
                block = np.zeros((len(sideways), n_forces))
                for column, i in enumerate(wheels):
                    a = columns.slices[i][0]
                    block[:, a : a + 2] = np.outer(sideways[:, column], lateral)
                equations.append(({CONTACT_FORCES: block}, np.zeros(len(sideways))))
        return equations

    def _slope_shifts(
        self, robot: Robot, q: np.ndarray, S: np.ndarray, mass: float, object_mass: float, gravity: np.ndarray, rows
    ) -> dict[str, np.ndarray]:
        """On a ramp, what the leaning weights change in the problem's own equations: the robot's
        in the reduced dynamics (``"dynamics"``, (nx,)) and the object's in its own balance
        (``"object"``, on the task's ``rows``); empty on a level floor.

        Args:
            robot, q: the robot and its configuration; S its null space at q, (nv, nx).
            mass, object_mass: the robot's and the object's masses (kg).
            gravity: gravity in the floor's axes (:meth:`gravity`), (3,).
            rows: the task's rows of a 6-D wrench.
        """
        shifts = {}
        if self.slope:  # the weights lean with the ramp: the reduced dynamics' and the object's own
            lean = gravity - np.array([0.0, 0.0, -_G])
            shifts["dynamics"] = -S.T @ weight_lean(robot, q, gravity)  # xi = -S^T g(q)
            shifts["object"] = np.r_[-object_mass * lean, np.zeros(3)][rows]  # g_o = -m_o g
        return shifts

    def _contact_inequalities(
        self,
        support: Support,
        columns: _ContactColumns,
        mu: float | None,
        faces: int,
        carried: float,
        gravity: np.ndarray,
        heading: float,
    ) -> tuple[dict[str, np.ndarray], np.ndarray, list[str], list[str], list[float]]:
        """The floor's inequalities on the contact forces, each with its label: no contact lifts
        (its normal force at least its reserve), unless contacts may pull (``lift``), and, with a
        friction coefficient ``mu``, every driven wheel's traction inside its pyramid of ``faces``
        faces turned to the platform's ``heading`` (rad), less the reserve.

        Args:
            support: the contacts; ``columns`` where each one's force is in the contact forces.
            carried: the mass the floor carries, robot and object (kg); ``gravity`` in the
                floor's axes, (3,) m/s^2: the reserve is a share of their weight.

        Returns:
            ``(G, h, labels, kinds, scales)``: G by variable name (r, n_forces), h (r,), one label
            per row, its kind (``"contact"``: a contact's load; ``"traction"``) and its scale (N:
            a contact's equal share of the weight, or the friction that share gives a wheel's
            pyramid). Whether the robot tips is read where the rows bind, from the zero-moment
            point (:func:`mobmanip.analysis.reaches.floor_limits`).
        """
        sharing_model, n_forces = self.sharing(mu), columns.size
        G_rows, h_rows, labels, kinds, scales = [], [], [], [], []
        share = carried * -gravity[2] / len(support.contacts)  # N: a contact's equal share of the weight
        least = self.reserve * share
        for contact, col in zip(support.contacts if not self.lift else (), columns.normals):
            row = np.zeros(n_forces)
            row[col] = -1.0
            G_rows.append(row)
            h_rows.append(-least)
            lifts = "normal force 0" if least == 0.0 else f"normal force at its reserve {least:.4g} N"
            why = "; the robot tips over" if sharing_model == "any" else f"; {_springs(support)}, before any tip-over"
            labels.append(f"{contact.name} lifts off the floor ({lifts}{why})")
            kinds.append("contact")  # tip-over is where such rows bind with the ZMP on the edge
            scales.append(share)
        if mu is not None and not self.lift:
            tilt = mu * math.cos(math.pi / faces) * (1.0 - self.reserve)
            for contact, (a, b) in zip(support.contacts, columns.slices):
                if not contact.driven:
                    continue
                for u in pyramid_faces(faces, heading):
                    row = np.zeros(n_forces)
                    row[a:b] = (u[0], u[1], -tilt)
                    G_rows.append(row)
                    h_rows.append(0.0)
                    labels.append(f"{contact.name} slips (traction at its friction limit, mu = {mu:g})")
                    kinds.append("traction")
                    scales.append(tilt * share if tilt > 0.0 else share)
        G = {CONTACT_FORCES: np.array(G_rows).reshape(-1, n_forces)}
        return G, np.array(h_rows, dtype=float), labels, kinds, scales

    def _level_band(
        self,
        G: dict[str, np.ndarray],
        h: np.ndarray,
        labels: list[str],
        kinematics: list[np.ndarray],
        arms,
        level: list[int],
        heading: float,
        nx: int,
    ) -> tuple[dict[str, np.ndarray], np.ndarray, list[str]]:
        """The contact inequalities ``(G, h, labels)`` with the level requirement's rows added:
        each hand's accelerations on the ``level`` rows within :attr:`level_tolerance` of zero,
        both senses.

        Args:
            kinematics: each hand's rows on the level rows, ``J[level] S`` (len(level), nx).
            arms: the robot's arms, in the hands' order (for the labels).
            heading: the platform's heading (rad): the band on roll and pitch is about its axes.
            nx: the number of reduced velocities.
        """
        n_forces = G[CONTACT_FORCES].shape[1]
        # the band on roll and pitch about the platform's own axes: a square in the world's
        # would make the set depend on the heading (by 7e-6 of a reach)
        kin = np.vstack([_platform_axes(block, level, heading) for block in kinematics])
        G = {CONTACT_FORCES: np.vstack([G[CONTACT_FORCES], np.zeros((2 * len(kin), n_forces))]),
             "xdot": np.vstack([np.zeros((len(h), nx)), kin, -kin])}  # fmt: skip
        h = np.r_[h, np.full(2 * len(kin), self.level_tolerance)]
        names = ("vertical acceleration", "roll acceleration", "pitch acceleration")
        labels = labels + [
            f"{arm.name} hand's {names[r - 2]} at the level band ({sign}{self.level_tolerance:g}; held level)"
            for sign in "+-"
            for arm in arms
            for r in level
        ]
        return G, h, labels

    def _report(
        self,
        support: Support,
        mu: float | None,
        faces: int,
        pose: tuple[float, float, float],
        points: np.ndarray,
        slices: list[tuple[int, int]],
        gravity: np.ndarray,
    ) -> dict:
        """What the floor reports with the set (``set.model["floor"]``), JSON-ready: its settings,
        the platform's pose, each contact (world point, columns in the contact forces, stiffness,
        rollers' free direction), the support polygon and, on a ramp, the slope and gravity."""
        info = {
            "floor": {
                "mu": None if self.lift else mu,
                "lift": self.lift,
                "load": self.sharing(mu),
                "reserve": self.reserve,
                "faces": faces,
                "pose": list(pose),
                "contacts": [
                    {
                        "name": ct.name,
                        "point": p.tolist(),
                        "driven": ct.driven,
                        "columns": list(s),
                        "stiffness": ct.stiffness,
                        "free": None if ct.free is None else list(ct.free),
                    }
                    for ct, p, s in zip(support.contacts, points, slices)
                ],
                "polygon": support.polygon(pose).tolist(),
                "level": self.level,
            }
        }
        if self.slope:
            info["floor"].update(slope=self.slope, uphill=self.uphill, gravity=gravity.tolist())
        return info


def _standing_robot(terms: Terms) -> tuple[Robot, np.ndarray, HeldObject]:
    """The robot, its configuration and the held object of ``terms``, checked for the floor.

    Raises:
        ArgumentError: terms without a robot, a configuration or an object.
        SpecError: a platform that does not move on the floor (:data:`FLOOR_KINDS`).
    """
    robot, q = terms.robot, terms.q
    if robot is None or q is None or terms.held_object is None:
        raise ArgumentError("the floor needs the robot, its configuration and the object (terms from terms_at)")
    if robot.wheel_platform is None or robot.platform.kind not in FLOOR_KINDS:
        raise _not_on_floor(robot.name, robot.platform.kind)
    return robot, q, terms.held_object


def check_floor_platform(name: str, kind: str) -> None:
    """Refuse the floor for robot ``name`` when its platform ``kind`` does not move on the floor
    (not one of :data:`FLOOR_KINDS`); the commands call it before any work is done.

    Raises:
        SpecError: naming the robot, its platform and the kinds the floor covers.
    """
    if kind not in FLOOR_KINDS:
        raise _not_on_floor(name, kind)


def _not_on_floor(name: str, kind: str) -> SpecError:
    return SpecError(
        f"the floor model covers platforms that move on the floor "
        f"({', '.join(kind.replace('_', ' ') for kind in FLOOR_KINDS)}); "
        f"{name!r} has {a_platform(kind)}"
    )


class _ContactColumns(NamedTuple):
    """The contact force variable's columns: 3 per driven contact (world x, y, z), 1 (the normal)
    per passive one.

    Attributes:
        wrench: the contact forces' wrench about the robot's centre of mass, (6, size).
        slices: each contact's ``(start, end)`` columns.
        normals: each contact's normal force column.
    """

    wrench: np.ndarray
    slices: list[tuple[int, int]]
    normals: list[int]

    @property
    def size(self) -> int:
        """How many columns in all."""
        return int(self.wrench.shape[1])


def _contact_columns(support: Support, points: np.ndarray, c: np.ndarray) -> _ContactColumns:
    """The contact force variable's columns for ``support``'s contacts at world ``points`` (n, 3)
    m, their wrench taken about the centre of mass ``c`` (3,) m."""
    blocks: list[np.ndarray] = []
    normals: list[int] = []
    slices: list[tuple[int, int]] = []
    for contact, p in zip(support.contacts, points):
        start = sum(block.shape[1] for block in blocks)
        wrench = np.vstack([np.eye(3), skew(p - c)])
        block = wrench if contact.driven else wrench[:, 2:3]
        blocks.append(block)
        slices.append((start, start + block.shape[1]))
        normals.append(start + block.shape[1] - 1)
    return _ContactColumns(np.hstack(blocks), slices, normals)


class _HandRows(NamedTuple):
    """Per hand (one entry per arm), what the floor's equations take of it (see :func:`_hand_rows`)."""

    task: list[np.ndarray]
    level: list[np.ndarray]
    kinematics: list[np.ndarray]
    grasp_task: list[np.ndarray]
    grasp_level: list[np.ndarray]


def _hand_rows(
    robot: Robot, S: np.ndarray, c: np.ndarray, center: np.ndarray, rows: list[int], level: list[int]
) -> _HandRows:
    """Each hand's wrench on the object seen by the whole robot and by the object, at the current
    frame placements and joint Jacobians of ``robot.data``.

    Args:
        robot: the robot; ``S`` its null space at the configuration, (nv, nx).
        c: its centre of mass, (3,) m; ``center`` the object's centre, (3,) m.
        rows: the task's rows of a 6-D wrench; ``level`` the level rows it leaves out.

    Returns:
        per hand: its wrench moved to c on the task's rows (``task``, (6, len(rows))) and on the
        level rows (``level``, (6, len(level))); its rows ``J[level] S`` (``kinematics``); its
        grasp map's level rows on the task's rows and on the level rows (``grasp_task``,
        ``grasp_level``).
    """
    model, data = robot.model, robot.data
    out = _HandRows([], [], [], [], [])
    for arm in robot.arms:
        p = data.oMf[arm.frame_id].translation
        about_c = wrench_shift(p - c)  # wrench at c
        out.task.append(about_c[:, rows])
        out.level.append(about_c[:, level])
        J = pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)
        out.kinematics.append(J[level] @ S)
        G6 = wrench_shift(p - center)
        out.grasp_task.append(G6[np.ix_(level, rows)])
        out.grasp_level.append(G6[np.ix_(level, level)])
    return out


def _level_hold(
    hands: _HandRows, level: list[int], object_mass: float, gravity: np.ndarray
) -> tuple[dict[str, np.ndarray], np.ndarray, dict[str, np.ndarray], list[_Equations]]:
    """The object held level: its level rows balance its weight, shared by the hands without
    squeezing it on those rows.

    Args:
        hands: from :func:`_hand_rows`; ``level`` the level rows a task leaves out.
        object_mass: kg; ``gravity`` in the floor's axes, (3,) m/s^2.

    Returns:
        ``(object_E, object_e, coupling, squeeze)``: the object's own rows (blocks by variable,
        right-hand side), the level wrenches' term in the reduced dynamics (by variable) and the
        no-squeeze equations (empty when the hands cannot squeeze on those rows).
    """
    # the object held level: its level rows balance its weight (g_o's convention: +m g up;
    # the object's own rows: in a team every robot's hands share them) ...
    object_e = np.array([-object_mass * gravity[r] if r < 3 else 0.0 for r in level])
    object_E = {"h": np.hstack(hands.grasp_task), LEVEL_WRENCHES: np.hstack(hands.grasp_level)}
    coupling = {LEVEL_WRENCHES: np.hstack([kin.T for kin in hands.kinematics])}
    # ... shared by the hands without squeezing it on those rows (the minimum-norm share:
    # no part in the null space of their grasp map)
    squeeze = _null_space(np.hstack(hands.grasp_level))
    equations = [({LEVEL_WRENCHES: squeeze}, np.zeros(len(squeeze)))] if len(squeeze) else []
    return object_E, object_e, coupling, equations


def pyramid_faces(faces: int, heading: float) -> np.ndarray:
    """The outward directions of a friction pyramid's faces in the floor plane, (faces, 2).

    The pyramid is inscribed in the round cone; its faces turn with the platform (the first one
    along its heading, ``heading`` rad from the world's +x), so that a robot turned on the floor
    has the same floor model, and its sets turn with it. Fixed in the world, an 8-face pyramid
    made reaches depend on the heading by up to 1 - cos(pi / 8) = 7.6 %."""
    angles = heading + 2.0 * math.pi * np.arange(faces) / faces
    return np.column_stack([np.cos(angles), np.sin(angles)])


def compliant_sharing(points: np.ndarray, stiffness: np.ndarray | None = None) -> np.ndarray:
    """The equations that make the normal forces at ``points`` (n, 2 or 3; m, on the floor) those
    of springs under a rigid platform: f_i = k_i d_i with the deflections d an affine function of
    the points' floor positions (``stiffness`` k, (n,), relative; default all equal). Returns
    N (n - 3, n) with orthonormal rows and N f_n = 0 exactly for those f_n; empty for three
    contacts or fewer."""
    xy = np.asarray(points, dtype=float)[:, :2]
    affine = np.column_stack([np.ones(len(xy)), xy - xy.mean(axis=0)])
    u, sigma, _ = np.linalg.svd(affine, full_matrices=True)
    rank = int(np.sum(sigma > 1e-9 * max(float(sigma[0]), 1e-300)))
    deflections = u[:, rank:].T  # N0 d = 0 for affine deflections d
    if stiffness is None:
        return deflections
    k = np.asarray(stiffness, dtype=float)
    if len(deflections) == 0 or np.all(k == k[0]):
        return deflections
    rows = deflections / k[None, :]  # d = f / k
    q, _ = np.linalg.qr(rows.T)
    return q.T


#: Platform kinds whose wheels all roll along the platform's x (their sideways direction is its y).
PARALLEL_WHEELS = ("differential_drive", "skid_steer")
#: Wheels whose contacts lie within this distance (m) along the platform's x share one axle.
AXLE_TOLERANCE = 1e-3


def lateral_sharing(x: np.ndarray, stiffness: np.ndarray | None = None) -> np.ndarray:
    """The equations that make the sideways forces of wheels rolling along the platform's x,
    at platform-frame positions ``x`` (n,) m along it, those of tyres as springs under a rigid
    platform: a sideways shift s and a turn theta of the platform deflect wheel i by s + theta x_i,
    so f_i = k_i (s + theta x_i) (``stiffness`` k, (n,), relative; default all equal). Wheels
    within :data:`AXLE_TOLERANCE` of each other along x are on one axle (one x for all of them):
    a file's rounding must not let two wheels of one axle squeeze the platform between them.
    Returns N (n - r, n) with orthonormal rows, N f = 0 for those f (r: 1 for one axle, 2 for
    more); empty when every wheel's force is free."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x)
    axle = np.zeros(len(x), dtype=int)
    for previous, current in zip(order[:-1], order[1:]):
        axle[current] = axle[previous] + int(x[current] - x[previous] > AXLE_TOLERANCE)
    n_axles = int(axle.max()) + 1 if len(x) else 0
    snapped = np.array([x[axle == axle[i]].mean() for i in range(len(x))])
    affine = np.column_stack([np.ones(len(x)), snapped - snapped.mean()])
    u, _, _ = np.linalg.svd(affine, full_matrices=True)
    deflections = u[:, min(n_axles, 2) :].T  # N0 d = 0 for the deflections s + theta x
    if stiffness is None or len(deflections) == 0 or np.all(stiffness == stiffness[0]):
        return deflections
    q, _ = np.linalg.qr((deflections / np.asarray(stiffness, dtype=float)[None, :]).T)
    return q.T


def _wheel_equations(
    robot, q, S, support: Support, points, slices, n_forces: int, gravity, mass: float, rows, lift: bool = False
) -> tuple[list[tuple[dict[str, np.ndarray], np.ndarray]], np.ndarray | None]:
    """What each platform kind adds to the whole robot's balance: the equations of its wheels that
    the reduced and whole-robot rows leave out, the efforts that are the floor's own traction,
    and the rollers' free directions (see the module's docstring); and, for a platform whose
    wheels scrub when it turns, the contact forces' term in the reduced dynamics,
    ``-(J_c S)^T`` (nx, n_forces), else ``None``. No equations for a differential drive.

    - Wheels whose rates are not reduced velocities of their own (a skid-steer side's second
      wheel, a steered base's free rear wheels) keep their own row of the dynamics,
      ``M_j S xdot + g_j = B_j tau + (J_c^T lambda)_j``: their contact's force along the rolling
      direction is what their share of the effort and their spin leave (zero effort: a free
      wheel).
    - The reduced dynamics have no contact force: they hold when the contact forces do no work
      along S, which rolling contacts do by themselves. A platform whose wheels scrub when it
      turns (:attr:`~mobmanip.platforms.base.Platform.scrubs`, a skid-steer's) cannot turn on
      the floor without sliding them sideways, and on the floor no wheel slides: at rest its
      base does not start a turn (its yaw acceleration, S's yaw row, is zero), and the sideways
      forces that hold it are constraint forces within friction, which do work along S (they
      join the reduced dynamics). A difference of the sides' torques is then held by the
      wheels' sideways friction. With contacts free to pull (``lift``, the ideal set) the turn
      is the kinematic model's: the sideways forces do no net work along it (reduced by SVD,
      the sides' opposite rows count once). Held by the kind, not by testing the rows for zero:
      a file's rounding that tilts a wheel's axis by 1e-8 must not add a constraint.
    - Platform efforts that act on the base itself (an omnidirectional base's planar joint) are
      the floor's traction: ``S_k^T sum_c J_c^T lambda_c = tau_k``.
    - A contact with rollers pushes nothing along their free direction.
    """
    model = robot.model
    base = [0, 1, 2]
    platform_joints = [v for v in np.flatnonzero(np.abs(S).sum(axis=1) > 0.0) if v >= 3]
    joint_rows = S.T[:, 3:]
    dependent: list[int] = []
    # one reduced velocity per joint (a differential drive): the rows are complete already
    rank = S.shape[1] if S.shape[1] == model.nv - 3 else int(np.linalg.matrix_rank(joint_rows))
    for v in platform_joints if rank < model.nv - 3 else ():  # the wheels whose own rows the system lacks
        unit = np.zeros((1, model.nv - 3))
        unit[0, v - 3] = 1.0
        grown = int(np.linalg.matrix_rank(np.vstack([joint_rows, unit])))
        if grown > rank:
            dependent.append(int(v))
            joint_rows, rank = np.vstack([joint_rows, unit]), grown
    traction = [k for k in range(S.shape[1]) if np.abs(robot.B[base, k]).max() > 0.0]
    rolled = [c for c, contact in enumerate(support.contacts) if contact.free is not None]
    out: list[tuple[dict[str, np.ndarray], np.ndarray]] = []
    if not (dependent or traction or rolled or robot.platform.scrubs):
        return out, None
    data = robot.data
    pin.computeJointJacobians(model, data, q)
    jacobians = np.zeros((n_forces, model.nv))  # each force column's generalized force
    wheel_ids = {name: model.getJointId(name) for name, _ in robot.platform.wheels()}
    for contact, p, (a, b) in zip(support.contacts, points, slices):
        jid = wheel_ids.get(contact.name, 1) if contact.source == "wheel" else 1
        J = pin.getJointJacobian(model, data, jid, pin.LOCAL_WORLD_ALIGNED)
        J_point = J[:3] - skew(p - data.oMi[jid].translation) @ J[3:]
        jacobians[a:b] = J_point[3 - (b - a) :]
    if dependent:
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        g = -mass * pin.jacobianCenterOfMass(model, data, q).T @ gravity
        hands = np.vstack(
            [pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[rows] for arm in robot.arms]
        )
        out.append(
            (
                {"xdot": M[dependent] @ S, "tau": -robot.B[dependent], CONTACT_FORCES: -jacobians[:, dependent].T,
                 "h": hands[:, dependent].T},
                -g[dependent],
            )
        )  # fmt: skip
    work = (jacobians @ S).T  # the contact forces' work along each reduced velocity, (nx, n_forces)
    if traction:
        out.append(({CONTACT_FORCES: work[traction], "tau": -np.eye(S.shape[1])[traction]}, np.zeros(len(traction))))
    turning = None
    if robot.platform.scrubs and not lift:  # no wheel slides: the base does not start a turn
        yaw_row = S[2:3] / np.linalg.norm(S[2])
        out.append(({"xdot": yaw_row}, np.zeros(1)))
        turning = -work
    elif robot.platform.scrubs:  # no work along the platform's own motions (rolling wheels do none by themselves)
        scrubbed = [k for k in range(robot.platform.n_reduced) if k not in traction]
        # one row per independent scrubbing motion (a skid-steer scrubs only as it turns: its two
        # sides' rows are opposite); directions below 1e-6 of the largest are the same motion
        _, sigma, vt = np.linalg.svd(work[scrubbed], full_matrices=False)
        keep = sigma > 1e-6 * sigma[0] if len(sigma) and sigma[0] > 0.0 else np.zeros(len(sigma), dtype=bool)
        if keep.any():
            out.append(({CONTACT_FORCES: vt[keep]}, np.zeros(int(keep.sum()))))
    if rolled:
        yaw = platform_pose(q)[2]
        block = np.zeros((len(rolled), n_forces))
        for i, c in enumerate(rolled):
            fx, fy = support.contacts[c].free or (0.0, 0.0)
            a = slices[c][0]
            block[i, a : a + 2] = (math.cos(yaw) * fx - math.sin(yaw) * fy, math.sin(yaw) * fx + math.cos(yaw) * fy)
        out.append(({CONTACT_FORCES: block}, np.zeros(len(rolled))))
    return out, turning


def _platform_axes(rows: np.ndarray, level: list[int], heading: float) -> np.ndarray:
    """A hand's rows on the level rows ``level`` with its roll and pitch rows (3 and 4, about the
    world's x and y) turned to the platform's forward and left axes at ``heading`` (rad)."""
    out = rows.copy()
    if 3 in level and 4 in level:
        i, j = level.index(3), level.index(4)
        c, s = math.cos(heading), math.sin(heading)
        out[i], out[j] = c * rows[i] + s * rows[j], -s * rows[i] + c * rows[j]
    return out


def _null_space(A: np.ndarray) -> np.ndarray:
    """Orthonormal rows spanning the null space of A (p, n), (n - rank, n); A's entries are
    dimensionless or metres (a grasp map), so its rank is read at 1e-9 of its largest singular value."""
    _, sigma, vt = np.linalg.svd(A)
    rank = int(np.sum(sigma > 1e-9 * max(float(sigma[0]) if len(sigma) else 0.0, 1e-300)))
    return vt[rank:]


def _springs(support: Support) -> str:
    """How the compliant model sees the contacts, for messages."""
    k = support.stiffness
    return "equally stiff contacts" if np.all(k == k[0]) else "contacts as springs of the spec's stiffness"


def friction_of(support: Support, mu: float | str | None, faces: int | None) -> tuple[float | None, int]:
    """The friction coefficient and pyramid faces a floor uses on ``support``: ``mu`` (``"spec"``:
    the support's own; ``None``: no traction limit) and ``faces`` (``None``: the support's). The
    one place a floor's friction is resolved (the floor at rest's and the floor of motion's)."""
    mu = support.mu if mu == "spec" else mu
    return (None if mu is None else float(mu)), int(support.faces if faces is None else faces)


def _robot_support(robot) -> Support:
    """The robot's own support, found once per robot (it reads the URDF for casters)."""
    cached = robot.__dict__.get("_floor_support")
    if cached is None:
        cached = robot_support(robot)
        robot.__dict__["_floor_support"] = cached
    return cached


def _weight(mass: float, gravity: np.ndarray) -> np.ndarray:
    """The robot's weight as a wrench about its centre of mass, (6,)."""
    return np.r_[mass * gravity, 0.0, 0.0, 0.0]


def _stack(equations: list[tuple[dict[str, np.ndarray], np.ndarray]], sizes: dict[str, int]):
    """Row blocks over named variables -> one block per variable (zeros where a block has none)."""
    names = sorted({name for blocks, _ in equations for name in blocks})
    E = {
        name: np.vstack([blocks.get(name, np.zeros((len(rhs), sizes[name]))) for blocks, rhs in equations])
        for name in names
    }
    return E, np.concatenate([rhs for _, rhs in equations])


def ground_reaction(info: dict, forces: np.ndarray) -> dict:
    """What the floor does at a solution: each contact's force, the zero-moment point and the
    stability margin.

    Args:
        info: the floor's entry of a set's model (``set.model["floor"]``).
        forces: the contact force variable at the solution (``witness.variables["contact_forces"]``).

    Returns:
        JSON-ready: ``contacts`` (name -> {normal (N), tangential (N), traction_use (``|f_t| / (mu f_n)``;
        ``None`` for an unloaded wheel)}),
        ``zmp`` (x, y; m, world: the centre of pressure, where the floor's resultant moment has no
        horizontal component), ``margin`` (m: signed distance of the ZMP to the support polygon's
        nearest edge, positive inside).
    """
    out: dict = {"contacts": {}}
    total, moment = 0.0, np.zeros(2)
    for contact in info["contacts"]:
        a, b = contact["columns"]
        f = np.zeros(3)
        f[3 - (b - a) :] = forces[a:b]
        normal, tangential = float(f[2]), float(np.hypot(f[0], f[1]))
        entry: dict[str, float | None] = {"normal": normal, "tangential": tangential}
        if contact["driven"] and info["mu"]:
            # |f_t| / (mu f_n); None for an unloaded wheel (it can push nothing along the floor)
            entry["traction_use"] = tangential / (info["mu"] * normal) if normal > 1e-9 else None
        out["contacts"][contact["name"]] = entry
        total += normal
        moment += normal * np.asarray(contact["point"][:2])
    if total > 1e-9:
        zmp = moment / total
        out["zmp"] = zmp.tolist()
        out["margin"] = polygon_margin(np.asarray(info["polygon"]), zmp)
    else:
        out["zmp"], out["margin"] = None, None
    return out
