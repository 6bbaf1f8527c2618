"""Teams: several mobile manipulators holding one object."""

from .analysis import LoadSharing, MemberTerms, TeamAnalysis, analyze_team, member_terms, ray_radius, stack_terms
from .members import DEFAULT_TOLERANCE, Member, Team, box_inertia, hand_positions, load_team, team_from_dict
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
    "team_from_dict",
]
