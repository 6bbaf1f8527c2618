"""Omni wheels whose rollers are not at 45 deg: on the floor, an omnidirectional base's wheels push
nothing along their rollers' free directions, each direction worked out here from the spec's
angle (deg, from the platform's forward axis, counter-clockwise) and the platform's heading.

The mecanum bases elsewhere in the tests have their rollers at +-45 deg, where an angle measured
from the wrong axis gives the same line (cos 45 = sin 45): rollers at 30 and -60 deg tell the two
apart."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from mobmanip.postures.named import named_configuration
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor

ROOT = Path(__file__).resolve().parents[1]
ROLLERS = (30.0, -60.0, -60.0, 30.0)
HEADING = 1.0  # rad


@pytest.fixture(scope="module")
def grounded(tmp_path_factory):
    """The paper's arms on the omnidirectional base with these rollers, at (0.4, -0.3) m and a
    heading of 1 rad, holding 2 kg: its grounded dynamic polytope (mu = 0.5)."""
    text = (ROOT / "robots" / "planar_dual_arm_omni.toml").read_text()
    text = text.replace('urdf = "planar_dual_arm.urdf"', f'urdf = "{ROOT / "robots" / "planar_dual_arm.urdf"}"')
    text = text.replace("rollers = [45.0, -45.0, -45.0, 45.0]", f"rollers = {list(ROLLERS)}")
    assert f"rollers = {list(ROLLERS)}" in text
    spec = tmp_path_factory.mktemp("rollers") / "omni.toml"
    spec.write_text(text)
    robot = mobmanip.load_robot(spec)
    q = named_configuration(robot, "home")
    q[:4] = (0.4, -0.3, math.cos(HEADING), math.sin(HEADING))
    analysis = mobmanip.analyze(
        robot, q, "planar", object_mass=2.0, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    )
    return analysis.measures["dynamic_polytope"]


@pytest.mark.parametrize("axis", [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)])
def test_each_wheel_pushes_nothing_along_its_rollers(grounded, axis):
    e = np.array(axis)
    reach = grounded.straight_line_reach(e)
    assert reach > 0.0
    forces = grounded.straight_line_witness(e).variables[CONTACT_FORCES]
    contacts = [c for c in grounded.model["floor"]["contacts"] if c["driven"]]
    assert len(contacts) == len(ROLLERS)
    across = []
    for contact, angle in zip(contacts, ROLLERS):
        a, b = contact["columns"]
        f = forces[a : a + 2]
        turn = HEADING + math.radians(angle)
        free = np.array([math.cos(turn), math.sin(turn)])
        normal = np.array([-math.sin(turn), math.cos(turn)])
        assert abs(free @ f) <= 1e-6 * max(1.0, float(np.abs(forces[a:b]).max())), (contact["name"], axis)
        across.append(abs(normal @ f))
    assert max(across) > 1.0  # N: the wheels do push, across their rollers
