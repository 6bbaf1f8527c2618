"""The kinematic measures' gradient chain through the compiled row loops
(:func:`mobmanip.gradients.adjoint.kinematic_chunk_compiled`, Numba) against the stacked NumPy
chain it replaces where Numba is available (the reference, kept for machines without Numba):
values, gradients and the hands' frames equal to round-off on every robot shape the chain meets
(planar and spatial tasks, one and two arms, the object's grasp moving with the hands in a task
with rotations, block objectives), and a configuration whose rank the Gram bound cannot certify
left to the NumPy chain's SVD. The chain itself is checked against the forward chain and finite
differences in tests/test_gradients*.py and tests/test_gradient_adjoint.py, which now run it.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")
import mobmanip  # noqa: E402
from mobmanip.gradients.adjoint import gradient_chunk, kinematic_chunk_compiled  # noqa: E402
from mobmanip.gradients.evaluator import GradientEvaluator  # noqa: E402

CASES = [
    ("planar_dual_arm", None, "kinematic:capacity:+x"),
    ("planar_dual_arm", None, "kinematic:log_volume"),
    ("planar_dual_arm", None, "kinematic:log_isotropy"),
    ("planar_dual_arm", None, "kinematic:minor_axis"),
    ("tiago_dual", "spatial", "kinematic:log_volume"),  # the grasp moves with the hands: p_bar
    ("tiago_dual", "spatial", "kinematic:minor_axis:angular"),  # a block's shadow
    ("tiago_dual", "translational", "kinematic:capacity:1,1,0"),
    ("tiago", None, "kinematic:log_volume"),  # one arm
    ("stretch", None, "kinematic:capacity:+z"),
]


def _configurations(robot, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q0 = robot.hold_configuration()
    out = []
    for _ in range(count):
        q = robot.check_configuration(q0).copy()
        v = rng.normal(0.0, 0.15, robot.model.nv)
        import pinocchio as pin

        q = pin.integrate(robot.model, q, v)
        out.append(np.clip(q, robot.model.lowerPositionLimit, robot.model.upperPositionLimit))
    return np.array(out)


@pytest.mark.parametrize(("name", "task", "objective"), CASES)
def test_the_compiled_chain_equals_the_numpy_chain(name, task, objective):
    robot = mobmanip.load_robot(name)
    compiled = GradientEvaluator(robot, objective, task)
    reference = GradientEvaluator(robot, objective, task)
    assert compiled.tree is not None and compiled.tree.kernel is not None
    reference.tree.kernel = None  # the stacked NumPy forms
    qs = _configurations(robot, 5, seed=len(name) + len(objective))
    passes: list = []
    found = kinematic_chunk_compiled(compiled, compiled.tree, qs, passes)
    assert found is not None  # these configurations are certified full rank
    value, grad, ok = found
    ref_passes: list = []
    ref_value, ref_grad, ref_ok = gradient_chunk(reference, reference.tree, qs, ref_passes)
    assert ref_ok.all() and ok.all()
    assert np.allclose(value, ref_value, rtol=1e-12, atol=1e-12 * np.abs(ref_value).max())
    scale = np.abs(ref_grad).max()
    assert scale > 0.0
    assert np.abs(grad - ref_grad).max() <= 1e-11 * scale
    t, r = passes[0], ref_passes[0]
    for mine, theirs in ((t.positions + t.reference[:, None], r.positions + r.reference[:, None]),
                         (t.frame_rotations, r.frame_rotations), (t.frames, r.frames)):  # fmt: skip
        assert np.abs(mine - theirs).max() <= 1e-12 * max(1.0, float(np.abs(theirs).max()))


def test_a_row_is_the_same_alone_and_in_a_batch():
    robot = mobmanip.load_robot("tiago_dual")
    ev = GradientEvaluator(robot, "kinematic:log_volume", "spatial")
    qs = _configurations(robot, 6, seed=3)
    value, grad, _ = kinematic_chunk_compiled(ev, ev.tree, qs)
    for i in range(len(qs)):
        v1, g1, _ = kinematic_chunk_compiled(ev, ev.tree, qs[i : i + 1])
        assert v1[0] == value[i] and np.array_equal(g1[0], grad[i])


def test_an_uncertified_rank_is_left_to_the_numpy_chain():
    """The paper robot's arms stretched straight: the hands' Jacobian loses rank. The compiled
    chain declines (its Gram bound cannot certify the rank) and the chain answers as NumPy does:
    undefined there, with zero value and gradient."""
    robot = mobmanip.load_robot("planar_dual_arm")
    ev = GradientEvaluator(robot, "kinematic:log_volume", None)
    q = robot.hold_configuration().copy()
    arm_joints = [robot.model.joints[robot.model.getJointId(n)] for n in robot.model.names[1:] if "arm" in n]
    for joint in arm_joints:
        if "_1_" not in robot.model.names[joint.id]:
            q[joint.idx_q] = 0.0  # elbows and wrists straight
    qs = np.array([q, _configurations(robot, 1, seed=1)[0]])
    assert kinematic_chunk_compiled(ev, ev.tree, qs) is None
    value, grad, ok = gradient_chunk(ev, ev.tree, qs)
    reference = GradientEvaluator(robot, "kinematic:log_volume", None)
    reference.tree.kernel = None
    ref_value, ref_grad, ref_ok = gradient_chunk(reference, reference.tree, qs)
    assert not ok[0] and ok[1] and np.array_equal(ok, ref_ok)
    assert value[0] == 0.0 and not grad[0].any()
    assert np.array_equal(value, ref_value) and np.array_equal(grad, ref_grad)


def test_a_task_with_more_rows_than_the_robot_has_velocities_is_undefined():
    """Stretch (5 reduced velocities) in the spatial task (6 rows): its kinematic ellipsoid is
    flat in the task (analyze gives a zero semi-axis), so its log-volume has no value to climb:
    the chain says undefined (it used to solve the singular Jh Jh^T and report about -40)."""
    robot = mobmanip.load_robot("stretch")
    q = robot.hold_configuration()
    axes = mobmanip.analyze(robot, q, "spatial", measures=("kinematic",)).measures["kinematic"].semi_axes
    assert robot.nx == 5 and axes.min() <= 1e-12 * axes.max()
    ev = GradientEvaluator(robot, "kinematic:log_volume", "spatial")
    value, grad, ok = ev(q)
    assert not ok and value == 0.0 and not np.any(grad)
    assert GradientEvaluator(robot, "kinematic:log_volume", "translational")(q)[2]  # 3 rows: defined
