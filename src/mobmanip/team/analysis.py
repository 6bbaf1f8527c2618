"""What a team of robots can do with the object they hold together (see :mod:`mobmanip.team`).

The team's terms are the robots' own, stacked: J_u = blkdiag(J_i S_i), P = blkdiag(P_i),
Q = blkdiag(Q_i), xi = (xi_1, ..., xi_k), the limits concatenated, and one grasp matrix
W = [W_1 ... W_k] over all grasping hands about the object's centre, with one object (M_o, g_o).
Every registered measure (:mod:`mobmanip.measures`) computes from these arrays as it does for
one robot: the unified kinematic and dynamic ellipsoids and the exact capacity polytopes.

* The exact kinematic set is the intersection of the robots' own sets through the shared object,
  ``{v_o : W_i^T v_o = J_i S_i x_i, |x_i| <= xdot_max_i for every i}``; the kinematic ellipsoid
  adds the robots' quadratic forms (A = sum_i A_i when each J_i S_i has full row rank).
* The exact dynamic set couples the robots through the internal forces of the grasp: one robot
  may push while another pulls.

**Which robot limits the team along a direction.** :meth:`TeamAnalysis.contributions` gives, for
each robot, the elasticity of the team's reach along a direction d with respect to that robot's
limits: d log r(d) / d log s_i when all of robot i's limits (speed limits for velocity measures,
effort limits for acceleration measures) are scaled by s_i. The reach is, by default
(``along="ray"``), how far the set extends from its centre exactly in the direction d
(:func:`ray_radius`: the largest t with ``c + t d / |d|`` in the set); ``along="support"`` takes the
set's :meth:`~mobmanip.sets.taskset.TaskSet.radius_along` instead (its extent along d, any motion
across d allowed). A robot whose limits do not bound the team along d contributes 0. For the
kinematic polytope along a ray, the team's set being the intersection of the robots' own sets,
the robot whose own set is the shortest along d contributes 1 and the others 0 (0.5 each on a
tie). The velocity sets are homogeneous of degree one in the limits, so their contributions sum
to 1 (Euler's theorem); the acceleration sets under gravity are not.

**Load sharing.** :meth:`TeamAnalysis.load_sharing` chooses the hands' wrenches h on the object
(W h = M_o a_o + g_o: the object's equation of motion) so that the worst normalised torque over
all robots, ``max_j |tau_j| / tau_max_j``, is smallest: a linear program (scipy's HiGHS). Holding
still (a_o = 0), every robot stands still (qdd = 0) and tau_i = Q_i^-1 (J_i^T h_i - xi_i); for
an acceleration a_o, the robots' accelerations are free subject to J_i qdd_i = W_i^T a_o and
tau_i = Q_i^-1 (P_i qdd_i - xi_i + J_i^T h_i). A worst normalised torque above 1 is an overload:
no choice of internal forces holds the object within the limits, and the result is flagged
``empty``.
"""

from __future__ import annotations

import math
import types
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.optimize import linprog

from ..errors import ArgumentError, NumericalError, SetQueryError
from ..measures import MeasureTerms, Quantity, get_measure, resolve_measures
from ..robot.tasks import get_task
from ..sets.ellipsoid import Ellipsoid
from ..sets.taskset import TaskSet, check_direction
from ..terms.builder import terms_at
from ..terms.constraints.base import Constraint, ConstraintRows, Terms
from .members import Member, Team

__all__ = ["LoadSharing", "MemberTerms", "TeamAnalysis", "analyze_team", "member_terms", "ray_radius", "stack_terms"]


#: A robot's share (:meth:`TeamAnalysis.contributions`) below this does not limit the team: it
#: rounds to 0.00 as printed, and the elasticities' finite differences leave noise of about 5e-4.
NO_SHARE = 0.005


@dataclass(frozen=True)
class MemberTerms:
    """One robot's own terms in a team (robot and object at rest).

    Attributes:
        J_u: its grasping hands' unified Jacobian J_i S_i, (m k_i, nx_i).
        W: its grasp blocks [W_i1 ...] about the object's centre, (m, m k_i).
        P: reduced inertia (decoupled when the team says so), (nx_i, nx_i).
        Q: input matrix, (nx_i, nx_i).
        xi: bias at rest (-S^T g), (nx_i,).
        velocity_limits: (nx_i,).
        effort_limits: (nx_i,).
    """

    J_u: np.ndarray
    W: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    xi: np.ndarray
    velocity_limits: np.ndarray
    effort_limits: np.ndarray


