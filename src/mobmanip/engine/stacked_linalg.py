"""Small dense linear algebra over stacks of matrices (n, r, c), for the NumPy and SVD paths.

LAPACK's per-matrix calls cost more than the arithmetic at these sizes (2 x 2 .. 16 x 16), so
some of these are written out and vectorised over the stack; none of them raises on a singular
or non-finite row (such rows give NaN, for the callers' certificates to refuse).
"""

from __future__ import annotations

import numpy as np


def sym_eigh(A: np.ndarray):
    """Stacked eigh of the symmetric part; rows with non-finite entries give NaN."""
    A = 0.5 * (A + np.swapaxes(A, 1, 2))
    finite = np.isfinite(A).all(axis=(1, 2))
    if finite.all():
        return np.linalg.eigh(A)
    A[~finite] = np.eye(A.shape[-1])
    lam, V = np.linalg.eigh(A)
    lam[~finite] = np.nan
    return lam, V


def safe_inv(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stacked inverse that does not raise: exactly singular rows get NaN (and True in the mask)."""
    try:
        return np.linalg.inv(A), np.zeros(A.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        singular = ~(np.linalg.det(A) != 0.0)  # LU hit an exact zero pivot (or det under/overflowed)
        B = A.copy()
        B[singular] = np.eye(A.shape[-1])
        inv = np.linalg.inv(B)
        inv[singular] = np.nan
        return inv, singular


def lower_inverse(L: np.ndarray) -> np.ndarray:
    """Stacked inverse of lower-triangular matrices by forward substitution, vectorised over the
    stack (LAPACK's per-matrix calls cost more than the arithmetic at these sizes)."""
    n = L.shape[-1]
    X = np.zeros_like(L)
    d = 1.0 / np.diagonal(L, axis1=1, axis2=2)
    for i in range(n):
        if i:
            X[:, i, :i] = -(L[:, i : i + 1, :i] @ X[:, :i, :i])[:, 0, :] * d[:, i, None]
        X[:, i, i] = d[:, i]
    return X


def spd_solver(A: np.ndarray):
    """A solver B -> A^-1 B for a stack of symmetric positive definite A, and ||A^-1||_F (an upper
    bound). Cholesky when every matrix admits it, else a plain inverse (singular rows give NaN)."""
    try:
        Li = lower_inverse(np.linalg.cholesky(A))
    except np.linalg.LinAlgError:
        Ai, _ = safe_inv(A)
        return (lambda B: Ai @ B), fro(Ai)
    LiT = np.ascontiguousarray(np.swapaxes(Li, 1, 2))
    return (lambda B: LiT @ (Li @ B)), np.einsum("nij,nij->n", Li, Li)


def fro(A: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("nij,nij->n", A, A))


def cross3(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u x v over the last axis (3-vectors, broadcast). The same products and differences as
    ``np.cross`` (equal bit for bit) without its axis handling, which costs more than the
    arithmetic on the small stacks of the gradient chain and the placement constraints."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    c0 = u1 * v2 - u2 * v1
    out = np.empty(c0.shape + (3,), dtype=c0.dtype)
    out[..., 0] = c0
    out[..., 1] = u2 * v0 - u0 * v2
    out[..., 2] = u0 * v1 - u1 * v0
    return out
