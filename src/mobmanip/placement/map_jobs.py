"""Placement maps cut into bands of rows that run anywhere: in this process, a process pool or a
Dask cluster, with the same result.

A :class:`MapJob` describes a map by values that travel (the robot's built-in name or spec path,
the object, the objective's text, the grid). :func:`run_map` cuts the grid's rows into bands of
``rows_per_task`` rows; each band is solved on its own by
:func:`mobmanip.placement.maps.placement_map` (continuation from the row before inside the
band, fresh starts on its first row), so a band's cells do not depend on which worker solved
it, on the order the bands finish, or on a band being run twice after its worker was lost. In
this process every band goes into one call, which advances them together and batches their
cells' evaluations; the cells come out the same. The band boundaries are fixed by
``rows_per_task``: keep it to compare runs.
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, UnreachableObjectError
from ..robot.model import robot_in_process
from .maps import PlacementMap, fill_gaps, placement_map
from .optimize import PlacementProblem, check_turn

#: Rows of the grid per task by default.
ROWS_PER_TASK = 3


@dataclass(frozen=True)
class MapJob:
    """A placement map, by values a worker process can load it from.

    Attributes:
        robot: built-in robot name or spec path (absolute, for workers elsewhere).
        target: object centre (m, world).
        objective: as :func:`mobmanip.placement.place` (text, e.g. ``"kinematic:capacity:+x"``).
        x, y: the grid's platform positions (m), increasing.
        task, object_mass, decoupled: as :func:`placement_map`.
        reference: the reference configuration whose hold the hands keep, (nq,); None: the spec's hold.
        hold_turn: fixed object orientation (rad) or None (free).
        avoid_collision: self-collision margin (m) or None (not checked).
        rows_per_task: rows of the grid per band (task).
    """

    robot: str
    target: tuple[float, float, float]
    objective: str
    x: tuple[float, ...]
    y: tuple[float, ...]
    task: str | None = None
    object_mass: float | None = None
    decoupled: bool = False
    reference: tuple[float, ...] | None = None
    hold_turn: float | None = None
    avoid_collision: float | None = None
    rows_per_task: int = ROWS_PER_TASK

    def bands(self) -> list[tuple[int, int]]:
        """(first row, stop row) of each task."""
        n, k = len(self.y), self.rows_per_task
        return [(s, min(s + k, n)) for s in range(0, n, k)]


def run_band(job: MapJob, start: int, stop: int) -> tuple[int, PlacementMap | None]:
    """Rows [start, stop) of the map (a worker task): their map, or None where no cell holds the object."""
    return start, _rows(job, start, stop)


def _rows(job: MapJob, start: int, stop: int, progress=None) -> PlacementMap | None:
    """Rows [start, stop) of the map in bands of ``job.rows_per_task`` rows, solved together."""
    robot, collision, reference = _loaded(job)
    try:
        return placement_map(
            robot,
            job.target,
            job.objective,
            job.x,
            job.y[start:stop],
            job.task,
            object_mass=job.object_mass,
            decoupled=job.decoupled,
            reference=reference,
            hold_turn=job.hold_turn,
            collision=collision,
            rows_per_band=job.rows_per_task,
            fill=False,  # the whole map's gaps are filled once its bands are together
            progress=progress,
        )
    except UnreachableObjectError:
        return None


def run_map(job: MapJob, executor: cf.Executor | None = None, progress: bool = False) -> PlacementMap:
    """The whole map, its bands run in this process (``executor`` None) or on ``executor``
    (e.g. a Dask client's); the result does not depend on which.

    Raises:
        ArgumentError: ``rows_per_task`` below 1; a malformed grid (as :func:`placement_map`).
        UnreachableObjectError: no cell holds the object.
    """
    if not isinstance(job.rows_per_task, int) or job.rows_per_task < 1:
        raise ArgumentError(f"rows per task must be a positive integer, got {job.rows_per_task!r}")
    started = time.perf_counter()
    nx, ny = len(job.x), len(job.y)
    bands: dict[int, PlacementMap | None] = {}

    from tqdm import tqdm

    bar = tqdm(total=nx * ny, unit="cell", disable=not progress, desc="map", leave=False)

    def store(start: int, band: PlacementMap | None) -> None:
        bands[start] = band
        bar.update(nx * (min(start + job.rows_per_task, ny) - start))

    try:
        if executor is None:  # every band in one call: their cells' evaluations are batched together
            bands[0] = _rows(job, 0, ny, progress=bar.update)
        else:
            futures = [executor.submit(run_band, job, start, stop) for start, stop in job.bands()]
            for future in cf.as_completed(futures):
                store(*future.result())
    finally:
        bar.close()
    solved = [band for band in bands.values() if band is not None]
    if not solved:
        raise UnreachableObjectError(
            f"no platform position of the map holds the object at {list(job.target)} m "
            f"(x {job.x[0]:g}..{job.x[-1]:g} m, y {job.y[0]:g}..{job.y[-1]:g} m)"
        )
    first = solved[0]
    nq = first.configurations.shape[-1]
    values, heading, turns = np.full((ny, nx), np.nan), np.full((ny, nx), np.nan), np.full((ny, nx), np.nan)
    configurations = np.full((ny, nx, nq), np.nan)
    for start, band in bands.items():
        if band is None:
            continue
        rows = slice(start, start + len(band.y))
        values[rows], heading[rows], configurations[rows] = band.values, band.heading, band.configurations
        if band.hold_turn is not None:
            turns[rows] = band.hold_turn
    grid = PlacementMap(
        objective=first.objective,
        target=first.target,
        x=np.array(job.x, dtype=float),
        y=np.array(job.y, dtype=float),
        headings=None,
        values=values,
        heading=heading,
        configurations=configurations,
        evaluations=sum(band.evaluations for band in solved),
        seconds=time.perf_counter() - started,
        hold_turn=turns,
        task=first.task,
    )
    problem = _problem(job)
    fill_gaps(grid, problem, None if job.hold_turn is None else check_turn(job.hold_turn))
    return dataclasses.replace(grid, evaluations=grid.evaluations + problem.ev.evaluations,
                               seconds=time.perf_counter() - started)  # fmt: skip


def _loaded(job: MapJob):
    """The job's robot in this process, its self-collision check (None: not checked) and its
    reference configuration (None: the spec's hold)."""
    robot = robot_in_process(job.robot)
    collision = None
    if job.avoid_collision is not None:
        from ..robot.collision import SelfCollision

        collision = SelfCollision(robot, margin=job.avoid_collision)
    return robot, collision, None if job.reference is None else np.array(job.reference)


def _problem(job: MapJob) -> PlacementProblem:
    """The placement problem of the job's request (in this process), for filling the map's gaps."""
    robot, collision, reference = _loaded(job)
    return PlacementProblem.of_objective(robot, job.objective, job.task, np.array(job.target), None, reference,
                                         collision, object_mass=job.object_mass, decoupled=job.decoupled)  # fmt: skip
