"""One chunk's per-configuration terms: J_u, P, xi and the grasp, from the Pinocchio pass.

:class:`ChunkTerms` holds a chunk's Pinocchio outputs and, once computed, its terms. The
compiled kernel computes the terms itself; :func:`numpy_terms` computes them stacked in NumPy
for the NumPy and SVD paths.
"""

from __future__ import annotations

import numpy as np

from .probed import Workspace, pinocchio_pass
from .setup import BatchSetup
from .stacked_linalg import fro, spd_solver


class ChunkTerms:
    """One chunk's per-configuration quantities.

    Pinocchio's outputs for the probed model (views into the chunk's workspace, valid until the
    next chunk): world joint Jacobians ``Ja`` (n, 6, nv_p) and mass matrices ``Ma``. The
    end-effector positions ``positions`` (n, k, 3) and the derived terms -- J_u, P, xi and the
    grasp (W, T, C, M_o diagonal; ``None`` for a grasp that does not move) -- come either from
    the compiled kernel (rows it could not certify are all that is needed after it) or from
    stacked NumPy (:func:`numpy_terms`), whichever ran first.
    """

    __slots__ = ("n", "Ja", "Ma", "positions", "J_u", "P", "xi", "W", "T", "C", "Mo", "_gram")

    def __init__(self, n, Ja, Ma, positions):
        self.n, self.Ja, self.Ma, self.positions = n, Ja, Ma, positions
        self.J_u = self.P = self.xi = self.W = self.T = self.C = self.Mo = self._gram = None

    def __len__(self) -> int:
        return self.n

    def gram(self):
        """(J^T contiguous, solver B -> (J J^T)^-1 B, an upper bound on kappa_2(J J^T)), cached."""
        if self._gram is None:
            Jt = np.ascontiguousarray(np.swapaxes(self.J_u, 1, 2))
            Gu = self.J_u @ Jt
            solve, inv_norm = spd_solver(Gu)
            self._gram = (Jt, solve, fro(Gu) * inv_norm)
        return self._gram


def frame_jacobians(setup: BatchSetup, Jw: np.ndarray, pos: np.ndarray, out: np.ndarray) -> None:
    """LOCAL_WORLD_ALIGNED frame Jacobians from world joint Jacobians (n, 6, nv) and frame
    positions (n, k, 3): linear rows v_O + omega x p, columns outside the frame's support zeroed
    (as ``pin.getFrameJacobian``)."""
    w = Jw[:, 3:, :]
    for a, support in enumerate(setup.frame_supports):
        p = pos[:, a, :, None]
        out[:, a, 0] = Jw[:, 0] + w[:, 1] * p[:, 2] - w[:, 2] * p[:, 1]
        out[:, a, 1] = Jw[:, 1] + w[:, 2] * p[:, 0] - w[:, 0] * p[:, 2]
        out[:, a, 2] = Jw[:, 2] + w[:, 0] * p[:, 1] - w[:, 1] * p[:, 0]
        out[:, a, 3:] = w
        out[:, a] *= support


def chunk_terms(setup: BatchSetup, qs: np.ndarray, ws: Workspace) -> ChunkTerms:
    """Run the Pinocchio pass on a chunk of configurations (n, nq) and wrap its outputs."""
    n = qs.shape[0]
    pinocchio_pass(setup.probed, qs, ws)
    return ChunkTerms(n, ws.Ja[:n], ws.Ma[:n], ws.pos[:n])