def member_terms(team: Team) -> tuple[MemberTerms, ...]:
    """Each robot's terms: its own from :func:`mobmanip.terms.builder.terms_at` (the one builder),
    its grasping hands' rows of J_u and its blocks of the team's grasp matrix."""
    task = get_task(team.task)
    W = team.held_object.grasp_matrix(task)
    m = task.dim
    out, hand = [], 0
    for member in team.members:
        robot = member.robot
        own = terms_at(robot, member.q, task.name, object_mass=0.0, decoupled=team.decoupled)
        rows = own.J_u.reshape(len(robot.arms), m, -1)
        k = len(member.arms)
        out.append(
            MemberTerms(
                J_u=rows[list(member.arms)].reshape(m * k, -1),
                W=W[:, m * hand : m * (hand + k)],
                P=own.P,
                Q=own.Q,
                xi=own.xi,
                velocity_limits=robot.velocity_limits,
                effort_limits=robot.effort_limits,
            )
        )
        hand += k
    return tuple(out)


def stack_terms(
    team: Team,
    parts: Iterable[MemberTerms],
    scales: Mapping[int, float] | None = None,
    *,
    quantity: Quantity | None = None,
) -> MeasureTerms:
    """The team's :class:`MeasureTerms` from its robots' terms (limits of robot i scaled by
    ``scales[i]`` for the quantity's limits, when given)."""
    parts = tuple(parts)
    velocity = [p.velocity_limits for p in parts]
    effort = [p.effort_limits for p in parts]
    for i, s in (scales or {}).items():
        if quantity is None or quantity.limits == "velocity":
            velocity[i] = velocity[i] * s
        if quantity is None or quantity.limits == "effort":
            effort[i] = effort[i] * s
    task = get_task(team.task)
    obj = team.held_object
    return MeasureTerms(
        task=task.name,
        J_u=scipy.linalg.block_diag(*[p.J_u for p in parts]),
        W=np.hstack([p.W for p in parts]),
        P=scipy.linalg.block_diag(*[p.P for p in parts]),
        Q=scipy.linalg.block_diag(*[p.Q for p in parts]),
        xi=np.concatenate([p.xi for p in parts]),
        M_o=obj.inertia_matrix(task),
        g_o=obj.gravity_vector(task),
        velocity_limits=np.concatenate(velocity),
        effort_limits=np.concatenate(effort),
        decoupled=team.decoupled,
        # "robot: joint", so that a limit that binds names its robot
        reduced_names=tuple(f"{m.name}: {n}" for m in team.members for n in m.robot.reduced_velocity_names),
    )


@dataclass(frozen=True)
class LoadSharing:
    """How the robots share the object's load (see the module's docstring).

    Attributes:
        acceleration: the object's acceleration a_o (task units), (m,).
        wrenches: each hand's wrench on the object (N, N m; task rows), (n_hands, m).
        torques: each robot's torques (N m, N), one array (nx_i,) per robot.
        accelerations: each robot's reduced accelerations, one array (nx_i,) per robot.
        worst: the smallest worst normalised torque ``max_j |tau_j| / tau_max_j`` achievable.
        worst_by_robot: each robot's own worst normalised torque in that choice, (k,).
        empty: an overload: ``worst`` > 1, no internal forces hold the object within the limits.
        limiting: ``"robot/joint"`` of the most loaded joint (``""`` when no torque is needed).
    """

    acceleration: np.ndarray
    wrenches: np.ndarray
    torques: tuple[np.ndarray, ...]
    accelerations: tuple[np.ndarray, ...]
    worst: float
    worst_by_robot: np.ndarray
    empty: bool
    limiting: str

    def to_dict(self, names: Iterable[str], hands: Iterable[str]) -> dict:
        """JSON-ready, with the robots' and hands' names."""
        return {
            "acceleration": self.acceleration.tolist(),
            "worst_normalised_torque": self.worst,
            "empty": self.empty,
            "limiting_joint": self.limiting,
            "robots": {
                name: {"torques": t.tolist(), "worst_normalised_torque": float(w)}
                for name, t, w in zip(names, self.torques, self.worst_by_robot)
            },
            "hand_wrenches": {hand: w.tolist() for hand, w in zip(hands, self.wrenches)},
        }


