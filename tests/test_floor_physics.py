"""The grounded capacity replayed in MuJoCo (issue 24's referee): a physics engine no one here
wrote, built from the same URDF (tests/mujoco_referee.py), checks what mobmanip promises.

For each grounded axis maximum (straight-line reach, mu = 0.5, the default compliant sharing of
the weight), the efforts that reach 97 % of it with the least reduced acceleration among those
with at least half the most slack (:meth:`LiftedPolytope.witness_at` with ``least="xdot"``) are
applied from rest, to a referee whose supports are equally stiff (``equal_supports``):

- at t = 0 the object's acceleration is the predicted one within 3 % per component (components
  below 3 % of the acceleration's norm are held to 3 % of that norm), and every contact's normal
  force is the predicted one within 0.1 % of the weight (measured: at most 0.03 %);
- for 20 ms no support rises off the floor by more than 0.1 mm (soft contacts breathe by some
  0.01 mm as the load moves), the base turns by less than 5e-4 rad in roll and pitch, and no
  driven wheel slips (its contact point slides slower than 1 mm/s; measured: at most 0.01 mm/s).
  One axis holds for 5 ms only: TIAGo++ -x, whose maximum swings the object with the arms (the
  base accelerates at 3.9 m/s^2, the object at 27 m/s^2, arm joints at up to 390 rad/s^2); under
  constant efforts the arms reach 8 rad/s within 20 ms, the posture moves, the back casters
  (0.6 N of margin at t = 0) unload and the wheels slip from about 7 ms. The capacity is an
  instantaneous property; a replay of constant efforts leaves the state it was computed for.
  mobmanip's own replay (:mod:`mobmanip.motion.hold`) predicts that drift: it follows MuJoCo's
  normal forces and accelerations while every contact is loaded, and the reach it holds for 20 ms
  (with the efforts that hold it, not the calm ones) holds for 20 ms in MuJoCo on every axis,
  TIAGo++ -x included, where it is 81 % of the maximum; 97 % of that maximum holds for 8.25 ms
  with the best efforts found in mobmanip's replay, and 9.9 ms in MuJoCo (the last two tests).
  The maxima themselves, not 97 % of them, hold for 20 ms on 19 of the 20 axes; with a safety
  reserve of 0.3 (``Floor(reserve=0.3)``) on all twenty, TIAGo++ -x included (with 0.2 it slips).

The sharing matters: with ``load="any"`` (every sharing that balances the robot: exact for
tip-over, optimistic for traction) the predicted normal forces differ from MuJoCo's by up to 43 %
of the weight (more than 5 % on some axis of every case) and wheels slip on eight of the twenty
axes (TIAGo++'s twelve, the paper robot's four at 0 and at 90 deg). The ideal model's maximum
efforts, on every axis where they reach more than 5 % beyond the grounded maximum with every
sharing (``load="any"``, which contains MuJoCo's, whatever it is) over the friction pyramid's own
conservatism (1 / cos(pi / faces): MuJoCo's cone is round), tip the robot
(a support rises by more than 0.3 mm, or the base turns by more than 1e-3 rad) or slip a wheel
(faster than 0.1 m/s at the contact).

MuJoCo welds the object to the hands, which hold it level: every floor here is
``Floor(level=True)`` (for TIAGo++'s spatial task the same as without: it leaves no row out).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")
import mobmanip  # noqa: E402
from mobmanip.casestudy import configuration_at, optimal_posture  # noqa: E402
from mobmanip.motion.hold import held_reach, replay  # noqa: E402
from mobmanip.postures.named import named_configuration  # noqa: E402
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor, ground_reaction  # noqa: E402
from mujoco_referee import PAPER_CASTERS, build, urdf_casters  # noqa: E402

MU = 0.5
MASS = 2.0


def _case(name):
    if name == "tiago_dual":
        robot = mobmanip.load_robot("tiago_dual")
        return robot, named_configuration(robot, "hold"), "spatial", urdf_casters(robot), np.eye(6)
    robot = mobmanip.load_robot("planar_dual_arm")
    if name == "paper home":  # arms straight: near a singularity, the posture moves fast
        return robot, named_configuration(robot, "home"), "planar", PAPER_CASTERS, np.eye(2)
    angle = float(name.split()[-1])
    return robot, configuration_at(robot, optimal_posture(robot), angle), "planar", PAPER_CASTERS, np.eye(2)


def _axes(base):
    return [s * e for e in base for s in (1.0, -1.0)]


def _normals(referee, info, contacts):
    """MuJoCo's normal force at each of mobmanip's contacts (matched by position), (n,) N."""
    x, y, yaw = info["pose"]
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    out = []
    for c in info["contacts"]:
        s = min(referee.supports, key=lambda s: np.linalg.norm(R @ s.point[:2] + [x, y] - c["point"][:2]))
        assert np.linalg.norm(R @ s.point[:2] + [x, y] - c["point"][:2]) < 1e-6, c["name"]
        out.append(contacts[s.name].normal)
    return np.array(out)


def _slip(run):
    return max(run.slip_speed[:, k].max() for k, s in enumerate(run.supports) if s.driven)


def _at_t0(referee, grounded, target, task, why):
    """The calm efforts at ``target`` applied from rest in MuJoCo: the object's acceleration within
    3 % per component (components below 3 % of the norm held to 3 % of it) and every contact's
    normal force within 0.1 % of the weight of the prediction; returns the efforts' witness."""
    w = grounded.witness_at(target, least="xdot")
    acc, contacts = referee.forward(w.variables["tau"])
    got = acc[: len(target)] if task == "planar" else acc
    scale = np.maximum(np.abs(target), 0.03 * np.linalg.norm(target))
    assert np.all(np.abs(got - target) <= 0.03 * scale), (*why, got, target)
    floor = ground_reaction(grounded.model["floor"], w.variables[CONTACT_FORCES])
    predicted = [c["normal"] for c in floor["contacts"].values()]
    measured = _normals(referee, grounded.model["floor"], contacts)
    assert np.abs(measured - predicted).max() <= 1e-3 * referee.weight, (*why, measured, predicted)
    return w


