"""Benchmark of the exact capacity polytopes (``python scripts/benchmark.py --polytopes``).

Per configuration, medians over random configurations in one run (BLAS single-threaded, as the
main benchmark): building each polytope with its vertices, faces and halfspaces (task dimension
<= 3), or its halfspaces and one support query (6-D), for the paper's robot (planar) and
TIAGo++ (translational and spatial, both hands holding a 1 kg object); beside pycapacity's
polytope functions on the same matrices, run in a child process with a time limit:

- a zonotope (the exact dynamic set): ``velocity_polytope(G, 1, -1)`` on its generators, which is
  what pycapacity's velocity and acceleration polytopes compute; ours is timed on the same
  generators and, separately, from the dynamics (P, J_u, W, ...), which pycapacity cannot take;
- the kinematic set of two hands holding an object (a zonotope cut by a subspace):
  ``iterative_convex_hull_method`` with the grasp's equality, an approximation to its ``tol``;
- UR5 and Panda (translational task, no object): ``velocity_polytope`` and
  ``acceleration_polytope`` with the gravity torques as bias.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import mobmanip
from mobmanip.sets.capacity import dynamic_polytope, kinematic_polytope, min_norm_dynamic_polytope
from mobmanip.sets.polytope import Polytope

TARGETS_MS = {("planar_dual_arm", "both"): 2.0, ("tiago_dual", "kinematic"): 20.0}
SUPPORT_TARGET_MS = 1.0
SPEEDUP_TARGET = 5.0
PYCAPACITY_TOL = 1e-6  # tolerance given to pycapacity's iterative convex hull method


def configurations_within_limits(robot, rng, count, xy_range=2.0, one_turn=True):
    """``count`` configurations: the platform anywhere in a square of half-side ``xy_range`` (m)
    at any heading, each joint uniform between its limits, a full turn [-pi, pi] where it has
    none; ``one_turn`` also keeps a joint whose range is wider than a turn within [-pi, pi]."""
    model = robot.model
    out = []
    for _ in range(count):
        q = robot.neutral()
        yaw = rng.uniform(-math.pi, math.pi)
        q[:4] = (*rng.uniform(-xy_range, xy_range, size=2), math.cos(yaw), math.sin(yaw))
        for j in range(2, model.njoints):
            i = model.joints[j].idx_q
            if model.joints[j].nq == 2:
                a = rng.uniform(-math.pi, math.pi)
                q[i : i + 2] = (math.cos(a), math.sin(a))
                continue
            lo, hi = model.lowerPositionLimit[i], model.upperPositionLimit[i]
            if one_turn:
                lo, hi = max(lo, -math.pi), min(hi, math.pi)
            elif not (math.isfinite(lo) and math.isfinite(hi)):
                lo, hi = -math.pi, math.pi
            q[i] = rng.uniform(lo, hi)
        out.append(q)
    return out


def _terms(robot, q, task, mass):
    an = mobmanip.analyze(robot, q, task, method="exact", object_mass=mass)
    obj = an.held_object
    kin = (an.unified_jacobian, an.grasp_matrix, robot.velocity_limits)
    dyn = (
        an.unified_jacobian,
        an.grasp_matrix,
        an.reduced_inertia,
        robot.Q,
        an.bias,
        obj.inertia_matrix(task),
        obj.gravity_vector(task),
        robot.effort_limits,
    )
    return kin, dyn


def _full(poly):
    """Everything a user of a planar or 3-D polytope gets: vertices, faces, halfspaces."""
    poly.vertices, poly.faces, poly.halfspaces  # noqa: B018
    return poly


def _median_ms(fn, items) -> float:
    times = []
    for item in items:
        start = time.perf_counter()
        fn(item)
        times.append(time.perf_counter() - start)
    return float(np.median(times)) * 1e3


# ---------------------------------------------------------------------------------------------
# pycapacity in a child process


def pycapacity_child(path: str, kind: str) -> None:
    """Time pycapacity on the matrices saved at ``path``; print the median seconds as JSON."""
    from pycapacity.algorithms import iterative_convex_hull_method
    from pycapacity.robot import acceleration_polytope, velocity_polytope

    data = np.load(path)
    times = []
    for i in range(int(data["count"])):
        start = time.perf_counter()
        if kind == "zonotope":
            G = data[f"G{i}"]
            velocity_polytope(G, np.ones(G.shape[1]), -np.ones(G.shape[1]))
        elif kind == "section":
            Wt, J, lim = data[f"Wt{i}"], data[f"J{i}"], data[f"lim{i}"]
            iterative_convex_hull_method(Wt, J, -lim, lim, PYCAPACITY_TOL)
        elif kind == "velocity":
            velocity_polytope(data[f"J{i}"], data[f"lim{i}"], -data[f"lim{i}"])
        elif kind == "acceleration":
            lim = data[f"lim{i}"]
            acceleration_polytope(data[f"J{i}"], data[f"M{i}"], lim, -lim, t_bias=data[f"bias{i}"])
        times.append(time.perf_counter() - start)
    print(json.dumps({"median_s": float(np.median(times)), "count": len(times)}))


def _pycapacity(kind: str, arrays: list[dict], timeout: float) -> float | None:
    """Median ms of pycapacity on these matrices, or None when it did not finish in time (or
    failed: then its last error line is printed)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "matrices.npz"
        flat = {f"{k}{i}": v for i, item in enumerate(arrays) for k, v in item.items()}
        np.savez(path, count=len(arrays), **flat)
        try:
            child = subprocess.run(
                [sys.executable, __file__, "--pycapacity-child", str(path), kind],
                capture_output=True,
                text=True,
                timeout=timeout,
                check=True,
            )
        except subprocess.TimeoutExpired:
            return None
        except subprocess.CalledProcessError as error:
            last = (error.stderr or "").strip().splitlines()
            print(f"  pycapacity ({kind}) failed: {last[-1] if last else 'no message'}")
            return None
    return json.loads(child.stdout.strip().splitlines()[-1])["median_s"] * 1e3


