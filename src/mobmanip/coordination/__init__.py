"""Teams that move: several mobile manipulators carrying one object along a path
(:func:`team_carry`, the command ``mobmanip team-carry``)."""

from .capacity import TeamCapacity, ellipsoid_index, shape_index
from .carry import FRAMES, TeamCarryResult, TeamCarryRun, lateral_slip, team_carry

__all__ = [
    "FRAMES",
    "TeamCapacity",
    "TeamCarryResult",
    "TeamCarryRun",
    "ellipsoid_index",
    "lateral_slip",
    "shape_index",
    "team_carry",
]
