"""The heaviest object over a map of object positions, and along a path: the payload program
(:func:`mobmanip.analysis.payload.payload`) at every position of a polar grid around the robot
(:func:`payload_map`), or at every sample of a motion (:func:`payload_along`).

The grid is a sweep's (:class:`mobmanip.sweep.spec.SweepGrid`): the object at an angle from the
platform's heading and a horizontal distance from the arms' reference point, the arms holding it
in the posture the sweep finds there (the paper's closed form, or inverse kinematics from the hold
posture); a position the arms cannot reach has no payload. Each reachable position is one linear
program, so a 15 x 15 map of the paper's robot takes about a second. On an executor (a Dask
client's, ``payload --map --dask``) the reachable positions go out in tasks of
:data:`CELLS_PER_TASK` configurations, each worker loading the robot once by its name or spec
path; every cell is the same program either way, so the map is the same.
"""

from __future__ import annotations

import concurrent.futures as cf
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from ..analysis.payload import checked_acceleration, payload
from ..errors import ArgumentError
from ..robot.model import Robot, robot_in_process
from ..robot.tasks import get_task
from ..terms.constraints.base import Constraint
from .runner import sweep_configurations, sweep_postures
from .spec import SweepGrid

#: What a cell of the map can be: the program's outcomes, and out of the arms' reach.
CELL_STATUSES = ("bounded", "unbounded", "infeasible", "unreachable")
#: Positions per task on an executor: each is one program of a few milliseconds, against a
#: scheduler's millisecond or so per task.
CELLS_PER_TASK = 16


@dataclass(frozen=True)
class PayloadCells:
    """Some of a map's positions, by values a worker process can load them from (a task).

    Attributes:
        robot: the robot's built-in name or spec path (absolute, for workers elsewhere).
        configurations: the configurations holding the positions, (n, nq).
        task, acceleration, constraints, static: as :func:`mobmanip.analysis.payload.payload`.
    """

    robot: str
    configurations: np.ndarray
    task: str
    acceleration: tuple[float, ...] | None
    constraints: tuple[Constraint, ...]
    static: bool


def payload_cells(cells: PayloadCells) -> list[tuple[str, float, str]]:
    """Each position's (status, mass or NaN, what stops it)."""
    robot = robot_in_process(cells.robot)
    return _cells(robot, cells.configurations, cells.task, cells.acceleration, cells.constraints, cells.static)


def _cells(robot, configurations, task, acceleration, constraints, static) -> list[tuple[str, float, str]]:
    out = []
    for q in configurations:
        found = payload(robot, q, task, acceleration=acceleration, constraints=constraints, static=static)
        if found.mass is None:  # unbounded or infeasible
            out.append((found.status, np.nan, ""))
        else:
            out.append((found.status, float(found.mass), "; ".join(found.reading)))
    return out


@dataclass(frozen=True)
class _Payloads:
    """The payload program's answers at many postures.

    Attributes:
        robot, task: what was asked.
        mass: the heaviest object at each posture (kg), NaN where there is none (see ``status``).
        status: each posture's outcome: :data:`CELL_STATUSES`.
        limit: what stops the mass at each bounded posture (the payload's reading), "" elsewhere.
        acceleration: the object's acceleration asked for (zeros: held still), (m,).
        static: whether the robot was held static too.
        constraints: the constraints, as described in JSON.
    """

    robot: str
    task: str
    mass: np.ndarray
    status: np.ndarray
    limit: np.ndarray
    acceleration: np.ndarray
    static: bool
    constraints: tuple[dict, ...]

    def _asked(self) -> dict:
        """The JSON of what was asked, and the masses (no NaN: ``null`` where there is none)."""
        bounded = self.status == "bounded"
        masses = np.empty(self.mass.shape, dtype=object)
        masses[bounded] = [float(m) for m in self.mass[bounded]]
        return {
            "robot": self.robot,
            "task": self.task,
            "acceleration": self.acceleration.tolist(),
            "static": self.static,
            "constraints": [dict(c) for c in self.constraints],
            "mass": masses.tolist(),
            "status": self.status.tolist(),
            "limit": self.limit.tolist(),
        }


