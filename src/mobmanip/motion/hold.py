"""How long a grounded capacity holds: constant efforts replayed from rest in mobmanip's own model.

A capacity is a property of one instant: the efforts that reach a grounded maximum keep every
support loaded and every driven wheel within friction at rest. Held constant, they set the robot
moving, the posture changes and velocity terms appear (centrifugal forces of the arms, the
platform's own), and the contact forces drift: in MuJoCo, TIAGo++'s -x maximum (the arms swing
the held object) unloads a caster and slips a wheel after 7 ms. This module predicts that time
and finds the largest reach that holds for a chosen duration.

The replay integrates the reduced dynamics of the robot holding its object (the hands hold it in
the task's rows and keep it level, as the floor constraint does: a planar task's object may turn
about the vertical in the hands) under constant efforts tau: at each state (q, x), with the terms of
:func:`mobmanip.motion.in_motion.motion_terms`, the reduced accelerations xdot, the hands' wrench h
(m k) and the object's acceleration a_o solve::

    P xdot + J_u^T h = Q tau + xi(q, x)                    (reduced dynamics)
    J_u xdot - W^T a_o = Wdot^T v_o - d/dt(J_u) x           (the hands move with the object)
    W h - M_o a_o = c_o + g_o                               (the object's own dynamics)

(internal wrenches included: two hands on one object form a closed chain), then q and x advance
by a semi-implicit Euler step (x first, q along ``pin.integrate`` with S(q) x). At every step the
floor's resultant wrench (:func:`mobmanip.motion.ground.floor_wrench`, velocity terms included) is
shared by the contacts as the floor constraint shares it
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
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task
from ..sets.lifted import Witness
from ..terms.constraints.floor import LEVEL_ROWS, Floor
from ..terms.grasp import GRAVITY
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
    nx, mk, m = terms.P.shape[0], terms.J_u.shape[0], terms.W.shape[0]
    A = np.zeros((nx + mk + m, nx + mk + m))
    A[:nx, :nx] = terms.P
    A[:nx, nx : nx + mk] = terms.J_u.T
    A[nx : nx + mk, :nx] = terms.J_u
    A[nx : nx + mk, nx + mk :] = -terms.W.T
    A[nx + mk :, nx : nx + mk] = terms.W
    A[nx + mk :, nx + mk :] = -terms.M_o
    b = np.concatenate([terms.Q @ tau + terms.xi, terms.grasp_drift - terms.drift, terms.c_o + terms.g_o])
    solution = np.linalg.lstsq(A, b, rcond=None)[0]
    return solution[:nx], solution[nx : nx + mk], solution[nx + mk :]


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
    for value, what in ((duration, "duration"), (step, "step")):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
            raise ArgumentError(f"the replay's {what} must be a positive number of seconds, got {value!r}")
    q = robot.check_configuration(q)
    tau = np.asarray(tau, dtype=float)
    if tau.shape != (robot.nx,) or not np.all(np.isfinite(tau)):
        raise ArgumentError(f"tau must be {robot.nx} finite efforts (wheels, then joints), got shape {tau.shape}")
    if robot.wheel_platform is None or robot.platform.kind != "differential_drive":
        raise SpecError(
            f"a replay on the floor covers differential-drive platforms; {robot.name!r} has a {robot.platform.kind} "
            "platform"
        )
    floor = Floor() if floor is None else floor
    support, mu, _ = floor.resolve(robot)
    if mu is None:
        raise TaskError("a replay checks the wheels' traction: the floor needs a friction coefficient mu")
    task_space = get_task(task or robot.spec.default_task)
    mass_o = float(robot.spec.object_mass if object_mass is None else object_mass)
    driven = np.array([c.driven for c in support.contacts])
    stiffness = np.array([c.stiffness for c in support.contacts], dtype=float)
    weight = (float(pin.computeTotalMass(robot.model)) + mass_o) * float(-GRAVITY[2])
    least = floor.reserve * weight / len(support.contacts)
    names = tuple(c.name for c in support.contacts)
    wheels = tuple(c.name for c in support.contacts if c.driven)

    # the hands hold the object in the task's rows and keep it level (as the floor constraint
    # does): a planar task's object is held level by the same closed chain that moves it
    held_rows = tuple(sorted(set(task_space.rows) | set(LEVEL_ROWS)))
    labels = get_task("spatial").labels
    welded = TaskSpace(f"{task_space.name}_level", held_rows, tuple(labels[r] for r in held_rows))
    rows = [held_rows.index(r) for r in task_space.rows]
    count = int(math.ceil(duration / step - 1e-9))
    x = np.zeros(robot.nx)
    times, configurations, accelerations, normals, uses = [], [], [], [], []
    binds: str | None = None
    held = duration
    for i in range(count + 1):
        t = i * step
        terms = motion_terms(robot, q, x, welded, object_mass=mass_o)
        xdot, _, a_o = forward_accelerations(terms, tau)
        full = np.zeros(6)
        full[list(held_rows)] = a_o
        offset, linear = floor_wrench(robot, q, x, mass_o, full, np.zeros((6, robot.nx)))
        wrench = offset + linear @ xdot
        force, moment = wrench[:3], wrench[3:]
        if force[2] <= 0.0:
            raise TaskError(f"at t = {t:.6g} s the efforts lift the whole robot off the floor")
        z = support.floor_z
        zmp = np.array([(z * force[0] - moment[1]) / force[2], (moment[0] + z * force[1]) / force[2]])
        pose = (float(q[0]), float(q[1]), math.atan2(float(q[3]), float(q[2])))
        normal, _, use = contact_forces(support.world_points(pose), driven, force, moment, zmp, mu, stiffness)
        times.append(t)
        configurations.append(q)
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
        q = pin.integrate(robot.model, q, step * (terms.S @ x))
    return Hold(
        held=held,
        duration=float(duration),
        binds=binds,
        time=np.array(times),
        q=np.array(configurations),
        object_acceleration=np.array(accelerations),
        normal=np.array(normals),
        use=np.array(uses),
        contacts=names,
        wheels=wheels,
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
        instant_hold: the replay of the instantaneous maximum's efforts (at ``fraction`` of it).
        fraction: the share of the instantaneous maximum ``instant_hold`` replayed.
        witness: the solution whose efforts were replayed at the held reach (None when 0).
    """

    direction: np.ndarray
    reach: float
    instant: float
    duration: float
    hold: Hold | None
    instant_hold: Hold
    fraction: float
    witness: Witness | None


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
) -> HeldReach:
    """The largest straight-line reach along ``direction`` whose efforts, held constant from rest,
    keep every support loaded and every driven wheel within friction for ``duration`` (this
    module's replay).

    The efforts at a point s d of a grounded polytope are its calm witness
    (``witness_at(s d, least="xdot")``: among the solutions with half the most slack, the least
    reduced acceleration). The instantaneous maximum is replayed at ``fraction`` of it (at the
    maximum itself some limit is tight and gives way at once); s is then found by bisection to
    ``tolerance`` times the instantaneous reach, on the assumption that a smaller s holds longer
    (true of every axis of the built-in robots sampled here; a replay at the result is returned,
    so the claim is checked where it is reported).

    Args:
        robot, q, task, object_mass: as the analysis that produced ``polytope``.
        polytope: a grounded dynamic polytope (a :class:`mobmanip.sets.lifted.LiftedPolytope`
            with the efforts ``tau`` among its variables).
        direction: the task direction, (m,) (normalised here).
        floor: the floor the polytope was computed on (its mu and reserve), default ``Floor()``.
        duration: how long the efforts must hold (s).
        fraction: the share of the instantaneous reach replayed first, in (0, 1].
        tolerance: the bisection's resolution, as a share of the instantaneous reach.
        step: the replay's integration step (s).

    Raises:
        TaskError: a polytope without efforts, or a direction not in the task's dimension.
    """
    d = np.asarray(direction, dtype=float)
    if d.shape != (polytope.dim,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0.0:
        raise TaskError(f"the direction must be a nonzero finite {polytope.dim}-vector, got {d.tolist()}")
    d = d / np.linalg.norm(d)
    if "tau" not in getattr(polytope, "variables", {}):
        raise TaskError("a held reach replays efforts: the set must be a polytope with the efforts tau as a variable")
    if not (0.0 < fraction <= 1.0 and 0.0 < tolerance < 1.0):
        raise ArgumentError(f"fraction must be in (0, 1] and tolerance in (0, 1), got {fraction!r}, {tolerance!r}")

    def run(s: float):
        witness = polytope.witness_at(s * d, least="xdot")
        hold = replay(robot, q, witness.variables["tau"], task, object_mass=object_mass, floor=floor,
                      duration=duration, step=step)  # fmt: skip
        return witness, hold

    instant = float(polytope.straight_line_reach(d))
    if instant <= 0.0:
        witness, hold = run(0.0)
        return HeldReach(d, 0.0, 0.0, float(duration), hold if hold.holds else None, hold, fraction,
                         witness if hold.holds else None)  # fmt: skip
    top = fraction * instant
    witness, instant_hold = run(top)
    if instant_hold.holds:
        return HeldReach(d, top, instant, float(duration), instant_hold, instant_hold, fraction, witness)
    best: tuple[float, Hold, Witness] | None = None
    low, high = 0.0, top
    while high - low > tolerance * instant:
        middle = 0.5 * (low + high)
        witness, hold = run(middle)
        if hold.holds:
            low, best = middle, (middle, hold, witness)
        else:
            high = middle
    if best is None:
        witness, hold = run(0.0)
        if not hold.holds:
            return HeldReach(d, 0.0, instant, float(duration), None, instant_hold, fraction, None)
        best = (0.0, hold, witness)
    return HeldReach(d, best[0], instant, float(duration), best[1], instant_hold, fraction, best[2])
