"""Teams: several mobile manipulators holding one object."""

from .analysis import LoadSharing, MemberTerms, TeamAnalysis, analyze_team, member_terms, ray_radius, stack_terms
from .members import DEFAULT_TOLERANCE, Member, Team, box_inertia, hand_positions, load_team, team_from_dict
from .payload import team_payload
from .sweep import sweep_heading

__all__ = [
    "DEFAULT_TOLERANCE",
    "LoadSharing",
    "Member",
    "MemberTerms",
    "Team",
    "TeamAnalysis",
    "analyze_team",
    "box_inertia",
    "hand_positions",
    "load_team",
    "member_terms",
    "ray_radius",
    "stack_terms",
    "sweep_heading",
    "team_payload",
    "team_from_dict",
]
