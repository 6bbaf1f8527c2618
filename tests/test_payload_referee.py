"""The payload against MuJoCo: TIAGo++ at its hold posture, static, on a floor with mu 0.5.

The payload LP (``mobmanip.analysis.payload``) says how heavy an object the robot can hold with
every support loaded (equally stiff contacts) and, with a reserve R, every support keeping R of
its equal share. MuJoCo, a physics engine mobmanip does not contain, holds the robot and the
object with the LP's efforts (or the efforts of the paper's policy at other masses) and a joint
feedback, and says what the floor does.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from mobmanip.analysis.payload import payload
from mobmanip.motion.in_motion import motion_terms
from mobmanip.terms.constraints.floor import Floor

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def tiago():
    robot = mobmanip.load_robot("tiago_dual")
    return robot, mobmanip.named_configuration(robot, "hold")


def _referee(robot, q, mass):
    import mobmanip.referee as referee_package

    analysis = mobmanip.analyze(
        robot, q, "spatial", object_mass=mass, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    )
    info = analysis.measures["dynamic_polytope"].model["floor"]
    held = referee_package.object_for_referee(analysis.held_object)
    return referee_package.build(robot, q, contacts=referee_package.contacts_of_floor(info), object=held, mu=0.5)


def test_the_payload_with_a_reserve_is_held_for_a_second(tiago):
    """2.2437 kg with a 0.3 reserve (the back-left caster at its reserve, 49.19 N): MuJoCo holds
    it still for 1 s with the LP's efforts, every normal force equal to the LP's within 0.1 %,
    no wheel sliding, a joint feedback under 1e-4 N m."""
    robot, q = tiago
    found = payload(robot, q, "spatial", constraints=(Floor(mu=0.5, reserve=0.3),), static=True)
    assert found.mass == pytest.approx(2.2437, abs=1e-4)
    run = _referee(robot, q, found.mass).rollout(found.efforts, 1.0, feedback=(200.0, 20.0))
    assert not run.lifted and not run.slipping
    planned = np.array([c["normal"] for c in found.floor["contacts"].values()])
    names = list(found.floor["contacts"])
    measured = run.normal.min(axis=0)[[next(k for k, s in enumerate(run.supports) if s.name == n) for n in names]]
    assert np.allclose(measured, planned, rtol=1e-3)
    assert run.slip_speed.max() < 1e-6 and run.feedback < 1e-4
    drift = np.linalg.norm(run.base_position[-1] - run.base_position[0])
    assert drift < 1e-4


@pytest.mark.parametrize("factor, lifts", [(0.9, False), (1.1, True)])
def test_the_payload_without_a_reserve_is_where_a_support_lifts(tiago, factor, lifts):
    """Without a reserve the payload is 9.638 kg, where the back-left caster unloads. Holding 90 %
    of it (efforts of the paper's policy, within every limit) MuJoCo keeps all six supports
    loaded; holding 110 % (still within every effort limit) a back caster lifts. A 0.3 reserve is
    a margin, not a limit: 110 % of that payload is still held (measured: 47.7 N left on the
    caster)."""
    robot, q = tiago
    found = payload(robot, q, "spatial", constraints=(Floor(mu=0.5),), static=True)
    assert found.mass == pytest.approx(9.638, abs=1e-3)
    mass = factor * found.mass
    tau = motion_terms(robot, q, np.zeros(robot.nx), "spatial", object_mass=mass).static_torques()
    assert np.all(np.abs(tau) <= np.asarray(robot.effort_limits))
    run = _referee(robot, q, mass).rollout(tau, 0.2, feedback=(200.0, 20.0))
    assert bool(run.lifted) == lifts
    if lifts:
        assert any("caster_back" in name for name in run.lifted)
    else:
        assert run.normal.min() > 5.0
