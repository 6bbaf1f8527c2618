"""Base placement that maximises a measure's reading, on the floor or not.

:func:`mobmanip.placement.optimize.place` climbs the ellipsoids' analytic gradients. Any other
registered measure is read along a task direction (:class:`mobmanip.gradients.ReadingObjective`:
its straight-line reach or its support). A polytope's reading, and above all a grounded one (the
floor constraint's contacts in the linear program), has no closed-form gradient: it is the value
of a linear program whose data move with the configuration, piecewise smooth, with kinks where
the binding rows change. :func:`place_polytope` therefore works in stages:

1. the ellipsoid's capacity along the same direction (the kinematic ellipsoid for a velocity
   set, the dynamic one for an acceleration set; for a measure of another quantity, such as
   force, the kinematic ellipsoid's volume), without the floor, by
   :func:`~mobmanip.placement.optimize.place` (its gradients, its starts): the *ungrounded
   optimum*;
2. the polytope's reading (with the constraints, e.g. on the floor) at the seeds: the ungrounded
   optimum and place's own starts (the reference hold at the object, the platform at evenly
   spread headings, projected onto the hold), while they take at most half the budget;
3. from the :data:`SEARCHES` best seeds, derivative-free searches (scipy's Nelder-Mead, adaptive
   to the dimension) over the placement variables z (platform pose, torso and arm joints, the
   hold's turn psi), sharing what is left of a stated budget of evaluations. Each evaluation
   takes the nearest z that holds the object (the same projection as the placement's starts)
   and computes the polytope with the constraints there; a z no projection reaches counts as
   infeasible.

The best configuration evaluated wins, so the result is never worse than the ungrounded optimum
read on the floor. The searches are local: a grid or more starts can still find better
placements far away.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import minimize

from ..analysis.single import analyze
from ..errors import ArgumentError, MobmanipError, TaskError
from ..gradients.readings import ReadingObjective
from ..measures import get_measure
from ..robot.model import Robot, platform_pose
from ..robot.tasks import get_task
from .maps import PlacementMap
from .optimize import DEFAULT_STARTS, Placement, PlacementProblem, Region, _project, check_turn, place

#: Default budget of the derivative-free stage (evaluations, each a projection and a set).
DEFAULT_BUDGET = 300
#: Derivative-free searches, from the best seeds (the budget shared among them).
SEARCHES = 2
#: The ellipsoid whose gradient gives stage 1's start, per quantity of the measure: its capacity
#: along the same direction. A quantity with no ellipsoid of its kind (the force measures, a
#: user's) starts from the hold of the largest kinematic ellipsoid (:data:`FALLBACK_SURROGATE`).
SURROGATES = {"velocity": "kinematic", "acceleration": "dynamic"}
#: Stage 1's objective for a measure whose quantity has no ellipsoid of its kind.
FALLBACK_SURROGATE = "kinematic:log_volume"

#: The objectives of this module (any registered measure's reading), under their old name.
PolytopeObjective = ReadingObjective


def surrogate(objective: ReadingObjective) -> str:
    """Stage 1's ellipsoid objective: the ellipsoid of the measure's quantity, its capacity along
    the same direction, or :data:`FALLBACK_SURROGATE`."""
    ellipsoid = SURROGATES.get(get_measure(objective.measure).quantity.name)
    if ellipsoid is None:
        return FALLBACK_SURROGATE
    return f"{ellipsoid}:capacity:" + (objective.direction_text or ",".join(repr(v) for v in objective.direction))


def polytope_value(
    robot: Robot, q: np.ndarray, objective: ReadingObjective, task, object_mass, constraints, decoupled=False
) -> float:
    """The objective's reading at ``q`` (0 when the set is empty)."""
    result = analyze(robot, q, task, object_mass=object_mass, constraints=tuple(constraints),
                     measures=(objective.measure,), decoupled=decoupled)  # fmt: skip
    return objective.read(result.measure(objective.measure))


