"""Benchmark: the unified ellipsoids per configuration, batched, against Pinocchio and pycapacity.

Measures in one run, as medians over interleaved rounds (the machine may be shared and noisy):

(a) the floor: Pinocchio's own calls per configuration -- forward kinematics, the end
    effectors' frame Jacobians, CRBA and the nonlinear effects -- for the paper's robot
    (planar_dual_arm, task planar) and TIAGo++ (tiago_dual, task spatial);
(b) ``mobmanip.analyze`` per configuration (and, for reference, its exact SVD path);
(c) ``mobmanip.analyze_batch`` per configuration at N = 10,000 (and its NumPy fast path, the
    stacked alternative to the compiled kernel);
(d) pycapacity's ``velocity_ellipsoid`` plus ``acceleration_ellipsoid`` per configuration on
    the same unified Jacobian and reduced inertia, precomputed (not timed);
(e) a sweep of the paper's robot on 2 worker processes against 1 (in-process);

and the peak resident memory of a 10^6-configuration sweep of the paper's robot (2 workers),
run in a fresh process (``resource.getrusage``: the main process and the largest worker).

BLAS runs single-threaded (set before NumPy loads), so per-configuration numbers use one core.

Usage::

    python scripts/benchmark.py            # full run (a few minutes)
    python scripts/benchmark.py --quick    # smoke run (seconds)
    python scripts/benchmark.py --polytopes [--quick]   # the capacity polytopes instead
    python scripts/benchmark.py --decisions [--quick]   # decisions beside the code they replace
    python scripts/benchmark.py --sweeps [--quick]      # polytope sweeps, compiled beside one at a time
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from pycapacity.robot import acceleration_ellipsoid, velocity_ellipsoid  # noqa: E402

import mobmanip  # noqa: E402
from mobmanip.batch import BatchSetup, Workspace, pinocchio_pass, warm_kernel  # noqa: E402
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep  # noqa: E402
from mobmanip.terms.dynamics import reduced_dynamics, unified_jacobian  # noqa: E402

ROBOTS = (("planar_dual_arm", "planar"), ("tiago_dual", "spatial"))
TARGETS = {  # (b)/(a), (c)/(a) upper bounds per robot
    "planar_dual_arm": (20.0, 3.0),
    "tiago_dual": (10.0, 2.0),
}


def _numba_version() -> str:
    try:
        import numba
    except ImportError:
        return "missing (NumPy paths)"
    return numba.__version__


def random_configurations(robot, rng, count):
    """Platform pose and every joint angle uniform (x, y in [-3, 3] m, angles in [-pi, pi])."""
    model = robot.model
    qs = np.tile(pin.neutral(model), (count, 1))
    yaw = rng.uniform(-math.pi, math.pi, count)
    qs[:, 0:2] = rng.uniform(-3.0, 3.0, (count, 2))
    qs[:, 2], qs[:, 3] = np.cos(yaw), np.sin(yaw)
    for j in range(2, model.njoints):
        joint = model.joints[j]
        angle = rng.uniform(-math.pi, math.pi, count)
        if joint.nq == 2:
            qs[:, joint.idx_q], qs[:, joint.idx_q + 1] = np.cos(angle), np.sin(angle)
        else:
            qs[:, joint.idx_q] = angle
    return qs


def per_config(fn, count: int) -> float:
    """Seconds per configuration of one call of fn over ``count`` configurations."""
    start = time.perf_counter()
    fn()
    return (time.perf_counter() - start) / count


class Case:
    """One robot's measurements."""

    def __init__(self, name: str, task: str, n_single: int, n_batch: int, rng):
        self.name, self.task = name, task
        self.robot = mobmanip.load_robot(name)
        self.qs_single = random_configurations(self.robot, rng, n_single)
        self.qs_batch = random_configurations(self.robot, rng, n_batch)
        self.times: dict[str, list[float]] = {}
        robot = self.robot
        # precomputed for pycapacity (not timed): the unified Jacobian and reduced inertia
        self.precomputed = [(unified_jacobian(robot, q, task), reduced_dynamics(robot, q).P) for q in self.qs_single]
        self.setup = BatchSetup(robot, task)
        warm_kernel(robot, task)  # analyze takes the compiled kernel only once it is compiled
        self.workspace = Workspace(self.setup.probed, n_single)

    def floor(self):
        model, data = self.robot.model, self.robot.data
        frames = [arm.frame_id for arm in self.robot.arms]
        v0 = np.zeros(model.nv)
        lwa = pin.LOCAL_WORLD_ALIGNED
        for q in self.qs_single:
            pin.forwardKinematics(model, data, q)
            for f in frames:
                pin.computeFrameJacobian(model, data, q, f, lwa)
            pin.crba(model, data, q)
            pin.nonLinearEffects(model, data, q, v0)

    def batch_pass(self):
        pinocchio_pass(self.setup.probed, self.qs_single, self.workspace)

    def single(self):
        robot, task = self.robot, self.task
        for q in self.qs_single:
            mobmanip.analyze(robot, q, task)

    def single_exact(self):
        robot, task = self.robot, self.task
        for q in self.qs_single:
            mobmanip.analyze(robot, q, task, method="exact")

    def batch(self):
        mobmanip.analyze_batch(self.robot, self.qs_batch, self.task)

    def batch_numpy(self):
        mobmanip.analyze_batch(self.robot, self.qs_batch, self.task, method="numpy")

    def pycapacity(self):
        vlim, elim = self.robot.velocity_limits, self.robot.effort_limits
        for J, P in self.precomputed:
            velocity_ellipsoid(J, vlim)
            acceleration_ellipsoid(J, P, elim)

    def round(self):
        n1, nb = len(self.qs_single), len(self.qs_batch)
        for key, fn, count in (
            ("floor", self.floor, n1),
            ("pass", self.batch_pass, n1),
            ("single", self.single, n1),
            ("single_exact", self.single_exact, n1),
            ("batch", self.batch, nb),
            ("batch_numpy", self.batch_numpy, nb),
            ("pycapacity", self.pycapacity, n1),
        ):
            self.times.setdefault(key, []).append(per_config(fn, count))

    def median_us(self, key: str) -> float:
        return float(np.median(self.times[key]) * 1e6)


