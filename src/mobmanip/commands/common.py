"""Options and helpers shared by several subcommands."""

from __future__ import annotations

import argparse

import numpy as np

from ..tasks import TASKS


def add_robot_options(parser: argparse.ArgumentParser) -> None:
    """ROBOT, --q and --task."""
    parser.add_argument("robot", help="built-in robot name (e.g. planar_dual_arm) or path of a robot spec (.toml)")
    parser.add_argument(
        "--q", metavar="Q.json", help='configuration {"platform": [x, y, yaw], "joints": {NAME: value}}'
    )
    parser.add_argument("--task", choices=list(TASKS), help="task space (default: the spec's default_task)")


def load_robot_and_configuration(args):
    """The robot named on the command line and its configuration (neutral without --q)."""
    from ..io import read_configuration
    from ..model import load_robot

    robot = load_robot(args.robot)
    q = read_configuration(robot, args.q) if args.q else robot.neutral()
    return robot, q


def format_matrix(matrix: np.ndarray, indent: str = "  ") -> str:
    """Rows of a matrix, aligned, for the console."""
    return "\n".join(indent + " ".join(f"{v:9.4f}" for v in row) for row in np.atleast_2d(matrix))


def add_analysis_options(parser: argparse.ArgumentParser) -> None:
    """Limits, platform and object options shared by analyze, view and sweep."""
    parser.add_argument("--wheel-velocity-limit", type=float, metavar="RAD_S", help="both wheels' qdot_max (rad/s)")
    parser.add_argument("--wheel-effort-limit", type=float, metavar="NM", help="both wheels' tau_max (N m)")
    parser.add_argument("--decoupled", action="store_true", help="neglect platform-arm dynamic interaction")
    parser.add_argument("--platform", choices=["own", "fixed"], default="own", help="'fixed' locks the platform")
    parser.add_argument("--object-mass", type=float, metavar="KG", help="mass of the held object (default: spec)")


def apply_analysis_options(robot, args):
    """The robot with the command line's wheel limits and platform choice applied."""
    if args.wheel_velocity_limit is not None or args.wheel_effort_limit is not None:
        robot = robot.with_wheel_limits(velocity=args.wheel_velocity_limit, effort=args.wheel_effort_limit)
    if args.platform == "fixed":
        robot = robot.with_platform("fixed")
    return robot
