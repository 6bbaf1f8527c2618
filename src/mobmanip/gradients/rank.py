"""Rank tests and stand-ins for stacked matrices, shared by the forward and the reverse gradient chains."""

from __future__ import annotations

import numpy as np

#: A measure is not differentiable where the smallest singular value of J_hat (or L, or J_u) is
#: below this fraction of the largest (a singular posture).
SINGULAR_RTOL = 1e-9


def svd_full_rank(A: np.ndarray) -> np.ndarray:
    """Per stacked matrix: min(rows, cols) singular values above SINGULAR_RTOL times the largest."""
    s = np.linalg.svd(A, compute_uv=False)
    return s[..., -1] > SINGULAR_RTOL * s[..., 0]


def guarded(A: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """A with the matrices where not ``ok`` replaced by a full-rank stand-in (results there are
    discarded; this only keeps the stacked solves from failing)."""
    if ok.all():
        return A
    A = A.copy()
    A[~ok] = np.eye(A.shape[-2], A.shape[-1])
    return A
