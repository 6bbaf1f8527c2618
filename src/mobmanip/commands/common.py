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
