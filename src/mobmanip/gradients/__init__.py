"""Gradients of the measures' indices with respect to the configuration, in Pinocchio's tangent space."""

from .evaluator import (
    ELLIPSOIDS,
    INDICES,
    GradientBatch,
    GradientEvaluator,
    Objective,
    measure_gradient,
    measure_gradients,
    objective_names,
    platform_gradient,
)
from .rank import SINGULAR_RTOL
from .readings import READINGS, ReadingGradient, ReadingObjective, is_reading_objective, objective_evaluator

__all__ = [
    "ELLIPSOIDS",
    "GradientBatch",
    "GradientEvaluator",
    "INDICES",
    "Objective",
    "READINGS",
    "ReadingGradient",
    "ReadingObjective",
    "SINGULAR_RTOL",
    "is_reading_objective",
    "measure_gradient",
    "measure_gradients",
    "objective_evaluator",
    "objective_names",
    "platform_gradient",
]
