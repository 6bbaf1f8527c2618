"""The floor for every platform kind (issue 35, items 2 and 6): a skid-steer (a Husky carrying a
KUKA iiwa, composed by ``init-spec --mount``; PAL's TIAGo Pro), a steered tricycle, and an
omnidirectional base whose wheels are not joints of the file (the paper's arms on a planar-joint
base with four mecanum wheels from ``[support] wheels`` and ``rollers``).

Each grounded reading (support and straight-line reach along every task axis, both senses) on
three floors (no tip-over only; mu = 0.5 with compliant sharing; mu = 0.5 with any sharing) equals
the independent whole-robot LP of tests/floor_reference.py: the free-flyer Pinocchio model from
the URDF, every wheel's contact with its own Jacobian, each kind's actuation written there from
the kind's mechanism (a side's effort shared by its wheels, a tricycle's rear wheels rolling free,
an omnidirectional base moved by the floor's traction alone) and the statement that the floor's
forces do no work along the platform's motions (a skid-steer's sideways forces held to none at
rest). The robots stand at a heading of 1 rad away from the origin, and the floor binds (the
grounded reaches are below the ideal ones somewhere)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import floor_reference as fr
import mobmanip
from mobmanip.postures.named import named_configuration
from mobmanip.robot.support import robot_support
from mobmanip.robot.tasks import get_task
from mobmanip.terms.constraints.floor import Floor

ROOT = Path(__file__).resolve().parents[1]
REL = 1e-6

#: the omnidirectional base's wheels: a mecanum wheel at each corner of the paper robot's base,
#: on its floor (0.075 m below base_link), its rollers' free direction at +-45 deg
OMNI_SUPPORT = """
[support]
wheels = [[0.25, -0.2, -0.075], [0.25, 0.2, -0.075], [-0.25, -0.2, -0.075], [-0.25, 0.2, -0.075]]
rollers = [45.0, -45.0, -45.0, 45.0]
"""


def omni_spec(directory: Path) -> Path:
    text = (ROOT / "robots" / "planar_dual_arm_omni.toml").read_text()
    text = text[: text.index("[support]")]  # its own wheels, wider apart than the built-in's
    text = text.replace('urdf = "planar_dual_arm.urdf"', f'urdf = "{ROOT / "robots" / "planar_dual_arm.urdf"}"')
    path = directory / "omni.toml"
    path.write_text(text + OMNI_SUPPORT)
    return path


def husky_iiwa_spec(directory: Path) -> Path:
    """The Husky carrying the iiwa, as ``init-spec --mount`` composes it (side limits as the hand-
    merged robot of tests/test_skid_steer.py)."""
    pybullet_data = pytest.importorskip("pybullet_data", reason="the Husky and iiwa URDFs ship with pybullet")
    from test_skid_steer import SIDE_SPEED, SIDE_TORQUE

    data = Path(pybullet_data.getDataPath())
    spec = directory / "husky_iiwa.toml"
    run = subprocess.run(
        [sys.executable, "-m", "mobmanip", "init-spec", "--mount", str(data / "kuka_iiwa" / "model.urdf"),
         "--on", str(data / "husky" / "husky.urdf"), "--at", "0.15,0,0.01,0", "--on-link", "top_plate_link",
         "--ee", "lbr_iiwa_link_7", "--out", str(spec), "--wheel-velocity-limit", str(SIDE_SPEED),
         "--wheel-effort-limit", str(SIDE_TORQUE)],
        capture_output=True, text=True,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    return spec


def tricycle_spec(directory: Path) -> Path:
    from test_steered import write_tricycle

    return write_tricycle(directory)


def _pose(robot, q, joints=None):
    """q at (0.4, -0.3) m, heading 1 rad, with the named joints set."""
    q = q.copy()
    q[:4] = (0.4, -0.3, math.cos(1.0), math.sin(1.0))
    for name, value in (joints or {}).items():
        q[robot.model.joints[robot.model.getJointId(name)].idx_q] = value
    return q


IIWA_BENT = {"lbr_iiwa_joint_2": 0.6, "lbr_iiwa_joint_4": -1.2, "lbr_iiwa_joint_6": 0.5}
TRICYCLE_POSE = {"steer_joint": 0.4, "arm_2": 0.3, "arm_3": -0.6}
#: name -> (spec maker or built-in name, task, object mass kg, joints to set)
KINDS = {
    "husky_iiwa": (husky_iiwa_spec, "translational", 2.0, IIWA_BENT),
    "tiago_pro": ("tiago_pro", "planar", 1.0, {}),
    "tricycle": (tricycle_spec, "translational", 1.0, TRICYCLE_POSE),
    "omni": (omni_spec, "planar", 2.0, {}),
}
FLOORS = {
    "no tip-over": (Floor(mu=None), "no_tip", {}),
    "mu 0.5": (Floor(mu=0.5), "friction", {"mu": 0.5, "springs": True}),
    "mu 0.5, any": (Floor(mu=0.5, load="any"), "friction", {"mu": 0.5}),
}


@pytest.fixture(scope="module")
def kinds(tmp_path_factory):
    out = {}
    for name, (source, task, mass, joints) in KINDS.items():
        spec = source if isinstance(source, str) else source(tmp_path_factory.mktemp(name))
        robot = mobmanip.load_robot(spec)
        q = _pose(robot, named_configuration(robot, "home"), joints)
        ideal = mobmanip.analyze(robot, q, task, object_mass=mass, measures=("dynamic_polytope",))
        out[name] = (robot, q, task, mass, ideal)
    return out


def _reference_casters(robot) -> tuple:
    """The supports that are not wheel joints, where the spec and file put them (the one input the
    reference shares: where the contacts are, and a mecanum roller's free direction)."""
    return tuple(
        fr.SupportPoint(
            c.name, robot.model.names[1], np.asarray(c.point, dtype=float), c.source == "spec_wheel", c.free
        )
        for c in robot_support(robot).contacts
        if c.source != "wheel"
    )


@pytest.mark.parametrize("floor", list(FLOORS))
@pytest.mark.parametrize("name", list(KINDS))
def test_every_kind_on_the_floor_is_the_independent_lp(kinds, name, floor):
    robot, q, task, mass, ideal = kinds[name]
    chosen, mode, options = FLOORS[floor]
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=mass, measures=("dynamic_polytope",), constraints=(chosen,)
    ).measures["dynamic_polytope"]
    problem = fr.build_problem(robot, q, task, ideal.held_object, casters=_reference_casters(robot))
    m = len(get_task(task).rows)
    below = 0.0
    for e in [s * e for e in np.eye(m) for s in (1.0, -1.0)]:
        ours, ref = grounded.straight_line_reach(e), fr.straight_line(problem, e, mode=mode, **options).value
        assert abs(ours - ref) <= REL * max(abs(ref), 1.0), (name, floor, e, ours, ref)
        ours, ref = grounded.support(e), fr.support(problem, e, mode=mode, **options).value
        assert abs(ours - ref) <= REL * max(abs(ref), 1.0), (name, floor, e, ours, ref)
        free = ideal.measures["dynamic_polytope"].straight_line_reach(e)
        below = max(below, (free - grounded.straight_line_reach(e)) / free)
    if mode == "friction":
        assert below > 0.01, (name, floor)  # the floor binds


