"""Subcommands of the ``mobmanip`` command, one module each with a ``register(subparsers)``."""

from . import (
    analyze,
    brake,
    carry,
    collision_matrix,
    init_spec,
    paper,
    payload,
    place,
    referee,
    retime,
    site,
    sweep,
    team,
    team_carry,
    trajectory,
    view,
)

COMMANDS = (
    analyze,
    paper,
    init_spec,
    view,
    sweep,
    place,
    collision_matrix,
    site,
    trajectory,
    carry,
    team,
    team_carry,
    referee,
    payload,
    brake,
    retime,
)
