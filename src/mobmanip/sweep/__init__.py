"""Sweeps: the measures over a grid of object directions, distances, headings and limit scales."""

from .budget import MAX_GRID_POINTS, SweepEstimate
from .results import SweepResult
from .runner import (
    POSTURE_METHODS,
    SweepGrid,
    SweepSpec,
    default_workers,
    parse_grid,
    run_sweep,
    sweep_configurations,
    sweep_postures,
)

__all__ = [
    "MAX_GRID_POINTS",
    "POSTURE_METHODS",
    "SweepEstimate",
    "SweepGrid",
    "SweepResult",
    "SweepSpec",
    "default_workers",
    "parse_grid",
    "run_sweep",
    "sweep_configurations",
    "sweep_postures",
]
