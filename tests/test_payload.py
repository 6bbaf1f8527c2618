"""The payload LP against an independent reference: a bisection on the object's mass over the
capacity sets that exist already (``analyze(..., object_mass=m).measures["dynamic_polytope"]``
contains the acceleration asked for exactly when m is at most the heaviest payload).

Three robots (TIAGo++ holding, Stretch at home, the paper's planar robot), held still and with an
acceleration, on the ideal model and on the floor (with mu 0.5; a 5 deg ramp for TIAGo++; held
level for the planar robot, whose planar task carries no weight otherwise). What stops the mass
is checked in the set's own rows just above the bisection's mass: the rows the LP names, alone,
still put the acceleration out of reach, and without them it is reached; the LP's efforts and
contact forces solve the set's rows at its mass.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import pytest

from mobmanip import cli
from mobmanip.analysis.payload import payload
from mobmanip.analysis.single import analyze
from mobmanip.errors import ArgumentError, TaskError
from mobmanip.postures.named import named_configuration
from mobmanip.robot.model import load_robot
from mobmanip.robot.tasks import get_task
from mobmanip.sets.linear_programs import LinearProgram
from mobmanip.terms.constraints.base import Constraint, ConstraintRows
from mobmanip.terms.constraints.floor import Floor
from mobmanip.terms.problems import capacity_polytope

#: The relative accuracy the LP must match the bisection to.
RTOL = 1e-6

#: name -> (robot, posture, the given acceleration in its default task: m/s^2, rad/s^2)
ROBOTS = {
    "tiago_dual": ("tiago_dual", "hold", (0.5, 0.0, 0.2, 0.0, 0.0, 0.0)),
    "stretch": ("stretch", "home", (0.2, 0.0, 0.1)),
    "planar_dual_arm": ("planar_dual_arm", "home", (0.5, 0.2)),
}

#: (robot, floor or None, held still) cases the LP is compared with the bisection on.
CASES = [
    ("tiago_dual", None, True),
    ("tiago_dual", None, False),
    ("tiago_dual", Floor(mu=0.5), True),
    ("tiago_dual", Floor(mu=0.5), False),
    ("tiago_dual", Floor(mu=0.5, slope=5.0), True),
    ("stretch", None, True),
    ("stretch", None, False),
    ("stretch", Floor(mu=0.5), True),
    ("stretch", Floor(mu=0.5), False),
    ("planar_dual_arm", None, False),
    ("planar_dual_arm", Floor(mu=0.5), False),
    ("planar_dual_arm", Floor(mu=0.5, level=True), True),
    ("planar_dual_arm", Floor(mu=0.5, level=True), False),
]


@pytest.fixture(scope="module")
def robots():
    out = {}
    for key, (name, posture, _) in ROBOTS.items():
        robot = load_robot(name)
        out[key] = (robot, named_configuration(robot, posture))
    return out


def grounded_set(robot, q, mass, floor):
    """The set of object accelerations at ``mass`` (kg), as the sets are built today."""
    constraints = () if floor is None else (floor,)
    result = analyze(
        robot, q, object_mass=mass, measures=("dynamic_polytope",), constraints=constraints, method="exact"
    )
    return result.measures["dynamic_polytope"]


def bisection(robot, q, a, floor) -> tuple[float, float]:
    """The heaviest mass whose set contains ``a``, bracketed (lo contains it, hi does not) to
    RTOL / 10 of the mass: doubling from 1 kg, then halving the bracket."""
    holds = lambda m: grounded_set(robot, q, m, floor).contains(a)  # noqa: E731
    assert holds(0.0), "the robot cannot do it with no object: no payload to compare"
    lo, hi = 0.0, 1.0
    while holds(hi):
        lo, hi = hi, 2.0 * hi
        assert hi < 1e5, "no mass up to 1e5 kg is too heavy"
    while hi - lo > 0.1 * RTOL * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if holds(mid) else (lo, mid)
    return lo, hi


def acceleration_of(key, still):
    return np.zeros(len(ROBOTS[key][2])) if still else np.array(ROBOTS[key][2])


@pytest.fixture(scope="module")
def compared(robots):
    """Each case's payload and bisection bracket, computed once."""
    out = {}
    for key, floor, still in CASES:
        robot, q = robots[key]
        a = acceleration_of(key, still)
        found = payload(robot, q, acceleration=None if still else a, constraints=() if floor is None else (floor,))
        out[key, floor, still] = (found, bisection(robot, q, a, floor))
    return out


