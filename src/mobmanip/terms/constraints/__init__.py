"""Constraints of the capacity problems: linear rows over named variables (see :mod:`.base`).

The joint boxes (:mod:`.joint_limits`) are the first two; every other constraint is one module
here (or in a user's code) with one :class:`Constraint` subclass.
"""

from .base import EQUATIONS, PROBLEMS, Constraint, ConstraintRows, Terms
from .joint_limits import JOINT_BOXES, EffortBox, VelocityBox

__all__ = [
    "EQUATIONS",
    "JOINT_BOXES",
    "PROBLEMS",
    "Constraint",
    "ConstraintRows",
    "EffortBox",
    "Terms",
    "VelocityBox",
]
