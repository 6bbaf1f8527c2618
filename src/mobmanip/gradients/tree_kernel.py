"""Compiled row loops of :mod:`mobmanip.gradients.tree_adjoint` (Numba, optional).

The same sums over the kinematic tree as the stacked NumPy forms in
:class:`mobmanip.gradients.tree_adjoint.TreeAdjoint`, one configuration at a time, which avoids the
stacked forms' temporaries. Imported on first use; without Numba the NumPy forms run (they are
the reference these loops are tested against).
"""

from __future__ import annotations

import numpy as np
from numba import njit

_jit = njit(cache=True, nogil=True)


@njit(inline="always")
def _entry(A, B, x, i):
    """The (x, i) entry of the product A @ B of two matrices, summed in the order of j."""
    s = 0.0
    for j in range(A.shape[1]):
        s += A[x, j] * B[j, i]
    return s


@_jit
def world_inertias(R, origins, mass, lever, rot_inertia, out):
    """Bodies' spatial inertias in the world frame at its origin (linear, angular rows).

    Args:
        R: joint frames' rotations, (n, nj, 3, 3). origins: their positions, (n, nj, 3).
        mass (nj,), lever (nj, 3), rot_inertia (nj, 3, 3): the bodies' inertias in their joint frames.
        out: (n, nj, 6, 6), filled.
    """
    n, nj = R.shape[0], R.shape[1]
    c = np.empty(3)
    Ic = np.empty((3, 3))
    S = np.empty((3, 3))
    for r in range(n):
        for j in range(nj):
            m = mass[j]
            for a in range(3):
                c[a] = (
                    origins[r, j, a]
                    + R[r, j, a, 0] * lever[j, 0]
                    + R[r, j, a, 1] * lever[j, 1]
                    + R[r, j, a, 2] * lever[j, 2]
                )
            for a in range(3):
                for b in range(3):
                    s = 0.0
                    for x in range(3):
                        for y in range(3):
                            s += R[r, j, a, x] * rot_inertia[j, x, y] * R[r, j, b, y]
                    Ic[a, b] = s
            S[0, 0], S[0, 1], S[0, 2] = 0.0, -c[2], c[1]
            S[1, 0], S[1, 1], S[1, 2] = c[2], 0.0, -c[0]
            S[2, 0], S[2, 1], S[2, 2] = -c[1], c[0], 0.0
            o = out[r, j]
            for a in range(3):
                for b in range(3):
                    o[a, b] = m if a == b else 0.0
                    o[a, 3 + b] = -m * S[a, b]
                    o[3 + a, b] = m * S[a, b]
                    ss = 0.0
                    for x in range(3):
                        ss += S[a, x] * S[x, b]
                    o[3 + a, 3 + b] = Ic[a, b] - m * ss


@_jit
def mass_and_gravity(xi, I, parent, dof_start, dof_count, A0, armature, M, g):
    """M and g from composite inertias, per row.

    Args:
        xi: world Jacobian columns, (n, 6, nv). I: bodies' world inertias, (n, nj, 6, 6).
        parent: each joint's parent (0-based over joints, -1 for the universe), (nj,).
        dof_start, dof_count: each joint's first tangent index and count, (nj,).
        A0: the gravity acceleration -gravity, (6,). armature: (nv,).
        M: (n, nv, nv), g: (n, nv), filled.
    """
    n, nj, nv = I.shape[0], I.shape[1], xi.shape[2]
    Ic = np.empty((nj, 6, 6))
    F = np.empty((6, nv))
    for r in range(n):
        for j in range(nj):
            Ic[j] = I[r, j]
        for j in range(nj - 1, -1, -1):
            p = parent[j]
            if p >= 0:
                Ic[p] += Ic[j]
        for i in range(nv):
            for k in range(nv):
                M[r, i, k] = 0.0
        for j in range(nj):
            for k in range(dof_start[j], dof_start[j] + dof_count[j]):
                for x in range(6):
                    F[x, k] = _entry(Ic[j], xi[r], x, k)
                gk = 0.0
                for x in range(6):
                    s = 0.0
                    for y in range(6):
                        s += Ic[j, x, y] * A0[y]
                    gk += xi[r, x, k] * s
                g[r, k] = gk
                # ancestors' dofs (and this joint's): walk up the chain
                a = j
                while a >= 0:
                    for i in range(dof_start[a], dof_start[a] + dof_count[a]):
                        s = 0.0
                        for x in range(6):
                            s += xi[r, x, i] * F[x, k]
                        M[r, i, k] = s
                        M[r, k, i] = s
                    a = parent[a]
        for i in range(nv):
            M[r, i, i] += armature[i]