@dataclass(frozen=True)
class TeamAnalysis:
    """A team analysed at rest.

    Attributes:
        team: the team.
        parts: each robot's own terms.
        terms: the team's stacked terms (:class:`MeasureTerms`).
        measures: the sets computed, by measure name, in the registry's order (read-only).
    """

    team: Team
    parts: tuple[MemberTerms, ...]
    terms: MeasureTerms
    measures: Mapping[str, TaskSet]

    def measure(self, name: str) -> TaskSet:
        """The set of measure ``name`` (computed now if it was not asked for)."""
        found = self.measures.get(get_measure(name).name)
        return found if found is not None else get_measure(name).compute(self.terms)

    def member_set(self, name: str, index: int) -> TaskSet:
        """Robot ``index``'s own set of a velocity measure through its own grasps: the team's
        exact kinematic set is the intersection of these.

        Raises:
            ArgumentError: an acceleration measure (the robots' dynamics couple through the
                internal forces; there is no set of one robot's own), or a bad index.
        """
        measure = get_measure(name)
        if measure.quantity.limits != "velocity":
            raise ArgumentError(f"member_set needs a velocity measure; {name!r} bounds {measure.quantity.name}")
        if not isinstance(index, int) or not 0 <= index < len(self.parts):
            raise ArgumentError(f"robot index must be 0 .. {len(self.parts) - 1}, got {index!r}")
        p = self.parts[index]
        terms = MeasureTerms(
            task=self.terms.task,
            J_u=p.J_u,
            W=p.W,
            P=p.P,
            Q=p.Q,
            xi=p.xi,
            M_o=self.terms.M_o,
            g_o=self.terms.g_o,
            velocity_limits=p.velocity_limits,
            effort_limits=p.effort_limits,
            decoupled=self.terms.decoupled,
        )
        return measure.compute(terms)

    def contributions(self, name: str, directions: np.ndarray, *, along: str = "ray", step: float = 1e-4) -> np.ndarray:
        """Each robot's share in limiting the team along each direction (see the module's
        docstring): the elasticity of the reach r(d) with respect to the robot's limits, as the
        mean of the one-sided differences in log s_i over ``step`` (exact where r is linear in
        s_i on both sides; at a kink, the mean of the two one-sided elasticities).

        Args:
            name: a measure name.
            directions: (n, m) or (m,), not necessarily unit.
            along: ``"ray"`` (:func:`ray_radius`) or ``"support"`` (``radius_along``).
            step: the relative change of the limits.

        Returns:
            (n, k): rows per direction, columns per robot (0 where the set has no reach).
        """
        measure = get_measure(name)
        if along not in ("ray", "support"):
            raise ArgumentError(f"along must be 'ray' or 'support', got {along!r}")
        d = np.atleast_2d(np.asarray(directions, dtype=float))
        if d.ndim != 2 or d.shape[1] != self.terms.W.shape[0] or not np.all(np.isfinite(d)):
            raise SetQueryError(f"directions must be finite, of shape (n, {self.terms.W.shape[0]}), got {d.shape}")

        def reach(task_set):
            return np.array([ray_radius(task_set, v) if along == "ray" else task_set.radius_along(v) for v in d])

        r0 = reach(self.measure(name))
        out = np.zeros((len(d), len(self.parts)))
        for i in range(len(self.parts)):
            r_up, r_down = (  # the same constraints (the floor's rows do not depend on the limits)
                reach(
                    measure.compute(
                        stack_terms(self.team, self.parts, {i: s}, quantity=measure.quantity).with_constraints(
                            self.terms.constraints
                        )
                    )
                )
                for s in (1.0 + step, 1.0 - step)
            )
            # a reach within the linear programs' rounding of zero has no share (its ratios are noise)
            tiny = 1e-9 * max(1.0, float(r0.max(initial=0.0)))
            ok = (r0 > tiny) & (r_up > tiny) & (r_down > tiny)
            # the mean of the one-sided differences: exact on each linear piece of a polytope's reach
            up = np.log(r_up[ok] / r0[ok]) / math.log1p(step)
            down = np.log(r0[ok] / r_down[ok]) / -math.log1p(-step)
            out[ok, i] = 0.5 * (up + down)
        return out

    def limiting_robots(self, name: str, directions: np.ndarray, *, along: str = "ray", tie: float = 1e-6) -> list[str]:
        """The robot that limits the team most along each direction: the largest contribution,
        robots within ``tie`` of it joined by ``"+"`` (a shared limit, e.g. in a symmetric
        team); ``""`` where the set has no reach or no robot's limits move it (every share
        below :data:`NO_SHARE`: on the floor, where a wheel's traction binds, the shares are the
        finite differences' noise, some 5e-4)."""
        shares = self.contributions(name, directions, along=along)
        names = [m.name for m in self.team.members]
        out = []
        for row in shares:
            top = float(row.max()) if row.size else 0.0
            out.append("+".join(n for n, v in zip(names, row) if v >= top - tie) if top >= NO_SHARE else "")
        return out

    def load_sharing(self, acceleration: np.ndarray | None = None) -> LoadSharing:
        """The hands' wrenches that hold (or accelerate) the object with the smallest worst
        normalised torque (see the module's docstring).

        Args:
            acceleration: the object's acceleration a_o (task units), (m,); default: held still.

        Raises:
            ArgumentError: a bad acceleration; NumericalError: the linear program failed.
        """
        return _load_sharing(self, acceleration)

    def to_dict(self) -> dict:
        """JSON-ready: the team, its robots' configurations, the stacked matrices, each measure
        under its JSON key and the load sharing at rest."""
        team = self.team
        sharing = self.load_sharing()
        return {
            "team": team.name,
            "task": team.task,
            "task_axes": list(get_task(team.task).labels),
            "decoupled": team.decoupled,
            "robots": [
                {
                    "name": m.name,
                    "robot": m.robot.name,
                    "platform": m.robot.platform.kind,
                    "q": m.robot.configuration_dict(m.q),
                    "grasping_arms": list(m.arm_names),
                    "reduced_velocity_names": list(m.robot.reduced_velocity_names),
                }
                for m in team.members
            ],
            "object": {
                "center": team.held_object.center.tolist(),
                "yaw": team.object_yaw,
                "mass": team.held_object.mass,
                "inertia": team.held_object.inertia.tolist(),
                "grasp_offsets": team.held_object.offsets.tolist(),
                "hands": list(team.hand_names),
            },
            "unified_jacobian": self.terms.J_u.tolist(),
            "grasp_matrix": self.terms.W.tolist(),
            "reduced_inertia": self.terms.P.tolist(),
            "input_matrix": self.terms.Q.tolist(),
            "bias": self.terms.xi.tolist(),
            "velocity_limits": self.terms.velocity_limits.tolist(),
            "effort_limits": self.terms.effort_limits.tolist(),
            **{get_measure(name).json_key: self._set_dict(name, s) for name, s in self.measures.items()},
            "limiting_robot": self._limiting_table(),
            "load_sharing": sharing.to_dict([m.name for m in team.members], team.hand_names),
        }

    def _set_dict(self, name: str, task_set: TaskSet) -> dict:
        """A set's JSON; on the floor, its readings along each task axis and what stops them
        (:func:`mobmanip.analysis.reaches.axis_reaches`)."""
        from ..analysis.reaches import axis_reaches

        out = task_set.to_dict()
        model = getattr(task_set, "model", None) or {}
        if any(isinstance(v, dict) and "floor" in v for v in model.values()):
            reaches = axis_reaches(task_set, self.team.task)
            if reaches is not None:
                out["reaches"] = reaches
        return out

    def _limiting_table(self) -> dict:
        """Per measure, per task axis both ways: the contributions of each robot."""
        m = self.terms.W.shape[0]
        labels = get_task(self.team.task).labels
        directions = np.vstack([np.eye(m), -np.eye(m)])
        names = [f"+{a}" for a in labels] + [f"-{a}" for a in labels]
        out = {}
        for measure in self.measures:
            shares = self.contributions(measure, directions)  # along rays
            out[measure] = {
                n: {member.name: float(s) for member, s in zip(self.team.members, row)} for n, row in zip(names, shares)
            }
        return out


