"""``mobmanip warmup``: compile every compiled kernel once, ahead of the first real run.

A first ``place``, ``carry``, ``sweep`` or ``analyze --polytope`` compiles the Numba kernels it
needs (each up to tens of seconds on a busy 2-core machine; kept in Numba's disk cache after).
``warmup`` pays all of them at once, one after the other, naming each: the face kernels of 2-D
and 3-D sets, the planar and 3-D polytope sweep kernels, the gradient tree kernel's loops and the
batch kernel for the pair (end effectors, task dimension) of each built-in robot's default task.
Per kernel it prints whether it was cached already or how long its compile took; ``--list``
prints what it would do (each kernel, cached or not, and up to how long it may take) without
compiling, ``--only TEXT`` keeps the kernels whose name holds TEXT. A batch kernel for another
pair compiles at its first use, announced.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: The built-in robots whose default task's batch kernel ``warmup`` compiles (their pairs of end
#: effectors and task dimension: 1 and 6, 2 and 2, 1 and 3, 2 and 6).
BATCH_ROBOTS = ("panda", "planar_dual_arm", "stretch", "tiago_dual")


@dataclass(frozen=True)
class Kernel:
    """One compiled kernel: how its compile's notice names it, the most its compile may take (s),
    whether Numba's disk cache holds it (``None``: cannot tell) and how to compile it."""

    name: str
    seconds: float
    cached: Callable[[], bool | None]
    compile: Callable[[], object]


def kernels() -> list[Kernel]:
    """Every kernel ``warmup`` compiles, in its order (see the module's docstring)."""
    from ..engine.compiled import expected_compile_seconds, kernel_name
    from ..engine.pipeline import BatchSetup
    from ..gradients.tree_adjoint import LOOPS, loops_cached
    from ..robot.model import load_robot
    from ..sets import polygon_kernel, zonotope_batch_kernel, zonotope_kernel
    from ..sets.capacity_batch import warm_kernels
    from ..support.compile_notice import up_to

    def faces(m: int) -> Callable[[], object]:
        generators = np.arange(1.0, 1.0 + m * (m + 2)).reshape(m, m + 2) ** 0.5  # in general position
        return lambda: zonotope_kernel.faces(np.zeros(m), generators)

    dynamic = tuple(name for name in LOOPS if name != "kinematic chain")
    faces_name = "the zonotope/polytope face kernel for {}-D sets"
    out = [
        Kernel(faces_name.format(2), up_to("faces 2-D"), lambda: zonotope_kernel.kernel_cached(2), faces(2)),
        Kernel(faces_name.format(3), up_to("faces 3-D"), lambda: zonotope_kernel.kernel_cached(3), faces(3)),
        Kernel(
            "the planar polytope sweep kernel", up_to("planar sweep"), polygon_kernel.kernel_cached,
            lambda: warm_kernels(2),
        ),
        Kernel(
            "the 3-D zonotope sweep kernel", up_to("3-D sweep"), zonotope_batch_kernel.kernel_cached,
            lambda: warm_kernels(3),
        ),
        Kernel(
            f"the gradient tree kernel's {', '.join(dynamic)} loops",
            sum(up_to(name) for name in dynamic),
            lambda: _all_cached([loops_cached(name) for name in dynamic]),
            lambda: _tree_gradient("dynamic:log_volume"),
        ),
        Kernel(
            "the gradient tree kernel's kinematic chain loops",
            up_to("kinematic chain"),
            lambda: loops_cached("kinematic chain"),
            lambda: _tree_gradient("kinematic:log_volume"),
        ),
    ]  # fmt: skip
    pairs: dict[tuple[int, int], str] = {}
    for name in BATCH_ROBOTS:
        setup = BatchSetup(load_robot(name))
        pairs.setdefault((setup.k, setup.m), name)
    for (k, m), name in sorted(pairs.items()):
        out.append(Kernel(kernel_name(k, m), expected_compile_seconds(k), *_batch(k, m, name)))
    return out


def _batch(k: int, m: int, robot: str) -> tuple[Callable[[], bool | None], Callable[[], object]]:
    """Whether the batch kernel of the pair is cached, and how to compile it (on ``robot``)."""
    from ..engine.compiled import kernel_cached
    from ..engine.pipeline import warm_kernel
    from ..robot.model import load_robot

    return (lambda: kernel_cached(k, m)), (lambda: warm_kernel(load_robot(robot)))


def _all_cached(states: list[bool | None]) -> bool | None:
    if any(state is None for state in states):
        return None
    return all(states)


def _tree_gradient(objective: str) -> None:
    """One gradient of ``objective`` on the paper's robot through the tree kernel (its first call
    compiles the loops it runs)."""
    from ..casestudy import configuration_at, optimal_posture
    from ..gradients import measure_gradients
    from ..robot.model import load_robot

    robot = load_robot("planar_dual_arm")
    measure_gradients(robot, configuration_at(robot, optimal_posture(robot), 45.0)[None, :], objective)


def register(sub) -> None:
    parser = sub.add_parser(
        "warmup",
        help="compile every compiled kernel once, ahead of the first real run (each up to tens of seconds)",
    )
    parser.add_argument("--list", action="store_true", help="list the kernels, cached or not, without compiling")
    parser.add_argument("--only", metavar="TEXT", help="only the kernels whose name holds TEXT")
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..engine.compiled import kernel_available
    from ..errors import UsageError

    if not kernel_available():
        print("Numba is not installed: nothing to compile (the NumPy paths run); pip install 'mobmanip[fast]'")
        return 0
    every = kernels()
    chosen = [k for k in every if args.only is None or args.only in k.name]
    if not chosen:
        names = "; ".join(k.name for k in every)
        raise UsageError(f"--only {args.only!r} names no kernel; they are: {names}")
    if args.list:
        for kernel in chosen:
            state = {True: "cached", False: "not cached", None: "cannot tell"}[kernel.cached()]
            print(f"{kernel.name}: {state} (a compile takes up to {kernel.seconds:.0f} s)")
        return 0
    compiled, total = 0, 0.0
    for kernel in chosen:
        if kernel.cached():
            print(f"{kernel.name}: cached")
            continue
        started = time.perf_counter()
        kernel.compile()
        took = time.perf_counter() - started
        compiled, total = compiled + 1, total + took
        print(f"{kernel.name}: compiled in {took:.1f} s (up to {kernel.seconds:.0f} s)", flush=True)
    print(f"{len(chosen)} kernels: {compiled} compiled in {total:.1f} s, {len(chosen) - compiled} already cached")
    return 0
