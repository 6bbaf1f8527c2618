"""Subcommands of the ``mobmanip`` command, one module each with a ``register(subparsers)``."""

from . import analyze, paper

COMMANDS = (analyze, paper)
