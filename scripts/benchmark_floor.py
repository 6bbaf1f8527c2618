"""Grounded capacity: what the floor costs, beside the ideal sets, in one run.

Run as ``python scripts/benchmark.py --floor``. Prints medians (ms) over interleaved rounds of:

- a straight-line reach query along +x of TIAGo++ holding 2 kg in its hold posture (spatial task),
  on the floor with mu = 0.5, beside the same query on the ideal exact polytope (target: 5 ms);
- the whole grounded planar polytope (terms, floor rows, every vertex) of the paper robot with
  the object at 0 deg, beside the ideal one (target: 5 ms).
"""

from __future__ import annotations

import time

import numpy as np

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.postures.named import named_configuration
from mobmanip.sets.lifted import LiftedPolytope
from mobmanip.terms.builder import terms_at
from mobmanip.terms.constraints.floor import Floor
from mobmanip.terms.problems import capacity_polytope


def _median_ms(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def run(quick: bool = False) -> int:
    rounds, repeats = (2, 5) if quick else (7, 20)
    floor = Floor(mu=0.5)
    tiago = mobmanip.load_robot("tiago_dual")
    q_hold = named_configuration(tiago, "hold")
    ex = np.eye(6)[0]
    tiago_sets = {
        name: mobmanip.analyze(
            tiago, q_hold, "spatial", object_mass=2.0, measures=("dynamic_polytope",), constraints=c
        ).measures["dynamic_polytope"]
        for name, c in (("ideal", ()), ("grounded", (floor,)))
    }
    paper = mobmanip.load_robot("planar_dual_arm")
    q0 = configuration_at(paper, optimal_posture(paper), 0.0)

    def planar(constraints):
        def build():
            T = terms_at(paper, q0, "planar", object_mass=2.0, constraints=constraints)
            if constraints:
                return capacity_polytope(T, "acceleration").vertices
            return mobmanip.get_measure("dynamic_polytope").compute(T).vertices

        return build

    def highs_only(build):
        """The same polygon with every vertex program on HiGHS (the certified DAQP path off)."""

        def run_on_highs():
            LiftedPolytope.certified_vertices = False
            try:
                return build()
            finally:
                LiftedPolytope.certified_vertices = True

        return run_on_highs

    def query(P):
        def one():
            P._cache.pop(("ray", tuple(ex), tuple(np.zeros(6))), None)  # a fresh LP each time
            return P.straight_line_reach(ex)

        return one

    cases = {
        "TIAGo++ straight-line +x, ideal exact polytope": lambda: tiago_sets["ideal"].straight_line_reach(ex),
        "TIAGo++ straight-line +x, on the floor (mu 0.5)": query(tiago_sets["grounded"]),
        "paper robot planar polytope, ideal (terms + vertices)": planar(()),
        "paper robot planar polytope, on the floor (terms + floor + vertices)": planar((floor,)),
        "  the same, every vertex program on HiGHS": highs_only(planar((floor,))),
    }
    for fn in cases.values():  # warm-up
        fn()
    samples: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(rounds):
        for name, fn in cases.items():
            samples[name].append(_median_ms(fn, repeats))
    print(f"{'grounded capacity, ms (median of ' + str(rounds) + ' interleaved rounds)':<72} {'ms':>8}")
    for name, values in samples.items():
        print(f"{name:<72} {np.median(values):8.3f}")
    grounded = np.median(samples["TIAGo++ straight-line +x, on the floor (mu 0.5)"])
    polygon = np.median(samples["paper robot planar polytope, on the floor (terms + floor + vertices)"])
    on_highs = np.median(samples["  the same, every vertex program on HiGHS"])
    print(f"grounded polygon, HiGHS only / certified DAQP: {on_highs / polygon:.2f}x")
    for label, value in (("TIAGo++ grounded query", grounded), ("paper robot grounded planar polytope", polygon)):
        print(f"target {label} <= 5 ms: {value:.3f} ms, {'met' if value <= 5 else 'NOT met'}")
    return 0
