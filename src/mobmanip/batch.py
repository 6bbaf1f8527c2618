"""Analyse many configurations at once: the public face of :mod:`mobmanip.engine`.

:func:`analyze_batch` gives the same ellipsoids as :func:`mobmanip.analysis.analyze` (to 1e-10
of each ellipsoid's size) for every row of an (N, nq) configuration array; the sweep machinery
uses the lower-level :class:`BatchSetup`, :func:`iter_terms` and :func:`ellipsoids_from_terms`.
How the engine works, and where each part lives, is described in :mod:`mobmanip.engine`.
"""

from __future__ import annotations

from .engine import (
    DEFAULT_CHUNK,
    KERNEL_CHUNK,
    METHODS,
    BatchAnalysis,
    BatchSetup,
    ChunkTerms,
    EllipsoidBatch,
    OneRow,
    ProbedModel,
    SvdBacklog,
    Workspace,
    analyze_batch,
    check_configurations,
    default_chunk,
    ellipsoids_from_terms,
    evaluate_one,
    iter_terms,
    kernel_available,
    kernel_cached,
    kernel_ready,
    pinocchio_pass,
    warm_kernel,
)
from .support.tolerances import FAST_PATH_TOLERANCE

__all__ = [
    "DEFAULT_CHUNK",
    "FAST_PATH_TOLERANCE",
    "KERNEL_CHUNK",
    "METHODS",
    "BatchAnalysis",
    "BatchSetup",
    "ChunkTerms",
    "EllipsoidBatch",
    "OneRow",
    "ProbedModel",
    "SvdBacklog",
    "Workspace",
    "analyze_batch",
    "check_configurations",
    "default_chunk",
    "ellipsoids_from_terms",
    "evaluate_one",
    "iter_terms",
    "kernel_available",
    "kernel_cached",
    "kernel_ready",
    "pinocchio_pass",
    "warm_kernel",
]
