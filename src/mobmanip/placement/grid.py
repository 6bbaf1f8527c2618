"""Brute-force base placement: the objective over a grid of platform poses around a fixed object.

The baseline :func:`mobmanip.placement.place` is measured against, and a map of the measure over
where the platform stands. A grid point is an object direction ``angle`` alpha (deg, from the
platform heading), a horizontal ``distance`` d (m, from the arms' reference point) and a platform
``heading`` phi (deg, world). The arms hold the object as :func:`mobmanip.postures.inverse_kinematics.solve_postures`
finds it (the reference hold turned by alpha, at the reference height); the platform then stands
where that puts the object centre on the target: p = X - R(phi) c(alpha, d). Every grid point
costs one evaluation of the measure (through :func:`mobmanip.analyze_batch`, the reference
ellipsoids).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..batch import analyze_batch
from ..engine import EllipsoidBatch
from ..errors import ArgumentError, UnreachableGridError
from ..gradients.evaluator import Objective
from ..postures.inverse_kinematics import solve_postures
from ..robot.model import Robot
from ..robot.tasks import get_task


def objective_values(objective: Objective, ellipsoids: EllipsoidBatch) -> np.ndarray:
    """The objective of each ellipsoid of a batch from its semi-axes, axes and centre, (N,);
    -inf where degenerate or empty (a measure of a set with no volume)."""
    s = ellipsoids.semi_axes
    bad = ellipsoids.degenerate | ellipsoids.empty
    if objective.rows is not None:  # a block: the shadow on its rows, C restricted to them
        r = np.asarray(objective.rows)
        C = np.einsum("nki,nk,nkj->nij", ellipsoids.axes, s**2, ellipsoids.axes)[:, r][:, :, r]
        s = np.sqrt(np.maximum(np.linalg.eigvalsh(C)[:, ::-1], 0.0))
        bad = ellipsoids.empty | (s[:, -1] <= 0.0)
    m = s.shape[1]
    safe = np.where(bad[:, None], 1.0, s)
    if objective.index == "log_volume":
        out = 0.5 * m * math.log(math.pi) - math.lgamma(0.5 * m + 1.0) + np.sum(np.log(safe), axis=1)
    elif objective.index == "log_isotropy":
        out = np.mean(np.log(safe**2), axis=1) - np.log(np.mean(safe**2, axis=1))
    elif objective.index == "capacity":
        d = np.asarray(objective.direction)
        along = np.einsum("nkj,j->nk", ellipsoids.axes, d)
        return np.where(ellipsoids.empty, -np.inf, ellipsoids.center @ d + np.sqrt(np.sum((s * along) ** 2, axis=1)))
    else:
        out = s[:, -1].copy()
    return np.where(bad, -np.inf, out)


@dataclass(frozen=True)
class PlacementGrid:
    """The objective over a grid of platform poses around the target.

    Attributes:
        objective: the objective.
        angle_deg, distance, heading_deg: the grid's axes, (A,), (D,), (H,).
        values: the objective per grid point, (A, D, H); NaN where the hold is unreachable,
            -inf where the set has no volume.
        configurations: the configuration per grid point, (A, D, H, nq); NaN where unreachable.
        evaluations: number of grid points evaluated (reachable ones).
        seconds: wall time, postures included (s).
    """

    objective: Objective
    angle_deg: np.ndarray
    distance: np.ndarray
    heading_deg: np.ndarray
    values: np.ndarray
    configurations: np.ndarray
    evaluations: int
    seconds: float

    def best(self) -> tuple[float, np.ndarray]:
        """(best value, its configuration)."""
        flat = np.where(np.isnan(self.values), -np.inf, self.values).ravel()
        k = int(np.argmax(flat))
        return float(flat[k]), self.configurations.reshape(-1, self.configurations.shape[-1])[k]


def placement_grid(
    robot: Robot,
    target: ArrayLike,
    objective: Objective | str,
    angle_deg: ArrayLike,
    distance: ArrayLike,
    heading_deg: ArrayLike,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
) -> PlacementGrid:
    """The objective at every (angle, distance, heading) of a grid, the object centre at ``target``.

    The target's height must be the reference hold's (the grid's postures hold the object there).

    Raises:
        ArgumentError: a target at another height than the hold's, or a malformed grid.
        UnreachableGridError: no grid point can hold the object.
    """
    started = time.perf_counter()
    task = get_task(task or robot.spec.default_task)
    if not isinstance(objective, Objective):
        objective = Objective.parse(objective, task)
    objective.check_task(task)
    target = np.asarray(target, dtype=float).reshape(3)
    angle = np.asarray(angle_deg, dtype=float).reshape(-1)
    dist = np.asarray(distance, dtype=float).reshape(-1)
    heading = np.asarray(heading_deg, dtype=float).reshape(-1)
    if not (angle.size and dist.size and heading.size):
        raise ArgumentError("the placement grid needs at least one angle, distance and heading")
    table = solve_postures(robot, angle, dist, reference=robot.hold_configuration())
    hold = table.hold
    if abs(target[2] - hold.height) > 1e-9:
        raise ArgumentError(
            f"the grid holds the object at the reference height {hold.height:.4f} m; target z is {target[2]:g}"
        )
    if not table.reachable.any():
        raise UnreachableGridError(f"no grid point holds the object for {robot.name}")
    A, D, H = angle.size, dist.size, heading.size
    nq = robot.model.nq
    qs = np.full((A, D, H, nq), np.nan)
    joint_ids = [robot.model.getJointId(n) for n in table.joint_names]
    alpha = np.radians(angle)
    for a in range(A):
        for d in range(D):
            if not table.reachable[a, d]:
                continue
            q = table.reference.copy()
            for value, j in zip(table.joints[a, d], joint_ids):
                joint = robot.model.joints[j]
                if joint.nq == 2:
                    q[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
                else:
                    q[joint.idx_q] = value
            centre = hold.origin + dist[d] * np.array([math.cos(alpha[a]), math.sin(alpha[a])])
            for h, phi in enumerate(np.radians(heading)):
                c, s = math.cos(phi), math.sin(phi)
                xy = target[:2] - np.array([c * centre[0] - s * centre[1], s * centre[0] + c * centre[1]])
                q[:4] = (xy[0], xy[1], c, s)
                qs[a, d, h] = q
    reachable = ~np.isnan(qs[..., 0])
    values = np.full((A, D, H), np.nan)
    batch = analyze_batch(robot, qs[reachable], task.name, object_mass=object_mass, decoupled=decoupled)
    values[reachable] = objective_values(objective, getattr(batch, objective.ellipsoid))
    return PlacementGrid(
        objective=objective,
        angle_deg=angle,
        distance=dist,
        heading_deg=heading,
        values=values,
        configurations=qs,
        evaluations=int(reachable.sum()),
        seconds=time.perf_counter() - started,
    )