@dataclass(frozen=True)
class PayloadMap(_Payloads):
    """The payload at every object position of a polar grid (see the module's docstring); its
    arrays are (A, D), one entry per angle and distance.

    Attributes:
        angle_deg: the object's directions from the platform's heading (deg), (A,).
        distance: its horizontal distances from the arms' reference point (m), (D,).
        configurations: the robot's configuration holding each position (the home posture where
            out of reach), (A, D, nq).
    """

    angle_deg: np.ndarray = field(default_factory=lambda: np.zeros(0))
    distance: np.ndarray = field(default_factory=lambda: np.zeros(0))
    configurations: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))

    def best(self) -> tuple[int, int] | None:
        """(angle index, distance index) of the heaviest bounded cell, or ``None``."""
        if not np.any(self.status == "bounded"):
            return None
        i, j = np.unravel_index(
            int(np.nanargmax(np.where(self.status == "bounded", self.mass, np.nan))), self.mass.shape
        )
        return int(i), int(j)

    def table(self) -> tuple[list[str], list[list]]:
        """One row per position: angle_deg, distance, mass (empty where none), status, limit."""
        rows = []
        for i, angle in enumerate(self.angle_deg):
            for j, distance in enumerate(self.distance):
                mass = "" if self.status[i, j] != "bounded" else repr(float(self.mass[i, j]))
                rows.append(
                    [repr(float(angle)), repr(float(distance)), mass, str(self.status[i, j]), str(self.limit[i, j])]
                )
        return ["angle_deg", "distance", "mass", "status", "limit"], rows

    def to_dict(self) -> dict:
        """JSON-ready (no NaN: a position without a payload has ``null``)."""
        best = self.best()
        return {
            **self._asked(),
            "angle_deg": self.angle_deg.tolist(),
            "distance": self.distance.tolist(),
            "best": None
            if best is None
            else {
                "angle_deg": float(self.angle_deg[best[0]]),
                "distance": float(self.distance[best[1]]),
                "mass": float(self.mass[best]),
                "limit": str(self.limit[best]),
            },  # fmt: skip
        }


