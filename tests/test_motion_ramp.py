"""The floor in motion on a ramp (``CarryFloor(slope=, uphill=)``; ``carry``/``retime --slope``).

The platform's plane is the ramp's: the world's x, y and z are the ramp's own axes (z its normal)
and gravity leans. Every gravity a reference takes is worked out here from the ramp's slope and
uphill direction (:func:`_gravity`: the level floor's gravity turned by the ramp's rotation,
Rodrigues' formula), never read from the code under test: a gravity leaning the wrong way would
lean both sides alike.

References: standing still, the statics of the whole robot (the centre of mass of robot and
object seen along gravity on the ramp; the floor carries the weight's normal part) and the floor
at rest of the capacity sets on the same ramp (its verdict, its zero-moment point and its
compliant contact loads); in motion, the floor's resultant wrench assembled here at every grid
point of a retimed path from Pinocchio's centroidal momentum rate, the object's m a_o and the
weights under the test's own gravity, with the contact loads and the wheels' traction shared as
in tests/test_retime.py; time reversal (a path run backward down the ramp takes exactly as long
as up it).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.analysis.reaches import floor_at_rest
from mobmanip.errors import MobmanipError, NumericalError
from mobmanip.motion.carry_floor import CarryFloor, floor_rows
from mobmanip.motion.retime import path_rows, retime, stops_along
from mobmanip.motion.trajectory import read_trajectory, trajectory_from_samples
from mobmanip.postures.named import named_configuration
from mobmanip.robot.support import robot_support
from mobmanip.robot.tasks import get_task
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor, ground_reaction

MASS = 2.0
G = 9.81


def _gravity(slope: float, uphill: float) -> np.ndarray:
    """Gravity in a ramp's axes (m/s^2), (3,), from first principles: the ramp is the level floor
    turned by its slope s about the horizontal axis u x z, u = (cos a, sin a, 0) the uphill
    direction, so that u rises (to u cos s + z sin s); the world's gravity (0, 0, -9.81) seen in
    the turned axes is R^T g, R from Rodrigues' formula."""
    s, a = math.radians(slope), math.radians(uphill)
    u, z = np.array([math.cos(a), math.sin(a), 0.0]), np.array([0.0, 0.0, 1.0])
    k = np.cross(u, z)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    R = np.eye(3) + math.sin(s) * K + (1.0 - math.cos(s)) * K @ K
    np.testing.assert_allclose(R @ u, math.cos(s) * u + math.sin(s) * z, atol=1e-15)  # uphill rises
    return R.T @ np.array([0.0, 0.0, -G])


def _polygon_margin(polygon: np.ndarray, p: np.ndarray) -> float:
    """Signed distance of p to a convex polygon's nearest edge (positive inside), by hand."""
    polygon = np.asarray(polygon, dtype=float)
    edges = np.roll(polygon, -1, axis=0) - polygon
    area = np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1])
    inward = np.c_[-edges[:, 1], edges[:, 0]] * np.sign(area) / np.linalg.norm(edges, axis=1)[:, None]
    return float(np.min(np.einsum("ij,ij->i", inward, p - polygon)))


def _hands(robot, q) -> np.ndarray:
    model, data = robot.model, robot.model.createData()
    pin.framesForwardKinematics(model, data, q)
    return np.array([data.oMf[arm.frame_id].translation for arm in robot.arms])


def _still_path(robot, q):
    """Three samples at q, nothing moving: a path's grid point standing still."""
    n = 3
    zero = np.zeros((n, robot.nx))
    return trajectory_from_samples(robot, np.arange(float(n)), np.tile(q, (n, 1)), zero, zero)


# ----- (a) standing still: the floor in motion is the floor at rest -----

#: (slope, uphill) deg -> what breaks standing still (None: it stands). Facing down a 5 deg ramp
#: TIAGo++'s back casters unload (the equally stiff contacts share it so); on a 10 deg ramp rising
#: towards -60 deg its left wheel's motor cannot hold it.
STILL = {
    (0.0, 0.0): None,
    (5.0, 0.0): None,
    (5.0, 90.0): None,
    (3.0, -135.0): None,
    (5.0, 180.0): {"support caster_back_right_2_link loaded", "support caster_back_left_2_link loaded"},
    (10.0, -60.0): {"effort wheel_left_joint"},
}


