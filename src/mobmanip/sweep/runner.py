"""Sweeps: the measures' indices over object direction, distance, platform heading and limits.

A sweep places the object at direction ``angle`` (deg, from the platform heading, 0 in front,
90 to the left) and horizontal ``distance`` (m) from the arms' reference point, turns the
platform to ``heading`` (deg), and scales the wheels' velocity and effort limits; at every grid
point it records, for each measure swept (by default the kinematic and the dynamic ellipsoid;
any measure of :mod:`mobmanip.measures` with a batch form), the volume, the isotropy, the
directional capacity (how far the set reaches along a direction: ``max d . p`` over it, for a
unit d), the straight-line reach along d (the largest s >= 0 with s d in the set: how far
exactly along d from rest; at most the capacity, smaller when gravity shifts the set or the set's
farthest point along d is off the ray), the empty and degenerate flags and the measure's per-axis
arrays (the ellipsoids' semi-axes, the polytopes' widths). Both directional indices are NaN where
the set is empty.

The arms' postures depend on (angle, distance) only; they are found once, in the calling
process, before the grid's configurations are analysed. Two providers (``SweepSpec.postures``):

``planar`` -- the paper's closed form (:mod:`mobmanip.postures.planar`), for robots with two
3-joint planar arms with vertical axes sharing their first joint (like ``planar_dual_arm``; the
reference point is that joint, P_o): each arm takes its most manipulable posture at the reach,
arm 2 the mirror image of arm 1, both pointed at the object and holding it at its centre.
Distances beyond the reach of the arms are unreachable.

``ik`` -- any robot: inverse kinematics holds the object as a reference posture (by default
the spec's ``[hold]`` posture, else its home configuration) does, turned towards the object's direction, with the object
centre at the given distance from the horizontal centroid of the arms' first joints and at the
reference posture's height; :mod:`mobmanip.postures.inverse_kinematics` defines this precisely. Grid points where
some end effector cannot be brought within :data:`mobmanip.postures.inverse_kinematics.POSITION_TOLERANCE` of its
target are unreachable.

``auto`` (the default) takes ``planar`` where it applies and no reference posture is given,
else ``ik``. Unreachable grid points hold NaN indices; a grid with no reachable point at all is
an error (:class:`UnreachableGridError`).

Execution: the grid's configurations are cut into chunks that run through any
:class:`concurrent.futures.Executor` (a local process pool by default; a ``dask.distributed``
client's ``get_executor()`` runs the same sweep across machines). Each worker loads the robot
itself from the spec name or path; only small arrays travel. Results do not depend on the
executor or the number of workers: chunk boundaries are fixed by ``chunk_size``.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import math
import multiprocessing
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..batch import BatchSetup, check_configurations, default_chunk, iter_terms, warm_kernel
from ..errors import ArgumentError, GridError, MobmanipError, SpecError, UnreachableGridError
from ..measures import POLYTOPE_KINDS, BatchRequest, Measure, evaluate_batch, get_measure, resolve_measures
from ..postures.inverse_kinematics import POSITION_TOLERANCE, IKPostureTable, reference_configuration, solve_postures
from ..postures.planar import (
    PlanarArm,
    PostureTable,
    ReachPosture,
    planar_arm,
    posture_at_reach,
    posture_table,
    postures_at_reaches,
)
from ..robot.model import Robot
from ..robot.tasks import get_task
from ..sets.taskset import TaskSetBatch
from .budget import MAX_GRID_POINTS, check_grid, check_scaled_limits, exit_with_parent
from .results import FLAGS, SCALAR_INDICES, SweepResult, check_index_name, index_names
from .spec import AXES, POSTURE_METHODS, SweepGrid, SweepSpec, parse_grid

_log = logging.getLogger(__name__)

__all__ = [
    "AXES",
    "FLAGS",
    "POSTURE_METHODS",
    "SCALAR_INDICES",
    "GridError",
    "PlanarArm",
    "PostureTable",
    "ReachPosture",
    "SweepGrid",
    "SweepResult",
    "SweepSpec",
    "UnreachableGridError",
    "check_index_name",
    "default_workers",
    "index_names",
    "parse_grid",
    "planar_arm",
    "posture_at_reach",
    "posture_table",
    "postures_at_reaches",
    "run_sweep",
    "sweep_configurations",
    "sweep_postures",
]


@dataclass(frozen=True)
class _PostureRows:
    """Inverse-kinematics postures of consecutive (angle, distance) pairs, for one chunk.

    Attributes:
        first: flat index (angle * D + distance) of the first row.
        joints: arm joint positions, (rows, n); NaN where unreachable.
        reachable: (rows,).
        joint_names: the arm joints.
    """

    first: int
    joints: np.ndarray
    reachable: np.ndarray
    joint_names: tuple[str, ...]


def _posture_rows(table: IKPostureTable, first: int = 0, stop: int | None = None) -> _PostureRows:
    n = table.joints.shape[-1]
    joints = table.joints.reshape(-1, n)[first:stop]
    return _PostureRows(first, joints, table.reachable.reshape(-1)[first:stop], table.joint_names)


def sweep_postures(
    robot: Robot,
    grid: SweepGrid,
    method: str = "auto",
    reference: Mapping[str, float] | None = None,
    map_fn: Callable = map,
) -> PostureTable | IKPostureTable:
    """The arms' postures for a grid (see the module's docstring for the methods).

    Args:
        robot: the robot.
        grid: the grid (only its angles and distances matter).
        method: ``"auto"``, ``"planar"`` or ``"ik"``.
        reference: joint positions by name for the inverse kinematics' reference posture
            (joints not named stay at home); ``None``: the spec's hold posture
            (:meth:`mobmanip.robot.model.Robot.hold_configuration`).
        map_fn: runs the planar posture search on slices of the distances (an executor's
            ``map`` spreads it over workers); the result does not depend on it.

    Raises:
        SpecError: ``"planar"`` on a robot without two planar 3-joint arms sharing their base.
        ArgumentError: an unknown method, or a reference posture with ``"planar"``.
        JointNotFoundError, ConfigurationError: a bad reference posture.
    """
    if method not in POSTURE_METHODS:
        raise ArgumentError(f"postures must be one of {', '.join(POSTURE_METHODS)}, got {method!r}")
    if method == "planar" and reference is not None:
        raise ArgumentError(
            "the planar postures follow the paper's closed form; a reference posture needs postures 'ik'"
        )
    if method != "ik" and reference is None:
        try:
            return posture_table(robot, grid.distance, map_fn)
        except SpecError:
            if method == "planar":
                raise
    q_ref = robot.hold_configuration() if reference is None else reference_configuration(robot, reference)
    return solve_postures(robot, grid.angle_deg, grid.distance, q_ref)


def sweep_configurations(
    robot: Robot, grid: SweepGrid, table: PostureTable | IKPostureTable | _PostureRows, flat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Configurations at flat indices into (angle, distance, heading), and which are reachable.

    Unreachable rows get the home posture (finite, but not meaningful).
    """
    ia, idist, ih = np.unravel_index(flat, grid.shape[:3])
    n = len(flat)
    qs = np.repeat(robot.neutral()[None, :], n, axis=0)
    heading = np.radians(grid.heading_deg[ih])
    qs[:, 0:2] = 0.0
    qs[:, 2], qs[:, 3] = np.cos(heading), np.sin(heading)
    if isinstance(table, PostureTable):
        values, reachable = table.joint_values(np.radians(grid.angle_deg[ia]), idist)
        names = tuple(name for arm in robot.arms for name in arm.joint_names)
        rows = np.arange(n)
    else:
        chunk = _posture_rows(table) if isinstance(table, IKPostureTable) else table
        pair = ia * grid.shape[1] + idist - chunk.first
        reachable = chunk.reachable[pair]
        rows = np.flatnonzero(reachable)
        values, names = chunk.joints[pair[rows]], chunk.joint_names
    model = robot.model
    for name, value in zip(names, values.T):
        joint = model.joints[model.getJointId(name)]
        if joint.nq == 2:
            qs[rows, joint.idx_q], qs[rows, joint.idx_q + 1] = np.cos(value), np.sin(value)
        else:
            qs[rows, joint.idx_q] = value
    return qs, reachable


