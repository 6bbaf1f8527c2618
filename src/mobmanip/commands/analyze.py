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


def _describe(name: str, ellipsoid, unit: str) -> str:
    if ellipsoid.empty:
        return f"{name}: EMPTY (the limits cannot hold the load still)"
    axes = ", ".join(f"{s:.4f}" for s in ellipsoid.semi_axes)
    text = f"{name} semi-axes ({unit}): {axes}; isotropy {ellipsoid.isotropy:.3f}"
    if np.any(ellipsoid.center != 0.0):
        text += f"; centre {np.array2string(ellipsoid.center, precision=4)}"
    if ellipsoid.degenerate:
        text += " [degenerate: zero semi-axis]"
    return text


def run(args) -> int:
    from ..analysis import analyze
    from ..io import write_json

    robot, q = load_robot_and_configuration(args)
    robot = apply_analysis_options(robot, args)
    result = analyze(robot, q, task=args.task, object_mass=args.object_mass, decoupled=args.decoupled)
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
    print(_describe("kinematic ellipsoid", result.kinematic, "m/s, rad/s"))
    coupling = "decoupled" if result.decoupled else "coupled"
    print(_describe(f"dynamic ellipsoid ({coupling})", result.dynamic, "m/s^2, rad/s^2"))
    if args.json:
        write_json(args.json, result.to_dict())
        print(f"wrote {args.json}")
    return 0
