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

__all__ = [
    "ELLIPSOIDS",
    "GradientBatch",
    "GradientEvaluator",
    "INDICES",
    "Objective",
    "SINGULAR_RTOL",
    "measure_gradient",
    "measure_gradients",
    "objective_names",
    "platform_gradient",
]
