"""The capacity polytope as a task-space set: sections of zonotopes, queried exactly.

Every capacity polytope of this toolkit has the form

    K = {a in R^m : F a in c + G [-1, 1]^n}          (F injective, (p, m); G (p, n))

with y in the box the joint quantities normalised by their limits: the preimage of a zonotope
under an injective linear map, i.e. a zonotope cut by a subspace. The kinematic set of several
hands holding one object is one (F = W^T), the exact dynamic set is a plain zonotope (F = I),
and the paper's minimum-norm dynamic set is one with G = I (the torque box itself). The form
is closed under projection on task coordinates (quotient by the range of the dropped columns
of F) and under slicing (the fixed coordinates move into c), so these stay exact as well.

Queries and how they are answered:

- halfspaces ``A a <= b``: the zonotope's facets (:mod:`mobmanip.sets.zonotope`) pulled back by F,
  plus the equalities of the directions in which the zonotope is flat; irredundant for m <= 3, and
  no halfspace listed twice in any dimension (rows that several generator subsets give are one);
- vertices and faces (m <= 3): one Qhull call on the polar set (:mod:`mobmanip.sets.hull`);
  a zonotope's vertices are then recomputed exactly as c + G sign(G^T d) from their normals
  (:mod:`mobmanip.sets.polytope_vertices`, which also enumerates vertices above 3 dimensions);
- support: sum_j ``|g_j . d|`` for a zonotope, the vertices for m <= 3, otherwise a linear program
  on HiGHS kept warm between directions;
- membership: the halfspaces; ``inputs`` gives joint values (within their limits) reaching
  given points.

:attr:`Polytope.center` is the point reached with the least normalised effort, the minimiser of
min {||y||_inf : F a = c + G y}: the origin for a velocity set, the acceleration at zero torque
for the exact dynamic set (both centres of symmetry), and for a set without symmetry (the
minimum-norm dynamic set under gravity) the acceleration with the largest margin to every torque
limit. The set is empty exactly when that least effort exceeds 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from ..errors import TaskError
from ..support.tolerances import RANK_RTOL
from . import zonotope
from .hull import enumerate_hull
from .linear_programs import LinearProgram
from .polytope_vertices import distinct_rows, exact_vertices, halfspace_vertices, volume_from_vertices
from .taskset import TaskSet, check_membership_points, membership

_RANK_RTOL = RANK_RTOL
_EMPTY_TOL = 1e-9  # least effort above 1 + this: empty; above 1 - this: no interior


class Halfspaced(Protocol):
    """A set that gives its halfspaces (A a <= b), or raises TaskError where it cannot."""

    @property
    def halfspaces(self) -> tuple[np.ndarray, np.ndarray]: ...


def halfspaces_json(task_set: Halfspaced) -> dict:
    """A set's halfspaces for its JSON: ``{"halfspaces": {"A", "b"}}`` (A a <= b), or
    ``{"halfspaces": None, "halfspaces_omitted": why}`` when it cannot give them."""
    try:
        A, b = task_set.halfspaces
    except TaskError as error:
        return {"halfspaces": None, "halfspaces_omitted": str(error)}
    return {"halfspaces": {"A": A.tolist(), "b": b.tolist()}}


class Polytope(TaskSet):
    """The set {a : F a in c + G [-1, 1]^n} in an m-dimensional task space.

    Args:
        F: injective map from the task space, (p, m).
        c: centre of the zonotope, (p,).
        G: generators of the zonotope, columns, (p, n).
        input_limits: the limit of each box coordinate in physical units (joint speeds in rad/s
            or m/s, torques in N m or N), (n,); :meth:`inputs` returns y scaled by them.
            Defaults to ones.

    Raises:
        TaskError: shapes that do not fit, non-finite entries, or F not injective (the set
            would be unbounded).
    """

    kind = "polytope"

    def __init__(
        self,
        F: ArrayLike,
        c: ArrayLike,
        G: ArrayLike,
        input_limits: ArrayLike | None = None,
        *,
        _center: ArrayLike | None = None,
        _effort: ArrayLike | None = None,
    ) -> None:
        F, c, G = (np.array(x, dtype=float) for x in (F, c, G))
        if F.ndim != 2 or G.ndim != 2 or c.shape != (F.shape[0],) or G.shape[0] != F.shape[0]:
            raise TaskError(f"polytope needs shapes F (p, m), c (p,), G (p, n); got {F.shape}, {c.shape}, {G.shape}")
        for name, x in (("F", F), ("c", c), ("G", G)):
            if not np.all(np.isfinite(x)):
                raise TaskError(f"polytope {name} has a non-finite entry at {np.argwhere(~np.isfinite(x))[0].tolist()}")
        n = G.shape[1]
        limits = np.ones(n) if input_limits is None else np.array(input_limits, dtype=float).reshape(-1)
        if limits.shape != (n,) or not np.all(np.isfinite(limits)) or np.any(limits < 0):
            raise TaskError(f"input_limits must be {n} finite non-negative numbers, got {input_limits!r}")
        p, m = F.shape
        if p == m and np.array_equal(F, np.eye(m)):  # already a zonotope (the usual dynamic case)
            Uf, sf, Vtf = F, np.ones(m), F
        else:
            Uf, sf, Vtf = np.linalg.svd(F, full_matrices=False)
        if m and (sf.size < m or sf[-1] <= _RANK_RTOL * max(sf[0], 1e-300)):
            raise TaskError(f"polytope map F {F.shape} is not injective (singular values {sf.tolist()})")
        if p == m and m:  # a plain zonotope: a = F^-1 c + F^-1 G y
            if not np.array_equal(F, np.eye(m)):
                F_inv = (Vtf.T / sf) @ Uf.T
                c, G, F = F_inv @ c, F_inv @ G, np.eye(m)
            if _center is None:
                _center, _effort = c.copy(), 0.0
        self._F, self._c, self._G, self._limits = F, c, G, limits
        self.is_zonotope = bool(p == m and np.array_equal(F, np.eye(m)))
        self._F_min_sv = 1.0 if self.is_zonotope else float(sf[-1]) if m else 0.0
        self._cache: dict = {}
        for x in (F, c, G, limits):
            x.setflags(write=False)
        self._setup_flat()
        self._setup_center(_center, _effort)

    # ------------------------------------------------------------------------------------------
    # Construction

    @classmethod
    def zonotope(cls, center: ArrayLike, generators: ArrayLike, input_limits: ArrayLike | None = None) -> Polytope:
        """The zonotope ``{center + G y : |y_i| <= 1}``, G (m, n)."""
        center = np.asarray(center, dtype=float).reshape(-1)
        return cls(np.eye(center.shape[0]), center, generators, input_limits)

    def _setup_flat(self):
        """Split off the directions in which the zonotope is flat: equalities on a."""
        F, c, G = self._F, self._c, self._G
        p, m = F.shape
        U, s, _ = np.linalg.svd(G, full_matrices=True)
        r = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1e-300))) if s.size else 0
        self._Ur, self._scale = U[:, :r], float(s[0]) if r else 0.0
        size = self._scale / max(self._F_min_sv, 1e-300) if m else 0.0
        self._size = max(size, float(np.linalg.norm(c)), 1e-300)
        if r == p:  # G spans R^p (the usual case): no equalities, the set is full-dimensional
            self._eq_A, self._eq_b = np.zeros((0, m)), np.zeros(0)
            self._consistent, self._N = True, np.eye(m)
            return
        E, f = U[:, r:].T @ F, U[:, r:].T @ c
        Ue, se, Vte = np.linalg.svd(E, full_matrices=True) if E.size else (np.eye(0), np.zeros(0), np.eye(m))
        q = int(np.sum(se > _RANK_RTOL * max(float(np.abs(F).max(initial=0.0)), 1e-300)))
        proj = Ue.T @ f
        self._eq_A = Vte[:q].copy()  # orthonormal rows: eq_A a = eq_b
        self._eq_b = proj[:q] / se[:q]
        self._consistent = bool(np.linalg.norm(proj[q:]) <= 1e-9 * max(float(np.linalg.norm(c)), self._scale, 1e-300))
        self._N = Vte[q:].T.copy()  # directions of the affine hull, (m, k)

    def _setup_center(self, center, effort):
        m = self.dim
        self.symmetric = False
        if center is None and self._consistent and not self._c.any():  # a velocity set: the origin
            center, effort = np.zeros(m), 0.0
        elif center is None and self._consistent:
            a = np.linalg.lstsq(self._F, self._c, rcond=None)[0]
            if np.linalg.norm(self._F @ a - self._c) <= 1e-12 * max(
                float(np.linalg.norm(self._c)), self._scale, 1e-300
            ):
                center, effort = a, 0.0
        if effort == 0.0:
            self.symmetric = True
        elif center is None:
            center, effort = self._least_effort()
        if center is None or effort > 1.0 + _EMPTY_TOL:
            self.empty = True
            self.center = np.zeros(m) if center is None else np.asarray(center, dtype=float)
        else:
            self.empty = False
            self.center = np.asarray(center, dtype=float)
        self.least_effort = math.inf if center is None else float(effort)
        self.degenerate = bool(self.empty or self._N.shape[1] < m or self.least_effort >= 1.0 - _EMPTY_TOL)
        self.center.setflags(write=False)

    def _least_effort(self) -> tuple[np.ndarray | None, float]:
        """argmin over a of min {||y||_inf : F a = c + G y}: one linear program over (a, y, t)."""
        F, c, G = self._F, self._c, self._G
        (p, m), n = F.shape, G.shape[1]
        A = np.zeros((p + 2 * n, m + n + 1))
        A[:p, :m], A[:p, m : m + n] = F, -G
        A[p : p + n, m : m + n], A[p + n :, m : m + n] = np.eye(n), -np.eye(n)
        A[p:, -1] = -1.0
        lo = np.r_[c, np.full(2 * n, -np.inf)]
        hi = np.r_[c, np.zeros(2 * n)]
        col_lo, col_hi = np.r_[np.full(m + n, -np.inf), 0.0], np.full(m + n + 1, np.inf)
        cost = np.zeros(m + n + 1)
        cost[-1] = 1.0
        result = LinearProgram(A, lo, hi, col_lo, col_hi).solve(cost, maximize=False)
        if result is None:
            return None, math.inf
        return result[1][:m], max(result[0], 0.0)

    # ------------------------------------------------------------------------------------------
    # The TaskSet interface

    @property
    def dim(self) -> int:
        return int(self._F.shape[1])

    @property
    def input_limits(self) -> np.ndarray:
        """The physical limit of each box coordinate, (n,)."""
        return self._limits

    @property
    def generators(self) -> np.ndarray:
        """The zonotope's generators G (m, n), when :attr:`is_zonotope` (then K = center + G box)."""
        if not self.is_zonotope:
            raise TaskError("this polytope is a section of a zonotope, not a zonotope: it has no generators")
        return self._G

    def support(self, direction: ArrayLike) -> float:
        return float(self.supports(np.asarray(direction, dtype=float).reshape(1, -1))[0])

    def supports(self, directions: ArrayLike) -> np.ndarray:
        """max over the set of d . a for each row d of ``directions`` (k, m); zeros when empty."""
        D = self._directions(directions)
        if self.empty:
            return np.zeros(len(D))
        if self.is_zonotope:
            return D @ self._c + np.abs(D @ self._G).sum(axis=1)
        if self.dim <= 3:
            try:
                return (D @ self.vertices.T).max(axis=1)
            except TaskError:  # too many candidate facets to enumerate (e.g. a team of robots)
                pass
        return np.array([self._support_lp(d) for d in D])

    def ray_radius(self, direction: ArrayLike) -> float:
        """How far the set extends from its centre exactly along d: the largest t >= 0 with
        ``centre + t d / |d|`` in the set (one linear program; 0 when empty or flat across d)."""
        u = self._unit_direction(direction, "ray_radius")
        if self.empty:
            return 0.0
        return self._farthest_along(u, self._c - self._F @ self.center)  # from the centre

    def straight_line_reach(self, direction: ArrayLike) -> float:
        """The largest s >= 0 with ``s d / |d|`` in the set: how far along d from rest (the origin),
        exactly along d (0 when no point of the ray is in the set, or it is empty). A full-dimensional
        set of up to 3 dimensions intersects the ray with its facet inequalities; any other set
        solves one linear program."""
        u = self._unit_direction(direction, "straight_line_reach")
        if self.empty:
            return 0.0
        if self.dim <= 3 and not len(self._eq_A):
            try:
                A, b0, h = self._inequalities()
            except TaskError:  # too many candidate facets: the program below
                pass
            else:
                return _ray_in_halfspaces(A, b0 + h, u)
        return self._farthest_along(u, self._c)  # from the origin

    def _unit_direction(self, direction: ArrayLike, what: str) -> np.ndarray:
        """``direction`` scaled to unit length; a TaskError naming ``what`` when it is zero."""
        d = self._directions(np.asarray(direction, dtype=float).reshape(1, -1))[0]
        norm = float(np.linalg.norm(d))
        if norm == 0.0:
            raise TaskError(f"{what} needs a non-zero direction")
        return d / norm

    def _farthest_along(self, u: np.ndarray, rhs: np.ndarray) -> float:
        """The largest t >= 0 with ``F u t - G y = rhs`` for some ``|y| <= 1`` (one linear program;
        0 when there is none): how far the set reaches along the unit u from the point ``rhs``
        stands for."""
        from scipy.optimize import linprog

        n = self._G.shape[1]
        A = np.hstack([(self._F @ u)[:, None], -self._G])  # columns (t, y)
        result = linprog(
            np.r_[-1.0, np.zeros(n)], A_eq=A, b_eq=rhs, bounds=[(0.0, None)] + [(-1.0, 1.0)] * n, method="highs"
        )
        return float(result.x[0]) if result.status == 0 else 0.0

    def radius_along(self, direction: ArrayLike) -> float:
        d = self._unit_direction(direction, "radius_along")
        return 0.0 if self.empty else max(self.support(d) - float(d @ self.center), 0.0)

    def contains(self, points: ArrayLike, tol: float = 1e-9) -> bool | np.ndarray:
        """Whether points are reached with every ``|y_i| <= 1 + tol``: a ``bool`` for one point
        (m,), a bool array (n,) for points (n, m).

        That is: every joint within (1 + tol) times its own limit; the equalities (directions in
        which the set is flat) hold to ``tol`` times the set's size.

        Raises:
            SetQueryError: any other shape (named), or a non-finite coordinate.
        """
        P, single = check_membership_points(points, self.dim)
        if self.empty:
            return membership(np.zeros(len(P), dtype=bool), single)
        try:
            A, b0, h = self._inequalities()
        except TaskError:  # too many candidate facets: one feasibility program per point
            return membership(np.array([self._feasible_y(p, 1.0 + tol) is not None for p in P], dtype=bool), single)
        inside = np.all(P @ A.T <= b0 + (1.0 + tol) * h + 1e-12 * self._size, axis=1)
        if len(self._eq_A):
            inside &= np.all(np.abs(P @ self._eq_A.T - self._eq_b) <= tol * self._size + 1e-12 * self._size, axis=1)
        return membership(inside, single)

    def project(self, dims: Sequence[int] = (0, 1)) -> Polytope:
        """The shadow on the task coordinates ``dims``: {a_D : some a_R completes a point of the set}.

        Exact: with F = [F_D F_R], F_D a_D + F_R a_R in Z for some a_R iff Q^T F_D a_D lies in
        Q^T Z, Q an orthonormal basis of range(F_R)'s complement. The same joint values reach it.
        """
        D, R = self._split(dims)
        F_R = self._F[:, R]
        U, s, _ = np.linalg.svd(F_R, full_matrices=True)
        rank = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1e-300)))
        Qp = U[:, rank:]
        return self._derived(Qp.T @ self._F[:, D], Qp.T @ self._c, Qp.T @ self._G, D)

    def slice(self, dims: Sequence[int] = (0, 1)) -> Polytope:
        """The cut through :attr:`center` in the coordinates ``dims`` (the others at the centre's)."""
        D, R = self._split(dims)
        return self._derived(self._F[:, D], self._c - self._F[:, R] @ self.center[R], self._G, D)

    def _derived(self, F, c, G, D) -> Polytope:
        # The centre is still a least-effort point of the projection or slice, with the same effort.
        effort = 0.0 if self.symmetric else self.least_effort
        center = None if (self.empty and not np.isfinite(effort)) else self.center[D]
        return Polytope(F, c, G, self._limits, _center=center, _effort=effort)

    @property
    def volume(self) -> float:
        """m-dimensional volume (0 when empty or degenerate)."""
        if "volume" not in self._cache:
            self._cache["volume"] = 0.0 if self.degenerate else self._volume()
        return self._cache["volume"]

    @property
    def isotropy(self) -> float:
        """Smallest over largest reach from the centre, min_d h(d) / max_d h(d) over unit d
        with h(d) = support(d) - d . center: the distance from the centre to the nearest facet over
        the distance to the farthest vertex. 0 when empty or degenerate."""
        if self.degenerate:
            return 0.0
        far = self.circumradius
        return self.inradius / far if far > 0.0 else 0.0

    @property
    def inradius(self) -> float:
        """Distance from :attr:`center` to the boundary (0 when empty or degenerate)."""
        if self.degenerate:
            return 0.0
        A, b0, h = self._inequalities()
        return float(max(np.min(b0 + h - A @ self.center), 0.0))

    @property
    def circumradius(self) -> float:
        """Largest distance from :attr:`center` to a point of the set (0 when empty)."""
        if self.empty:
            return 0.0
        if "circumradius" not in self._cache:
            far = zonotope.max_norm(self._G) if self.is_zonotope and self.dim > 3 else None
            if far is None:
                far = float(np.max(np.linalg.norm(self._all_vertices() - self.center, axis=1), initial=0.0))
            self._cache["circumradius"] = far
        return self._cache["circumradius"]

    # ------------------------------------------------------------------------------------------
    # Representations

    @property
    def halfspaces(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, b) with the set = {a : A a <= b}, unit rows; equalities appear as two opposite rows.

        For m <= 3 only facets are listed; for larger m every pulled-back facet of the
        zonotope is, and some rows may be redundant. No halfspace is listed twice: rows whose unit
        normals agree to :data:`~mobmanip.sets.polytope_vertices.DUPLICATE_RTOL` in every coordinate
        and offsets to that times the set's size are one, kept once
        (:func:`~mobmanip.sets.polytope_vertices.distinct_rows`).
        """
        A, b0, h = self._inequalities()
        if self.dim <= 3 and not self.empty:
            rows = self._vrep()["facet_rows"]
            rows = rows[np.sort(np.unique(rows, return_index=True)[1])]  # faces in one plane share a row
            A, b0, h = A[rows], b0[rows], h[rows]
        eq_A, eq_b = self._eq_A, self._eq_b
        A, b = np.vstack([A, eq_A, -eq_A]), np.concatenate([b0 + h, eq_b, -eq_b])
        unique, _ = distinct_rows(A, b, self._size)  # e.g. a facet row that repeats an equality's side
        return A[unique], b[unique]

    @property
    def vertices(self) -> np.ndarray:
        """Vertices, (v, m) for m <= 3 (counter-clockwise for m = 2); (0, m) when empty."""
        self._low_dim("vertices")
        return np.zeros((0, self.dim)) if self.empty else self._vrep()["vertices"]

    @property
    def faces(self) -> list[np.ndarray]:
        """Facets as vertex indices (m <= 3): polygons counter-clockwise seen from outside for
        m = 3, edges in boundary order for m = 2; for a flat set, the faces within its plane."""
        self._low_dim("faces")
        return [] if self.empty else self._vrep()["faces"]

    @property
    def triangles(self) -> np.ndarray:
        """The boundary of a 3-D polytope as triangles, (t, 3), outward-oriented (a flat
        polygon is one fan); (0, 3) otherwise."""
        if self.dim != 3 or self.empty or self._affine_dim < 2:
            return np.zeros((0, 3), dtype=int)
        faces = self.faces if self._affine_dim == 3 else [np.arange(len(self.vertices))]
        tris = [np.stack([np.full(len(f) - 2, f[0]), f[1:-1], f[2:]], axis=1) for f in faces if len(f) >= 3]
        return np.vstack(tris) if tris else np.zeros((0, 3), dtype=int)

    @property
    def vertex_inputs(self) -> np.ndarray:
        """Joint values within their limits that reach each vertex, (v, n) in physical units."""
        self._low_dim("vertex_inputs")
        if self.empty:
            return np.zeros((0, self._G.shape[1]))
        rep = self._vrep()
        Y = rep.get("Y")
        if Y is None:
            Y = np.full((len(rep["vertices"]), self._G.shape[1]), np.nan)
        missing = np.flatnonzero(np.isnan(Y).any(axis=1))
        if len(missing):
            Y = Y.copy()
            for i in missing:
                Y[i] = self._vertex_y(rep["vertices"][i])
            rep["Y"] = Y
        return rep["Y"] * self._limits

    def inputs(self, points: ArrayLike, tol: float = 1e-9) -> np.ndarray:
        """Joint values (``|y_i| <= 1 + tol`` of their limits) reaching each point, (k, n) in physical units.

        Raises:
            TaskError: a point is not in the set.
        """
        P = np.atleast_2d(np.asarray(points, dtype=float))
        out = []
        for p in P:
            y = None if self.empty else self._feasible_y(p, 1.0 + tol)
            if y is None:
                raise TaskError(
                    f"point {p.tolist()} is outside the polytope: no joint values within the limits reach it"
                )
            out.append(y)
        return np.array(out).reshape(len(P), -1) * self._limits

    @property
    def chebyshev_center(self) -> np.ndarray:
        """Centre of the largest ball inside the set (within its plane when flat), (m,)."""
        return self._chebyshev()[0]

    @property
    def chebyshev_radius(self) -> float:
        """Radius of the largest ball inside the set (0 when empty or flat)."""
        return 0.0 if self.degenerate else self._chebyshev()[1]

    def to_dict(self) -> dict:
        """JSON-ready: ``halfspaces`` {"A", "b"} with A a <= b, ``vertices`` and ``faces`` for m <= 3."""
        out = {
            "kind": self.kind,
            "dim": self.dim,
            "empty": self.empty,
            "degenerate": self.degenerate,
            "center": self.center.tolist(),
            "least_effort": self.least_effort if np.isfinite(self.least_effort) else None,
        }
        out.update(halfspaces_json(self))
        if self.dim <= 3:
            out["vertices"] = self.vertices.tolist()
            out["faces"] = [f.tolist() for f in self.faces]
        if self.is_zonotope:
            out["generators"] = self._G.tolist()
        try:
            out["volume"] = self.volume
            out["isotropy"] = self.isotropy
            out["chebyshev"] = {"center": self.chebyshev_center.tolist(), "radius": self.chebyshev_radius}
        except TaskError:  # no halfspaces to measure from (see "halfspaces_omitted")
            out["volume"] = out["isotropy"] = out["chebyshev"] = None
        return out

    def __repr__(self) -> str:
        state = "empty" if self.empty else ("degenerate" if self.degenerate else "full")
        what = "zonotope" if self.is_zonotope else "zonotope section"
        return f"Polytope({what}, dim={self.dim}, inputs={self._G.shape[1]}, {state})"

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_cache"] = {k: v for k, v in self._cache.items() if k != "program"}
        return state

    # ------------------------------------------------------------------------------------------
    # Internals

    @property
    def _affine_dim(self) -> int:
        return -1 if self.empty else (0 if self.least_effort >= 1.0 - _EMPTY_TOL else self._N.shape[1])

    def _low_dim(self, what: str):
        if self.dim > 3:
            raise TaskError(f"{what} are given for task dimensions up to 3, not {self.dim}: project or slice first")

    def _split(self, dims) -> tuple[list[int], list[int]]:
        D = [int(d) for d in np.atleast_1d(dims)]
        if len(set(D)) != len(D) or not D or any(d < 0 or d >= self.dim for d in D):
            raise TaskError(f"dims must be distinct task coordinates in 0..{self.dim - 1}, got {list(dims)!r}")
        return D, [i for i in range(self.dim) if i not in D]

    def _directions(self, directions) -> np.ndarray:
        D = np.atleast_2d(np.asarray(directions, dtype=float))
        if D.ndim != 2 or D.shape[1] != self.dim or not np.all(np.isfinite(D)):
            raise TaskError(f"directions must be finite with {self.dim} coordinates, got shape {np.shape(directions)}")
        return D

    def _inequalities(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit rows A, offsets b0 and generator parts h with K = {a : A a <= b0 + h} (and the
        equalities); scaling the box by (1 + t) scales h alone."""
        if "ineq" not in self._cache:
            F, c, G, Ur = self._F, self._c, self._G, self._Ur
            r = Ur.shape[1]
            if r == 0:
                rows = np.zeros((0, self._F.shape[0]))
                h = np.zeros(0)
            else:
                Gr = Ur.T @ G
                nu = zonotope.facet_normals(Gr)
                h = np.abs(nu @ Gr).sum(axis=1)
                rows = nu @ Ur.T  # zonotope normals in R^p
                rows, h = np.vstack([rows, -rows]), np.concatenate([h, h])
            A, b0 = rows @ F, rows @ c
            length = np.linalg.norm(A, axis=1)
            keep = length > 1e-12 * max(float(length.max(initial=0.0)), 1e-300)
            length = length[keep]
            A, b0, h, rows = A[keep] / length[:, None], b0[keep] / length, h[keep] / length, rows[keep]
            # Several generator subsets give one facet (coplanar generators; zonotope facets that F
            # pulls back onto one task halfspace): one row each (the rule of distinct_rows).
            unique, _ = distinct_rows(A, np.c_[b0, h], self._size)
            self._cache["ineq"] = (A[unique], b0[unique], h[unique])
            self._cache["z_normals"] = rows[unique]
        return self._cache["ineq"]

    def _interior_point(self) -> np.ndarray:
        if self.least_effort <= 0.5:
            return self.center
        return self._chebyshev()[0]

    def _vrep(self) -> dict:
        """Vertices, faces and facet rows (m <= 3, not empty)."""
        if "vrep" in self._cache:
            return self._cache["vrep"]
        k = self._affine_dim
        if self.is_zonotope and k == self.dim and "ineq" not in self._cache and self._fast_zonotope():
            return self._cache["vrep"]
        A, b0, h = self._inequalities()
        if k <= 0:
            rep = {"vertices": self.center[None, :].copy(), "faces": [], "facet_rows": np.zeros(0, dtype=int)}
            rep["hull"] = None
        else:
            p0 = self._interior_point()
            s = b0 + h - A @ p0
            hull = enumerate_hull(A @ self._N, s)
            V = p0 + hull.vertices @ self._N.T
            rep = {"vertices": V, "faces": hull.faces, "facet_rows": hull.facet_rows, "hull": hull}
            if k > 2:  # a polygon's vertex is two facet lines meeting, accurate as it stands
                self._exact_vertices(rep, hull)
        rep["vertices"].setflags(write=False)  # type: ignore[union-attr]
        self._cache["vrep"] = rep
        return rep

    def _fast_zonotope(self) -> bool:
        """Vertices, faces and halfspaces of a 2-D or 3-D zonotope from its generators alone."""
        fast = zonotope.low_dim_faces(self._c, self._G)
        if fast is None:
            return False
        normals, offsets, widths = fast["normals"], fast["offsets"], fast["widths"]
        unique, row_of = distinct_rows(normals, np.c_[offsets, widths], self._size)  # one row per facet plane
        self._cache["ineq"] = (normals[unique], offsets[unique], widths[unique])
        self._cache["z_normals"] = normals[unique]  # F = I: the zonotope's normals are the set's
        vertices = fast["vertices"]
        vertices.setflags(write=False)
        self._cache["vrep"] = {
            "vertices": vertices,
            "faces": fast["faces"],
            "facet_rows": row_of,  # each face's row: faces in one plane share it
            "hull": None,
            "Y": fast["Y"],
        }
        return True

    def _exact_vertices(self, rep, hull):
        """Each vertex and its joint values recomputed from the zonotope face it lies on
        (:func:`mobmanip.sets.polytope_vertices.exact_vertices`)."""
        d = hull.normal_sums(self._cache["z_normals"][hull.facet_rows])
        rep["vertices"], rep["Y"] = exact_vertices(self._F, self._c, self._G, rep["vertices"], d, self._size)

    def _vertex_y(self, v) -> np.ndarray:
        """Box coordinates reaching the point v (a linear program, polished)."""
        y = self._feasible_y(v, 1.0)
        if y is None:
            y = self._feasible_y(v, 1.0 + 1e-9)
        if y is None:
            raise TaskError(f"vertex {v.tolist()} could not be reached within the limits (numerical failure)")
        return np.clip(y, -1.0, 1.0)

    def _program(self) -> LinearProgram:
        """max d . a subject to F a - G y = c, |y| <= 1 (columns a, then y); kept warm."""
        if "program" not in self._cache:
            m, n = self.dim, self._G.shape[1]
            A = np.hstack([self._F, -self._G])
            bounds = np.r_[np.full(m, np.inf), np.ones(n)]
            self._cache["program"] = LinearProgram(A, self._c, self._c, -bounds, bounds)
        return self._cache["program"]

    def _support_lp(self, d) -> float:
        m, n = self.dim, self._G.shape[1]
        bounds = np.r_[np.full(m, np.inf), np.ones(n)]
        result = self._program().solve(np.r_[d, np.zeros(n)], True, -bounds, bounds)
        return 0.0 if result is None else result[0]

    def _feasible_y(self, p, box: float) -> np.ndarray | None:
        """Some y with F p = c + G y and |y| <= box, polished: None when there is none."""
        m, n = self.dim, self._G.shape[1]
        if p.shape != (m,):
            raise TaskError(f"a point must have {m} coordinates, got shape {p.shape}")
        result = self._program().solve(np.zeros(m + n), True, np.r_[p, np.full(n, -box)], np.r_[p, np.full(n, box)])
        if result is None:
            return None
        y = result[1][m:]
        target = self._F @ p - self._c
        at_bound = np.abs(y) >= box * (1.0 - 1e-9)
        polished = np.where(at_bound, np.sign(y) * box, 0.0)
        if (~at_bound).any():
            rest = target - self._G[:, at_bound] @ polished[at_bound]
            polished[~at_bound] = np.linalg.lstsq(self._G[:, ~at_bound], rest, rcond=None)[0]
        if (
            np.all(np.abs(polished) <= box + 1e-12)
            and np.linalg.norm(self._G @ polished - target) <= np.linalg.norm(self._G @ y - target) + 1e-12 * self._size
        ):
            return polished
        return y

    def _chebyshev(self) -> tuple[np.ndarray, float]:
        if "chebyshev" not in self._cache:
            if self.empty or self._affine_dim <= 0:
                self._cache["chebyshev"] = (self.center, 0.0)
            elif self.symmetric:
                A, b0, h = self._inequalities()
                self._cache["chebyshev"] = (self.center, float(max(np.min(b0 + h - A @ self.center), 0.0)))
            else:
                self._cache["chebyshev"] = self._chebyshev_lp()
        return self._cache["chebyshev"]

    def _chebyshev_lp(self) -> tuple[np.ndarray, float]:
        """max r subject to A (center + N u) + r ||A_i N|| <= b, in the set's own plane."""
        A, b0, h = self._inequalities()
        N = self._N
        An = A @ N
        k = N.shape[1]
        M = np.hstack([An, np.linalg.norm(An, axis=1, keepdims=True)])
        rhs = b0 + h - A @ self.center
        cost = np.zeros(k + 1)
        cost[-1] = 1.0
        program = LinearProgram(M, np.full(len(rhs), -np.inf), rhs, np.r_[np.full(k, -np.inf), 0.0], np.inf)
        result = program.solve(cost, maximize=True)
        if result is None:
            return self.center, 0.0
        return self.center + N @ result[1][:k], float(result[0])

    def _all_vertices(self) -> np.ndarray:
        """Every vertex (for m > 3 from Qhull's halfspace intersection in the set's plane)."""
        if self.dim <= 3:
            return self.vertices
        if "all_vertices" not in self._cache:
            A, b0, h = self._inequalities()
            if self._affine_dim <= 0:
                V = self.center[None, :]
            else:
                p0 = self._interior_point()
                U = halfspace_vertices(A @ self._N, b0 + h - A @ p0, self.dim)
                V = p0 + U @ self._N.T
            self._cache["all_vertices"] = V
        return self._cache["all_vertices"]

    def _volume(self) -> float:
        m = self.dim
        if self.is_zonotope and zonotope.subset_count(self._G.shape[1], m) <= zonotope.MAX_SUBSETS:
            return zonotope.volume(self._G)
        if m <= 3:
            return volume_from_vertices(self.vertices, self.triangles, self.center)
        return volume_from_vertices(self._all_vertices(), np.zeros((0, 3), dtype=int), self.center)


def _ray_in_halfspaces(A: np.ndarray, b: np.ndarray, u: np.ndarray) -> float:
    """The largest s >= 0 with A (s u) <= b, or 0 when there is none: the ray leaves the set at
    the nearest row it moves towards and must have entered it past the farthest it moves away from."""
    au = A @ u
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = b / au
    hi = float(np.min(ratio[au > 0.0], initial=np.inf))
    lo = max(float(np.max(ratio[au < 0.0], initial=-np.inf)), 0.0)
    if np.any((au == 0.0) & (b < 0.0)) or hi < lo or not np.isfinite(hi):
        return 0.0
    return hi
