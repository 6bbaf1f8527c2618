"""Shared fixtures: the paper's robot, a seeded random generator, random configurations, URDF variants."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "robots"
PAPER_URDF = ROBOTS / "planar_dual_arm.urdf"
PAPER_SPEC = ROBOTS / "planar_dual_arm.toml"

# Table 2 of the paper.
WHEEL_RADIUS = 0.075
HALF_TRACK = 0.171


@pytest.fixture(scope="session")
def robot():
    """The paper's two-arm differential-drive robot (built-in ``planar_dual_arm``)."""
    return mobmanip.load_robot("planar_dual_arm")


@pytest.fixture(scope="session")
def paper(robot):
    """The paper's robot again, by the name the tests that also load other robots give it."""
    return robot


@pytest.fixture(scope="session")
def posture(robot):
    """The paper's optimal arm posture (its case study's, :func:`mobmanip.casestudy.optimal_posture`)."""
    from mobmanip.casestudy import optimal_posture

    return optimal_posture(robot)


@pytest.fixture(scope="session")
def tiago():
    """PAL's TIAGo++ (built-in ``tiago_dual``)."""
    return mobmanip.load_robot("tiago_dual")


@pytest.fixture
def rng():
    """A fresh generator with a fixed seed, so every test sees the same draws."""
    return np.random.default_rng(20240607)


def paper_case(angle_deg):
    """The paper's robot in its optimal posture holding the object at ``angle_deg`` (its case
    study): (robot, q)."""
    from mobmanip.casestudy import configuration_at, optimal_posture

    robot = mobmanip.load_robot("planar_dual_arm")
    return robot, configuration_at(robot, optimal_posture(robot), angle_deg)


def random_configuration(robot, rng, xy_range=3.0):
    """A random configuration: platform pose and every joint angle drawn from ``rng``.

    ``pin.randomConfiguration`` cannot be used for the platform (the planar joint's x, y
    limits may be infinite), so x, y, yaw come from ``rng``; every other joint angle is
    uniform in [-pi, pi] (wheels included).
    """
    model = robot.model
    q = pin.neutral(model)
    x, y = rng.uniform(-xy_range, xy_range, size=2)
    yaw = rng.uniform(-math.pi, math.pi)
    q[:4] = (x, y, math.cos(yaw), math.sin(yaw))
    for j in range(2, model.njoints):
        set_joint(q, model.joints[j], rng.uniform(-math.pi, math.pi))
    return q


def random_configurations(robot, rng, count):
    return [random_configuration(robot, rng) for _ in range(count)]


def configuration_within_limits(robot, rng, xy_range=2.0, one_turn=True):
    """A random configuration that respects the joint limits, drawn from ``rng``: the platform
    anywhere in a square of half-side ``xy_range`` (m) at any heading, each joint uniform between
    its limits, a full turn [-pi, pi] where it has none (continuous joints included).

    ``one_turn`` also keeps a joint whose range is wider than a turn within [-pi, pi].
    """
    model = robot.model
    q = pin.neutral(model)
    yaw = rng.uniform(-math.pi, math.pi)
    q[:4] = (*rng.uniform(-xy_range, xy_range, size=2), math.cos(yaw), math.sin(yaw))
    for j in range(2, model.njoints):
        joint = model.joints[j]
        lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
        if joint.nq == 2:  # continuous
            lo, hi = -math.pi, math.pi
        elif one_turn:
            lo, hi = max(lo, -math.pi), min(hi, math.pi)
        elif not (np.isfinite(lo) and np.isfinite(hi)):
            lo, hi = -math.pi, math.pi
        set_joint(q, joint, rng.uniform(lo, hi))
    return q


def set_joint(q, joint, value):
    """Write one joint's value into q (in place), here rather than by mobmanip: a continuous joint
    (two coordinates) as the cosine and sine of its angle, any other as it is."""
    if joint.nq == 2:
        q[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
    else:
        q[joint.idx_q] = value


def central_differences(f, model, q, step):
    """The derivative of ``f`` (q -> array) along each tangent direction at q, by central
    differences through ``pin.integrate``: (f's shape, nv), the direction last."""
    columns = []
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = step
        columns.append((f(pin.integrate(model, q, e)) - f(pin.integrate(model, q, -e))) / (2 * step))
    return np.stack(columns, axis=-1)


def set_joints(model, q, values):
    """Write each named joint's value into q (in place, :func:`set_joint`); returns q."""
    for name, value in values.items():
        set_joint(q, model.joints[model.getJointId(name)], value)
    return q


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium through Playwright (:mod:`browser_util`), one per test module; the
    module's browser tests are skipped where either is missing."""
    from browser_util import chromium, missing_browser

    reason = missing_browser()
    if reason is not None:
        pytest.skip(f"browser tests need Chromium and Playwright: {reason}")
    with chromium() as b:
        yield b


def write_variant(tmp_path: Path, urdf_text: str, spec_edits=(), name="variant") -> Path:
    """Write a URDF and a copy of the paper's spec pointing at it; return the spec path.

    ``spec_edits`` are ``(old, new)`` replacements applied to the spec text (each must match).
    """
    urdf_path = tmp_path / f"{name}.urdf"
    urdf_path.write_text(urdf_text)
    spec = PAPER_SPEC.read_text()
    assert 'urdf = "planar_dual_arm.urdf"' in spec
    spec = spec.replace('urdf = "planar_dual_arm.urdf"', f'urdf = "{urdf_path.name}"')
    for old, new in spec_edits:
        assert old in spec, old
        spec = spec.replace(old, new)
    spec_path = tmp_path / f"{name}.toml"
    spec_path.write_text(spec)
    return spec_path


def replace_joint_block(urdf_text: str, joint: str, old: str, new: str) -> str:
    """Replace ``old`` by ``new`` inside the ``<joint name="joint">...</joint>`` element only."""
    pattern = re.compile(rf'<joint name="{joint}".*?</joint>', re.S)
    match = pattern.search(urdf_text)
    assert match is not None, joint
    block = match.group(0)
    assert old in block, (joint, old)
    return urdf_text[: match.start()] + block.replace(old, new) + urdf_text[match.end() :]


def flipped_wheel_urdf(side: str = "left") -> str:
    """The paper's URDF with one wheel's axis written as ``0 -1 0``."""
    return replace_joint_block(
        PAPER_URDF.read_text(), f"wheel_{side}_joint", '<axis xyz="0 1 0"/>', '<axis xyz="0 -1 0"/>'
    )


#: Axle centre of the offset variant, in the base_link frame (m).
OFFSET_AXLE = (-0.2, 0.05)


def offset_axle_urdf() -> str:
    """The paper's URDF with the wheel axle moved to OFFSET_AXLE (P_o no longer at base_link)."""
    text = PAPER_URDF.read_text()
    px, py = OFFSET_AXLE
    text = replace_joint_block(
        text, "wheel_right_joint", 'origin xyz="0 -0.171 0"', f'origin xyz="{px!r} {py - HALF_TRACK!r} 0"'
    )
    text = replace_joint_block(
        text, "wheel_left_joint", 'origin xyz="0 0.171 0"', f'origin xyz="{px!r} {py + HALF_TRACK!r} 0"'
    )
    return text