@pytest.mark.parametrize("ramp", list(STILL))
def test_standing_still_on_a_ramp_the_motion_floor_is_the_floor_at_rest(tiago, ramp):
    """TIAGo++ in its hold posture holding 2 kg, nothing moving, tip-over and loads only (the
    traction splits of the two models differ by design). The rows of ``retime`` at s' = s'' = 0
    and of a ``carry`` step at x = x_prev = 0 hold exactly where the floor at rest lets the robot
    stand perfectly still, and break the same way where it does not; the zero-moment point they
    keep is the statics' (the centre of mass of robot and object seen along the test's gravity),
    its margin the floor at rest's, and each support's compliant load the floor at rest's, the
    loads adding up to the weight's normal part (M + m) g cos s."""
    slope, uphill = ramp
    q = named_configuration(tiago, "hold")
    gravity = _gravity(slope, uphill)
    at_rest = Floor(mu=None, load="compliant", slope=slope, uphill=uphill)
    analysis = mobmanip.analyze(tiago, q, "spatial", object_mass=MASS, measures=("dynamic_polytope", "force_polytope"),
                                constraints=(at_rest,))  # fmt: skip
    rest = floor_at_rest(analysis.measures["dynamic_polytope"])
    floor = CarryFloor(mu=None, zmp_margin=0.0, slope=slope, uphill=uphill)
    rows = path_rows(tiago, _still_path(tiago, q), "spatial", object_mass=MASS, floor=floor)[1]
    G_step, g_step, labels = floor_rows(tiago, q, np.zeros(tiago.nx), 0.1, get_task("spatial"), MASS, floor)

    broken = {label for label, d in zip(rows.labels, rows.d) if d < 0.0}
    assert rest["still"] is (STILL[ramp] is None)
    assert broken == (STILL[ramp] or set())
    # the carry step's floor rows at x = 0 are the path's floor rows standing still
    on_floor = np.array([kind in ("tip-over", "contact") for kind in rows.kinds])
    assert [label for label, keep in zip(rows.labels, on_floor) if keep] == labels
    np.testing.assert_allclose(g_step, rows.d[on_floor], rtol=1e-10, atol=1e-9)

    # the statics, from first principles
    mass = pin.computeTotalMass(tiago.model)
    normal = -(mass + MASS) * gravity[2]  # the floor carries the weight's normal part
    assert normal == pytest.approx((mass + MASS) * G * math.cos(math.radians(slope)), rel=1e-14)
    c = mass * pin.centerOfMass(tiago.model, tiago.model.createData(), q) + MASS * _hands(tiago, q).mean(axis=0)
    c /= mass + MASS
    support = robot_support(tiago)
    seen = c[:2] - (c[2] - support.floor_z) * gravity[:2] / gravity[2]  # along gravity onto the ramp
    polygon = support.polygon((0.0, 0.0, 0.0))
    # each edge's row at rest is F_z (its distance inside): their least over F_z is the margin
    tip = np.array([kind == "tip-over" for kind in rows.kinds])
    margin = float(rows.d[tip].min() / normal)
    assert margin == pytest.approx(_polygon_margin(polygon, seen), abs=1e-9)
    loads = {label.split()[1]: d for label, d, kind in zip(rows.labels, rows.d, rows.kinds) if kind == "contact"}
    assert sum(loads.values()) == pytest.approx(normal, rel=1e-10)
    if rest["still"]:
        assert rest["margin"] == pytest.approx(margin, abs=1e-9)
        F = analysis.measures["force_polytope"]
        reaction = ground_reaction(F.model["floor"], F.witness_at(np.zeros(6)).variables[CONTACT_FORCES])
        for name, load in loads.items():
            assert load == pytest.approx(reaction["contacts"][name]["normal"], rel=1e-8, abs=1e-8 * normal)
    else:
        with pytest.raises(NumericalError, match="cannot be passed at rest|cannot start from rest|no timing"):
            retime(tiago, _still_path(tiago, q), "spatial", object_mass=MASS, floor=floor)


