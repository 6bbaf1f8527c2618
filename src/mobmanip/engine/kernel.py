"""Compiled per-configuration kernel: everything after Pinocchio, one configuration at a time.

The stacked NumPy fast path (:mod:`mobmanip.engine.numpy_path`) computes the same quantities, but every
stacked operation on tiny matrices (6 x 6, 12 x 16) pays NumPy's per-call overhead, which after
Pinocchio dominates the cost. This module runs the same algorithm, with the same a-priori error
certificates, as loops compiled by Numba, row by row over a chunk:

1. terms, from one CRBA of the probed model (:class:`mobmanip.engine.probed.ProbedModel`): the
   end-effector positions from the probe columns of the world joint Jacobian,
   LOCAL_WORLD_ALIGNED frame Jacobians, J_u = J S, P = S^T M S (upper triangle of M, as
   :func:`mobmanip.terms.dynamics.mass_matrix`), xi = -S^T g with g from the gravity probe's row of
   M, through S stored column-compressed;
2. grasp: the object at the centroid of the end effectors (or at explicit offsets), W, its
   pseudo-inverse T = (W W^T)^-1 W, a basis C of null(W) in closed form, and M_o;
3. the kinematic and dynamic fast paths (see :mod:`mobmanip.engine` for the algebra), with
   the symmetric eigenproblems solved by Householder tridiagonalisation and implicit QL
   (backward stable, as the LAPACK routines NumPy calls).

A row the certificates do not accept is flagged and left to the exact SVD paths; the kernel
never guesses. Compilation is cached on disk (first use in a fresh environment takes seconds).

The thresholds of the certificates come from :mod:`mobmanip.support.tolerances` as an argument of
:func:`run_chunk` (``tolerances``), not as globals: Numba compiles globals in as constants and
its disk cache does not notice when another module's values change. Machine epsilon, which
cannot change, is the one constant read as a global.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..support.tolerances import EPS

_jit = njit(cache=True, nogil=True, error_model="numpy", fastmath={"reassoc", "contract", "nsz"})


@_jit
def _cholesky(A, L, n):
    """Lower Cholesky factor of the leading n x n block of A into L; False if not positive definite."""
    for j in range(n):
        s = A[j, j]
        for p in range(j):
            s -= L[j, p] * L[j, p]
        if not s > 0.0:  # also catches NaN
            return False
        d = np.sqrt(s)
        L[j, j] = d
        inv_d = 1.0 / d  # one division per column, as LAPACK's dpotf2
        for i in range(j + 1, n):
            s = A[i, j]
            for p in range(j):
                s -= L[i, p] * L[j, p]
            L[i, j] = s * inv_d
        for i in range(j):
            L[i, j] = 0.0
    return True


@_jit
def _lower_inverse(L, X, n):
    """X = L^-1 for lower-triangular L (leading n x n blocks); returns ||X||_F^2."""
    total = 0.0
    for i in range(n):
        d = 1.0 / L[i, i]
        X[i, i] = d
        total += d * d
        for j in range(i):
            s = 0.0
            for p in range(j, i):
                s += L[i, p] * X[p, j]
            X[i, j] = -s * d
            total += X[i, j] * X[i, j]
        for j in range(i + 1, n):
            X[i, j] = 0.0
    return total


@_jit
def _spd_inverse(A, L, X, out, n):
    """out = A^-1 for symmetric positive definite A by Cholesky; False if it fails."""
    if not _cholesky(A, L, n):
        return False
    _lower_inverse(L, X, n)
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for p in range(j, n):
                s += X[p, i] * X[p, j]
            out[i, j] = s
            out[j, i] = s
    return True


@_jit
def _fro2(A, rows, cols):
    s = 0.0
    for i in range(rows):
        for j in range(cols):
            s += A[i, j] * A[i, j]
    return s


@_jit
def _stacked_grams(J, w, G, Gw, rows, row_arm, pair_cols, n_pair_cols):
    """G = J J^T and Gw = J diag(w) J^T for the first ``rows`` rows of a stacked Jacobian (row p
    belongs to arm row_arm[p]), summing only over the columns both rows' arms can move."""
    for p in range(rows):
        ap = row_arm[p]
        for q in range(p, rows):
            aq = row_arm[q]
            cols = pair_cols[ap, aq]
            s = 0.0
            sw = 0.0
            for t in range(n_pair_cols[ap, aq]):
                j = cols[t]
                x = J[p, j] * J[q, j]
                s += x
                sw += x * w[j]
            G[p, q] = s
            G[q, p] = s
            Gw[p, q] = sw
            Gw[q, p] = sw


@_jit
def _add_jt_product(J, Y, out, rows, cols, row_arm, arm_cols, n_arm_cols):
    """out += J^T Y for the first ``rows`` rows of a stacked Jacobian J (row p belongs to arm
    row_arm[p] and is zero outside arm_cols[row_arm[p]]) and Y (rows, cols)."""
    for p in range(rows):
        arm = row_arm[p]
        arm_c = arm_cols[arm]
        for t in range(n_arm_cols[arm]):
            j = arm_c[t]
            jpj = J[p, j]
            for q in range(cols):
                out[j, q] += jpj * Y[p, q]


