"""Each grounded axis maximum replayed in MuJoCo: what ``mobmanip referee`` prints.

For a task axis e and a sense, the grounded straight-line maximum's efforts (or those of a
fraction of it: the calm ones, :meth:`witness_at` with ``least="xdot"``) are applied from rest to
MuJoCo's model of the robot standing on the floor with the object held (:mod:`mobmanip.referee.model`). At
t = 0 MuJoCo's object acceleration, on the task's rows only, is compared with the target the
efforts reach in mobmanip, and every contact's normal force with the floor's prediction; over the
horizon (constant efforts, 20 ms by default) the replay records how far a support rose off the
floor and how fast a driven wheel's contact point slid.

An axis *agrees* when the acceleration is within :data:`ACCELERATION_TOLERANCE` of the predicted
one's norm (largest component error) and, where the floor shares the weight by compliance (the
sharing MuJoCo's equally stiff contacts make), every normal force within
:data:`NORMAL_TOLERANCE` of the weight: with ``load="any"`` the prediction is one balancing
share among many and is printed, not judged. It *holds* when no support rose by more than
:data:`RISE` and no driven wheel slid faster than :data:`SLIDE`. It passes when both.

Both sides hold the same object. The one :meth:`HeldObject.between` makes for a single hand is a
point mass at the hand, which MuJoCo refuses (a free body needs a positive inertia):
:func:`object_for_referee` gives it the inertia of a uniform solid sphere of radius
:data:`POINT_OBJECT_RADIUS` centred at the hand (2/5 m r^2, the same rule as between two hands),
and the analysis replayed is made with that object, so mobmanip and MuJoCo use the same numbers.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError, TaskError
from ..robot.tasks import get_task
from ..terms.constraints.floor import CONTACT_FORCES, ground_reaction
from ..terms.grasp import HeldObject

#: A support that rose more than this off the floor during the replay did not hold (m).
RISE = 1e-4
#: A driven wheel whose contact point slid faster than this did not hold (m/s).
SLIDE = 1e-3
#: A driven wheel using this share of its friction or more is at its limit (MuJoCo's cone caps
#: the use at 1; the rollout's own slip test uses the same).
AT_LIMIT = 0.999
#: MuJoCo's acceleration at t = 0 agrees when its largest error on the task's rows is within this
#: share of the predicted acceleration's norm.
ACCELERATION_TOLERANCE = 0.03
#: A straight-line maximum below this share of the set's longest one (over the axes replayed) is
#: taken as 0: the linear programs behind it hold their equations to about 1e-7 of the set's scale
#: (HiGHS's feasibility tolerance), so a smaller one is their round-off, not a motion to replay.
REACH_RESOLUTION = 1e-6
#: MuJoCo's normal forces at t = 0 agree when each is within this share of the weight of the
#: predicted one (judged where the floor shares the weight by compliance).
NORMAL_TOLERANCE = 1e-3
#: Radius (m) of the solid sphere whose inertia a one-hand object is given (see the docstring).
POINT_OBJECT_RADIUS = 0.05


def object_for_referee(held: HeldObject) -> HeldObject:
    """The object both sides use: ``held`` itself, or, when its inertia is not positive definite
    (one hand: a point mass), the same object with the inertia of a uniform solid sphere of
    radius :data:`POINT_OBJECT_RADIUS` about its centre.

    Raises:
        ArgumentError: an object without mass (MuJoCo's model holds a body of positive mass).
    """
    if held.mass <= 0.0:
        raise ArgumentError("the referee holds the object in MuJoCo as a body: give it a positive --object-mass")
    if np.linalg.eigvalsh(held.inertia)[0] > 0.0:
        return held
    inertia = 0.4 * held.mass * POINT_OBJECT_RADIUS**2 * np.eye(3)
    return dataclasses.replace(held, inertia=inertia)


@dataclass
class AxisReplay:
    """One axis and sense replayed in MuJoCo.

    Attributes:
        axis: its label, e.g. ``"+x"``.
        direction: the task direction, (m,).
        reach: the grounded straight-line maximum along it (task units).
        target: the task acceleration the replayed efforts reach in mobmanip, (m,); ``None``
            when the reach is 0 (nothing to replay).
        acceleration: MuJoCo's on the task's rows at t = 0, (m,).
        acceleration_error: its largest component error, as a share of ``|target|``.
        normals: contact name -> (predicted, MuJoCo's) normal force at t = 0 (N).
        normal_error: the largest normal force difference (N).
        rise: how far a support rose off the floor during the replay (m; 0 if none did).
        slide: the fastest slide of a driven wheel's contact point (m/s).
        weight: the weight of the robot and the object (N).
        judge_normals: whether the normal forces take part in the verdict.
        first_failure: the first support to rise or driven wheel to slide during the replay,
            ``None`` if none did: its name, ``"rises"`` or ``"slides"``, when (s), and its
            normal force and traction use at t = 0 and then (what moved it to its limit).
        extra: what the caller adds to the JSON (e.g. a predicted hold time).
    """

    axis: str
    direction: np.ndarray
    reach: float
    target: np.ndarray | None
    acceleration: np.ndarray | None = None
    acceleration_error: float = 0.0
    normals: dict[str, tuple[float, float]] = field(default_factory=dict)
    normal_error: float = 0.0
    rise: float = 0.0
    slide: float = 0.0
    weight: float = 1.0
    judge_normals: bool = True
    first_failure: dict | None = None
    extra: dict = field(default_factory=dict)

    @property
    def replayed(self) -> bool:
        return self.target is not None

    @property
    def agrees(self) -> bool:
        """MuJoCo at t = 0 as predicted (see the module's docstring)."""
        if not self.replayed:
            return True
        normals = not self.judge_normals or self.normal_error <= NORMAL_TOLERANCE * self.weight
        return self.acceleration_error <= ACCELERATION_TOLERANCE and normals

    @property
    def holds(self) -> bool:
        """No support rose, no driven wheel slid during the replay."""
        return self.rise <= RISE and self.slide <= SLIDE

    @property
    def passed(self) -> bool:
        return self.agrees and self.holds

    def to_dict(self) -> dict:
        out: dict = {"axis": self.axis, "direction": self.direction.tolist(), "reach": self.reach}
        if self.target is None or self.acceleration is None:
            return {**out, "replayed": False, "passed": True}
        out.update(
            replayed=True,
            target=self.target.tolist(),
            acceleration=self.acceleration.tolist(),
            acceleration_error=self.acceleration_error,
            normal_forces={name: {"predicted": p, "mujoco": m} for name, (p, m) in self.normals.items()},
            normal_error=self.normal_error,
            normal_error_of_weight=self.normal_error / self.weight,
            normals_judged=self.judge_normals,
        )
        verdict = ("rise", "slide", "agrees", "holds", "first_failure", "passed")
        out.update({name: getattr(self, name) for name in verdict})
        return {**out, **self.extra}


def axis_directions(task: str) -> list[tuple[str, np.ndarray]]:
    """Each task axis in both senses: ``("+x", e_x), ("-x", -e_x), ...``."""
    labels = get_task(task).labels
    out = []
    for k, name in enumerate(labels):
        for sign in (1.0, -1.0):
            e = np.zeros(len(labels))
            e[k] = sign
            out.append((f"{'+' if sign > 0 else '-'}{name}", e))
    return out


def replay_axis(referee, grounded, task: str, axis: str, direction, reach: float, target, witness, *, duration=0.02):
    """Apply a witness's efforts (mobmanip's reduced efforts, which reach ``target`` on the task
    in the grounded set ``grounded``) from rest in ``referee``; see the module's docstring.

    Args:
        referee: the :class:`~mobmanip.referee.model.Referee` built for the same robot, posture,
            object and floor (its contacts named as the floor's).
        grounded: the grounded set replayed (its ``model["floor"]`` gives the contacts).
        task: the task name.
        axis, direction, reach: the axis's label, direction and straight-line maximum.
        target: the task acceleration the witness reaches in mobmanip, (m,).
        witness: a point of ``grounded`` (its variables ``tau`` and the contact forces).
        duration: how long they are held (s).
    """
    info, tau = grounded.model["floor"], witness.variables["tau"]
    goal = np.asarray(target, dtype=float)
    found = AxisReplay(axis, np.asarray(direction, dtype=float), float(reach), goal)
    found.weight = referee.weight
    found.judge_normals = info.get("load") == "compliant"
    forces = np.asarray(witness.variables[CONTACT_FORCES], dtype=float)
    traction = {c["name"]: forces[c["columns"][0] : c["columns"][0] + 2] for c in info["contacts"] if c["driven"]}
    acceleration, contacts = referee.forward(tau, traction)
    if acceleration.ndim == 2:  # no object: the first hand's
        acceleration = acceleration[0]
    found.acceleration = acceleration[list(get_task(task).rows)]
    scale = float(np.linalg.norm(goal))
    found.acceleration_error = float(np.abs(found.acceleration - goal).max()) / scale if scale else 0.0
    predicted = ground_reaction(info, witness.variables[CONTACT_FORCES])["contacts"]
    for name, entry in predicted.items():
        found.normals[name] = (float(entry["normal"]), float(contacts[name].normal))
    found.normal_error = max((abs(p - m) for p, m in found.normals.values()), default=0.0)
    run = referee.rollout(tau, duration=duration, traction=traction)
    found.rise = max(float(-run.penetration.min()), 0.0)
    driven = [k for k, s in enumerate(run.supports) if s.driven]
    found.slide = max((float(run.slip_speed[:, k].max()) for k in driven), default=0.0)
    found.first_failure = first_failure(run)
    return found


def first_failure(run) -> dict | None:
    """What gave way first in a rollout where a support rose more than :data:`RISE` or a driven
    wheel slid faster than :data:`SLIDE`: the earliest of a support rising, a support losing its
    load, a driven wheel reaching its friction limit (the cause of a slide, which follows) and a
    wheel sliding: ``{"support", "event", "time" (s), "normal" (N, at t = 0 and then),
    "traction_use" (at t = 0 and then; driven wheels)}``, or ``None`` when nothing rose or slid."""
    order = ("rises", "unloads", "reaches its friction limit", "slides")
    failed, events = False, []
    for k, support in enumerate(run.supports):
        found = {"rises": -run.penetration[:, k] > RISE, "unloads": run.normal[:, k] <= 0.0}
        if support.driven:
            found["reaches its friction limit"] = run.friction_use[:, k] >= AT_LIMIT
            found["slides"] = run.slip_speed[:, k] > SLIDE
        failed |= bool(found["rises"].any()) or bool(found.get("slides", np.zeros(1, bool)).any())
        for event, steps in found.items():
            if steps.any():
                events.append((int(np.argmax(steps)), order.index(event), k, event))
    if not failed:
        return None
    step, _, k, event = min(events)
    out = {
        "support": run.supports[k].name,
        "event": event,
        "time": float(run.time[step]),
        "normal": [float(run.normal[0, k]), float(run.normal[step, k])],
    }
    if run.supports[k].driven:
        out["traction_use"] = [float(run.friction_use[0, k]), float(run.friction_use[step, k])]
    return out


def replay_maxima(referee, grounded, task: str, *, fraction: float = 1.0, duration: float = 0.02) -> list[AxisReplay]:
    """Every task axis, both senses: ``fraction`` of the grounded straight-line maximum, reached
    with the calm efforts (the least reduced acceleration among those with half the most slack;
    at the maximum itself, where that program may find the point a hair outside the set, the
    maximum's own witness), replayed by :func:`replay_axis`; an axis whose maximum is 0 (to
    :data:`REACH_RESOLUTION` of the longest) is listed with a reach of 0, not replayed."""
    out = []
    axes = axis_directions(task)
    reaches = [float(grounded.straight_line_reach(e)) for _, e in axes]
    resolution = REACH_RESOLUTION * max(reaches, default=0.0)
    for (axis, e), reach in zip(axes, reaches):
        if reach <= resolution:
            out.append(AxisReplay(axis, e, 0.0, None))
            continue
        target = fraction * reach * e
        try:
            witness = grounded.witness_at(target, least="xdot")
        except TaskError:  # the maximum itself, a hair outside the set as the calm program reads it
            if fraction < 1.0:
                raise
            witness = grounded.straight_line_witness(e)
        out.append(replay_axis(referee, grounded, task, axis, e, reach, target, witness, duration=duration))
    return out
