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

``--decisions`` also times the two placement decisions as the command a user types (see
:func:`time_commands`): each in a fresh process of the ``mobmanip`` console script, with the
environment this script was started with (not the one-thread settings above; Python's bytecode
cache allowed, as an installed package has it), beside the same
work in this warm process, quiet and again beside 4 busy processes.

Usage::

    python scripts/benchmark.py            # full run (a few minutes)
    python scripts/benchmark.py --quick    # smoke run (seconds)
    python scripts/benchmark.py --polytopes [--quick]   # the capacity polytopes instead
    python scripts/benchmark.py --decisions [--quick]   # decisions beside the code they replace
    python scripts/benchmark.py --decisions --as-commands   # only the decisions as a user types them
    python scripts/benchmark.py --sweeps [--quick]      # polytope sweeps, compiled beside one at a time
"""

from __future__ import annotations

import os

#: The environment as the user started this script: the commands timed as a user types them get
#: it, with Python's bytecode cache allowed (warm caches: an installed mobmanip has its bytecode
#: compiled at install, a source checkout writes it on its first run, the warm-up here; without
#: it every command compiles mobmanip's modules again, 0.2 to 0.4 s).
USER_ENVIRONMENT = {name: value for name, value in os.environ.items() if name != "PYTHONDONTWRITEBYTECODE"}

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

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


# ----------------------------------------------------------------------------------------------
# the decisions as a user types them

#: Busy processes of the parallel load: on a 2-core machine, 4 keep both cores busy twice over.
LOAD_PROCESSES = 4
#: Upper bounds: a command's CPU time on the quiet machine (s), and its CPU time loaded over quiet.
COMMAND_CPU_BOUND = 1.5
LOAD_RATIO_BOUND = 1.5


class CommandCase:
    """One decision as a command (``argv`` after ``mobmanip``; ``{out}`` is a fresh directory)
    and as the library call that does its work in this process (``call``)."""

    def __init__(self, name: str, argv: list[str], call):
        self.name, self.argv, self.call = name, argv, call
        self.times: dict[tuple[str, str], list[float]] = {}

    def add(self, load: str, column: str, value: float) -> None:
        self.times.setdefault((load, column), []).append(value)

    def median(self, load: str, column: str) -> float:
        return float(np.median(self.times[(load, column)]))

    def cell(self, load: str, column: str) -> str:
        values = self.times[(load, column)]
        return f"{np.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def command_cases(quick: bool) -> list[CommandCase]:
    """The two placement decisions of benchmark_decisions.py, as a user types them."""
    from mobmanip.placement import place
    from mobmanip.placement.map_jobs import MapJob, run_map
    from mobmanip.placement.maps import default_extent

    tiago = mobmanip.load_robot("tiago_dual")
    paper = mobmanip.load_robot("planar_dual_arm")
    target = (1.0, 0.5, 0.35)
    cells = 7 if quick else 15
    x0, x1, y0, y1 = default_extent(paper, target)
    job = MapJob(robot="planar_dual_arm", target=target, objective="kinematic:capacity:+x",
                 x=tuple(np.linspace(x0, x1, cells)), y=tuple(np.linspace(y0, y1, cells)))  # fmt: skip
    return [
        CommandCase(
            "place, TIAGo++, 8 starts",
            "place tiago_dual --object 1.5,0.5,0.85 --mass 1 --objective dynamic:log_volume".split(),
            lambda: place(tiago, [1.5, 0.5, 0.85], "dynamic:log_volume", object_mass=1.0, starts=8),
        ),
        CommandCase(
            f"place --map, paper robot ({cells} x {cells})",
            "place planar_dual_arm --object 1,0.5,0.35 --objective kinematic:capacity:+x --map {out}".split()
            + ["--map-cells", str(cells)],
            lambda: run_map(job),
        ),
    ]


def _console_script() -> list[str]:
    """The ``mobmanip`` command installed beside this Python (else ``python -m mobmanip``)."""
    script = Path(sys.executable).with_name("mobmanip")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "mobmanip"]


def _argv(case: CommandCase, out: str) -> list[str]:
    return [str(Path(out) / "map") if part == "{out}" else part for part in case.argv]


def time_command(case: CommandCase) -> tuple[float, float]:
    """(CPU, wall) seconds of the command in a fresh process with the user's environment; the
    CPU time is the child's, from this process's RUSAGE_CHILDREN before and after."""
    with tempfile.TemporaryDirectory() as out:
        argv = _console_script() + _argv(case, out)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        child = subprocess.run(argv, env=USER_ENVIRONMENT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if child.returncode != 0:
        raise RuntimeError(f"mobmanip {' '.join(case.argv)} failed: {child.stderr.strip()}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def time_main(case: CommandCase) -> float:
    """CPU seconds of the same command run by ``mobmanip.cli.main`` in this warm process."""
    import contextlib
    import io

    from mobmanip.cli import main as cli_main

    with tempfile.TemporaryDirectory() as out:
        sink = io.StringIO()
        start = time.process_time()
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            code = cli_main(_argv(case, out))
        cpu = time.process_time() - start
    if code != 0:
        raise RuntimeError(f"mobmanip {' '.join(case.argv)} failed in-process: {sink.getvalue().strip()}")
    return cpu


def time_call(case: CommandCase) -> float:
    """CPU seconds of the decision's library call in this warm process."""
    start = time.process_time()
    case.call()
    return time.process_time() - start


