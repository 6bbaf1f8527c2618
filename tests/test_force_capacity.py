"""Force capacity (issue 24, item 3): the wrenches the object (or one hand) exerts ON the environment
at rest, gravity included, checked against three independent references and against statics.

* pycapacity's force polytope of a fixed-base arm, ``pycapacity.robot.force_polytope(J, tau_max,
  -tau_max, t_bias=g(q))`` = ``{f : J^T f = tau - g(q), tau in the box}``: f is the force the arm
  applies ON the environment (at rest tau = g(q) + J^T f, the environment pushing back with -f),
  and its bias is the gravity torque g(q) (Pinocchio's ``computeGeneralizedGravity``), which
  is mobmanip's -xi. Same convention as mobmanip's; J and g(q) are computed here by Pinocchio.
  pycapacity rounds its vertex torques to 1e-7 N m, so the vertices agree to about 1e-10 of the
  set's size, well inside the issue's 1e-7.
* the whole robot on the floor with a free-flyer base (tests/floor_reference.py, written from
  Pinocchio, not from mobmanip's terms), in its force mode (xdot = 0, a_o = 0, W h = g_o + f),
  ideal contacts (contact forces free): mobmanip's force polytope without the floor constraint.
* Pinocchio's RNEA with the environment's reaction -f applied at the hand: the efforts that hold
  the arm still at each vertex are within their limits and saturate as a vertex must.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pinocchio as pin
import pytest

import floor_reference as fr
import mobmanip
from conftest import configuration_within_limits, paper_case
from mobmanip.cli import main
from mobmanip.errors import TaskError
from mobmanip.postures.named import named_configuration
from mobmanip.sets.force import force_ellipsoid, force_polytope, unbounded_force_direction
from mobmanip.sets.polytope import Polytope
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
from mobmanip.terms.builder import terms_at
from mobmanip.terms.constraints.floor import Floor
from mobmanip.terms.force import force_problem
from toy_constraint import EffortShare

MASS = 2.0  # kg, the object of issue 24's table
ROWS = {"translational": slice(0, 3), "spatial": slice(0, 6)}
PYCAPACITY_TOL = 1e-7  # the bound, relative to the set's size
LP_RTOL = 1e-6  # the bound against the independent LP


def _unit(rng, count, dim):
    d = rng.normal(size=(count, dim))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _distance(ours, theirs):
    """Largest distance from each of our points to theirs and back (sets of points)."""
    d = np.linalg.norm(ours[:, None, :] - theirs[None, :, :], axis=2)
    return max(d.min(axis=1).max(), d.min(axis=0).max())


def _vertices(polytope: Polytope) -> np.ndarray:
    """Every vertex: the set's own for m <= 3; above, Qhull's intersection of its halfspaces."""
    if polytope.dim <= 3:
        return polytope.vertices
    from scipy.spatial import HalfspaceIntersection

    A, b = polytope.halfspaces
    V = HalfspaceIntersection(np.hstack([A, -b[:, None]]), polytope.center).intersections
    keep: list[np.ndarray] = []
    for v in V:  # a vertex where more than m facets meet comes once per facet subset
        if not keep or np.min(np.linalg.norm(np.array(keep) - v, axis=1)) > 1e-9 * np.abs(V).max():
            keep.append(v)
    return np.array(keep)


class Arm:
    """One fixed-base arm at a configuration, with J, g(q) and the limits straight from Pinocchio."""

    def __init__(self, robot, q, task):
        self.robot, self.q, self.task = robot, q, task
        model, data = robot.model, robot.model.createData()
        self.frame = robot.model.getFrameId(robot.arms[0].end_effector)
        self.v = list(robot.arm_v_indices)
        J6 = pin.computeFrameJacobian(model, data, q, self.frame, pin.LOCAL_WORLD_ALIGNED)
        self.J = J6[ROWS[task]][:, self.v]
        self.gravity = pin.computeGeneralizedGravity(model, data, q)[self.v]
        self.limits = model.effortLimit[self.v]
        self.position = data.oMf[self.frame].translation.copy()

    def holding_torques(self, f: np.ndarray) -> np.ndarray:
        """The efforts that hold the arm still while the environment pushes the hand with -f (RNEA)."""
        model, data = self.robot.model, self.robot.model.createData()
        pin.framesForwardKinematics(model, data, self.q)
        wrench = np.zeros(6)
        wrench[: len(f)] = -np.asarray(f)  # the reaction, world axes, at the hand
        world = pin.Force(wrench[:3], np.cross(self.position, wrench[:3]) + wrench[3:])  # about the world origin
        joint = model.frames[self.frame].parentJoint
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        fext[joint] = data.oMi[joint].actInv(world)
        zero = np.zeros(model.nv)
        return pin.rnea(model, data, self.q, zero, zero, fext)[self.v]


def _force_sets(robot, q, task, mass=0.0, **options):
    analysis = mobmanip.analyze(
        robot, q, task=task, object_mass=mass, measures=("force_ellipsoid", "force_polytope"), **options
    )
    return analysis, analysis.measures["force_ellipsoid"], analysis.measures["force_polytope"]


# ----- 1. a fixed-base arm: pycapacity's force polytope -----


@pytest.mark.parametrize("name", ["ur5", "panda"])
@pytest.mark.parametrize("task", ["translational", "spatial"])
def test_force_polytope_equals_pycapacitys(name, task, rng):
    from pycapacity.robot import force_polytope as pycapacity_force_polytope

    robot = mobmanip.load_robot(name)
    for _ in range(3):
        q = configuration_within_limits(robot, rng)
        arm = Arm(robot, q, task)
        _, _, ours = _force_sets(robot, q, task)
        ref = pycapacity_force_polytope(arm.J, arm.limits, -arm.limits, t_bias=arm.gravity).vertices.T
        V = _vertices(ours)
        assert len(V) == len(ref)
        assert _distance(V, ref) <= PYCAPACITY_TOL * np.abs(ref).max()
        if task == "spatial":  # 6-D: the volume too (pycapacity's hull against the zonotope formula)
            from scipy.spatial import ConvexHull

            assert ours.volume == pytest.approx(ConvexHull(ref).volume, rel=1e-6)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_each_vertex_is_held_by_efforts_within_their_limits(name, rng):
    """At each vertex f, Pinocchio's RNEA with the reaction -f on the hand gives the efforts that
    hold the arm still: they are the polytope's own, within the box, and at least m of them
    (one per task dimension) are at their limit. This fixes the sign: f acts ON the environment."""
    robot = mobmanip.load_robot(name)
    q = configuration_within_limits(robot, rng)
    arm = Arm(robot, q, "translational")
    _, _, ours = _force_sets(robot, q, "translational")
    for f, tau in zip(ours.vertices, ours.vertex_inputs):
        held = arm.holding_torques(f)
        np.testing.assert_allclose(held, tau, atol=1e-9 * arm.limits.max())
        ratio = np.abs(held) / arm.limits
        assert ratio.max() <= 1.0 + 1e-9
        assert np.sum(ratio >= 1.0 - 1e-9) >= 3
    # the reverse sign is not the set: pushing the hand with +f would need other efforts
    f = ours.vertices[0]
    assert np.abs(arm.holding_torques(-f) - ours.vertex_inputs[0]).max() > 1e-3


# ----- 2. the force ellipsoid inside the force polytope -----


@pytest.fixture(scope="module")
def tiago():
    robot = mobmanip.load_robot("tiago_dual")
    return robot, named_configuration(robot, "hold")


@pytest.fixture(scope="module")
def paper0():
    return paper_case(0.0)


@pytest.fixture(scope="module")
def paper90():
    return paper_case(90.0)


def _assert_ellipsoid_inside(ellipsoid, polytope, rng, count=200):
    m = ellipsoid.dim
    assert not ellipsoid.empty and not polytope.empty
    boundary = ellipsoid.center + _unit(rng, count, m) @ ellipsoid.generator.T
    assert polytope.contains(boundary, tol=1e-9).all()
    directions = _unit(rng, count, m)
    ours, theirs = polytope.supports(directions), np.array([ellipsoid.support(d) for d in directions])
    assert np.all(theirs <= ours + 1e-9 * np.abs(ours).max())


@pytest.mark.parametrize("name", ["ur5", "panda"])
@pytest.mark.parametrize("task", ["translational", "spatial"])
def test_force_ellipsoid_lies_inside_the_force_polytope(name, task, rng):
    robot = mobmanip.load_robot(name)
    q = configuration_within_limits(robot, rng)
    _, ellipsoid, polytope = _force_sets(robot, q, task, mass=1.5)
    _assert_ellipsoid_inside(ellipsoid, polytope, rng)


def test_force_ellipsoid_inside_with_two_hands_and_internal_forces(tiago, paper0, rng):
    """Two hands on one object: the ellipsoid takes the minimum-norm internal force, the polytope
    any; still inside."""
    for (robot, q), task in ((tiago, "spatial"), (paper0, "planar")):
        _, ellipsoid, polytope = _force_sets(robot, q, task, mass=MASS)
        _assert_ellipsoid_inside(ellipsoid, polytope, rng, count=60)


def test_force_ellipsoid_touches_the_polytope_where_one_effort_saturates_alone(rng):
    """UR5, spatial task: J is square, so for each joint i the wrench f = J^-T (+-tau_max_i e_i - g(q))
    asks that joint alone for its whole limit: it lies on the ellipsoid's boundary (||Z tau|| = 1)
    and on a facet of the polytope (|tau_i| = tau_max_i), so both sets touch there."""
    robot = mobmanip.load_robot("ur5")
    q = configuration_within_limits(robot, rng)
    arm = Arm(robot, q, "spatial")
    _, ellipsoid, polytope = _force_sets(robot, q, "spatial")
    for i in range(6):
        for sign in (1.0, -1.0):
            f = np.linalg.solve(arm.J.T, sign * arm.limits[i] * np.eye(6)[i] - arm.gravity)
            for task_set in (ellipsoid, polytope):
                c = task_set.center
                assert task_set.contains(f, tol=1e-9)
                assert not task_set.contains(c + (1.0 + 1e-6) * (f - c), tol=1e-9)


# ----- 3. a mobile robot: the independent whole-robot LP -----


@pytest.mark.parametrize("which", ["tiago", "paper0"])
def test_mobile_force_polytope_equals_the_whole_robot_lp(which, request, rng):
    """TIAGo++ in its hold posture with 2 kg (spatial) and the paper robot at 0 deg (planar), only
    the joint boxes: the closed form and the linear programs through the constraint seam equal the
    free-flyer model's force LP with free contact forces, support along 16 directions and
    straight-line reach along every task axis."""
    robot, q = request.getfixturevalue(which)
    task, casters = ("spatial", None) if which == "tiago" else ("planar", fr.PAPER_CASTERS)
    analysis, _, closed = _force_sets(robot, q, task, mass=MASS)
    lifted = force_problem(analysis.terms)
    problem = fr.build_problem(robot, q, task, analysis.held_object, casters=casters)
    m = problem.W.shape[0]
    errors = []
    for d in np.vstack([np.eye(m), _unit(rng, 16 - m, m)]):
        ref = fr.force_support(problem, d).value
        for ours in (closed.support(d), lifted.support(d)):
            errors.append(abs(ours - ref) / abs(ref))
    for e in np.vstack([np.eye(m), -np.eye(m)]):
        ref = fr.force_straight_line(problem, e).value
        for ours in (closed.straight_line_reach(e), lifted.straight_line_reach(e)):
            errors.append(abs(ours - ref) / abs(ref))
    assert max(errors) <= LP_RTOL, max(errors)


FLOORS = {"no_tip": (None, "no_tip"), "mu=0.5": (0.5, "friction"), "mu=1.0": (1.0, "friction")}


@pytest.mark.parametrize("floor", list(FLOORS))
@pytest.mark.parametrize("which", ["tiago", "paper0", "paper90"])
def test_grounded_force_polytope_equals_the_whole_robot_lp(which, floor, request, rng):
    """With the floor constraint (no tip-over; and traction within mu = 0.5 or 1.0) the force
    polytope is the reference's force LP in the same floor model: support along 16 directions
    and straight-line reach along every task axis, 1e-6 relative. The floor comes through the
    constraint seam; nothing in the force problem knows about it."""
    robot, q = request.getfixturevalue(which)
    task, casters = ("spatial", None) if which == "tiago" else ("planar", fr.PAPER_CASTERS)
    mu, mode = FLOORS[floor]
    analysis, _, grounded = _force_sets(robot, q, task, mass=MASS, constraints=(Floor(mu=mu),))
    assert grounded.model["problem"] == "force" and "floor" in grounded.model
    problem = fr.build_problem(robot, q, task, analysis.held_object, casters=casters)
    m = problem.W.shape[0]
    errors = []
    for d in np.vstack([np.eye(m), _unit(rng, 16 - m, m)]):
        ref = fr.force_support(problem, d, mode=mode, mu=mu, springs=mode == "friction").value
        errors.append(abs(grounded.support(d) - ref) / max(abs(ref), 1e-9))
    for e in np.vstack([np.eye(m), -np.eye(m)]):
        ref = fr.force_straight_line(problem, e, mode=mode, mu=mu, springs=mode == "friction").value
        errors.append(abs(grounded.straight_line_reach(e) - ref) / max(abs(ref), 1e-9))
    assert max(errors) <= LP_RTOL, max(errors)


def _binding_rows_of_its_own_lp(polytope, e, robot) -> tuple[float, set]:
    """The straight-line push along ``e`` solved here with HiGHS over the set's rows (max s with
    the task point s e, every equation and inequality row, every bound) and the inequality rows
    whose multipliers (``res.ineqlin.marginals``) are not zero, each named from its contents, not
    from the set's labels: a row on one effort tau_k with bound the robot's limit k is that joint's
    effort limit (its sign the coefficient's); a row -lambda_n <= 0 on one contact force is that
    contact lifting off; a row on a wheel's forces with a negative coefficient on its normal
    force is that wheel slipping. The contacts are named in the order the reference reads them
    from the robot (floor_reference: driven wheels, then casters), their columns told apart by
    those rows: a wheel's normal force is the one column all its friction rows weigh."""
    from scipy.optimize import linprog

    rows = polytope.lifted_rows()
    n = len(rows.lower)
    entries = np.abs(rows.A_ub) > 1e-12 * np.abs(rows.A_ub).max(axis=1, keepdims=True)  # cos(pi/2) is not 0
    tau, contact = polytope.variables["tau"], polytope.variables["contact_forces"]
    A_eq = np.vstack([np.hstack([rows.A_eq, np.zeros((len(rows.b_eq), 1))]),
                      np.hstack([np.eye(n)[rows.task], -np.asarray(e, dtype=float)[:, None]])])  # fmt: skip
    b_eq = np.r_[rows.b_eq, np.zeros(len(rows.task))]
    A_ub = np.hstack([rows.A_ub, np.zeros((len(rows.b_ub), 1))])
    bounds = [
        (lo if np.isfinite(lo) else None, hi if np.isfinite(hi) else None) for lo, hi in zip(rows.lower, rows.upper)
    ]
    res = linprog(np.r_[np.zeros(n), -1.0], A_ub=A_ub, b_ub=rows.b_ub, A_eq=A_eq, b_eq=b_eq,
                  bounds=[*bounds, (0.0, None)], method="highs")  # fmt: skip
    assert res.status == 0, res.message
    multipliers = res.ineqlin.marginals
    nonzero = np.abs(multipliers) > 1e-9 * np.abs(multipliers).max()

    columns = np.arange(n)
    on_tau, on_contact = np.isin(columns, columns[tau]), np.isin(columns, columns[contact])
    friction = [set(np.flatnonzero(used).tolist()) for used in entries
                if used.any() and not used[~on_contact].any() and used.sum() > 1]  # fmt: skip
    wheels: list[list[set]] = []  # the friction rows of each wheel: rows sharing a column
    for used in friction:
        group = next((g for g in wheels if used & set().union(*g)), None)
        wheels.append([used]) if group is None else group.append(used)
    normals = [set.intersection(*group) for group in wheels]  # a wheel's normal force: in all its rows
    assert all(len(normal) == 1 for normal in normals), normals
    wheel_normals = sorted(normal.pop() for normal in normals)
    caster_normals = sorted(set(columns[contact].tolist()) - set().union(*friction))
    names = dict(zip(wheel_normals, [c.name for c in fr.driven_wheels(robot)], strict=True))
    names |= dict(zip(caster_normals, [c.name for c in fr.urdf_casters(robot)], strict=True))
    assert len(wheel_normals) == 2 and len(caster_normals) == 4, (wheel_normals, caster_normals)

    found = set()
    for row, bound, where in zip(rows.A_ub[nonzero], rows.b_ub[nonzero], entries[nonzero]):
        used = np.flatnonzero(where)
        if len(used) == 1 and on_tau[used[0]]:
            k = int(used[0] - tau.start)
            assert bound == pytest.approx(robot.effort_limits[k], rel=1e-12)
            found.add(("effort", robot.reduced_velocity_names[k], "+" if row[used[0]] > 0 else "-"))
        elif len(used) == 1 and on_contact[used[0]] and row[used[0]] < 0 and bound == 0.0:
            found.add(("lifts off", names[int(used[0])]))
        elif on_contact[used].all():
            (normal,) = set(used.tolist()) & set(wheel_normals)
            assert row[normal] == pytest.approx(-0.5 * np.cos(np.pi / 8), rel=1e-12) and bound == 0.0
            found.add(("slips", names[normal]))
        else:
            raise AssertionError(f"a binding row of unknown kind: {dict(zip(used, row[used]))} <= {bound}")
    return -res.fun, found


def _read_label(label: str) -> tuple:
    effort = re.fullmatch(r"(\S+) effort limit \(([+-])\)", label)
    if effort:
        return ("effort", effort.group(1), effort.group(2))
    contact = re.match(r"(\S+) (lifts off|slips) ", label)
    assert contact, label
    return (contact.group(2), contact.group(1))


def test_what_stops_a_grounded_push(tiago):
    """TIAGo++ in its hold posture with 2 kg, on the floor with mu = 0.5: the floor never makes the
    robot stronger (each grounded reach <= the ideal one), and what the witness says stops the
    push (which effort limit, which contact lifts or slips) is what the LP's own multipliers,
    computed here, say binds (:func:`_binding_rows_of_its_own_lp`)."""
    robot, q = tiago
    ideal = _force_sets(robot, q, "spatial", mass=MASS)[2]
    grounded = _force_sets(robot, q, "spatial", mass=MASS, constraints=(Floor(mu=0.5),))[2]
    stopped_by_floor = 0
    for e in np.vstack([np.eye(6)[:3], -np.eye(6)[:3]]):
        reach = grounded.straight_line_reach(e)
        assert reach <= ideal.straight_line_reach(e) * (1.0 + 1e-9)
        value, binding_here = _binding_rows_of_its_own_lp(grounded, e, robot)
        assert reach == pytest.approx(value, rel=1e-7), e
        binding = grounded.straight_line_witness(e).binding
        assert binding
        assert {_read_label(label) for label in binding} == binding_here, e
        if any(kind in ("lifts off", "slips") for kind, *_ in binding_here):
            stopped_by_floor += 1
    assert stopped_by_floor >= 1


def test_the_force_problem_is_the_reference_lp_at_its_maximiser(tiago):
    """The witness of the straight-line push forward satisfies the reference's equations: the
    efforts and hand wrenches mobmanip finds hold the whole free-flyer robot still (with some
    contact forces) while the object pushes f on the environment."""
    robot, q = tiago
    analysis, _, _ = _force_sets(robot, q, "spatial", mass=MASS)
    witness = force_problem(analysis.terms).straight_line_witness(np.eye(6)[0])
    f, tau, h = witness.point, witness.variables["tau"], witness.variables["h"]
    np.testing.assert_allclose(witness.variables["xdot"], 0.0, atol=1e-12)
    np.testing.assert_allclose(witness.variables["a"], 0.0, atol=1e-12)
    P = fr.build_problem(robot, q, "spatial", analysis.held_object)
    np.testing.assert_allclose(P.W @ h, P.g_o + f, atol=1e-7 * np.abs(f).max())
    C, _ = fr.contact_force_columns(P)
    residual = P.g - P.B @ tau + P.hand_jacobian.T @ h  # the contact forces must take exactly this
    contact_forces = np.linalg.lstsq(C, residual, rcond=None)[0]
    assert np.abs(C @ contact_forces - residual).max() <= 1e-7 * np.abs(P.g).max()
    assert np.abs(tau).max() <= robot.effort_limits.max() and witness.binding


def test_every_constraint_of_the_acceleration_problem_applies(paper0):
    """A constraint written in its own file (tests/toy_constraint.py) reaches the force polytope:
    with efforts within half their limits it is the closed form of the halved limits; the
    ellipsoid ignores it and says so."""
    robot, q = paper0
    share = 0.5
    analysis, ellipsoid, polytope = _force_sets(robot, q, "planar", mass=MASS, constraints=(EffortShare(share),))
    T = analysis.terms
    halved = force_polytope(T.J_u, T.W, T.Q, T.xi, T.g_o, share * T.effort_limits)
    directions = np.array([[np.cos(t), np.sin(t)] for t in np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)])
    np.testing.assert_allclose(polytope.supports(directions), halved.supports(directions), rtol=1e-9)
    assert polytope.model["problem"] == "force"
    assert [c["name"] for c in polytope.model["constraints"]] == ["effort_limits", "effort_share"]
    assert analysis.ignored_constraints("force_ellipsoid") == ("effort_share",)
    assert analysis.ignored_constraints("force_polytope") == ()
    plain = force_ellipsoid(T.J_u, T.W, T.Q, T.xi, T.g_o, T.effort_limits)
    np.testing.assert_allclose(ellipsoid.semi_axes, plain.semi_axes, rtol=1e-12)
    binding = polytope.straight_line_witness([1.0, 0.0]).binding
    assert binding and all(f"at {share:g} of its effort limit" in label for label in binding)


