"""``mobmanip analyze ROBOT``: analyse one configuration, print a summary, optionally write JSON."""

from __future__ import annotations

import numpy as np

from .common import (
    add_analysis_options,
    add_robot_options,
    apply_analysis_options,
    format_matrix,
    load_robot_and_configuration,
)


def register(sub) -> None:
    parser = sub.add_parser("analyze", help="analyse one configuration")
    add_robot_options(parser)
    add_analysis_options(parser)
    parser.add_argument("--json", metavar="OUT.json", help="write the full result as JSON")
    parser.set_defaults(func=run)


def _describe_ellipsoid(name: str, ellipsoid, unit: str) -> str:
    axes = ", ".join(f"{s:.4f}" for s in ellipsoid.semi_axes)
    text = f"{name} semi-axes ({unit}): {axes}; isotropy {ellipsoid.isotropy:.3f}"
    if np.any(ellipsoid.center != 0.0):
        text += f"; centre {np.array2string(ellipsoid.center, precision=4)}"
    if ellipsoid.degenerate:
        text += " [degenerate: zero semi-axis]"
    return text


def _describe_set(name: str, task_set, unit: str) -> str:
    """Any task-space set: its reach from its centre along each task axis, both ways."""
    m = task_set.dim
    reach = [f"-{task_set.radius_along(-e):.4f} .. +{task_set.radius_along(e):.4f}" for e in np.eye(m)]
    text = f"{name} reach along the task axes ({unit}): {'; '.join(reach)}; isotropy {task_set.isotropy:.3f}"
    if np.any(task_set.center != 0.0):
        text += f"; centre {np.array2string(task_set.center, precision=4)}"
    if task_set.degenerate:
        text += " [degenerate: no reach in some direction]"
    return text


#: How the summary describes a set, by its kind (other kinds: :func:`_describe_set`).
DESCRIBE = {"ellipsoid": _describe_ellipsoid}


def _describe(name: str, task_set, unit: str) -> str:
    if task_set.empty:
        return f"{name}: EMPTY (the limits cannot hold the load still)"
    return DESCRIBE.get(task_set.kind, _describe_set)(name, task_set, unit)


def run(args) -> int:
    from ..analysis import analyze
    from ..io import require_finite, write_json
    from ..measures import get_measure

    robot, q = load_robot_and_configuration(args)
    robot = apply_analysis_options(robot, args)
    result = analyze(
        robot, q, task=args.task, object_mass=args.object_mass, decoupled=args.decoupled, measures=args.measures
    )
    document = result.to_dict()
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
    for name, task_set in result.measures.items():
        measure = get_measure(name)
        label = f"{measure.label} ({coupling})" if measure.quantity.inertial else measure.label
        print(_describe(label, task_set, measure.quantity.units))
    if args.json:
        write_json(args.json, document)
        print(f"wrote {args.json}")
    return 0