@contextlib.contextmanager
def busy_load(processes: int):
    """``processes`` Python processes spinning while the block runs (killed and reaped after it,
    so their CPU time never enters a command's RUSAGE_CHILDREN difference)."""
    spinners = [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(processes)]
    try:
        time.sleep(0.5)  # until they run
        yield
    finally:
        for spinner in spinners:
            spinner.kill()
        for spinner in spinners:
            spinner.wait()


COMMAND_COLUMNS = (
    ("call", "in-process call, CPU"),
    ("main", "in-process cli.main, CPU"),
    ("cpu", "command, CPU"),
    ("wall", "command, wall"),
)


def time_commands(quick: bool = False, rounds: int | None = None, only: str | None = None) -> int:
    """Each placement decision as the command a user types, beside it in this warm process.

    Columns, each a median (min-max) over ``rounds`` interleaved rounds (default 5; quick 2)
    after one warm-up run of each (Numba's disk cache, the robots' caches, the files read): the
    decision's library call (what the decisions table times), the command run by
    ``mobmanip.cli.main`` in this process (the call plus parsing, checks and output files), and
    the command in a fresh process as a user types it (plus the interpreter's start and the
    imports), CPU time of the child and wall time. Then all of it again beside
    :data:`LOAD_PROCESSES` busy processes, and the loaded figures over the quiet ones.
    """
    rounds = rounds or (2 if quick else 5)
    cases = [case for case in command_cases(quick) if only is None or only in case.name]
    if not cases:
        return 0
    print(f"as a user types it: load average {os.getloadavg()[0]:.2f} before, {os.cpu_count()} cores; thread "
          f"variables passed on: {_thread_variables(USER_ENVIRONMENT) or 'none'}", flush=True)  # fmt: skip
    if "PYTHONDONTWRITEBYTECODE" in os.environ:
        print("  note: PYTHONDONTWRITEBYTECODE is not passed on: the commands use Python's bytecode cache", flush=True)
    if os.getloadavg()[0] >= 1.0:
        print("  note: the machine is busy already (load average >= 1): the quiet figures are not quiet", flush=True)
    for case in cases:  # warm-up, not counted
        time_call(case), time_main(case), time_command(case)
    loads = (("quiet", contextlib.nullcontext), (f"{LOAD_PROCESSES} busy", lambda: busy_load(LOAD_PROCESSES)))
    for load, context in loads:
        with context():
            for _ in range(rounds):
                for case in cases:
                    case.add(load, "call", time_call(case))
                    case.add(load, "main", time_main(case))
                    cpu, wall = time_command(case)
                    case.add(load, "cpu", cpu)
                    case.add(load, "wall", wall)
        print(f"  {load}: done, load average {os.getloadavg()[0]:.2f}", flush=True)

    quiet, loaded = (name for name, _ in loads)
    header = f"{'seconds, median (min-max) of ' + str(rounds):<40}{'load':<10}" + "".join(
        f"{label:>26}" for _, label in COMMAND_COLUMNS
    )
    print()
    print(header)
    print("-" * len(header))
    for case in cases:
        for k, load in enumerate((quiet, loaded)):
            print(f"{case.name if k == 0 else '':<40}{load:<10}" + "".join(
                f"{case.cell(load, key):>26}" for key, _ in COMMAND_COLUMNS))  # fmt: skip
        ratios = [case.median(loaded, key) / case.median(quiet, key) for key, _ in COMMAND_COLUMNS]
        print(f"{'':<40}{'ratio':<10}" + "".join(f"{ratio:>26.2f}" for ratio in ratios))
    print()
    for case in cases:
        cpu, ratio = case.median(quiet, "cpu"), case.median(loaded, "cpu") / case.median(quiet, "cpu")
        start_up = case.median(quiet, "cpu") - case.median(quiet, "main")
        print(
            f"{case.name}: command {cpu:.2f} s CPU quiet (<= {COMMAND_CPU_BOUND:g}: "
            f"{verdict(cpu, COMMAND_CPU_BOUND)}), {ratio:.2f}x loaded (<= {LOAD_RATIO_BOUND:g}: "
            f"{verdict(ratio, LOAD_RATIO_BOUND)}); a fresh process adds {start_up:.2f} s CPU to cli.main"
        )
    return 0


