"""``mobmanip analyze ROBOT``: analyse one configuration, print a summary, optionally write JSON."""

from __future__ import annotations

import numpy as np

from .common import add_robot_options, format_matrix, load_robot_and_configuration


def register(sub) -> None:
    parser = sub.add_parser("analyze", help="analyse one configuration")
    add_robot_options(parser)
    parser.add_argument("--json", metavar="OUT.json", help="write the full result as JSON")
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..analysis import analyze
    from ..io import write_json

    robot, q = load_robot_and_configuration(args)
    result = analyze(robot, q, task=args.task)
    print(f"robot {robot.name} ({robot.platform.kind}), task {result.task}, {robot.nx} reduced velocities")
    print("reduced velocities: " + ", ".join(robot.reduced_velocity_names))
    for arm, pos in zip(robot.arms, result.end_effector_positions):
        print(f"end effector {arm.end_effector}: ({pos[0]:.3f}, {pos[1]:.3f}, {pos[2]:.3f}) m")
    print("unified Jacobian J_u:")
    print(format_matrix(result.unified_jacobian))
    eigenvalues = np.linalg.eigvalsh(result.reduced_inertia)
    print(f"reduced inertia P: eigenvalues {np.array2string(eigenvalues, precision=4)}")
    if args.json:
        write_json(args.json, result.to_dict())
        print(f"wrote {args.json}")
    return 0