def numpy_terms(setup: BatchSetup, t: ChunkTerms) -> None:
    """J_u, P, xi and the grasp of a chunk, stacked in NumPy (when the kernel has not run)."""
    if t.J_u is not None:
        return
    n, proj, nv, m, k, probed = t.n, setup.projection, setup.nv, setup.m, setup.k, setup.probed
    t.positions[...] = probed.frame_positions(t.Ja)
    J6 = np.empty((n, k, 6, nv))
    frame_jacobians(setup, probed.robot_jacobians(t.Ja), t.positions, J6)
    M = probed.robot_mass_matrices(t.Ma)
    J = J6[:, :, setup.row_slice, :] if setup.row_slice is not None else J6[:, :, setup.rows, :]
    t.J_u = proj.right(J.reshape(n, k * m, nv))
    if not setup.crba_symmetric:  # M from the upper triangle, as mobmanip.terms.dynamics.mass_matrix
        M = np.triu(M) + np.swapaxes(np.triu(M, 1), 1, 2)
    P = proj.left_transpose(proj.right(M))
    t.P = 0.5 * (P + np.swapaxes(P, 1, 2))
    t.xi = -proj.right(probed.gravity_torques(t.Ma))
    if setup.moving_grasp:
        t.W, t.T, t.C, t.Mo = moving_grasp(setup, t.positions)


def moving_grasp(setup: BatchSetup, pos: np.ndarray):
    """W, (W^T)^+, a basis of null(W) and diag(M_o) per configuration, for grasps with offsets.

    The object is centred at the centroid of the end effectors (as
    :meth:`mobmanip.terms.grasp.HeldObject.between`), a uniform sphere reaching the farthest grasp.
    Task rows are ordered linear then angular, so each grasp block is W_i = [[I, 0], [K_i, I]]
    with K_i the angular-by-linear part of skew(r_i); W_k^-1 = [[I, 0], [-K_k, I]] gives the
    null-space basis in closed form, and W W^T = [[k I, S^T], [S, k I + sum K_i K_i^T]]
    (S = sum K_i, zero up to rounding) is inverted blockwise.
    """
    n, k, m = pos.shape[0], setup.k, setup.m
    nl = m - setup.n_angular
    center = pos.mean(axis=1)
    offsets = pos - center[:, None, :]
    rx, ry, rz = offsets[..., 0], offsets[..., 1], offsets[..., 2]
    skew = np.zeros((n, k, 3, 3))
    skew[:, :, 0, 1], skew[:, :, 0, 2] = -rz, ry
    skew[:, :, 1, 0], skew[:, :, 1, 2] = rz, -rx
    skew[:, :, 2, 0], skew[:, :, 2, 1] = -ry, rx
    K = skew[:, :, setup.angular_rows3][:, :, :, setup.linear_rows]  # (n, k, na, nl)
    blocks = np.zeros((n, k, m, m))
    blocks[:, :, np.arange(m), np.arange(m)] = 1.0
    blocks[:, :, nl:, :nl] = K
    W = np.swapaxes(blocks, 1, 2).reshape(n, m, k * m)
    # (W W^T)^-1 by blocks
    Ks = K.sum(axis=1)  # (n, na, nl)
    D = k * np.eye(m - nl) + np.einsum("nkal,nkbl->nab", K, K) - (Ks @ np.swapaxes(Ks, 1, 2)) / k
    Di = np.linalg.inv(D)
    E = -(Di @ Ks) / k  # (n, na, nl)
    WWt_inv = np.empty((n, m, m))
    WWt_inv[:, :nl, :nl] = np.eye(nl) / k - (np.swapaxes(Ks, 1, 2) @ E) / k
    WWt_inv[:, :nl, nl:] = np.swapaxes(E, 1, 2)
    WWt_inv[:, nl:, :nl] = E
    WWt_inv[:, nl:, nl:] = Di
    T = WWt_inv @ W
    # null(W): h_k = -W_k^-1 (W_1 h_1 + ... + W_{k-1} h_{k-1}); W_k^-1 W_i = [[I, 0], [K_i - K_k, I]]
    C = np.zeros((n, k * m, (k - 1) * m))
    C[:, : (k - 1) * m, :] = np.eye((k - 1) * m)
    for i in range(k - 1):
        C[:, (k - 1) * m + np.arange(m), i * m + np.arange(m)] = -1.0
        C[:, (k - 1) * m + nl : k * m, i * m : i * m + nl] = -(K[:, i] - K[:, k - 1])
    radius2 = np.max(np.sum(offsets**2, axis=2), axis=1)
    Mo = np.where(setup.angular[None, :], 0.4 * setup.mass * radius2[:, None], setup.mass)
    return W, T, C, Mo
