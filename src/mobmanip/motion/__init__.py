"""Robots in motion: the terms and ellipsoids at a moving state, trajectories and carried paths."""

from .in_motion import (
    MotionAnalysis,
    MotionTerms,
    analyze_motion,
    check_reduced_velocity,
    grasp_matrix_rate,
    motion_terms,
)

__all__ = [
    "MotionAnalysis",
    "MotionTerms",
    "analyze_motion",
    "check_reduced_velocity",
    "grasp_matrix_rate",
    "motion_terms",
]