def ray_radius(task_set: TaskSet, direction: np.ndarray) -> float:
    """How far a set extends from its centre c exactly along a direction d: the largest t >= 0
    with ``c + t d / |d|`` in the set (0 when the set is empty or flat across d).

    Ellipsoids: 1 / sqrt(u^T A u) for the unit u, u in the span of the positive semi-axes.
    Polytopes: their own ``ray_radius`` (one linear program; :meth:`mobmanip.sets.polytope.Polytope.ray_radius`,
    :meth:`mobmanip.sets.lifted.LiftedPolytope.ray_radius`).

    Raises:
        SetQueryError: a zero or non-finite direction; ArgumentError: a kind of set without a
            ray radius here.
    """
    u = check_direction(direction, task_set.dim)
    u = u / np.linalg.norm(u)
    if task_set.empty:
        return 0.0
    if isinstance(task_set, Ellipsoid):
        coords = task_set.axes @ u
        positive = task_set.semi_axes > 0
        if np.any(np.abs(coords[~positive]) > 1e-12):
            return 0.0
        return float(1.0 / np.linalg.norm(coords[positive] / task_set.semi_axes[positive]))
    own = getattr(task_set, "ray_radius", None)  # a polytope's, or one of linear programs (on the floor)
    if callable(own):
        return float(own(u))
    raise ArgumentError(f"ray_radius knows ellipsoids and polytopes, not {task_set.kind!r} sets")


