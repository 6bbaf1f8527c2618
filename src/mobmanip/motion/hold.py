"""How long a grounded capacity holds: constant efforts replayed from rest in mobmanip's own model.

A capacity is a property of one instant: the efforts that reach a grounded maximum keep every
support loaded and every driven wheel within friction at rest. Held constant, they set the robot
moving, the posture changes and velocity terms appear (centrifugal forces of the arms, the
platform's own), and the contact forces drift: in MuJoCo, the calm efforts of 97 % of TIAGo++'s
-x maximum (the arms swing the held object) unload a caster and slip a wheel after about 7 ms,
and the efforts that hold it longest after 9.9 ms. This module predicts that time
and finds the largest reach that holds for a chosen duration, with the efforts that hold it
(:func:`held_reach`: which of the many efforts that reach a point are used decides how long
it holds).

The replay integrates the reduced dynamics of the robot holding its object (the hands hold it in
the task's rows and, when the floor holds it level, in the level rows too, as the floor
constraint does: a planar task's object may then turn about the vertical in the hands) under
constant efforts tau: at each state (q, x), with the terms of
:func:`mobmanip.motion.in_motion.motion_terms`, the reduced accelerations xdot, the hands' wrench h
(m k) and the object's acceleration a_o solve::

    P xdot + J_u^T h = Q tau + xi(q, x)                    (reduced dynamics)
    J_u xdot - W^T a_o = Wdot^T v_o - d/dt(J_u) x           (the hands move with the object)
    W h - M_o a_o = c_o + g_o                               (the object's own dynamics)

(internal wrenches included: two hands on one object form a closed chain), then q and x advance
by a semi-implicit Euler step (x first, q along ``pin.integrate`` with S(q) x). At every step the
floor's resultant wrench (the robot's own, :func:`mobmanip.motion.ground.floor_wrench` with
velocity terms, and each hand's wrench h_i on the object applied at the hand, as the floor
constraint takes them: what the hands do not hold of the object, e.g. a planar task's weight
unless held level, is borne elsewhere) is shared by the contacts as the floor constraint shares it
(:func:`mobmanip.motion.traction.contact_forces`): the hold ends when a support's normal force
drops to its reserve (0 by default: it lifts) or a driven wheel's traction leaves its friction
cone (its use ``|f_t| / (mu f_n)`` above 1 - reserve: it slips).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..errors import ArgumentError, SpecError, TaskError
from ..platforms import a_platform
from ..robot.model import Robot, platform_pose
from ..robot.tasks import TaskSpace, get_task
from ..sets.lifted import Witness
from ..sets.linear_programs import LinearProgram
from ..terms.constraints.floor import LEVEL_ROWS, Floor, pyramid_faces
from ..terms.constraints.floor_wrench import WrenchSharing, both_ways
from ..terms.grasp import GRAVITY, object_mass_of, wrench_shift
from .ground import floor_wrench
from .in_motion import motion_terms
from .traction import contact_forces

#: Integration step of the replay (s): halving it changes TIAGo++'s hold times by under 0.1 ms.
STEP = 2.5e-4


@dataclass(frozen=True)
class Hold:
    """A replay of constant efforts from rest (see the module's docstring).

    Attributes:
        held: how long every contact held (s); ``duration`` when nothing gave way.
        duration: the replay's length (s).
        binds: what gave way first, e.g. ``"caster_back_left lifts off the floor"`` (None: nothing).
        time: the samples' times (s), (N,).
        q: the configuration at each sample, (N, nq).
        velocity: the reduced velocity at each sample, (N, nx).
        object_acceleration: the object's acceleration in the task's rows per sample, (N, m).
        normal: every contact's normal force per sample (N), (N, n).
        use: every driven wheel's traction use per sample, (N, d).
        contacts: the contacts' names, in the columns' order of ``normal``.
        wheels: the driven wheels' names, in the columns' order of ``use``.
    """

    held: float
    duration: float
    binds: str | None
    time: np.ndarray
    q: np.ndarray
    velocity: np.ndarray
    object_acceleration: np.ndarray
    normal: np.ndarray
    use: np.ndarray
    contacts: tuple[str, ...]
    wheels: tuple[str, ...]

    @property
    def holds(self) -> bool:
        """Whether every contact held for the whole replay."""
        return self.binds is None


def forward_accelerations(terms, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(xdot (nx,), hands' wrench h (m k,), object acceleration a_o (m,)) under efforts tau, from
    the three equations of the module's docstring (least squares where the grasp leaves internal
    wrenches undetermined)."""
    nx, mk = terms.P.shape[0], terms.J_u.shape[0]
    b = np.concatenate([terms.Q @ tau + terms.xi, terms.grasp_drift - terms.drift, terms.c_o + terms.g_o])
    solution = np.linalg.lstsq(_chain(terms), b, rcond=None)[0]
    return solution[:nx], solution[nx : nx + mk], solution[nx + mk :]


def _chain(terms) -> np.ndarray:
    """The closed chain's matrix over (xdot, h, a_o): the left-hand sides of the module's docstring."""
    nx, mk, m = terms.P.shape[0], terms.J_u.shape[0], terms.W.shape[0]
    A = np.zeros((nx + mk + m, nx + mk + m))
    A[:nx, :nx] = terms.P
    A[:nx, nx : nx + mk] = terms.J_u.T
    A[nx : nx + mk, :nx] = terms.J_u
    A[nx : nx + mk, nx + mk :] = -terms.W.T
    A[nx + mk :, nx : nx + mk] = terms.W
    A[nx + mk :, nx + mk :] = -terms.M_o
    return A


def replay(
    robot: Robot,
    q: ArrayLike,
    tau: ArrayLike,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    floor: Floor | None = None,
    duration: float = 0.02,
    step: float = STEP,
    stop: bool = True,
) -> Hold:
    """Constant efforts ``tau`` applied from rest at ``q``: how long the floor holds them.

    Args:
        robot: a robot with a differential-drive platform.
        q: the configuration it starts from, at rest, (nq,).
        tau: the wheels' and joints' efforts (nx,), e.g. a witness's ``variables["tau"]``.
        task, object_mass: as :func:`mobmanip.analysis.analyze` (the object between the hands).
        floor: the contacts' friction and reserve (default: ``Floor()``, the spec's support and mu).
        duration: how long to replay (s).
        step: the integration step (s).
        stop: end the replay at the first contact that gives way (False: replay the whole duration).

    Raises:
        ArgumentError: a duration or step that is not a positive finite number, or ``tau`` of the
            wrong size.
        SpecError: a platform that is not a differential drive (the floor model's).
        TaskError: a floor without a friction coefficient (the replay checks traction).
    """
    return _replay(robot, q, tau, task, object_mass, floor, duration, step, stop, False)[0]


def _replay(robot, q, tau, task, object_mass, floor, duration, step, stop, keep) -> tuple[Hold, list[ContactMaps]]:
    """:func:`replay`, and with ``keep`` the contact forces' affine maps at every sample."""
    for value, what in ((duration, "duration"), (step, "step")):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
            raise ArgumentError(f"the replay's {what} must be a positive number of seconds, got {value!r}")
    q = robot.check_configuration(q)
    tau = np.asarray(tau, dtype=float)
    if tau.shape != (robot.nx,) or not np.all(np.isfinite(tau)):
        raise ArgumentError(f"tau must be {robot.nx} finite efforts (wheels, then joints), got shape {tau.shape}")
    if robot.wheel_platform is None or robot.platform.kind != "differential_drive":
        raise SpecError(
            f"a replay on the floor covers differential-drive platforms; "
            f"{robot.name!r} has {a_platform(robot.platform.kind)}"
        )
    floor = Floor() if floor is None else floor
    if floor.slope:
        raise ArgumentError("a replay on a ramp is not modelled (its dynamics assume a level floor): slope 0 only")
    support, mu, _ = floor.resolve(robot)
    if mu is None:
        raise TaskError("a replay checks the wheels' traction: the floor needs a friction coefficient mu")
    task_space = get_task(task or robot.spec.default_task)
    mass_o = object_mass_of(robot, object_mass)
    driven = np.array([c.driven for c in support.contacts])
    stiffness = np.array([c.stiffness for c in support.contacts], dtype=float)
    weight = (float(pin.computeTotalMass(robot.model)) + mass_o) * float(-GRAVITY[2])
    least = floor.reserve * weight / len(support.contacts)
    names = tuple(c.name for c in support.contacts)
    wheels = tuple(c.name for c in support.contacts if c.driven)

    # the hands hold the object in the task's rows and, held level, in the level rows (as the
    # floor constraint does): the same closed chain that moves the object keeps it level
    held_rows = tuple(sorted(set(task_space.rows) | (set(LEVEL_ROWS) if floor.level else set())))
    labels = get_task("spatial").labels
    welded = TaskSpace(f"{task_space.name}_level", held_rows, tuple(labels[r] for r in held_rows))
    rows = [held_rows.index(r) for r in task_space.rows]
    count = int(math.ceil(duration / step - 1e-9))
    x = np.zeros(robot.nx)
    times, configurations, velocities, accelerations, normals, uses = [], [], [], [], [], []
    maps: list[ContactMaps] = []
    binds: str | None = None
    held = duration
    for i in range(count + 1):
        t = i * step
        state = _affine_state(robot, q, x, welded, mass_o)
        xdot = state.xdot[0] @ tau + state.xdot[1]
        a_o = state.a_o[0] @ tau + state.a_o[1]
        wrench = state.wrench[0] @ tau + state.wrench[1]
        if keep:
            maps.append(_contact_maps(state, q, support, stiffness))
        force, moment = wrench[:3], wrench[3:]
        if force[2] <= 0.0:
            raise TaskError(f"at t = {t:.6g} s the efforts lift the whole robot off the floor")
        z = support.floor_z
        zmp = np.array([(z * force[0] - moment[1]) / force[2], (moment[0] + z * force[1]) / force[2]])
        pose = platform_pose(q)
        normal, _, use = contact_forces(support.world_points(pose), driven, force, moment, zmp, mu, stiffness)
        times.append(t)
        configurations.append(q)
        velocities.append(x)
        accelerations.append(a_o[rows])
        normals.append(normal)
        uses.append(use)
        if binds is None:
            low = np.flatnonzero(normal <= least)
            slips = np.flatnonzero(use > 1.0 - floor.reserve)
            if len(low) and least > 0.0:
                binds = f"{names[low[0]]} unloads to its reserve {least:.4g} N (normal force {normal[low[0]]:.4g} N)"
            elif len(low):
                binds = f"{names[low[0]]} lifts off the floor (normal force {normal[low[0]]:.4g} N)"
            elif len(slips):
                binds = f"{wheels[slips[0]]} slips (traction use {use[slips[0]]:.4g})"
            if binds is not None:
                held = max(t - step, 0.0)
                if stop:
                    break
        if i == count:
            break
        x = x + step * xdot
        q = pin.integrate(robot.model, q, step * (state.S @ x))
    hold = Hold(
        held=held,
        duration=float(duration),
        binds=binds,
        time=np.array(times),
        q=np.array(configurations),
        velocity=np.array(velocities),
        object_acceleration=np.array(accelerations),
        normal=np.array(normals),
        use=np.array(uses),
        contacts=names,
        wheels=wheels,
    )
    return hold, maps


@dataclass(frozen=True)
class ContactMaps:
    """The contacts' forces at one state of a replay as affine functions of the efforts tau (the
    state fixed; see :func:`contact_maps`).

    Attributes:
        normal: (N (n, nx), n0 (n,)): every contact's normal force N tau + n0 (N).
        tangential: (T (2d, nx), t0 (2d,)): the driven wheels' tangential forces (world x, y per
            wheel) T tau + t0 + F s for any split s (N).
        split: F (2d, f): the directions in which the wheels may share the load among themselves;
            none under the floor's compliant sharing, which gives each tyre of an axle half of
            its lateral force (the least-squares share of ``tangential``).
    """

    normal: tuple[np.ndarray, np.ndarray]
    tangential: tuple[np.ndarray, np.ndarray]
    split: np.ndarray


def contact_maps(
    robot: Robot,
    q: np.ndarray,
    x: np.ndarray,
    task: TaskSpace,
    object_mass: float,
    support,
    stiffness: np.ndarray | None = None,
) -> ContactMaps:
    """The replay's contact forces at the state (q, x) as affine functions of the efforts.

    At a fixed state every step of the replay is linear in tau: the closed chain's solution
    (:func:`forward_accelerations`), the object's acceleration from the hands' motion,
    ``a_o = (W^T)^+ (J_u xdot + d/dt(J_u) x - Wdot^T v_o)``, the floor's resultant wrench (affine in
    xdot and a_o; :func:`mobmanip.motion.ground.floor_wrench`), the compliant normal forces (linear
    in the resultant's normal force and its moments) and the wheels' particular tangential forces.

    Args:
        robot, q, x: the robot, a configuration (nq,) and a reduced velocity (nx,).
        task: the rows the hands hold the object in (the replay's: the task's and the level rows).
        object_mass: the object's mass (kg).
        support: the contacts (a :class:`mobmanip.robot.support.Support`).
        stiffness: the contacts' relative stiffness, (n,); default all equal.
    """
    return _contact_maps(_affine_state(robot, q, x, task, object_mass), q, support, stiffness)


@dataclass(frozen=True)
class _AffineState:
    """One state's replay quantities as affine maps (M, m0) of the efforts: value = M tau + m0."""

    S: np.ndarray
    xdot: tuple[np.ndarray, np.ndarray]
    a_o: tuple[np.ndarray, np.ndarray]
    wrench: tuple[np.ndarray, np.ndarray]


def _affine_state(robot: Robot, q: np.ndarray, x: np.ndarray, task: TaskSpace, object_mass: float) -> _AffineState:
    """The closed chain's accelerations (the module's docstring), the object's and the floor's
    resultant wrench [force; moment about the world origin] at (q, x), affine in the efforts."""
    terms = motion_terms(robot, q, x, task, object_mass=object_mass)
    nx, mk, m = terms.P.shape[0], terms.J_u.shape[0], terms.W.shape[0]
    rhs = np.zeros((nx + mk + m, nx + 1))
    rhs[:nx, :nx] = terms.Q
    rhs[:nx, nx] = terms.xi
    rhs[nx : nx + mk, nx] = terms.grasp_drift - terms.drift
    rhs[nx + mk :, nx] = terms.c_o + terms.g_o
    solution = np.linalg.lstsq(_chain(terms), rhs, rcond=None)[0]
    X, x0 = solution[:nx, :nx], solution[:nx, nx]  # xdot = X tau + x0
    # The floor carries the robot and what its hands apply to the object, each hand's wrench h_i
    # at its own point (as the floor constraint has it): the object's rows the hands do not hold
    # (a planar task's weight and tipping moments, unless held level) are borne elsewhere, and a
    # squeeze between hands at different heights tips the robot.
    constant, linear = floor_wrench(robot, q, x, 0.0, np.zeros(6), np.zeros((6, nx)))
    pin.framesForwardKinematics(robot.model, robot.data, q)
    held = list(task.rows)
    to_origin = np.zeros((6, mk))  # [force; moment about the origin] of the hands' wrenches
    for i, arm in enumerate(robot.arms):
        p = robot.data.oMf[arm.frame_id].translation
        to_origin[:, i * len(held) : (i + 1) * len(held)] = wrench_shift(p)[:, held]
    H, h0 = solution[nx : nx + mk, :nx], solution[nx : nx + mk, nx]
    return _AffineState(
        S=terms.S,
        xdot=(X, x0),
        a_o=(solution[nx + mk :, :nx], solution[nx + mk :, nx]),
        wrench=(linear @ X + to_origin @ H, constant + linear @ x0 + to_origin @ h0),
    )


def _contact_maps(state: _AffineState, q: np.ndarray, support, stiffness: np.ndarray | None) -> ContactMaps:
    """The contact forces of :func:`contact_maps` from one state's affine wrench."""
    G, g = state.wrench
    pose = platform_pose(q)
    components = both_ways([contact.driven for contact in support.contacts])
    # the floor of motion's one sharing, in the world's frame (the wrench's)
    sharing = WrenchSharing.of(support.world_points(pose), components, support.floor_z, stiffness)
    to_tangential = sharing.require_traction()
    return ContactMaps(
        normal=(sharing.normal @ G, sharing.normal @ g),
        tangential=(to_tangential @ G, to_tangential @ g),
        split=np.zeros((len(components), 0)),
    )


@dataclass(frozen=True)
class HeldReach:
    """The largest straight-line reach whose efforts hold for a duration (see :func:`held_reach`).

    Attributes:
        direction: the unit task direction, (m,).
        reach: the held reach (task units); 0 when not even holding the object still holds.
        instant: the instantaneous straight-line reach of the set (task units).
        duration: the duration asked for (s).
        hold: the replay of the held reach's efforts (None when the reach is 0).
        instant_hold: the replay, at ``fraction`` of the instantaneous maximum, of the efforts
            that hold it longest (found as :func:`held_reach` says; its calm efforts when they hold).
        fraction: the share of the instantaneous maximum ``instant_hold`` replayed.
        witness: the solution whose efforts were replayed at the held reach (None when 0).
        bound: the largest reach the linearised program allows around its last round's replay
            (the held reach is within about ``tolerance`` of it), or None when the rounds did not
            settle (the reach then comes from the trust-region rounds).
        instant_witness: the solution whose efforts ``instant_hold`` replayed.
    """

    direction: np.ndarray
    reach: float
    instant: float
    duration: float
    hold: Hold | None
    instant_hold: Hold
    fraction: float
    witness: Witness | None
    bound: float | None = None
    instant_witness: Witness | None = None


def held_reach(
    robot: Robot,
    q: ArrayLike,
    polytope,
    direction: ArrayLike,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    floor: Floor | None = None,
    duration: float = 0.02,
    fraction: float = 0.97,
    tolerance: float = 0.005,
    step: float = STEP,
    iterations: int = 8,
) -> HeldReach:
    """The largest straight-line reach along ``direction`` whose efforts, held constant from rest,
    keep every support loaded and every driven wheel within friction for ``duration`` (this
    module's replay), with the efforts that hold it.

    Which efforts reach a point matters: a redundant robot reaches it with many, and they drift
    apart once the robot moves. The reach is found by a sequential linear program over the
    polytope's own rows (every limit at t = 0) and, at every step of a replay, its contact forces
    as affine functions of the efforts at that step's state (:func:`contact_maps`): each normal
    force at least the reserve, each driven wheel's tangential force in the friction pyramid with
    any split between the wheels. Around the states of the last replay it finds the largest reach
    s, then, ``tolerance`` times the instantaneous reach below it, the efforts with the most
    margin at every step; their replay gives the next states. The first states are those of the
    calm efforts at ``fraction`` of the instantaneous maximum. It stops when the largest reach
    settles (within a tenth of ``tolerance``) and its efforts hold, after at most ``iterations``
    rounds, and returns the largest reach whose replay held (every claim is a replay's). Where the
    rounds do not settle (near a singularity the posture moves so fast that the linearisation
    misleads them), the reach starts from the best that held, else from a bisection over the calm
    efforts (``witness_at(s d, least="xdot")``), and grows by rounds that keep the efforts within
    a trust region around the last that held (20 % of the effort limits, grown by half after a
    round that holds a larger reach, halved after one that does not).

    The instantaneous maximum is replayed at ``fraction`` of it (at the maximum itself some limit
    is tight and gives way at once): with its calm efforts and, where they give way, with the
    efforts that hold it longest. Those come from the same program at that reach over the
    longest run of a replay's first steps whose rows it satisfies with a margin (bisection over
    the run's length), replayed in turn while the hold grows (then within a trust region).

    Args:
        robot, q, task, object_mass: as the analysis that produced ``polytope``.
        polytope: a grounded dynamic polytope (a :class:`mobmanip.sets.lifted.LiftedPolytope`
            with the efforts ``tau`` among its variables).
        direction: the task direction, (m,) (normalised here).
        floor: the floor the polytope was computed on (its mu and reserve), default ``Floor()``.
        duration: how long the efforts must hold (s).
        fraction: the share of the instantaneous reach replayed as the maximum, in (0, 1].
        tolerance: the resolution, as a share of the instantaneous reach.
        step: the replay's integration step (s).
        iterations: the most rounds of the sequential program.

    Raises:
        TaskError: a polytope without efforts, or a direction not in the task's dimension.
    """
    d = np.asarray(direction, dtype=float)
    if d.shape != (polytope.dim,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0.0:
        raise TaskError(f"the direction must be a nonzero finite {polytope.dim}-vector, got {d.tolist()}")
    d = d / np.linalg.norm(d)
    if "tau" not in getattr(polytope, "variables", {}):
        raise TaskError("a held reach replays efforts: the set must be a polytope with the efforts tau as a variable")
    _check_user_rows(polytope)
    if not (0.0 < fraction <= 1.0 and 0.0 < tolerance < 1.0):
        raise ArgumentError(f"fraction must be in (0, 1] and tolerance in (0, 1), got {fraction!r}, {tolerance!r}")
    if isinstance(iterations, bool) or not isinstance(iterations, int) or iterations < 1:
        raise ArgumentError(f"iterations must be a positive integer, got {iterations!r}")
    floor = Floor() if floor is None else floor

    def play(tau: np.ndarray) -> tuple[Hold, list[ContactMaps]]:
        return _replay(robot, q, tau, task, object_mass, floor, duration, step, False, True)

    instant = float(polytope.straight_line_reach(d))
    if instant <= 0.0:
        witness = polytope.witness_at(np.zeros_like(d), least="xdot")
        hold = play(witness.variables["tau"])[0]
        return HeldReach(d, 0.0, 0.0, float(duration), hold if hold.holds else None, hold, fraction,
                         witness if hold.holds else None, None, witness)  # fmt: skip
    top = fraction * instant
    witness = polytope.witness_at(top * d, least="xdot")
    calm_hold, calm_maps = play(witness.variables["tau"])
    if calm_hold.holds and fraction == 1.0:
        return HeldReach(d, top, instant, float(duration), calm_hold, calm_hold, fraction, witness, None, witness)
    q = np.asarray(q, dtype=float)
    heading = platform_pose(q)[2]
    program = _HoldingProgram(robot, polytope, d, object_mass, floor, heading)
    calm_witness = witness
    # a held reach: (reach, its replay, its efforts, the replay's contact maps)
    Held = tuple[float, Hold, Witness, list[ContactMaps]]
    best: Held | None = (top, calm_hold, witness, calm_maps) if calm_hold.holds else None
    maps, last, bound, settled = calm_maps, None, None, False
    for _ in range(iterations):
        found = program.widest(maps, tolerance * instant)
        if found is None:
            break
        bound, witness = found
        hold, maps = play(witness.variables["tau"])
        reach = float(witness.point @ d)
        if hold.holds and (best is None or reach > best[0]):
            best = (reach, hold, witness, maps)
        if hold.holds and last is not None and abs(bound - last) <= 0.1 * tolerance * instant:
            settled = True
            break
        last = bound
    if not settled:
        if best is None:  # the calm efforts, by bisection
            low, high = 0.0, top
            while high - low > tolerance * instant:
                middle = 0.5 * (low + high)
                witness = polytope.witness_at(middle * d, least="xdot")
                hold, maps = play(witness.variables["tau"])
                if hold.holds:
                    low, best = middle, (middle, hold, witness, maps)
                else:
                    high = middle
        if best is None:
            witness = polytope.witness_at(np.zeros_like(d), least="xdot")
            hold, maps = play(witness.variables["tau"])
            if hold.holds:
                best = (0.0, hold, witness, maps)
        # rounds that trust the linearisation only near efforts that held: where it changed too
        # fast for the rounds above (e.g. the paper robot's arms stretched, near a singularity)
        radius = 0.2
        for _ in range(iterations if best is not None else 0):
            assert best is not None
            around = (best[2].variables["tau"], radius * robot.effort_limits)
            found = program.widest(best[3], tolerance * instant, around)
            if found is not None:
                witness = found[1]
                hold, maps = play(witness.variables["tau"])
                reach = float(witness.point @ d)
                if hold.holds and reach > best[0]:
                    gain, best = reach - best[0], (reach, hold, witness, maps)
                    if gain <= 0.1 * tolerance * instant:
                        break
                    radius = min(1.5 * radius, 1.0)
                    continue
            radius *= 0.5
        bound = None
    instant_witness, instant_hold = calm_witness, calm_hold
    if not calm_hold.holds:  # the efforts that hold the maximum longest
        instant_witness, instant_hold = _longest(program, play, top, calm_witness, calm_hold, calm_maps, best,
                                                 robot.effort_limits, iterations)  # fmt: skip
    if best is None:
        return HeldReach(d, 0.0, instant, float(duration), None, instant_hold, fraction, None, None, instant_witness)
    return HeldReach(
        d, best[0], instant, float(duration), best[1], instant_hold, fraction, best[2], bound, instant_witness
    )


def _check_user_rows(polytope) -> None:
    """Refuse a user constraint's row over anything but the efforts: the replay holds the efforts
    constant, so rows over them hold throughout, but rows over the accelerations or the hands'
    wrenches would be kept at the start only.

    Raises:
        ArgumentError: such a row, named by its label.
    """
    rows = polytope.lifted_rows()
    others = np.ones(rows.A_ub.shape[1], dtype=bool)
    others[polytope.variables["tau"]] = False
    for k, kind in enumerate(polytope.kinds):
        if kind == "user" and np.any(rows.A_ub[k, others] != 0.0):
            raise ArgumentError(
                f"a held reach replays constant efforts and keeps a constraint's rows over the efforts only: "
                f"row {polytope.labels[k]!r} limits other variables too"
            )


def _longest(program, play, top, witness, hold, maps, held, limits, iterations) -> tuple[Witness, Hold]:
    """The efforts at the reach ``top`` that hold longest (see :func:`held_reach`), starting from
    the calm ones (``witness``, its replay ``hold`` and contact ``maps``) or, when the held reach
    ``held`` (reach, replay, efforts, maps) is at least ``top``, from the held reach's replay. A
    round whose replay does not hold longer shrinks a trust region around the best efforts (first
    none, then 20 % of the effort limits, halved each time); two such rounds in a row end it."""
    best_witness, best_hold, best_maps = witness, hold, maps
    if held is not None and held[0] >= top:
        best_maps = held[3]  # linearise around efforts that hold, beyond top
    around, radius = (held[2] if held is not None and held[0] >= top else witness).variables["tau"], None
    failed = 0
    for _ in range(iterations):
        box = None if radius is None else (around, radius * limits)
        longer = program.longest(best_maps, top, box)
        if longer is not None:
            replayed, replayed_maps = play(longer.variables["tau"])
            if replayed.held > best_hold.held:
                best_witness, best_hold, best_maps = longer, replayed, replayed_maps
                around, failed = longer.variables["tau"], 0
                if replayed.holds:
                    break
                radius = None if radius is None else min(1.5 * radius, 1.0)
                continue
        failed += 1
        if failed == 2:  # unconstrained, then a trust region: no longer hold
            break
        radius = 0.2 if radius is None else 0.5 * radius
    return best_witness, best_hold


class _HoldingProgram:
    """The linear program of :func:`held_reach` around one replay's states (see its docstring).

    Columns: the polytope's variables z, the wheels' splits per step, the reach s and the margin t.
    """

    def __init__(self, robot, polytope, d, object_mass, floor: Floor, heading: float):
        self.polytope, self.d = polytope, d
        mass = object_mass_of(robot, object_mass)
        self.support, mu, faces = floor.resolve(robot)
        if mu is None:
            raise TaskError("a held reach checks the wheels' traction: the floor needs a friction coefficient mu")
        self.driven = np.array([c.driven for c in self.support.contacts])
        weight = (float(pin.computeTotalMass(robot.model)) + mass) * float(-GRAVITY[2])
        self.least = floor.reserve * weight / len(self.support.contacts)
        self.tilt = float(mu) * math.cos(math.pi / faces) * (1.0 - floor.reserve)
        self.faces = pyramid_faces(faces, heading)
        self.rows = polytope.lifted_rows()
        self.tau = np.arange(len(self.rows.lower))[polytope.variables["tau"]]

    def _program(self, maps: list[ContactMaps]) -> tuple[LinearProgram, np.ndarray, np.ndarray, list[int]]:
        """The program over the polytope's rows and ``maps``' contact rows, with its column bounds
        (the reach s >= 0 and the margin t >= 0; the last two columns) and the first row of each
        sample's contact rows (they run to the end, sample after sample)."""
        rows, n = self.rows, len(self.rows.lower)
        splits = [m.split.shape[1] for m in maps]
        first = np.concatenate([[0], np.cumsum(splits)]).astype(int)
        cols = n + int(first[-1]) + 2
        s_col, t_col = cols - 2, cols - 1
        fix = np.zeros((len(rows.task), cols))
        fix[np.arange(len(rows.task)), rows.task] = 1.0
        fix[:, s_col] = -self.d  # the task point is s d
        blocks = [np.c_[rows.A_eq, np.zeros((len(rows.A_eq), cols - n))], fix,
                  np.c_[rows.A_ub, np.zeros((len(rows.A_ub), cols - n))]]  # fmt: skip
        lo = [rows.b_eq, np.zeros(len(rows.task)), np.full(len(rows.b_ub), -np.inf)]
        hi = [rows.b_eq, np.zeros(len(rows.task)), rows.b_ub]
        lean = math.sqrt(1.0 + self.tilt**2)  # a pyramid row's norm over (f_t, f_n): its margin in N
        first_row = []
        for k, m in enumerate(maps):
            first_row.append(sum(len(b) for b in blocks))
            N, n0 = m.normal
            block = np.zeros((len(N), cols))
            block[:, self.tau] = -N
            block[:, t_col] = 1.0  # N tau + n0 >= least + t
            blocks.append(block)
            lo.append(np.full(len(N), -np.inf))
            hi.append(n0 - self.least)
            T, t0 = m.tangential
            for j, wheel in enumerate(np.flatnonzero(self.driven)):
                # faces . (T tau + t0 + F s) <= tilt (N tau + n0) - lean t
                block = np.zeros((len(self.faces), cols))
                block[:, self.tau] = self.faces @ T[2 * j : 2 * j + 2] - self.tilt * N[wheel]
                block[:, n + first[k] : n + first[k + 1]] = self.faces @ m.split[2 * j : 2 * j + 2]
                block[:, t_col] = lean
                blocks.append(block)
                lo.append(np.full(len(self.faces), -np.inf))
                hi.append(self.tilt * n0[wheel] - self.faces @ t0[2 * j : 2 * j + 2])
        lower = np.r_[rows.lower, np.full(cols - n - 2, -np.inf), 0.0, 0.0]
        upper = np.r_[rows.upper, np.full(cols - n - 2, np.inf), np.inf, np.inf]
        program = LinearProgram(np.vstack(blocks), np.concatenate(lo), np.concatenate(hi), lower, upper)
        return program, lower, upper, first_row

    def _box(self, lower: np.ndarray, upper: np.ndarray, around: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Narrow the efforts' column bounds to ``around`` (efforts, radii), in place."""
        if around is not None:
            lower[self.tau] = np.maximum(lower[self.tau], around[0] - around[1])
            upper[self.tau] = np.minimum(upper[self.tau], around[0] + around[1])

    def _most_margin(
        self, program, lower, upper, s: float, row_lo=None, row_hi=None
    ) -> tuple[float, np.ndarray] | None:
        """(the largest margin t, the solution) at the reach s (the margin may be negative), with
        the rows' bounds ``row_lo``, ``row_hi`` when given."""
        lower, upper = lower.copy(), upper.copy()
        lower[-2] = upper[-2] = s
        lower[-1] = -np.inf
        margin = np.zeros(len(lower))
        margin[-1] = 1.0
        return program.solve(margin, True, lower, upper, row_lo, row_hi)

    def widest(
        self, maps: list[ContactMaps], below: float, around: tuple[np.ndarray, np.ndarray] | None = None
    ) -> tuple[float, Witness] | None:
        """(the largest reach around a replay's states (its contact ``maps``), the efforts with the
        most margin ``below`` under it), or None when even the smallest reach has no margin there.
        ``around``: (efforts, radii): only efforts within the radii of those."""
        program, lower, upper, _ = self._program(maps)
        self._box(lower, upper, around)
        widest = np.zeros(len(lower))
        widest[-2] = 1.0
        found = program.solve(widest, True, lower, upper)
        if found is None:
            return None
        bound = float(found[0])
        found = self._most_margin(program, lower, upper, max(bound - below, 0.0))
        if found is None:  # pragma: no cover - the first program's point is feasible here
            return None
        return bound, self.polytope.witness_of(found[1][: len(self.rows.lower)])

    def longest(
        self, maps: list[ContactMaps], s: float, around: tuple[np.ndarray, np.ndarray] | None = None
    ) -> Witness | None:
        """The efforts at the reach s with the most margin over the longest run of a replay's
        first samples (their contact ``maps``) whose rows admit s with a margin >= 0 (found by
        bisection over the run's length), or None when not even the first sample does.
        ``around``: (efforts, radii): only efforts within the radii of those."""

        program, lower, upper, first_row = self._program(maps)
        self._box(lower, upper, around)
        row_lo, row_hi = program.row_bounds()

        def margin(count: int) -> tuple[float, np.ndarray] | None:
            lo, hi = row_lo.copy(), row_hi.copy()
            if count < len(maps):  # the samples after the first count ones: rows that bind nothing
                lo[first_row[count] :], hi[first_row[count] :] = -np.inf, np.inf
            return self._most_margin(program, lower, upper, s, lo, hi)

        found = margin(len(maps))
        if found is None or found[0] < 0.0:
            low, high, found = 0, len(maps), None
            while high - low > 1:
                middle = (low + high) // 2
                attempt = margin(middle)
                if attempt is not None and attempt[0] >= 0.0:
                    low, found = middle, attempt
                else:
                    high = middle
        return None if found is None else self.polytope.witness_of(found[1][: len(self.rows.lower)])