def test_the_efforts_on_a_ramp_are_pinocchios_with_its_gravity_turned(tiago):
    """Standing still on a 5 deg ramp rising towards 120 deg, the efforts ``retime`` keeps (no
    object) are Pinocchio's generalized gravity of a model whose gravity is the test's, through
    S: the wheels' motors hold the weight's share along the ramp."""
    q = named_configuration(tiago, "hold")
    model = tiago.model.copy()
    model.gravity = pin.Motion(np.r_[_gravity(5.0, 120.0), 0.0, 0.0, 0.0])
    generalized = pin.computeGeneralizedGravity(model, model.createData(), q)
    expected = np.linalg.solve(tiago.Q, tiago.null_space(q).T @ generalized)
    floor = CarryFloor(mu=None, zmp_margin=0.0, slope=5.0, uphill=120.0)
    rows = path_rows(tiago, _still_path(tiago, q), "spatial", object_mass=0.0, floor=floor)[1]
    effort = np.array([kind == "effort" for kind in rows.kinds])
    limits = np.asarray(tiago.effort_limits, dtype=float)
    static = limits - rows.d[effort][: tiago.nx]  # d = limit - static on the upper rows
    np.testing.assert_allclose(static, expected, rtol=0, atol=1e-10 * np.abs(expected).max())
    level = path_rows(tiago, _still_path(tiago, q), "spatial", object_mass=0.0, floor=CarryFloor(mu=None))[1]
    assert np.abs(static - (limits - level.d[effort][: tiago.nx])).max() > 1.0  # N m: the lean matters


# ----- (b) a retimed path on a 5 deg ramp -----


def _straight(robot, n=61, length=1.5, backward=False):
    """TIAGo++ driving straight along +x (heading 0), 0.5 m per unit of s, arms still; backward:
    the same path run the other way (from its end to its start, the robot facing +x)."""
    home = robot.hold_configuration()
    s = np.linspace(0.0, length / 0.5, n)
    q = np.tile(home, (n, 1))
    q[:, 0] = home[0] + (0.5 * s[::-1] if backward else 0.5 * s)
    known = [name for name in robot.joint_names if "wheel" not in name]
    return trajectory_from_samples(robot, s, q, known_joints=known)


FLOOR = dict(mu=0.5, zmp_margin=0.02, reserve=0.1)


@pytest.fixture(scope="module")
def timed(tiago):
    """Retimings of the straight drive: level, up a 5 deg ramp rising along +x, and backward down
    it (the same path run from its end), reserve 0.1."""
    up, down = _straight(tiago), _straight(tiago, backward=True)
    return {
        "level": retime(tiago, up, object_mass=MASS, floor=CarryFloor(**FLOOR)),
        "uphill": retime(tiago, up, object_mass=MASS, floor=CarryFloor(**FLOOR, slope=5.0)),
        "downhill": retime(tiago, down, object_mass=MASS, floor=CarryFloor(**FLOOR, slope=5.0)),
        "path": up,
    }


def test_uphill_is_slower_than_level_and_downhill_backward_takes_as_long(tiago, timed):
    """Driving 1.5 m up a 5 deg ramp takes longer than on the level floor (measured 3.262 s
    against 2.822 s): the wheels' motors bind (effort rows), and on the ramp they also hold the
    weight's share along it, (M + m) g sin 5 deg, so the run accelerates with that much less
    effort and brakes with that much more; a rest-to-rest time, like T = sqrt(2 L (1/a1 + 1/a2)),
    grows as the two part. Backward down the ramp (the same path run the other way) takes exactly
    as long: reversed in time, a motion has the same accelerations at the same configurations
    (velocity terms are quadratic), so its rows are the same. What differs is the stop: from
    0.92 m/s up the ramp the robot stops within 0.3 m, down it from 0.46 m/s only (gravity helps
    braking uphill and hinders it downhill); the level floor's 0.58 m/s lies between."""
    level, uphill, downhill = timed["level"], timed["uphill"], timed["downhill"]
    assert uphill.duration > 1.1 * level.duration
    assert downhill.duration == pytest.approx(uphill.duration, rel=1e-9)
    assert "effort" in uphill.binding_kind
    assert uphill.floor["slope"] == 5.0 and uphill.floor["uphill"] == 0.0
    path = timed["path"]
    stops = {
        name: stops_along(tiago, p, 0.3, object_mass=MASS, floor=CarryFloor(**FLOOR, slope=slope)).to_dict()
        for name, p, slope in (("level", path, 0.0), ("uphill", path, 5.0),
                               ("downhill", _straight(tiago, backward=True), 5.0))
    }  # fmt: skip
    speeds = {name: stop["lowest_base_speed"] for name, stop in stops.items()}
    assert speeds["downhill"] < speeds["level"] < speeds["uphill"], speeds
    # the reserve's contact rows bind on the level floor: its back casters carry least, and the
    # ramp's lean loads them (uphill is behind them)
    assert level.binding_kind.count("contact") > uphill.binding_kind.count("contact")


