"""Runs served in batches (:mod:`mobmanip.support.lockstep`): each run's result is what it is on
its own, placement's starts and a map's bands included, and failures end every run.

Placement evaluates its starts, and a map its bands, together: one batched evaluation per
round for all runs waiting. What that must not change is the answer: every start's (and every
band's) SLSQP iterates are those of the same run made alone, one evaluation at a time (the
code before the batching), so the placement found is the same, not merely no worse.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import mobmanip
from mobmanip.placement import place
from mobmanip.placement.map_jobs import MapJob, run_band, run_map
from mobmanip.placement.maps import default_extent
from mobmanip.support.lockstep import Lockstep


def _one_at_a_time(monkeypatch):
    """Every lockstep runs its runs one after the other, each request evaluated on its own."""
    monkeypatch.setattr(Lockstep, "run", lambda self, runs: [run() for run in runs])


def _newton_sqrt(lockstep: Lockstep, a: float) -> tuple[float, int]:
    """sqrt(a) by Newton steps on x^2 - a, asking for (f, f') one point at a time."""
    x, steps = max(a, 1.0), 0
    while True:
        f, df = lockstep.ask(x)
        step = f / df
        x -= step
        steps += 1
        if abs(step) < 1e-15 * x or steps == 60:
            return x, steps


def test_runs_get_their_own_answers_in_fewer_batched_calls():
    targets = [2.0, 10.0, 1e6, 0.25, 7.0]
    calls: list[int] = []

    # each run asks with its own target: the evaluation needs to know which run asked
    def evaluate_tagged(requests):
        calls.append(len(requests))
        return [(x * x - a, 2.0 * x) for a, x in requests]

    lockstep = Lockstep(evaluate_tagged)

    class Tagged:
        def __init__(self, a):
            self.a = a

        def ask(self, x):
            return lockstep.ask((self.a, x))

    results = lockstep.run([lambda a=a: _newton_sqrt(Tagged(a), a) for a in targets])
    alone = [_newton_sqrt(Tagged(a), a) for a in targets]  # outside run: one request per call
    assert results == alone  # the same iterates, bit for bit
    for (x, _), a in zip(results, targets):
        assert x == pytest.approx(np.sqrt(a), rel=1e-15)
    in_lockstep = calls[: lockstep.batches - sum(steps for _, steps in alone)]
    assert max(in_lockstep) == len(targets)  # the first rounds serve every run at once
    assert len(in_lockstep) == max(steps for _, steps in alone)  # one call per round
    assert sum(in_lockstep) == sum(steps for _, steps in alone)


def test_a_failing_run_ends_the_others_and_raises_in_the_caller():
    lockstep = Lockstep(lambda requests: [r + 1 for r in requests])
    unwound = []

    def good(k):
        total = 0
        try:
            for _ in range(100):
                total = lockstep.ask(total)
        finally:
            unwound.append((k, total))
        return total

    def bad():
        lockstep.ask(0)
        raise RuntimeError("run 1 broke")

    with pytest.raises(RuntimeError, match="run 1 broke"):
        lockstep.run([lambda: good(0), bad, lambda: good(2)])
    # run 0 had its first reply and asked again; run 2, served after the failing run, had none:
    # both were unwound where they waited
    assert sorted(unwound) == [(0, 1), (2, 0)]
    assert lockstep.run([lambda: good(3)]) == [100]  # and the lockstep is usable again


def test_a_failing_evaluation_or_an_interrupt_ends_every_run():
    for error in (ValueError("bad batch"), KeyboardInterrupt()):

        def evaluate(requests, error=error):
            if len(requests) > 1:
                raise error
            return requests

        unwound: list[int] = []

        def run(k, lockstep, unwound=unwound):
            try:
                return lockstep.ask(k)
            finally:
                unwound.append(k)

        lockstep = Lockstep(evaluate)
        with pytest.raises(type(error)):
            lockstep.run([lambda ls=lockstep: run(1, ls), lambda ls=lockstep: run(2, ls)])
        assert sorted(unwound) == [1, 2]


def test_an_interrupt_inside_a_run_ends_every_run_at_once():
    """A signal arrives in whichever run executes (the runs share the caller's thread): the
    interrupt leaves that run, every other run is unwound, no batch is evaluated after it, and
    the caller sees the interrupt itself."""
    batches = []
    lockstep = Lockstep(lambda requests: batches.append(len(requests)) or requests)
    unwound = []

    def run(k):
        try:
            for step in range(50):
                lockstep.ask(step)
                if k == 1 and step == 3:
                    raise KeyboardInterrupt
            return k
        finally:
            unwound.append(k)

    with pytest.raises(KeyboardInterrupt):
        lockstep.run([lambda k=k: run(k) for k in range(4)])
    assert sorted(unwound) == [0, 1, 2, 3]
    assert len(batches) == 4  # the rounds up to the interrupt, none after


def test_runs_never_execute_at_the_same_time():
    """Runs share state that is not thread-safe (a Pinocchio Data): one runs at a time."""
    inside = []
    lockstep = Lockstep(lambda requests: requests)

    def run(k):
        for step in range(20):
            inside.append(k)
            time.sleep(0.001)  # lets another thread run, were any free to
            assert inside == [k], inside
            inside.pop()
            lockstep.ask(step)
        return k

    assert lockstep.run([lambda k=k: run(k) for k in range(6)]) == list(range(6))


def test_place_finds_the_same_placement_as_one_start_at_a_time_on_20_objects(monkeypatch):
    """The issue's check: on 20 random object positions, the placement with batched starts is
    no worse than the code before (one start after the other, one evaluation at a time), with
    the same starts. It is the same: value, configuration and every start's result."""
    tiago = mobmanip.load_robot("tiago_dual")
    rng = np.random.default_rng(2026)
    objects = np.column_stack([rng.uniform(-2.0, 2.0, 20), rng.uniform(-2.0, 2.0, 20), rng.uniform(0.65, 1.05, 20)])
    batched = [place(tiago, o, "dynamic:log_volume", object_mass=1.0, starts=4) for o in objects]
    _one_at_a_time(monkeypatch)
    alone = [place(tiago, o, "dynamic:log_volume", object_mass=1.0, starts=4) for o in objects]
    for b, a in zip(batched, alone):
        assert b.value >= a.value
        assert b.value == a.value and np.array_equal(b.q, a.q) and b.runs == a.runs
        assert b.evaluations == a.evaluations


def test_a_map_solved_in_one_call_equals_its_bands_solved_alone():
    """Serial maps run every band together (batched); a cluster worker solves one band alone.
    The cells are the same bit for bit, and so are the serial map's configurations."""
    paper = mobmanip.load_robot("planar_dual_arm")
    target = (1.0, 0.5, 0.35)
    x0, x1, y0, y1 = default_extent(paper, target)
    job = MapJob(robot="planar_dual_arm", target=target, objective="kinematic:capacity:+x",
                 x=tuple(np.linspace(x0, x1, 9)), y=tuple(np.linspace(y0, y1, 9)), rows_per_task=2)  # fmt: skip
    whole = run_map(job)
    assert np.isfinite(whole.values).sum() >= 20
    for start, stop in job.bands():
        _, band = run_band(job, start, stop)
        if band is None:
            assert np.isnan(whole.values[start:stop]).all()
            continue
        assert np.array_equal(band.values, whole.values[start:stop], equal_nan=True)
        assert np.array_equal(band.configurations, whole.configurations[start:stop], equal_nan=True)


@pytest.mark.parametrize(
    ("name", "objective", "decoupled"),
    [
        ("planar_dual_arm", "kinematic:capacity:+x", False),
        ("planar_dual_arm", "dynamic:log_volume", True),
        ("planar_dual_arm_omni", "dynamic:minor_axis", False),
        ("tiago_dual", "dynamic:log_volume", False),
        ("tiago_dual", "kinematic:capacity:+z", False),
        ("tiago", "dynamic:capacity:+x", True),
        ("stretch", "dynamic:log_volume", False),
    ],
)
@pytest.mark.parametrize("compiled", [None, False], ids=["loops", "numpy"])
def test_a_batch_row_equals_the_same_configuration_alone_bit_for_bit(name, objective, decoupled, compiled):
    """What lets batching leave results unchanged: the gradient chain computes every row of a
    batch exactly as it computes that configuration alone (no product whose summation depends
    on the batch's size), in the compiled loops and in the NumPy forms a placement of a few
    starts runs (each product one matrix per configuration, never one over the stacked rows)."""
    import pinocchio as pin

    from mobmanip.gradients.evaluator import GradientEvaluator

    robot = mobmanip.load_robot(name)
    evaluator = GradientEvaluator(
        robot, objective, robot.spec.default_task, object_mass=1.0, decoupled=decoupled, compiled=compiled
    )
    rng = np.random.default_rng(7)
    q0 = robot.hold_configuration()
    qs = np.array([pin.integrate(robot.model, q0, rng.normal(scale=0.4, size=robot.model.nv)) for _ in range(7)])
    value, grad, ok = evaluator._chunk(qs)
    for i in range(len(qs)):
        v1, g1, ok1 = evaluator._chunk(qs[i : i + 1])
        assert ok1[0] == ok[i] and v1[0] == value[i] and np.array_equal(g1[0], grad[i]), (name, i)


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual", "stretch"])
def test_the_hands_frames_from_the_gradient_pass_equal_pinocchios(name):
    """The hold constraints use the hands' poses and Jacobians that the objective's batched pass
    brings along (from its probe joints); they equal Pinocchio's frame placements and
    ``getFrameJacobian(LOCAL_WORLD_ALIGNED)``, platform far from the origin included."""
    import pinocchio as pin

    from mobmanip.gradients.evaluator import GradientEvaluator
    from mobmanip.placement.optimize import PlacementProblem

    robot = mobmanip.load_robot(name)
    evaluator = GradientEvaluator(robot, "dynamic:log_volume", robot.spec.default_task, object_mass=1.0)
    problem = PlacementProblem(robot, evaluator, np.array([1.0, 0.5, 0.8]), None, robot.hold_configuration())
    model, data = robot.model, robot.model.createData()
    rng = np.random.default_rng(5)
    qs = []
    for _ in range(6):
        q = pin.integrate(model, robot.hold_configuration(), rng.normal(scale=0.5, size=model.nv))
        q[:2] += rng.uniform(-5.0, 5.0, 2)
        qs.append(q)
    for q, (_, _, _, (positions, rotations, jacobians)) in zip(qs, problem._evaluate_batch(qs)):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for i, arm in enumerate(robot.arms):
            np.testing.assert_allclose(positions[i], data.oMf[arm.frame_id].translation, rtol=0, atol=1e-12)
            np.testing.assert_allclose(rotations[i], data.oMf[arm.frame_id].rotation, rtol=0, atol=1e-12)
            J = pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(jacobians[i], J, rtol=0, atol=1e-12)


def test_a_runs_last_evaluation_is_reused_only_at_the_same_point():
    """A run's optimum is usually the point SLSQP evaluated last: ``value_at`` answers it from the
    objective's last evaluation when the configuration is the same bit for bit, else asks anew;
    both equal an independent evaluation of the measure at that configuration."""
    from mobmanip.gradients.evaluator import GradientEvaluator
    from mobmanip.placement.optimize import PlacementProblem

    robot = mobmanip.load_robot("planar_dual_arm")
    evaluator = GradientEvaluator(robot, "kinematic:capacity:+x", None)
    problem = PlacementProblem(robot, evaluator, np.array([1.0, 0.5, 0.35]), None, robot.hold_configuration())
    z = problem.start(0.3, np.random.default_rng(0))
    problem.objective(z)
    q = problem.configuration(z)
    reference = mobmanip.analyze(robot, q, measures=("kinematic",)).measures["kinematic"].support(np.eye(2)[0])
    before = evaluator.evaluations
    value, ok = problem.value_at(q)
    assert ok and evaluator.evaluations == before and value == pytest.approx(reference, rel=1e-12)
    moved = q.copy()
    moved[-1] += 1e-3
    value2, _ = problem.value_at(moved)
    assert evaluator.evaluations == before + 1
    expected = mobmanip.analyze(robot, moved, measures=("kinematic",)).measures["kinematic"].support(np.eye(2)[0])
    assert value2 == pytest.approx(expected, rel=1e-12)
