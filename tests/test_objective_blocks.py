"""Objectives per block (``dynamic:minor_axis:linear``): the index of the set's shadow on the
task's linear (or angular) rows, one unit each, as ``analyze`` reports per block.

Values are checked against the reference analysis (``analyze``'s sets projected on the rows,
their semi-axes by definition), gradients against central differences of those values through
``pin.integrate``, and the reverse chain against the forward one.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from mobmanip.analysis.single import analyze
from mobmanip.cli import main
from mobmanip.errors import ArgumentError
from mobmanip.gradients.evaluator import GradientEvaluator, Objective
from mobmanip.robot.tasks import get_task
from mobmanip.viz.labels import objective_label

STEP = 1e-5


def _reference(robot, q, objective: Objective, task: str) -> float:
    """The block's index from analyze's set: its shadow on the rows, semi-axes by definition."""
    shadow = analyze(robot, q, task, object_mass=2.0).measure(objective.ellipsoid).project(objective.rows)
    s = np.asarray(shadow.semi_axes, dtype=float)
    m = len(s)
    if objective.index == "minor_axis":
        return float(s[-1])
    if objective.index == "log_volume":
        return 0.5 * m * math.log(math.pi) - math.lgamma(0.5 * m + 1.0) + float(np.sum(np.log(s)))
    return float(np.mean(np.log(s**2)) - np.log(np.mean(s**2)))


def _configurations(robot, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q0 = robot.hold_configuration()
    out = []
    for _ in range(n):
        out.append(pin.integrate(robot.model, q0, 0.15 * rng.standard_normal(robot.model.nv)))
    return np.array(out)


@pytest.mark.parametrize(
    "text", ["dynamic:minor_axis:linear", "kinematic:minor_axis:linear", "kinematic:log_volume:angular",
             "dynamic:log_isotropy:linear"]
)  # fmt: skip
def test_block_objective_is_the_shadow_index_and_its_gradient_the_differences(tiago, text):
    objective = Objective.parse(text, "spatial")
    assert objective.rows == tuple(
        get_task("spatial").linear_rows if "linear" in text else get_task("spatial").angular_rows
    )
    assert objective.name == text
    ev = GradientEvaluator(tiago, objective, "spatial", object_mass=2.0)
    qs = _configurations(tiago, 4, 7)
    got = ev.batch(qs)
    assert got.defined.all()
    forward = ev.forward_chunk(qs)
    np.testing.assert_allclose(forward[0], got.value, rtol=1e-10)
    np.testing.assert_allclose(forward[1], got.gradient, rtol=1e-7, atol=1e-9 * np.abs(got.gradient).max())
    for q, value, gradient in zip(qs, got.value, got.gradient):
        assert value == pytest.approx(_reference(tiago, q, objective, "spatial"), rel=1e-9)
        fd = np.empty(tiago.model.nv)
        for k in range(tiago.model.nv):
            e = np.zeros(tiago.model.nv)
            e[k] = STEP
            plus = _reference(tiago, pin.integrate(tiago.model, q, e), objective, "spatial")
            minus = _reference(tiago, pin.integrate(tiago.model, q, -e), objective, "spatial")
            fd[k] = (plus - minus) / (2 * STEP)
        assert np.linalg.norm(gradient - fd) <= 1e-5 * np.linalg.norm(fd)


def test_the_linear_block_differs_from_the_whole_mixed_set(tiago):
    """On the spatial task the whole set's minor semi-axis mixes m/s^2 and rad/s^2; the linear
    block's is the smallest linear one, and at least the whole set's (a shadow only grows)."""
    q = tiago.hold_configuration()
    whole = GradientEvaluator(tiago, "dynamic:minor_axis", "spatial", object_mass=2.0)(q)[0]
    linear = GradientEvaluator(tiago, "dynamic:minor_axis:linear", "spatial", object_mass=2.0)(q)[0]
    assert linear >= whole
    assert objective_label(Objective.parse("dynamic:minor_axis:linear", "spatial"), "spatial") == (
        "dynamic minor semi-axis of the linear block (m/s$^2$)"
    )
    assert objective_label(Objective.parse("dynamic:minor_axis", "spatial"), "spatial").endswith(
        "(mixed: m/s$^2$, rad/s$^2$)"
    )


def test_block_objectives_refuse_what_they_cannot_mean():
    with pytest.raises(ArgumentError, match="no angular rows"):
        Objective.parse("kinematic:minor_axis:angular", "translational")
    with pytest.raises(ArgumentError, match="needs a direction, not a block"):
        Objective.parse("kinematic:capacity:linear", "spatial")
    with pytest.raises(ArgumentError, match="block must be one of"):
        Objective("kinematic", "minor_axis", block="upper", rows=(0,))


def test_place_refuses_a_block_the_task_lacks(capsys):
    argv = ["place", "tiago_dual", "--object", "2,1,0.9", "--task", "translational"]
    assert main([*argv, "--objective", "dynamic:minor_axis:angular"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mobmanip: error: ") and "no angular rows" in err[0]