def case_id(case):
    key, floor, still = case
    where = "ideal" if floor is None else "floor" + ("-level" if floor.level else "") + ("-ramp" if floor.slope else "")
    return f"{key}-{where}-{'still' if still else 'accelerating'}"


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_the_payload_equals_a_bisection_over_the_sets(compared, case):
    found, (lo, hi) = compared[case]
    assert found.status == "bounded", found.summary()
    assert found.mass == pytest.approx(0.5 * (lo + hi), rel=RTOL)
    assert lo <= found.mass * (1 + RTOL) and found.mass <= hi * (1 + RTOL)


def lifted_set(robot, q, mass, floor):
    """The set at ``mass`` as the projection of its rows (the ideal set's closed form has none)."""
    constraints = () if floor is None else (floor,)
    result = analyze(
        robot, q, object_mass=mass, measures=("dynamic_polytope",), constraints=constraints, method="exact"
    )
    return capacity_polytope(result.terms, "acceleration")


def reaches(rows, keep, a, still=None) -> bool:
    """Whether the rows (with only the inequality rows ``keep``) have a solution whose task point
    is a (with the columns ``still``, a slice, at zero)."""
    lower, upper = rows.lower.copy(), rows.upper.copy()
    if still is not None:
        lower[still] = upper[still] = 0.0
    lower[rows.task] = upper[rows.task] = a
    A = np.vstack([rows.A_eq, rows.A_ub[keep]])
    lo = np.r_[rows.b_eq, np.full(int(keep.sum()), -np.inf)]
    hi = np.r_[rows.b_eq, rows.b_ub[keep]]
    return LinearProgram(A, lo, hi, lower, upper).solve(np.zeros(len(lower))) is not None


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_what_stops_it_stops_it_in_the_set(robots, compared, case):
    """The rows the LP names are enough to stop the mass: in the set's own rows at 1e-5 above the
    bisection's mass, with every other inequality row dropped, a is still out of reach (and with
    none of them, a is reached: they are the limit, not the equations)."""
    key, floor, still = case
    robot, q = robots[key]
    found, (_, hi) = compared[case]
    assert found.binding, "a bounded payload is stopped by some limit"
    a = acceleration_of(key, still)
    heavier = lifted_set(robot, q, hi * (1 + 1e-5), floor)
    rows = heavier.lifted_rows()
    named = np.array([label in found.binding for label in heavier.labels])
    assert named.sum() >= len(found.binding)
    assert not reaches(rows, named, a)
    assert not reaches(rows, np.ones(len(named), dtype=bool), a)
    assert reaches(rows, ~named, a)


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_the_efforts_at_the_optimum_solve_the_set_at_that_mass(robots, compared, case):
    """The LP's variables (efforts, contact forces, ...) solve the set's rows at the LP's mass and
    reach a there."""
    key, floor, still = case
    robot, q = robots[key]
    found, _ = compared[case]
    at_mass = lifted_set(robot, q, found.mass, floor)
    z = np.concatenate([found.variables[name] for name in at_mass.variables])
    solution = at_mass.witness_of(z)
    np.testing.assert_allclose(solution.point, acceleration_of(key, still), atol=1e-12)
    np.testing.assert_array_equal(solution.variables["tau"], found.efforts)


#: (robot, floor or None) cases of the static payload: the object still and the robot too.
STATIC_CASES = [
    ("tiago_dual", None),
    ("tiago_dual", Floor(mu=0.5)),
    ("tiago_dual", Floor(mu=0.5, reserve=0.3)),
    ("stretch", Floor(mu=0.5)),
    ("planar_dual_arm", Floor(mu=0.5, level=True)),
]


def static_bisection(robot, q, floor) -> tuple[float, float]:
    """The heaviest mass whose set holds the object still with every reduced acceleration zero
    (:meth:`LiftedPolytope.witness_at` with ``still=("xdot",)``), bracketed to RTOL / 10."""
    a = np.zeros(get_task(robot.spec.default_task).dim)

    def holds(m):
        try:
            lifted_set(robot, q, m, floor).witness_at(a, still=("xdot",))
        except TaskError:
            return False
        return True

    assert holds(0.0)
    lo, hi = 0.0, 1.0
    while holds(hi):
        lo, hi = hi, 2.0 * hi
        assert hi < 1e5
    while hi - lo > 0.1 * RTOL * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if holds(mid) else (lo, mid)
    return lo, hi


def static_id(case):
    key, floor = case
    return case_id((key, floor, True)) + ("-reserve" if floor is not None and floor.reserve else "")


