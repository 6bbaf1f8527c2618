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
                    s = 0.0
                    for y in range(6):
                        s += Ic[j, x, y] * xi[r, y, k]
                    F[x, k] = s
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