def sweep_grid(n_configurations: int) -> SweepGrid:
    """A paper-robot grid of about n configurations: angle x distance (0.4 .. 1.45 m, in reach)."""
    side = max(2, int(round(math.sqrt(n_configurations))))
    return SweepGrid(angle_deg=np.linspace(0.0, 360.0, side), distance=np.linspace(0.4, 1.45, side))


def timed_sweep(grid: SweepGrid, workers: int) -> float:
    start = time.perf_counter()
    run_sweep(SweepSpec("planar_dual_arm"), grid, workers=workers, chunk_size=4096)
    return time.perf_counter() - start


def memory_child(n_configurations: int) -> None:
    """Run one sweep on 2 workers and print its peak resident memory as JSON."""
    grid = sweep_grid(n_configurations)
    seconds = timed_sweep(grid, workers=2)
    self_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    child_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    print(
        json.dumps(
            {
                "configurations": grid.n_configurations,
                "seconds": seconds,
                "main_mb": self_kb / 1024,
                "largest_worker_mb": child_kb / 1024,
            }
        )
    )


def verdict(value: float, bound: float, below: bool = True) -> str:
    return "met" if (value <= bound if below else value >= bound) else "NOT met"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes, for a fast smoke run")
    parser.add_argument("--rounds", type=int, help="interleaved measurement rounds (default 7; quick 2)")
    parser.add_argument("--memory-child", type=int, metavar="N", help=argparse.SUPPRESS)
    parser.add_argument(
        "--polytopes", action="store_true", help="only the capacity polytopes (scripts/benchmark_polytopes.py)"
    )
    parser.add_argument("--floor", action="store_true", help="only the grounded capacity (scripts/benchmark_floor.py)")
    parser.add_argument(
        "--decisions",
        action="store_true",
        help="decisions beside the code they replace, on one run (scripts/benchmark_decisions.py)",
    )
    parser.add_argument("--only", metavar="TEXT", help="with --decisions: only the decisions whose name contains TEXT")
    parser.add_argument(
        "--sweeps", action="store_true", help="only the compiled polytope sweeps (scripts/benchmark_sweeps.py)"
    )
    args = parser.parse_args(argv)
    if args.memory_child:
        memory_child(args.memory_child)
        return 0
    if args.polytopes:
        from benchmark_polytopes import run

        return run(quick=args.quick)
    if args.decisions:
        from benchmark_decisions import run as run_decisions

        return run_decisions(quick=args.quick, rounds=args.rounds, only=args.only)
    if args.floor:
        from benchmark_floor import run as run_floor

        return run_floor(quick=args.quick)
    if args.sweeps:
        from benchmark_sweeps import run as run_sweeps

        return run_sweeps(quick=args.quick)
    quick = args.quick
    rounds = args.rounds or (2 if quick else 7)
    n_single, n_batch = (200, 2000) if quick else (1000, 10000)
    sweep_n, sweep_rounds = (40_000, 1) if quick else (1_000_000, 3)
    memory_n = 40_000 if quick else 1_000_000

    rng = np.random.default_rng(20240607)
    versions = (
        f"mobmanip {mobmanip.__version__}, pinocchio {pin.__version__}, numpy {np.__version__}, "
        f"numba {_numba_version()}"
    )
    print(f"{versions}, {os.cpu_count()} cores")
    cases = [Case(name, task, n_single, n_batch, rng) for name, task in ROBOTS]
    for case in cases:  # warm-up round, not counted
        case.round()
        case.times.clear()
    for _ in range(rounds):
        for case in cases:
            case.round()

    header = f"{'per configuration, us (median of ' + str(rounds) + ' rounds)':<66}" + "".join(
        f"{c.name:>17}" for c in cases
    )
    print()
    print(header)
    print("-" * len(header))
    rows = (
        ("(a) floor: Pinocchio FK + frame Jacobians + CRBA + NLE", "floor"),
        ("    batch's Pinocchio pass (its calls + copies into stacks)", "pass"),
        ("(b) analyze, one configuration", "single"),
        ("    analyze(method='exact'): SVD path only", "single_exact"),
        (f"(c) analyze_batch, N = {n_batch}", "batch"),
        ("    analyze_batch(method='numpy'): stacked NumPy fast path", "batch_numpy"),
        ("(d) pycapacity velocity + acceleration ellipsoid, J and M given", "pycapacity"),
    )
    for label, key in rows:
        print(f"{label:<66}" + "".join(f"{c.median_us(key):>17.2f}" for c in cases))
    print("  tasks: " + ", ".join(f"{c.name} {c.task} (m = {len(c.setup.rows)}, nx = {c.robot.nx})" for c in cases))
    print()
    print(f"{'ratio (target)':<66}" + "".join(f"{c.name:>17}" for c in cases))
    print("-" * len(header))
    met = []
    for label, num, den, which in (
        ("(b)/(a) single configuration vs floor", "single", "floor", 0),
        ("(c)/(a) batched vs floor", "batch", "floor", 1),
        ("(c)/(d) batched vs pycapacity's two ellipsoids", "batch", "pycapacity", None),
    ):
        cells = []
        for c in cases:
            ratio = c.median_us(num) / c.median_us(den)
            bound = 1.0 if which is None else TARGETS[c.name][which]
            v = verdict(ratio, bound) if which is not None else verdict(ratio, 1.0 - 1e-12)
            met.append((label, c.name, ratio, bound, v))
            cells.append(f"{ratio:6.2f} (<={bound:g}) {v:<7}")
        print(f"{label:<66}" + "".join(f"{cell:>17}" for cell in cells))

    grid = sweep_grid(sweep_n)
    print()
    print(f"sweep of planar_dual_arm, {grid.n_configurations} configurations (median of {sweep_rounds}):")
    serial, parallel = [], []
    for _ in range(sweep_rounds):
        serial.append(timed_sweep(grid, 1))
        parallel.append(timed_sweep(grid, 2))
    t1, t2 = float(np.median(serial)), float(np.median(parallel))
    speedup = t1 / t2
    print(f"  1 worker (in-process) {t1:8.2f} s  ({t1 / grid.n_configurations * 1e6:.2f} us/configuration)")
    print(f"  2 worker processes    {t2:8.2f} s  ({t2 / grid.n_configurations * 1e6:.2f} us/configuration)")
    print(f"  speed-up {speedup:.2f} (target >= 1.7: {verdict(speedup, 1.7, below=False)})")

    child = subprocess.run(
        [sys.executable, __file__, "--memory-child", str(memory_n)], capture_output=True, text=True, check=True
    )
    mem = json.loads(child.stdout.strip().splitlines()[-1])
    peak = mem["main_mb"] + 2 * mem["largest_worker_mb"]
    print()
    print(
        f"memory, {mem['configurations']} configurations on 2 workers ({mem['seconds']:.1f} s): main process "
        f"{mem['main_mb']:.0f} MB, largest worker {mem['largest_worker_mb']:.0f} MB peak resident; "
        f"total at most {peak:.0f} MB (target < 2048 MB: {verdict(peak, 2048.0)})"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
