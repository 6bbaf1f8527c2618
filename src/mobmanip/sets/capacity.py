"""Exact capacity polytopes of the object (or end effector): box limits instead of the unit sphere.

The paper's ellipsoids bound the joints in the Euclidean norm; real limits bound each wheel and
joint on its own. The sets below are the exact answers under those box limits, computed from
the same arrays as :mod:`mobmanip.sets.ellipsoid` (robot and object at rest):

Kinematic, ``{v_o : W^T v_o = J_u x, |x_i| <= xdot_max_i}``: the zonotope J_u diag(xdot_max) box
in the end effectors' space cut by range(W^T) (the motions a rigid object can follow) and
mapped back to the object by W^T's left inverse. With one hand (W = I) a plain zonotope.

Dynamic, exact, ``{a_o : P qdd = xi + Q tau - J_u^T h, J_u qdd = W^T a_o, W h = M_o a_o + g_o,
|tau_i| <= tau_max_i}`` over any qdd, tau and internal forces h (h is what the hands apply to
the object). This is the forward dynamics of the closed chain robot + object: with the
accelerations z = (qdd, a_o) and the constraint C z = 0, C = [J_u, -W^T], the equations read
diag(P, M_o) z = (xi + Q tau, -g_o) - C^T h. With N a basis of null(C),
z = N (N^T diag(P, M_o) N)^-1 N^T (xi + Q tau, -g_o). N^T diag(P, M_o) N is positive definite
(z in null(C) with qdd = 0 has W^T a_o = 0, so a_o = 0), even when J_u loses rank or W has
internal-force directions the joints cannot feel: the acceleration is unique for every torque
and the set is the zonotope

    a_o = c + G tau_n,  c = N_a H^-1 (N_q^T xi - N_a^T g_o),  G = N_a H^-1 N_q^T Q diag(tau_max),

with tau_n in [-1, 1]^n. It is never empty: whatever the torques, robot and object move
somehow. Under an overload every point of it is a fall; whether the load can be held still is
``contains(0)``. Its centre c is the acceleration at zero torque.

Dynamic, the paper's policy: qdd = J_u^+ W^T a_o and h = W^+ (M_o a_o + g_o), i.e.
tau = Lambda_o a_o + mu_o (Eq. 33-35, with the corrected sign of xi) and the set
``{a_o : |Lambda_o a_o + mu_o| <= tau_max}`` over the object accelerations the end effectors can
follow (W^T a_o in range(J_u)). It lies inside the exact set (the policy is one admissible
choice of qdd and h). It contains the dynamic ellipsoid {||Z (Lambda_o a_o + mu_o)|| <= 1}
(||.||_inf <= ||.||_2), so an empty polytope implies an empty ellipsoid; the converse fails
(the polytope reaches up to sqrt(n) times further). It is empty when the least normalised
torque needed for any acceleration, min_a ||Z (Lambda_o a + mu_o)||_inf, exceeds 1.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from ..errors import LimitError, ModelError, TaskError
from .ellipsoid import _RANK_RTOL, _is_identity, _null_space, _torque_offset
from .polytope import Polytope
from .taskset import TaskSet

if TYPE_CHECKING:
    from .capacity_batch import CompiledPolytopeBatch

KINDS = ("kinematic", "dynamic", "dynamic_min_norm")
_DYNAMIC_TERMS = ("J_u", "W", "P", "Q", "xi", "M_o", "g_o", "effort_limits")
#: The terms each kind is computed from: the keyword arguments :func:`polytopes` needs (the
#: names of :class:`mobmanip.terms.builder.MeasureTerms`).
POLYTOPE_TERMS = {"kinematic": ("J_u", "W", "velocity_limits"), "dynamic": _DYNAMIC_TERMS,
                  "dynamic_min_norm": _DYNAMIC_TERMS}  # fmt: skip


def kinematic_polytope(J_u: np.ndarray, W: np.ndarray, velocity_limits: np.ndarray) -> Polytope:
    """The exact set of object velocities under per-joint speed limits.

    Args:
        J_u: unified Jacobian, (m k, nx).
        W: grasp matrix, (m, m k), of full row rank.
        velocity_limits: xdot_max per reduced velocity (rad/s or m/s), (nx,).

    Returns:
        A polytope centred (and symmetric) at the origin, in m/s and rad/s; its
        :meth:`~Polytope.inputs` are reduced velocities x.
    """
    J_u, W = _check_jacobian_grasp(J_u, W)
    limits = _check_limits(velocity_limits, J_u.shape[1], "velocity")
    return Polytope(W.T, np.zeros(W.shape[1]), J_u * limits, limits)


def dynamic_polytope(
    J_u: np.ndarray,
    W: np.ndarray,
    P: np.ndarray,
    Q: np.ndarray,
    xi: np.ndarray,
    M_o: np.ndarray,
    g_o: np.ndarray,
    effort_limits: np.ndarray,
) -> Polytope:
    """The exact set of object accelerations at rest under per-joint torque limits (a zonotope).

    Args:
        J_u: unified Jacobian, (m k, nx).
        W: grasp matrix, (m, m k), of full row rank.
        P: reduced inertia (coupled or decoupled), symmetric positive definite, (nx, nx).
        Q: reduced input matrix, (nx, nx).
        xi: reduced bias at rest (-S^T g), (nx,).
        M_o: object inertia in the task space, (m, m).
        g_o: object gravity wrench (Eq. 22), (m,).
        effort_limits: tau_max per reduced velocity (N m or N), (nx,).

    Returns:
        A zonotope centred at the acceleration with zero torque, in m/s^2 and rad/s^2; its
        :meth:`~Polytope.inputs` are torques tau.

    Raises:
        ModelError: the closed chain's inertia N^T diag(P, M_o) N is not positive definite
            (moving links without mass).
    """
    J_u, W, P, Q, xi, M_o, g_o = _check_dynamic(J_u, W, P, Q, xi, M_o, g_o)
    limits = _check_limits(effort_limits, J_u.shape[1], "effort")
    nx = J_u.shape[1]
    C = np.hstack([J_u, -W.T])
    _, s, Vt = np.linalg.svd(C, full_matrices=True)
    rank = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1e-300)))
    N = Vt[rank:].T  # accelerations (qdd, a_o) the grasp allows, (nx + m, d)
    N_q, N_a = N[:nx], N[nx:]
    H = N_q.T @ P @ N_q + N_a.T @ M_o @ N_a
    try:
        factor = scipy.linalg.cho_factor(0.5 * (H + H.T))
    except np.linalg.LinAlgError:
        raise ModelError(
            "the closed chain's inertia is singular: an acceleration needs no torque (links without mass or inertia)"
        ) from None
    # a_o = N_a H^-1 N^T (xi + Q tau, -g_o)
    K = N_a @ scipy.linalg.cho_solve(factor, np.eye(N.shape[1]))
    center = K @ (N_q.T @ xi - N_a.T @ g_o)
    generators = K @ (N_q.T @ (Q * limits))
    return Polytope.zonotope(center, generators, limits)


def min_norm_dynamic_polytope(
    J_u: np.ndarray,
    W: np.ndarray,
    P: np.ndarray,
    Q: np.ndarray,
    xi: np.ndarray,
    M_o: np.ndarray,
    g_o: np.ndarray,
    effort_limits: np.ndarray,
) -> Polytope:
    """The object accelerations the paper's minimum-norm policy reaches within the torque box.

    Same arguments as :func:`dynamic_polytope`. The set is ``{a_o : |Lambda_o a_o + mu_o| <= tau_max}``
    over the a_o with W^T a_o in range(J_u); its :meth:`~Polytope.inputs` are the policy's
    torques tau = Lambda_o a_o + mu_o.

    Returns:
        A polytope, ``empty`` when the torques cannot hold the load still under this policy;
        its centre is the acceleration with the largest margin to every torque limit.
    """
    J_u, W, P, Q, xi, M_o, g_o = _check_dynamic(J_u, W, P, Q, xi, M_o, g_o)
    limits = _check_limits(effort_limits, J_u.shape[1], "effort")
    m = W.shape[0]
    Q_or_none = None if _is_identity(Q) else Q
    U, s, Vt = np.linalg.svd(J_u, full_matrices=False)
    rank = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1e-300)))
    U_r, s_r, Vt_r = U[:, :rank], s[:rank], Vt[:rank]
    J_pinv = (Vt_r.T / s_r) @ U_r.T
    W_pinv = np.linalg.pinv(W)
    Lam = P @ (J_pinv @ W.T) + J_u.T @ (W_pinv @ M_o)
    if Q_or_none is not None:
        Lam = np.linalg.solve(Q, Lam)
    mu = _torque_offset(J_u, W_pinv, Q_or_none, xi, g_o)
    # Object accelerations the end effectors can follow at rest: W^T a_o in range(J_u).
    N = _null_space(W.T - U_r @ (U_r.T @ W.T), m)
    if N.shape[1] and np.linalg.matrix_rank(Lam @ N, tol=_RANK_RTOL * max(np.abs(Lam).max(), 1e-300)) < N.shape[1]:
        raise ModelError("an object acceleration needs no joint torque: the model has moving links without mass")
    F, c, G = Lam, -mu, np.diag(limits)
    if N.shape[1] < m:
        blocked = _null_space(N.T, m).T  # rows: directions the end effectors cannot follow
        F = np.vstack([F, blocked])
        c = np.concatenate([c, np.zeros(len(blocked))])
        G = np.vstack([G, np.zeros((len(blocked), G.shape[1]))])
    return Polytope(F, c, G, limits)


def polytopes(kind: str, **terms: Any) -> Polytope:
    """One capacity polytope by name: ``"kinematic"``, ``"dynamic"`` or ``"dynamic_min_norm"``.

    ``terms`` are the keyword arguments of the matching function (``J_u``, ``W`` and
    ``velocity_limits`` for the kinematic set; ``J_u, W, P, Q, xi, M_o, g_o, effort_limits``
    for the dynamic ones).
    """
    if kind == "kinematic":
        return kinematic_polytope(terms["J_u"], terms["W"], terms["velocity_limits"])
    if kind in ("dynamic", "dynamic_min_norm"):
        fn = dynamic_polytope if kind == "dynamic" else min_norm_dynamic_polytope
        names = POLYTOPE_TERMS[kind]
        missing = [k for k in names if k not in terms]
        if missing:
            raise TaskError(f"the {kind} polytope needs {', '.join(missing)}")
        return fn(*(terms[k] for k in names))
    raise TaskError(f"unknown polytope kind {kind!r}; choose one of {', '.join(KINDS)}")


@dataclass(frozen=True)
class PolytopeIndices:
    """Scalar indices of one kind of polytope over N configurations.

    Attributes:
        volume: (N,), in the task's units to the power m; NaN where unavailable (a 6-D set
            with too many facets to enumerate its vertices, see :attr:`Polytope.volume`).
        isotropy: (N,), in [0, 1]; NaN where unavailable, as ``volume``.
        empty: (N,) bool.
        degenerate: (N,) bool.
        support: max of d . a per direction, (N, k) (k = number of directions; 0 when none).
        radius_along: reach beyond the centre along each unit direction, (N, k).
    """

    volume: np.ndarray
    isotropy: np.ndarray
    empty: np.ndarray
    degenerate: np.ndarray
    support: np.ndarray
    radius_along: np.ndarray


class PolytopeBatch:
    """N capacity polytopes of one kind in an m-dimensional task space (a sweep's chunk).

    A :class:`mobmanip.sets.taskset.TaskSetBatch`: row n is the :class:`Polytope` ``batch[n]``; the
    properties answer for every row at once. Volumes and isotropies are computed on first use.

    Args:
        polytopes: the sets, all of one task dimension.

    Raises:
        TaskError: no sets, or sets of different dimensions.
    """

    def __init__(self, polytopes: Iterable[TaskSet]) -> None:
        self.polytopes = tuple(polytopes)
        dims = {p.dim for p in self.polytopes}
        if len(dims) > 1:
            raise TaskError(f"a polytope batch needs sets of one task dimension, got dimensions {sorted(dims)}")
        self._dim = dims.pop() if dims else 0
        self.empty = np.array([p.empty for p in self.polytopes], dtype=bool)
        self.degenerate = np.array([p.degenerate for p in self.polytopes], dtype=bool)
        self._cache: dict[str, np.ndarray] = {}

    def __len__(self) -> int:
        return len(self.polytopes)

    def __getitem__(self, index: int) -> TaskSet:
        return self.polytopes[index]

    @property
    def dim(self) -> int:
        """Task dimension m."""
        return self._dim

    def _scalar(self, name: str) -> np.ndarray:
        if name not in self._cache:
            out = np.empty(len(self))
            for i, p in enumerate(self.polytopes):
                try:
                    out[i] = getattr(p, name)
                except TaskError:  # a 6-D set whose vertices are impractical to enumerate
                    out[i] = np.nan
            self._cache[name] = out
        return self._cache[name]

    @property
    def volume(self) -> np.ndarray:
        """Volumes, (N,) (0 where empty or degenerate; NaN where unavailable: a 6-D set with
        too many facets to enumerate its vertices)."""
        return self._scalar("volume")

    @property
    def isotropy(self) -> np.ndarray:
        """Isotropies in [0, 1], (N,) (0 where empty or degenerate; NaN where unavailable)."""
        return self._scalar("isotropy")

    def _rows(self, direction) -> np.ndarray:
        d = np.asarray(direction, dtype=float)
        if d.ndim == 1:
            d = np.broadcast_to(d, (len(self), d.shape[0]))
        if d.shape != (len(self), self.dim) or not np.all(np.isfinite(d)):
            raise TaskError(
                f"directions must be finite, ({self.dim},) or ({len(self)}, {self.dim}), "
                f"got shape {np.shape(direction)}"
            )
        return d

    def support(self, direction: ArrayLike) -> np.ndarray:
        """max over set n of d . a, (N,), for one direction (m,) or one per row (N, m); 0 where empty."""
        d = self._rows(direction)
        return np.array([p.support(row) for p, row in zip(self.polytopes, d)])

    def radius_along(self, direction: ArrayLike) -> np.ndarray:
        """How far set n reaches from its centre along the unit direction of d, (N,); 0 where empty."""
        d = self._rows(direction)
        norms = np.linalg.norm(d, axis=1)
        if np.any(norms == 0.0):
            raise TaskError("radius_along needs non-zero directions")
        return np.array([p.radius_along(row) for p, row in zip(self.polytopes, d)])

    def straight_line_reach(self, direction: ArrayLike) -> np.ndarray:
        """The largest s >= 0 with s d / ``|d|`` in set n, (N,): how far along d from rest (the origin)
        (0 where the origin's ray misses the set or it is empty): each row's own
        ``straight_line_reach`` (one linear program per row for a :class:`Polytope`).

        Raises:
            TaskError: a zero direction, or a set that has no straight-line reach.
        """
        d = self._rows(direction)
        if np.any(~d.any(axis=1)):
            raise TaskError("straight_line_reach needs non-zero directions")
        out = np.zeros(len(self))
        for i, (p, row) in enumerate(zip(self.polytopes, d)):
            reach = getattr(p, "straight_line_reach", None)
            if reach is None:
                raise TaskError(f"a {p.kind} has no straight-line reach")
            out[i] = 0.0 if p.empty else reach(row)
        return out

    @property
    def widths(self) -> np.ndarray:
        """Extent along each task axis, support(e_k) + support(-e_k), (N, m) (0 where empty)."""
        if "widths" not in self._cache:
            axes = np.vstack([np.eye(self.dim), -np.eye(self.dim)])
            out = np.zeros((len(self), self.dim))
            for i, p in enumerate(self.polytopes):
                if not p.empty:
                    s = p.supports(axes)
                    out[i] = np.maximum(s[: self.dim] + s[self.dim :], 0.0)
            self._cache["widths"] = out
        return self._cache["widths"]


_STACKED = {"J_u": 3, "W": 3, "P": 3, "Q": 3, "xi": 2, "M_o": 3, "g_o": 2, "velocity_limits": 2, "effort_limits": 2}


#: Terms that change with the configuration (stacked by :func:`stacked_terms`); the others are
#: the same at every configuration of one robot, task and object.
_PER_ROW = ("J_u", "P", "xi")
_SHARED = ("W", "Q", "M_o", "g_o", "velocity_limits", "effort_limits")


def stacked_terms(rows: Sequence[Any]) -> dict[str, np.ndarray]:
    """The keyword terms of :func:`polytope_batch` from per-configuration terms (objects with
    ``J_u, W, P, Q, xi, M_o, g_o, velocity_limits, effort_limits``, e.g.
    :func:`mobmanip.terms.builder.terms_at`'s): ``J_u``, ``P`` and ``xi`` stacked, the others shared.

    Raises:
        TaskError: no rows, or a shared term that differs between rows (a different robot,
            task, object or limits: those rows belong to different batches).
    """
    rows = list(rows)
    if not rows:
        raise TaskError("stacked_terms needs at least one configuration's terms")
    first = rows[0]
    for name in _SHARED:
        for k, row in enumerate(rows[1:], start=1):
            if not np.array_equal(getattr(row, name), getattr(first, name)):
                raise TaskError(
                    f"{name} of row {k} differs from row 0's: one batch shares it (same robot, task, object)"
                )
    out = {name: np.stack([getattr(row, name) for row in rows]) for name in _PER_ROW}
    out.update({name: np.asarray(getattr(first, name)) for name in _SHARED})
    return out


def polytope_batch(kind: str, *, compiled: bool = True, **terms: Any) -> PolytopeBatch | CompiledPolytopeBatch:
    """One kind of polytope for N configurations.

    Args:
        kind: ``"kinematic"``, ``"dynamic"`` or ``"dynamic_min_norm"``.
        compiled: build the sets of all rows at once and compute their indices in one compiled
            pass where :mod:`mobmanip.sets.capacity_batch` covers them (planar tasks; the
            zonotopes of 3-D tasks; the same sets, to round-off); False: one :class:`Polytope`
            per row, as every other case.
        **terms: the arrays of :func:`polytopes`, each stacked with a leading axis N
            (``J_u`` (N, m k, nx), ``xi`` (N, nx), ...); an array without it (``Q`` (nx, nx),
            limits (nx,), ``M_o`` (m, m), ...) is shared by every configuration.

    Raises:
        TaskError: J_u not stacked, an unknown term, or terms with different counts.
    """
    if kind not in KINDS:
        raise TaskError(f"unknown polytope kind {kind!r}; choose one of {', '.join(KINDS)}")
    if "J_u" not in terms:
        raise TaskError("polytope_batch needs J_u stacked as (N, m k, nx)")
    if np.ndim(terms["J_u"]) != 3:
        raise TaskError(f"J_u must be stacked as (N, m k, nx), got shape {np.shape(terms['J_u'])}")
    count = np.shape(terms["J_u"])[0]
    rows = []
    for name, value in terms.items():
        stacked = _STACKED.get(name)
        if stacked is None:
            raise TaskError(f"unknown term {name!r}; expected some of {', '.join(_STACKED)}")
        value = np.asarray(value, dtype=float)
        if value.ndim == stacked and value.shape[0] != count:
            raise TaskError(f"{name} has {value.shape[0]} rows but J_u has {count}")
        rows.append((name, value, value.ndim == stacked))

    def row(i: int) -> Polytope:
        return polytopes(kind, **{name: (v[i] if per_row else v) for name, v, per_row in rows})

    if compiled and "W" in terms and np.ndim(terms["W"]) >= 2 and np.shape(terms["W"])[-2] in (2, 3):
        from .capacity_batch import compiled_polytope_batch

        fast = compiled_polytope_batch(kind, row, **{name: v for name, v, _ in rows})
        if fast is not None:
            return fast
    return PolytopeBatch(row(i) for i in range(count))


def polytope_indices(kind: str, directions: ArrayLike | None = None, **terms: Any) -> PolytopeIndices:
    """Volume, isotropy, flags and directional capacity of one kind of polytope for N configurations.

    Args:
        kind: ``"kinematic"``, ``"dynamic"`` or ``"dynamic_min_norm"``.
        directions: task directions (k, m) for ``support`` and ``radius_along``; optional.
        **terms: as :func:`polytope_batch`.
    """
    batch = polytope_batch(kind, **terms)
    D = None if directions is None else np.atleast_2d(np.asarray(directions, dtype=float))
    k = 0 if D is None else len(D)
    support, radius = np.zeros((len(batch), k)), np.zeros((len(batch), k))
    for j in range(k):
        support[:, j] = batch.support(D[j])  # type: ignore[index]
        radius[:, j] = batch.radius_along(D[j])  # type: ignore[index]
    return PolytopeIndices(batch.volume, batch.isotropy, batch.empty, batch.degenerate, support, radius)


# ---------------------------------------------------------------------------------------------
# Input checks


def _array(x, name: str, shape: tuple) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != shape:
        raise TaskError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ModelError(f"{name} has a non-finite entry at {np.argwhere(~np.isfinite(a))[0].tolist()}")
    return a


def _check_jacobian_grasp(J_u, W) -> tuple[np.ndarray, np.ndarray]:
    J_u = np.asarray(J_u, dtype=float)
    if J_u.ndim != 2:
        raise TaskError(f"J_u must be a matrix (m k, nx), got shape {J_u.shape}")
    W = np.asarray(W, dtype=float)
    if W.ndim != 2 or W.shape[1] != J_u.shape[0]:
        raise TaskError(f"W must have shape (m, {J_u.shape[0]}) to match J_u's rows, got {W.shape}")
    J_u, W = _array(J_u, "J_u", J_u.shape), _array(W, "W", W.shape)
    s = np.sqrt(np.maximum(np.linalg.eigvalsh(W @ W.T), 0.0))[::-1]  # singular values of W (m x m problem)
    if W.shape[0] > W.shape[1] or s[-1] <= 1e-7 * max(s[0], 1e-300):
        raise TaskError(f"grasp matrix W {W.shape} must have full row rank (singular values {s.tolist()})")
    return J_u, W


def _check_dynamic(J_u, W, P, Q, xi, M_o, g_o):
    J_u, W = _check_jacobian_grasp(J_u, W)
    m, nx = W.shape[0], J_u.shape[1]
    P = _array(P, "P", (nx, nx))
    Q = _array(Q, "Q", (nx, nx))
    xi = _array(xi, "xi", (nx,))
    M_o = _array(M_o, "M_o", (m, m))
    g_o = _array(g_o, "g_o", (m,))
    if not _is_identity(Q) and np.linalg.matrix_rank(Q) < nx:
        raise ModelError("the input matrix Q is singular: some reduced velocity has no actuator")
    return J_u, W, P, Q, xi, M_o, g_o


def _check_limits(values, n: int, kind: str) -> np.ndarray:
    limits = np.asarray(values, dtype=float)
    if limits.shape != (n,):
        raise TaskError(f"{kind} limits must have shape ({n},), got {limits.shape}")
    for i, value in enumerate(limits):
        if not np.isfinite(value) or value < 0.0:
            raise LimitError(f"reduced velocity {i}", kind, float(value))
    return limits