def _held(run) -> bool:
    """No support rises by more than 0.1 mm, the base turns by less than 5e-4 rad in roll and
    pitch, no driven wheel's contact slides faster than 1 mm/s."""
    return -run.penetration.min() <= 1e-4 and np.abs(run.base_rpy[:, :2]).max() <= 5e-4 and _slip(run) <= 1e-3


SHORT = {("tiago_dual", -1.0, 0)}  # TIAGo++ -x: the arms swing the object (see the docstring)


@pytest.mark.parametrize("name", ["tiago_dual", "paper 0", "paper 90"])
def test_grounded_maxima_hold_in_mujoco_and_ideal_ones_do_not(name):
    robot, q, task, casters, base = _case(name)
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(level=True, mu=MU),)
    ).measures["dynamic_polytope"]
    assert grounded.model["floor"]["load"] == "compliant"
    free = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(level=True, lift=True),)
    )
    referee = build(robot, q, support_points=casters, object=free.held_object, mu=MU)
    ideal = free.measures["dynamic_polytope"]
    # every sharing of the load and of the sideways forces (MuJoCo's own among them): beyond it,
    # no sharing holds the ideal maximum
    bound = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",),
        constraints=(Floor(level=True, mu=MU, load="any"),),
    ).measures["dynamic_polytope"]  # fmt: skip
    tipped_or_slipped = 0
    for e in _axes(base):
        reach = grounded.straight_line_reach(e)
        assert reach > 0.0, (name, e)
        target = 0.97 * reach * e
        w = _at_t0(referee, grounded, target, task, (name, e))
        short = (name, float(e.sum()), int(np.argmax(np.abs(e)))) in SHORT
        run = referee.rollout(w.variables["tau"], duration=0.005 if short else 0.02)
        assert -run.penetration.min() <= 1e-4, (name, e, -run.penetration.min(axis=0))
        assert np.abs(run.base_rpy[:, :2]).max() <= 5e-4, (name, e)
        assert _slip(run) <= 1e-3, (name, e, _slip(run))
        if short:  # and it does not hold for 20 ms: the case is a real limit, not a slack test
            assert _slip(referee.rollout(w.variables["tau"], duration=0.02)) > 0.1
        ideal_reach = ideal.straight_line_reach(e)
        pyramid = np.cos(np.pi / grounded.model["floor"]["faces"])
        if ideal_reach > 1.05 * reach / pyramid:
            run = referee.rollout(ideal.straight_line_witness(e).variables["tau"], duration=0.02)
            tips = -run.penetration.min() > 3e-4 or np.abs(run.base_rpy[:, :2]).max() > 1e-3
            # beyond every sharing it must fail; beyond the compliant one only, MuJoCo's own
            # sharing may still hold it (TIAGo++ +y: 27.4 held where the springs give 23.6)
            beyond_any = ideal_reach > 1.05 * bound.straight_line_reach(e) / pyramid
            assert tips or _slip(run) > 0.1 or not beyond_any, (name, e, ideal_reach, reach)
            tipped_or_slipped += tips or _slip(run) > 0.1
    assert tipped_or_slipped >= 1  # every case has an axis where the floor binds in MuJoCo