@_jit
def bilinear_rows(xi, coef, offset, I, parent, dof_start, dof_count, R, out):
    """sum over pairs r of d(a_r^T M b_r)/dq_k (b's twists shifted by ``offset``), per row.

    Args:
        xi: (n, 6, nv). coef: the a's then the b's, (n, 2R, nv). offset: (6, 2R).
        I: (n, nj, 6, 6). parent, dof_start, dof_count: as :func:`mass_and_gravity`.
        R: the number of pairs. out: (n, nv), filled.
    """
    n, nj = I.shape[0], I.shape[1]
    R2 = 2 * R
    V = np.empty((nj, 6, R2))
    H = np.empty((nj, 6, R2))
    gam = np.empty(6)
    for r in range(n):
        for j in range(nj):
            p = parent[j]
            for x in range(6):
                for c in range(R2):
                    V[j, x, c] = V[p, x, c] if p >= 0 else offset[x, c]
            for k in range(dof_start[j], dof_start[j] + dof_count[j]):
                for x in range(6):
                    for c in range(R2):
                        V[j, x, c] += xi[r, x, k] * coef[r, c, k]
            for x in range(6):
                for c in range(R2):
                    s = 0.0
                    for y in range(6):
                        s += I[r, j, x, y] * V[j, y, c]
                    H[j, x, c] = s
        for j in range(nj - 1, -1, -1):
            p = parent[j]
            if p >= 0:
                H[p] += H[j]
        for j in range(nj):
            p = parent[j]
            for x in range(6):
                gam[x] = 0.0
            for c in range(R2):
                d = c + R if c < R else c - R  # a's pre-twist with b's momentum and vice versa
                if p >= 0:
                    vy0, vy1, vy2 = V[p, 0, c], V[p, 1, c], V[p, 2, c]
                    wy0, wy1, wy2 = V[p, 3, c], V[p, 4, c], V[p, 5, c]
                else:
                    vy0, vy1, vy2 = offset[0, c], offset[1, c], offset[2, c]
                    wy0, wy1, wy2 = offset[3, c], offset[4, c], offset[5, c]
                xl0, xl1, xl2 = H[j, 0, d], H[j, 1, d], H[j, 2, d]
                xa0, xa1, xa2 = H[j, 3, d], H[j, 4, d], H[j, 5, d]
                gam[0] += wy1 * xl2 - wy2 * xl1
                gam[1] += wy2 * xl0 - wy0 * xl2
                gam[2] += wy0 * xl1 - wy1 * xl0
                gam[3] += vy1 * xl2 - vy2 * xl1 + wy1 * xa2 - wy2 * xa1
                gam[4] += vy2 * xl0 - vy0 * xl2 + wy2 * xa0 - wy0 * xa2
                gam[5] += vy0 * xl1 - vy1 * xl0 + wy0 * xa1 - wy1 * xa0
            for k in range(dof_start[j], dof_start[j] + dof_count[j]):
                s = 0.0
                for x in range(6):
                    s += xi[r, x, k] * gam[x]
                out[r, k] = -s


# ----- the kinematic chain, row by row (mobmanip.gradients.adjoint's kinematic measures) -----