@pytest.mark.parametrize("case", STATIC_CASES, ids=static_id)
def test_the_static_payload_equals_a_bisection_with_the_robot_still(robots, case):
    """``static=True``: the robot does not move at all, the statics (what holds for a while); the
    named rows alone stop the mass with the reduced accelerations at zero."""
    key, floor = case
    robot, q = robots[key]
    constraints = () if floor is None else (floor,)
    found = payload(robot, q, constraints=constraints, static=True)
    instant = payload(robot, q, constraints=constraints)
    lo, hi = static_bisection(robot, q, floor)
    assert found.status == "bounded", found.summary()
    assert found.mass == pytest.approx(0.5 * (lo + hi), rel=RTOL)
    assert found.mass <= instant.mass * (1 + RTOL)
    np.testing.assert_array_equal(found.variables["xdot"], 0.0)
    heavier = lifted_set(robot, q, hi * (1 + 1e-5), floor)
    rows = heavier.lifted_rows()
    named = np.array([label in found.binding for label in heavier.labels])
    still = heavier.variables["xdot"]
    a = np.zeros(heavier.dim)
    assert not reaches(rows, named, a, still)
    assert reaches(rows, ~named, a, still)


def test_a_stretch_about_to_tip_reads_as_tip_over(robots):
    """Stretch held static on the floor: the payload leaves its left wheel unloaded and the
    zero-moment point on the support's edge (from the optimum's own contact forces), and the
    reading says tip-over where the program's rows name the wheel's lift and friction rows."""
    robot, q = robots["stretch"]
    found = payload(robot, q, constraints=(Floor(mu=0.5),), static=True)
    normals = {name: c["normal"] for name, c in found.floor["contacts"].items()}
    total = sum(normals.values())
    assert total == pytest.approx(9.81 * (pin.computeTotalMass(robot.model) + found.mass), rel=1e-6)
    assert abs(normals["joint_left_wheel"]) <= 1e-6 * total
    assert abs(found.floor["margin"]) <= 1e-6
    assert any(label.startswith("joint_left_wheel lifts off") for label in found.binding)
    assert any("tips over" in label and "joint_left_wheel lifting off" in label for label in found.reading)


def test_static_with_an_acceleration_is_refused(robots):
    robot, q = robots["stretch"]
    with pytest.raises(ArgumentError, match="static"):
        payload(robot, q, acceleration=(0.1, 0.0, 0.0), static=True)


def test_tiago_on_the_floor_is_stopped_by_a_support_and_its_arms(compared):
    """On the floor, TIAGo++'s payload held still is lower than on the ideal model and a caster
    that would lift takes part in stopping it (the ideal one: efforts only)."""
    ideal, _ = compared["tiago_dual", None, True]
    grounded, _ = compared["tiago_dual", Floor(mu=0.5), True]
    assert grounded.mass < ideal.mass
    assert all("effort limit" in label for label in ideal.binding)
    assert any("lifts off the floor" in label for label in grounded.binding)


def test_a_planar_task_carries_no_weight_unless_held_level(robots):
    """The planar task's object is moved in the plane: its weight is not the hands', so nothing
    stops the mass held still (in words, never an infinity)."""
    robot, q = robots["planar_dual_arm"]
    found = payload(robot, q)
    assert found.status == "unbounded" and found.mass is None
    assert "unbounded" in found.summary() and "inf" not in found.summary().replace("unbounded", "")
    assert json.loads(json.dumps(found.to_dict(), allow_nan=False))["mass"] is None
    # and the bisection agrees: no mass up to 1e4 kg leaves 0 outside the set
    assert grounded_set(robot, q, 1e4, None).contains(np.zeros(2))


def test_an_acceleration_beyond_the_robot_with_no_object_is_infeasible_in_words(robots):
    robot, q = robots["stretch"]
    a = np.array([100.0, 0.0, 0.0])
    assert not grounded_set(robot, q, 0.0, None).contains(a)  # the set without an object says so
    found = payload(robot, q, acceleration=a)
    assert found.status == "infeasible" and found.mass is None
    assert "even with no object" in found.summary()


@dataclass(frozen=True)
class MassLimit(Constraint):
    """A made-up limit on the first effort that depends on the object's mass: as m^2
    (``square``) or as m times the effort (``scaled``)."""

    how: str = "square"
    name: str = "made_up"
    problem: str = "acceleration"

    def rows(self, terms):
        m, n = terms.held_object.mass, len(terms.effort_limits)
        row = np.zeros((1, n))
        row[0, 0] = 1.0 + (m if self.how == "scaled" else 0.0)
        bound = 1e3 + (m * m if self.how == "square" else 0.0)
        return ConstraintRows(self.name, self.problem, G={"tau": row}, h=np.array([bound]), labels=("made up",))


@pytest.mark.parametrize("how, what", [("square", "not affine"), ("scaled", "multiplies a variable")])
def test_a_constraint_not_linear_in_the_mass_is_refused_by_name(robots, how, what):
    robot, q = robots["stretch"]
    with pytest.raises(ArgumentError, match=what) as caught:
        payload(robot, q, constraints=(MassLimit(how),))
    assert "made_up" in str(caught.value)


