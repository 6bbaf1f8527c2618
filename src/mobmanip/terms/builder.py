"""The one builder of the paper's terms at a configuration, and what measures are computed from.

:func:`terms_at` computes, for a robot at configuration q (robot and object at rest), the unified
Jacobian J_u = J S, the reduced dynamics P, Q, xi, the grasp W and the object's M_o, g_o, and
keeps the constraints the sets must honour (:mod:`mobmanip.terms.constraints`). The result, a
:class:`MeasureTerms`, is what every measure is computed from (``Measure.compute(terms)``) and
what :attr:`mobmanip.analysis.Analysis.terms` holds.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ArgumentError
from ..robot.tasks import get_task
from .constraints.base import Constraint, ConstraintRows, Terms
from .constraints.joint_limits import JOINT_BOXES
from .dynamics import decouple, frame_jacobians, placed_end_effectors, reduced_dynamics_unchecked
from .grasp import HeldObject, held_mass

if TYPE_CHECKING:
    from ..robot.model import Robot


@dataclass(frozen=True)
class MeasureTerms(Terms):
    """What a measure is computed from at one configuration (robot and object at rest): the
    paper's terms, which :class:`~mobmanip.terms.constraints.base.Terms` names one by one, and the
    coupled P.

    Attributes:
        P_coupled: the coupled P, (nx, nx) (``None``: the same as P).
    """

    P_coupled: np.ndarray | None = None

    def __post_init__(self):
        if not self.reduced_names:
            object.__setattr__(self, "reduced_names", tuple(f"x{i}" for i in range(len(self.velocity_limits))))
        constraints = tuple(self.constraints)
        for c in constraints:
            if not isinstance(c, Constraint):
                raise ArgumentError(f"a constraint must be a mobmanip Constraint, got {c!r}")
        names = [c.name for c in constraints]
        if len(set(names)) != len(names):
            raise ArgumentError(f"constraints must have distinct names, got {names}")
        object.__setattr__(self, "constraints", constraints)

    @classmethod
    def of(cls, analysis: Any) -> MeasureTerms:
        """The terms an :class:`mobmanip.analysis.Analysis` was computed from (``analysis.terms``)."""
        return analysis.terms

    @property
    def all_constraints(self) -> tuple[Constraint, ...]:
        """The joint boxes, then :attr:`constraints`."""
        return JOINT_BOXES + self.constraints

    def constrained(self, problem: str) -> tuple[Constraint, ...]:
        """The constraints beyond the joint boxes on ``problem`` (``"velocity"`` or ``"acceleration"``)."""
        return tuple(c for c in self.constraints if c.problem == problem)

    def rows(self, problem: str) -> tuple[ConstraintRows, ...]:
        """The rows of every constraint on ``problem``, joint box first, evaluated once."""
        return self._rows[problem]

    @functools.cached_property
    def _rows(self) -> dict[str, tuple[ConstraintRows, ...]]:
        out: dict[str, list[ConstraintRows]] = {"velocity": [], "acceleration": []}
        for constraint in self.all_constraints:
            rows = constraint.rows(self)
            if rows.problem != constraint.problem:
                raise ArgumentError(f"constraint {constraint.name!r} returned rows of the {rows.problem} problem")
            out[rows.problem].append(rows)
        return {k: tuple(v) for k, v in out.items()}

    def with_constraints(self, constraints: Iterable[Constraint]) -> MeasureTerms:
        """The same terms with other constraints (beyond the joint boxes)."""
        import dataclasses

        return dataclasses.replace(self, constraints=tuple(constraints))


def terms_at(
    robot: Robot,
    q: np.ndarray,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
    constraints: Iterable[Constraint] = (),
    check: bool = True,
) -> MeasureTerms:
    """The terms of ``robot`` at configuration ``q`` (robot and object at rest).

    Args:
        robot: the loaded robot.
        q: configuration, (nq,).
        task: task-space name; defaults to the spec's ``default_task``.
        object_mass: mass of the default object (kg), held between the end effectors; defaults
            to the spec's.
        held_object: an explicit object (overrides ``object_mass``); one grasp offset per arm.
        decoupled: P without the platform-arm blocks (the paper's Section 4.3).
        constraints: constraints beyond the joint boxes (:mod:`mobmanip.terms.constraints`).
        check: check q (off when the caller already has).

    Raises:
        ConfigurationError: a bad q; TaskError: a bad task or object.
    """
    q = robot.check_configuration(q) if check else q
    task = get_task(task or robot.spec.default_task)
    mass = held_mass(robot, object_mass, held_object)
    dyn = reduced_dynamics_unchecked(robot, q, None, False)
    J_u = frame_jacobians(robot, q, task) @ robot.null_space(q)
    positions = placed_end_effectors(robot)  # the frame placements were updated with the Jacobians
    obj = held_object if held_object is not None else HeldObject.between(positions, mass)
    return assemble_terms(robot, q, task.name, decoupled, J_u, dyn.P, dyn.xi, positions, obj, constraints=constraints)


def assemble_terms(
    robot: Robot,
    q: np.ndarray,
    task: str,
    decoupled: bool,
    J_u: np.ndarray,
    P: np.ndarray,
    xi: np.ndarray,
    positions: np.ndarray,
    held_object: HeldObject,
    W: np.ndarray | None = None,
    constraints: Iterable[Constraint] = (),
) -> MeasureTerms:
    """:class:`MeasureTerms` from arrays already computed (the compiled engine's, say)."""
    return MeasureTerms(
        task=task,
        J_u=J_u,
        W=held_object.grasp_matrix(task) if W is None else W,
        P=decouple(robot, P) if decoupled else P,
        Q=robot.Q,
        xi=xi,
        M_o=held_object.inertia_matrix(task),
        g_o=held_object.gravity_vector(task),
        velocity_limits=robot.velocity_limits,
        effort_limits=robot.effort_limits,
        decoupled=decoupled,
        constraints=tuple(constraints),
        reduced_names=tuple(robot.reduced_velocity_names),
        robot=robot,
        q=q,
        held_object=held_object,
        positions=positions,
        P_coupled=P,
    )