# ----------------------------------------------------------------------------------------------
# the job and its chunks


@dataclass(frozen=True)
class _Job:
    spec: SweepSpec
    grid: SweepGrid
    table: PostureTable | _PostureRows  # the planar table, or the chunk's own rows of an IK table
    start: int
    stop: int
    chunk_size: int


_WORKER_CACHE: dict = {}


def _worker_setup(spec: SweepSpec):
    """The robot and batch setup for a spec, loaded once per process."""
    key = spec
    if key not in _WORKER_CACHE:
        robot = spec.load()
        _WORKER_CACHE.clear()
        _WORKER_CACHE[key] = (robot, BatchSetup(robot, spec.task, spec.object_mass))
    return _WORKER_CACHE[key]


def _wheel_limits(robot: Robot, base: np.ndarray, scales: np.ndarray) -> list[np.ndarray]:
    """Limit vectors with the drive wheels' entries scaled (unchanged with a locked platform)."""
    drives = [k for k, name in enumerate(robot.platform.reduced_names) if name in robot.platform.drive_names]
    out = []
    for s in scales:
        limits = np.array(base, dtype=float)
        limits[drives] *= s
        out.append(limits)
    return out


def _directions(spec: SweepSpec, m: int, alpha_world: np.ndarray) -> np.ndarray:
    """Unit capacity directions per configuration, (n, m)."""
    d = np.zeros((len(alpha_world), m))
    if isinstance(spec.direction, str):
        phi = alpha_world + (math.pi / 2 if spec.direction == "tangential" else 0.0)
        d[:, 0], d[:, 1] = np.cos(phi), np.sin(phi)
    else:
        d[:] = np.asarray(spec.direction, dtype=float) / np.linalg.norm(spec.direction)
    return d