def test_an_explicit_object_keeps_its_inertia_per_kilogram(robots):
    """An object given with 2 kg is the default one's shape: the same payload."""
    from mobmanip.analysis.single import default_object

    robot, q = robots["tiago_dual"]
    a = acceleration_of("tiago_dual", False)
    default = payload(robot, q, acceleration=a)
    given = payload(robot, q, acceleration=a, object=default_object(robot, q, 2.0))
    assert given.mass == pytest.approx(default.mass, rel=1e-9)


# ------------------------------------------------------------------------------------------------
# the command


def run_cli(argv, capsys):
    code = cli.main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_the_command_writes_the_functions_result(robots, tmp_path, capsys):
    robot, q = robots["tiago_dual"]
    target = tmp_path / "payload.json"
    code, out, err = run_cli(
        [
            "payload",
            "tiago_dual",
            "--posture",
            "hold",
            "--mu",
            "0.5",
            "--accel",
            "0.5,0,0.2,0,0,0",
            "--json",
            str(target),
        ],
        capsys,
    )
    assert code == 0, err
    expected = payload(robot, q, acceleration=(0.5, 0, 0.2, 0, 0, 0), constraints=(Floor(mu=0.5),))
    written = json.loads(target.read_text())
    assert written["mass"] == pytest.approx(expected.mass, rel=1e-9)
    assert written["binding"] == list(expected.binding)
    assert written["status"] == "bounded"
    assert f"{expected.mass:.6g} kg" in out
    assert "stops it" in out


def test_the_static_command_writes_the_functions_result(robots, tmp_path, capsys):
    robot, q = robots["tiago_dual"]
    target = tmp_path / "static.json"
    argv = ["payload", "tiago_dual", "--posture", "hold", "--mu", "0.5", "--reserve", "0.3", "--static"]
    code, out, err = run_cli([*argv, "--json", str(target)], capsys)
    assert code == 0, err
    expected = payload(robot, q, constraints=(Floor(mu=0.5, reserve=0.3),), static=True)
    written = json.loads(target.read_text())
    assert written == json.loads(json.dumps(expected.to_dict()))
    assert "with the robot static" in out and f"{expected.mass:.6g} kg" in out


def test_an_instants_payload_names_what_can_be_held_for_a_while(tmp_path, capsys):
    """The UR5 at home (arm stretched out, a singular posture): the instant's program holds the
    object still with 39.25 kg while the joints accelerate at about 1,000 rad/s^2. The command
    says so and gives the payload with the robot static too, here against a closed form: nothing
    moves, so tau = g(q) + m g0 J^T e_z (Pinocchio's gravity and the hand's Jacobian, the hand
    pushing the object up), and the payload is the least over the joints of the mass that brings
    one to its effort limit (1e-9). Stretch, whose static payload is the instant's to 2e-6, gets no
    such note."""
    ur5 = load_robot("ur5")
    q = ur5.neutral()
    model, data = ur5.model, ur5.data
    gravity = ur5.null_space(q).T @ pin.computeGeneralizedGravity(model, data, q)
    frame = model.getFrameId(ur5.arms[0].end_effector)
    J = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)
    per_kg = 9.81 * (ur5.null_space(q).T @ J[2])  # effort per kg held: the hand pushes up on the object
    limits = np.asarray(ur5.effort_limits, dtype=float)
    closed_form = min(
        ((limits[i] - gravity[i]) if b > 0 else (limits[i] + gravity[i])) / abs(b)
        for i, b in enumerate(per_kg)
        if abs(b) > 1e-12
    )
    target = tmp_path / "payload.json"
    code, out, err = run_cli(["payload", "ur5", "--json", str(target)], capsys)
    assert code == 0, err
    written = json.loads(target.read_text())
    assert written["static_mass"] == pytest.approx(closed_form, rel=1e-9)
    assert written["mass"] > 3.0 * closed_form  # the instant's, with the joints accelerating
    assert np.abs(written["variables"]["xdot"]).max() > 100.0
    assert f"what can be held for a while: {closed_form:.6g} kg" in out
    code, out, err = run_cli(["payload", "stretch"], capsys)
    assert code == 0, err
    assert "for an instant only" not in out


def test_the_command_says_unbounded_in_words(capsys):
    code, out, err = run_cli(["payload", "planar_dual_arm"], capsys)
    assert code == 0, err
    assert "unbounded" in out and "inf" not in out.replace("unbounded", "")


@pytest.mark.parametrize(
    "accel, what",
    [("1,2,3", "2 components"), ("nan,0", "finite"), ("1,x", "--accel")],
)
def test_bad_accelerations_are_one_line(accel, what, capsys):
    code, out, err = run_cli(["payload", "planar_dual_arm", "--accel", accel], capsys)
    assert code == 2
    assert err.startswith("mobmanip: error: ") and err.count("\n") == 1
    assert what in err
