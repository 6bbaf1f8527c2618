"""What a constraint is: linear rows over the named variables of one configuration's problem.

mobmanip's capacity sets are the task-space shadows of linear problems at one configuration,
robot and object at rest. Two problems, with their variables (SI units):

- **velocity**: ``x`` (reduced velocities, nx) and ``v`` (the object's velocity, m), tied by the
  rigid grasp J_u x = W^T v;
- **acceleration**: ``xdot`` (reduced accelerations, nx), ``tau`` (reduced efforts, nx), ``h``
  (the wrench each hand applies ON the object, m k) and ``a`` (the object's acceleration, m),
  tied by the paper's equations: ``dynamics`` P xdot - Q tau + J_u^T h = xi, ``grasp``
  J_u xdot - W^T a = 0 and ``object`` W h - M_o a = g_o.

A :class:`Constraint` adds rows ``G z <= h`` and ``E z = e`` over those variables and over
variables it declares itself (a contact force, say), as :class:`ConstraintRows`. The joint
boxes are the first two constraints (:mod:`.joint_limits`). Every polytope measure honours every
constraint; a set that cannot (an ellipsoid, the compiled engine) says which ones it ignored. A
new constraint is one file: a subclass with one method, :meth:`Constraint.rows` (mink's limits
and pink's tasks are the pattern).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError

if TYPE_CHECKING:
    from ..grasp import HeldObject

#: The problems and their own variables, in column order.
PROBLEMS: dict[str, tuple[str, ...]] = {
    "velocity": ("x", "v"),
    "acceleration": ("xdot", "tau", "h", "a"),
}
#: The equations of each problem, which a constraint may add terms of its own variables to
#: (:attr:`ConstraintRows.couplings`; e.g. the floor's hand loads outside a planar task enter the
#: reduced dynamics).
EQUATIONS: dict[str, tuple[str, ...]] = {
    "velocity": ("grasp",),
    "acceleration": ("dynamics", "grasp", "object"),
}
#: What an inequality row limits (:attr:`ConstraintRows.kinds`): a joint's effort or speed, a
#: contact's load (``"contact"``: it may not pull), the robot tipping over (a row on the
#: zero-moment point; a reading names contacts unloading with the zero-moment point on the
#: support's edge so too), a driven wheel's traction, the object held level, or a row of a
#: user's own constraint.
ROW_KINDS = ("effort", "velocity", "contact", "tip-over", "traction", "level", "user")


@dataclass(frozen=True)
class Terms:
    """The paper's terms at one configuration (robot and object at rest), as a constraint reads
    them: :class:`mobmanip.terms.builder.MeasureTerms`, what every measure is computed from, is
    these with what a measure reads besides. The names are the paper's;
    :mod:`mobmanip.sets.ellipsoid` takes the same arrays.

    Attributes:
        task: task-space name.
        J_u: unified Jacobian J S, (m k, nx).
        W: grasp matrix, (m, m k).
        P: reduced inertia, coupled or decoupled as ``decoupled`` says, (nx, nx).
        Q: reduced input matrix, (nx, nx).
        xi: reduced bias at rest (-S^T g), (nx,).
        M_o: object inertia in the task space, (m, m).
        g_o: object gravity wrench (Eq. 22), (m,).
        velocity_limits: qdot_max per reduced velocity (rad/s or m/s), (nx,).
        effort_limits: tau_max per reduced velocity (N m or N), (nx,).
        decoupled: whether P is the decoupled one.
        constraints: the constraints beyond the joint boxes that the sets must honour.
        reduced_names: the name of each reduced velocity (wheels, then joints), (nx,).
        robot, q, held_object, positions: the configuration the terms belong to (the robot, its
            configuration (nq,), the object and the end effectors' positions (k, 3)); a
            constraint that needs more than the arrays (the floor's contacts) reads them. ``None``
            for terms assembled by hand (a team's, a test's).
    """

    task: str
    J_u: np.ndarray
    W: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    xi: np.ndarray
    M_o: np.ndarray
    g_o: np.ndarray
    velocity_limits: np.ndarray
    effort_limits: np.ndarray
    decoupled: bool
    constraints: tuple[Constraint, ...] = ()
    reduced_names: tuple[str, ...] = ()
    robot: Any = None
    q: np.ndarray | None = None
    held_object: HeldObject | None = None
    positions: np.ndarray | None = None


@dataclass(frozen=True)
class ConstraintRows:
    """A constraint's rows at one configuration.

    Attributes:
        name: the constraint's name (messages, JSON).
        problem: ``"velocity"`` or ``"acceleration"`` (see :data:`PROBLEMS`).
        variables: the extra variables it declares, name -> (size, lower bound, upper bound);
            bounds are scalars or arrays of that size (+-inf where free).
        G: inequality blocks by variable name, each (r, size of the variable).
        h: inequality right-hand side, (r,).
        E: equality blocks by variable name, each (p, size of the variable).
        e: equality right-hand side, (p,).
        couplings: terms it adds to the problem's own equations, equation name -> variable name ->
            block with as many rows as the equation (``"dynamics"``: nx rows, ``"grasp"``: m k,
            ``"object"``: m; see :data:`EQUATIONS`).
        object_E: equality blocks of the held object's own balance in rows the task leaves out
            (the floor's: a planar task's object is still held level), by variable name, each
            (p, size). There is one object: in a team these rows of every robot add up into
            one set (each robot's hands carry part of the load), where ``E`` is each robot's own.
        object_e: their right-hand side, (p,): the object's, the same for every robot.
        shifts: changes to the right-hand sides of the problem's own equations, equation name ->
            (rows of the equation,): ``"dynamics"`` (nx) a robot's own loads (its weight on a
            slope), ``"object"`` (m) the object's own (one object: in a team every robot gives
            the same, and it is added once).
        labels: one label per inequality row (what binds when the row is tight), (r,).
        info: what the constraint wants reported with the set (JSON-ready).
        kinds: what each inequality row limits, one of :data:`ROW_KINDS`, (r,); empty: every
            row ``"user"``.
        scales: the size of the limit each inequality row stands for, in the row's units, (r,)
            positive: what "1 % more of this limit" means when the limits that bind are ranked by
            their multipliers (a joint box's: its limit; the floor's: a contact's equal share of
            the weight, or the friction of that share). Empty: each row's ``|h|``, 1 where h is 0.
    """

    name: str
    problem: str
    variables: Mapping[str, tuple[int, Any, Any]] = field(default_factory=dict)
    G: Mapping[str, np.ndarray] = field(default_factory=dict)
    h: np.ndarray = field(default_factory=lambda: np.zeros(0))
    E: Mapping[str, np.ndarray] = field(default_factory=dict)
    e: np.ndarray = field(default_factory=lambda: np.zeros(0))
    couplings: Mapping[str, Mapping[str, np.ndarray]] = field(default_factory=dict)
    object_E: Mapping[str, np.ndarray] = field(default_factory=dict)
    object_e: np.ndarray = field(default_factory=lambda: np.zeros(0))
    shifts: Mapping[str, np.ndarray] = field(default_factory=dict)
    labels: tuple[str, ...] = ()
    info: Mapping[str, Any] = field(default_factory=dict)
    kinds: tuple[str, ...] = ()
    scales: tuple[float, ...] = ()

    def __post_init__(self):
        if self.problem not in PROBLEMS:
            raise ArgumentError(
                f"constraint {self.name!r}: problem must be one of {sorted(PROBLEMS)}, got {self.problem!r}"
            )
        unknown = (set(self.couplings) | set(self.shifts)) - set(EQUATIONS[self.problem])
        if unknown:
            raise ArgumentError(
                f"constraint {self.name!r} adds to unknown equations {sorted(unknown)}; "
                f"the {self.problem} problem has {list(EQUATIONS[self.problem])}"
            )
        clash = set(self.variables) & set(PROBLEMS[self.problem])
        if clash:
            raise ArgumentError(f"constraint {self.name!r} declares variables the problem already has: {sorted(clash)}")
        for rows, rhs, what in (
            (self.G, self.h, "G"),
            (self.E, self.e, "E"),
            (self.object_E, self.object_e, "object_E"),
        ):
            for name, block in rows.items():
                block = np.asarray(block)
                if block.ndim != 2 or block.shape[0] != len(rhs):
                    raise ArgumentError(
                        f"constraint {self.name!r}: {what}[{name!r}] has shape {block.shape}, expected {len(rhs)} rows"
                    )
                if not np.all(np.isfinite(block)):
                    raise ArgumentError(f"constraint {self.name!r}: {what}[{name!r}] is not finite")
            if not np.all(np.isfinite(rhs)):
                raise ArgumentError(f"constraint {self.name!r}: its right-hand side is not finite")
        for equation, shift in self.shifts.items():
            if np.asarray(shift).ndim != 1 or not np.all(np.isfinite(shift)):
                raise ArgumentError(f"constraint {self.name!r}: its {equation} shift must be finite and 1-D")
        if self.labels and len(self.labels) != len(self.h):
            raise ArgumentError(f"constraint {self.name!r}: {len(self.labels)} labels for {len(self.h)} rows")
        if self.kinds and len(self.kinds) != len(self.h):
            raise ArgumentError(f"constraint {self.name!r}: {len(self.kinds)} kinds for {len(self.h)} rows")
        unknown_kinds = sorted(set(self.kinds) - set(ROW_KINDS))
        if unknown_kinds:
            raise ArgumentError(
                f"constraint {self.name!r}: unknown row kinds {unknown_kinds}; expected some of {list(ROW_KINDS)}"
            )
        if self.scales:
            scales = np.asarray(self.scales, dtype=float)
            if scales.shape != (len(self.h),) or not np.all(np.isfinite(scales) & (scales > 0.0)):
                raise ArgumentError(
                    f"constraint {self.name!r}: its row scales must be {len(self.h)} positive finite numbers"
                )

    def row_kinds(self) -> tuple[str, ...]:
        """What each inequality row limits (:attr:`kinds`, ``"user"`` where not given), (r,)."""
        return tuple(self.kinds) or ("user",) * len(self.h)

    def row_labels(self) -> tuple[str, ...]:
        """Each inequality row's label (:attr:`labels`, the constraint's name where not given), (r,)."""
        return tuple(self.labels) or (self.name,) * len(self.h)

    def row_scales(self) -> np.ndarray:
        """The size of the limit each inequality row stands for (:attr:`scales`; ``|h|`` where not
        given, 1 where h is 0), (r,)."""
        if self.scales:
            return np.asarray(self.scales, dtype=float)
        h = np.abs(np.asarray(self.h, dtype=float))
        return np.where(h > 0.0, h, 1.0)


class Constraint(ABC):
    """A linear constraint of the capacity problems (see the module's docstring).

    Subclasses set :attr:`name` and :attr:`problem` and implement :meth:`rows`; they are
    immutable value objects (frozen dataclasses are a good fit) whose parameters say what they
    model (a friction coefficient, a limit).
    """

    #: How it is named in results and messages.
    name: str = ""
    #: ``"velocity"`` or ``"acceleration"``: the problem it constrains.
    problem: str = "acceleration"
    #: Whether it is one of the joint boxes every set already honours (ellipsoids included, in
    #: their Euclidean way); only other constraints are reported as ignored.
    joint_box: bool = False

    @abstractmethod
    def rows(self, terms: Terms) -> ConstraintRows:
        """Its rows at the configuration of ``terms`` (which also carries the robot and q)."""

    def describe(self) -> dict:
        """JSON-ready description (its name and parameters)."""
        params = {k: v for k, v in vars(self).items() if not k.startswith("_")}
        return {"name": self.name, **{k: _jsonable(v) for k, v in params.items()}}


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (tuple, list)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return repr(value)
