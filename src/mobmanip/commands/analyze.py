"""``mobmanip analyze ROBOT``: analyse one configuration, print a summary, optionally write JSON.

``--polytope`` adds the exact capacity polytopes to the measures; the summary gives each
polytope's reach along its ellipsoid's principal axes (the ellipsoid of the same quantity, from
its centre, both ways) beside the ellipsoid's semi-axes, and their ratio, and along each task
axis its straight-line reach (from rest, exactly along the axis) and its support (the other
components free). ``--ground`` (``--mu``, ``--no-traction``) computes the polytopes on the floor
and names, for each axis, what stops it: a joint's effort, a wheel's traction or a support
lifting off, with the zero-moment point and its margin to the support polygon. ``--hold SECONDS``
(on the floor, with a traction limit) gives, beside each axis maximum, the largest straight-line
reach whose efforts, held constant from rest in mobmanip's own model, hold that long, with those
efforts (:func:`mobmanip.motion.hold.held_reach`), and how long the efforts that hold the maximum
longest hold it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..support.reading import decimal
from .common import (
    add_configuration_command,
    add_json_option,
    configuration_from_command,
    describe_reaches,
    format_matrix,
    print_warnings,
)


def register(sub) -> None:
    parser = add_configuration_command(sub, "analyze", "analyse one configuration")
    parser.add_argument(
        "--hold",
        type=decimal,
        metavar="SECONDS",
        help="on the floor: also the straight-line reach along each axis whose efforts, held constant from rest, "
        "keep every support loaded and every wheel within friction for SECONDS (e.g. 0.02; at most 1)",
    )
    add_json_option(parser, "the full result")
    parser.set_defaults(func=run)


#: The longest --hold (s): constant efforts replayed longer say little about a real motion.
LONGEST_HOLD = 1.0


def _check_hold(args, constraints) -> float | None:
    """--hold's duration, or None; refused without a floor that limits traction."""
    from ..errors import ArgumentError

    hold = getattr(args, "hold", None)
    if hold is None:
        return None
    if not (math.isfinite(hold) and 0.0 < hold <= LONGEST_HOLD):
        raise ArgumentError(f"--hold must be a duration in (0, {LONGEST_HOLD:g}] s, got {hold!r}")
    floor = _floor_of(constraints)
    if floor is None or floor.lift or floor.mu is None:
        raise ArgumentError(
            "--hold replays efforts on the floor: it needs --ground with a traction limit (not --no-traction)"
        )
    if floor.slope:
        raise ArgumentError("--hold replays efforts on a level floor: a ramp (--slope) is not modelled there")
    return float(hold)


def _floor_of(constraints):
    """The floor among ``constraints`` (the options put it first when given), or None."""
    from ..terms.constraints.floor import Floor

    return next((c for c in constraints if isinstance(c, Floor)), None)


