"""The optimal value's gradient with respect to the object centre (envelope theorem) against
central differences of the re-optimised value."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

import mobmanip
from mobmanip.gradients import GradientEvaluator
from mobmanip.placement import Region, object_gradient, place
from mobmanip.placement.maps import newton_project
from mobmanip.placement.optimize import PlacementProblem, slsqp_constraints

STEP = 1e-4


def local_optimum(robot, objective, target, z0, region=None, mass=None):
    """The value of a local SLSQP from z0 (moved onto the hold at ``target``), to ftol 1e-14."""
    ev = GradientEvaluator(robot, objective, object_mass=mass)
    problem = PlacementProblem(robot, ev, np.asarray(target, dtype=float), region, robot.hold_configuration())
    bounds = problem.bounds()
    z = newton_project(problem, z0, bounds)
    res = minimize(problem.objective, z, jac=True, method="SLSQP", bounds=bounds,
                   constraints=slsqp_constraints(problem), options={"maxiter": 300, "ftol": 1e-14})  # fmt: skip
    assert problem.residual(res.x) < 1e-8
    return -res.fun


@pytest.mark.parametrize(
    "name, objective, target, mass, region",
    [
        ("planar_dual_arm", "kinematic:log_volume", [1.0, 0.5, 0.35], None, Region(0.0, 0.2, 0.0, 0.2)),
        ("tiago_dual", "dynamic:log_volume", [2.0, 1.0, 0.85], 2.0, None),
    ],
    ids=["paper_in_a_region", "tiago_height"],
)
def test_object_gradient_equals_differences_of_the_optimum(name, objective, target, mass, region):
    """The paper's robot with its platform pushed against a region's corner (the value then
    depends on where the object is horizontally) and TIAGo++ free (only the height matters; any
    horizontal shift is followed by the platform, so that gradient is zero): the gradient equals
    central differences of the re-optimised value to 1e-5 relative; the planar arms cannot follow
    the object vertically (NaN)."""
    robot = mobmanip.load_robot(name)
    result = place(robot, target, objective, starts=4, tolerance=1e-14, object_mass=mass, region=region)
    g = object_gradient(robot, result, object_mass=mass, region=region)
    problem = PlacementProblem(robot, GradientEvaluator(robot, objective, object_mass=mass), result.target, region,
                       robot.hold_configuration())  # fmt: skip
    z = problem.variables(result.q, result.hold_turn)
    fd = np.full(3, np.nan)
    for k in range(3):
        if np.isnan(g[k]):
            continue
        e = np.zeros(3)
        e[k] = STEP
        fd[k] = (local_optimum(robot, objective, result.target + e, z, region, mass)
                 - local_optimum(robot, objective, result.target - e, z, region, mass)) / (2 * STEP)  # fmt: skip
    if name == "planar_dual_arm":
        assert np.isnan(g[2]) and np.all(np.isfinite(g[:2]))
        assert np.linalg.norm(g[:2]) > 0.1
    else:
        assert np.all(np.isfinite(g)) and abs(g[2]) > 0.1
    ok = ~np.isnan(g)
    np.testing.assert_allclose(g[ok], fd[ok], rtol=1e-5, atol=1e-5 * np.abs(fd[ok]).max())