@pytest.mark.parametrize("reserve", [0.0, 0.3])
@pytest.mark.parametrize("name", ["tiago_dual", "paper 0", "paper 90"])
def test_each_maximum_itself_holds_for_20_ms_in_mujoco(name, reserve):
    """The calm efforts of each grounded axis maximum itself (not 97 % of it), replayed from rest:
    at t = 0 the object's acceleration within 3 % per component and the normal forces within 0.1 %
    of the weight; for 20 ms no support rises, the base does not rock and no wheel slips.
    Without a reserve this holds on 19 of the 20 axes; TIAGo++ -x gives way (a wheel slides at
    0.62 m/s by 20 ms: the arms swing the object, see the module's docstring). With a safety
    reserve of 0.3 (every support keeps 30 % of its equal share of the weight, every wheel uses at
    most 70 % of its friction pyramid; its reaches equal the independent LP's, tests/test_floor.py)
    it holds on all 20, TIAGo++ -x at 75 % of its maximum without a reserve (the held reach
    without one: 81 %); with 0.2 it slips (measured on the 20 axes at 0.3: 0.12 %, 0.019 % of the
    weight, no rise, the fastest slide 4.8e-6 m/s)."""
    robot, q, task, casters, base = _case(name)
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",),
        constraints=(Floor(level=True, mu=MU, reserve=reserve),),
    ).measures["dynamic_polytope"]  # fmt: skip
    referee = build(robot, q, support_points=casters, object=_object(robot, q, task), mu=MU)
    gave_way = []
    for e in _axes(base):
        target = grounded.straight_line_reach(e) * e
        assert np.linalg.norm(target) > 0.0, (name, e)
        w = _at_t0(referee, grounded, target, task, (name, e))
        run = referee.rollout(w.variables["tau"], duration=0.02)
        if not _held(run):
            gave_way.append((float(e.sum()), int(np.argmax(np.abs(e)))))
            assert _slip(run) > 0.1, (name, e, _slip(run))  # a real slide, not a marginal one
    short = [(s, k) for (n, s, k) in SHORT if n == name]
    assert gave_way == (short if reserve == 0.0 else []), (name, reserve, gave_way)


@pytest.mark.parametrize("name", ["tiago_dual", "paper 0", "paper 90"])
def test_any_sharing_of_the_weight_is_not_what_the_floor_does(name):
    """With ``load="any"`` the LP loads the wheels as the balance allows; MuJoCo's equally stiff
    contacts share the weight otherwise (by more than 5 % of the weight on some axis of every
    case), and replayed, some of those maxima slip a wheel (on TIAGo++ and on the paper robot at
    0 and 90 deg: 8 of 20 axes measured, 5 of TIAGo++'s 12)."""
    robot, q, task, casters, base = _case(name)
    optimistic = mobmanip.analyze(
        robot,
        q,
        task,
        object_mass=MASS,
        measures=("dynamic_polytope",),
        constraints=(Floor(level=True, mu=MU, load="any"),),
    ).measures["dynamic_polytope"]
    referee = build(robot, q, support_points=casters, object=_object(robot, q, task), mu=MU)
    worst, slipped = 0.0, 0
    for e in _axes(base):
        w = optimistic.witness_at(0.97 * optimistic.straight_line_reach(e) * e, least="xdot")
        _, contacts = referee.forward(w.variables["tau"])
        predicted = [
            c["normal"]
            for c in ground_reaction(optimistic.model["floor"], w.variables[CONTACT_FORCES])["contacts"].values()
        ]
        worst = max(worst, np.abs(_normals(referee, optimistic.model["floor"], contacts) - predicted).max())
        slipped += _slip(referee.rollout(w.variables["tau"], duration=0.02)) > 1e-3
    assert worst > 0.05 * referee.weight
    assert slipped >= 1


def _object(robot, q, task):
    return mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("kinematic",)).held_object


