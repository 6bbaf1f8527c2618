"""Cost of a gradient against the value it differentiates, per configuration, batched.

Prints, for the paper's robot and TIAGo++, microseconds per configuration of
``analyze_batch`` (both ellipsoids' values; compiled kernel and NumPy path) and of
``GradientEvaluator.batch`` (one objective's value and tangent-space gradient), on 2000 random
configurations. Run: ``python scripts/benchmark_gradients.py``.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pinocchio as pin

import mobmanip
from mobmanip.gradients import GradientEvaluator

N = 2000


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
    fn(qs[:20])  # warm up (compiles the kernel on first use)
    started = time.perf_counter()
    fn(qs)
    return (time.perf_counter() - started) / len(qs) * 1e6


def main() -> None:
    rng = np.random.default_rng(0)
    print(f"{'robot':16s} {'value: kernel':>14s} {'value: numpy':>13s} {'objective':>24s} {'gradient':>9s}")
    for name in ("planar_dual_arm", "tiago_dual"):
        robot = mobmanip.load_robot(name)
        qs = random_configurations(robot, rng, N)
        kernel = per_config(lambda x, r=robot: mobmanip.analyze_batch(r, x, method="auto"), qs)
        numpy_path = per_config(lambda x, r=robot: mobmanip.analyze_batch(r, x, method="numpy"), qs)
        for objective in ("kinematic:log_volume", "dynamic:log_volume"):
            ev = GradientEvaluator(robot, objective)
            grad = per_config(ev.batch, qs)
            print(f"{name:16s} {kernel:11.1f} us {numpy_path:10.1f} us {objective:>24s} {grad:6.1f} us")


if __name__ == "__main__":
    main()