@dataclass(frozen=True)
class PolytopePlacement:
    """The result of :func:`place_polytope`.

    Attributes:
        q: the chosen configuration, (nq,).
        objective: what was maximised.
        value: its value at ``q``.
        ungrounded: the first stage's placement (the ellipsoid's optimum, without constraints).
        ungrounded_value: the objective (with the constraints) at ``ungrounded.q``.
        hold_turn: psi at ``q`` (rad).
        residual: largest hold error at ``q`` (m or rad).
        evaluations: evaluations of the seeds and the searches (projections and polytopes).
        budget: their budget.
        seconds: wall time of both stages (s).
    """

    q: np.ndarray
    objective: ReadingObjective
    value: float
    ungrounded: Placement
    ungrounded_value: float
    hold_turn: float
    residual: float
    evaluations: int
    budget: int
    seconds: float

    @property
    def platform(self) -> tuple[float, float, float]:
        """(x m, y m, heading rad) of the platform."""
        return platform_pose(self.q)


def place_polytope(
    robot: Robot,
    target: ArrayLike,
    objective: str | ReadingObjective,
    task: str | None = None,
    *,
    constraints: tuple = (),
    object_mass: float | None = None,
    decoupled: bool = False,
    region: Region | None = None,
    reference: np.ndarray | None = None,
    starts: int = DEFAULT_STARTS,
    hold_turn: float | None = None,
    budget: int = DEFAULT_BUDGET,
    seeds: Sequence[tuple[np.ndarray, float]] = (),
) -> PolytopePlacement:
    """The placement that maximises a polytope's reading (see the module's docstring).

    Args:
        robot, target, task, object_mass, decoupled, region, reference, starts, hold_turn: as
            :func:`~mobmanip.placement.optimize.place`.
        objective: ``POLYTOPE:READING:DIRECTION``, e.g. ``"dynamic_polytope:reach:+x"``.
        constraints: the analysis's constraints (e.g. ``(Floor(mu=0.5),)``: the grounded reading).
        budget: evaluations of the derivative-free stage (>= 1).
        seeds: more seeds of stage 2, each (configuration (nq,), hold turn psi), e.g. the best
            cells of :func:`reading_map`: the result is at least as good as each of them.

    Raises:
        ArgumentError, MeasureError: a malformed objective or budget.
        UnreachableObjectError: no pose holds the object at ``target``.
    """
    started = time.perf_counter()
    task = get_task(task or robot.spec.default_task)
    if not isinstance(objective, ReadingObjective):
        objective = ReadingObjective.parse(objective, task)
    if isinstance(budget, bool) or not isinstance(budget, int) or budget < 1:
        raise ArgumentError(f"the search's budget must be a positive number of evaluations, got {budget!r}")
    first = place(robot, target, surrogate(objective), task.name, object_mass=object_mass, decoupled=decoupled,
                  region=region, reference=reference, starts=starts, hold_turn=hold_turn)  # fmt: skip
    problem = PlacementProblem.of_objective(
        robot, surrogate(objective), task, first.target, region, reference, object_mass=object_mass, decoupled=decoupled
    )
    bounds = problem.bounds()
    if hold_turn is not None:
        turn = check_turn(hold_turn)
        bounds[-1] = (turn, turn)

    def value_at(q: np.ndarray) -> float:
        try:
            return polytope_value(robot, q, objective, task.name, object_mass, constraints, decoupled)
        except MobmanipError:  # e.g. the floor cannot hold the robot still there
            return 0.0

    z0 = problem.variables(first.q, first.hold_turn)
    start_value = value_at(first.q)
    best: dict = {"value": start_value, "z": z0}
    count = [0]

    def evaluate(z: np.ndarray) -> tuple[float, np.ndarray | None]:
        """The reading at the nearest z that holds the object (-inf where none does)."""
        count[0] += 1
        held = _project(problem, z, bounds)
        if held is None:
            return -math.inf, None
        value = value_at(problem.configuration(held))
        if value > best["value"]:
            best["value"], best["z"] = value, held
        return value, held

    def cost(z: np.ndarray) -> float:
        value = evaluate(z)[0]
        return 1e6 if value == -math.inf else -value

    # the seeds: the ungrounded optimum, the caller's and place's own starts (projected), best first
    given = list(seeds)
    seeds = [(start_value, z0)]
    for q_seed, psi in given:
        z_seed = problem.variables(robot.check_configuration(q_seed), psi)
        count[0] += 1
        value = value_at(problem.configuration(z_seed))
        if value > best["value"]:
            best["value"], best["z"] = value, z_seed
        seeds.append((value, z_seed))
    rng = np.random.default_rng(0)
    for s in range(starts):
        if count[0] >= budget // 2:
            break
        z = problem.start(2.0 * math.pi * s / starts, rng)
        if hold_turn is not None:
            z[-1] = bounds[-1][0]
        value, held = evaluate(z)
        if held is not None:
            seeds.append((value, held))
    seeds.sort(key=lambda seed: -seed[0])
    lower = np.array([-np.inf if lo is None else lo for lo, _ in bounds])
    upper = np.array([np.inf if hi is None else hi for _, hi in bounds])
    steps = np.full(problem.n, 0.1)
    steps[:2] = 0.05
    for k, (_, z_seed) in enumerate(seeds[:SEARCHES]):
        left = budget - count[0]
        share = left // (min(SEARCHES, len(seeds)) - k)
        if share < problem.n + 2:
            break
        simplex = np.clip(np.vstack([z_seed, z_seed + np.diag(steps)]), lower, upper)
        minimize(cost, z_seed, method="Nelder-Mead", bounds=list(zip(lower, upper)),
                 options={"maxfev": share, "initial_simplex": simplex, "adaptive": True, "xatol": 1e-6,
                          "fatol": 1e-9})  # fmt: skip
    value, z = float(best["value"]), np.asarray(best["z"])
    return PolytopePlacement(
        q=problem.configuration(z), objective=objective, value=float(value), ungrounded=first,
        ungrounded_value=float(start_value), hold_turn=float(z[-1]), residual=problem.residual(z),
        evaluations=count[0], budget=budget, seconds=time.perf_counter() - started,
    )  # fmt: skip