def _columns(referee, info) -> list[int]:
    """The referee's support column of each of mobmanip's contacts (matched by position at rest)."""
    x, y, yaw = info["pose"]
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    found = []
    for c in info["contacts"]:
        gaps = [np.linalg.norm(R @ s.point[:2] + [x, y] - c["point"][:2]) for s in referee.supports]
        assert min(gaps) < 1e-6, c["name"]
        found.append(int(np.argmin(gaps)))
    return found


@pytest.mark.parametrize("name", ["tiago_dual", "paper 0", "paper 90"])
def test_the_replay_predicts_mujoco_and_held_reaches_hold_for_20_ms(name):
    """mobmanip's own replay of constant efforts (:mod:`mobmanip.motion.hold`) against MuJoCo's.

    At 97 % of each grounded axis maximum (calm witness), while every contact of the replay stays
    loaded (and for at most 10 ms, where MuJoCo's base starts to rock on its soft contacts), every
    normal force agrees with MuJoCo's within 0.5 % of the weight and the object's acceleration
    within 1 % of its norm (measured: 0.33 % and 0.13 %). The held reach (the largest
    straight-line reach whose efforts the replay holds for 20 ms) then holds for 20 ms in MuJoCo
    on every axis, under the criteria of the test above, TIAGo++ -x included (its instantaneous
    maximum's calm efforts give way after 2-7 ms: the replay predicts its back caster unloading
    at 2.25 ms). Every held reach is at least 80 % of its maximum (measured: 81 % on TIAGo++ -x,
    96-99.5 % elsewhere).
    """
    robot, q, task, casters, base = _case(name)
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(level=True, mu=MU),)
    ).measures["dynamic_polytope"]
    referee = build(robot, q, support_points=casters, object=_object(robot, q, task), mu=MU)
    columns = _columns(referee, grounded.model["floor"])
    gave_way = 0
    for e in _axes(base):
        target = 0.97 * grounded.straight_line_reach(e) * e
        tau = grounded.witness_at(target, least="xdot").variables["tau"]
        run = referee.rollout(tau, duration=0.02)
        step = float(run.time[1] - run.time[0])  # the replay samples where MuJoCo records
        ours = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(level=True, mu=MU), step=step, stop=False)
        compared = 0
        for i, t in enumerate(ours.time):
            if t > 0.01 or (ours.normal[i] <= 0.0).any():
                break
            j = int(np.argmin(np.abs(run.time - t)))
            assert abs(run.time[j] - t) <= 1e-6
            theirs = run.acceleration[j][: len(e)] if task == "planar" else run.acceleration[j]
            mine = ours.object_acceleration[i]
            assert np.abs(theirs - mine).max() <= 0.01 * np.linalg.norm(mine), (name, e, t)
            assert np.abs(run.normal[j][columns] - ours.normal[i]).max() <= 5e-3 * referee.weight, (name, e, t)
            compared += 1
        assert compared >= 8  # 2 ms at least
        found = held_reach(robot, q, grounded, e, task, object_mass=MASS, floor=Floor(level=True, mu=MU), duration=0.02)
        gave_way += not ours.holds
        assert found.reach > 0.8 * found.instant, (name, e)  # measured: at least 81 % (TIAGo++ -x)
        run = referee.rollout(found.witness.variables["tau"], duration=0.02)
        assert -run.penetration.min() <= 1e-4, (name, e, -run.penetration.min(axis=0))
        assert np.abs(run.base_rpy[:, :2]).max() <= 5e-4, (name, e)
        assert _slip(run) <= 1e-3, (name, e, _slip(run))
    assert gave_way >= 1  # on every case the calm efforts of some maximum do not hold for 20 ms


