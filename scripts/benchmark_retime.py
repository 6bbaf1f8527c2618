"""Time the fastest timing of a path (``mobmanip.motion.retime``), beside TOPP-RA's own implementation.

Run: ``python scripts/benchmark.py --retime [--quick]`` (or this file directly). In one process,
warm, BLAS and OpenMP limited to one thread as the ``mobmanip`` command runs, medians of
interleaved rounds:

- TIAGo++ carrying 2 kg along a 200-sample whole-body path (1.2 m along an arc while the arms
  move), with the floor (zero-moment point 5 cm inside, traction mu 0.5, reserve 0.2) and
  without it;
- the Panda on a 200-sample path with joint velocity and effort limits only, beside ``toppra``
  (the same limits, RNEA in its torque rows): the same problem both ways.

CPU time is the process's (``time.process_time``); wall time beside it.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: The issue's bound on retiming 200 samples of TIAGo++ with the floor (s of CPU, in process, warm).
BOUND = 0.100


def _tiago_path(robot, n: int):
    from mobmanip.motion.trajectory import trajectory_from_samples

    home = robot.hold_configuration()
    s = np.linspace(0.0, 6.0, n)
    u = 0.5 - 0.5 * np.cos(math.pi * s / 6.0)
    yaw = 0.4 * u
    q = np.tile(home, (n, 1))
    q[:, 0], q[:, 1] = 3.0 * np.sin(yaw), 3.0 * (1.0 - np.cos(yaw))
    q[:, 2], q[:, 3] = np.cos(yaw), np.sin(yaw)
    for name, change in (("arm_left_2_joint", 0.3), ("arm_right_2_joint", 0.3), ("arm_left_4_joint", -0.4)):
        q[:, robot.model.joints[robot.model.getJointId(name)].idx_q] += change * u
    known = [name for name in robot.joint_names if "wheel" not in name]
    return trajectory_from_samples(robot, s, q, known_joints=known)


def _panda_case(n: int):
    """(our call, toppra's call) on the same sine path of the Panda's seven joints (the reference
    of ``tests/test_retime.py``)."""
    import pinocchio as pin

    from mobmanip import load_robot
    from mobmanip.motion.retime import retime
    from mobmanip.motion.trajectory import trajectory_from_samples

    sys.path.insert(0, str(ROOT / "tests"))
    from retime_util import arm_indices, sine_path, toppra_duration

    robot = load_robot("panda")
    model = robot.model
    iq, iv = arm_indices(robot)
    s, q, x_s, x_ss = sine_path(robot, n)
    path = trajectory_from_samples(robot, s, q, x_s, x_ss)

    def ours():
        return retime(robot, path, object_mass=0.0).duration

    try:
        import toppra
    except ImportError:
        return ours, None
    toppra.setup_logging("WARNING")
    data = model.createData()
    home = robot.hold_configuration()

    def inverse_dynamics(qq, qd, qdd):
        full, v, a = home.copy(), np.zeros(model.nv), np.zeros(model.nv)
        full[iq], v[iv], a[iv] = qq, qd, qdd
        return pin.rnea(model, data, full, v, a)[iv]

    vlim, elim = np.asarray(robot.velocity_limits), np.asarray(robot.effort_limits)

    def theirs():
        return toppra_duration(home[iq], s, vlim, elim, inverse_dynamics)

    return ours, theirs


def interleaved(cases: dict, rounds: int) -> tuple[dict[str, tuple[float, float]], dict]:
    """Each case called once to warm up, then ``rounds`` rounds calling every case in turn (a busy
    moment of the machine falls on all alike): name -> (median CPU s, median wall s), and each
    case's last value."""
    for call in cases.values():
        call()
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in cases}
    values = {}
    for _ in range(rounds):
        for name, call in cases.items():
            wall, cpu = time.perf_counter(), time.process_time()
            values[name] = call()
            times[name].append((time.process_time() - cpu, time.perf_counter() - wall))
    medians = {
        name: (statistics.median(p[0] for p in pairs), statistics.median(p[1] for p in pairs))
        for name, pairs in times.items()
    }
    return medians, values


def run(quick: bool = False, rounds: int | None = None) -> int:
    from mobmanip import load_robot
    from mobmanip.motion.carry_floor import CarryFloor
    from mobmanip.motion.retime import retime
    from mobmanip.support.threads import limit_threads

    rounds = rounds or (2 if quick else 7)
    n = 50 if quick else 200
    with limit_threads():
        tiago = load_robot("tiago_dual")
        path = _tiago_path(tiago, n)
        floor = CarryFloor(mu=0.5, zmp_margin=0.05, reserve=0.2)
        cases = {
            "TIAGo++ 2 kg, floor": lambda: retime(tiago, path, object_mass=2.0, floor=floor).duration,
            "TIAGo++ 2 kg, limits only": lambda: retime(tiago, path, object_mass=2.0).duration,
        }
        ours, theirs = _panda_case(n)
        cases["Panda, limits only"] = ours
        if theirs is not None:
            cases["Panda, limits only (toppra)"] = theirs
        medians, durations = interleaved(cases, rounds)
    title = f"retime, {n} samples, medians of {rounds} interleaved rounds (one BLAS thread)"
    medians = print_medians(title, medians, durations, "duration s", ".6f")
    if "Panda, limits only (toppra)" in medians:
        ratio = medians["Panda, limits only"] / medians["Panda, limits only (toppra)"]
        gap = durations["Panda, limits only"] / durations["Panda, limits only (toppra)"] - 1.0
        print(f"Panda: mobmanip / toppra CPU {ratio:.1f}x; durations apart by {gap:.1e}")
    if not quick:
        print_bound(f"TIAGo++ with the floor, {n} samples", medians["TIAGo++ 2 kg, floor"], BOUND)
    return 0


def print_medians(title: str, timed: dict, values: dict, value: str, form: str) -> dict[str, float]:
    """Print the medians of :func:`interleaved` as a table under ``title``, each case's last value
    in the column ``value`` (formatted by ``form``); return the CPU medians by case."""
    width = max(32, *(len(name) for name in timed))
    print(title)
    print(f"{'case':{width}s} {'CPU ms':>9s} {'wall ms':>9s} {value:>12s}")
    for name, (cpu, wall) in timed.items():
        print(f"{name:{width}s} {1e3 * cpu:9.1f} {1e3 * wall:9.1f} {values[name]:12{form}}")
    return {name: cpu for name, (cpu, _) in timed.items()}


def print_bound(what: str, cpu: float, bound: float) -> None:
    """One line: the CPU time (s) of ``what`` and whether it is within its bound (s)."""
    verdict = "within" if cpu <= bound else "ABOVE"
    print(f"{what}: {1e3 * cpu:.1f} ms of CPU, {verdict} the {1e3 * bound:.0f} ms bound")


def main(run, doc: str) -> int:
    """The command line of a benchmark run directly: ``--quick`` and ``--rounds N``."""
    sys.path.insert(0, str(ROOT / "src"))
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--rounds", type=int)
    arguments = parser.parse_args()
    return run(quick=arguments.quick, rounds=arguments.rounds)


if __name__ == "__main__":
    sys.exit(main(run, __doc__))
