"""Decisions beside the code they replace, on one run (``python scripts/benchmark.py --decisions``).

Each entry is a decision the code made, measured against the alternative it decided against
(usually the code before it) in the same process, in interleaved rounds: each round times the
current way, then the chosen way; the table prints both medians and their ratio. BLAS runs
single-threaded (set by scripts/benchmark.py before NumPy loads).

An entry is a :class:`Decision`: a name, the question, and a ``prepare(quick)`` that builds both
sides once and returns them as :class:`Side` objects (a label and a callable that runs one round
and returns its time per unit: per configuration, per call). Add an entry by appending to
:data:`DECISIONS`.

Entries:

- ``place planar_dual_arm ... --map`` (15 x 15) and ``place tiago_dual ...`` (8 starts), CPU
  time: runs one after the other, one evaluation at a time, against runs advancing together
  with their evaluations batched (the same cells and placement either way: they are printed);
- self-collision distances and gradients of TIAGo++ per configuration (random configurations
  within the joint limits, platform anywhere): every pair that may meet, against the pairs the
  shipped collision matrix keeps (robots/tiago_dual.collision.json);
- ``place tiago_dual --object 1.5,0.5,0.85 --mass 1 --objective dynamic:log_volume
  --avoid-collision 0.02`` (8 starts), wall and CPU time of :func:`mobmanip.placement.place`
  with every pair against with the matrix's pairs;
- a planar sweep of the paper robot's three polytopes (``sweep --polytope``), one ``Polytope`` per
  configuration against the compiled batch, and TIAGo++'s translational exact dynamic polytope
  likewise (a chunk's indices from given terms; scripts/benchmark_sweeps.py has the details).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import mobmanip


@dataclass
class Side:
    """One way of doing it: ``run()`` does one round and returns its seconds per unit."""

    label: str
    run: Callable[[], float]


@dataclass
class Decision:
    name: str
    question: str
    unit: str
    prepare: Callable[[bool], tuple[Side, Side]]  # (current, chosen), given quick


def _collision_sides(quick: bool) -> tuple[Side, Side]:
    from benchmark_polytopes import configurations_within_limits
    from mobmanip.robot.collision import SelfCollision

    robot = mobmanip.load_robot("tiago_dual")
    every = SelfCollision(robot, margin=0.02, matrix=None)
    kept = SelfCollision(robot, margin=0.02)  # the matrix stored beside the spec
    assert kept.matrix is not None
    rng = np.random.default_rng(11)
    configurations = configurations_within_limits(robot, rng, 100 if quick else 1000, xy_range=3.0, one_turn=False)

    def timer(checker):
        def run() -> float:
            times = []
            for q in configurations:
                start = time.perf_counter()
                checker.distances(q)
                times.append(time.perf_counter() - start)
            return float(np.median(times))

        return run

    return (
        Side(f"all pairs ({len(every.pairs)})", timer(every)),
        Side(f"matrix ({len(kept.pairs)} pairs)", timer(kept)),
    )


def _place_sides(quick: bool) -> tuple[Side, Side]:
    from mobmanip.placement import place
    from mobmanip.robot.collision import SelfCollision

    robot = mobmanip.load_robot("tiago_dual")
    every = SelfCollision(robot, margin=0.02, matrix=None)
    kept = SelfCollision(robot, margin=0.02)
    starts = 2 if quick else 8
    place(robot, [1.5, 0.5, 0.85], "dynamic:log_volume", object_mass=1.0, starts=1)  # compile, warm caches

    def timer(checker):
        def run() -> float:
            wall, cpu = time.perf_counter(), time.process_time()
            result = place(robot, [1.5, 0.5, 0.85], "dynamic:log_volume", object_mass=1.0, starts=starts,
                           collision=checker)  # fmt: skip
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            print(f"    {checker.engine.first.size} pairs: value {result.value:.4f}, clearance "
                  f"{every.clearance(result.q):.4f} m (all pairs), {wall:.2f} s wall, {cpu:.2f} s CPU")  # fmt: skip
            return wall

        return run

    return (Side(f"all pairs ({len(every.pairs)})", timer(every)), Side(f"matrix ({len(kept.pairs)})", timer(kept)))


def _sweep_sides(quick: bool) -> tuple[Side, Side]:
    """The paper robot's planar sweep of its three polytopes (scripts/benchmark_sweeps.py)."""
    from benchmark_sweeps import POLYTOPES, _grid, _timed
    from mobmanip.sweep import SweepGrid, SweepSpec

    spec = SweepSpec("planar_dual_arm", measures=POLYTOPES, decoupled=True)
    grid = _grid(400 if quick else 2000)
    small = SweepGrid(angle_deg=grid.angle_deg[:2], distance=grid.distance[:2])
    _timed(spec, small, True)  # compile, postures, caches
    _timed(spec, small, False)
    return (
        Side("one Polytope per configuration", lambda: _timed(spec, grid, False)),
        Side("compiled batch", lambda: _timed(spec, grid, True)),
    )


def _zonotope_sides(quick: bool) -> tuple[Side, Side]:
    """TIAGo++'s translational exact dynamic polytope: a chunk's sweep indices, terms given."""
    from benchmark_sweeps import _chunk_indices, _tiago_chunk

    terms = _tiago_chunk(100 if quick else 200)
    _chunk_indices(terms, True)
    return (
        Side("one Polytope per configuration", lambda: _chunk_indices(terms, False)),
        Side("compiled batch", lambda: _chunk_indices(terms, True)),
    )


