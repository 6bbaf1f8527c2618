"""Time the trajectory analysis: 1,000 TIAGo++ samples (both measures, demands, time-scaling margin).

Run: ``python scripts/benchmark_motion.py [--samples N]``. The motion: the platform on a circle
(0.3 m/s, 0.1 rad/s) while every arm joint swings; rates estimated from the samples.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import mobmanip
from mobmanip.motion.trajectory import trajectory_from_samples
from mobmanip.motion.trajectory_analysis import analyze_trajectory


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    args = parser.parse_args()
    robot = mobmanip.load_robot("tiago_dual")
    q0 = robot.hold_configuration()
    base = robot.configuration_dict(q0)["joints"]
    arms = [name for arm in robot.arms for name in arm.joint_names]
    t = np.linspace(0.0, 10.0, args.samples)
    qs = []
    for ti in t:
        joints = dict(base)
        for k, name in enumerate(arms):
            joints[name] = base[name] + 0.2 * math.sin(0.7 * ti + k)
        yaw = 0.1 * ti
        qs.append(robot.configuration((3.0 * math.sin(yaw), 3.0 * (1.0 - math.cos(yaw)), yaw), joints))
    qs = np.array(qs)
    analyze_trajectory(robot, trajectory_from_samples(robot, t[:5], qs[:5], known_joints=arms))  # warm up
    start = time.perf_counter()
    trajectory = trajectory_from_samples(robot, t, qs, known_joints=arms)
    result = analyze_trajectory(robot, trajectory)
    seconds = time.perf_counter() - start
    print(f"tiago_dual, {args.samples} samples: {seconds:.2f} s ({1e3 * seconds / args.samples:.2f} ms per sample)")
    scaling = result.scaling
    print(f"time-scaling margin {scaling.k_max:.4f} ({scaling.limit}), max slip {trajectory.slip.max():.1e}")


if __name__ == "__main__":
    main()