def analyze_team(
    team: Team, measures: Iterable[str] | str | None = None, *, constraints: Iterable[Constraint] = ()
) -> TeamAnalysis:
    """Analyse a team at rest: every measure asked for (default: the default ones) of the
    object held by all the team's hands.

    Args:
        team: the team.
        measures: measure names (default: the default ones).
        constraints: constraints beyond the joint boxes (:mod:`mobmanip.terms.constraints`),
            each applied to every robot on its own terms; the polytopes honour them.

    Raises:
        UnknownMeasureError: a measure name that is not registered.
    """
    wanted = resolve_measures(measures)
    parts = member_terms(team)
    terms = stack_terms(team, parts)
    constraints = tuple(constraints)
    if constraints:
        terms = terms.with_constraints(_stacked_constraints(team, parts, constraints))
    sets = {measure.name: measure.compute(terms) for measure in wanted}
    return TeamAnalysis(team, parts, terms, types.MappingProxyType(sets))


def _load_sharing(analysis: TeamAnalysis, acceleration) -> LoadSharing:
    """The LP: variables (qdd (when accelerating), h, t); minimise t subject to
    -t <= Z tau <= t, W h = M_o a_o + g_o, J qdd = W^T a_o."""
    terms = analysis.terms
    m = terms.W.shape[0]
    moving = acceleration is not None
    a_o = np.zeros(m) if acceleration is None else np.asarray(acceleration, dtype=float)
    if a_o.shape != (m,) or not np.all(np.isfinite(a_o)):
        raise ArgumentError(f"object acceleration must be {m} finite numbers, got {acceleration!r}")
    nx, nh = terms.J_u.shape[1], terms.W.shape[1]
    Qinv = np.linalg.inv(terms.Q)
    Z = 1.0 / terms.effort_limits
    # tau = Qinv (P qdd - xi + J^T h) = A_q qdd + A_h h + b
    A_q = Qinv @ terms.P if moving else np.zeros((nx, 0))
    A_h = Qinv @ terms.J_u.T
    b = -Qinv @ terms.xi
    n_q = A_q.shape[1]
    T = Z[:, None] * np.hstack([A_q, A_h])  # normalised torques of (qdd, h)
    ones = np.ones((nx, 1))
    A_ub = np.vstack([np.hstack([T, -ones]), np.hstack([-T, -ones])])
    b_ub = np.concatenate([-Z * b, Z * b])
    eq = [np.hstack([np.zeros((m, n_q)), terms.W, np.zeros((m, 1))])]
    rhs = [terms.M_o @ a_o + terms.g_o]
    if moving:
        eq.append(np.hstack([terms.J_u, np.zeros((nh, nh + 1))]))
        rhs.append(terms.W.T @ a_o)
    cost = np.zeros(n_q + nh + 1)
    cost[-1] = 1.0
    result = linprog(
        cost,
        A_ub=A_ub,
        b_ub=b_ub,
        A_eq=np.vstack(eq),
        b_eq=np.concatenate(rhs),
        bounds=[(None, None)] * (n_q + nh) + [(0.0, None)],
        method="highs",
    )
    if result.status != 0:
        raise NumericalError(f"the load-sharing linear program failed: {result.message}")
    qdd, h = result.x[:n_q], result.x[n_q : n_q + nh]
    h = _polish(terms.W, h, terms.M_o @ a_o + terms.g_o)
    tau = A_q @ qdd + A_h @ h + b
    normalised = np.abs(Z * tau)
    worst = float(normalised.max()) if normalised.size else 0.0
    slices = analysis.team.member_slices()
    torques = tuple(tau[s] for s in slices)
    accelerations = tuple((qdd if moving else np.zeros(nx))[s] for s in slices)
    by_robot = np.array([float(normalised[s].max()) if s.stop > s.start else 0.0 for s in slices])
    j = int(np.argmax(normalised)) if normalised.size else 0
    k = next(i for i, s in enumerate(slices) if s.start <= j < s.stop)
    member: Member = analysis.team.members[k]
    limiting = f"{member.name}/{member.robot.reduced_velocity_names[j - slices[k].start]}" if worst > 0.0 else ""
    wrenches = h.reshape(-1, m)
    return LoadSharing(a_o, wrenches, torques, accelerations, worst, by_robot, worst > 1.0, limiting)


