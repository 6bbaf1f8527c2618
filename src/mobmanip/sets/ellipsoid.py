"""Unified kinematic (Eq. 23-26) and dynamic (Eq. 27-38) task-space ellipsoids.

Both are computed from arrays only (J_u, W, P, Q, xi, M_o, g_o and the limits), so single
configurations and stacked batches share the same mathematics.

Kinematic ellipsoid: normalised reduced velocities qbar = Y x with ||qbar|| <= 1 (Y = diag(1 /
qdot_max)) move the end effectors as v = J_hat qbar, J_hat = J_u Y^-1. The object moves with
v_o when v = W^T v_o. The set of object velocities reachable this way is
{v_o : ||J_hat^+ W^T v_o|| <= 1} (the consistent form of Eq. 26; the printed Eq. 26 applies Y
a second time). It is computed as the image of the unit ball of the joint motions that are
consistent with a rigid object, which stays exact when J_hat loses rank.

Dynamic ellipsoid: with robot and object at rest, tau = Lambda_o a_o + mu_o with
Lambda_o = Q^-1 P J^+ W^T + Q^-1 J^T W^+ M_o and mu_o = -Q^-1 xi + Q^-1 J^T W^+ g_o (Eq. 33-35;
the printed Eq. 35 has the sign of xi wrong). The set {a_o : ||Z (Lambda_o a_o + mu_o)|| <= 1}
(Eq. 38, Z = diag(1 / tau_max)) is an ellipsoid whose centre shifts under gravity; it is empty
when the part of Z mu_o that no acceleration can cancel already has norm >= 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ModelError, SetQueryError
from ..support.tolerances import FAST_RTOL
from ..support.tolerances import RANK_RTOL as _RANK_RTOL
from .taskset import TaskSet, check_dims, check_direction, check_membership_points, membership

# The full-rank branches below (J of full row rank, every W^T a_o reachable) skip the null-space
# projections; they run while the smallest singular value exceeds FAST_RTOL times the largest
# (read here at call time, so a test can set it to infinity to force the general branches).
# Otherwise the general branch handles the (near-)singular case exactly.


def _null_space(A: np.ndarray, n: int) -> np.ndarray:
    """Orthonormal basis (n, d) of the null space of A (rows may be zero)."""
    if A.size == 0:
        return np.eye(n)
    _, s, vt = np.linalg.svd(A)
    scale = max(s[0] if s.size else 0.0, 1.0)
    rank = int(np.sum(s > _RANK_RTOL * scale))
    return vt[rank:].T


@dataclass(frozen=True)
class Ellipsoid(TaskSet):
    """The set {c + sum_k s_k z_k e_k : ||z|| <= 1} in an m-dimensional task space.

    A :class:`mobmanip.sets.taskset.TaskSet` of kind ``"ellipsoid"``: its capacities
    (:meth:`radius_along`) are measured from its centre.

    Attributes:
        center: centre c, (m,).
        semi_axes: semi-axis lengths s_k, descending, (m,). Zero where the task cannot move.
        axes: unit directions, ``axes[k]`` belongs to ``semi_axes[k]``, (m, m) orthonormal rows.
        matrix: A with (p - c)^T A (p - c) <= 1 on the non-degenerate axes, (m, m); a
            pseudo-inverse (zero along degenerate axes) when ``degenerate``.
        degenerate: some semi-axis is zero (a singular arm, a zero limit, a blocked direction).
        empty: no point satisfies the limits (e.g. torques cannot even hold the load still);
            then ``semi_axes`` are zero and ``center`` is the least-violating point.
    """

    center: np.ndarray
    semi_axes: np.ndarray
    axes: np.ndarray
    matrix: np.ndarray
    degenerate: bool
    empty: bool

    kind = "ellipsoid"

    @property
    def dim(self) -> int:
        """Task dimension m."""
        return int(self.semi_axes.shape[0])

    @property
    def volume(self) -> float:
        """Volume of the m-ball scaled by the semi-axes: pi^(m/2) / Gamma(m/2 + 1) prod s_k."""
        m = self.dim
        return float(math.pi ** (m / 2) / math.gamma(m / 2 + 1) * np.prod(self.semi_axes))

    @property
    def manipulability(self) -> float:
        """Yoshikawa-style measure: the product of the semi-axes."""
        return float(np.prod(self.semi_axes))

    @property
    def isotropy(self) -> float:
        """Smallest over largest semi-axis, in [0, 1] (0 when degenerate or empty)."""
        largest = float(self.semi_axes[0]) if self.dim else 0.0
        return float(self.semi_axes[-1] / largest) if largest > 0.0 else 0.0

    @property
    def generator(self) -> np.ndarray:
        """G with the ellipsoid = {c + G z : ||z|| <= 1}, (m, m)."""
        return self.axes.T * self.semi_axes

    def support(self, direction: np.ndarray) -> float:
        """max over the ellipsoid of d . p for a direction d, (m,) (not necessarily unit):
        d . c + ||G^T d||; 0 when empty.

        Raises:
            SetQueryError: d has the wrong shape, is zero or not finite.
        """
        d = check_direction(direction, self.dim)
        if self.empty:
            return 0.0
        return float(d @ self.center + np.linalg.norm(self.generator.T @ d))

    def radius_along(self, direction: np.ndarray) -> float:
        """How far the ellipsoid reaches from its centre along the unit direction of d (capacity);
        0 when empty.

        Raises:
            SetQueryError: d has the wrong shape, is zero or not finite.
        """
        d = check_direction(direction, self.dim)
        d = d / np.linalg.norm(d)
        return float(np.linalg.norm(self.generator.T @ d))

    def straight_line_reach(self, direction: np.ndarray) -> float:
        """The largest s >= 0 with ``s d / |d|`` in the ellipsoid: how far along d from rest (the
        origin), exactly along d (closed form, :func:`straight_line_reaches`; 0 when the ray from
        the origin misses the ellipsoid or it is empty). At most :meth:`support` of the unit d.

        Raises:
            SetQueryError: d has the wrong shape, is zero or not finite.
        """
        d = check_direction(direction, self.dim)
        reach = straight_line_reaches(self.center[None], self.semi_axes[None], self.axes[None], d[None])
        return 0.0 if self.empty else float(reach[0])

    def contains(self, points: ArrayLike, tol: float = 1e-9) -> bool | np.ndarray:
        """Whether points lie in the ellipsoid (within ``tol`` in the normalised norm, and ``tol``
        in task units along a zero semi-axis): a ``bool`` for one point (m,), a bool array (n,)
        for points (n, m).

        Raises:
            SetQueryError: any other shape (named), or a non-finite coordinate.
        """
        P, single = check_membership_points(points, self.dim)
        p = P - self.center
        if self.empty:
            return membership(np.zeros(len(p), dtype=bool), single)
        coords = p @ self.axes.T  # components along each axis
        inside = np.ones(len(p), dtype=bool)
        positive = self.semi_axes > 0
        norm2 = np.sum((coords[:, positive] / self.semi_axes[positive]) ** 2, axis=1)
        inside &= norm2 <= (1.0 + tol) ** 2
        if (~positive).any():
            inside &= np.all(np.abs(coords[:, ~positive]) <= tol, axis=1)
        return membership(inside, single)

    def project(self, dims: Sequence[int] = (0, 1)) -> Ellipsoid:
        """The shadow of the ellipsoid on the task coordinates ``dims`` (e.g. (0, 1) gives a 2-D
        ellipse; the other coordinates are free).

        Raises:
            SetQueryError: ``dims`` repeated, empty or out of range.
        """
        dims = check_dims(dims, self.dim)
        return Ellipsoid.from_generator(self.center[dims], self.generator[dims], empty=self.empty)

    def slice(self, dims: Sequence[int] = (0, 1)) -> Ellipsoid:
        """The cut through the centre in the task coordinates ``dims`` (others at the centre's).

        Raises:
            SetQueryError: ``dims`` repeated, empty or out of range.
        """
        dims = check_dims(dims, self.dim)
        k = len(dims)
        if self.empty:
            return Ellipsoid.from_generator(self.center[dims], np.zeros((k, k)), empty=True)
        # Points c + B y with B selecting the coordinates; inside iff ||G^+ B y|| <= 1 and
        # B y in the range of G.
        B = np.zeros((self.dim, k))
        B[dims, list(range(k))] = 1.0
        G = self.generator
        G_pinv = np.linalg.pinv(G, rcond=_RANK_RTOL)
        blocked = B - G @ (G_pinv @ B)  # component of B y outside range(G)
        N = _null_space(blocked, k)
        if N.shape[1] == 0:
            return Ellipsoid.from_generator(self.center[dims], np.zeros((k, k)))
        # within y = N w: ||G^+ B N w|| <= 1  ->  image of the unit ball under (G^+ B N)^+.
        K = G_pinv @ B @ N
        return Ellipsoid.from_generator(self.center[dims], N @ np.linalg.pinv(K, rcond=_RANK_RTOL))

    def boundary(self, n: int = 200) -> np.ndarray:
        """Points on a 2-D ellipse's boundary, (n, 2) (use :meth:`project` or :meth:`slice` first)."""
        if self.dim != 2:
            raise SetQueryError(f"boundary() needs a 2-D ellipse, this one is {self.dim}-D; project or slice first")
        t = np.linspace(0.0, 2.0 * np.pi, n)
        return self.center + (self.generator @ np.vstack([np.cos(t), np.sin(t)])).T

    @classmethod
    def from_generator(cls, center: np.ndarray, G: np.ndarray, empty: bool = False) -> Ellipsoid:
        """The ellipsoid {c + G z : ||z|| <= 1} for any G (m, d)."""
        center = np.asarray(center, dtype=float)
        m = center.shape[0]
        G = np.asarray(G, dtype=float).reshape(m, -1)
        U, s, _ = np.linalg.svd(G, full_matrices=True)
        semi = np.zeros(m)
        k = min(m, s.shape[0])
        semi[:k] = s[:k]
        scale = max(semi[0] if m else 0.0, 1e-300)
        semi[semi <= _RANK_RTOL * scale] = 0.0
        if empty:
            semi[:] = 0.0
        positive = semi > 0
        inverse = np.zeros(m)
        inverse[positive] = 1.0 / semi[positive] ** 2
        matrix = (U * inverse) @ U.T
        return cls(
            center=center,
            semi_axes=semi,
            axes=U.T.copy(),
            matrix=matrix,
            degenerate=bool((~positive).any()),
            empty=empty,
        )

    def to_dict(self) -> dict:
        """JSON-ready dictionary (``axes[k]`` is the unit direction of ``semi_axes[k]``); ``"kind"``
        is ``"ellipsoid"``."""
        return {
            "kind": self.kind,
            "center": self.center.tolist(),
            "semi_axes": self.semi_axes.tolist(),
            "axes": self.axes.tolist(),
            "matrix": self.matrix.tolist(),
            "volume": self.volume,
            "isotropy": self.isotropy,
            "degenerate": self.degenerate,
            "empty": self.empty,
        }


#: A ray whose unit direction has a component above this across a flat ellipsoid's plane crosses
#: it (one point of the ray is in the set at most); below it, the ray runs along the plane.
PLANE_CROSSING = 1e-8


def straight_line_reaches(
    center: np.ndarray, semi_axes: np.ndarray, axes: np.ndarray, directions: np.ndarray
) -> np.ndarray:
    """Straight-line reach of N ellipsoids: the largest s >= 0 with s u_n in ellipsoid n, (N,),
    u_n the unit direction of ``directions[n]``; 0 where the ray from the origin misses the set.

    In the axes' coordinates a point s u of the ray is ``s y - z`` from the centre (y = axes u,
    z = axes c). Along the positive semi-axes it must satisfy ``sum_k ((s y_k - z_k) / s_k)^2 <=
    1``, the quadratic ``a s^2 - 2 b s + e <= 0``: an interval of s between its roots. Along a
    zero semi-axis (a flat set) it must stay in the centre's plane, to the set's rounding
    ``tol = RANK_RTOL * size``: a ray that crosses the plane (``|y_k| > PLANE_CROSSING``) meets it
    at the one point s = z_k / y_k, which counts when it satisfies every other condition; a ray
    along the plane keeps ``|s y_k - z_k| <= tol`` over an interval. The reach is the top of what
    remains with s >= 0. Empty sets are the caller's to flag.

    Args:
        center: centres, (N, m).
        semi_axes: semi-axis lengths, (N, m) (zero along flat directions).
        axes: unit directions, ``axes[n, k]`` belongs to ``semi_axes[n, k]``, (N, m, m).
        directions: finite non-zero directions, (N, m); normalised here.
    """
    u = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    y = np.einsum("nkj,nj->nk", axes, u)
    z = np.einsum("nkj,nj->nk", axes, center)
    positive = semi_axes > 0.0
    full = bool(positive.all())  # a sweep's usual chunk: no flat set, a > 0 in every row
    inverse = 1.0 / semi_axes if full else np.where(positive, 1.0 / np.where(positive, semi_axes, 1.0), 0.0)
    w, v = y * inverse, z * inverse
    a, b = np.einsum("nk,nk->n", w, w), np.einsum("nk,nk->n", w, v)
    e = np.einsum("nk,nk->n", v, v) - 1.0
    disc = b * b - a * e
    # the two roots without cancellation: (b +- root) / a, the other one as e / (b +- root)
    big = b + np.copysign(np.sqrt(np.maximum(disc, 0.0)), b)
    with np.errstate(divide="ignore", invalid="ignore"):
        first, second = big / a, e / big
    if full:  # both roots 0 when big = 0 (e = 0: the origin on the boundary); fmax skips that NaN
        hi = np.fmax(first, second)
        return np.where((disc >= 0.0) & (hi >= 0.0), hi, 0.0)
    crossed = (a > 0.0) & (disc >= 0.0)
    second = np.where(big != 0.0, second, 0.0)
    lo = np.where(crossed, np.minimum(first, second), np.where(e <= 0.0, -np.inf, np.inf))
    hi = np.where(crossed, np.maximum(first, second), np.where(e <= 0.0, np.inf, -np.inf))
    lo = np.maximum(lo, 0.0)
    flat = ~positive
    if flat.any():
        size = np.maximum(np.maximum(semi_axes[:, 0], np.linalg.norm(center, axis=1)), 1e-300)
        tol = _RANK_RTOL * size[:, None]
        # along the plane: an interval of s (the whole line when z_k is within tol)
        along = flat & (np.abs(y) <= PLANE_CROSSING)
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = np.stack([(z - tol) / y, (z + tol) / y])
        moving = along & (y != 0.0)
        lo = np.maximum(lo, np.where(moving, ends.min(axis=0), -np.inf).max(axis=1))
        hi = np.minimum(hi, np.where(moving, ends.max(axis=0), np.inf).min(axis=1))
        hi = np.where((along & (y == 0.0) & (np.abs(z) > tol)).any(axis=1), -np.inf, hi)
        # across the plane: the one crossing point, at the flat axis the ray crosses most steeply
        across = flat & ~along
        pinned = across.any(axis=1)
        if pinned.any():
            k = np.argmax(np.where(across, np.abs(y), -1.0), axis=1)
            rows = np.arange(len(k))
            point = np.where(pinned, z[rows, k] / np.where(pinned, y[rows, k], 1.0), 0.0)
            in_plane = np.all(~across | (np.abs(point[:, None] * y - z) <= tol), axis=1)
            ok = in_plane & (lo <= point) & (point <= hi)
            lo = np.where(pinned, point, lo)
            hi = np.where(pinned, np.where(ok, point, -np.inf), hi)
    return np.where((lo <= hi) & np.isfinite(hi), hi, 0.0)


def kinematic_ellipsoid(J_u: np.ndarray, W: np.ndarray, velocity_limits: np.ndarray) -> Ellipsoid:
    """The unified kinematic (velocity) ellipsoid of the object (or end effector, W = I).

    Args:
        J_u: unified Jacobian, stacked end-effector task velocities per reduced velocity, (m k, nx).
        W: grasp matrix, (m, m k).
        velocity_limits: qdot_max per reduced velocity (rad/s or m/s), (nx,).

    Returns:
        The ellipsoid of object velocities (m/s, rad/s) centred at zero.
    """
    J_hat = J_u * np.asarray(velocity_limits, dtype=float)  # J Y^-1
    m = W.shape[0]
    # Full row rank J_hat = U diag(s) V^T: the set is v_o^T W U diag(s^-2) U^T W^T v_o <= 1.
    U, s, _ = np.linalg.svd(J_hat, full_matrices=False)
    if s.shape[0] == J_hat.shape[0] and s[-1] > FAST_RTOL * s[0]:
        B = (W @ U) / s
        # A = B B^T; semi-axes and axes from the SVD of B (eigh(A) would square its conditioning
        # and lose the large semi-axes' accuracy).
        Ub, sb, _ = np.linalg.svd(B, full_matrices=False)
        if sb[-1] > 0.0:
            return Ellipsoid(np.zeros(m), 1.0 / sb[::-1], Ub[:, ::-1].T.copy(), B @ B.T, False, False)
    # General case: image of the unit ball of the joint motions a rigid object can follow.
    Wt_pinv = np.linalg.pinv(W.T)  # left inverse of W^T: v_o = (W^T)^+ v
    inconsistent = J_hat - W.T @ (Wt_pinv @ J_hat)
    N = _null_space(inconsistent, J_hat.shape[1])
    return Ellipsoid.from_generator(np.zeros(m), Wt_pinv @ J_hat @ N)


def dynamic_ellipsoid(
    J_u: np.ndarray,
    W: np.ndarray,
    P: np.ndarray,
    Q: np.ndarray,
    xi: np.ndarray,
    M_o: np.ndarray,
    g_o: np.ndarray,
    effort_limits: np.ndarray,
) -> Ellipsoid:
    """The unified dynamic (acceleration) ellipsoid of the object, at rest (Eq. 27-38).

    Args:
        J_u: unified Jacobian, (m k, nx).
        W: grasp matrix, (m, m k).
        P: reduced inertia (coupled or decoupled), (nx, nx).
        Q: reduced input matrix, (nx, nx).
        xi: reduced bias at rest (-S^T g), (nx,).
        M_o: object inertia in the task space, (m, m).
        g_o: object gravity wrench (Eq. 22), (m,).
        effort_limits: tau_max per reduced velocity (N m or N), (nx,).

    Returns:
        The ellipsoid of object accelerations (m/s^2, rad/s^2); shifted by gravity, ``empty``
        when the limits cannot hold the load, ``degenerate`` along directions the end effectors
        cannot accelerate in (W^T a_o outside the range of J).
    """
    m = W.shape[0]
    Z = 1.0 / np.asarray(effort_limits, dtype=float)
    if _is_identity(Q):
        Q = None  # skip the solves with Q (the usual case: wheel and joint torques)
    U, s, Vt = np.linalg.svd(J_u, full_matrices=False)
    if s.shape[0] == J_u.shape[0] and s[-1] > FAST_RTOL * s[0]:
        # J of full row rank: every W^T a_o is reachable.
        J_pinv = (Vt.T / s) @ U.T
        W_pinv = np.linalg.solve(W @ W.T, W).T
        fast = _dynamic_from(Z, J_u, J_pinv, W, W_pinv, P, Q, xi, M_o, g_o, None)
        if fast is not None:
            return fast
    # Range of J and J^+ from one SVD with one rank decision, so that they agree near a
    # singularity (a residual W^T - J J^+ W^T would carry round-off of order cond(J) eps).
    rank = int(np.sum(s > _RANK_RTOL * max(s[0], 1e-300)))
    U_r, s_r, Vt_r = U[:, :rank], s[:rank], Vt[:rank]
    J_pinv = (Vt_r.T / s_r) @ U_r.T
    W_pinv = np.linalg.pinv(W)
    # Object accelerations the end effectors can follow at rest: W^T a_o in range(J).
    N = _null_space(W.T - U_r @ (U_r.T @ W.T), m)
    if N.shape[1] == 0:
        mu_bar = Z * _torque_offset(J_u, W_pinv, Q, xi, g_o)
        return Ellipsoid.from_generator(np.zeros(m), np.zeros((m, 1)), empty=bool(np.linalg.norm(mu_bar) >= 1.0))
    ellipsoid = _dynamic_from(Z, J_u, J_pinv, W, W_pinv, P, Q, xi, M_o, g_o, N)
    assert ellipsoid is not None  # with the null space N given, the general form always answers
    return ellipsoid


def _torque_offset(J_u, W_pinv, Q, xi, g_o) -> np.ndarray:
    """mu_o = Q^-1 (-xi + J^T W^+ g_o): torques that hold robot and object still (Q None: identity)."""
    mu = -xi + J_u.T @ (W_pinv @ g_o)
    return mu if Q is None else np.linalg.solve(Q, mu)


def _is_identity(Q: np.ndarray) -> bool:
    return Q.shape[0] == Q.shape[1] and bool(np.all(Q == np.eye(Q.shape[0])))


def _dynamic_from(Z, J_u, J_pinv, W, W_pinv, P, Q, xi, M_o, g_o, N) -> Ellipsoid | None:
    """The dynamic ellipsoid restricted to object accelerations a_o = N b (N orthonormal, m x d).

    With L = Z Lambda_o N and mu_bar = Z mu_o, ||L b + mu_bar||^2 <= 1 is an ellipsoid around
    b_c = -L^+ mu_bar of "radius" rho^2 = 1 - |mu_bar outside range(L)|^2. N None stands for the
    identity (the fast path), which returns None when L is too ill-conditioned for it; Q None
    stands for the identity.
    """
    m = W.shape[0]
    Lam = P @ (J_pinv @ W.T) + J_u.T @ (W_pinv @ M_o)
    if Q is not None:
        Lam = np.linalg.solve(Q, Lam)
    L = Z[:, None] * (Lam if N is None else Lam @ N)
    mu_bar = Z * _torque_offset(J_u, W_pinv, Q, xi, g_o)
    U, s, Vt = np.linalg.svd(L, full_matrices=False)
    if N is None:
        if s[-1] <= FAST_RTOL * s[0]:
            return None
        along = U.T @ mu_bar
        center = -(Vt.T @ (along / s))
        rho2 = 1.0 - max(float(mu_bar @ mu_bar - along @ along), 0.0)
        if rho2 <= 0.0:
            return Ellipsoid.from_generator(center, np.zeros((m, 1)), empty=True)
        # s is descending, so the semi-axes rho / s come out ascending: reverse them.
        matrix = (Vt.T * (s * s / rho2)) @ Vt
        return Ellipsoid(center, (math.sqrt(rho2) / s)[::-1], Vt[::-1].copy(), matrix, False, False)
    if s[-1] <= _RANK_RTOL * max(s[0], 1e-300):
        raise ModelError(
            "an object acceleration needs no joint torque: the model has moving links without mass or inertia"
        )
    along = U.T @ mu_bar
    outside2 = max(float(mu_bar @ mu_bar - along @ along), 0.0)
    center = N @ (-(Vt.T @ (along / s)))
    rho2 = 1.0 - outside2
    if rho2 <= 0.0:
        return Ellipsoid.from_generator(center, np.zeros((m, 1)), empty=True)
    return Ellipsoid.from_generator(center, N @ (Vt.T * (math.sqrt(rho2) / s)))