@_jit
def tree_frames(Ja, vmap, x_idx, y_idx, k, supports, xi, points, rotations, reference, frames):
    """The pass :meth:`TreeAdjoint.run` reads from Pinocchio's world joint Jacobians, per row.

    Args:
        Ja: the probed model's world joint Jacobians, (n, 6, nv_p). vmap: the robot's columns, (nv,).
        x_idx, y_idx: each frame's two probe columns (end effectors, then joints), (k + nj,).
        k: the number of end effectors. supports: (k, nv).
        xi: (n, 6, nv), points: (n, k + nj, 3) (relative to ``reference``), rotations: (n, k + nj, 3, 3),
        reference: (n, 3), frames: (n, k, 6, nv); filled.
    """
    n, nv, nf = Ja.shape[0], vmap.shape[0], x_idx.shape[0]
    for r in range(n):
        for a in range(6):
            for j in range(nv):
                xi[r, a, j] = Ja[r, a, vmap[j]]
        for f in range(nf):
            cx, cy = x_idx[f], y_idx[f]
            vx0, vx1, vx2 = Ja[r, 0, cx], Ja[r, 1, cx], Ja[r, 2, cx]
            wx0, wx1, wx2 = Ja[r, 3, cx], Ja[r, 4, cx], Ja[r, 5, cx]
            vy0, vy1, vy2 = Ja[r, 0, cy], Ja[r, 1, cy], Ja[r, 2, cy]
            wy0, wy1, wy2 = Ja[r, 3, cy], Ja[r, 4, cy], Ja[r, 5, cy]
            # p = w_x x v_x + w_x (w_x . (w_y x v_y)) (mobmanip.engine.probed.frame_positions)
            b0 = wy1 * vy2 - wy2 * vy1
            b1 = wy2 * vy0 - wy0 * vy2
            b2 = wy0 * vy1 - wy1 * vy0
            s = wx0 * b0 + wx1 * b1 + wx2 * b2
            points[r, f, 0] = (wx1 * vx2 - wx2 * vx1) + wx0 * s
            points[r, f, 1] = (wx2 * vx0 - wx0 * vx2) + wx1 * s
            points[r, f, 2] = (wx0 * vx1 - wx1 * vx0) + wx2 * s
            rotations[r, f, 0, 0], rotations[r, f, 1, 0], rotations[r, f, 2, 0] = wx0, wx1, wx2
            rotations[r, f, 0, 1], rotations[r, f, 1, 1], rotations[r, f, 2, 1] = wy0, wy1, wy2
            rotations[r, f, 0, 2] = wx1 * wy2 - wx2 * wy1
            rotations[r, f, 1, 2] = wx2 * wy0 - wx0 * wy2
            rotations[r, f, 2, 2] = wx0 * wy1 - wx1 * wy0
        r0, r1, r2 = points[r, k, 0], points[r, k, 1], points[r, k, 2]
        reference[r, 0], reference[r, 1], reference[r, 2] = r0, r1, r2
        for f in range(nf):
            points[r, f, 0] -= r0
            points[r, f, 1] -= r1
            points[r, f, 2] -= r2
        for j in range(nv):
            w0, w1, w2 = xi[r, 3, j], xi[r, 4, j], xi[r, 5, j]
            xi[r, 0, j] += w1 * r2 - w2 * r1
            xi[r, 1, j] += w2 * r0 - w0 * r2
            xi[r, 2, j] += w0 * r1 - w1 * r0
        for a in range(k):
            p0, p1, p2 = points[r, a, 0], points[r, a, 1], points[r, a, 2]
            for j in range(nv):
                w0, w1, w2 = xi[r, 3, j], xi[r, 4, j], xi[r, 5, j]
                sup = supports[a, j]
                frames[r, a, 0, j] = (xi[r, 0, j] + (w1 * p2 - w2 * p1)) * sup
                frames[r, a, 1, j] = (xi[r, 1, j] + (w2 * p0 - w0 * p2)) * sup
                frames[r, a, 2, j] = (xi[r, 2, j] + (w0 * p1 - w1 * p0)) * sup
                frames[r, a, 3, j] = w0 * sup
                frames[r, a, 4, j] = w1 * sup
                frames[r, a, 5, j] = w2 * sup


@_jit
def kinematic_shape(frames, rows, S, vlim, W, Jh, X, C, bound):
    """The kinematic ellipsoid's shape C = (W (Jh Jh^T)^-1 W^T)^-1, Jh = J S diag(qdot_max), per row,
    and the rank certificate of Jh (mobmanip.gradients.adjoint.full_rank's Gram bound).

    Args:
        frames: (n, k, 6, nv). rows: the task's rows of a twist, (m,). S: (nv, nx). vlim: (nx,).
        W: the grasp matrices, (n, m, k m).
        Jh: (n, k m, nx), X: (n, k m, m) = K^-1 W^T, C: (n, m, m), bound: (n,); filled.
    """
    n, k, nv = frames.shape[0], frames.shape[1], frames.shape[3]
    m = rows.shape[0]
    J = np.empty((k * m, nv))
    for r in range(n):
        for a in range(k):
            for i in range(m):
                J[a * m + i] = frames[r, a, rows[i]]
        Jr = (J @ S) * vlim
        Jh[r] = Jr
        K = Jr @ Jr.T
        G = K if Jr.shape[0] <= Jr.shape[1] else Jr.T @ Jr  # the smaller Gram matrix
        Gi = np.linalg.inv(G)
        bound[r] = np.sqrt(np.sum(G * G) * np.sum(Gi * Gi))
        Xr = np.linalg.solve(K, np.ascontiguousarray(W[r].T))
        X[r] = Xr
        Ci = np.linalg.inv(W[r] @ Xr)
        C[r] = 0.5 * (Ci + Ci.T)


