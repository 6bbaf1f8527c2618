"""Polytope sweeps: the compiled batch beside one polytope per configuration, in one run.

Run as ``python scripts/benchmark.py --sweeps`` (one core: ``NUMBA_NUM_THREADS=1
OPENBLAS_NUM_THREADS=1``). Prints:

- per configuration (ms, median of interleaved rounds), a sweep of the paper robot
  (``planar_dual_arm``, planar task, decoupled as in the paper) recording the three polytopes'
  indices (kinematic, exact dynamic, minimum-norm: ``sweep --polytope``), in this process: with
  one :class:`~mobmanip.sets.polytope.Polytope` per configuration (the path before the compiled
  batch) and with :mod:`mobmanip.sets.capacity_batch`, and their ratio;
- per configuration (ms), TIAGo++'s translational (3-D) exact dynamic polytope: the indices a
  sweep records (volume, isotropy, support, widths) for a chunk of 200 random configurations
  whose terms are given, one polytope at a time beside the compiled batch (a TIAGo++ sweep's
  inverse kinematics, a few ms per point, would hide both);
- a 10^5-point planar sweep of the three polytopes on the compiled path (target: at most 10 s on one core);
- the compile time of the planar kernel, in a child process with an empty Numba cache.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from mobmanip.sets import capacity
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep

POLYTOPES = ("kinematic_polytope", "dynamic_polytope", "dynamic_polytope_min_norm")  # sweep --polytope


def _grid(count: int) -> SweepGrid:
    """About ``count`` reachable points of the paper robot: angles x distances (0.6 to 1.4 m)."""
    distances = max(1, int(round(np.sqrt(count / 4.0))))
    angles = max(1, -(-count // distances))
    return SweepGrid(
        angle_deg=np.linspace(0.0, 360.0, angles, endpoint=False), distance=np.linspace(0.6, 1.4, distances)
    )


def _one_at_a_time():
    """The sweep's polytope batch with one Polytope per configuration (the path before)."""
    original = capacity.polytope_batch

    def batch(kind, **terms):
        return original(kind, compiled=False, **terms)

    return original, batch


def _tiago_chunk(count: int):
    """The stacked terms of TIAGo++ holding 2 kg at ``count`` random joint configurations (translational)."""
    import mobmanip
    from mobmanip.terms.builder import terms_at

    robot = mobmanip.load_robot("tiago_dual")
    rng = np.random.default_rng(3)
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    rows = []
    for _ in range(count):
        q = robot.neutral()
        for name in robot.spec.arm_joint_names:
            j = robot.model.joints[robot.model.getJointId(name)]
            q[j.idx_q] = rng.uniform(max(lo[j.idx_q], -np.pi), min(hi[j.idx_q], np.pi))
        rows.append(terms_at(robot, q, "translational", object_mass=2.0))
    return capacity.stacked_terms(rows)


def _chunk_indices(terms: dict, compiled: bool) -> float:
    """Seconds per configuration for the indices a sweep records, from given terms."""
    start = time.perf_counter()
    batch = capacity.polytope_batch("dynamic", compiled=compiled, **terms)
    batch.volume, batch.isotropy, batch.widths  # noqa: B018 - computed on access
    batch.support(np.array([1.0, 0.0, 0.0]))
    return (time.perf_counter() - start) / len(batch)


def _timed(spec: SweepSpec, grid: SweepGrid, compiled: bool) -> float:
    original, slow = _one_at_a_time()
    capacity.polytope_batch = original if compiled else slow  # type: ignore[assignment]
    try:
        start = time.perf_counter()
        result = run_sweep(spec, grid, workers=1)
        seconds = time.perf_counter() - start
    finally:
        capacity.polytope_batch = original  # type: ignore[assignment]
    return seconds / max(int(result.reachable.sum()), 1)


_COMPILE_CHILD = """
import time, numpy as np
from mobmanip.sets import polygon_kernel
G = np.random.default_rng(0).normal(size=(4, 4, 8))
F = np.broadcast_to(np.vstack([np.eye(2), np.eye(2)]), (4, 4, 2))
args = (F, np.zeros((4, 4)), G, np.zeros((4, 2)), np.zeros(4, dtype=bool))
start = time.perf_counter(); polygon_kernel.polygons(*args); first = time.perf_counter() - start
start = time.perf_counter(); polygon_kernel.polygons(*args); second = time.perf_counter() - start
print(first, second)
"""


def _compile_seconds() -> float:
    """First call minus second call of the planar kernel in a process with an empty Numba cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run(
            [sys.executable, "-c", _COMPILE_CHILD], env=env, capture_output=True, text=True, check=True
        )
    first, second = (float(x) for x in out.stdout.split())
    return first - second


def run(quick: bool = False) -> int:
    rounds = 2 if quick else 5
    n_compare, n_total = (400, 10_000) if quick else (2_000, 100_000)
    threads = ", ".join(f"{k}={os.environ.get(k, 'unset')}" for k in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS"))
    print(f"polytope sweeps, one worker in this process ({threads}); load {os.getloadavg()[0]:.2f}")
    paper = SweepSpec("planar_dual_arm", measures=POLYTOPES, decoupled=True)
    cases = {
        "paper robot, planar: the three polytopes (sweep --polytope)": (paper, _grid(n_compare)),
    }
    tiago = _tiago_chunk(200)
    tiago_name = "TIAGo++, translational exact dynamic polytope (chunk of 200)"
    for spec, grid in cases.values():  # warm-up: compiles, postures, caches
        small = SweepGrid(angle_deg=grid.angle_deg[:2], distance=grid.distance[:2])
        _timed(spec, small, True)
        _timed(spec, small, False)
    _chunk_indices(tiago, True)
    _chunk_indices(tiago, False)
    samples: dict[str, dict[bool, list[float]]] = {name: {True: [], False: []} for name in (*cases, tiago_name)}
    for _ in range(rounds):
        for name, (spec, grid) in cases.items():
            for compiled in (False, True):
                samples[name][compiled].append(_timed(spec, grid, compiled))
        for compiled in (False, True):
            samples[tiago_name][compiled].append(_chunk_indices(tiago, compiled))
    title = f"per configuration, ms (median of {rounds} interleaved rounds)"
    print(f"{title:<58} {'before':>9} {'now':>9} {'ratio':>7}")
    for name, by in samples.items():
        before, now = np.median(by[False]) * 1e3, np.median(by[True]) * 1e3
        print(f"{name:<58} {before:9.4f} {now:9.4f} {before / now:6.1f}x")
    grid = _grid(n_total)
    totals = []
    for _ in range(1 if quick else 3):
        start = time.perf_counter()
        result = run_sweep(paper, grid, workers=1)
        totals.append(time.perf_counter() - start)
    total = float(np.median(totals))
    count = int(result.reachable.sum())
    print(
        f"planar polytope sweep of the paper robot, {count} points, compiled: {total:.2f} s, median of "
        f"{len(totals)} ({min(totals):.2f} to {max(totals):.2f} s; {total / count * 1e3:.4f} ms per point)"
    )
    if count >= 100_000:
        print(f"target 10^5 points <= 10 s on one core: {'met' if total <= 10.0 else 'NOT met'}")
    print(f"compile time of the planar polytope kernel (empty Numba cache): {_compile_seconds():.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(run(quick="--quick" in sys.argv))