def payload_map(
    robot: Robot,
    grid: SweepGrid,
    task: str | None = None,
    *,
    acceleration: Iterable[float] | None = None,
    constraints: Iterable[Constraint] = (),
    static: bool = False,
    postures: str = "auto",
    executor: cf.Executor | None = None,
    robot_source: str | None = None,
) -> PayloadMap:
    """The payload at every object position of ``grid`` (its angles and distances; one heading,
    the wheels' limits as they are).

    Args:
        robot: the loaded robot.
        grid: the positions (:class:`mobmanip.sweep.spec.SweepGrid`, its other axes single values of 1).
        task, acceleration, constraints, static: as :func:`mobmanip.analysis.payload.payload`.
        postures: how the arms hold each position, as a sweep's (``"auto"``, ``"planar"``, ``"ik"``).
        executor: run the positions' programs there (e.g. a Dask client's executor) in tasks of
            :data:`CELLS_PER_TASK`; ``None``: in this process.
        robot_source: the robot's built-in name or spec path, from which the executor's workers
            load it (required with ``executor``).

    Raises:
        ArgumentError: a grid with more than one heading or a wheel-limit scale other than 1; an
            executor without ``robot_source``.
    """
    if grid.shape[2:] != (1, 1, 1) or grid.wheel_velocity_scale[0] != 1.0 or grid.wheel_effort_scale[0] != 1.0:
        raise ArgumentError("a payload map covers object positions: one heading and the wheels' own limits")
    task_space = get_task(task or robot.spec.default_task)
    constraints = tuple(constraints)
    table = sweep_postures(robot, grid, postures)
    a_count, d_count = grid.shape[:2]
    qs, reachable = sweep_configurations(robot, grid, table, np.arange(a_count * d_count))
    mass = np.full(a_count * d_count, np.nan)
    status = np.full(a_count * d_count, "unreachable", dtype=object)
    limit = np.full(a_count * d_count, "", dtype=object)
    a = checked_acceleration(acceleration, task_space.dim, task_space.name)
    asked = tuple(float(v) for v in a)
    cells = np.flatnonzero(reachable)
    if executor is None:
        found = _cells(robot, qs[cells], task_space.name, asked, constraints, static)
    else:
        if robot_source is None:
            raise ArgumentError(
                "a payload map on an executor needs robot_source: the name or spec path its workers load"
            )
        tasks = [
            executor.submit(
                payload_cells, PayloadCells(robot_source, qs[part], task_space.name, asked, constraints, static)
            )
            for part in np.array_split(cells, max(1, -(-len(cells) // CELLS_PER_TASK)))
            if len(part)
        ]
        found = [cell for task in tasks for cell in task.result()]
    for k, (cell_status, cell_mass, cell_limit) in zip(cells, found):
        status[k], mass[k], limit[k] = cell_status, cell_mass, cell_limit
    shape = (a_count, d_count)
    return PayloadMap(
        robot=robot.name,
        task=task_space.name,
        angle_deg=grid.angle_deg.copy(),
        distance=grid.distance.copy(),
        mass=mass.reshape(shape),
        status=status.reshape(shape).astype(str),
        limit=limit.reshape(shape).astype(str),
        acceleration=a,
        static=static,
        constraints=tuple(c.describe() for c in constraints),
        configurations=qs.reshape(*shape, -1),
    )


@dataclass(frozen=True)
class PayloadAlong(_Payloads):
    """The payload at every sample of a motion's path (see :func:`payload_along`); its arrays are
    (N,), one entry per sample.

    Attributes:
        t: the samples' time stamps (s), (N,).
    """

    t: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def lightest(self) -> int | None:
        """The sample whose payload is the least among the bounded ones, or ``None``."""
        bounded = np.flatnonzero(self.status == "bounded")
        return None if not bounded.size else int(bounded[np.argmin(self.mass[bounded])])

    def table(self) -> tuple[list[str], list[list]]:
        """One row per sample: t, mass (empty where none), status, limit."""
        rows = [[repr(float(t)), "" if s != "bounded" else repr(float(m)), str(s), str(limit)]
                for t, m, s, limit in zip(self.t, self.mass, self.status, self.limit)]  # fmt: skip
        return ["t", "mass", "status", "limit"], rows

    def to_dict(self) -> dict:
        """JSON-ready (no NaN: a sample without a payload has ``null``)."""
        k = self.lightest()
        return {
            **self._asked(),
            "t": self.t.tolist(),
            "lightest": None
            if k is None
            else {
                "sample": k,
                "t": float(self.t[k]),
                "mass": float(self.mass[k]),
                "limit": str(self.limit[k]),
            },  # fmt: skip
        }


def payload_along(
    robot: Robot,
    trajectory,
    task: str | None = None,
    *,
    acceleration: Iterable[float] | None = None,
    constraints: Iterable[Constraint] = (),
    static: bool = False,
) -> PayloadAlong:
    """The payload (:func:`mobmanip.analysis.payload.payload`) at the posture of every sample of a
    motion (:class:`mobmanip.motion.trajectory.Trajectory`): the heaviest object the robot could
    hold still (or give ``acceleration``) had it stopped there. The lightest sample bounds what can
    be carried along the whole path at rest; the motion's own accelerations are not in it (the
    fastest timing of a path with its object is :func:`mobmanip.motion.retime.retime`).

    Args:
        robot: the loaded robot.
        trajectory: the motion (its configurations are used).
        task, acceleration, constraints, static: as :func:`mobmanip.analysis.payload.payload`.
    """
    task_space = get_task(task or robot.spec.default_task)
    constraints = tuple(constraints)
    a = checked_acceleration(acceleration, task_space.dim, task_space.name)
    found = _cells(robot, trajectory.q, task_space.name, tuple(float(v) for v in a), constraints, static)
    status, mass, limit = (np.array(column) for column in zip(*found))
    return PayloadAlong(
        robot=robot.name,
        task=task_space.name,
        t=np.asarray(trajectory.t, dtype=float).copy(),
        mass=mass.astype(float),
        status=status.astype(str),
        limit=limit.astype(str),
        acceleration=a,
        static=static,
        constraints=tuple(c.describe() for c in constraints),
    )