# ----- 4. statics -----


def test_a_held_load_moves_the_set_down_by_its_weight(tiago, rng):
    """f + g_o = W h: holding m kg shifts every wrench the hands can apply by the load's weight.
    Pushing straight down reaches exactly m g further and lifting exactly m g less (straight-line
    reach from zero force); every support moves by -d . g_o. One fixed arm and two hands."""
    weight = MASS * 9.81
    ur5 = mobmanip.load_robot("ur5")
    ur5_q = configuration_within_limits(ur5, rng)
    for (robot, q), task in (((ur5, ur5_q), "translational"), (tiago, "spatial")):
        empty = force_problem(terms_at(robot, q, task, object_mass=0.0))
        loaded = force_problem(terms_at(robot, q, task, object_mass=MASS))
        m = empty.dim
        down = -np.eye(m)[2]
        assert loaded.straight_line_reach(down) == pytest.approx(empty.straight_line_reach(down) + weight, rel=1e-9)
        assert loaded.straight_line_reach(-down) == pytest.approx(empty.straight_line_reach(-down) - weight, rel=1e-9)
        for d in _unit(rng, 20, m):
            assert loaded.support(d) == pytest.approx(empty.support(d) - weight * d[2], rel=1e-9, abs=1e-9)
    # the closed form shifts its vertices the same way (one fixed arm, 3-D)
    sets = [_force_sets(ur5, ur5_q, "translational", mass=mass)[2] for mass in (0.0, MASS)]
    shifted = sets[0].vertices - weight * np.eye(3)[2]
    assert _distance(sets[1].vertices, shifted) <= 1e-9 * np.abs(shifted).max()