# ---------------------------------------------------------------------------------------------


def run(quick: bool = False, timeout: float | None = None) -> int:
    """Measure, print the table and the targets; returns 0."""
    rng = np.random.default_rng(20240607)
    count = 8 if quick else 40
    timeout = timeout or (20.0 if quick else 120.0)
    rows, verdicts = [], []

    def row(label, ours_ms, theirs_ms=None, missing=""):
        if theirs_ms is None:
            rows.append((label, f"{ours_ms:.3f}", missing, ""))
            return
        speedup = theirs_ms / ours_ms
        rows.append((label, f"{ours_ms:.3f}", f"{theirs_ms:.3f}", f"{speedup:.1f}x"))
        verdicts.append((f"{label}: >= {SPEEDUP_TARGET:g}x faster than pycapacity ({speedup:.1f}x)", speedup >= 5.0))

    # warm-up: compiled facet kernel, HiGHS
    paper = mobmanip.load_robot("planar_dual_arm")
    q0 = configurations_within_limits(paper, rng, 1)[0]
    kin, dyn = _terms(paper, q0, "planar", None)
    _full(kinematic_polytope(*kin))
    _full(min_norm_dynamic_polytope(*dyn))

    for name, task, mass in (("planar_dual_arm", "planar", None), ("tiago_dual", "translational", 1.0)):
        robot = mobmanip.load_robot(name)
        terms = [_terms(robot, q, task, mass) for q in configurations_within_limits(robot, rng, count)]
        t_kin = _median_ms(lambda t: _full(kinematic_polytope(*t[0])), terms)
        t_dyn = _median_ms(lambda t: _full(dynamic_polytope(*t[1])), terms)
        t_min = _median_ms(lambda t: _full(min_norm_dynamic_polytope(*t[1])), terms)
        t_both = _median_ms(lambda t: (_full(kinematic_polytope(*t[0])), _full(dynamic_polytope(*t[1]))), terms)
        sections = [{"Wt": t[0][1].T, "J": t[0][0] * t[0][2], "lim": np.ones(len(t[0][2]))} for t in terms]
        late = f"> {timeout:g} s"
        row(f"{name} {task} kinematic (zonotope section)", t_kin, _pycapacity("section", sections, timeout), late)
        zonotopes = [{"G": dynamic_polytope(*t[1]).generators} for t in terms]
        theirs = _pycapacity("zonotope", zonotopes, timeout)
        row(f"{name} {task} dynamic, exact, from P, J_u, W, ...", t_dyn, None, "-")
        t_same = _median_ms(lambda z: _full(Polytope.zonotope(np.zeros(len(z["G"])), z["G"])), zonotopes)
        row(f"{name} {task} dynamic, exact, from its generators", t_same, theirs, late)
        row(f"{name} {task} dynamic, minimum-norm policy", t_min, None, "no counterpart")
        if name == "planar_dual_arm":
            row(f"{name} {task} kinematic + exact dynamic", t_both, None, "-")
            bound = TARGETS_MS[(name, "both")]
            verdicts.append((f"{name} both planar polytopes <= {bound:g} ms ({t_both:.3f})", t_both <= bound))
        else:
            bound = TARGETS_MS[(name, "kinematic")]
            verdicts.append((f"{name} {task} object-velocity polytope <= {bound:g} ms ({t_kin:.3f})", t_kin <= bound))

    # TIAGo++, spatial (m = 6): build with halfspaces, then one support query (warm)
    robot = mobmanip.load_robot("tiago_dual")
    terms = [_terms(robot, q, "spatial", 1.0) for q in configurations_within_limits(robot, rng, count)]
    directions = rng.normal(size=(200, 6))
    for label, build in (
        ("kinematic", lambda t: kinematic_polytope(*t[0])),
        ("dynamic, exact", lambda t: dynamic_polytope(*t[1])),
        ("dynamic, minimum-norm policy", lambda t: min_norm_dynamic_polytope(*t[1])),
    ):
        t_build = _median_ms(lambda t, build=build: build(t).halfspaces, terms)
        polys = [build(t) for t in terms]
        for p in polys:
            p.support(directions[0])
        support_times = []
        for p in polys:
            for d in directions[:50]:
                start = time.perf_counter()
                p.support(d)
                support_times.append(time.perf_counter() - start)
        t_support = float(np.median(support_times)) * 1e3
        row(f"tiago_dual spatial {label}: build + halfspaces", t_build, None, "-")
        row(f"tiago_dual spatial {label}: one support query", t_support, None, "-")
        verdicts.append((f"tiago_dual 6-D {label} support query <= 1 ms ({t_support:.4f})", t_support <= 1.0))
        if label == "dynamic, exact":
            zonotopes = [{"G": p.generators} for p in polys[: max(2, count // 10)]]
            theirs = _pycapacity("zonotope", zonotopes, timeout)
            label = "tiago_dual spatial dynamic, exact (pycapacity: + vertices)"
            row(label, t_build, theirs, f"> {timeout:g} s / failed")

    # One fixed-base arm, no object: pycapacity's own use case
    for name in ("ur5", "panda"):
        robot = mobmanip.load_robot(name)
        terms = [_terms(robot, q, "translational", 0.0) for q in configurations_within_limits(robot, rng, count)]
        t_vel = _median_ms(lambda t: _full(kinematic_polytope(*t[0])), terms)
        t_acc = _median_ms(lambda t: _full(dynamic_polytope(*t[1])), terms)
        vel = [{"J": t[0][0], "lim": t[0][2]} for t in terms]
        acc = [{"J": t[1][0], "M": t[1][2], "lim": t[1][7], "bias": -t[1][4]} for t in terms]
        late = f"> {timeout:g} s"
        row(f"{name} translational velocity polytope", t_vel, _pycapacity("velocity", vel, timeout), late)
        row(f"{name} translational acceleration polytope", t_acc, _pycapacity("acceleration", acc, timeout), late)

    print()
    print(f"capacity polytopes, ms per configuration (median over {count} random configurations, one run)")
    width = max(62, *(len(label) + 2 for label, *_ in rows))
    header = f"{'set':<{width}}{'mobmanip':>10}{'pycapacity':>16}{'speed-up':>10}"
    print(header)
    print("-" * len(header))
    for label, ours, theirs, ratio in rows:
        print(f"{label:<{width}}{ours:>10}{theirs:>16}{ratio:>10}")
    print(f"  (pycapacity's section method is iterative, to tol = {PYCAPACITY_TOL:g}; its time limit {timeout:g} s)")
    print()
    for text, ok in verdicts:
        print(f"  {text}: {'met' if ok else 'NOT met'}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--pycapacity-child":
        pycapacity_child(sys.argv[2], sys.argv[3])
    else:
        raise SystemExit(run("--quick" in sys.argv))
