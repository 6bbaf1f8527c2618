"""A polytope given as the shadow of a larger one: task-space sets of linear programs.

When the limits are more than a box on the joints (contact forces that must push, wheels that
must not slip, constraints a user adds), the capacity set is no longer a zonotope section. It is
the projection onto the task coordinates a of a polytope in a larger space z = (a, rest):

    K = {a : exists z with z[task] = a, A_eq z = b_eq, A_ub z <= b_ub, lower <= z <= upper}

:class:`LiftedPolytope` answers the questions every :class:`~mobmanip.sets.taskset.TaskSet`
answers with linear programs on HiGHS (:class:`~mobmanip.sets.linear_programs.LinearProgram`,
kept warm between directions):

- ``support(d)``: max d . a over the set (the other task components free);
- ``straight_line_reach(d)``: the largest s with s d / |d| in the set (from rest, exactly
  along d); ``ray_radius(d)`` the same from :attr:`center`;
- ``witness(d)`` / ``straight_line_witness(d)``: the whole maximiser z, split by variable name
  (which torques, contact forces ... achieve the maximum) with the rows that bind there;
- vertices and halfspaces for m <= 3, by refining an inner polytope along the outer normals of
  its facets until every facet is a facet of K (Bretl and Lall's projection algorithm): each
  vertex found is an LP optimum, so the result is exact to the LP's tolerance; volume and
  isotropy from them. Above three dimensions only LP queries are answered (volume ``n/a``).

Its :attr:`center` is the centre of its bounding box along the task axes (the midpoint of the
supports along +-e_i), a point of the set for every convex K.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ModelError, TaskError
from .linear_programs import CertifiedProgram, LinearProgram
from .polytope import halfspaces_json
from .polytope_vertices import DUPLICATE_RTOL, distinct_rows
from .taskset import TaskSet, check_dims, check_direction, check_membership_points, check_points, membership

_TOL = 1e-9  # relative to the set's size: a support beyond a facet by less than this adds no vertex
#: Below this (in the task's units: m/s^2, N, ...) two points are one, whatever the set's size: a
#: set that has collapsed to a point (its extent some 1e-14) is not measured by its own rounding.
_ABS_TOL = 1e-10
_MAX_ROUNDS = 400


class LiftedPolytope(TaskSet):
    """The projection onto task coordinates of ``{z : A_eq z = b_eq, A_ub z <= b_ub, lower <= z <= upper}``.

    Args:
        task: column indices of z holding the task coordinates a, in task order, (m,).
        A_eq, b_eq: equalities, (p, n) and (p,).
        A_ub, b_ub: inequalities, (r, n) and (r,).
        lower, upper: bounds of z, (n,) each (+-inf where free).
        variables: named slices of z (e.g. ``{"tau": slice(8, 16)}``), for :meth:`witness`.
        model: what produced the set, for its JSON form (e.g. ``{"constraints": [...]}``).
        labels: what each inequality row stands for (e.g. ``"wheel_right_joint effort limit
            (+)"``), (r,): a maximiser's tight rows are reported by these.
        kinds: what kind of limit each inequality row is (``"effort"``, ``"traction"``, ...),
            (r,); default ``"user"`` for every row.
        scales: the size of the limit each inequality row stands for, in its own units, (r,)
            positive: a maximum's binding limits are ranked by their multipliers times these
            (:class:`Limit`); default each row's ``|b_ub|``, 1 where it is 0.
    """

    kind = "polytope"
    #: Whether the projection's vertex programs go to the certified DAQP path
    #: (:class:`~mobmanip.sets.linear_programs.CertifiedProgram`) or all to HiGHS (for comparisons).
    certified_vertices: bool = True

    def __init__(
        self,
        task: ArrayLike,
        A_eq: ArrayLike,
        b_eq: ArrayLike,
        A_ub: ArrayLike,
        b_ub: ArrayLike,
        lower: ArrayLike,
        upper: ArrayLike,
        variables: Mapping[str, slice] | None = None,
        model: Mapping | None = None,
        labels: Sequence[str] | None = None,
        kinds: Sequence[str] | None = None,
        scales: ArrayLike | None = None,
    ):
        self._task = np.asarray(task, dtype=int)
        self._A_eq = np.asarray(A_eq, dtype=float).reshape(-1, np.shape(lower)[0])
        self._b_eq = np.asarray(b_eq, dtype=float).reshape(-1)
        self._A_ub = np.asarray(A_ub, dtype=float).reshape(-1, np.shape(lower)[0])
        self._b_ub = np.asarray(b_ub, dtype=float).reshape(-1)
        self._lower = np.asarray(lower, dtype=float).copy()
        self._upper = np.asarray(upper, dtype=float).copy()
        self.variables = dict(variables or {})
        self.model = dict(model or {})
        self.labels = tuple(labels) if labels is not None else tuple(f"row {i}" for i in range(len(self._b_ub)))
        self.kinds = tuple(kinds) if kinds else ("user",) * len(self._b_ub)
        if scales is None or not len(np.atleast_1d(scales)):
            self.scales = np.where(self._b_ub != 0.0, np.abs(self._b_ub), 1.0)
        else:
            self.scales = np.asarray(scales, dtype=float).reshape(-1)
        if not (len(self.labels) == len(self.kinds) == len(self.scales) == len(self._b_ub)):
            raise TaskError(
                f"each inequality row needs one label, kind and scale: {len(self._b_ub)} rows, {len(self.labels)} "
                f"labels, {len(self.kinds)} kinds, {len(self.scales)} scales"
            )
        n = len(self._lower)
        for name, rows in (("A_eq", self._A_eq), ("A_ub", self._A_ub)):
            if rows.shape[1] != n or not np.all(np.isfinite(rows)):
                raise TaskError(f"{name} must be finite with {n} columns, got shape {rows.shape}")
        if len(self._b_eq) != len(self._A_eq) or len(self._b_ub) != len(self._A_ub):
            raise TaskError("each row of A_eq and A_ub needs one right-hand side")
        if not (np.all(np.isfinite(self._b_eq)) and np.all(np.isfinite(self._b_ub))):
            raise TaskError("the right-hand sides of a lifted polytope must be finite")
        self._cache: dict = {}
        self.empty = self._feasible_point() is None
        if self.empty:
            self.center = np.zeros(self.dim)
            self._cache["degenerate"] = True
            self._size = 1.0  # the scale of the programs' tolerances
            return
        if self.dim <= 3:  # the bounding box from the extreme points along the axes, which also
            # start the vertices' projection (enumerated on first use: a reading along one
            # direction, one program, does not need them, and they took some 150 programs)
            self._size = 1.0  # the programs' tolerance scale until the box is known
            axis_points = self._axis_points()
            lo, hi = axis_points.min(axis=0), axis_points.max(axis=0)
        else:
            lo, hi = -self._axis_supports(-1.0), self._axis_supports(1.0)
        self.center = 0.5 * (lo + hi)
        self._size = float(max(np.max(hi - lo), 1e-300))

    @property
    def degenerate(self) -> bool:
        """The set has no interior in the task space (some direction's width is relatively zero);
        for m <= 3 judged from the vertices, enumerated then if they were not yet."""
        if "degenerate" not in self._cache:
            self._cache["degenerate"] = self._flat()
        return self._cache["degenerate"]

    @degenerate.setter
    def degenerate(self, value: bool) -> None:
        self._cache["degenerate"] = bool(value)

    # ------------------------------------------------------------------------------------------
    # linear programs

    @property
    def dim(self) -> int:
        return len(self._task)

    def _program(self) -> LinearProgram:
        if "program" not in self._cache:
            A = np.vstack([self._A_eq, self._A_ub])
            lo = np.r_[self._b_eq, np.full(len(self._b_ub), -np.inf)]
            hi = np.r_[self._b_eq, self._b_ub]
            self._cache["program"] = LinearProgram(A, lo, hi, self._lower, self._upper)
        return self._cache["program"]

    def _vertex_program(self) -> CertifiedProgram:
        """The program the projection's many support queries use: DAQP, certified, else HiGHS."""
        if "certified" not in self._cache:
            A = np.vstack([self._A_eq, self._A_ub])
            lo = np.r_[self._b_eq, np.full(len(self._b_ub), -np.inf)]
            hi = np.r_[self._b_eq, self._b_ub]
            self._cache["certified"] = CertifiedProgram(A, lo, hi, self._lower, self._upper, self._program)
        return self._cache["certified"]

    def _vertex(self, d: np.ndarray) -> tuple[float, np.ndarray]:
        """A maximiser along d for the projection (its multipliers are not kept)."""
        if not self.certified_vertices:
            return self._maximise(d)
        result = self._vertex_program().solve(self._cost(d))
        if result is None:
            raise TaskError("the set is empty: it has no maximiser")
        return result

    def _cost(self, d: np.ndarray) -> np.ndarray:
        cost = np.zeros(len(self._lower))
        cost[self._task] = d
        return cost

    def _feasible_point(self) -> np.ndarray | None:
        result = self._vertex_program().solve(np.zeros(len(self._lower)))
        return None if result is None else result[1]

    def _maximise(self, d: np.ndarray) -> tuple[float, np.ndarray]:
        result = self._program().solve(self._cost(d))
        if result is None:  # only when empty (checked at construction)
            raise TaskError("the set is empty: it has no maximiser")
        return result

    def _ub_duals(self, program: LinearProgram, first_ub: int) -> np.ndarray:
        return program.row_duals[first_ub : first_ub + len(self._b_ub)].copy()

    def _tol(self) -> float:
        """Two points closer than this are one: relative to the set's size, at least _ABS_TOL."""
        return max(_TOL * getattr(self, "_size", 1.0), _ABS_TOL)

    def _axis_points(self) -> np.ndarray:
        """The maximisers along +e_i and -e_i of each task axis, in that order, (2 m, m): the
        bounding box of the set, and the first points of its projection (:meth:`_refine`)."""
        if "axis_points" not in self._cache:
            points = [self._vertex(s * e)[1][self._task] for e in np.eye(self.dim) for s in (1.0, -1.0)]
            self._cache["axis_points"] = np.array(points)
        return self._cache["axis_points"]

    def _axis_supports(self, sign: float) -> np.ndarray:
        return np.array([self._maximise(sign * row)[0] for row in np.eye(self.dim)])

    def _flat(self) -> bool:
        """Whether the set has no interior: some direction's width is (relatively) zero."""
        if self.dim <= 3:
            V = self.vertices
            if len(V) <= self.dim:
                return True
            return bool(np.linalg.matrix_rank(V - V.mean(axis=0), tol=self._tol()) < self.dim)
        widths = [self._maximise(e)[0] + self._maximise(-e)[0] for e in np.eye(self.dim)]
        return bool(min(widths) <= self._tol())

    # ------------------------------------------------------------------------------------------
    # TaskSet queries

    def support(self, direction: ArrayLike) -> float:
        d = check_direction(direction, self.dim)
        return 0.0 if self.empty else float(self._maximise(d)[0])

    def witness(self, direction: ArrayLike) -> Witness:
        """What achieves the support along d: the maximiser, split by :attr:`variables`, and the
        rows that bind there."""
        d = check_direction(direction, self.dim)
        if self.empty:
            raise TaskError("the set is empty: nothing reaches along any direction")
        value, z = self._maximise(d)
        return self._witness(value, z, self._ub_duals(self._program(), len(self._b_eq)))

    def restricted(self, name: str, rows: ArrayLike, values: ArrayLike | None = None) -> LiftedPolytope:
        """This set with the equations ``rows @ z[name] = values`` added (default values 0): a new
        set over the same task coordinates, e.g. with some reduced accelerations held at zero.

        Raises:
            TaskError: ``name`` is not one of the set's variables, or ``rows`` do not fit it.
        """
        if name not in self.variables:
            raise TaskError(f"restricted: {name!r} is not one of the set's variables {sorted(self.variables)}")
        where = np.arange(len(self._lower))[self.variables[name]]
        block = np.atleast_2d(np.asarray(rows, dtype=float))
        if block.shape[1] != len(where) or not np.all(np.isfinite(block)):
            raise TaskError(f"restricted: rows on {name!r} need {len(where)} finite columns, got shape {block.shape}")
        rhs = np.zeros(len(block)) if values is None else np.asarray(values, dtype=float).reshape(-1)
        if rhs.shape != (len(block),):
            raise TaskError(f"restricted: {len(block)} rows need {len(block)} values, got {rhs.shape[0]}")
        A = np.zeros((len(block), len(self._lower)))
        A[:, where] = block
        return LiftedPolytope(
            self._task, np.vstack([self._A_eq, A]), np.r_[self._b_eq, rhs], self._A_ub, self._b_ub,
            self._lower, self._upper, self.variables, self.model, self.labels, self.kinds, self.scales,
        )  # fmt: skip

    def straight_line_reach(self, direction: ArrayLike) -> float:
        """The largest s >= 0 with s d/|d| in the set: how far along d from rest, exactly along d
        (0 when no point of that ray is in the set, or the set is empty)."""
        found = self._ray(direction, np.zeros(self.dim))
        return 0.0 if found is None else found[0]

    def ray_radius(self, direction: ArrayLike) -> float:
        """The largest t >= 0 with center + t d/|d| in the set (0 when empty)."""
        found = self._ray(direction, self.center)
        return 0.0 if found is None else found[0]

    def straight_line_witness(self, direction: ArrayLike) -> Witness:
        """What achieves the straight-line reach along d (see :meth:`witness`).

        Raises:
            TaskError: the origin (no motion at all) is outside the set.
        """
        found = self._ray(direction, np.zeros(self.dim))
        if found is None:
            raise TaskError("the origin is outside the set: no straight line from rest exists")
        return self._witness(found[0], found[1][:-1], found[2])

    def witness_at(self, point: ArrayLike, least: str | None = None, still: Sequence[str] = ()) -> Witness:
        """A solution that reaches ``point``, as far inside every inequality row as it can be
        (max t with each row's slack >= t |row|): no limit is tight unless ``point`` needs it.

        Args:
            point: in the set, (m,).
            least: the name of a variable (e.g. ``"xdot"``, the reduced accelerations) to keep
                small: among the solutions with at least half that greatest slack, the one with
                the least 1-norm of that variable. The greatest slack alone may use large
                internal motions (self-motions of redundant arms) to gain a little margin; a
                replay of such a solution drifts away from it within milliseconds. At a point
                on the boundary, where HiGHS may not settle that second program (no slack to
                halve), the greatest-slack solution is returned.
            still: names of variables held at zero (e.g. ``("xdot",)``: the robot does not move
                at all, not even its joints).

        Raises:
            TaskError: the point is not in the set (with the ``still`` variables at zero), or
                ``least`` or a ``still`` name is not one of its variables.
        """
        p = check_points(point, self.dim)[0]
        if least is not None and least not in self.variables:
            raise TaskError(f"least must name one of the set's variables {sorted(self.variables)}, got {least!r}")
        for name in still:
            if name not in self.variables:
                raise TaskError(f"still must name the set's variables {sorted(self.variables)}, got {name!r}")
        n = len(self._lower)
        lower, upper = self._lower.copy(), self._upper.copy()
        for name in still:
            lower[self.variables[name]] = upper[self.variables[name]] = 0.0
        fix = np.zeros((self.dim, n + 1))
        fix[np.arange(self.dim), self._task] = 1.0
        norms = np.linalg.norm(self._A_ub, axis=1)
        A = np.vstack([np.c_[self._A_eq, np.zeros(len(self._A_eq))], fix, np.c_[self._A_ub, norms]])
        lo = np.r_[self._b_eq, p, np.full(len(self._b_ub), -np.inf)]
        hi = np.r_[self._b_eq, p, self._b_ub]
        program = LinearProgram(A, lo, hi, np.r_[lower, -np.inf], np.r_[upper, np.inf])
        cost = np.zeros(n + 1)
        cost[n] = 1.0
        result = program.solve(cost)
        if result is None or result[0] < -1e-9 * max(self._size, 1.0):
            held = f" with {', '.join(still)} at zero" if still else ""
            raise TaskError(f"the point {p.tolist()} is not in the set{held}")
        if least is None:
            return self._witness(float(result[0]), result[1][:-1], None)
        # the same rows with half the slack, and |v| <= u for the chosen variable v: min sum u
        where = np.arange(n)[self.variables[least]]
        k = len(where)
        pick = np.zeros((k, n))
        pick[np.arange(k), where] = 1.0
        half = 0.5 * max(float(result[0]), 0.0) * norms
        A2 = np.block(
            [
                [self._A_eq, np.zeros((len(self._A_eq), k))],
                [fix[:, :n], np.zeros((self.dim, k))],
                [self._A_ub, np.zeros((len(self._A_ub), k))],
                [pick, -np.eye(k)],
                [-pick, -np.eye(k)],
            ]
        )
        lo2 = np.r_[self._b_eq, p, np.full(len(self._b_ub) + 2 * k, -np.inf)]
        hi2 = np.r_[self._b_eq, p, self._b_ub - half, np.zeros(2 * k)]
        calm = LinearProgram(A2, lo2, hi2, np.r_[lower, np.zeros(k)], np.r_[upper, np.full(k, np.inf)])
        try:
            second = calm.solve(np.r_[np.zeros(n), -np.ones(k)])
        except ModelError:  # at a point on the boundary (no slack to halve) HiGHS may not settle
            second = None  # the degenerate program: the greatest-slack solution stands
        z = result[1][:-1] if second is None else second[1][:n]
        return self._witness(float(result[0]), self._polished(z, p, lower, upper), None)

    def _polished(self, z: np.ndarray, point: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """An interior solution reaching ``point`` with its equations made exact: the program holds them to its
        feasibility tolerance (1e-9 on scaled rows), which a poorly conditioned reduced inertia
        turns into accelerations 1e-6 off those its efforts give; the least-norm correction moves
        z by about that much, far less than the slack every inequality keeps, and is kept when z
        stays within its bounds."""
        if not len(self._A_eq):
            return z
        fix = np.zeros((self.dim, len(z)))  # the point stays where it is asked to be
        fix[np.arange(self.dim), self._task] = 1.0
        A, b = np.vstack([self._A_eq, fix]), np.r_[self._b_eq, point]
        correction = np.linalg.lstsq(A, A @ z - b, rcond=None)[0]
        polished = z - correction
        inside = np.all(polished >= lower - 1e-12 * np.abs(lower)) and np.all(polished <= upper + 1e-12 * np.abs(upper))
        return polished if inside else z

    def _ray(self, direction: ArrayLike, origin: np.ndarray) -> tuple[float, np.ndarray, np.ndarray] | None:
        d = check_direction(direction, self.dim)
        d = d / np.linalg.norm(d)
        if self.empty:
            return None
        key = ("ray", tuple(d), tuple(origin))
        if key not in self._cache:
            n = len(self._lower)
            tie = np.zeros((self.dim, n + 1))
            tie[np.arange(self.dim), self._task] = 1.0
            tie[:, n] = -d  # a = origin + s d
            A = np.vstack(
                [np.c_[self._A_eq, np.zeros(len(self._A_eq))], tie, np.c_[self._A_ub, np.zeros(len(self._A_ub))]]
            )
            lo = np.r_[self._b_eq, origin, np.full(len(self._b_ub), -np.inf)]
            hi = np.r_[self._b_eq, origin, self._b_ub]
            program = LinearProgram(A, lo, hi, np.r_[self._lower, 0.0], np.r_[self._upper, np.inf])
            cost = np.zeros(n + 1)
            cost[n] = 1.0
            result = program.solve(cost)
            duals = self._ub_duals(program, len(self._b_eq) + self.dim)
            self._cache[key] = None if result is None else (float(result[0]), result[1], duals)
        return self._cache[key]

    def radius_along(self, direction: ArrayLike) -> float:
        d = check_direction(direction, self.dim)
        d = d / np.linalg.norm(d)
        return 0.0 if self.empty else max(self.support(d) - float(d @ self.center), 0.0)

    def contains(self, points: ArrayLike, tol: float = 1e-9) -> bool | np.ndarray:
        """Whether points lie in the set, each with the task coordinates free by ``tol`` times the
        set's size (one feasibility program per point): a ``bool`` for one point (m,), a bool array
        (n,) for points (n, m).

        Raises:
            SetQueryError: any other shape (named), or a non-finite coordinate.
        """
        P, single = check_membership_points(points, self.dim)
        if self.empty:
            return membership(np.zeros(len(P), dtype=bool), single)
        out = np.zeros(len(P), dtype=bool)
        slack = tol * self._size
        lower, upper = self._lower.copy(), self._upper.copy()
        for i, p in enumerate(P):
            lower[self._task], upper[self._task] = p - slack, p + slack
            out[i] = self._program().solve(np.zeros(len(lower)), True, lower, upper) is not None
        self._program().solve(np.zeros(len(lower)), True, self._lower, self._upper)  # restore the bounds
        return membership(out, single)

    def project(self, dims: Sequence[int] = (0, 1)) -> LiftedPolytope:
        keep = check_dims(dims, self.dim)
        return self._derived(self._task[keep], self._A_eq, self._b_eq)

    def slice(self, dims: Sequence[int] = (0, 1)) -> LiftedPolytope:
        keep = check_dims(dims, self.dim)
        fixed = [i for i in range(self.dim) if i not in keep]
        rows = np.zeros((len(fixed), len(self._lower)))
        rows[np.arange(len(fixed)), self._task[fixed]] = 1.0
        A_eq = np.vstack([self._A_eq, rows])
        b_eq = np.r_[self._b_eq, self.center[fixed]]
        return self._derived(self._task[keep], A_eq, b_eq)

    def lifted_rows(self) -> LiftedRows:
        """The lifted problem's rows (read-only views), for programs that add their own rows or
        variables to it (e.g. :func:`mobmanip.motion.hold.held_reach`)."""
        arrays = [self._task, self._A_eq, self._b_eq, self._A_ub, self._b_ub, self._lower, self._upper]
        views = []
        for a in arrays:
            view = a.view()
            view.flags.writeable = False
            views.append(view)
        return LiftedRows(*views)

    def witness_of(self, z: ArrayLike) -> Witness:
        """The parts of a solution ``z`` of :meth:`lifted_rows` (e.g. one found with more rows), with
        the rows tight there as ``binding`` and its task point's norm as ``value``.

        Raises:
            TaskError: ``z`` is not a solution (an equation or a bound off by more than round-off).
        """
        z = np.asarray(z, dtype=float)
        if z.shape != self._lower.shape or not np.all(np.isfinite(z)):
            raise TaskError(f"a solution of the lifted rows has {len(self._lower)} finite entries, got shape {z.shape}")
        scale = 1e-7 * max(1.0, float(np.abs(z).max(initial=0.0)))
        off = max(
            float(np.abs(self._A_eq @ z - self._b_eq).max(initial=0.0)),
            float((self._A_ub @ z - self._b_ub).max(initial=0.0)),
            float((self._lower - z).max(initial=0.0)),
            float((z - self._upper).max(initial=0.0)),
        )
        largest = max(1.0, float(np.abs(self._A_ub).max(initial=0.0)), float(np.abs(self._A_eq).max(initial=0.0)))
        if off > scale * largest:
            raise TaskError(f"z is not a solution of the lifted rows (off by {off:.3g})")
        return self._witness(float(np.linalg.norm(z[self._task])), z, None)

    def _derived(self, task, A_eq, b_eq) -> LiftedPolytope:
        return LiftedPolytope(
            task, A_eq, b_eq, self._A_ub, self._b_ub, self._lower, self._upper, self.variables, self.model,
            self.labels, self.kinds, self.scales,
        )  # fmt: skip

    def _witness(self, value: float, z: np.ndarray, duals: np.ndarray | None) -> Witness:
        """The maximiser's parts; binding: the rows whose multiplier is not zero (the maximum moves
        with their bounds), or without multipliers the rows that are tight; with multipliers, the
        binding limits ranked (:func:`ranked_limits`)."""
        variables = {name: z[where].copy() for name, where in self.variables.items()}
        limits: tuple[Limit, ...] = ()
        if duals is not None:
            scale = float(np.abs(duals).max(initial=0.0))
            chosen = np.abs(duals) > 1e-9 * max(scale, 1e-300)
            limits = ranked_limits(np.where(chosen, np.abs(duals), 0.0), self.labels, self.kinds, self.scales)
        else:
            slack = self._b_ub - self._A_ub @ z
            chosen = slack <= 1e-7 * (np.maximum(np.abs(self._b_ub), np.abs(self._A_ub) @ np.abs(z)) + 1e-12)
        binding = tuple(label for label, c in zip(self.labels, chosen) if c)
        return Witness(float(value), z[self._task].copy(), variables, binding, limits)

    # ------------------------------------------------------------------------------------------
    # vertices, halfspaces and indices (m <= 3)

    @property
    def vertices(self) -> np.ndarray:
        """The vertices, (v, m), m <= 3: counter-clockwise for m = 2.

        Raises:
            TaskError: m > 3 (only LP queries are answered there).
        """
        if self.dim > 3:
            raise TaskError(f"vertices are enumerated up to 3 task dimensions, this set has {self.dim}")
        if self.empty:
            return np.zeros((0, self.dim))
        if "vertices" not in self._cache:
            self._cache["vertices"] = self._refine()
        return self._cache["vertices"]

    def _refine(self) -> np.ndarray:
        """Bretl and Lall's projection: grow an inner polytope by supports along its facets'
        normals, from the extreme points along the task axes (whose box sized the tolerance)."""
        m = self.dim
        found = list(self._axis_points())
        if m == 1:
            return np.unique(np.round(np.array(found), 15), axis=0)
        tol = self._tol()
        if m == 2:
            planar = self._refine_planar(np.array(found), tol)
            if planar is not None:
                return planar
        checked: set[tuple] = set()
        for _ in range(_MAX_ROUNDS):
            V = _unique_rows(np.array(found), tol)
            normals, offsets = _facets(V, tol)
            if normals is None:  # flat so far: try the directions across its span
                extra = _across(V, m, tol)
                added = False
                for d in extra:
                    p = self._vertex(d)[1][self._task]
                    if np.min(np.linalg.norm(V - p, axis=1)) > tol:
                        found.append(p)
                        added = True
                if not added:
                    return _ordered(V)
                continue
            added = False
            assert offsets is not None  # given with the normals
            for n, b in zip(normals, offsets):
                key = tuple(np.round(n, 12)) + (round(float(b) / self._size, 12),)
                if key in checked:
                    continue
                value, z = self._vertex(n)
                if value > b + tol:
                    found.append(z[self._task])
                    added = True
                else:
                    checked.add(key)
            if not added:
                return _ordered(V)
        raise TaskError("the projection did not converge (a set with very many vertices)")

    def _refine_planar(self, found: np.ndarray, tol: float) -> np.ndarray | None:
        """Bretl and Lall's projection for a polygon, edge by edge: the support along each edge's
        outer normal either lies on the edge (the edge is a facet) or is a new vertex that splits
        it in two. One program per vertex and one per facet; ``None`` when the starting points
        span no area (the general refinement handles flat sets)."""
        start = _ordered(_unique_rows(found, tol))
        if len(start) < 3:
            return None
        out: list[np.ndarray] = []
        known = list(start)
        pending = [(start[k], start[(k + 1) % len(start)]) for k in reversed(range(len(start)))]
        for _ in range(_MAX_ROUNDS):
            if not pending:
                return _ordered(np.array(out))
            a, b = pending.pop()
            edge = b - a
            length = math.hypot(edge[0], edge[1])
            if length <= tol:
                continue
            normal = np.array([edge[1], -edge[0]]) / length  # outward: the polygon runs counter-clockwise
            value, z = self._vertex(normal)
            p = z[self._task]
            if value <= normal @ a + tol:
                out.append(a)
                continue
            if np.min(np.linalg.norm(np.array(known) - p, axis=1)) <= tol:
                return None  # a known point beyond an edge: too thin to order this way
            known.append(p)
            pending.append((p, b))  # a -> p first, then p -> b
            pending.append((a, p))
        return None  # very many vertices: the general refinement decides

    @property
    def halfspaces(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, b) with the set = {a : A a <= b}, rows of unit norm (m <= 3, full-dimensional); no
        halfspace twice (unit normals that agree to 1e-9 and offsets to 1e-9 of the set's size are
        one row, :func:`~mobmanip.sets.polytope_vertices.distinct_rows`)."""
        V = self.vertices
        normals, offsets = _facets(V, self._tol()) if len(V) else (None, None)
        if normals is None or offsets is None:
            raise TaskError("the set has no interior: it has no halfspace description of its own dimension")
        return normals, offsets

    @property
    def faces(self) -> list[np.ndarray]:
        """Vertex indices of each facet (m <= 3)."""
        V = self.vertices
        if self.dim == 2 and len(V) > 2:
            return [np.array([i, (i + 1) % len(V)]) for i in range(len(V))]
        if self.dim == 3 and len(V) > 3 and not self.degenerate:
            from scipy.spatial import ConvexHull

            return [np.asarray(s) for s in ConvexHull(V).simplices]
        return []

    @property
    def triangles(self) -> np.ndarray:
        """Boundary triangles as vertex indices, (t, 3), for m = 3 (the viewer's mesh)."""
        faces = self.faces if self.dim == 3 else []
        return np.array(faces, dtype=int).reshape(-1, 3)

    @property
    def volume(self) -> float:
        if self.empty or self.degenerate:
            return 0.0
        V = self.vertices
        if self.dim == 1:
            return float(np.ptp(V))
        from scipy.spatial import ConvexHull

        return float(ConvexHull(V).volume)

    @property
    def inradius(self) -> float:
        """Distance from :attr:`center` to the nearest facet (0 when empty or degenerate)."""
        if self.empty or self.degenerate:
            return 0.0
        A, b = self.halfspaces
        return float(max(np.min(b - A @ self.center), 0.0))

    @property
    def circumradius(self) -> float:
        """Largest distance from :attr:`center` to a vertex (0 when empty)."""
        if self.empty:
            return 0.0
        return float(np.max(np.linalg.norm(self.vertices - self.center, axis=1), initial=0.0))

    @property
    def isotropy(self) -> float:
        """Nearest facet over farthest vertex, seen from :attr:`center` (0 when empty or degenerate)."""
        if self.empty or self.degenerate:
            return 0.0
        far = self.circumradius
        return self.inradius / far if far > 0.0 else 0.0

    def to_dict(self) -> dict:
        out: dict = {
            "kind": self.kind,
            "dim": self.dim,
            "empty": self.empty,
            "degenerate": self.degenerate,
            "center": self.center.tolist(),
            "model": self.model,
        }
        if self.dim <= 3 and not self.empty:
            out["vertices"] = self.vertices.tolist()
            out["faces"] = [f.tolist() for f in self.faces]
            out.update(halfspaces_json(self))
            out["volume"], out["isotropy"] = self.volume, self.isotropy
        else:
            out["halfspaces"] = None
            out["halfspaces_omitted"] = (
                "the set is empty" if self.empty else f"only linear-program queries above 3 dimensions ({self.dim})"
            )
            out["volume"] = out["isotropy"] = None
        return out

    def indices(self) -> dict[str, float]:
        if self.dim > 3:
            return {"volume": float("nan"), "isotropy": float("nan")}
        return super().indices()

    def __repr__(self) -> str:
        state = "empty" if self.empty else ("degenerate" if self.degenerate else "full")
        return f"LiftedPolytope(dim={self.dim}, variables={len(self._lower)}, {state})"


@dataclass(frozen=True)
class LiftedRows:
    """A lifted polytope's rows: the task point is ``z[task]`` for the variables z with
    ``A_eq z = b_eq``, ``A_ub z <= b_ub`` and ``lower <= z <= upper``."""

    task: np.ndarray
    A_eq: np.ndarray
    b_eq: np.ndarray
    A_ub: np.ndarray
    b_ub: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


@dataclass(frozen=True)
class Witness:
    """What achieves a maximum of a :class:`LiftedPolytope`.

    Attributes:
        value: the maximum (the support, or the straight-line reach).
        point: the task-space point reached, (m,).
        variables: every variable of the lifted problem at the maximiser, by name.
        binding: the labels of the inequality rows that limit the maximum (a non-zero multiplier:
            what stops it); for :meth:`LiftedPolytope.witness_at`, the rows that are tight.
        limits: the limits that bind at a maximum, the one worth most first (:func:`ranked_limits`);
            empty where no multipliers are known (:meth:`LiftedPolytope.witness_at`,
            :meth:`LiftedPolytope.witness_of`).
    """

    value: float
    point: np.ndarray
    variables: Mapping[str, np.ndarray]
    binding: tuple[str, ...]
    limits: tuple[Limit, ...] = ()


#: A limit's gain is quoted for this relative change of its scale (1 %).
GAIN_STEP = 0.01
#: A binding limit worth less than this share of the first is the program's rounding.
GAIN_ROUNDING = 1e-6


@dataclass(frozen=True)
class Limit:
    """A limit that binds at a maximum, and what relaxing it is worth.

    Attributes:
        label: what it is (the rows' label: several rows may share one, e.g. a wheel's friction
            pyramid).
        kind: what kind of limit (``"effort"``, ``"traction"``, ``"tip-over"``, ...).
        multiplier: the sum of its rows' multipliers: the growth of the maximum per unit by which
            each of its rows is relaxed, in the task's units per the rows' unit (m/s^2 per N m).
        gain: the growth of the maximum, to first order, when each of its rows is relaxed by
            :data:`GAIN_STEP` (1 %) of its scale: ``GAIN_STEP * sum(multiplier_i * scale_i)``, in
            the task's units. Comparable across kinds: the limits are ranked by it.
    """

    label: str
    kind: str
    multiplier: float
    gain: float


def ranked_limits(
    multipliers: np.ndarray, labels: Sequence[str], kinds: Sequence[str], scales: ArrayLike
) -> tuple[Limit, ...]:
    """The limits of the rows whose multiplier is not zero, one per label, the largest gain first
    (ties by label); a limit worth less than :data:`GAIN_ROUNDING` of the first is the program's
    rounding (a multiplier of some 1e-9), left out.

    Args:
        multipliers: each inequality row's multiplier, >= 0 (zero where it does not bind), (r,).
        labels, kinds: each row's label and kind, (r,).
        scales: the size of the limit each row stands for, (r,) positive.
    """
    multipliers = np.asarray(multipliers, dtype=float)
    scales = np.asarray(scales, dtype=float)
    found: dict[str, list] = {}
    for i in (int(k) for k in np.flatnonzero(multipliers > 0.0)):
        entry = found.setdefault(labels[i], [kinds[i], 0.0, 0.0])
        entry[1] += float(multipliers[i])
        entry[2] += GAIN_STEP * float(multipliers[i] * scales[i])
    limits = sorted(
        (Limit(label, kind, multiplier, gain) for label, (kind, multiplier, gain) in found.items()),
        key=lambda lim: (-lim.gain, lim.label),
    )
    return tuple(lim for lim in limits if lim.gain > GAIN_ROUNDING * limits[0].gain)


# ----------------------------------------------------------------------------------------------
# small geometry of the inner polytope


def _unique_rows(V: np.ndarray, tol: float) -> np.ndarray:
    """The rows of V farther than ``tol`` from every row kept before them, in order. The kept rows
    fill one array as they come: rebuilt from a list at each row, they made the 3-D projections
    of a 16-joint robot's grounded set quadratic in copies (5.7 s of 20 in ``analyze``)."""
    keep = np.empty_like(V)
    count = 0
    for v in V:
        if count == 0 or np.min(np.linalg.norm(keep[:count] - v, axis=1)) > tol:
            keep[count] = v
            count += 1
    return keep[:count].copy()


def _facets(V: np.ndarray, tol: float) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Outer unit normals and offsets of the hull of V, or (None, None) when V has no interior."""
    m = V.shape[1]
    if len(V) <= m or np.linalg.matrix_rank(V - V.mean(axis=0), tol=max(tol, 1e-300)) < m:
        return None, None
    if m == 2:
        P = _ordered(V)
        edges = np.roll(P, -1, axis=0) - P
        normals = np.c_[edges[:, 1], -edges[:, 0]]
        length = np.linalg.norm(normals, axis=1)
        keep = length > tol
        normals = normals[keep] / length[keep, None]
        return _distinct(normals, np.einsum("ij,ij->i", normals, P[keep]), tol)
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(V)
    except QhullError:  # flat to Qhull's own precision: no facets of its dimension
        return None, None
    normals, offsets = hull.equations[:, :-1], -hull.equations[:, -1]
    scale = np.linalg.norm(normals, axis=1)
    # Qhull lists a facet once per simplex of it (a square facet twice): one row per facet
    return _distinct(normals / scale[:, None], offsets / scale, tol)


def _distinct(normals: np.ndarray, offsets: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """One row per halfspace (:func:`~mobmanip.sets.polytope_vertices.distinct_rows`): unit normals
    that agree to its relative tolerance and offsets that agree to ``tol``, the set's own."""
    keep, _ = distinct_rows(normals, offsets, tol / DUPLICATE_RTOL)
    return normals[keep], offsets[keep]


def _ordered(V: np.ndarray) -> np.ndarray:
    """Planar points in counter-clockwise order around their hull (interior points dropped);
    other dimensions: the hull's vertices."""
    if V.shape[1] != 2 or len(V) < 3:
        if V.shape[1] == 3 and len(V) > 3:
            from scipy.spatial import ConvexHull

            try:
                return V[ConvexHull(V).vertices]
            except Exception:  # a flat set: every point is kept  # noqa: BLE001
                return V
        return V
    # Andrew's monotone chain sorts by x, then y. Points on one vertical edge found by different
    # programs differ in x by rounding (3e-13 on a 18 m/s^2 box): sorted by that noise, the chain
    # ran down the edge and back up and dropped a corner as "straight on". Their x is compared on
    # a grid of 1e-9 of the set's size, so that they sort by y.
    grid = 1e-9 * max(float(np.max(np.abs(V))), 1e-300)
    pts = sorted(map(tuple, V), key=lambda p: (round(p[0] / grid), p[1]))
    lower: list = []
    upper: list = []
    for p in pts:
        while len(lower) >= 2 and _turns_right(lower[-2], lower[-1], p):
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and _turns_right(upper[-2], upper[-1], p):
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def _turns_right(o, a, b) -> bool:
    """Whether o -> a -> b turns clockwise or goes straight on (a is then no vertex): the cross
    product at most _TOL times the two lengths (a point on an edge, up to rounding, is dropped)."""
    cross = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    return cross <= _TOL * math.hypot(a[0] - o[0], a[1] - o[1]) * math.hypot(b[0] - a[0], b[1] - a[1])


def _across(V: np.ndarray, m: int, tol: float) -> list[np.ndarray]:
    """Directions orthogonal to the affine span of V (both senses)."""
    centered = V - V.mean(axis=0)
    _, s, Vt = np.linalg.svd(centered, full_matrices=True)
    rank = int(np.sum(s > tol))
    return [sign * row for row in Vt[rank:] for sign in (1.0, -1.0)]