@pytest.mark.parametrize("name", list(KINDS))
def test_every_kind_with_contacts_free_to_pull_is_its_ideal_set(kinds, name):
    robot, q, task, mass, ideal = kinds[name]
    relaxed = mobmanip.analyze(
        robot, q, task, object_mass=mass, measures=("dynamic_polytope",), constraints=(Floor(lift=True),)
    ).measures["dynamic_polytope"]
    free = ideal.measures["dynamic_polytope"]
    m = len(get_task(task).rows)
    for e in [s * e for e in np.eye(m) for s in (1.0, -1.0)]:
        for reading in ("straight_line_reach", "support"):
            a, b = getattr(relaxed, reading)(e), getattr(free, reading)(e)
            assert abs(a - b) <= REL * max(abs(b), 1.0), (name, reading, e, a, b)


def test_the_reference_knows_what_each_kind_adds(kinds):
    """The reference's statement that the floor's forces do no work along the platform's motions
    is a condition only for the skid-steer: a rolling wheel's contact does none by itself
    (J_c S = 0 for the tricycle's wheels), a skid-steer's off-axle wheels scrub when it turns, and
    an omnidirectional base's contacts move with it (their work is its effort)."""
    for name, expect_zero in (("tricycle", True), ("husky_iiwa", False), ("omni", False)):
        robot, q, task, _, ideal = kinds[name]
        problem = fr.build_problem(robot, q, task, ideal.held_object, casters=_reference_casters(robot))
        C, _ = fr.contact_force_columns(problem)
        work = np.abs(problem.S.T @ C).max()
        assert (work < 1e-12) == expect_zero, (name, work)


def test_a_mecanum_roller_pushes_nothing_along_its_free_direction(kinds):
    """At the omnidirectional base's +x maximum, every wheel's force along its rollers' free
    direction is zero, and without the rollers (traction in every direction) the base reaches
    at least as far."""
    robot, q, task, mass, _ = kinds["omni"]
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=mass, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    ).measures["dynamic_polytope"]
    e = np.array([1.0, 0.0])
    witness = grounded.witness_at(grounded.straight_line_reach(e) * e)
    forces = witness.variables["contact_forces"]
    info = grounded.model["floor"]
    yaw = info["pose"][2]
    for contact, angle in zip(info["contacts"], (45.0, -45.0, -45.0, 45.0)):
        a, b = contact["columns"]
        free = np.array([math.cos(yaw + math.radians(angle)), math.sin(yaw + math.radians(angle))])
        assert abs(free @ forces[a : a + 2]) <= 1e-6 * max(1.0, np.abs(forces[a:b]).max())


def test_a_robot_described_twice_stands_the_same(kinds, tmp_path):
    """The Husky carrying the iiwa, composed by ``init-spec --mount`` and merged by hand into one
    URDF (tests/test_skid_steer.py): the same robot, so the same grounded reaches on every floor
    (its casters, wheels and every inertia come from two different files)."""
    from test_skid_steer import husky_with_arm, spec_text

    mounted, q, task, mass, _ = kinds["husky_iiwa"]
    (tmp_path / "husky_iiwa.toml").write_text(spec_text(husky_with_arm(tmp_path)))
    by_hand = mobmanip.load_robot(tmp_path / "husky_iiwa.toml")
    assert list(by_hand.model.names) == list(mounted.model.names)
    for floor in (Floor(mu=None), Floor(mu=0.5), Floor(mu=0.5, reserve=0.2)):
        sets = [
            mobmanip.analyze(
                r, q, task, object_mass=mass, measures=("dynamic_polytope",), constraints=(floor,)
            ).measures["dynamic_polytope"]
            for r in (mounted, by_hand)
        ]
        for e in [s * e for e in np.eye(3) for s in (1.0, -1.0)]:
            a, b = (p.straight_line_reach(e) for p in sets)
            assert abs(a - b) <= REL * max(abs(a), 1.0), (floor, e, a, b)
