"""Constraints the command line can ask for: one option each, registered as measures are.

A constraint (:class:`~mobmanip.terms.constraints.base.Constraint`) reaches the Python API as
soon as it is written. To reach the command line it needs an option: one
:class:`ConstraintOption` and one :func:`register_constraint_option` call::

    register_constraint_option(ConstraintOption("--effort-share", EffortShare, "keep every effort ..."))

Every command that takes the floor's options (``--ground``, ``--mu``, ...) then takes the option
too. The commands whose problems the constraint's rows join (the capacity sets at rest:
``analyze``, ``sweep``, ``team``, ``view``, ``payload``, ``place`` with a measure's reading) add
it to their constraints; every other one refuses it in one line naming the option, the
constraint and what the command solves instead, never drops it. The floor keeps its own options
(several flags build one constraint).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from ...errors import ArgumentError
from .base import PROBLEMS, Constraint

#: What an option's flag may look like: ``--`` and lower-case words joined by hyphens.
FLAG = re.compile(r"--[a-z][a-z0-9]*(-[a-z0-9]+)*")


@dataclass(frozen=True)
class ConstraintOption:
    """A command-line option that adds one constraint.

    Attributes:
        flag: the option, ``--lower-case-words``.
        build: the constraint from the option's value (a number); raises
            :class:`~mobmanip.errors.ArgumentError` naming a bad value.
        help: one line for ``--help``.
        metavar: the value's name in ``--help``.
        problem: the problem at rest its rows join (``"velocity"`` or ``"acceleration"``), as the
            constraint's :attr:`~mobmanip.terms.constraints.base.Constraint.problem` says.
    """

    flag: str
    build: Callable[[float], Constraint]
    help: str
    metavar: str = "VALUE"
    problem: str = "acceleration"

    def __post_init__(self):
        if not (isinstance(self.flag, str) and FLAG.fullmatch(self.flag)):
            raise ArgumentError(f"a constraint option is --lower-case-words, got {self.flag!r}")
        if self.problem not in PROBLEMS:
            raise ArgumentError(f"option {self.flag}: problem must be one of {sorted(PROBLEMS)}, got {self.problem!r}")
        if not callable(self.build):
            raise ArgumentError(f"option {self.flag}: build must be callable")

    @property
    def dest(self) -> str:
        """Its attribute on the parsed arguments."""
        return "constraint_" + self.flag[2:].replace("-", "_")


#: The registered options, by flag, in registration order.
CONSTRAINT_OPTIONS: dict[str, ConstraintOption] = {}


def register_constraint_option(option: ConstraintOption) -> ConstraintOption:
    """Add an option to every command that takes constraints (see the module's docstring).

    Raises:
        ArgumentError: not a :class:`ConstraintOption`, or its flag is registered already.
    """
    if not isinstance(option, ConstraintOption):
        raise ArgumentError(f"expected a ConstraintOption, got {type(option).__name__}")
    if option.flag in CONSTRAINT_OPTIONS:
        raise ArgumentError(f"constraint option {option.flag} is registered already")
    CONSTRAINT_OPTIONS[option.flag] = option
    return option


def unregister_constraint_option(flag: str) -> ConstraintOption:
    """Remove a registered option; returns it.

    Raises:
        ArgumentError: no option has that flag.
    """
    if flag not in CONSTRAINT_OPTIONS:
        known = ", ".join(CONSTRAINT_OPTIONS) or "none"
        raise ArgumentError(f"no constraint option {flag!r} is registered (registered: {known})")
    return CONSTRAINT_OPTIONS.pop(flag)