def _one_at_a_time():
    """Lockstep runs executed one after the other, each evaluation on its own (the code before
    the batching): a context manager."""
    import contextlib

    from mobmanip.support.lockstep import Lockstep

    @contextlib.contextmanager
    def patched():
        batched = Lockstep.run
        Lockstep.run = lambda self, runs: [run() for run in runs]
        try:
            yield
        finally:
            Lockstep.run = batched

    return patched()


def _cpu_timer(work, alone: bool) -> Callable[[], float]:
    def run() -> float:
        if alone:
            with _one_at_a_time():
                start = time.process_time()
                work()
                return time.process_time() - start
        start = time.process_time()
        work()
        return time.process_time() - start

    return run


def _map_sides(quick: bool) -> tuple[Side, Side]:
    """``place planar_dual_arm --object 1,0.5,0.35 --objective kinematic:capacity:+x --map DIR``:
    the 15 x 15 map (bands of 3 rows, as the command runs it), CPU time."""
    from mobmanip.placement.map_jobs import MapJob, run_map
    from mobmanip.placement.maps import default_extent

    robot = mobmanip.load_robot("planar_dual_arm")
    target = (1.0, 0.5, 0.35)
    x0, x1, y0, y1 = default_extent(robot, target)
    cells = 7 if quick else 15
    job = MapJob(robot="planar_dual_arm", target=target, objective="kinematic:capacity:+x",
                 x=tuple(np.linspace(x0, x1, cells)), y=tuple(np.linspace(y0, y1, cells)))  # fmt: skip
    run_map(job)  # compile, warm caches

    def work():
        grid = run_map(job)
        print(f"    {np.isfinite(grid.values).sum()} cells hold the object, {grid.evaluations} evaluations, "
              f"sum of values {np.nansum(grid.values):.9f}")  # fmt: skip

    return Side("bands one after the other", _cpu_timer(work, True)), Side("bands batched", _cpu_timer(work, False))


def _starts_sides(quick: bool) -> tuple[Side, Side]:
    """``place tiago_dual --object 1.5,0.5,0.85 --mass 1 --objective dynamic:log_volume`` (8
    starts), CPU time of :func:`mobmanip.placement.place`."""
    from mobmanip.placement import place

    robot = mobmanip.load_robot("tiago_dual")
    place(robot, [1.5, 0.5, 0.85], "dynamic:log_volume", object_mass=1.0, starts=1)

    def work():
        result = place(robot, [1.5, 0.5, 0.85], "dynamic:log_volume", object_mass=1.0, starts=8)
        print(f"    value {result.value:.12f}, {result.evaluations} evaluations")

    return Side("starts one after the other", _cpu_timer(work, True)), Side("starts batched", _cpu_timer(work, False))


DECISIONS: list[Decision] = [
    Decision(
        "place --map, paper robot",
        "a map's bands advance together, their evaluations batched (support/lockstep.py)",
        "s CPU per map",
        _map_sides,
    ),
    Decision(
        "place, TIAGo++, 8 starts",
        "the starts advance together, their evaluations batched",
        "s CPU per placement",
        _starts_sides,
    ),
    Decision(
        "self-collision, TIAGo++",
        "an allowed-collision matrix computed once (robots/tiago_dual.collision.json) instead of every pair",
        "ms per configuration",
        _collision_sides,
    ),
    Decision(
        "place --avoid-collision 0.02, TIAGo++",
        "the same matrix as SLSQP constraints",
        "s wall per placement",
        _place_sides,
    ),
    Decision(
        "polytope sweep --polytope, paper robot",
        "a chunk's planar polytopes stacked and measured in one compiled pass (sets/capacity_batch.py)",
        "ms per configuration",
        _sweep_sides,
    ),
    Decision(
        "3-D exact dynamic polytope, TIAGo++",
        "the same batch for 3-D zonotopes, through the reference's face kernel",
        "ms per configuration",
        _zonotope_sides,
    ),
]


def run(quick: bool = False, rounds: int | None = None, only: str | None = None) -> int:
    rounds = rounds or (1 if quick else 3)
    rows = []
    for decision in DECISIONS:
        if only is not None and only not in decision.name:
            continue
        print(f"{decision.name}: {decision.question}", flush=True)
        current, chosen = decision.prepare(quick)
        times: tuple[list[float], list[float]] = ([], [])
        for _ in range(rounds):
            times[0].append(current.run())
            times[1].append(chosen.run())
        a, b = float(np.median(times[0])), float(np.median(times[1]))
        scale = 1e3 if decision.unit.startswith("ms") else 1.0
        rows.append((decision.name, decision.unit, current.label, a * scale, chosen.label, b * scale, a / b))
    print()
    header = f"{'decision':<40}{'unit':<22}{'current':>30}{'':>10}{'chosen':>30}{'':>10}{'ratio':>8}"
    print(f"medians of {rounds} interleaved rounds")
    print(header)
    print("-" * len(header))
    for name, unit, label_a, a, label_b, b, ratio in rows:
        print(f"{name:<40}{unit:<22}{label_a:>30}{a:>10.3f}{label_b:>30}{b:>10.3f}{ratio:>8.2f}")
    return 0