def reading_map(
    grid: PlacementMap,
    robot: Robot,
    objective: str | ReadingObjective,
    *,
    constraints: tuple = (),
    object_mass: float | None = None,
    decoupled: bool = False,
) -> PlacementMap:
    """A measure's reading over a placement map of its surrogate: at each cell, the reading (with
    ``constraints``) at the hold the map found best for the surrogate ellipsoid there (stage 1 and
    2 of :func:`place_polytope`, cell by cell).

    Each cell's value is therefore the reading at one hold, a lower bound of the best the reading
    itself could reach from that platform position; NaN where the cell holds no object or the
    set has no reading there (e.g. the floor cannot hold the robot still). Its best cells are
    seeds for :func:`place_polytope`, which then ends at least as high.

    Args:
        grid: the surrogate's map (:func:`mobmanip.placement.maps.placement_map` of
            :func:`surrogate` of the objective), on the objective's task.
        robot, object_mass, decoupled: as the map's.
        objective: the reading, e.g. ``"dynamic_polytope:reach:+x"``.
        constraints: what the reading's sets honour (the floor, a user's constraint).
    """
    started = time.perf_counter()
    task = get_task(grid.task or robot.spec.default_task)
    if not isinstance(objective, ReadingObjective):
        objective = ReadingObjective.parse(objective, task)
    values = np.full(grid.values.shape, np.nan)
    for index in zip(*np.nonzero(np.isfinite(grid.values))):
        try:
            value = polytope_value(robot, grid.configurations[index], objective, task.name, object_mass, constraints,
                                   decoupled)  # fmt: skip
        except MobmanipError:  # e.g. the floor cannot hold the robot still there
            continue
        if math.isfinite(value):
            values[index] = value
    if not np.isfinite(values).any():
        raise TaskError(f"no cell of the map has a reading of {objective.name} (every set failed there)")
    evaluations = int(np.isfinite(grid.values).sum())
    return dataclasses.replace(grid, objective=objective, values=values, evaluations=grid.evaluations + evaluations,
                               seconds=grid.seconds + time.perf_counter() - started)  # fmt: skip