def _record(e: TaskSetBatch, measure: Measure, directions: np.ndarray, rows: np.ndarray, out: dict, col: int):
    """Store one measure's indices of a chunk's rows at limit column ``col``."""
    prefix = measure.name
    out[f"{prefix}_volume"][rows, col] = e.volume
    out[f"{prefix}_isotropy"][rows, col] = e.isotropy
    capacity = e.support(directions)
    out[f"{prefix}_capacity"][rows, col] = np.where(e.empty, np.nan, capacity)
    reach = getattr(e, "straight_line_reach", None)  # NaN for a batch form without it (a user's)
    if reach is not None:
        out[f"{prefix}_straight_line_reach"][rows, col] = np.where(e.empty, np.nan, reach(directions))
    for attribute, _ in measure.axis_indices:
        out[f"{prefix}_{attribute}"][rows, col] = getattr(e, attribute)
    out[f"{prefix}_degenerate"][rows, col] = e.degenerate
    out[f"{prefix}_empty"][rows, col] = e.empty


def _empty_chunk(n: int, nv: int, ne: int, m: int, measures: tuple[Measure, ...]) -> dict:
    """NaN-filled (False for flags) result arrays of a chunk of n configurations: per measure,
    one column per value of its limit scale (nv velocity, ne effort scales)."""
    out = {"reachable": np.zeros(n, dtype=bool)}
    for measure in measures:
        prefix, count = measure.name, nv if measure.quantity.limits == "velocity" else ne
        for name in SCALAR_INDICES:
            out[f"{prefix}_{name}"] = np.full((n, count), np.nan)
        for attribute, _ in measure.axis_indices:
            out[f"{prefix}_{attribute}"] = np.full((n, count, m), np.nan)
        for flag in FLAGS:
            out[f"{prefix}_{flag}"] = np.zeros((n, count), dtype=bool)
    return out


