"""A team's heading sweep run anywhere: in this process, a process pool or a Dask cluster, with
the same result.

The headings of a sweep are not independent: each heading's inverse kinematics starts from the
joints solved at its neighbour (see :func:`mobmanip.team.sweep.walk_headings`), which keeps the
postures continuous, and cannot be cut into independent pieces without changing the sweep. But
once a heading's joints are solved, the rest of its point (the measures, their reach, load
sharing: most of the work with polytopes) depends on nothing else. So this process walks the
headings in the sweep's order solving only the inverse kinematics, and hands each reachable
heading with its solved joints to the executor in tasks of ``headings_per_task`` headings; a
task builds the team with those joints in place (no inverse kinematics) and analyses it. A
task's points depend on nothing but its headings and joints, not on which worker ran it, the
order tasks finish, or a task being run twice after its worker was lost; the sweep equals
:func:`mobmanip.team.sweep.sweep_heading` bit for bit (given the same NumPy and BLAS, see
:mod:`mobmanip.support.cluster`). The walk bounds the speed-up: about the serial sweep's time
spent in inverse kinematics.

A :class:`HeadingJob` travels by values: the parsed team description, the absolute folder its
robots' spec paths are relative to (built-in robots by name), the offsets and the measures'
names. Tasks are handed out while the walk goes on, so the workers start on the first headings
while this process solves the next ones.
"""

from __future__ import annotations

import concurrent.futures as cf
from collections.abc import Mapping
from dataclasses import dataclass, field

from ..errors import ArgumentError
from ..support.progress import progress_bar
from .members import team_from_dict
from .sweep import (
    HeadingPoint,
    TeamSweep,
    checked_offsets,
    measure_names,
    point_with_joints,
    solve_heading,
    sweep_heading,
    unreachable,
    walk_headings,
)

__all__ = ["HEADINGS_PER_TASK", "HeadingJob", "run_heading_sweep", "run_headings"]

#: Headings per task by default.
HEADINGS_PER_TASK = 4


@dataclass(frozen=True)
class HeadingJob:
    """A team's heading sweep, by values a worker process can rebuild the team from.

    Attributes:
        description: the parsed team description (see :mod:`mobmanip.team`); robots by built-in
            name or spec path.
        offsets: the heading changes (deg), added to the object's ``yaw_deg``.
        base_dir: the folder relative robot spec paths are found in (absolute, for workers
            elsewhere).
        measures: the measures' names, in order (None: the default ones).
        where: the description's name in messages.
        headings_per_task: headings per task handed to the executor.
        constraints: constraints beyond the joint boxes (e.g. the floor), as :func:`analyze_team`'s.
    """

    description: Mapping = field(hash=False)
    offsets: tuple[float, ...]
    base_dir: str
    measures: tuple[str, ...] | None = None
    where: str = "team"
    headings_per_task: int = HEADINGS_PER_TASK
    constraints: tuple = ()


def run_headings(job: HeadingJob, items: tuple[tuple[int, dict], ...]) -> list[tuple[int, HeadingPoint]]:
    """A worker task: the points at reachable headings ``items`` (index into ``job.offsets``, the
    grasping arms' joints solved there: robot name -> joint -> value), with their indices."""
    names = measure_names(job.measures)
    data, base_dir, where = job.description, job.base_dir, job.where
    return [
        (k, point_with_joints(data, job.offsets[k], joints, base_dir, names, where, tuple(job.constraints)))
        for k, joints in items
    ]


def run_heading_sweep(job: HeadingJob, executor: cf.Executor | None = None, progress: bool = False) -> TeamSweep:
    """The whole sweep, in this process (``executor`` None: :func:`sweep_heading`) or with its
    headings analysed on ``executor`` (e.g. a Dask client's); the result does not depend on which.

    Args:
        job: the sweep.
        executor: where the headings are analysed; None for this process.
        progress: show a progress bar over the finished headings on standard error.

    Raises:
        ArgumentError: ``headings_per_task`` below 1; no offsets, or a non-finite one.
        TeamError: the description is wrong (checked at its own heading first).
    """
    if isinstance(job.headings_per_task, bool) or not isinstance(job.headings_per_task, int):
        raise ArgumentError(f"headings per task must be a positive integer, got {job.headings_per_task!r}")
    if job.headings_per_task < 1:
        raise ArgumentError(f"headings per task must be a positive integer, got {job.headings_per_task!r}")
    if executor is None:
        return sweep_heading(job.description, job.offsets, base_dir=job.base_dir, measures=job.measures,
                             where=job.where, progress=progress, constraints=job.constraints)  # fmt: skip
    offsets = checked_offsets(job.offsets)
    names = measure_names(job.measures)
    job = HeadingJob(job.description, tuple(float(v) for v in offsets), job.base_dir, names, job.where,
                     job.headings_per_task, tuple(job.constraints))  # fmt: skip
    task = team_from_dict(job.description, job.base_dir, where=job.where).task  # the description must hold
    points: dict[int, HeadingPoint] = {}
    pending: set[cf.Future] = set()
    batch: list[tuple[int, dict]] = []
    with progress_bar(len(offsets), desc="team headings", unit="heading", show=progress) as bar:

        def collect(futures) -> None:
            for future in futures:
                pending.discard(future)
                done = future.result()
                points.update(done)
                bar.update(len(done))

        def submit() -> None:
            pending.add(executor.submit(run_headings, job, tuple(batch)))
            batch.clear()
            collect([f for f in pending if f.done()])

        def visit(k: int, seed: dict | None) -> dict | None:
            solved = solve_heading(job.description, offsets[k], seed, job.base_dir, job.where)[1]
            if solved is None:
                points[k] = unreachable(offsets[k])
                bar.update(1)
            else:
                batch.append((k, solved))
                if len(batch) == job.headings_per_task:
                    submit()
            return solved

        try:
            walk_headings(offsets, visit)
            if batch:
                submit()
            collect(cf.as_completed(list(pending)))
        finally:
            for future in pending:
                future.cancel()
    return TeamSweep(task, names, tuple(points[k] for k in range(len(offsets))))