@_jit
def _gram_twice(A, out, copy, rows, cols):
    """out = copy = A A^T over the leading rows x cols block of A (copy is the eigensolver's
    input, which it overwrites)."""
    for p in range(rows):
        for q in range(p, rows):
            s = 0.0
            for j in range(cols):
                s += A[p, j] * A[q, j]
            out[p, q] = s
            out[q, p] = s
            copy[p, q] = s
            copy[q, p] = s


@_jit
def _tridiagonalize(V, d, e, n):
    """First half of :func:`eigh`: scale the symmetric n x n block of V to entries at most 1,
    reduce it to tridiagonal form (d diagonal, e[i] the entry between i and i + 1, e[n - 1] = 0)
    and leave the accumulated Householder transforms in V. Returns the scale, or 0.0 where
    nothing is left to do: a zero matrix (V = I, d = 0) or a non-finite one (V = I, d = NaN)."""
    big = 0.0
    finite = True
    for i in range(n):
        for j in range(n):
            x = abs(V[i, j])
            finite = finite and x < np.inf  # False for inf and NaN
            big = max(big, x)
    if not finite or big == 0.0:
        for i in range(n):
            d[i] = 0.0 if finite else np.nan
            for j in range(n):
                V[i, j] = 1.0 if i == j else 0.0
        return 0.0
    inv_big = 1.0 / big
    for i in range(n):
        for j in range(n):
            V[i, j] *= inv_big
    for j in range(n):
        d[j] = V[n - 1, j]
    for i in range(n - 1, 0, -1):
        scale = 0.0
        h = 0.0
        for k in range(i):
            scale += abs(d[k])
        if scale == 0.0:
            e[i] = d[i - 1]
            for j in range(i):
                d[j] = V[i - 1, j]
                V[i, j] = 0.0
                V[j, i] = 0.0
        else:
            inv_scale = 1.0 / scale
            for k in range(i):
                d[k] *= inv_scale
                h += d[k] * d[k]
            f = d[i - 1]
            g = math.sqrt(h)
            if f > 0.0:
                g = -g
            e[i] = scale * g
            h -= f * g
            d[i - 1] = f - g
            for j in range(i):
                e[j] = 0.0
            for j in range(i):
                f = d[j]
                V[j, i] = f
                g = e[j] + V[j, j] * f
                for k in range(j + 1, i):
                    g += V[k, j] * d[k]
                    e[k] += V[k, j] * f
                e[j] = g
            f = 0.0
            inv_h = 1.0 / h
            for j in range(i):
                e[j] *= inv_h
                f += e[j] * d[j]
            hh = f / (h + h)
            for j in range(i):
                e[j] -= hh * d[j]
            for j in range(i):
                f = d[j]
                g = e[j]
                for k in range(j, i):
                    V[k, j] -= f * e[k] + g * d[k]
                d[j] = V[i - 1, j]
                V[i, j] = 0.0
        d[i] = h
    for i in range(n - 1):
        V[n - 1, i] = V[i, i]
        V[i, i] = 1.0
        h = d[i + 1]
        if h != 0.0:
            inv_h = 1.0 / h
            for k in range(i + 1):
                d[k] = V[k, i + 1] * inv_h
            for j in range(i + 1):
                g = 0.0
                for k in range(i + 1):
                    g += V[k, i + 1] * V[k, j]
                for k in range(i + 1):
                    V[k, j] -= g * d[k]
        for k in range(i + 1):
            V[k, i + 1] = 0.0
    for j in range(n):
        d[j] = V[n - 1, j]
        V[n - 1, j] = 0.0
    V[n - 1, n - 1] = 1.0
    for i in range(1, n):
        e[i - 1] = e[i]
    e[n - 1] = 0.0
    return big


@_jit
def _ql_next(d, e, n, l, f, tst1):
    """Deflate converged eigenvalues from index l on; returns the next (l, m, tst1) that needs a
    QL iteration on the block l..m (l == n when all have converged)."""
    while l < n:
        tst1 = max(tst1, abs(d[l]) + abs(e[l]))
        m = l
        while m < n - 1:
            if abs(e[m]) <= EPS * tst1:
                break
            m += 1
        if m > l:
            return l, m, tst1
        d[l] = d[l] + f
        e[l] = 0.0
        l += 1
    return l, l, tst1


@_jit
def _ql_shift(d, e, n, l, m):
    """Start one QL iteration on the block l..m: the Wilkinson-type shift. Returns the amount h
    subtracted from the diagonal, d[l + 1] and e[l + 1] after it, and d[m] (the sweep's p)."""
    g = d[l]
    p = (d[l + 1] - g) / (2.0 * e[l])
    r = math.sqrt(p * p + 1.0)
    if p < 0.0:
        r = -r
    d[l] = e[l] / (p + r)
    d[l + 1] = e[l] * (p + r)
    h = g - d[l]
    for i in range(l + 2, n):
        d[i] -= h
    return h, d[l + 1], e[l + 1], d[m]


@_jit
def _ql_close(d, e, n, l, f, tst1, c, s, s_b, c_c, el, dl):
    """End one QL iteration on the block starting at l (c, s the sweep's last rotation, s_b and
    c_c the ones before); if e[l] has converged, deflate and find the next block. Returns the
    new (l, m, tst1) and whether l moved on."""
    p = -s * s_b * c_c * el * e[l] / dl
    e[l] = s * p
    d[l] = c * p
    if abs(e[l]) > EPS * tst1:
        return l, 0, tst1, False
    d[l] = d[l] + f
    e[l] = 0.0
    l, m, tst1 = _ql_next(d, e, n, l + 1, f, tst1)
    return l, m, tst1, True