def _run_job(job: _Job) -> tuple[int, dict]:
    """One chunk of a sweep: its configurations' indices at every limit scale (a worker task)."""
    robot, setup = _worker_setup(job.spec)
    grid = job.grid
    flat = np.arange(job.start, job.stop)
    qs, reachable = sweep_configurations(robot, grid, job.table, flat)
    nv, ne, m = len(grid.wheel_velocity_scale), len(grid.wheel_effort_scale), setup.m
    measures = resolve_measures(job.spec.measures, sweep=True)
    out = _empty_chunk(len(flat), nv, ne, m, measures)
    out["reachable"][:] = reachable
    rows = np.flatnonzero(reachable)
    if rows.size == 0:
        return job.start, out
    qs = check_configurations(robot, qs[rows])
    ia, _, ih = np.unravel_index(flat[rows], grid.shape[:3])
    alpha_world = np.radians(grid.angle_deg[ia] + grid.heading_deg[ih])
    directions = _directions(job.spec, m, alpha_world)
    vlims = _wheel_limits(robot, robot.velocity_limits, grid.wheel_velocity_scale)
    elims = _wheel_limits(robot, robot.effort_limits, grid.wheel_effort_scale)
    for start, t in iter_terms(setup, qs, min(job.chunk_size, default_chunk())):
        n = t.n
        sub = rows[start : start + n]
        dirs = directions[start : start + n]
        # one pass per scale, every measure that still has a scale left at once (measures that
        # share a batch form, like the two ellipsoids, in one call)
        for col in range(max(len(vlims), len(elims))):
            limits = {}
            for measure in measures:
                by_scale = vlims if measure.quantity.limits == "velocity" else elims
                if col < len(by_scale):
                    limits[measure.name] = by_scale[col]
            request = BatchRequest(
                setup, t, limits, job.spec.decoupled, qs[start : start + n], job.spec.constraints
            )  # fmt: skip
            results = evaluate_batch(request)
            for measure in measures:
                if measure.name in limits:
                    _record(results[measure.name], measure, dirs, sub, out, col)
    return job.start, out


# ----------------------------------------------------------------------------------------------
# running