def _wrench(robot, q, x, xdot, gravity):
    """The floor's resultant wrench on TIAGo++ and its 2 kg object (force; moment about the world
    origin), assembled here: Pinocchio's centroidal momentum rate at qdd = S xdot (the heading
    does not change along the straight drive, so S does not), the object's m a_o at the hands'
    midpoint (it moves with the hands, without turning), less the weights under ``gravity``."""
    model, data = robot.model, robot.model.createData()
    S = robot.null_space(q)
    v, a = S @ x, S @ xdot
    pin.computeCentroidalMomentumTimeVariation(model, data, q, v, a)
    c, rate = data.com[0].copy(), data.dhg
    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    hands = np.array([data.oMf[arm.frame_id].translation for arm in robot.arms])
    frames = [arm.frame_id for arm in robot.arms]
    world = pin.LOCAL_WORLD_ALIGNED
    a_o = np.mean([pin.getFrameClassicalAcceleration(model, data, f, world).linear for f in frames], axis=0)
    c_o, mass = hands.mean(axis=0), pin.computeTotalMass(model)
    force = rate.linear + MASS * a_o - (mass + MASS) * gravity
    moment = (rate.angular + np.cross(c, rate.linear) + MASS * np.cross(c_o, a_o)
              - np.cross(c, mass * gravity) - np.cross(c_o, MASS * gravity))  # fmt: skip
    return force, moment


def _loads_and_traction(support, pose, force, moment):
    """Equally stiff contacts under a rigid platform (a plane of compressions balancing F_z and
    the moments about the ramp's plane) and the driven wheels' tangential forces (the least-norm
    split of F_x, F_y and the yaw moment, the casters rolling freely), as tests/test_retime.py."""
    points = support.world_points(pose)
    z = support.floor_z
    A = np.c_[np.ones(len(points)), points[:, 0], points[:, 1]]
    balance = np.vstack([np.ones(len(points)), points[:, 1], -points[:, 0]])
    target = np.array([force[2], moment[0] + z * force[1], moment[1] - z * force[0]])
    loads = A @ np.linalg.solve(balance @ A, target)
    driven = [c for c, contact in enumerate(support.contacts) if contact.driven]
    B = np.zeros((3, 2 * len(driven)))
    B[0, 0::2], B[1, 1::2] = 1.0, 1.0
    B[2, 0::2], B[2, 1::2] = -points[driven, 1], points[driven, 0]
    split = np.linalg.lstsq(B, np.array([force[0], force[1], moment[2]]), rcond=None)[0]
    return loads, driven, split.reshape(-1, 2)


