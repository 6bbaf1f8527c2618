"""Time the payload program at a posture and over a 15 x 15 map of object positions.

Run: ``python scripts/benchmark.py --payload [--quick]`` (or this file directly). In one process,
warm, BLAS and OpenMP limited to one thread as the ``mobmanip`` command runs; CPU medians of
interleaved rounds (``time.process_time``), wall time beside them:

- the payload program at TIAGo++'s hold posture, held still, on the ideal model and on the floor
  (mu 0.5), and the paper's robot's given 1 m/s^2 along x;
- the paper robot's map of 15 x 15 object positions (-60..60 deg, 0.3..0.9 m), the object given
  1 m/s^2 along x, on the floor (mu 0.5).
"""

from __future__ import annotations

import sys

import numpy as np

#: The issue's bounds (s of CPU): one program at a posture, and the 15 x 15 map.
POSTURE_BOUND, MAP_BOUND = 0.010, 2.0


def run(quick: bool = False, rounds: int | None = None) -> int:
    import mobmanip
    from benchmark_retime import interleaved, print_bound, print_medians
    from mobmanip.analysis.payload import payload
    from mobmanip.support.threads import limit_threads
    from mobmanip.sweep.payload_map import payload_map
    from mobmanip.sweep.spec import SweepGrid
    from mobmanip.terms.constraints.floor import Floor

    rounds = rounds or (2 if quick else 5)
    side = 5 if quick else 15
    with limit_threads():
        tiago = mobmanip.load_robot("tiago_dual")
        hold = mobmanip.named_configuration(tiago, "hold")
        paper = mobmanip.load_robot("planar_dual_arm")
        home = paper.hold_configuration()
        grid = SweepGrid(np.linspace(-60.0, 60.0, side), np.linspace(0.3, 0.9, side))
        floor = (Floor(mu=0.5),)
        cases = {
            "TIAGo++ at hold, ideal": lambda: payload(tiago, hold).mass,
            "TIAGo++ at hold, floor": lambda: payload(tiago, hold, constraints=floor).mass,
            "paper robot, 1 m/s^2, floor": lambda: (
                payload(paper, home, "planar", acceleration=(1.0, 0.0), constraints=floor).mass
            ),  # fmt: skip
            f"paper robot map {side} x {side}, floor": lambda: float(
                np.nanmax(payload_map(paper, grid, "planar", acceleration=(1.0, 0.0), constraints=floor).mass)
            ),
        }
        timed, values = interleaved(cases, rounds)
    title = f"payload, medians of {rounds} interleaved rounds (one BLAS thread)"
    medians = print_medians(title, timed, values, "heaviest kg", ".4f")
    if not quick:
        print_bound("slowest program at a posture", max(medians[name] for name in list(cases)[:3]), POSTURE_BOUND)
        print_bound("15 x 15 map", medians[f"paper robot map {side} x {side}, floor"], MAP_BOUND)
    return 0


if __name__ == "__main__":
    from benchmark_retime import main

    sys.exit(main(run, __doc__))
