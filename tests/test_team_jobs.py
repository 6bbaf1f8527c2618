"""A team's heading sweep run through an executor (:mod:`mobmanip.team.heading_jobs`): the same
points as the serial sweep bit for bit, whatever the executor, the task size or the order in
which tasks run; every heading analysed once; the progress bar counts finished headings."""

from __future__ import annotations

import concurrent.futures as cf
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mobmanip.errors import ArgumentError, TeamError
from mobmanip.team import heading_jobs
from mobmanip.team.heading_jobs import HeadingJob, run_heading_sweep, run_headings
from mobmanip.team.sweep import sweep_heading

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
BEAM = EXAMPLES / "beam_team.toml"
ROBOTS = EXAMPLES.parent / "robots"
DATA = tomllib.loads(BEAM.read_text())
#: From -90 deg (out of reach) to +40 deg: the sweep starts at 0 in the middle and goes both
#: ways, and the unreachable headings hand their neighbour's seed on.
OFFSETS = (-90.0, -75.0, -60.0, -45.0, -30.0, -15.0, 0.0, 10.0, 25.0, 40.0)
MEASURES = ("kinematic", "dynamic", "kinematic_polytope")


@pytest.fixture(scope="module")
def serial():
    return sweep_heading(DATA, OFFSETS, base_dir=EXAMPLES, measures=MEASURES)


def assert_same_points(a, b):
    assert a.task == b.task and a.measures == b.measures and len(a.points) == len(b.points)
    for p, q in zip(a.points, b.points):
        assert p.offset_deg == q.offset_deg and p.reachable == q.reachable
        assert p.reach.keys() == q.reach.keys()
        for name in p.reach:
            assert np.array_equal(p.reach[name], q.reach[name]), (p.offset_deg, name)
        assert p.limiting == q.limiting and p.volume == q.volume
        assert p.worst_torque == q.worst_torque and p.overload == q.overload
        assert p.joints == q.joints  # the postures, exactly: the seeds were handed on as in the serial walk


def test_the_grid_has_reachable_and_unreachable_headings(serial):
    # otherwise the comparisons below would not exercise the seeds handed on past a lost heading
    reachable = serial.reachable
    assert reachable.any() and not reachable.all()
    assert reachable[OFFSETS.index(0.0)]


@pytest.mark.parametrize("per_task", [1, 3, 4, 10])
def test_a_thread_pool_gives_the_serial_sweep(serial, per_task):
    job = HeadingJob(DATA, OFFSETS, str(EXAMPLES), MEASURES, str(BEAM), per_task)
    with cf.ThreadPoolExecutor(2) as executor:
        assert_same_points(run_heading_sweep(job, executor), serial)


def test_a_process_pool_gives_the_serial_sweep(serial):
    job = HeadingJob(DATA, OFFSETS, str(EXAMPLES), MEASURES, str(BEAM), 3)
    with cf.ProcessPoolExecutor(2) as executor:
        swept = run_heading_sweep(job, executor)
    assert_same_points(swept, serial)
    assert swept.to_dict() == serial.to_dict()  # the JSON the command writes


def test_without_an_executor_the_job_is_the_serial_sweep(serial):
    assert_same_points(run_heading_sweep(HeadingJob(DATA, OFFSETS, str(EXAMPLES), MEASURES)), serial)


class Recording(cf.Executor):
    """Runs each task at once, in this thread, and keeps what it was given."""

    def __init__(self):
        self.tasks = []

    def submit(self, fn, /, *args, **kwargs):
        self.tasks.append(args)
        future = cf.Future()
        future.set_result(fn(*args, **kwargs))
        return future


def test_each_reachable_heading_is_in_one_task_and_a_task_alone_gives_its_points(serial):
    executor = Recording()
    job = HeadingJob(DATA, OFFSETS, str(EXAMPLES), MEASURES, str(BEAM), 4)
    run_heading_sweep(job, executor)
    headings = [k for _, items in executor.tasks for k, _ in items]
    assert sorted(headings) == np.flatnonzero(serial.reachable).tolist()  # the unreachable: no task
    assert [len(items) for _, items in executor.tasks] == [4, 3]
    # what travels is the solved joints, the same the serial sweep reports at that heading
    for _, items in executor.tasks:
        for k, joints in items:
            assert joints == serial.points[k].joints
    # a task run again, by itself and in the reverse order (a lost worker's task, elsewhere)
    sent, items = executor.tasks[-1]
    for k, point in run_headings(sent, tuple(reversed(items))):
        assert_same_points(type(serial)(serial.task, serial.measures, (point,)),
                           type(serial)(serial.task, serial.measures, (serial.points[k],)))  # fmt: skip


def test_the_bar_counts_finished_headings(monkeypatch):
    counts = []

    class Bar:
        def __init__(self, total, **kwargs):
            self.total = total

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def update(self, n):
            counts.append(n)

    monkeypatch.setattr(heading_jobs, "progress_bar", Bar)
    job = HeadingJob(DATA, (-90.0, -10.0, 0.0, 10.0, 20.0), str(EXAMPLES), ("kinematic",), str(BEAM), 2)
    with cf.ThreadPoolExecutor(2) as executor:
        swept = run_heading_sweep(job, executor, progress=True)
    assert swept.reachable.tolist() == [False, True, True, True, True]
    # one update per finished task, by its headings (two tasks of two), and one for the heading
    # found out of reach in this process
    assert sorted(counts) == [1, 2, 2]


@pytest.mark.parametrize("per_task", [0, -2, 1.5, True])
def test_a_bad_task_size_is_refused(per_task):
    with pytest.raises(ArgumentError, match="headings per task"):
        run_heading_sweep(HeadingJob(DATA, OFFSETS, str(EXAMPLES), ("kinematic",), headings_per_task=per_task))


def test_bad_offsets_and_a_bad_description_are_refused_before_any_task():
    executor = Recording()
    with pytest.raises(ArgumentError, match="finite"):
        run_heading_sweep(HeadingJob(DATA, (0.0, float("nan")), str(EXAMPLES)), executor)
    broken = {**DATA, "robots": [{**DATA["robots"][0], "robot": "no_such_robot"}]}
    with pytest.raises(TeamError, match="no_such_robot"):
        run_heading_sweep(HeadingJob(broken, (0.0, 10.0), str(EXAMPLES)), executor)
    assert executor.tasks == []


def test_robots_by_spec_path_load_on_the_workers_from_the_absolute_folder(tmp_path, monkeypatch):
    # the team's robots by spec paths relative to the team file, the workers started elsewhere
    specs = tmp_path / "team" / "specs"
    specs.mkdir(parents=True)
    for name in ("planar_dual_arm.toml", "planar_dual_arm.urdf"):
        shutil.copy(ROBOTS / name, specs / name)
    data = {**DATA, "robots": [{**entry, "robot": "specs/planar_dual_arm.toml"} for entry in DATA["robots"]]}
    offsets = (-60.0, -20.0, 0.0, 20.0)
    serial = sweep_heading(data, offsets, base_dir=tmp_path / "team", measures=("kinematic",))
    assert serial.reachable.any()
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    job = HeadingJob(data, offsets, str(tmp_path / "team"), ("kinematic",), headings_per_task=1)
    with cf.ProcessPoolExecutor(2) as executor:
        assert_same_points(run_heading_sweep(job, executor), serial)