def default_workers() -> int:
    """Worker processes by default: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def _local_pool(workers: int, mp_context: str | None) -> cf.ProcessPoolExecutor:
    """A process pool. By default "fork" where the platform has it (no ``__main__`` guard needed
    in user scripts; the workers still load the robot themselves: the parent never fills their
    cache), else "spawn"."""
    if mp_context is None:
        mp_context = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    return cf.ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context(mp_context),
        initializer=exit_with_parent,  # no orphaned workers when this process is killed
        initargs=(os.getpid(),),
    )


def run_sweep(
    spec: SweepSpec,
    grid: SweepGrid,
    *,
    executor: cf.Executor | None = None,
    workers: int | None = None,
    chunk_size: int = 4096,
    progress: bool = False,
    mp_context: str | None = None,
    max_points: int | None = MAX_GRID_POINTS,
) -> SweepResult:
    """Run a sweep, serially, on local processes, or on any ``concurrent.futures.Executor``.

    Args:
        spec: what to sweep (robot by name or spec path, task, platform, limits...).
        grid: the grid.
        executor: run the chunks here, e.g. ``dask.distributed.Client(...).get_executor()``;
            the caller owns it. Without one: a local process pool of ``workers`` processes, or
            in this process when ``workers == 1``.
        workers: local worker processes (default: the usable cores).
        chunk_size: configurations per task; memory per task is proportional to it, and the
            results do not depend on it only up to rounding (keep it fixed to compare runs).
        progress: show a tqdm progress bar on standard error.
        mp_context: start method of the local pool ("fork", "spawn", "forkserver"); default
            "fork" where available. With "spawn"/"forkserver", scripts need the usual
            ``if __name__ == "__main__":`` guard.
        max_points: the largest grid (points) to run; ``None``: any that fits in memory.

    Raises:
        SpecError: ``postures="planar"`` on a robot without planar 3-joint arms sharing their base.
        UnknownMeasureError, MeasureError: an unknown measure, or one without a batch form.
        UnreachableGridError: the arms reach no grid point.
        GridError, ArgumentError: bad grid or settings.
    """
    if not isinstance(chunk_size, int) or chunk_size < 1:
        raise ArgumentError(f"chunk size must be a positive integer, got {chunk_size!r}")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ArgumentError(f"workers must be a positive integer, got {workers!r}")
    check_grid(grid.shape, max_points)  # before anything is allocated
    robot = spec.load()
    check_scaled_limits(robot, grid)
    task = get_task(spec.task or robot.spec.default_task)
    measures = tuple(measure.name for measure in resolve_measures(spec.measures, sweep=True))
    spec = replace(spec, task=task.name, direction=_check_direction(spec.direction, task.dim), measures=measures)
    BatchSetup(robot, task.name, spec.object_mass)  # validate the object mass here, once
    if executor is None and any(get_measure(name).set_kind == "ellipsoid" for name in measures):
        # compile (or load) the kernel here, once: before the progress bar counts throughput and
        # before local workers fork from this process (they inherit it)
        warm_kernel(robot, task.name, spec.object_mass)
    if executor is None and any(name in POLYTOPE_KINDS for name in measures):
        from ..sets.capacity_batch import warm_kernels

        warm_kernels(task.dim)  # the compiled polytope batch, likewise
    n_workers = workers or default_workers()
    _log.info(
        "sweep of %s: %d grid points, measures %s, %d worker(s)",
        robot.name,
        math.prod(grid.shape),
        ", ".join(measures),
        1 if executor is None and n_workers == 1 else n_workers,
    )
    with contextlib.ExitStack() as stack:
        if executor is None and n_workers > 1:
            executor = stack.enter_context(_local_pool(n_workers, mp_context))
            window = 4 * n_workers
        else:
            window = 64
        return _run_sweep(spec, grid, robot, task, executor, window, chunk_size, progress)


def _run_sweep(spec, grid, robot, task, executor, window, chunk_size, progress) -> SweepResult:
    """run_sweep with its arguments checked: in this process (``executor`` None) or on one."""
    reference = None if spec.reference is None else dict(spec.reference)
    table = sweep_postures(robot, grid, spec.postures, reference, map if executor is None else executor.map)
    if not np.any(table.reachable):
        raise UnreachableGridError(_unreachable_message(robot, grid, table))
    if isinstance(table, PostureTable):
        _check_postures(robot, grid, table)
    else:
        _check_ik_postures(robot, grid, table)
    n = grid.n_configurations
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    jobs = [_Job(spec, grid, _chunk_table(grid, table, s, e), s, e, chunk_size) for s, e in bounds]
    nv, ne, m = len(grid.wheel_velocity_scale), len(grid.wheel_effort_scale), task.dim
    merged = _empty_chunk(n, nv, ne, m, resolve_measures(spec.measures, sweep=True))

    from tqdm import tqdm

    bar = tqdm(total=n, unit="cfg", disable=not progress, desc=f"sweep {robot.name}", leave=False)

    def store(start: int, out: dict) -> None:
        stop = start + len(out["reachable"])
        for key, value in out.items():
            merged[key][start:stop] = value
        bar.update(stop - start)

    try:
        if executor is None:
            for job in jobs:
                store(*_run_job(job))
        else:
            _drain(executor, jobs, store, window=window)
    finally:
        bar.close()
    return _assemble(spec, grid, task, merged, table)


def _drain(executor: cf.Executor, jobs: list, store, window: int) -> None:
    """Submit jobs with at most ``window`` in flight (bounded memory), store results as they come."""
    pending = set()
    queue = iter(jobs)
    for job in queue:
        pending.add(executor.submit(_run_job, job))
        if len(pending) >= window:
            done, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for future in done:
                store(*future.result())
    for future in cf.as_completed(pending):
        store(*future.result())


def _check_direction(direction, m: int):
    if isinstance(direction, str):
        if direction not in ("radial", "tangential"):
            raise ArgumentError(f"direction must be 'radial', 'tangential' or {m} numbers, got {direction!r}")
        return direction
    try:
        values = tuple(float(v) for v in direction)
    except (TypeError, ValueError):
        raise ArgumentError(f"direction must be 'radial', 'tangential' or {m} numbers, got {direction!r}") from None
    if len(values) != m or not all(math.isfinite(v) for v in values) or not any(values):
        raise ArgumentError(f"direction must have {m} finite numbers, not all zero, got {list(values)}")
    return values


def _check_postures(robot: Robot, grid: SweepGrid, table: PostureTable) -> None:
    """Both end effectors at the object for one configuration per reachable distance (FK check)."""
    model, data = robot.model, robot.data
    for i in np.flatnonzero(table.reachable):
        flat = np.ravel_multi_index((0, i, 0), grid.shape[:3])
        q = sweep_configurations(robot, grid, table, np.array([flat]))[0][0]
        pin.framesForwardKinematics(model, data, q)
        heading = math.radians(grid.angle_deg[0] + grid.heading_deg[0])
        target = grid.distance[i] * np.array([math.cos(heading), math.sin(heading)])
        for arm in robot.arms:
            base = data.oMi[model.getJointId(arm.joint_names[0])].translation[:2]
            tip = data.oMf[arm.frame_id].translation[:2]
            if np.max(np.abs(tip - base - target)) > 1e-9 * max(1.0, grid.distance[i]):
                raise MobmanipError(
                    f"posture check failed: {arm.end_effector} misses the object at distance {grid.distance[i]:g} m"
                )


def _chunk_table(grid: SweepGrid, table, start: int, stop: int):
    """What a chunk of flat configuration indices [start, stop) needs of the posture table."""
    if isinstance(table, PostureTable):
        return table
    h = grid.shape[2]
    return _posture_rows(table, start // h, (stop - 1) // h + 1)


def _check_ik_postures(robot: Robot, grid: SweepGrid, table: IKPostureTable) -> None:
    """Every end effector at its target, at the first heading, for every reachable (angle, distance)."""
    model, data = robot.model, robot.data
    d, h = grid.shape[1:3]
    pairs = np.flatnonzero(table.reachable.reshape(-1))
    qs, _ = sweep_configurations(robot, grid, table, pairs * h)
    alpha = np.radians(grid.angle_deg[pairs // d])
    targets, _ = table.hold.targets(alpha, grid.distance[pairs % d], alpha)
    yaw = math.radians(grid.heading_deg[0])
    turn = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    for q, target in zip(qs, targets @ turn.T):
        pin.framesForwardKinematics(model, data, q)
        for arm, point in zip(robot.arms, target):
            miss = float(np.linalg.norm(data.oMf[arm.frame_id].translation - point))
            if miss > POSITION_TOLERANCE + 1e-12:
                raise MobmanipError(f"posture check failed: {arm.end_effector} misses its target by {miss:.3g} m")


def _span(values: np.ndarray, unit: str) -> str:
    values = np.unique(values)
    if len(values) <= 4:
        return ", ".join(f"{v:g}" for v in values) + f" {unit}"
    return f"{values[0]:g} .. {values[-1]:g} {unit} ({len(values)} values)"


def _unreachable_message(robot: Robot, grid: SweepGrid, table) -> str:
    if isinstance(table, PostureTable):
        reach = min(planar_arm(robot, i).max_reach for i in range(len(robot.arms)))
        return (
            f"{robot.name}: no grid distance is within the arms' reach: distance {_span(grid.distance, 'm')} "
            f"from their first joint, and they reach {reach:g} m at most"
        )
    hold = table.hold
    held = ""
    if len(robot.arms) > 1:
        width = float(np.max(np.linalg.norm(hold.offsets[:, None] - hold.offsets[None], axis=2)))
        held = f", hands {width:.3g} m apart"
    return (
        f"{robot.name}: the arms reach none of the grid's points: distance {_span(grid.distance, 'm')}, "
        f"angle {_span(grid.angle_deg, 'deg')}, from the reference point ({hold.origin[0]:.3g}, "
        f"{hold.origin[1]:.3g}) m, holding the object as the reference posture does (at height "
        f"{hold.height:.3g} m{held}); the inverse kinematics came within {np.min(table.position_error):.3g} m "
        "at best; try other distances or another reference posture"
    )


def _assemble(
    spec: SweepSpec, grid: SweepGrid, task, merged: dict, table: PostureTable | IKPostureTable
) -> SweepResult:
    a, d, h, nv, ne = grid.shape
    indices = {}
    for measure in resolve_measures(spec.measures, sweep=True):
        velocity = measure.quantity.limits == "velocity"
        count = nv if velocity else ne
        keys = [f"{measure.name}_{name}" for name in SCALAR_INDICES]
        keys += [f"{measure.name}_{attribute}" for attribute, _ in measure.axis_indices]
        keys += [f"{measure.name}_{flag}" for flag in FLAGS]
        for key in keys:
            value = merged[key]
            tail = value.shape[2:]
            arr = value.reshape((a, d, h, count) + tail)
            if velocity:
                arr = np.broadcast_to(arr[:, :, :, :, None], (a, d, h, nv, ne) + tail)
            else:
                arr = np.broadcast_to(arr[:, :, :, None, :], (a, d, h, nv, ne) + tail)
            indices[key] = np.ascontiguousarray(arr)
    return SweepResult(
        spec=spec,
        grid=grid,
        task=task.name,
        task_axes=task.labels,
        reachable=merged["reachable"].reshape(a, d, h),
        indices=indices,
        postures=table,
    )
