"""Subcommands of the ``mobmanip`` command, one module each with a ``register(subparsers)``.

A command's module is named after the command (``team-carry``: :mod:`.team_carry`) and is
imported when first needed: a command line names one command, and the ``mobmanip`` process
imports that command's module alone (:func:`mobmanip.cli.build_parser`).
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import Any

#: The commands' modules, in the order ``mobmanip --help`` lists them.
MODULES = (
    "analyze",
    "paper",
    "init_spec",
    "view",
    "sweep",
    "place",
    "collision_matrix",
    "site",
    "trajectory",
    "carry",
    "team",
    "team_carry",
    "referee",
    "payload",
    "brake",
    "retime",
    "warmup",
)
#: Command name (as typed) -> its module's name.
NAMES = {module.replace("_", "-"): module for module in MODULES}


def command_module(name: str) -> ModuleType:
    """The module of the command ``name`` (as typed, e.g. ``team-carry``), imported on first use."""
    return importlib.import_module(f".{NAMES[name]}", __name__)


def __getattr__(name: str) -> Any:
    """``COMMANDS`` (every command's module, in order) and the modules by name, imported on first use."""
    if name == "COMMANDS":
        return tuple(command_module(command) for command in NAMES)
    if name in MODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