def test_how_long_a_maximum_holds_is_predicted():
    """TIAGo++ -x, the axis whose maximum does not hold for 20 ms: the efforts mobmanip finds to
    hold the largest reach for 10 ms (95 % of the instantaneous maximum) hold 10 ms in MuJoCo too,
    and by 20 ms both give way (mobmanip's replay: a back caster unloads after 10 ms; MuJoCo,
    where the load then moves off that caster: a wheel slides faster than 0.1 m/s, measured
    0.33 m/s). The reach held for 20 ms is 81 % of the maximum: no
    efforts the held reach's program finds hold 97 % of it that long (its bound, 82 %, is the
    largest reach its linearised rows allow around its own replay); the longest they hold 97 %
    is 8.25 ms, and about as long in MuJoCo."""
    robot, q, task, casters, _ = _case("tiago_dual")
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(level=True, mu=MU),)
    ).measures["dynamic_polytope"]
    referee = build(robot, q, support_points=casters, object=_object(robot, q, task), mu=MU)
    e = -np.eye(6)[0]
    found = held_reach(robot, q, grounded, e, task, object_mass=MASS, floor=Floor(level=True, mu=MU), duration=0.01)
    tau = found.witness.variables["tau"]
    run = referee.rollout(tau, duration=0.01)
    assert -run.penetration.min() <= 1e-4 and np.abs(run.base_rpy[:, :2]).max() <= 5e-4 and _slip(run) <= 1e-3
    assert _slip(referee.rollout(tau, duration=0.02)) > 0.1
    ours = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(level=True, mu=MU), duration=0.02)
    assert not ours.holds and 0.01 <= ours.held < 0.02
    longer = held_reach(robot, q, grounded, e, task, object_mass=MASS, floor=Floor(level=True, mu=MU), duration=0.02)
    assert longer.reach <= found.reach < found.instant  # a longer hold, a smaller reach
    # 97 % of the maximum: the efforts that hold it longest (8.25 ms in mobmanip's replay) hold in
    # MuJoCo for at least 90 % of the prediction and give way within 125 % of it (measured 9.9 ms)
    predicted = longer.instant_hold.held
    assert 0.0 < predicted < 0.02
    tau = longer.instant_witness.variables["tau"]
    run = referee.rollout(tau, duration=0.9 * predicted)
    assert -run.penetration.min() <= 1e-4 and np.abs(run.base_rpy[:, :2]).max() <= 5e-4 and _slip(run) <= 1e-3
    assert _slip(referee.rollout(tau, duration=1.25 * predicted)) > 1e-3


@pytest.mark.parametrize("name", ["tiago_dual", "paper 0", "paper 90", "paper home"])
def test_the_efforts_reported_for_each_maximum_hold_in_mujoco_as_long_as_predicted(name):
    """What ``analyze --hold 0.02`` reports on every task axis (TIAGo++'s six, turning ones
    included), replayed in MuJoCo: the held reach's efforts hold 20 ms, and for 97 % of the
    maximum the efforts that hold it longest (``instant_efforts``) hold for at least 90 % of the
    predicted time (``instant_holds_for``): 20 ms where mobmanip predicts 20 ms; TIAGo++ -x
    8.25 ms predicted, 9.9 ms in MuJoCo; +-y and yaw 17-19 ms predicted, 20 ms in MuJoCo,
    whose friction test is a little looser than mobmanip's. The paper robot with its arms
    straight (its home posture), where the posture moves fast: +-y held 20 ms at 84 % of the
    maximum, and 97 % of it for 10.5 ms (its calm efforts: 1.5 ms)."""
    robot, q, task, casters, _ = _case(name)
    grounded = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(level=True, mu=MU),)
    ).measures["dynamic_polytope"]
    referee = build(robot, q, support_points=casters, object=_object(robot, q, task), mu=MU)

    def holds(tau, duration):
        run = referee.rollout(tau, duration=duration)
        return -run.penetration.min() <= 1e-4 and np.abs(run.base_rpy[:, :2]).max() <= 5e-4 and _slip(run) <= 1e-3

    short = 0
    for e in _axes(np.eye(grounded.dim)):
        found = held_reach(robot, q, grounded, e, task, object_mass=MASS, floor=Floor(level=True, mu=MU), duration=0.02)
        assert holds(found.witness.variables["tau"], 0.02), (name, e)
        assert found.reach >= 0.8 * found.instant, (name, e, found.reach / found.instant)
        predicted = found.instant_hold.held
        calm = grounded.witness_at(0.97 * found.instant * e, least="xdot").variables["tau"]
        calm_held = replay(robot, q, calm, task, object_mass=MASS, floor=Floor(level=True, mu=MU)).held
        assert predicted >= calm_held and predicted > 0.0, (name, e, predicted, calm_held)
        short += predicted < 0.02
        assert holds(found.instant_witness.variables["tau"], 0.9 * predicted), (name, e, predicted)
    # the path where 97 % gives way is exercised (TIAGo++: -x, +-y, +-yaw; home: +-y; at 90 deg +x,
    # 14.25 ms, where each wheel carries half of the sideways force), and at 0 deg 97 % of every
    # maximum holds 20 ms (held 18 ms in MuJoCo, above)
    assert short >= 1 if name in ("tiago_dual", "paper home", "paper 90") else short == 0
