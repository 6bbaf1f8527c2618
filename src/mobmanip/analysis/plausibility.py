"""Plausibility of an analysis: limits that look like placeholders, torques that cannot hold the
arms up, hands that do not hold the object, indices that mix units.

A URDF's limits are often placeholders (every joint at 100 N, 1 rad/s): the ellipsoids computed
from them are exact for those numbers and meaningless for the robot. Nothing here changes a
result; :func:`analysis_warnings` returns the messages that ``Analysis.warnings`` carries (the
commands print them on standard error and write them into the JSON under ``"warnings"``).

A task that mixes linear and angular rows (``spatial``, ``planar_rigid``) has ellipsoids whose
volume and isotropy multiply metres by radians; :func:`block_indices` gives the unit-consistent
indices of each block instead: the volume and isotropy of the set's shadow on its linear rows
(m/s or m/s^2) and on its angular rows (rad/s or rad/s^2).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping

import numpy as np

from ..errors import MobmanipError
from ..postures.named import hand_spread_warnings
from ..robot.model import Robot
from ..robot.tasks import TaskSpace

#: A group of joints sharing one limit value is suspicious from this many joints on.
PLACEHOLDER_MIN_JOINTS = 3

_LIMIT_WARNINGS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def is_round(value: float) -> bool:
    """Whether a limit looks typed in rather than measured: a multiple of 0.5 (1, 2.5, 100)."""
    return math.isfinite(value) and value > 0.0 and abs(value * 2.0 - round(value * 2.0)) < 1e-9


def limit_warnings(robot: Robot) -> tuple[str, ...]:
    """Limits that look like placeholders: within one arm (and the torso with it) of at least
    :data:`PLACEHOLDER_MIN_JOINTS` joints, every joint with the same round velocity or effort
    limit. Computed once per robot."""
    cached = _LIMIT_WARNINGS.get(robot)
    if cached is not None:
        return cached
    names = list(robot.reduced_velocity_names)
    out = []
    for arm in robot.arms:
        joints = list(robot.spec.torso) + list(arm.joint_names)
        cols = [names.index(j) for j in joints if j in names]
        if len(cols) < PLACEHOLDER_MIN_JOINTS:
            continue
        for kind, limits, unit in (
            ("velocity", robot.velocity_limits, "rad/s or m/s"),
            ("effort", robot.effort_limits, "N m or N"),
        ):
            values = limits[cols]
            if np.all(values == values[0]) and is_round(float(values[0])):
                out.append(
                    f"every joint of arm {arm.name!r} ({len(cols)} joints) has the same {kind} limit, "
                    f"{values[0]:g} {unit}: a placeholder of the URDF? The {_quantity(kind)} ellipsoid is only as "
                    f"good as these numbers (set real ones under [limits.{kind}] in the spec)"
                )
    result = tuple(out)
    _LIMIT_WARNINGS[robot] = result
    return result


def _quantity(kind: str) -> str:
    return "kinematic" if kind == "velocity" else "dynamic"


def weight_warnings(robot: Robot, xi: np.ndarray) -> list[str]:
    """Actuators whose effort limit is below the torque that holds the robot still against
    gravity at this configuration (from xi = -S^T g at rest: the inputs tau = -Q^-1 xi)."""
    try:
        held = np.linalg.solve(robot.Q, -np.asarray(xi, dtype=float))
    except np.linalg.LinAlgError:
        return []
    out = []
    for name, need, limit in zip(robot.reduced_velocity_names, held, robot.effort_limits):
        if abs(need) > limit:
            out.append(
                f"{name} needs {abs(need):.3g} (N m or N) to hold the robot's own weight here, more than its effort "
                f"limit {limit:.3g}: the limit is wrong or this posture cannot be held (the dynamic ellipsoid is "
                "empty or shifted far off)"
            )
    return out


def analysis_warnings(robot: Robot, positions: np.ndarray, xi: np.ndarray, held_object=None) -> tuple[str, ...]:
    """Every warning of one configuration: placeholder limits, weight, hands apart."""
    return (
        limit_warnings(robot)
        + tuple(weight_warnings(robot, xi))
        + tuple(hand_spread_warnings(robot, positions, held_object))
    )


def rest_warnings(analysis) -> list[str]:
    """The dynamic ellipsoid excludes rest while every effort that holds the load is within its
    own limit: the ellipsoid's Euclidean norm adds the efforts up, so read literally it says the
    robot cannot hold the object still, which the polytopes (each effort on its own) contradict."""
    from ..sets.ellipsoid import Ellipsoid

    out = []
    for name, task_set in analysis.measures.items():
        if not isinstance(task_set, Ellipsoid) or task_set.empty or name != "dynamic":
            continue
        if task_set.contains(np.zeros(task_set.dim)):
            continue
        terms = analysis.terms
        hold = -terms.xi + terms.J_u.T @ (np.linalg.pinv(terms.W) @ terms.g_o)  # the policy's efforts at rest
        hold = np.linalg.solve(terms.Q, hold)
        share = np.abs(hold) / terms.effort_limits
        if share.max() <= 1.0:
            k = int(np.argmax(share))
            out.append(
                "the dynamic ellipsoid does not contain zero acceleration, yet every effort that holds the object "
                f"still is within its own limit (the largest, {terms.reduced_names[k]}, at {share[k]:.0%}): the "
                "ellipsoid adds all efforts up in one Euclidean norm (||Z tau|| <= 1), so it reads 'cannot hold the "
                "load' where each joint can; the dynamic polytopes (--polytope) bound each effort on its own"
            )
    out.extend(singular_warnings(analysis))
    out.extend(floor_warnings(analysis))
    out.extend(ignored_warnings(analysis))
    return out


def singular_warnings(analysis) -> list[str]:
    """The posture is singular: the kinematic ellipsoid (computed from the terms when the analysis
    did not ask for it) has collapsed (:data:`COLLAPSED_RATIO`). Every set is then flat along
    the lost directions, and the exact ones change by a finite amount under a tilt of the joints
    as small as 1e-8 rad (TIAGo Pro with its arms hanging), so neither their readings nor a
    replay of them says much about the robot."""
    from ..measures import KINEMATIC
    from ..sets.ellipsoid import Ellipsoid, kinematic_ellipsoid

    found = analysis.measures.get(KINEMATIC.name)
    if not isinstance(found, Ellipsoid):
        terms = analysis.terms
        found = kinematic_ellipsoid(terms.J_u, terms.W, terms.velocity_limits)
    if found.empty or not collapsed(found) or _collapsed_everywhere(analysis):
        return []
    semi = np.asarray(found.semi_axes, dtype=float)
    unit = KINEMATIC.quantity.units_for(analysis.task)
    return [
        f"the posture is singular: the kinematic ellipsoid's semi-axes run from {semi[0]:.3g} down to {semi[-1]:.2g} "
        f"({unit}), so every set is flat along some direction and jumps under the smallest change of the joints; "
        "move the joints off the singularity (e.g. --posture or --q) for readings that hold"
    ]


#: How far (rad or m, at random within each joint's range) :func:`singular_warnings` moves the
#: joints to tell a singular posture from a task the robot cannot span anywhere.
SINGULAR_PROBE = 0.3


def _collapsed_everywhere(analysis) -> bool:
    """Whether the kinematic ellipsoid stays collapsed with every one-degree joint moved by up to
    :data:`SINGULAR_PROBE`: then the task has a direction no posture moves the object along (a
    planar robot's z in the spatial task), which is the robot's, not the posture's."""
    from ..sets.ellipsoid import kinematic_ellipsoid
    from ..terms.builder import terms_at

    robot, q = analysis.robot, np.array(analysis.q, dtype=float)
    model = robot.model
    rng = np.random.default_rng(0)
    for joint in model.joints[2:]:  # the platform's root joint is the first
        if joint.nq == 1:
            k = joint.idx_q
            q[k] = np.clip(q[k] + rng.uniform(-SINGULAR_PROBE, SINGULAR_PROBE), model.lowerPositionLimit[k],
                           model.upperPositionLimit[k])  # fmt: skip
    terms = terms_at(robot, q, analysis.task, held_object=analysis.held_object if analysis.object_given else None,
                     check=False)  # fmt: skip
    return collapsed(kinematic_ellipsoid(terms.J_u, terms.W, terms.velocity_limits))


def ignored_warnings(analysis) -> list[str]:
    """The constraints asked for that a computed measure cannot honour (an ellipsoid: a quadratic
    form has no room for a floor's rows), by measure, and the measures that do."""
    from ..measures import get_measure

    ignored = {name: analysis.ignored_constraints(name) for name in analysis.measures}
    ignored = {name: which for name, which in ignored.items() if which}
    if not ignored:
        return []
    honour = sorted(n for n in ("kinematic_polytope", "dynamic_polytope") if get_measure(n).honours_constraints)
    return [
        f"the {name} measure ignores the {', '.join(which)} constraint(s) asked for: an ellipsoid cannot honour "
        f"them; the polytopes do ({', '.join(honour)})"
        for name, which in ignored.items()
    ]


def floor_warnings(analysis) -> list[str]:
    """A grounded set that is empty, with the reason at rest: with compliant sharing, the supports
    that the robot's weight (and the object's) would unload, standing still (the zero-moment point
    at the centre of mass, outside the support's core); else the efforts or the traction."""
    import pinocchio as pin

    out = []
    for name, task_set in analysis.measures.items():
        model = getattr(task_set, "model", None)
        if not isinstance(model, dict) or "floor" not in model:
            continue
        if not task_set.empty and getattr(task_set, "degenerate", False):
            widths = [task_set.support(e) + task_set.support(-e) for e in np.eye(task_set.dim)]
            if model["floor"].get("mu") == 0.0:
                why = "with mu = 0 the wheels can neither push nor hold along the floor"
            else:
                why = (
                    "the floor's rows and the set's own policy leave almost no motion (e.g. the minimum-norm "
                    "policy cannot keep the object level in a translational task)"
                )
            out.append(
                f"{name} on the floor has collapsed (no extent along some direction; its widths along the task "
                f"axes {', '.join(f'{w:.3g}' for w in widths)}): {why}"
            )
            continue
        if not task_set.empty:
            continue
        floor = model["floor"]
        robot, obj = analysis.robot, analysis.held_object
        mass = float(pin.computeTotalMass(robot.model))
        com = pin.centerOfMass(robot.model, robot.data, analysis.q) * mass
        com = (com + obj.mass * np.asarray(obj.center, dtype=float)) / (mass + obj.mass)
        # standing still, the floor's centre of pressure is below the centre of mass along gravity
        # (straight below it on a level floor, downhill of it on a ramp)
        gravity = np.asarray(floor.get("gravity", (0.0, 0.0, -1.0)), dtype=float)
        floor_z = float(np.mean([c["point"][2] for c in floor["contacts"]]))
        centre = com[:2] - (com[2] - floor_z) * gravity[:2] / gravity[2]
        points = np.array([c["point"][:2] for c in floor["contacts"]])
        middle = points.mean(axis=0)
        plate = np.column_stack([np.ones(len(points)), points - middle])  # deflections, affine
        k = np.array([c.get("stiffness", 1.0) for c in floor["contacts"]])
        springs = "equally stiff contacts" if np.all(k == k[0]) else "the contacts' stiffness"
        # f = K plate theta balancing a unit weight at the centre: plate^T K plate theta = (1, centre)
        normals = k * (plate @ np.linalg.solve(plate.T @ (k[:, None] * plate), np.r_[1.0, centre - middle]))
        reserve = float(floor.get("reserve") or 0.0)  # each support's least share of the weight
        unloaded = [c["name"] for c, f in zip(floor["contacts"], normals) if f <= reserve / len(normals)]
        if floor.get("load") == "compliant" and unloaded:
            below = "unload" if reserve == 0.0 else f"bring below its reserve ({reserve:g} of an equal share)"
            out.append(
                f"{name} on the floor is empty: standing still, with {springs}, the weight would "
                f"{below} {', '.join(unloaded)} (the centre of mass, seen along gravity on the floor at "
                f"({centre[0]:.3f}, {centre[1]:.3f}) m, is outside the support's core; compliant sharing keeps every "
                "support loaded); --load any gives the tip-over limit, with optimistic traction"
            )
        else:
            out.append(
                f"{name} on the floor is empty: the robot cannot hold the object still on its support within its "
                "effort limits and the wheels' friction"
            )
    return out


#: Below this ratio of its smallest to its largest semi-axis a set counts as collapsed (a
#: singular posture): a measure of it, and any ratio to it, says more about the singularity than
#: about the robot's capacity.
COLLAPSED_RATIO = 1e-3


def collapsed(task_set) -> bool:
    """Whether an ellipsoid is empty or has collapsed (:data:`COLLAPSED_RATIO`)."""
    if task_set.empty:
        return True
    semi = np.asarray(task_set.semi_axes, dtype=float)
    return bool(semi[0] <= 0.0 or semi[-1] < COLLAPSED_RATIO * semi[0])


def mixes_units(task: TaskSpace) -> bool:
    """Whether the task has both linear and angular rows (its volume multiplies m by rad)."""
    return bool(task.linear_rows) and bool(task.angular_rows)


def block_indices(task: TaskSpace, sets: Mapping[str, object]) -> dict[str, dict] | None:
    """Unit-consistent indices of each set of a mixed task, per block.

    Args:
        task: the task space.
        sets: task-space sets by measure name (:class:`mobmanip.sets.taskset.TaskSet`).

    Returns:
        ``None`` for a task that does not mix units; else, per measure name, ``{"linear":
        {...}, "angular": {...}}`` with each block's ``volume`` and ``isotropy`` (of the set's
        shadow on those rows) and ``reach`` (its largest extent from the centre along them);
        a value that cannot be computed is ``None``.
    """
    if not mixes_units(task):
        return None
    out = {}
    for name, task_set in sets.items():
        blocks = {}
        for block, rows in (("linear", task.linear_rows), ("angular", task.angular_rows)):
            blocks[block] = _block(task_set, rows)
        out[name] = blocks
    return out


def _block(task_set, rows) -> dict:
    entry: dict = {"rows": list(rows), "volume": None, "isotropy": None, "reach": None}
    try:
        shadow = task_set.project(tuple(rows))
    except MobmanipError:
        return entry
    for key, get in (
        ("volume", lambda: shadow.volume),
        ("isotropy", lambda: shadow.isotropy),
        ("reach", lambda: max(shadow.radius_along(e) for e in np.eye(len(rows))) if not shadow.empty else 0.0),
    ):
        try:
            value = float(get())
        except MobmanipError:
            continue
        entry[key] = value if math.isfinite(value) else None
    if not task_set.empty and hasattr(shadow, "semi_axes"):
        entry["semi_axes"] = [float(v) for v in shadow.semi_axes]
    return entry