@_jit
def _ql_rotation(d, e, V, n, i, p, c, s):
    """One plane rotation of a QL sweep, at rows i, i + 1; returns the new (p, c, s)."""
    g = c * e[i]
    h = c * p
    r = math.sqrt(p * p + e[i] * e[i])
    e[i + 1] = s * r
    s = e[i] / r
    c = p / r
    p = c * d[i] - s * g
    d[i + 1] = h + s * (c * g + s * d[i])
    for k in range(n):
        h = V[k, i + 1]
        V[k, i + 1] = s * V[k, i] + c * h
        V[k, i] = c * V[k, i] - s * h
    return p, c, s


@_jit
def _sort_eigen(V, d, n, big):
    """Undo the scaling and sort the eigenvalues ascending, with their vectors."""
    for i in range(n):
        d[i] *= big
    for i in range(1, n):
        j = i
        while j > 0 and d[j - 1] > d[j]:
            d[j - 1], d[j] = d[j], d[j - 1]
            for r in range(n):
                V[r, j - 1], V[r, j] = V[r, j], V[r, j - 1]
            j -= 1


@_jit
def eigh_pair(V1, d1, e1, V2, d2, e2, n, want1, want2):
    """Two independent symmetric eigenproblems (see :func:`eigh`) solved in lockstep: the QL
    sweeps of both run in one loop, so that the processor overlaps their chains of square roots
    and divisions, each of which waits on the last. Each problem does exactly the arithmetic
    :func:`eigh` does alone. Returns whether each converged (True for a problem not wanted)."""
    ok1 = ok2 = True
    big1 = _tridiagonalize(V1, d1, e1, n) if want1 else 0.0
    big2 = _tridiagonalize(V2, d2, e2, n) if want2 else 0.0
    if want1 and big1 == 0.0:
        ok1 = not np.isnan(d1[0])
    if want2 and big2 == 0.0:
        ok2 = not np.isnan(d2[0])
    f1 = f2 = t1 = t2 = 0.0
    l1 = l2 = m1 = m2 = n
    if big1 > 0.0:
        l1, m1, t1 = _ql_next(d1, e1, n, 0, f1, t1)
    if big2 > 0.0:
        l2, m2, t2 = _ql_next(d2, e2, n, 0, f2, t2)
    it1 = it2 = 0
    p1 = c1 = s1 = s1b = c1b = c1c = el1 = dl1 = 0.0
    p2 = c2 = s2 = s2b = c2b = c2c = el2 = dl2 = 0.0
    while l1 < n or l2 < n:
        run1 = l1 < n
        run2 = l2 < n
        if run1:
            it1 += 1
            if it1 > 60:
                ok1 = False
                run1 = False
                l1 = n
        if run2:
            it2 += 1
            if it2 > 60:
                ok2 = False
                run2 = False
                l2 = n
        i1 = l1 - 1
        i2 = l2 - 1
        if run1:
            h, dl1, el1, p1 = _ql_shift(d1, e1, n, l1, m1)
            f1 += h
            c1 = c1b = c1c = 1.0
            s1 = s1b = 0.0
            i1 = m1 - 1
        if run2:
            h, dl2, el2, p2 = _ql_shift(d2, e2, n, l2, m2)
            f2 += h
            c2 = c2b = c2c = 1.0
            s2 = s2b = 0.0
            i2 = m2 - 1
        # the sweeps, from m - 1 down to l, interleaved
        while i1 >= l1 or i2 >= l2:
            if i1 >= l1:
                c1c = c1b
                c1b = c1
                s1b = s1
                p1, c1, s1 = _ql_rotation(d1, e1, V1, n, i1, p1, c1, s1)
                i1 -= 1
            if i2 >= l2:
                c2c = c2b
                c2b = c2
                s2b = s2
                p2, c2, s2 = _ql_rotation(d2, e2, V2, n, i2, p2, c2, s2)
                i2 -= 1
        if run1:
            l1, new_m, t1, moved = _ql_close(d1, e1, n, l1, f1, t1, c1, s1, s1b, c1c, el1, dl1)
            if moved:
                m1 = new_m
                it1 = 0
        if run2:
            l2, new_m, t2, moved = _ql_close(d2, e2, n, l2, f2, t2, c2, s2, s2b, c2c, el2, dl2)
            if moved:
                m2 = new_m
                it2 = 0
    if big1 > 0.0 and ok1:
        _sort_eigen(V1, d1, n, big1)
    if big2 > 0.0 and ok2:
        _sort_eigen(V2, d2, n, big2)
    return ok1, ok2


@_jit
def _eigen_inverse(V, lam, out, work, n):
    """out = V diag(lam)^-1 V^T (V's columns the eigenvectors of lam); work is (n,)."""
    for r in range(n):
        work[r] = 1.0 / lam[r]
    for p in range(n):
        for q in range(p, n):
            s = 0.0
            for r in range(n):
                s += V[p, r] * V[q, r] * work[r]
            out[p, q] = s
            out[q, p] = s


