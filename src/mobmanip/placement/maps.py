"""Placement maps: the best achievable measure at every platform position around a fixed object.

For a fixed object centre X, :func:`placement_map` gives, at every point p of a grid of platform
positions, the best value of an objective over the platform heading, the arm (and torso) joints
and the hold's turn psi about the vertical, with the hands holding the object at X exactly as in
:func:`mobmanip.placement.place` (same variables, constraints, joint limits). It is the inverse
of a sweep: a sweep fixes the platform and moves the object; a map fixes the object and asks
where the platform should stand. The map's best cell is :func:`place`'s answer to within the
grid's spacing.

Each cell is :func:`place`'s problem with the platform origin fixed at the cell (the region a
single point): SLSQP with the analytic gradients, started from the solved neighbouring cell
(continuation along a serpentine path through the grid), and from the reference hold facing the
object where no neighbour is solved or its start fails. Cells farther from X than the arms can
reach (a bound from the link lengths) are skipped. With ``headings`` the heading is fixed too,
one layer per heading.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..errors import ArgumentError, UnreachableObjectError
from ..gradients.evaluator import Objective
from ..robot.model import Robot
from .optimize import (
    CONSTRAINT_TOLERANCE,
    PlacementProblem,
    check_target,
    check_turn,
    clip_to_bounds,
    slsqp_run,
)

if TYPE_CHECKING:
    from ..gradients.readings import ReadingObjective
    from ..robot.collision import SelfCollision

_log = logging.getLogger(__name__)

#: Largest grid (cells per axis) a map accepts.
MAX_CELLS_PER_AXIS = 400


@dataclass(frozen=True)
class PlacementMap:
    """The best achievable objective over a grid of platform positions.

    Attributes:
        objective: the objective (a measure's reading: :func:`mobmanip.placement.grounded.reading_map`).
        target: the object centre (m, world), (3,).
        x, y: the grid's platform positions (m, world), (Nx,), (Ny,).
        headings: the fixed headings of the layers (rad), (H,); ``None`` when the heading is free.
        values: best value per cell, (Ny, Nx) (heading free) or (H, Ny, Nx); NaN where no pose
            holds the object.
        heading: the best heading per cell (rad), same shape; NaN where unreachable.
        configurations: the configuration per cell, values' shape + (nq,); NaN where unreachable.
        hold_turn: the hold's turn psi about the vertical per cell (rad), values' shape.
        evaluations: objective evaluations (value and gradient) spent.
        seconds: wall time (s).
    """

    objective: Objective | ReadingObjective
    target: np.ndarray
    x: np.ndarray
    y: np.ndarray
    headings: np.ndarray | None
    values: np.ndarray
    heading: np.ndarray
    configurations: np.ndarray
    evaluations: int
    seconds: float
    hold_turn: np.ndarray | None = None
    task: str | None = None

    def best(self) -> tuple[float, np.ndarray, tuple[int, ...]]:
        """(best value, its configuration, its index into ``values``).

        Raises:
            UnreachableObjectError: no cell holds the object.
        """
        if np.all(np.isnan(self.values)):
            raise UnreachableObjectError(f"no cell of the map holds the object at {self.target.tolist()} m")
        k = int(np.nanargmax(self.values))
        index = np.unravel_index(k, self.values.shape)
        return float(self.values[index]), self.configurations[index], tuple(int(i) for i in index)

    def best_cells(self, count: int) -> list[tuple[np.ndarray, float]]:
        """The ``count`` best cells that hold the object, best first, each (configuration, hold
        turn psi): starts for :func:`mobmanip.placement.optimize.place` (``seeds``)."""
        order = np.argsort(np.where(np.isnan(self.values), -np.inf, self.values), axis=None)[::-1]
        cells = []
        for k in order[: max(int(count), 0)]:
            index = np.unravel_index(int(k), self.values.shape)
            if np.isnan(self.values[index]):
                break
            turn = 0.0 if self.hold_turn is None else float(self.hold_turn[index])
            cells.append((self.configurations[index].copy(), turn))
        return cells

    def best_over_headings(self) -> tuple[np.ndarray, np.ndarray]:
        """(values, headings) per position, (Ny, Nx): the best layer's where headings are fixed."""
        if self.headings is None:
            return self.values, self.heading
        filled = np.where(np.isnan(self.values), -np.inf, self.values)
        layer = np.argmax(filled, axis=0)
        values = np.take_along_axis(self.values, layer[None], axis=0)[0]
        return values, np.where(np.isnan(values), np.nan, self.headings[layer])


def reach_bound(robot: Robot, reference: np.ndarray) -> float:
    """An upper bound (m) on the distance from the platform origin to the object centre over every
    posture: per arm, the distance to its first joint plus the distances between successive joint
    origins down to the end effector (constant for revolute joints), prismatic travel, and the
    grasp offset; the largest over the arms."""
    from ..postures.inverse_kinematics import hold_from

    model, data = robot.model, robot.model.createData()
    q = np.array(reference, dtype=float)
    q[:4] = (0.0, 0.0, 1.0, 0.0)
    pin.framesForwardKinematics(model, data, q)
    hold = hold_from(robot, reference)
    bound = 0.0
    root = 1  # the planar root joint
    for i, arm in enumerate(robot.arms):
        frame = model.frames[arm.frame_id]
        chain = []
        j = frame.parentJoint
        while j > root:
            chain.append(j)
            j = model.parents[j]
        chain.reverse()
        points = [data.oMi[j].translation for j in chain] + [data.oMf[arm.frame_id].translation]
        total = float(np.linalg.norm(points[0][:2]))  # horizontal: the platform turns about the vertical
        total += sum(float(np.linalg.norm(b - a)) for a, b in zip(points[:-1], points[1:]))
        for j in chain:
            joint = model.joints[j]
            if joint.shortname().removeprefix("JointModel").startswith("P") and joint.nq == 1:
                lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
                total += float(hi - lo) if np.isfinite(hi - lo) else 10.0
        bound = max(bound, total + float(np.linalg.norm(hold.offsets[i])))
    return bound


def default_extent(
    robot: Robot, target: ArrayLike, reference: np.ndarray | None = None
) -> tuple[float, float, float, float]:
    """The square of platform positions around the target within the arms' reach bound (m)."""
    target = check_target(target)
    reference = robot.hold_configuration() if reference is None else reference
    r = reach_bound(robot, reference)
    return target[0] - r, target[0] + r, target[1] - r, target[1] + r


def placement_map(
    robot: Robot,
    target: ArrayLike,
    objective: Objective | str,
    x: ArrayLike,
    y: ArrayLike,
    task: str | None = None,
    *,
    headings: ArrayLike | None = None,
    object_mass: float | None = None,
    decoupled: bool = False,
    reference: np.ndarray | None = None,
    max_iterations: int = 60,
    tolerance: float = 1e-7,
    hold_turn: float | None = None,
    collision: SelfCollision | None = None,
    rows_per_band: int | None = None,
    progress: Callable[[int], None] | None = None,
    fill: bool = True,
) -> PlacementMap:
    """The best achievable objective at every platform position (x, y) of a grid.

    Args:
        robot: the loaded robot (a moving platform).
        target: the object centre (m, world), (3,).
        objective: as :func:`mobmanip.placement.place`.
        x, y: the grid's platform positions (m, world), increasing, at most
            :data:`MAX_CELLS_PER_AXIS` each.
        task, object_mass, decoupled, reference: as :func:`mobmanip.placement.place`.
        headings: fixed platform headings (rad), one layer each; default the heading is free.
        max_iterations, tolerance: SLSQP's per cell.
        hold_turn, collision: a fixed object orientation and self-collision avoidance, as
            :func:`mobmanip.placement.place`'s.
        rows_per_band: the rows are cut into bands of this many (default: one band); each band
            is solved on its own, row after row from its first (each cell continued from the
            row before), so a band's cells are the same whether the band is solved here with
            the others or alone (e.g. on a cluster worker). All bands' rows advance together.
        progress: called with 1 after each cell.
        fill: then solve again, from every solved neighbour, each cell within reach that found no
            hold (:func:`fill_gaps`); off for a band of a larger map (the map fills its gaps once
            its bands are together).

    Raises:
        ArgumentError: a malformed target or grid; a fixed platform.
        MeasureError: an objective unknown for the measure.
        UnreachableObjectError: no cell holds the object.
    """
    started = time.perf_counter()
    target = check_target(target)
    xs, ys = _axis(x, "x"), _axis(y, "y")
    layers = None if headings is None else _axis(headings, "headings", increasing=False)
    if rows_per_band is None:
        rows_per_band = len(ys)
    if isinstance(rows_per_band, bool) or not isinstance(rows_per_band, int) or rows_per_band < 1:
        raise ArgumentError(f"rows per band must be a positive integer, got {rows_per_band!r}")
    bands = [(start, min(start + rows_per_band, len(ys))) for start in range(0, len(ys), rows_per_band)]
    if robot.platform_locked:
        raise ArgumentError(f"robot {robot.name!r} has a fixed platform: there is no base placement to map")
    problem = PlacementProblem.of_objective(
        robot, objective, task, target, None, reference, collision, object_mass=object_mass, decoupled=decoupled
    )
    evaluator, q_ref, task = problem.ev, problem.q_ref, problem.ev.task
    fixed = problem.fixed_errors(problem.start(0.0, np.random.default_rng(0)))
    if fixed.size and np.abs(fixed).max() > CONSTRAINT_TOLERANCE:  # e.g. the height of planar arms' hands
        raise UnreachableObjectError(
            f"no pose holds the object at {target.tolist()} m: {robot.name}'s hands cannot reach it there "
            f"from any platform position (the hold misses by {np.abs(fixed).max():.4g} in what no joint changes)"
        )
    reach = reach_bound(robot, q_ref)
    turn = None if hold_turn is None else check_turn(hold_turn)
    nq = robot.model.nq
    shape = (len(ys), len(xs)) if layers is None else (len(layers), len(ys), len(xs))
    values = np.full(shape, np.nan)
    heading = np.full(shape, np.nan)
    turns = np.full(shape, np.nan)
    configurations = np.full(shape + (nq,), np.nan)
    for layer in [None] if layers is None else range(len(layers)):
        fixed_heading = None if layer is None or layers is None else float(layers[layer])

        def band(start: int, stop: int) -> None:
            """Rows [start, stop), cell after cell along a serpentine, each continued from the
            cell before it and from one solved neighbour."""
            solved: dict[tuple[int, int], np.ndarray] = {}
            previous = None
            for iy, ix in _serpentine(start, stop, len(xs)):
                z = cell(iy, ix, previous, solved)
                previous = z
                if z is not None:
                    solved[(iy, ix)] = z
                if progress is not None:
                    progress(1)

        def cell(iy: int, ix: int, previous, solved, fixed_heading=fixed_heading, layer=layer) -> np.ndarray | None:
            p = np.array([xs[ix], ys[iy]])
            if np.hypot(*(target[:2] - p)) > reach:
                return None
            seeds = [previous] if previous is not None else []
            seeds += [solved[n] for n in _neighbours(iy, ix) if n in solved and solved[n] is not previous][:1]
            result = _solve_cell(problem, p, fixed_heading, turn, seeds, max_iterations, tolerance)
            if result is None:
                return None
            value, z = result
            index = (iy, ix) if layer is None else (layer, iy, ix)
            values[index] = value
            heading[index] = math.atan2(math.sin(z[2]), math.cos(z[2]))
            turns[index] = z[-1]
            configurations[index] = problem.configuration(z)
            return z

        # The bands run together: their cells' evaluations are batched, each band as on its own.
        _log.info("placement map of %s: %d x %d cells in %d bands, solved together", robot.name, len(xs), len(ys),
                  len(bands))  # fmt: skip
        problem.lockstep.run([functools.partial(band, start, stop) for start, stop in bands])
    out = PlacementMap(
        objective=evaluator.objective,
        target=target,
        x=xs,
        y=ys,
        headings=layers,
        values=values,
        heading=heading,
        configurations=configurations,
        evaluations=evaluator.evaluations,
        seconds=time.perf_counter() - started,
        hold_turn=turns,
        task=task.name,
    )
    if fill and layers is None:
        fill_gaps(out, problem, turn, max_iterations, tolerance)
        out = dataclasses.replace(out, evaluations=evaluator.evaluations, seconds=time.perf_counter() - started)
    if np.all(np.isnan(values)):
        raise UnreachableObjectError(
            f"no platform position of the map holds the object at {target.tolist()} m "
            f"(x {xs[0]:g}..{xs[-1]:g} m, y {ys[0]:g}..{ys[-1]:g} m; the arms reach at most {reach:.3f} m)"
        )
    return out


#: Rounds of :func:`fill_gaps` (each solves every gap next to a cell that holds the object).
FILL_ROUNDS = 3
#: The neighbours (the best ones) that seed a gap in :func:`fill_gaps`.
FILL_SEEDS = 3


def fill_gaps(grid: PlacementMap, problem: PlacementProblem, turn: float | None = None,
              max_iterations: int = 60, tolerance: float = 1e-7) -> int:  # fmt: skip
    """Solve again each cell of a heading-free map that found no hold but lies within reach and
    next to one that did, seeded from its best :data:`FILL_SEEDS` such neighbours only (the
    bands' continuation seeded it from one or two, and from the reference hold): a gap can be
    where continuation failed, not where nothing holds the object (TIAGo++ at (1.5, 0.5, 0.85) m
    had a gap where a placement confined to the cell held it). In place; cells in row-major
    order; after the first round only the gaps next to a cell filled in the round before, for
    :data:`FILL_ROUNDS` rounds at most. Returns the cells filled.

    Raises:
        ArgumentError: a map with fixed headings.
    """
    if grid.headings is not None:
        raise ArgumentError("gaps are filled in maps whose heading is free")
    reach = reach_bound(problem.robot, problem.q_ref)
    ny, nx = grid.values.shape
    turns = grid.hold_turn if grid.hold_turn is not None else np.zeros_like(grid.values)
    filled = 0
    fresh: set[tuple[int, int]] | None = None  # the cells filled in the round before (None: every cell)
    for _ in range(FILL_ROUNDS):
        found: set[tuple[int, int]] = set()
        for iy in range(ny):
            for ix in range(nx):
                p = np.array([grid.x[ix], grid.y[iy]])
                if not np.isnan(grid.values[iy, ix]) or np.hypot(*(grid.target[:2] - p)) > reach:
                    continue
                around = [(jy, jx) for jy in range(iy - 1, iy + 2) for jx in range(ix - 1, ix + 2)
                          if 0 <= jy < ny and 0 <= jx < nx and not np.isnan(grid.values[jy, jx])]  # fmt: skip
                if not around or (fresh is not None and not fresh.intersection(around)):
                    continue  # no neighbour holds it, or none new since this gap was last tried
                around.sort(key=lambda n: -grid.values[n])  # the best neighbours first, at most FILL_SEEDS
                seeds = [problem.variables(grid.configurations[n], float(turns[n])) for n in around[:FILL_SEEDS]]
                result = _solve_cell(problem, p, None, turn, seeds, max_iterations, tolerance, own=False)
                if result is None:
                    continue
                value, z = result
                grid.values[iy, ix] = value
                grid.heading[iy, ix] = math.atan2(math.sin(z[2]), math.cos(z[2]))
                turns[iy, ix] = z[-1]
                grid.configurations[iy, ix] = problem.configuration(z)
                found.add((iy, ix))
        filled += len(found)
        if not found:
            break
        fresh = found
    return filled


def _solve_cell(
    problem: PlacementProblem, p: np.ndarray, fixed_heading, turn, seeds, max_iterations, tolerance, own=True
):
    """(value, z) of the best run at platform position p, or None where nothing holds the object:
    from each seed (a neighbouring cell's optimum), then (``own``) from the reference hold at
    four platform headings; the first run that holds the object is kept."""
    bounds = problem.bounds()
    if turn is not None:
        bounds[-1] = (turn, turn)
    bounds[0] = (float(p[0]), float(p[0]))
    bounds[1] = (float(p[1]), float(p[1]))
    if fixed_heading is not None:
        bounds[2] = (fixed_heading, fixed_heading)
    toward = math.atan2(problem.target[1] - p[1], problem.target[0] - p[0])
    hold = problem.hold
    starts: list = []
    for offset in (0.0, math.pi / 2, -math.pi / 2, math.pi) if own else ():
        toward_hold = toward - math.atan2(hold.center[1], hold.center[0])
        heading = toward_hold + offset if fixed_heading is None else fixed_heading
        z = problem.start(heading, np.random.default_rng(len(starts)))
        z[:2] = p
        z[-1] = offset  # a fixed hold turn replaces it (the bounds)
        starts.append(z)
        if fixed_heading is not None:
            break
    best = None
    for z0 in [_seeded(s, p, fixed_heading) for s in seeds] + starts:
        z = newton_project(problem, clip_to_bounds(z0, bounds), bounds)
        if z is None:
            continue
        z = slsqp_run(problem, problem.objective, z, bounds, max_iterations, tolerance)
        if problem.residual(z) > CONSTRAINT_TOLERANCE:
            z = newton_project(problem, z, bounds)
            if z is None or problem.residual(z) > CONSTRAINT_TOLERANCE:  # off the hold, or colliding
                continue
        value, ok = problem.value_at(problem.configuration(z))
        if ok and (best is None or value > best[0]):
            best = (float(value), z)
        if best is not None:  # a seeded or first fresh start that succeeds is kept
            break
    return best


def newton_project(
    problem: PlacementProblem, z: np.ndarray, bounds: Sequence[tuple[float | None, float | None]], iterations: int = 40
) -> np.ndarray | None:
    """A z near ``z`` that holds the object, by damped Gauss-Newton steps on the hold errors over
    the variables not fixed by ``bounds``, clipped to the bounds; None when the errors stall
    above :data:`CONSTRAINT_TOLERANCE` (then the cell is taken as unreachable from this start)."""
    free = np.array([lo is None or hi is None or lo < hi for lo, hi in bounds])
    damping = 1e-4
    value, J = problem.constraints(z)
    error = float(value @ value)
    for _ in range(iterations):
        if math.sqrt(error) <= 0.1 * CONSTRAINT_TOLERANCE:
            break
        A = J[:, free]
        step = np.zeros_like(z)
        step[free] = -A.T @ np.linalg.solve(A @ A.T + damping * np.eye(A.shape[0]), value)
        trial = clip_to_bounds(z + step, bounds)
        v_trial, J_trial = problem.constraints(trial)
        e_trial = float(v_trial @ v_trial)
        if e_trial < error:
            z, value, J, error = trial, v_trial, J_trial, e_trial
            damping = max(damping * 0.1, 1e-12)
        else:
            damping *= 10.0
            if damping > 1e6:
                break
    hold_error = float(np.abs(problem.constraints(z, jacobian=False)).max())
    return z if hold_error <= CONSTRAINT_TOLERANCE else None


def _seeded(z: np.ndarray, p: np.ndarray, fixed_heading) -> np.ndarray:
    z = z.copy()
    z[:2] = p
    if fixed_heading is not None:
        z[2] = fixed_heading
    return z


def _serpentine(start: int, stop: int, nx: int):
    for iy in range(start, stop):
        for ix in range(nx) if (iy - start) % 2 == 0 else range(nx - 1, -1, -1):
            yield iy, ix


def _neighbours(iy: int, ix: int):
    return [(iy - 1, ix), (iy, ix - 1), (iy, ix + 1), (iy + 1, ix)]


def _axis(values, name: str, increasing: bool = True) -> np.ndarray:
    try:
        a = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ArgumentError(f"map {name} must be numbers, got {values!r}") from None
    if a.size == 0 or a.size > MAX_CELLS_PER_AXIS or not np.all(np.isfinite(a)):
        raise ArgumentError(f"map {name} must be 1 to {MAX_CELLS_PER_AXIS} finite numbers, got {a.size} values")
    if increasing and a.size > 1 and not np.all(np.diff(a) > 0):
        raise ArgumentError(f"map {name} must increase, got {a.tolist()!r}")
    return a