def _add_held(robot, q, result, document, duration: float, floor) -> None:
    """Each grounded polytope's axis entries gain ``held``: the reach that holds ``duration``."""
    from ..measures import get_measure
    from ..motion.hold import held_reach

    for name, task_set in result.measures.items():
        entry = document[get_measure(name).json_key]
        reaches = entry.get("reaches")
        if not reaches or "floor" not in entry.get("model", {}) or "tau" not in getattr(task_set, "variables", {}):
            continue
        for k, reach in enumerate(reaches):
            direction = np.zeros(task_set.dim)
            direction[k // 2] = 1.0 if k % 2 == 0 else -1.0
            found = held_reach(robot, q, task_set, direction, result.task, object_mass=result.held_object.mass,
                               floor=floor, duration=duration)  # fmt: skip
            held = found.hold
            reach["held"] = {
                "duration": duration,
                "straight_line": found.reach,
                # what achieves it: the efforts replayed and the floor's normal forces at the start
                "efforts": None if found.witness is None else found.witness.variables["tau"].tolist(),
                "normal_forces": None if held is None else dict(zip(held.contacts, held.normal[0].tolist())),
                "gives_way": None if held is None else held.binds,
                "instant_fraction": found.fraction,
                "instant_efforts": None
                if found.instant_witness is None
                else found.instant_witness.variables["tau"].tolist(),
                "instant_holds_for": found.instant_hold.held,
                "instant_gives_way": found.instant_hold.binds,
            }


def _describe_ellipsoid(name: str, ellipsoid, unit: str) -> str:
    axes = ", ".join(f"{s:.4f}" for s in ellipsoid.semi_axes)
    text = f"{name} semi-axes ({unit}): {axes}; isotropy {ellipsoid.isotropy:.3f}"
    return _centre_and_degeneracy(text, ellipsoid, "zero semi-axis")


def _describe_set(name: str, task_set, unit: str) -> str:
    """Any task-space set: its reach from its centre along each task axis, both ways."""
    m = task_set.dim
    reach = [f"-{task_set.radius_along(-e):.4f} .. +{task_set.radius_along(e):.4f}" for e in np.eye(m)]
    # a polytope of more than 3 task dimensions has no vertices, so no isotropy (its reaches are LPs)
    isotropy = f"isotropy {task_set.isotropy:.3f}" if _available(lambda: task_set.isotropy) else "isotropy n/a"
    text = f"{name} reach along the task axes ({unit}): {'; '.join(reach)}; {isotropy}"
    return _centre_and_degeneracy(text, task_set, "no reach in some direction")


def _centre_and_degeneracy(text: str, task_set, degenerate: str) -> str:
    """``text`` followed by the set's centre where it is off the origin, and by ``[degenerate:
    <degenerate>]`` where the set is."""
    if np.any(task_set.center != 0.0):
        text += f"; centre {np.array2string(task_set.center, precision=4)}"
    if task_set.degenerate:
        text += f" [degenerate: {degenerate}]"
    return text


def _volume_text(task_set, reference=None) -> str:
    """``volume V`` (and its ratio to the reference's), or ``volume n/a (why)``: never NaN."""
    from ..errors import MobmanipError

    try:
        volume = float(task_set.volume)
    except MobmanipError as error:
        return f"volume n/a ({error})"
    text = f"volume {volume:.4g}"
    if reference is not None and not reference.empty and reference.volume > 0.0:
        text += f" ({volume / reference.volume:.3f} x the ellipsoid's)"
    return text


def _describe_polytope(name: str, polytope, unit: str, ellipsoid=None) -> str:
    """A polytope: its reach along the ellipsoid's axes (both ways, from the ellipsoid's centre)
    beside the ellipsoid's semi-axes and the ratio; without an ellipsoid, along the task axes."""
    if ellipsoid is None or ellipsoid.empty or ellipsoid.dim != polytope.dim:
        return f"{_describe_set(name, polytope, unit)}; {_volume_text(polytope)}"
    lines = [f"{name} ({unit}): reach along the ellipsoid's axes, from its centre"]
    c = ellipsoid.center
    for k, (axis, s) in enumerate(zip(ellipsoid.axes, ellipsoid.semi_axes), start=1):
        plus = polytope.support(axis) - float(axis @ c)
        minus = polytope.support(-axis) + float(axis @ c)
        if s > 0.0:
            ratio = f"ratio {plus / s:.3f} / {minus / s:.3f}"
        else:
            ratio = "ratio n/a (zero semi-axis)"
        direction = "(" + ", ".join(f"{v:.3f}" for v in np.round(axis, 3) + 0.0) + ")"  # no "-0.000"
        # the polytope's extent along the axis as coordinates from the centre (both signs when it
        # lies to one side of the centre: "+0.0095 / +0.0085")
        lines.append(f"  axis {k} {direction}: ellipsoid {s:.4f}, polytope {plus:+.4f} / {-minus:+.4f}, {ratio}")
    isotropy = f"isotropy {polytope.isotropy:.3f}" if _available(lambda: polytope.isotropy) else "isotropy n/a"
    tail = f"  {_volume_text(polytope, ellipsoid)}; {isotropy}"
    if polytope.degenerate:
        tail += " [degenerate: no reach in some direction]"
    lines.append(tail)
    return "\n".join(lines)


def _describe_blocks(blocks: dict, units: str) -> str:
    """The per-block (linear, angular) indices of a set in a mixed task, each in its own unit."""
    linear_unit, _, angular_unit = units.partition(", ")
    parts = []
    for block, unit in (("linear", linear_unit), ("angular", angular_unit or linear_unit)):
        entry = blocks[block]
        values = []
        if entry.get("semi_axes"):
            values.append("semi-axes " + ", ".join(f"{v:.4g}" for v in entry["semi_axes"]))
        for key, fmt in (("reach", ".4g"), ("volume", ".4g"), ("isotropy", ".3f")):
            if key == "reach" and entry.get("semi_axes"):
                continue
            value = entry.get(key)
            values.append(f"{key} {'n/a' if value is None else format(value, fmt)}")
        parts.append(f"{block} ({unit}): " + ", ".join(values))
    return "  per block: " + "; ".join(parts)


def _available(get) -> bool:
    from ..errors import MobmanipError

    try:
        get()
    except MobmanipError:
        return False
    return True


#: How the summary describes a set, by its kind (other kinds: :func:`_describe_set`).
DESCRIBE: dict[str, Callable[..., str]] = {"ellipsoid": _describe_ellipsoid, "polytope": _describe_polytope}


def _describe(name: str, task_set, unit: str, ellipsoid=None) -> str:
    if task_set.empty:
        if "floor" in getattr(task_set, "model", {}):
            return f"{name}: EMPTY (on the floor as modelled; the warning below says why)"
        return f"{name}: EMPTY (the limits cannot hold the load still)"
    describe = DESCRIBE.get(task_set.kind, _describe_set)
    if task_set.kind == "polytope":
        return describe(name, task_set, unit, ellipsoid)
    return describe(name, task_set, unit)


def _ellipsoid_of(result, quantity):
    """The first ellipsoid of ``quantity`` the analysis holds (the polytopes are compared with it)."""
    from ..measures import get_measure

    for name, task_set in result.measures.items():
        if task_set.kind == "ellipsoid" and get_measure(name).quantity == quantity:
            return task_set
    return None


def run(args) -> int:
    from ..analysis.single import analyze
    from ..measures import get_measure
    from ..support.files import require_finite, write_json

    robot, q, options = configuration_from_command(args)
    constraints = options["constraints"]
    hold = _check_hold(args, constraints)
    # one configuration: the reference path, which needs no compiled kernel and gives the same
    # numbers whatever this process ran before
    result = analyze(robot, q, task=args.task, method="exact", **options)
    document = result.to_dict()
    if hold is not None:
        _add_held(robot, q, result, document, hold, _floor_of(constraints))
    require_finite(document)  # never a NaN or an infinity printed as a result
    print(f"robot {robot.name} ({robot.platform.kind}), task {result.task}, {robot.nx} reduced velocities")
    print("reduced velocities: " + ", ".join(robot.reduced_velocity_names))
    for arm, pos in zip(robot.arms, result.end_effector_positions):
        print(f"end effector {arm.end_effector}: ({pos[0]:.3f}, {pos[1]:.3f}, {pos[2]:.3f}) m")
    center = result.held_object.center
    print(f"task point: ({center[0]:.3f}, {center[1]:.3f}, {center[2]:.3f}) m, object {result.held_object.mass:g} kg")
    print("unified Jacobian J_u:")
    print(format_matrix(result.unified_jacobian))
    eigenvalues = np.linalg.eigvalsh(result.reduced_inertia)
    print(f"reduced inertia P: eigenvalues {np.array2string(eigenvalues, precision=4)}")
    coupling = "decoupled" if result.decoupled else "coupled"
    blocks = result.block_indices()
    for name, task_set in result.measures.items():
        measure = get_measure(name)
        units = measure.quantity.units_for(result.task)
        label = f"{measure.label} ({coupling})" if measure.quantity.inertial else measure.label
        ignored = result.ignored_constraints(name)
        if ignored:
            label += f" [ignores {', '.join(ignored)}: an ellipsoid cannot honour it]"
        print(_describe(label, task_set, units, _ellipsoid_of(result, measure.quantity)))
        if blocks is not None and not task_set.empty:
            print(_describe_blocks(blocks[name], measure.quantity.units))
        reaches = document[measure.json_key].get("reaches")
        if reaches:
            floor = document[measure.json_key].get("model", {}).get("floor")
            print(describe_reaches(reaches, units, floor))
    if blocks is not None:
        print(
            f"(task {result.task} mixes linear and angular rows: its volumes and isotropies multiply metres by "
            "radians; compare the per-block ones)"
        )
    print_warnings(result)
    if args.json:
        write_json(args.json, document)
        print(f"wrote {args.json}")
    return 0