@_jit
def eigh(V, d, e, n):
    """Eigen-decomposition of the symmetric n x n block of V (overwritten by the eigenvectors,
    as columns); eigenvalues into d, ascending; e is workspace (n,). Householder reduction to
    tridiagonal form, then the implicit QL iteration with Wilkinson-type shifts (the classical
    EISPACK tred2/tql2 pair): backward stable, like LAPACK's symmetric solvers. Returns False
    if an eigenvalue needs more than 60 iterations (the row then takes the SVD path) or the
    matrix is not finite. The QL rotations use sqrt(a^2 + b^2) rather than hypot: entries are
    pre-scaled to at most 1.
    """
    return eigh_pair(V, d, e, V, d, e, n, True, False)[0]


@_jit
def run_chunk(
    k_tuple,
    m_tuple,
    Jw,
    M,
    vmap,
    gravity,
    probe_cols,
    pos,
    supports,
    arm_cols,
    n_arm_cols,
    pair_cols,
    n_pair_cols,
    task_rows,
    n_linear,
    S_ptr,
    S_idx,
    S_val,
    P_ptr,
    P_row,
    P_col,
    P_u,
    P_w,
    P_c,
    Pz_ptr,
    Pz_idx,
    Q_inv,
    vlim,
    elim,
    offsets_in,
    Mo_in,
    mass,
    g_o,
    decouple_eta,
    want_kin,
    want_dyn,
    all_terms,
    tolerances,
    J_u,
    P,
    xi,
    W,
    Mo,
    kin_center,
    kin_semi,
    kin_axes,
    kin_matrix,
    kin_ok,
    dyn_center,
    dyn_semi,
    dyn_axes,
    dyn_matrix,
    dyn_ok,
    dyn_empty,
    bounds,
):
    """Terms and both fast-path ellipsoids for every row of a chunk (see the module docstring).

    k_tuple and m_tuple are tuples (of zeros, say) as long as the number of end effectors
    (``pos.shape[1]``) and the task dimension (``task_rows.shape[0]``).

    Inputs per row i, from the probed model of :class:`mobmanip.batch.ProbedModel`: Jw[i]
    (6, nv_p) world joint Jacobian and M[i] (nv_p, nv_p) (upper triangle read), where the
    robot's degrees of freedom are columns vmap (nv,), generalized gravity is ``gravity`` times
    row 0 of M, and columns probe_cols[a] are the x and y probes at end effector a, whose
    positions go to pos[i] (k, 3) (an output). Constants: supports
    (k, nv), 1 where a joint moves arm a's end effector; arm_cols[a, :n_arm_cols[a]] the
    reduced coordinates that can move it (J_u's other entries in arm a's rows are zero) and
    pair_cols[a, b, :n_pair_cols[a, b]] those that move both a's and b's; task rows (m,),
    linear ones first; S column-compressed; P = S^T M S as a list of terms
    P[P_row[t], P_col[t]] = sum P_c M[P_u, P_w] over M's structural nonzeros (upper triangle,
    indexed as the probed model's, P_ptr delimiting each listed entry; P is zero elsewhere) and
    P's nonzero columns per row, Pz_idx[Pz_ptr[j]:Pz_ptr[j + 1]]; Q_inv (nx, nx) or (0, 0)
    for Q = I; limits; offsets_in (k, 3) or (0, 3) for the centroid; Mo_in (m, m) or (0, 0)
    for a uniform sphere of ``mass`` reaching the farthest grasp; g_o (m,); decouple_eta > 0
    zeroes P's platform-arm blocks in the dynamic ellipsoid; ``tolerances`` is
    :func:`mobmanip.support.tolerances.kernel_tolerances`. Outputs: the ellipsoids of accepted rows and
    the acceptance flags kin_ok / dyn_ok (rows with False are left untouched); the a-priori
    error bounds of every row, bounds (n, 2) (kinematic, dynamic), relative to the ellipsoid's size (inf
    where the closed forms do not apply at all: a row is accepted exactly where its bound is at
    most the certificate threshold); and J_u, P (coupled), xi, W, Mo of the rows some asked
    ellipsoid was not accepted for (of every row with ``all_terms``).
    """
    n = Jw.shape[0]
    nv = vmap.shape[0]
    # The arm count and task dimension come as the lengths of tuples, which Numba compiles in
    # as constants (one specialisation per pair): the many short loops over them then unroll,
    # about 1.5 us per TIAGo++ configuration.
    k = len(k_tuple)
    m = len(m_tuple)
    nx = S_ptr.shape[0] - 1
    km = k * m
    c = km - m
    c1 = max(c, 1)
    has_q = Q_inv.shape[0] > 0
    has_offsets = offsets_in.shape[0] > 0
    has_mo = Mo_in.shape[0] > 0
    vmax = vlim.max()
    vmin = vlim.min()
    tol, cond_limit, gram_limit, kappa_plain = tolerances
    n_pairs = P_ptr.shape[0] - 1

    Jf = np.zeros((6, nv))
    Ju = np.zeros((km, nx))
    Pi = np.zeros((nx, nx))  # entries P_plan does not list stay zero
    xi_i = np.zeros(nx)
    Wi = np.zeros((m, km))
    Moi = np.zeros((m, m))
    r_off = np.zeros((k, 3))
    Kb = np.zeros((k, m, m))
    WWt = np.zeros((m, m))
    WWi = np.zeros((m, m))
    Lm = np.zeros((m, m))
    Xm = np.zeros((m, m))
    T = np.zeros((m, km))
    Cb = np.zeros((m, c1))  # bottom block of C (C's top block is the identity)
    Gu = np.zeros((km, km))
    Lg = np.zeros((km, km))
    Li = np.zeros((km, km))
    Jh = np.zeros((km, nx))
    Gk = np.zeros((km, km))
    GC = np.zeros((km, c1))
    KK = np.zeros((c1, c1))
    KKi = np.zeros((c1, c1))
    Lc = np.zeros((c1, c1))
    Xc = np.zeros((c1, c1))
    X = np.zeros((c1, m))
    Y = np.zeros((c1, m))
    Z = np.zeros((m, km))
    G = np.zeros((m, nx))
    B = np.zeros((m, m))
    Vk = np.zeros((m, m))  # the kinematic and the dynamic eigenproblem
    lamk = np.zeros(m)
    ek = np.zeros(m)
    Vd = np.zeros((m, m))
    lamd = np.zeros(m)
    ed = np.zeros(m)
    ework = np.zeros(m)
    sol = np.zeros((km, m))
    tmp = np.zeros((km, m))
    JpWt = np.zeros((nx, m))
    TMo = np.zeros((km, m))
    Lam = np.zeros((nx, m))
    Lam2 = np.zeros((nx, m))
    mu = np.zeros(nx)
    mu2v = np.zeros(nx)
    Wpg = np.zeros(km)
    L = np.zeros((nx, m))
    mub = np.zeros(nx)
    H = np.zeros((m, m))
    LV = np.zeros((nx, m))
    lam_rq = np.zeros(m)
    order = np.zeros(m, np.int64)
    Hinv = np.zeros((m, m))
    yv = np.zeros(m)
    cv = np.zeros(m)
    vlim2 = vlim * vlim
    row_arm = np.zeros(km, np.uint64)
    for p in range(km):
        row_arm[p] = p // m

    for i in range(n):
        Mi = M[i]
        Jwi = Jw[i]
        bounds[i, 0] = np.inf
        bounds[i, 1] = np.inf
        # ---------------- terms: positions, J_u, P, xi ----------------
        for a in range(k):
            # p = a + w_x (w_x . b), a = w_x x v_x and b = w_y x v_y from the probe columns
            cx = probe_cols[a, 0]
            cy = probe_cols[a, 1]
            vx0, vx1, vx2 = Jwi[0, cx], Jwi[1, cx], Jwi[2, cx]
            wx0, wx1, wx2 = Jwi[3, cx], Jwi[4, cx], Jwi[5, cx]
            vy0, vy1, vy2 = Jwi[0, cy], Jwi[1, cy], Jwi[2, cy]
            wy0, wy1, wy2 = Jwi[3, cy], Jwi[4, cy], Jwi[5, cy]
            s = wx0 * (wy1 * vy2 - wy2 * vy1) + wx1 * (wy2 * vy0 - wy0 * vy2) + wx2 * (wy0 * vy1 - wy1 * vy0)
            p0 = wx1 * vx2 - wx2 * vx1 + wx0 * s
            p1 = wx2 * vx0 - wx0 * vx2 + wx1 * s
            p2 = wx0 * vx1 - wx1 * vx0 + wx2 * s
            pos[i, a, 0] = p0
            pos[i, a, 1] = p1
            pos[i, a, 2] = p2
            for v in range(nv):
                if supports[a, v] == 0.0:
                    for r in range(6):
                        Jf[r, v] = 0.0
                    continue
                col = vmap[v]
                wx = Jwi[3, col]
                wy = Jwi[4, col]
                wz = Jwi[5, col]
                Jf[0, v] = Jwi[0, col] + wy * p2 - wz * p1
                Jf[1, v] = Jwi[1, col] + wz * p0 - wx * p2
                Jf[2, v] = Jwi[2, col] + wx * p1 - wy * p0
                Jf[3, v] = wx
                Jf[4, v] = wy
                Jf[5, v] = wz
            for r in range(m):
                tr = task_rows[r]
                Jr = Ju[a * m + r]
                for j in range(nx):
                    s = 0.0
                    for t in range(S_ptr[j], S_ptr[j + 1]):
                        s += Jf[tr, S_idx[t]] * S_val[t]
                    Jr[j] = s
        for e_ in range(n_pairs):
            s = 0.0
            for t in range(P_ptr[e_], P_ptr[e_ + 1]):
                s += P_c[t] * Mi[P_u[t], P_w[t]]
            Pi[P_row[e_], P_col[e_]] = s
            Pi[P_col[e_], P_row[e_]] = s
        for j in range(nx):
            s = 0.0
            for t in range(S_ptr[j], S_ptr[j + 1]):
                s += Mi[0, vmap[S_idx[t]]] * S_val[t]
            xi_i[j] = -gravity * s

        # ---------------- grasp: W, T, C, M_o ----------------
        if has_offsets:
            for a in range(k):
                for d in range(3):
                    r_off[a, d] = offsets_in[a, d]
        else:
            for d in range(3):
                cen = 0.0
                for a in range(k):
                    cen += pos[i, a, d]
                cen /= k
                for a in range(k):
                    r_off[a, d] = pos[i, a, d] - cen
        radius2 = 0.0
        for a in range(k):
            rr = r_off[a, 0] ** 2 + r_off[a, 1] ** 2 + r_off[a, 2] ** 2
            if rr > radius2:
                radius2 = rr
        for p in range(m):
            for q in range(m):
                if has_mo:
                    Moi[p, q] = Mo_in[p, q]
                elif p != q:
                    Moi[p, q] = 0.0
                elif p < n_linear:
                    Moi[p, q] = mass
                else:
                    Moi[p, q] = 0.4 * mass * radius2
        # W_a = I + K_a, K_a the angular-by-linear block of skew(r_a) on the task's rows
        for a in range(k):
            rx = r_off[a, 0]
            ry = r_off[a, 1]
            rz = r_off[a, 2]
            for p in range(n_linear, m):
                ra = task_rows[p] - 3
                for q in range(n_linear):
                    cl = task_rows[q]
                    if ra == 0:
                        val = -rz if cl == 1 else (ry if cl == 2 else 0.0)
                    elif ra == 1:
                        val = rz if cl == 0 else (-rx if cl == 2 else 0.0)
                    else:
                        val = -ry if cl == 0 else (rx if cl == 1 else 0.0)
                    Kb[a, p, q] = val
            for p in range(m):
                for q in range(m):
                    Wi[p, a * m + q] = Kb[a, p, q] + (1.0 if p == q else 0.0)
        for p in range(m):
            for q in range(p, m):
                s = 0.0
                for r in range(km):
                    s += Wi[p, r] * Wi[q, r]
                WWt[p, q] = s
                WWt[q, p] = s
        grasp_ok = _spd_inverse(WWt, Lm, Xm, WWi, m)
        for p in range(m):
            for r in range(km):
                s = 0.0
                for q in range(m):
                    s += WWi[p, q] * Wi[q, r]
                T[p, r] = s
        # null(W): h_k = -W_k^-1 (W_1 h_1 + ... + W_{k-1} h_{k-1}), W_k^-1 W_a = I + K_a - K_k;
        # C = [I; Cb] with Cb = -[W_k^-1 W_1 ... W_k^-1 W_{k-1}]
        for a in range(k - 1):
            for p in range(m):
                for q in range(m):
                    Cb[p, a * m + q] = -(Kb[a, p, q] - Kb[k - 1, p, q] + (1.0 if p == q else 0.0))

        # ---------------- Gram of J_u: Cholesky, kappa ----------------
        _stacked_grams(Ju, vlim2, Gu, Gk, km, row_arm, pair_cols, n_pair_cols)  # Gk = J_hat J_hat^T
        gram_ok = _cholesky(Gu, Lg, km)
        if gram_ok:
            inv_norm = _lower_inverse(Lg, Li, km)
            kappa = np.sqrt(_fro2(Gu, km, km)) * inv_norm
        else:
            kappa = np.inf

        # ---------------- kinematic ellipsoid: its generator G, B = G G^T ----------------
        kin_ok[i] = False
        kin_go = want_kin and grasp_ok
        hard = True
        second = 0.0
        z_norm = 1.0
        if kin_go:
            branch = np.sqrt(kappa) * (vmax / vmin) < cond_limit
            for p in range(km):
                cols = arm_cols[row_arm[p]]
                for t in range(n_arm_cols[row_arm[p]]):
                    j = cols[t]
                    Jh[p, j] = Ju[p, j] * vlim[j]
            hard = not branch
            second = 0.0
            if k == 1:
                for p in range(m):
                    for j in range(nx):
                        G[p, j] = Jh[p, j]
                z_norm = 1.0
            else:
                # GC = G_k C, KK = C^T G_k C, X = (G_k C)^T T^T
                for p in range(km):
                    for q in range(c):
                        s = Gk[p, q]
                        for r in range(m):
                            s += Gk[p, c + r] * Cb[r, q]
                        GC[p, q] = s
                for p in range(c):
                    for q in range(p, c):
                        s = GC[p, q]
                        for r in range(m):
                            s += Cb[r, p] * GC[c + r, q]
                        KK[p, q] = s
                        KK[q, p] = s
                for p in range(c):
                    for q in range(m):
                        s = 0.0
                        for r in range(km):
                            s += GC[r, p] * T[q, r]
                        X[p, q] = s
                if _spd_inverse(KK, Lc, Xc, KKi, c):
                    kk_norm = np.sqrt(_fro2(KK, c, c))
                    kappa_kk = kk_norm * np.sqrt(_fro2(KKi, c, c))
                else:
                    kk_norm = np.inf
                    kappa_kk = np.inf
                for p in range(c):
                    for q in range(m):
                        s = 0.0
                        for r in range(c):
                            s += KKi[p, r] * X[r, q]
                        Y[p, q] = s
                # Z = T - Y^T C^T
                for q in range(m):
                    for r in range(c):
                        Z[q, r] = T[q, r] - Y[r, q]
                    for r in range(m):
                        s = T[q, c + r]
                        for p in range(c):
                            s -= Y[p, q] * Cb[r, p]
                        Z[q, c + r] = s
                # G = Z J_hat, row by row of J_hat over its nonzero columns
                for q in range(m):
                    for j in range(nx):
                        G[q, j] = 0.0
                for r in range(km):
                    cols = arm_cols[row_arm[r]]
                    ncol = n_arm_cols[row_arm[r]]
                    for q in range(m):
                        z = Z[q, r]
                        for t in range(ncol):
                            j = cols[t]
                            G[q, j] += z * Jh[r, j]
                second = kk_norm * (EPS * kappa_kk * np.sqrt(_fro2(Y, c, m))) ** 2
                hard = hard or not (kappa_kk <= gram_limit)
                z_norm = np.sqrt(_fro2(Z, m, km))
            _gram_twice(G, B, Vk, m, nx)

        # The refinement of J^+ W^T is skipped where J J^T is so well conditioned that the
        # certificate will most likely accept the plain solution; a row it then rejects is
        # computed again, refined.
        dyn_ok[i] = False
        dyn_go = want_dyn and grasp_ok and kappa < gram_limit
        refine = not (kappa <= kappa_plain)
        for attempt in range(2):
            # ---------------- dynamic ellipsoid: L, H = L^T L ----------------
            if dyn_go:
                # J^+ W^T = J^T (J J^T)^-1 W^T, with one refinement step by the residual if asked
                for p in range(km):
                    for q in range(m):
                        tmp[p, q] = Wi[q, p]
                for q in range(nx):
                    for r in range(m):
                        JpWt[q, r] = 0.0
                for step in range(2 if refine else 1):
                    # sol = Li^T (Li tmp)
                    for p in range(km):
                        for q in range(m):
                            sol[p, q] = 0.0
                        for r in range(p + 1):
                            lpr = Li[p, r]
                            for q in range(m):
                                sol[p, q] += lpr * tmp[r, q]
                    for p in range(km):
                        for q in range(m):
                            s = 0.0
                            for r in range(p, km):
                                s += Li[r, p] * sol[r, q]
                            tmp[p, q] = s
                    _add_jt_product(Ju, tmp, JpWt, km, m, row_arm, arm_cols, n_arm_cols)  # JpWt += J_u^T sol
                    if refine and step == 0:
                        for p in range(km):
                            cols = arm_cols[row_arm[p]]
                            ncol = n_arm_cols[row_arm[p]]
                            for q in range(m):
                                s = Wi[q, p]
                                for t in range(ncol):
                                    j = cols[t]
                                    s -= Ju[p, j] * JpWt[j, q]
                                tmp[p, q] = s
                # Lambda = P J^+ W^T + J^T (T^T M_o)
                for p in range(km):
                    for q in range(m):
                        s = 0.0
                        for r in range(m):
                            s += T[r, p] * Moi[r, q]
                        TMo[p, q] = s
                for j in range(nx):
                    for q in range(m):
                        Lam[j, q] = 0.0
                    for t in range(Pz_ptr[j], Pz_ptr[j + 1]):
                        l_ = Pz_idx[t]
                        if decouple_eta > 0 and ((j < decouple_eta) != (l_ < decouple_eta)):
                            continue
                        pjl = Pi[j, l_]
                        for q in range(m):
                            Lam[j, q] += pjl * JpWt[l_, q]
                _add_jt_product(Ju, TMo, Lam, km, m, row_arm, arm_cols, n_arm_cols)
                for p in range(km):
                    s = 0.0
                    for q in range(m):
                        s += T[q, p] * g_o[q]
                    Wpg[p] = s
                for j in range(nx):
                    mu[j] = -xi_i[j]
                for p in range(km):
                    cols = arm_cols[row_arm[p]]
                    ncol = n_arm_cols[row_arm[p]]
                    wp = Wpg[p]
                    for t in range(ncol):
                        j = cols[t]
                        mu[j] += Ju[p, j] * wp
                if has_q:
                    for j in range(nx):
                        for q in range(m):
                            s = 0.0
                            for l_ in range(nx):
                                s += Q_inv[j, l_] * Lam[l_, q]
                            Lam2[j, q] = s
                        s = 0.0
                        for l_ in range(nx):
                            s += Q_inv[j, l_] * mu[l_]
                        mu2v[j] = s
                    for j in range(nx):
                        mu[j] = mu2v[j]
                        for q in range(m):
                            Lam[j, q] = Lam2[j, q]
                for j in range(nx):
                    zj = 1.0 / elim[j]
                    mub[j] = mu[j] * zj
                    for q in range(m):
                        L[j, q] = Lam[j, q] * zj
                _gram_twice(L.T, H, Vd, m, nx)

            # ---------------- both eigenproblems, in lockstep ----------------
            kin_eig, dyn_eig = eigh_pair(Vk, lamk, ek, Vd, lamd, ed, m, kin_go and attempt == 0, dyn_go)

            # ---------------- kinematic ellipsoid: certificate, semi-axes ----------------
            if kin_go and attempt == 0:
                eig_ok = kin_eig
                lmin = lamk[0]
                lmax = lamk[m - 1]
                gen_norm = z_norm * np.sqrt(_fro2(Jh, km, nx)) * np.sqrt(_fro2(G, m, nx))
                err = 8.0 * EPS * (gen_norm + np.sqrt(_fro2(B, m, m)))
                err += second
                est = err / (2.0 * np.sqrt(abs(lmin * lmax)))
                if eig_ok and not hard and lmin * gram_limit > lmax and lmin > 0.0 and np.isfinite(est):
                    bounds[i, 0] = est
                if bounds[i, 0] <= tol:
                    kin_ok[i] = True
                    for p in range(m):
                        kin_center[i, p] = 0.0
                        src = m - 1 - p
                        kin_semi[i, p] = np.sqrt(lamk[src])
                        for q in range(m):
                            kin_axes[i, p, q] = Vk[q, src]
                    _eigen_inverse(Vk, lamk, kin_matrix[i], ework, m)

            # ---------------- dynamic ellipsoid: certificate, semi-axes, centre ----------------
            if dyn_go:
                eig_ok = dyn_eig
                for j in range(nx):
                    for q in range(m):
                        s = 0.0
                        for p in range(m):
                            s += L[j, p] * Vd[p, q]
                        LV[j, q] = s
                for q in range(m):
                    lam_rq[q] = 0.0
                for j in range(nx):
                    for q in range(m):
                        lam_rq[q] += LV[j, q] * LV[j, q]
                _eigen_inverse(Vd, lam_rq, Hinv, ework, m)
                # centre: normal equations, then one refinement step
                for p in range(m):
                    s = 0.0
                    for j in range(nx):
                        s += L[j, p] * mub[j]
                    yv[p] = s
                for p in range(m):
                    s = 0.0
                    for q in range(m):
                        s += Hinv[p, q] * yv[q]
                    cv[p] = -s
                for p in range(m):
                    yv[p] = 0.0
                for j in range(nx):
                    s = mub[j]
                    for p in range(m):
                        s += L[j, p] * cv[p]
                    for p in range(m):
                        yv[p] += L[j, p] * s
                for p in range(m):
                    s = 0.0
                    for q in range(m):
                        s += Hinv[p, q] * yv[q]
                    cv[p] -= s
                outside2 = 0.0
                mub2 = 0.0
                for j in range(nx):
                    s = mub[j]
                    for p in range(m):
                        s += L[j, p] * cv[p]
                    outside2 += s * s
                    mub2 += mub[j] * mub[j]
                rho2 = 1.0 - outside2
                lmin = lam_rq.min()
                lmax = lam_rq.max()
                aniso = np.sqrt(lmax / lmin)
                # J^+ W^T's relative error: eps kappa(J)^2 as solved, eps (kappa(J) + eps kappa(J)^4) refined
                j_err = np.sqrt(kappa) + EPS * kappa * kappa if refine else kappa
                err_l = 8.0 * EPS * (1.0 + j_err) * aniso
                err_rho2 = 2.0 * np.sqrt(outside2 * mub2) * err_l + 8.0 * EPS * mub2
                c_norm = 0.0
                for p in range(m):
                    c_norm += cv[p] * cv[p]
                c_norm = np.sqrt(c_norm)
                scale = max(np.sqrt(abs(rho2) / lmin), c_norm)
                err_c = err_l * (c_norm + np.sqrt(outside2 / lmin)) / scale
                bounds[i, 1] = np.inf
                if eig_ok and lmin > 0.0 and np.isfinite(aniso) and aniso < cond_limit:
                    bounds[i, 1] = max(err_l, err_c, err_rho2 / (2.0 * abs(rho2)))
                if bounds[i, 1] <= tol:
                    dyn_ok[i] = True
                    for p in range(m):
                        dyn_center[i, p] = cv[p]
                    if rho2 <= 0.0:
                        dyn_empty[i] = True
                        for p in range(m):
                            dyn_semi[i, p] = 0.0
                            for q in range(m):
                                dyn_axes[i, p, q] = 1.0 if p == q else 0.0
                                dyn_matrix[i, p, q] = 0.0
                    else:
                        dyn_empty[i] = False
                        # ascending Rayleigh quotient = descending semi-axis
                        for p in range(m):
                            order[p] = p
                        for p in range(1, m):
                            j = p
                            while j > 0 and lam_rq[order[j - 1]] > lam_rq[order[j]]:
                                order[j - 1], order[j] = order[j], order[j - 1]
                                j -= 1
                        for p in range(m):
                            src = order[p]
                            dyn_semi[i, p] = np.sqrt(rho2 / lam_rq[src])
                            for q in range(m):
                                dyn_axes[i, p, q] = Vd[q, src]
                        inv_rho2 = 1.0 / rho2
                        for p in range(m):
                            for q in range(m):
                                dyn_matrix[i, p, q] = H[p, q] * inv_rho2

            if not dyn_go or dyn_ok[i] or refine:
                break
            refine = True

        # ---------------- terms, where the caller needs them ----------------
        if all_terms or (want_kin and not kin_ok[i]) or (want_dyn and not dyn_ok[i]):
            for p in range(km):
                for j in range(nx):
                    J_u[i, p, j] = Ju[p, j]
            for j in range(nx):
                xi[i, j] = xi_i[j]
                for l_ in range(nx):
                    P[i, j, l_] = Pi[j, l_]
            for p in range(m):
                for q in range(km):
                    W[i, p, q] = Wi[p, q]
                for q in range(m):
                    Mo[i, p, q] = Moi[p, q]
