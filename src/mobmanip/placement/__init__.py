"""Where the platform should stand: placement optimisation, its maps and its batched grid."""

from .optimize import (
    CONSTRAINT_TOLERANCE,
    DEFAULT_STARTS,
    Placement,
    Region,
    object_gradient,
    place,
    placement_document,
)

__all__ = [
    "CONSTRAINT_TOLERANCE",
    "DEFAULT_STARTS",
    "Placement",
    "Region",
    "object_gradient",
    "place",
    "placement_document",
]
