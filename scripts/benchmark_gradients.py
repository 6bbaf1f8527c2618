"""Cost of a gradient against the value it differentiates, per configuration, batched.

Prints, for the paper's robot and TIAGo++, microseconds per configuration of
``analyze_batch`` (both ellipsoids' values; compiled kernel and NumPy path) and of
``GradientEvaluator.batch`` (one objective's value and tangent-space gradient), on 2000 random
configurations, and the ratio of the gradient to the compiled value. Every timing is the median
of REPEATS runs taken in turn (value, gradient, value, ...), so that a busy machine slows both
alike. NumPy's BLAS is limited to one thread (per-configuration cost, as the value's kernel).
Run: ``python scripts/benchmark_gradients.py``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before NumPy loads its BLAS
os.environ.setdefault("OMP_NUM_THREADS", "1")

import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

import mobmanip  # noqa: E402
from mobmanip.gradients import GradientEvaluator  # noqa: E402

N = 2000
REPEATS = 7
OBJECTIVES = ("kinematic:log_volume", "dynamic:log_volume", "dynamic:capacity:+x")


def random_configurations(robot, rng, n):
    qs = np.repeat(pin.neutral(robot.model)[None], n, axis=0)
    for q in qs:
        yaw = rng.uniform(-math.pi, math.pi)
        q[:4] = (*rng.uniform(-3, 3, 2), math.cos(yaw), math.sin(yaw))
        for j in range(2, robot.model.njoints):
            joint = robot.model.joints[j]
            a = rng.uniform(-math.pi, math.pi)
            if joint.nq == 2:
                q[joint.idx_q : joint.idx_q + 2] = (math.cos(a), math.sin(a))
            else:
                q[joint.idx_q] = a
    return qs


def per_config(fn, qs) -> float:
    started = time.perf_counter()
    fn(qs)
    return (time.perf_counter() - started) / len(qs) * 1e6


def main() -> None:
    rng = np.random.default_rng(0)
    print(f"medians of {REPEATS} interleaved runs, {N} configurations, microseconds per configuration")
    header = ("robot", "value: kernel", "value: numpy", "objective", "gradient", "ratio")
    print("{:16s} {:>14s} {:>13s} {:>22s} {:>9s} {:>6s}".format(*header))
    for name in ("planar_dual_arm", "tiago_dual"):
        robot = mobmanip.load_robot(name)
        qs = random_configurations(robot, rng, N)
        timed = {
            "kernel": lambda x, r=robot: mobmanip.analyze_batch(r, x, method="auto"),
            "numpy": lambda x, r=robot: mobmanip.analyze_batch(r, x, method="numpy"),
        }
        for objective in OBJECTIVES:
            timed[objective] = GradientEvaluator(robot, objective).batch
        for fn in timed.values():
            fn(qs[:20])  # warm up (compiles the kernel on first use)
        runs = {key: [] for key in timed}
        for _ in range(REPEATS):
            for key, fn in timed.items():
                runs[key].append(per_config(fn, qs))
        median = {key: statistics.median(values) for key, values in runs.items()}
        for objective in OBJECTIVES:
            ratio = median[objective] / median["kernel"]
            print(
                f"{name:16s} {median['kernel']:11.1f} us {median['numpy']:10.1f} us {objective:>22s} "
                f"{median[objective]:6.1f} us {ratio:5.1f}x"
            )


if __name__ == "__main__":
    main()
