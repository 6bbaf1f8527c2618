"""Subcommands of the ``mobmanip`` command, one module each with a ``register(subparsers)``."""

from . import analyze, carry, init_spec, paper, place, sweep, team, trajectory, view

COMMANDS = (analyze, paper, init_spec, view, sweep, place, trajectory, carry, team)