def _polish(W: np.ndarray, h: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """h moved (least-norm) onto W h = rhs to round-off (the LP meets it to its own tolerance)."""
    residual = rhs - W @ h
    return h + np.linalg.lstsq(W, residual, rcond=None)[0]


# ----------------------------------------------------------------------------------------------
# constraints of the robots, in the team's variables


@dataclass(frozen=True)
class _StackedConstraint(Constraint):
    """One constraint applied to every robot of a team: its rows, evaluated on each robot's own
    terms, placed at the robot's columns of the team's variables (its extra variables named
    ``"<robot>.<variable>"``)."""

    stacked: ConstraintRows
    original: Constraint
    name: str = ""
    problem: str = "acceleration"

    def rows(self, terms: Terms) -> ConstraintRows:
        return self.stacked

    def describe(self) -> dict:
        return self.original.describe()


def _stacked_constraints(
    team: Team, parts: tuple[MemberTerms, ...], constraints: tuple[Constraint, ...]
) -> tuple[Constraint, ...]:
    task = get_task(team.task)
    nx = [p.J_u.shape[1] for p in parts]
    nh = [p.W.shape[1] for p in parts]
    x_at, h_at = np.cumsum([0] + nx), np.cumsum([0] + nh)
    sizes = {"x": x_at[-1], "xdot": x_at[-1], "tau": x_at[-1], "h": h_at[-1], "v": task.dim, "a": task.dim}
    out = []
    for constraint in constraints:
        member_rows = []
        for member, part in zip(team.members, parts):
            own = MeasureTerms(
                task=task.name, J_u=part.J_u, W=part.W, P=part.P, Q=part.Q, xi=part.xi,
                M_o=team.held_object.inertia_matrix(task), g_o=team.held_object.gravity_vector(task),
                velocity_limits=part.velocity_limits, effort_limits=part.effort_limits, decoupled=team.decoupled,
                reduced_names=tuple(member.robot.reduced_velocity_names), robot=member.robot,
                q=member.robot.check_configuration(member.q), held_object=team.held_object,
            )  # fmt: skip
            member_rows.append(constraint.rows(own))
        out.append(
            _StackedConstraint(
                _stack_rows(team, member_rows, sizes, x_at, h_at), constraint, constraint.name, constraint.problem
            )
        )
    return tuple(out)


def _stack_rows(
    team: Team, rows: list[ConstraintRows], sizes: dict, x_at: np.ndarray, h_at: np.ndarray
) -> ConstraintRows:
    """The members' rows in the team's columns: x, xdot, tau and h at each robot's offsets, v
    and a shared, each robot's own variables under its name; the robots' couplings to the
    dynamics (and grasp) equations at its rows of them."""

    def place(name: str, i: int, block: np.ndarray) -> tuple[str, np.ndarray]:
        block = np.asarray(block, dtype=float)
        if name in ("x", "xdot", "tau", "h"):
            at = h_at if name == "h" else x_at
            full = np.zeros((block.shape[0], sizes[name]))
            full[:, at[i] : at[i + 1]] = block
            return name, full
        if name in ("v", "a"):
            return name, block
        return f"{team.members[i].name}.{name}", block

    def stack(blocks_per_member: list[tuple[Mapping[str, np.ndarray], int]]) -> dict[str, np.ndarray]:
        total = sum(n for _, n in blocks_per_member)
        out: dict[str, np.ndarray] = {}
        start = 0
        for i, (blocks, n) in enumerate(blocks_per_member):
            for name, block in blocks.items():
                key, full = place(name, i, block)
                if key not in out:
                    out[key] = np.zeros((total, full.shape[1]))
                out[key][start : start + n] += full
            start += n
        return out

    first = rows[0]
    variables = {f"{team.members[i].name}.{k}": v for i, r in enumerate(rows) for k, v in r.variables.items()}
    couplings: dict[str, dict[str, np.ndarray]] = {}
    eq_rows = {"dynamics": x_at, "grasp": h_at}
    for equation in {e for r in rows for e in r.couplings}:
        if equation not in eq_rows:  # the object's equation is the team's one: its rows add up
            parts = [place(k, i, b) for i, r in enumerate(rows) for k, b in r.couplings.get(equation, {}).items()]
            couplings[equation] = {}
            for key, block in parts:
                couplings[equation][key] = couplings[equation].get(key, 0) + block
            continue
        at = eq_rows[equation]
        blocks: dict[str, np.ndarray] = {}
        for i, r in enumerate(rows):
            for name, block in r.couplings.get(equation, {}).items():
                key, full = place(name, i, block)
                if key not in blocks:
                    blocks[key] = np.zeros((at[-1], full.shape[1]))
                blocks[key][at[i] : at[i + 1]] += full
        couplings[equation] = blocks
    # the object's own rows: one object, so every robot's hands share them (their blocks add up)
    object_E: dict[str, np.ndarray] = {}
    shared = [(i, r) for i, r in enumerate(rows) if len(r.object_e)]
    object_e = shared[0][1].object_e if shared else np.zeros(0)
    for i, r in shared:
        if r.object_e.shape != object_e.shape or not np.allclose(r.object_e, object_e, rtol=1e-12, atol=1e-12):
            raise ArgumentError(
                f"constraint {r.name!r}: the object's own rows differ between {team.members[0].name} and "
                f"{team.members[i].name} ({object_e.tolist()} against {np.asarray(r.object_e).tolist()})"
            )
        for name, block in r.object_E.items():
            key, full = place(name, i, block)
            object_E[key] = object_E[key] + full if key in object_E else full
    # shifts: each robot's own equations at its rows; the object's one for all (added once)
    shifts: dict[str, np.ndarray] = {}
    for equation in sorted({e for r in rows for e in r.shifts}):
        if equation in eq_rows:
            at = eq_rows[equation]
            total = np.zeros(int(at[-1]))
            for i, r in enumerate(rows):
                if equation in r.shifts:
                    total[at[i] : at[i + 1]] += r.shifts[equation]
            shifts[equation] = total
            continue
        given = [(i, np.asarray(r.shifts[equation], dtype=float)) for i, r in enumerate(rows) if equation in r.shifts]
        own_load = given[0][1]
        for i, shift in given:
            if shift.shape != own_load.shape or not np.allclose(shift, own_load, rtol=1e-12, atol=1e-12):
                raise ArgumentError(
                    f"constraint {rows[i].name!r}: the object's own load differs between "
                    f"{team.members[given[0][0]].name} and {team.members[i].name}"
                )
        shifts[equation] = own_load
    labels = tuple(f"{team.members[i].name}: {label}" for i, r in enumerate(rows) for label in r.row_labels())
    return ConstraintRows(
        name=first.name,
        problem=first.problem,
        variables=variables,
        G=stack([(r.G, len(r.h)) for r in rows]),
        h=np.concatenate([r.h for r in rows]),
        E=stack([(r.E, len(r.e)) for r in rows]),
        e=np.concatenate([r.e for r in rows]),
        couplings=couplings,
        object_E=object_E,
        object_e=np.asarray(object_e, dtype=float),
        shifts=shifts,
        labels=labels,
        info={f"{team.members[i].name}": dict(r.info) for i, r in enumerate(rows) if r.info},
        kinds=tuple(kind for r in rows for kind in r.row_kinds()),
        scales=tuple(float(v) for r in rows for v in r.row_scales()),
    )
