"""Hostile input, round 2 (class 9): heavy objects within the documented range (up to 1e6 kg)
are a normal question. The dynamic polytopes are computed (empty where the limits cannot hold the
load), their vertices finite and the same set as their support function says; nothing is refused."""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from hostile_util import NON_FINITE, run_cli
from mobmanip.postures.named import named_configuration

MASSES = (2.0, 150.0, 300.0, 500.0, 700.0, 1000.0, 1e4, 1e6)


@pytest.mark.parametrize("mass", MASSES)
def test_heavy_objects_give_finite_dynamic_polytopes(mass):
    robot = mobmanip.load_robot("planar_dual_arm")
    analysis = mobmanip.analyze(
        robot, named_configuration(robot, "home"), object_mass=mass, measures=("dynamic_polytope",)
    )
    polytope = analysis.measures["dynamic_polytope"]
    if polytope.empty:
        return
    V = polytope.vertices
    assert len(V) >= 3 and np.all(np.isfinite(V))
    A, b = polytope.halfspaces
    scale = max(1.0, float(np.abs(V).max()))
    assert np.all(A @ V.T <= b[:, None] + 1e-9 * scale)  # every vertex inside every facet
    angles = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    # the vertices span the set the support function describes (computed from the generators)
    assert np.allclose((directions @ V.T).max(axis=1), polytope.supports(directions), rtol=1e-9, atol=1e-9 * scale)


@pytest.mark.parametrize("mass", ["150", "300", "1000", "1e6"])
def test_analyze_polytope_with_a_heavy_object_succeeds(capfd, mass):
    code, out, err = run_cli(capfd, "analyze", "planar_dual_arm", "--polytope", "--object-mass", mass)
    assert code == 0, err
    assert NON_FINITE.search(out) is None


def test_a_heavy_object_with_strong_wheels(capfd):
    code, out, err = run_cli(capfd, "analyze", "planar_dual_arm", "--polytope", "--object-mass", "1e6",
                             "--wheel-effort-limit", "1e7")  # fmt: skip
    assert code == 0, err
    assert NON_FINITE.search(out) is None
