"""The paper's dynamic ellipsoid by its closed form, written out here for the tests that hold
mobmanip's ellipsoids to it (none of mobmanip's set code is used)."""

from __future__ import annotations

import numpy as np


def dynamic_ellipsoid_closed_form(J, W, P, Q, xi, M_o, g_o, effort_limits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The object's accelerations a with |Z tau(a)| <= 1 under the minimum-norm policy, J and W of
    full row rank: tau(a) = Lam a + mu with Lam = Q^-1 (P J^+ W^T + J^T W^+ M_o) and mu = Q^-1
    (-xi + J^T W^+ g_o), Z = diag(1 / tau_max); with L = Z Lam, mu_bar = Z mu, the set is
    (a - c)^T A (a - c) <= 1 for c = -L^+ mu_bar, r = L c + mu_bar, A = L^T L / (1 - |r|^2).

    Returns:
        (A, c, semi-axes 1 / sqrt(eig A), largest first).
    """
    Q_inv = np.linalg.inv(Q)
    J_pinv, W_pinv = np.linalg.pinv(J), np.linalg.pinv(W)
    Lam = Q_inv @ (P @ J_pinv @ W.T + J.T @ W_pinv @ M_o)
    mu = Q_inv @ (-xi + J.T @ W_pinv @ g_o)
    Z = 1.0 / np.asarray(effort_limits, dtype=float)
    L, mu_bar = Z[:, None] * Lam, Z * mu
    centre = -np.linalg.pinv(L) @ mu_bar
    r = L @ centre + mu_bar
    A = L.T @ L / (1.0 - r @ r)
    return A, centre, np.sort(1.0 / np.sqrt(np.linalg.eigvalsh(A)))[::-1]