def _thread_variables(environ) -> str:
    names = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
    return ", ".join(f"{name}={environ[name]}" for name in names if name in environ)


def verdict(value: float, bound: float, below: bool = True) -> str:
    return "met" if (value <= bound if below else value >= bound) else "NOT met"


#: The benchmarks of their own, one flag each: (flag, module in scripts/, what it times, whether
#: its run takes --rounds).
ON_THEIR_OWN = (
    ("polytopes", "benchmark_polytopes", "the capacity polytopes", False),
    ("floor", "benchmark_floor", "the grounded capacity", False),
    ("sweeps", "benchmark_sweeps", "the compiled polytope sweeps", False),
    ("retime", "benchmark_retime", "the fastest timing of a path, beside toppra", True),
    ("payload", "benchmark_payload", "the payload program and its map", True),
)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes, for a fast smoke run")
    parser.add_argument("--rounds", type=int, help="interleaved measurement rounds (default 7; quick 2)")
    parser.add_argument("--memory-child", type=int, metavar="N", help=argparse.SUPPRESS)
    for flag, module, what, _ in ON_THEIR_OWN:
        parser.add_argument(f"--{flag}", action="store_true", help=f"only {what} (scripts/{module}.py)")
    decisions = parser.add_argument_group(
        "decisions",
        "beside the code they replace, on one run (scripts/benchmark_decisions.py); or, with --as-commands, "
        "only the placement decisions as the commands a user types (fresh processes)",
    )
    decisions.add_argument("--decisions", action="store_true", help="only the decisions")
    decisions.add_argument("--as-commands", action="store_true", help="with --decisions: as commands only")
    decisions.add_argument("--only", metavar="TEXT", help="with --decisions: only those whose name contains TEXT")
    args = parser.parse_args(argv)
    if args.memory_child:
        memory_child(args.memory_child)
        return 0
    if args.decisions:
        if not args.as_commands:
            from benchmark_decisions import run as run_decisions

            run_decisions(quick=args.quick, rounds=args.rounds, only=args.only)
            print()
        return time_commands(quick=args.quick, rounds=args.rounds, only=args.only)
    for flag, module, _, with_rounds in ON_THEIR_OWN:
        if getattr(args, flag):
            run = importlib.import_module(module).run
            return run(quick=args.quick, rounds=args.rounds) if with_rounds else run(quick=args.quick)
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
