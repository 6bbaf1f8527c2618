"""Subcommands of the ``mobmanip`` command, one module each with a ``register(subparsers)``."""

from . import analyze, carry, init_spec, paper, place, site, sweep, team, team_carry, trajectory, view

COMMANDS = (analyze, paper, init_spec, view, sweep, place, site, trajectory, carry, team, team_carry)