def test_at_a_singular_posture_the_capacity_is_unbounded_and_said_so():
    """UR5 at zero is singular: a wrench along a direction of null(J^T) needs no effort at all.
    Both paths refuse to return a bounded set, naming the direction."""
    robot = mobmanip.load_robot("ur5")
    T = terms_at(robot, robot.neutral(), "spatial", object_mass=0.0)
    direction = unbounded_force_direction(T.J_u, T.W)
    assert direction is not None and np.abs(T.J_u.T @ direction).max() <= 1e-9
    with pytest.raises(TaskError, match=r"unbounded along \+-\("):
        force_polytope(T.J_u, T.W, T.Q, T.xi, T.g_o, T.effort_limits)
    with pytest.raises(TaskError, match="unbounded"):
        force_ellipsoid(T.J_u, T.W, T.Q, T.xi, T.g_o, T.effort_limits)
    with pytest.raises(TaskError, match="unbounded"):
        force_problem(T)


# ----- 5. the command line, JSON and sweeps -----


def test_analyze_prints_and_writes_the_force_sets(tmp_path, capsys, rng):
    robot = mobmanip.load_robot("panda")
    q = configuration_within_limits(robot, rng)
    (tmp_path / "q.json").write_text(json.dumps(robot.configuration_dict(q)))
    out = tmp_path / "a.json"
    argv = ["analyze", "panda", "--task", "translational", "--q", str(tmp_path / "q.json"), "--object-mass", "0"]
    assert main([*argv, "--measure", "force_polytope", "--measure", "force_ellipsoid", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "force ellipsoid semi-axes (N):" in text and "force polytope (N):" in text  # translational: forces only
    assert not re.search(r"\bnan\b|\binf\b", text, re.IGNORECASE)
    document = json.loads(out.read_text())
    assert list(document)[-2:] == ["force_ellipsoid", "force_polytope"]
    arm = Arm(robot, q, "translational")
    from pycapacity.robot import force_polytope as pycapacity_force_polytope

    ref = pycapacity_force_polytope(arm.J, arm.limits, -arm.limits, t_bias=arm.gravity).vertices.T
    assert _distance(np.array(document["force_polytope"]["vertices"]), ref) <= PYCAPACITY_TOL * np.abs(ref).max()
    # --polytope adds the polytopes of the quantities asked for (and the motion ones)
    from mobmanip.cli import build_parser
    from mobmanip.commands.common import requested_measures

    parser = build_parser()
    assert "force_polytope" not in requested_measures(parser.parse_args(["analyze", "panda", "--polytope"]))
    args = parser.parse_args(["analyze", "panda", "--measure", "force_ellipsoid", "--polytope"])
    assert requested_measures(args)[:1] == ("force_ellipsoid",) and "force_polytope" in requested_measures(args)


def test_sweeps_of_force_sets_equal_single_analyses():
    """Both force measures sweep (one configuration at a time), with and without a constraint,
    and give the single analyses' volumes."""
    grid = SweepGrid(angle_deg=np.array([0.0, 90.0]), distance=np.array([0.7, 0.9]))
    robot = mobmanip.load_robot("planar_dual_arm")
    for constraints, share in (((), 1.0), ((EffortShare(0.5),), 0.5)):
        spec = SweepSpec(
            "planar_dual_arm", object_mass=MASS, measures=("force_ellipsoid", "force_polytope"), constraints=constraints
        )
        result = run_sweep(spec, grid, workers=1)
        names, values = result.joint_positions()
        checked = 0
        for i in range(2):
            for j in range(2):
                if np.isnan(values[i, j]).any():
                    continue
                q = robot.configuration((0.0, 0.0, 0.0), dict(zip(names, values[i, j])))
                T = terms_at(robot, q, object_mass=MASS)
                closed = force_polytope(T.J_u, T.W, T.Q, T.xi, T.g_o, share * T.effort_limits)
                plain = force_ellipsoid(T.J_u, T.W, T.Q, T.xi, T.g_o, T.effort_limits)
                assert result.index("force_polytope.volume")[i, j, 0] == pytest.approx(closed.volume, rel=1e-9)
                assert result.index("force_ellipsoid.volume")[i, j, 0] == pytest.approx(plain.volume, rel=1e-9)
                checked += 1
        assert checked >= 3