@_jit
def kinematic_shape_adjoint(C, C_bar, X, Jh, W, S, rows, vlim, k, J_bar6, W_bar):
    """The sensitivities of :func:`kinematic_shape`'s C to the frames' Jacobians and to W, per row:
    A_bar = -C C_bar C, W_bar = (A_bar + A_bar^T) X^T, K_bar = -X A_bar X^T,
    Jh_bar = (K_bar + K_bar^T) Jh, J_bar = Jh_bar diag(qdot_max) S^T on the task's rows.

    Args:
        C, C_bar: (n, m, m). X: (n, k m, m). Jh: (n, k m, nx). W: (n, m, k m). S: (nv, nx).
        rows: (m,). vlim: (nx,). k: the number of end effectors.
        J_bar6: (n, k, 6, nv), W_bar: (n, m, k m); filled.
    """
    n, m = C.shape[0], C.shape[1]
    J_bar6[:] = 0.0
    for r in range(n):
        Cr, Xr = C[r], X[r]
        Ab = -(Cr @ C_bar[r] @ Cr)
        W_bar[r] = (Ab + Ab.T) @ Xr.T
        Kb = -(Xr @ Ab @ Xr.T)
        Jb = (((Kb + Kb.T) @ Jh[r]) * vlim) @ S.T
        for a in range(k):
            for i in range(m):
                J_bar6[r, a, rows[i]] = Jb[a * m + i]


@_jit
def frame_term(xi, positions, frames, supports, suffix, J_bar, p_bar, out):
    """sum over frames of <J_bar, dJ/dq_k> + p_bar . dp/dq_k, per row
    (:meth:`TreeAdjoint.frame_term`'s stacked form).

    Args:
        xi: (n, 6, nv). positions: (n, k, 3). frames: (n, k, 6, nv). supports: (k, nv).
        suffix: (nv, nv). J_bar: (n, k, 6, nv). p_bar: (n, k, 3) (zeros for none). out: (n, nv), filled.
    """
    n, k, nv = J_bar.shape[0], J_bar.shape[1], J_bar.shape[3]
    gamma = np.empty((6, nv))
    G = np.empty((6, nv))
    for r in range(n):
        for i in range(nv):
            out[r, i] = 0.0
        for a in range(k):
            p0, p1, p2 = positions[r, a, 0], positions[r, a, 1], positions[r, a, 2]
            rho0, rho1, rho2 = 0.0, 0.0, 0.0
            for j in range(nv):
                sup = supports[a, j]
                l0, l1, l2 = J_bar[r, a, 0, j] * sup, J_bar[r, a, 1, j] * sup, J_bar[r, a, 2, j] * sup
                # beta = X_p^T J_bar: the angular rows gain p x (linear rows)
                h0 = J_bar[r, a, 3, j] * sup + (p1 * l2 - p2 * l1)
                h1 = J_bar[r, a, 4, j] * sup + (p2 * l0 - p0 * l2)
                h2 = J_bar[r, a, 5, j] * sup + (p0 * l1 - p1 * l0)
                v0, v1, v2 = xi[r, 0, j], xi[r, 1, j], xi[r, 2, j]
                w0, w1, w2 = xi[r, 3, j], xi[r, 4, j], xi[r, 5, j]
                c0, c1, c2 = w1 * l2 - w2 * l1, w2 * l0 - w0 * l2, w0 * l1 - w1 * l0
                gamma[0, j], gamma[1, j], gamma[2, j] = c0, c1, c2
                gamma[3, j] = (v1 * l2 - v2 * l1) + (w1 * h2 - w2 * h1)
                gamma[4, j] = (v2 * l0 - v0 * l2) + (w2 * h0 - w0 * h2)
                gamma[5, j] = (v0 * l1 - v1 * l0) + (w0 * h1 - w1 * h0)
                rho0 -= c0
                rho1 -= c1
                rho2 -= c2
            rho0 += p_bar[r, a, 0]
            rho1 += p_bar[r, a, 1]
            rho2 += p_bar[r, a, 2]
            for x in range(6):
                for i in range(nv):
                    G[x, i] = _entry(gamma, suffix, x, i)
            for i in range(nv):
                turn = 0.0
                for x in range(6):
                    turn += xi[r, x, i] * G[x, i]
                move = rho0 * frames[r, a, 0, i] + rho1 * frames[r, a, 1, i] + rho2 * frames[r, a, 2, i]
                out[r, i] += turn * supports[a, i]
                out[r, i] += move
