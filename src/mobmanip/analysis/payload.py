"""The heaviest object a robot can hold still, or give an acceleration, at one posture: one linear
program with the object's mass as a variable.

At rest, with the object's acceleration a given, every row of the acceleration problem (the
reduced dynamics, the grasp, the object's own equation ``W h = M_o a + g_o`` and every
constraint's rows: the joint boxes, the floor's whole-robot balance, its reserve, its ramp, the
object held level) is linear in the problem's variables (reduced accelerations, efforts, the
hands' wrenches, contact forces) and in the object's mass m: ``M_o`` and ``g_o`` are m times a
fixed shape (the object's inertia scales with its mass, its shape stays), and the floor's rows
carry the object's weight through the hands' wrenches or as m times a fixed vector. So the
largest m is one linear program (HiGHS, :class:`mobmanip.sets.linear_programs.LinearProgram`).

The program is not written again here: the rows are the ones the capacity sets use
(:func:`mobmanip.terms.problems.capacity_rows`), stacked at two masses; their difference is the
column of m. A third mass is checked to lie on that line, so a constraint whose rows are not
affine in the mass (or that multiplies a variable by it) is refused, not silently linearised.

With a = 0 ("held still"), the object is still; the robot is at rest, and its joints may
accelerate where the object does not feel it (its platform against its arm, an arm's
self-motion), as in every capacity set: the set at mass m contains a exactly when m is at most
this program's optimum. That is a capacity of one instant. ``static=True`` holds every reduced
acceleration at zero as well (statics: nothing moves), the payload that can be held for a while.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import ArgumentError, ModelError
from ..robot.model import Robot
from ..robot.tasks import get_task
from ..sets.lifted import ranked_limits
from ..sets.linear_programs import LinearProgram
from ..support.ranges import OBJECT_MASS
from ..terms.builder import MeasureTerms, assemble_terms, terms_at
from ..terms.constraints.base import Constraint, ConstraintRows
from ..terms.constraints.floor import CONTACT_FORCES, ground_reaction
from ..terms.grasp import HeldObject
from ..terms.problems import CapacityRows, capacity_rows
from .reaches import floor_limits, limit_entry, tip_over_reading
from .single import default_object

#: The masses (kg) the rows are stacked at: the first two give the line, the third checks it.
_MASSES = (0.0, 1.0, 2.5)  # the first must be 0: the program's rows are those at no object
#: How far (relative to the rows' largest entry) the third mass's rows may be off the line.
_AFFINE_RTOL = 1e-9
#: A multiplier below this fraction of the largest is no limit (what stops the mass).
_DUAL_RTOL = 1e-9
#: What the program's outcomes are called.
STATUSES = ("bounded", "unbounded", "infeasible")


@dataclass(frozen=True)
class Payload:
    """The heaviest object at one posture (see the module's docstring).

    Attributes:
        robot: the robot's name.
        task: the task space the acceleration is given in.
        acceleration: the object's acceleration, in the task's coordinates (m/s^2, rad/s^2), (m,);
            zeros: held still.
        status: ``"bounded"`` (a largest mass exists), ``"unbounded"`` (no limit stops the mass:
            e.g. a planar task, whose object's weight is not the hands') or ``"infeasible"``
            (the robot cannot do it even with no object).
        mass: the largest object mass (kg) when bounded, else ``None``.
        binding: what stops it: the labels of the inequality rows whose multiplier is not zero
            at the optimum (a joint's effort, a support lifting off, a wheel slipping); empty
            unless bounded.
        variables: every variable of the program at the optimum, by name (``"xdot"`` reduced
            accelerations, ``"tau"`` efforts in N m or N, ``"h"`` the hands' wrenches on the
            object, ``"contact_forces"`` on the floor, in N); empty unless bounded.
        reduced_names: the reduced velocities' names, in the order of ``tau`` and ``xdot``.
        constraints: the constraints beyond the joint boxes, as described in JSON.
        static: whether the robot was held static too (every reduced acceleration zero).
        floor: on the floor and bounded, what the floor does at the optimum
            (:func:`mobmanip.terms.constraints.floor.ground_reaction`: each contact's normal and
            tangential force in N, the zero-moment point and its margin to the support polygon
            in m); else ``None``.
        reading: what stops it in words: ``binding``, with a robot about to tip (its zero-moment
            point on the support's edge, contacts unloaded) named as tip-over about that edge in
            place of the unloaded contacts' rows (as the floor's reaches read).
        limits: what stops it ranked by the program's multipliers, the limit worth most first:
            each ``{"label", "kind", "gain"}``, gain the mass (kg) 1 % more of that limit adds
            (on the floor read as :func:`mobmanip.analysis.reaches.floor_limits` reads it);
            empty unless bounded.
    """

    robot: str
    task: str
    acceleration: np.ndarray
    status: str
    mass: float | None
    binding: tuple[str, ...] = ()
    variables: Mapping[str, np.ndarray] = field(default_factory=dict)
    reduced_names: tuple[str, ...] = ()
    constraints: tuple[dict, ...] = ()
    static: bool = False
    floor: Mapping[str, Any] | None = None
    reading: tuple[str, ...] = ()
    limits: tuple[dict, ...] = ()

    @property
    def held_still(self) -> bool:
        """Whether the acceleration asked for is zero (the object held still)."""
        return not np.any(self.acceleration)

    @property
    def efforts(self) -> np.ndarray | None:
        """The reduced efforts at the optimum (N m or N), (nx,); ``None`` unless bounded."""
        return self.variables.get("tau")

    @property
    def contact_forces(self) -> np.ndarray | None:
        """The floor's contact forces at the optimum (N; see :mod:`mobmanip.terms.constraints.floor`),
        or ``None`` (no floor, or not bounded)."""
        return self.variables.get("contact_forces")

    def summary(self) -> str:
        """One sentence: the mass and what stops it (never an infinity)."""
        what = (
            ("hold still with the robot static" if self.static else "hold still")
            if self.held_still
            else "give the acceleration (" + _numbers(self.acceleration) + ")"
        )
        where = "on the floor" if self.constraints else "on the ideal model (no floor)"
        if self.status == "unbounded":
            return f"no limit stops the mass of an object {self.robot} can {what} {where}: the payload is unbounded"
        if self.status == "infeasible":
            return f"{self.robot} cannot {what} {where} even with no object"
        assert self.mass is not None
        return f"heaviest object {self.robot} can {what} {where}: {self.mass:.6g} kg"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: every attribute, arrays as lists (no infinity: ``mass`` is ``null`` unless bounded)."""
        return {
            "robot": self.robot,
            "task": self.task,
            "task_axes": list(get_task(self.task).labels),
            "acceleration": self.acceleration.tolist(),
            "held_still": self.held_still,
            "static": self.static,
            "reading": list(self.reading),
            "floor": self.floor,
            "status": self.status,
            "mass": self.mass,
            "binding": list(self.binding),
            "limits": [dict(entry) for entry in self.limits],
            "reduced_velocity_names": list(self.reduced_names),
            "variables": {name: value.tolist() for name, value in self.variables.items()},
            "constraints": [dict(c) for c in self.constraints],
            "summary": self.summary(),
        }


def payload(
    robot: Robot,
    q: np.ndarray,
    task: str | None = None,
    *,
    acceleration: Iterable[float] | None = None,
    constraints: Iterable[Constraint] = (),
    object: HeldObject | None = None,  # noqa: A002 - the object held, as the issue names it
    decoupled: bool = False,
    static: bool = False,
) -> Payload:
    """The heaviest object the robot can hold still, or give ``acceleration``, at configuration q.

    Args:
        robot: the loaded robot.
        q: configuration, (nq,).
        task: task-space name; defaults to the spec's ``default_task``.
        acceleration: the object's acceleration in the task's coordinates (m/s^2 on linear rows,
            rad/s^2 on angular ones), (m,); ``None``: held still (zeros).
        constraints: constraints beyond the joint boxes (e.g. ``Floor(mu=0.5)``).
        object: the object's shape: its centre, grasp offsets and inertia per kilogram (its
            ``inertia / mass``; the inertia scales with the mass found). Default: the object
            :func:`mobmanip.analysis.single.default_object` places between the hands (a sphere
            reaching the farthest grasp point), as :func:`mobmanip.analysis.single.analyze` does.
        decoupled: the decoupled P (no platform-arm interaction).
        static: the robot static too: every reduced acceleration zero (statics; the object held
            still). Off: the object still, the robot's joints free to accelerate where the
            object does not feel it (an instant's capacity, as the sets').

    Raises:
        ArgumentError: an acceleration of the wrong length or not finite; an object of zero mass
            with an inertia (no shape per kilogram); a constraint whose rows are not affine in
            the object's mass; ``static`` with an acceleration.
    """
    q = robot.check_configuration(q)
    task_space = get_task(task or robot.spec.default_task)
    a = checked_acceleration(acceleration, task_space.dim, task_space.name)
    constraints = tuple(constraints)
    shape = _unit_object(robot, q, object)
    unloaded: list[MeasureTerms] = []

    def terms_of(mass: float) -> MeasureTerms:
        # the robot's terms once; only the object (and the constraints' rows) change with the mass
        if not unloaded:
            unloaded.append(_terms(robot, q, task_space.name, shape, mass, decoupled, constraints))
            return unloaded[0]
        return _with_object(unloaded[0], scaled_object(shape, mass), constraints)

    return heaviest(
        terms_of,
        a,
        name=robot.name,
        task=task_space.name,
        reduced_names=tuple(robot.reduced_velocity_names),
        constraints=constraints,
        static=static,
    )


def heaviest(
    terms_of: Callable[[float], MeasureTerms],
    acceleration: np.ndarray,
    *,
    name: str,
    task: str,
    reduced_names: tuple[str, ...],
    constraints: tuple[Constraint, ...],
    static: bool = False,
) -> Payload:
    """The program behind :func:`payload` for any terms that hold an object of a given mass: one
    robot's, or a team's (:func:`mobmanip.team.payload.team_payload`).

    Args:
        terms_of: the terms (with the constraints' rows) holding the object at a mass (kg); called
            first at mass 0.
        acceleration: the object's acceleration, checked, (m,).
        name: who holds it, for the result. task, reduced_names, constraints: as the result
            states them.
        static: as :func:`payload`.
    """
    a = acceleration
    if static and np.any(a):
        raise ArgumentError("a static robot holds the object still: give no acceleration with static")
    terms = [terms_of(m) for m in _MASSES]
    stacks = [capacity_rows(t, "acceleration") for t in terms]
    A, lo_rows, hi_rows, lo, hi = _program_rows(stacks, terms, a)
    if static:
        lo[stacks[0].columns["xdot"]] = hi[stacks[0].columns["xdot"]] = 0.0
    program = LinearProgram(A, lo_rows, hi_rows, lo, hi)
    cost = np.zeros(A.shape[1])
    cost[-1] = 1.0
    common: dict[str, Any] = dict(
        robot=name,
        task=task,
        acceleration=a,
        reduced_names=reduced_names,
        constraints=tuple(c.describe() for c in constraints),
        static=static,
    )
    try:
        result = program.solve(cost)
    except ModelError:
        if program.last_status != "Unbounded":
            raise
        return Payload(status="unbounded", mass=None, **common)
    if result is None:
        return Payload(status="infeasible", mass=None, **common)
    value, z = result
    mass = max(float(value), 0.0)
    first = stacks[0]
    n_eq, n_ub = len(first.rows.b_eq), len(first.rows.b_ub)
    duals = program.row_duals[n_eq : n_eq + n_ub]
    scale = float(np.abs(duals).max(initial=0.0))
    chosen = np.abs(duals) > _DUAL_RTOL * max(scale, 1e-300)
    labels = first.labels
    # a label that states a bound depending on the mass (a reserve's share): read at the optimum's mass
    if labels != stacks[1].labels and mass <= OBJECT_MASS[1]:
        labels = capacity_rows(terms_of(mass), "acceleration").labels
    slack = hi_rows[n_eq:] - A[n_eq:] @ z
    tight = slack <= 1e-7 * (np.abs(hi_rows[n_eq:]) + np.abs(A[n_eq:]) @ np.abs(z) + 1e-12)
    chosen |= _unloaded_wheels(labels, chosen, tight, first.model)
    binding = tuple(dict.fromkeys(label for label, c in zip(labels, chosen) if c))
    variables = {name: z[where].copy() for name, where in first.columns.items()}
    info = first.model.get("floor")
    floor, reading = None, binding
    ranked = ranked_limits(np.where(chosen, np.abs(duals), 0.0), labels, first.kinds, first.scales)
    limits = tuple(limit_entry(lim.label, lim.kind, lim.gain) for lim in ranked)
    if info is not None and CONTACT_FORCES in variables:
        floor = ground_reaction(info, variables[CONTACT_FORCES])
        reading = tuple(tip_over_reading(list(binding), info, floor))
        limits = tuple(floor_limits(ranked, info, floor))
    return Payload(
        status="bounded", mass=mass, binding=binding, variables=variables, floor=floor, reading=reading,
        limits=limits, **common,
    )  # fmt: skip


def _terms(robot, q, task, shape, mass, decoupled, constraints) -> MeasureTerms:
    return terms_at(
        robot,
        q,
        task,
        held_object=scaled_object(shape, mass),
        decoupled=decoupled,
        constraints=constraints,
        check=False,
    )


def _with_object(terms: MeasureTerms, held: HeldObject, constraints: tuple[Constraint, ...]) -> MeasureTerms:
    """The same robot's terms holding another object."""
    assert terms.q is not None and terms.positions is not None  # terms_at's
    P = terms.P if terms.P_coupled is None else terms.P_coupled
    return assemble_terms(
        terms.robot, terms.q, terms.task, terms.decoupled, terms.J_u, P, terms.xi, terms.positions, held,
        constraints=constraints,
    )  # fmt: skip


def _unloaded_wheels(labels: tuple[str, ...], chosen: np.ndarray, tight: np.ndarray, model: Mapping) -> np.ndarray:
    """The rows to name beside the multipliers' (a bool per inequality row): a wheel whose
    friction rows bind while its normal force is at its least (zero, or its reserve) can push
    nothing more along the floor because it carries no more load; its friction and lift-off rows
    are then one limit (the pyramid holds only a loaded wheel) and the multipliers may land on
    either, so both are named."""
    out = np.zeros(len(labels), dtype=bool)
    for contact in model.get("floor", {}).get("contacts", ()):
        name = contact["name"]
        slips = [i for i, label in enumerate(labels) if label.startswith(f"{name} slips")]
        lifts = [i for i, label in enumerate(labels) if label.startswith(f"{name} lifts off")]
        if any(chosen[i] for i in slips) and all(tight[i] for i in lifts):
            out[lifts] = True
    return out


def checked_acceleration(acceleration: Iterable[float] | None, dim: int, task: str) -> np.ndarray:
    if acceleration is None:
        return np.zeros(dim)
    try:
        a = np.asarray(list(acceleration), dtype=float)
    except (TypeError, ValueError):
        raise ArgumentError(f"the acceleration must be {dim} numbers (task {task}), got {acceleration!r}") from None
    if a.shape != (dim,):
        raise ArgumentError(f"the acceleration must have {dim} components (task {task}), got {a.size}")
    if not np.all(np.isfinite(a)):
        raise ArgumentError(f"the acceleration must be finite, got {a.tolist()}")
    return a


def _unit_object(robot: Robot, q: np.ndarray, given: HeldObject | None) -> HeldObject:
    """The object's shape at 1 kg: its inertia per kilogram, its centre and grasp offsets."""
    return default_object(robot, q, 1.0) if given is None else unit_object(given)


def unit_object(given: HeldObject) -> HeldObject:
    """``given``'s shape at 1 kg: its inertia per kilogram, its centre and grasp offsets.

    Raises:
        ArgumentError: an object of zero mass with an inertia (no inertia per kilogram).
    """
    if given.mass > 0.0:
        return replace(given, mass=1.0, inertia=np.asarray(given.inertia, dtype=float) / given.mass)
    if np.any(given.inertia):
        raise ArgumentError("an object of zero mass with an inertia has no inertia per kilogram: give it a mass")
    return replace(given, mass=1.0)


def scaled_object(shape: HeldObject, mass: float) -> HeldObject:
    """The object of ``shape`` (:func:`unit_object`) at ``mass`` kg: its inertia scaled with it."""
    return replace(shape, mass=float(mass), inertia=shape.inertia * float(mass))


def _program_rows(
    stacks: list[CapacityRows], terms: list[MeasureTerms], a: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The program over (z, m): the rows at mass 0 plus m times their change per kilogram, with
    the task's columns fixed at ``a``.

    Returns:
        A (p + r, n + 1), its rows' lower and upper bounds, the columns' lower and upper bounds.

    Raises:
        ArgumentError: the rows at the three masses are not on one line, or the mass multiplies
            a variable other than the object's acceleration, or changes a bound.
    """
    r0, r1, r2 = (s.rows for s in stacks)
    if any(s.rows.A_eq.shape != r0.A_eq.shape or s.rows.A_ub.shape != r0.A_ub.shape for s in stacks):
        raise ArgumentError("the problem's rows change in number with the object's mass: " + _culprit(terms))
    t = (_MASSES[2] - _MASSES[0]) / (_MASSES[1] - _MASSES[0])
    for name in ("A_eq", "b_eq", "A_ub", "b_ub"):
        x0, x1, x2 = (getattr(r, name) for r in (r0, r1, r2))
        scale = max(float(np.abs(x).max(initial=0.0)) for x in (x0, x1, x2))
        if np.abs(x2 - (x0 + t * (x1 - x0))).max(initial=0.0) > _AFFINE_RTOL * max(scale, 1.0):
            raise ArgumentError("the problem's rows are not affine in the object's mass: " + _culprit(terms))
    if not (np.array_equal(r0.lower, r1.lower) and np.array_equal(r0.upper, r1.upper)):
        raise ArgumentError("the variables' bounds change with the object's mass: " + _culprit(terms))
    others = np.ones(r0.A_eq.shape[1], dtype=bool)
    others[r0.task] = False
    for name in ("A_eq", "A_ub"):
        x0, x1 = getattr(r0, name), getattr(r1, name)
        scale = max(float(np.abs(x0).max(initial=0.0)), 1.0)
        if np.abs((x1 - x0)[:, others]).max(initial=0.0) > _AFFINE_RTOL * scale:
            raise ArgumentError(
                "the object's mass multiplies a variable other than its acceleration (the program would not "
                "be linear): " + _culprit(terms, _scales_a_variable)
            )
    # row(m) z = rhs(m) with z[task] = a: row0 z + m (d_row[:, task] a - d_rhs) = rhs0
    # (the rows at mass 0 are the first stack's: _MASSES starts at 0; the change per kilogram is the second's less it)
    per_kg = 1.0 / (_MASSES[1] - _MASSES[0])
    m_eq = per_kg * ((r1.A_eq - r0.A_eq)[:, r0.task] @ a - (r1.b_eq - r0.b_eq))
    m_ub = per_kg * ((r1.A_ub - r0.A_ub)[:, r0.task] @ a - (r1.b_ub - r0.b_ub))
    A = np.vstack([np.c_[r0.A_eq, m_eq], np.c_[r0.A_ub, m_ub]])
    lo_rows = np.r_[r0.b_eq, np.full(len(r0.b_ub), -np.inf)]
    hi_rows = np.r_[r0.b_eq, r0.b_ub]
    lo, hi = r0.lower.copy(), r0.upper.copy()
    lo[r0.task] = hi[r0.task] = a
    return A, lo_rows, hi_rows, np.r_[lo, 0.0], np.r_[hi, math.inf]


def _culprit(terms: list[MeasureTerms], wrong: Callable[[list[ConstraintRows | None]], bool] | None = None) -> str:
    """The constraints whose rows at the three masses are ``wrong`` (default: not on one line),
    for messages."""
    rows = [{r.name: r for r in t.rows("acceleration")} for t in terms]
    test = wrong or (lambda found: not _affine_rows(found))
    found = [name for name in rows[0] if test([r.get(name) for r in rows])]
    return ", ".join(f"constraint {name!r}" for name in found) or "the object's own equations"


def _scales_a_variable(rows: list[ConstraintRows | None]) -> bool:
    """Whether a constraint's coefficients of a variable other than the object's acceleration
    change with the mass (between the first two masses)."""
    first, second = rows[0], rows[1]
    if first is None or second is None:
        return True
    for one, two in ((first.G, second.G), (first.E, second.E), (first.object_E, second.object_E)):
        for name in set(one) | set(two):
            if name == "a":
                continue
            if name not in one or name not in two or np.shape(one[name]) != np.shape(two[name]):
                return True
            if not np.allclose(one[name], two[name], rtol=_AFFINE_RTOL, atol=0.0):
                return True
    for equation in set(first.couplings) | set(second.couplings):
        one, two = first.couplings.get(equation, {}), second.couplings.get(equation, {})
        for name in set(one) | set(two):
            if name != "a" and (name not in one or name not in two or not np.array_equal(one[name], two[name])):
                return True
    return False


def _affine_rows(rows: list[ConstraintRows | None]) -> bool:
    if any(r is None for r in rows):
        return False
    t = (_MASSES[2] - _MASSES[0]) / (_MASSES[1] - _MASSES[0])

    def arrays(r: Any) -> list[np.ndarray]:
        out = [np.asarray(r.h), np.asarray(r.e), np.asarray(r.object_e)]
        for blocks in (r.G, r.E, r.object_E):
            out += [np.asarray(blocks[k]) for k in sorted(blocks)]
        out += [np.asarray(r.shifts[k]) for k in sorted(r.shifts)]
        for eq in sorted(r.couplings):
            out += [np.asarray(r.couplings[eq][k]) for k in sorted(r.couplings[eq])]
        return out

    x0, x1, x2 = (arrays(r) for r in rows)
    if not (len(x0) == len(x1) == len(x2)) or any(
        a.shape != b.shape or a.shape != c.shape for a, b, c in zip(x0, x1, x2)
    ):
        return False
    for a0, a1, a2 in zip(x0, x1, x2):
        scale = max(float(np.abs(a0).max(initial=0.0)), float(np.abs(a2).max(initial=0.0)), 1.0)
        if np.abs(a2 - (a0 + t * (a1 - a0))).max(initial=0.0) > _AFFINE_RTOL * scale:
            return False
    return True


def _numbers(values: np.ndarray) -> str:
    return ", ".join(f"{v:.4g}" for v in values)