def test_up_the_ramp_the_floor_holds_at_every_grid_point(tiago, timed):
    """At every grid point of the retimed run up the 5 deg ramp, with the floor's wrench assembled
    here under the test's gravity: the zero-moment point on the ramp's plane at least 2 cm inside
    the support polygon, every support above its reserve (0.1 of its equal share of the weight's
    normal part, (M + m) g cos s / n) and each driven wheel's traction within 0.9 of its cone,
    mu times its load; and the floor binds (the least slack is zero to 1e-6)."""
    gravity = _gravity(5.0, 0.0)
    motion = timed["uphill"].trajectory
    support = robot_support(tiago)
    mass = pin.computeTotalMass(tiago.model)
    normal = (mass + MASS) * G * math.cos(math.radians(5.0))
    least = 0.1 * normal / len(support.contacts)
    margins, slack, traction = [], [], []
    for i in range(len(motion)):
        q = motion.q[i]
        force, moment = _wrench(tiago, q, motion.x[i], motion.xdot[i], gravity)
        pose = (q[0], q[1], math.atan2(q[3], q[2]))
        z = support.floor_z
        zmp = np.array([z * force[0] - moment[1], moment[0] + z * force[1]]) / force[2]
        margins.append(_polygon_margin(support.polygon(pose), zmp))
        loads, driven, tangential = _loads_and_traction(support, pose, force, moment)
        assert loads.sum() == pytest.approx(force[2], rel=1e-9)
        slack.append(float(loads.min() - least))
        traction.append(float((np.linalg.norm(tangential, axis=1) / (0.5 * 0.9 * loads[driven])).max()))
    assert min(margins) >= 0.02 - 1e-7
    assert min(slack) >= -1e-6 * normal
    assert max(traction) <= 1.0 + 1e-9
    assert min(slack) <= 1e-6 * normal  # a support at its reserve: the floor binds


# ----- the commands -----


def test_retime_and_carry_on_a_ramp_from_the_command_line(tiago, tmp_path):
    """``retime --ground --slope 5 --stop-within 0.3`` gives the API's duration and stops and its
    JSON records the ramp; ``carry --ground --slope 3 --uphill 20`` runs and records it; a ramp
    too steep is the floor's one-line error."""
    from mobmanip.commands.outputs import write_trajectory_csv

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "mobmanip", *map(str, args)], capture_output=True, text=True)

    path = _straight(tiago)
    source = write_trajectory_csv(tiago, tmp_path / "path.csv", path.t, path.q)
    run = cli("retime", "tiago_dual", source, "--object-mass", MASS, "--ground", "--mu", "0.5", "--reserve", "0.1",
              "--slope", "5", "--stop-within", "0.3", "--out", tmp_path / "r")  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "a ramp of 5 deg rising towards 0 deg" in run.stdout
    document = json.loads((tmp_path / "r" / "retime.json").read_text())
    assert document["floor"]["slope"] == 5.0 and document["floor"]["uphill"] == 0.0
    np.testing.assert_allclose(document["floor"]["gravity"], _gravity(5.0, 0.0), atol=1e-12)
    read = read_trajectory(tiago, source)  # the command's path, as it reads the file
    expected = retime(tiago, read, object_mass=MASS, floor=CarryFloor(**FLOOR, slope=5.0))
    assert document["duration"] == pytest.approx(expected.duration, rel=1e-9)
    stops = stops_along(tiago, read, 0.3, object_mass=MASS, floor=CarryFloor(**FLOOR, slope=5.0)).to_dict()
    assert document["stops"]["lowest_base_speed"] == pytest.approx(stops["lowest_base_speed"], rel=1e-9)

    short = tmp_path / "p.csv"
    short.write_text("t,x,y\n0,0,0\n2,0.3,0\n")
    run = cli("carry", "planar_dual_arm", "--path", short, "--ground", "--slope", "3", "--uphill", "20",
              "--prepare", "0", "--out", tmp_path / "c")  # fmt: skip
    assert run.returncode == 0, run.stderr
    floor = json.loads((tmp_path / "c" / "carry.json").read_text())["floor"]
    assert floor["slope"] == 3.0 and floor["uphill"] == 20.0
    bad = cli("retime", "tiago_dual", source, "--slope", "31")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "the floor's slope must be from 0 to 30 deg, got 31.0" in bad.stderr


def test_a_bad_ramp_is_refused_by_the_floors_one_check():
    for kwargs, message in (
        (dict(slope=45.0), "the carry floor's slope must be from 0 to 30 deg, got 45.0"),
        (dict(slope=-1.0), "the carry floor's slope must be from 0 to 30 deg"),
        (dict(slope=5.0, uphill=float("nan")), "the carry floor's uphill direction must be a finite angle"),
        (dict(slope=True), "the carry floor's slope must be a finite angle"),
    ):
        with pytest.raises(MobmanipError, match=message):
            CarryFloor(**kwargs)
