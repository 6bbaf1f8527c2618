"""The capacity of a team in motion and its gradient over every robot's reduced velocities.

The team's capacity is the one ``mobmanip team`` computes: the measure's set (the kinematic or
dynamic ellipsoid, :mod:`mobmanip.measures`) of the robots' stacked terms
(:func:`mobmanip.team.stack_terms`) about the object as it is held now, read by the objective's
index (:class:`mobmanip.gradients.Objective`: ``minor_axis``, ``log_volume``, ``log_isotropy``
or ``capacity`` along a direction). Its gradient is taken over the team's reduced velocities:
entry j of robot i is the derivative of the capacity along robot i's motion
``q_i -> pin.integrate(q_i, S_i e_j eps)`` with the object held where it is (its grasp matrix
fixed), by central differences (:data:`GRADIENT_STEP`). Moving one robot changes only its own
terms, so each difference rebuilds one robot's terms and restacks; for the kinematic ellipsoid,
whose matrix is the sum of the robots' own forms A_i = W_i (J_hat_i J_hat_i^T)^-1 W_i^T
(:mod:`mobmanip.team.analysis`), only robot i's form is rebuilt from its Jacobian.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import MeasureError
from ..gradients import Objective
from ..measures import get_measure
from ..motion.trajectory import tangent_integrate
from ..robot.tasks import get_task
from ..sets.ellipsoid import Ellipsoid
from ..team import MemberTerms, Team, stack_terms
from ..terms.builder import terms_at
from ..terms.grasp import HeldObject

__all__ = ["GRADIENT_STEP", "TeamCapacity", "ellipsoid_index", "shape_index"]

#: Step of the central differences of the team's capacity (rad or m of a reduced velocity's motion).
GRADIENT_STEP = 1e-6


def shape_index(objective: Objective, C: np.ndarray, c: np.ndarray) -> float:
    """The objective's index of the ellipsoid {c + G z : ``|z| <= 1``} with shape C = G G^T, (m, m):
    ``minor_axis`` its smallest semi-axis sqrt(lambda_min(C)), ``log_volume`` log of its volume,
    ``log_isotropy`` 1/m log det C - log(tr C / m), ``capacity`` d . c + sqrt(d^T C d).

    Raises:
        MeasureError: a flat ellipsoid for the logarithmic indices.
    """
    m = C.shape[0]
    if objective.index == "minor_axis":
        return float(math.sqrt(max(float(np.linalg.eigvalsh(C)[0]), 0.0)))
    if objective.index == "capacity":
        d = np.asarray(objective.direction, dtype=float)
        return float(d @ c + math.sqrt(max(float(d @ C @ d), 0.0)))
    sign, logdet = np.linalg.slogdet(C)
    if sign <= 0:
        raise MeasureError(f"the {objective.ellipsoid} ellipsoid is flat: its {objective.index} is not defined")
    if objective.index == "log_volume":
        return float(m / 2 * math.log(math.pi) - math.lgamma(m / 2 + 1) + 0.5 * logdet)
    return float(logdet / m - math.log(float(np.trace(C)) / m))


def ellipsoid_index(objective: Objective, ellipsoid: Ellipsoid) -> float:
    """The objective's index of an ellipsoid (:func:`shape_index` of its shape and centre).

    Raises:
        MeasureError: an empty ellipsoid, or a flat one for the logarithmic indices.
    """
    if ellipsoid.empty:
        raise MeasureError(f"the {objective.ellipsoid} ellipsoid is empty: the limits cannot hold the load")
    s = np.asarray(ellipsoid.semi_axes, dtype=float)
    C = ellipsoid.axes.T @ np.diag(s**2) @ ellipsoid.axes
    return shape_index(objective, C, np.asarray(ellipsoid.center, dtype=float))


@dataclass
class TeamCapacity:
    """The objective's value for a team holding its object, robot by robot.

    Attributes:
        team: the team (its robots, grasps, object and task; the configurations are given per call).
        objective: the measure and index.
    """

    team: Team
    objective: Objective

    def __post_init__(self):
        self.task = get_task(self.team.task)
        self.measure = get_measure(self.objective.ellipsoid)
        self.evaluations = 0
        self.first_hand = [sum(len(o.arms) for o in self.team.members[:i]) for i in range(len(self.team.members))]

    def _blocks(self, i: int, W: np.ndarray) -> np.ndarray:
        m, k = self.task.dim, len(self.team.members[i].arms)
        return W[:, m * self.first_hand[i] : m * (self.first_hand[i] + k)]

    def member(self, i: int, q: np.ndarray, held: HeldObject, W: np.ndarray | None = None) -> MemberTerms:
        """Robot i's terms at configuration q (its grasping hands' rows, its blocks of W)."""
        team, task = self.team, self.task
        member = team.members[i]
        robot = member.robot
        own = terms_at(robot, q, task.name, object_mass=0.0, decoupled=team.decoupled, check=False)
        m = task.dim
        rows = own.J_u.reshape(len(robot.arms), m, -1)
        W = held.grasp_matrix(task) if W is None else W
        return MemberTerms(
            J_u=rows[list(member.arms)].reshape(m * len(member.arms), -1),
            W=self._blocks(i, W),
            P=own.P,
            Q=own.Q,
            xi=own.xi,
            velocity_limits=robot.velocity_limits,
            effort_limits=robot.effort_limits,
        )

    def value_of(self, parts: Sequence[MemberTerms], held: HeldObject) -> float:
        """The objective of the team's stacked terms (the measure's own set, as ``mobmanip team``)."""
        self.evaluations += 1
        team = self.team
        at = dataclasses.replace(team, held_object=held)
        return ellipsoid_index(self.objective, self.measure.compute(stack_terms(at, parts)))

    def value(self, qs: Sequence[np.ndarray], held: HeldObject) -> float:
        """The objective with the robots at ``qs`` (one configuration each) holding ``held``."""
        W = held.grasp_matrix(self.task)
        return self.value_of([self.member(i, q, held, W) for i, q in enumerate(qs)], held)

    def kinematic_form(self, i: int, q: np.ndarray, W: np.ndarray) -> np.ndarray:
        """Robot i's quadratic form A_i = W_i (J_hat_i J_hat_i^T)^-1 W_i^T (J_hat_i = J_i S_i
        diag(xdot_max_i) over its grasping hands' task rows), (m, m): the team's kinematic
        ellipsoid is {v : v^T (sum_i A_i) v <= 1} when every J_hat_i has full row rank.

        Raises:
            numpy.linalg.LinAlgError: J_hat_i J_hat_i^T is singular.
        """
        member = self.team.members[i]
        robot = member.robot
        model, data = robot.model, robot.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        rows = list(self.task.rows)
        J = np.vstack(
            [
                pin.getFrameJacobian(model, data, robot.arms[a].frame_id, pin.LOCAL_WORLD_ALIGNED)[rows]
                for a in member.arms
            ]
        )
        Jh = (J @ robot.null_space(q)) * np.asarray(robot.velocity_limits, dtype=float)
        Wi = self._blocks(i, W)
        return Wi @ np.linalg.solve(Jh @ Jh.T, Wi.T)

    def gradient(self, qs: Sequence[np.ndarray], held: HeldObject) -> tuple[float, np.ndarray]:
        """(value, gradient over the team's reduced velocities (nx,)): see the module's docstring."""
        W = held.grasp_matrix(self.task)
        parts = [self.member(i, q, held, W) for i, q in enumerate(qs)]
        value = self.value_of(parts, held)
        if self.objective.ellipsoid == "kinematic":
            try:
                return value, self._kinematic_gradient(qs, W)
            except np.linalg.LinAlgError:
                pass
        grad = []
        for i, q in enumerate(qs):
            robot = self.team.members[i].robot
            S = robot.null_space(q)
            for j in range(S.shape[1]):
                ends = []
                for sign in (1.0, -1.0):
                    moved = list(parts)
                    dq = sign * GRADIENT_STEP * S[:, j]
                    moved[i] = self.member(i, tangent_integrate(robot.model, q, dq), held, W)
                    ends.append(self.value_of(moved, held))
                grad.append((ends[0] - ends[1]) / (2.0 * GRADIENT_STEP))
        return value, np.array(grad)

    def _kinematic_gradient(self, qs: Sequence[np.ndarray], W: np.ndarray) -> np.ndarray:
        """Central differences of the kinematic index through the sum of the robots' forms."""
        forms = [self.kinematic_form(i, q, W) for i, q in enumerate(qs)]
        total = sum(forms)
        m = self.task.dim
        grad = []
        for i, q in enumerate(qs):
            robot = self.team.members[i].robot
            S = robot.null_space(q)
            others = total - forms[i]
            for j in range(S.shape[1]):
                ends = []
                for sign in (1.0, -1.0):
                    A = others + self.kinematic_form(
                        i, tangent_integrate(robot.model, q, sign * GRADIENT_STEP * S[:, j]), W
                    )
                    self.evaluations += 1
                    ends.append(shape_index(self.objective, np.linalg.inv(A), np.zeros(m)))
                grad.append((ends[0] - ends[1]) / (2.0 * GRADIENT_STEP))
        return np.array(grad)
