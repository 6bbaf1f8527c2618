"""Small dense linear programs on HiGHS, kept between calls, and a faster certified path.

A polytope's support queries solve the same program with a different objective each time;
HiGHS (through its own Python bindings, ``highspy``) keeps the model and the last optimal basis,
so a new direction starts from the previous vertex. ``scipy.optimize.linprog`` would rebuild
and re-validate the model on every call (about five times slower for these sizes).

:class:`CertifiedProgram` answers the same programs with DAQP (a dual active-set solver for
small dense problems, about 30 us per program of some 40 variables against HiGHS's 100 to
300 us) and keeps an answer only when its optimality certificate holds: the multipliers DAQP
returns make the objective a combination of the active rows (stationarity), with the right
signs, and the solution is feasible, each to 1e-9 relative. Anything else (a failed solve, an
uncertified answer) is solved again on HiGHS, so every value returned is optimal to that
tolerance whichever solver found it.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

from ..errors import ModelError

_INF = float("inf")


def _highspy():
    try:
        import highspy
    except ImportError:  # pragma: no cover - highspy is a dependency
        raise ModelError("polytope queries need the 'highspy' package (HiGHS): pip install highspy") from None
    return highspy


#: HiGHS's feasibility tolerances on the equilibrated program (see :func:`equilibrate`): rows,
#: bounds and variables there are of order one, so these are relative to each row's own size.
FEASIBILITY = 1e-9
#: Entries below this, in the caller's units, are rounding (HiGHS drops them, ``small_matrix_value``):
#: they are dropped before the equilibration, which would otherwise scale a column of rounding
#: (a pseudo-inverse's at a singular posture) up to entries of order one.
ROUNDING = 1e-9


def _power_of_two(values: np.ndarray) -> np.ndarray:
    """2**round(log2(v)) for positive v (1 elsewhere): a scaling that rounds nothing."""
    out = np.ones_like(values)
    positive = values > 0.0
    out[positive] = np.exp2(np.round(np.log2(values[positive])))
    return out


def equilibrate(A: np.ndarray, row_lo, row_hi, col_lo, col_hi, sweeps: int = 6):
    """Row, column and variable scales that bring a program's rows, bounds and variables to order one.

    A program of this project mixes units in one matrix (newtons of contact force, metres per
    second squared, radians per second squared, newton-metres of effort), and its bounds span
    from fractions of a unit to the robot's weight (over 1,000 N). With absolute feasibility
    tolerances a solver then judges some rows to 1e-13 of their size and others to 1e-6, and
    its status on a barely infeasible program depends on the machine (HiGHS ended "Unknown").
    The scaled program ``R A C y``, ``y = s C^-1 x`` is the same program in units where every
    row's largest entry, right-hand side and every variable's bound is about one.

    The scales are Ruiz's iterative equilibration in the infinity norm of the matrix augmented
    with its bounds: ``[[A, b_rows], [I_bounded, b_cols]]``, where ``b_rows`` is each row's
    largest finite bound (0 if none), ``I_bounded`` a row per column with a finite bound, and
    the last column's scale ``s`` the unit of every variable at once. Scales are powers of two,
    so scaling rounds nothing.

    Args:
        A: the constraint matrix, (p, n).
        row_lo, row_hi: row bounds, (p,) (+-inf where none).
        col_lo, col_hi: column bounds, (n,).
        sweeps: Ruiz iterations (each halves the spread of the entries' logarithms).

    Returns:
        (r, c, s): row scales (p,), column scales (n,) and the variables' unit s (a float).
    """
    p, n = A.shape
    row_lo, row_hi = np.broadcast_to(row_lo, (p,)), np.broadcast_to(row_hi, (p,))
    col_lo, col_hi = np.broadcast_to(col_lo, (n,)), np.broadcast_to(col_hi, (n,))

    def largest_finite(lo, hi):
        both = np.abs(np.stack([lo, hi]))
        return np.where(np.isfinite(both), both, 0.0).max(axis=0)

    b_rows, b_cols = largest_finite(row_lo, row_hi), largest_finite(col_lo, col_hi)
    bounded = np.flatnonzero(np.isfinite(col_lo) | np.isfinite(col_hi))
    K = np.zeros((p + len(bounded), n + 1))
    K[:p, :n] = np.abs(A)
    K[:p, n] = b_rows
    K[p + np.arange(len(bounded)), bounded] = 1.0
    K[p:, n] = b_cols[bounded]
    rows, cols = np.ones(K.shape[0]), np.ones(n + 1)
    for _ in range(sweeps):
        norm = (K * cols).max(axis=1) * rows
        rows /= np.sqrt(np.where(norm > 0.0, norm, 1.0))
        norm = (K * rows[:, None]).max(axis=0) * cols
        cols /= np.sqrt(np.where(norm > 0.0, norm, 1.0))
    r, c, s = _power_of_two(rows[:p]), _power_of_two(cols[:n]), float(_power_of_two(cols[n:])[0])
    return r, c, s


class LinearProgram:
    """optimise c . x subject to row_lo <= A x <= row_hi and col_lo <= x <= col_hi.

    Infinite bounds are written as +-inf. The model is built once; :meth:`solve` changes the
    objective (and optionally the column bounds) and warm-starts from the last basis. Calls are
    serialised by a lock, so one program may be shared between threads.

    HiGHS solves the program equilibrated (:func:`equilibrate`), with feasibility tolerances of
    :data:`FEASIBILITY` there; values, solutions and multipliers are returned in the caller's
    units. A solve ends optimal, infeasible or unbounded; any other status of HiGHS is retried
    from scratch (with presolve, then with the interior-point method) and raises only if none
    settles.
    """

    def __init__(self, A: np.ndarray, row_lo, row_hi, col_lo, col_hi):
        A = np.asarray(A, dtype=float)
        self.n_rows, self.n_cols = A.shape
        self._lock = threading.Lock()
        highspy = self._highspy = _highspy()
        A = np.where(np.abs(A) < ROUNDING, 0.0, A)
        self._r, self._c, self._s = equilibrate(A, row_lo, row_hi, col_lo, col_hi)
        scaled = A * self._r[:, None] * self._c[None, :]
        h = highspy._Highs()  # the bindings' core class: no banner on standard output
        h.setOptionValue("output_flag", False)
        h.setOptionValue("presolve", "off")
        h.setOptionValue("primal_feasibility_tolerance", FEASIBILITY)
        h.setOptionValue("dual_feasibility_tolerance", FEASIBILITY)
        h.setOptionValue("small_matrix_value", 1e-15)  # rounding is dropped above, in the caller's units
        lp = highspy.HighsLp()
        lp.num_col_ = self.n_cols
        lp.num_row_ = self.n_rows
        lp.col_cost_ = np.zeros(self.n_cols)
        self._inf = highspy.kHighsInf
        lp.col_lower_, lp.col_upper_ = self._col_bounds(col_lo, col_hi)
        lp.row_lower_, lp.row_upper_ = self._scaled_row_bounds(row_lo, row_hi)
        cols, rows = np.nonzero(scaled.T)  # column-wise order
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=self.n_cols))]).astype(
            np.int32
        )
        lp.a_matrix_.index_ = rows.astype(np.int32)
        lp.a_matrix_.value_ = scaled.T[cols, rows]
        h.passModel(lp)
        self._h = h
        self._all = np.arange(self.n_cols, dtype=np.int32)
        #: The rows' dual values (multipliers) at the last optimum: a row whose multiplier is not
        #: zero limits the optimum (its sensitivity to that row's bound).
        self.row_duals = np.zeros(self.n_rows)
        #: HiGHS's model status of the last solve, by name ("Optimal", "Infeasible", "Unbounded").
        self.last_status = ""
        self._row_bounds = (
            np.broadcast_to(np.asarray(row_lo, dtype=float), (self.n_rows,)).copy(),
            np.broadcast_to(np.asarray(row_hi, dtype=float), (self.n_rows,)).copy(),
        )

    def row_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The rows' bounds the program was built with (copies; +-inf where unbounded)."""
        return self._row_bounds[0].copy(), self._row_bounds[1].copy()

    def solve(
        self, cost, maximize: bool = True, col_lo=None, col_hi=None, row_lo=None, row_hi=None
    ) -> tuple[float, np.ndarray] | None:
        """The optimum (value, x), or None when infeasible. New column or row bounds, when given,
        stay for the calls after this one.

        Raises:
            ModelError: the program is unbounded (the polytope's description was not bounded),
                or HiGHS settles on no status even from scratch.
        """
        h, highspy = self._h, self._highspy
        status_of = highspy.HighsModelStatus
        with self._lock:
            h.changeObjectiveSense(highspy.ObjSense.kMaximize if maximize else highspy.ObjSense.kMinimize)
            h.changeColsCost(self.n_cols, self._all, np.asarray(cost, dtype=float) * self._c)
            if col_lo is not None:
                h.changeColsBounds(self.n_cols, self._all, *self._col_bounds(col_lo, col_hi))
            if row_lo is not None:
                rows = np.arange(self.n_rows, dtype=np.int32)
                h.changeRowsBounds(self.n_rows, rows, *self._scaled_row_bounds(row_lo, row_hi))
            status = self._run()
            self.last_status = h.modelStatusToString(status)
            if status == status_of.kOptimal:
                solution = h.getSolution()
                x = np.array(solution.col_value) * self._c / self._s
                self.row_duals = np.array(solution.row_dual) * self._r
                return float(h.getInfo().objective_function_value) / self._s, x
            if status == status_of.kInfeasible:
                return None
            h.clearSolver()  # a failed basis must not seed the next call
            raise ModelError(f"the linear program of a polytope query ended as {self.last_status}")

    def _run(self):
        """Run HiGHS until it settles: warm; from scratch; with presolve; at HiGHS's own tolerances
        (1e-7: its postsolve can leave a dual infeasibility of some 1e-8 it cannot clean up at
        1e-9); with the interior-point method. Each attempt after the first starts from scratch."""
        h, settled = self._h, self._settled()
        looser = {"primal_feasibility_tolerance": 1e-7, "dual_feasibility_tolerance": 1e-7}
        attempts = ({}, {}, {"presolve": "on"}, looser, {"solver": "ipm"})
        defaults = {"presolve": "off", "primal_feasibility_tolerance": FEASIBILITY,
                    "dual_feasibility_tolerance": FEASIBILITY, "solver": "choose"}  # fmt: skip
        status = None
        for k, options in enumerate(attempts):
            if k:
                h.clearSolver()
            for option, value in options.items():
                h.setOptionValue(option, value)
            h.run()
            status = h.getModelStatus()
            if status == self._highspy.HighsModelStatus.kUnboundedOrInfeasible:
                h.clearSolver()  # presolve cannot tell which: the simplex from scratch can
                h.setOptionValue("presolve", "off")
                h.run()
                status = h.getModelStatus()
            for option in options:
                h.setOptionValue(option, defaults[option])
            if status in settled:
                return status
        return status

    def _settled(self) -> tuple:
        s = self._highspy.HighsModelStatus
        return (s.kOptimal, s.kInfeasible, s.kUnbounded)

    def _col_bounds(self, lo, hi) -> tuple[np.ndarray, np.ndarray]:
        """Column bounds in the equilibrated program's units (HiGHS's infinity where none)."""
        unit = self._s / self._c
        return self._finite(lo, self.n_cols) * unit, self._finite(hi, self.n_cols) * unit

    def _scaled_row_bounds(self, lo, hi) -> tuple[np.ndarray, np.ndarray]:
        """Row bounds in the equilibrated program's units (HiGHS's infinity where none)."""
        unit = self._r * self._s
        return self._finite(lo, self.n_rows) * unit, self._finite(hi, self.n_rows) * unit

    def _finite(self, values, n: int) -> np.ndarray:
        """Bounds with +-inf mapped to HiGHS's infinity, (n,)."""
        out = np.broadcast_to(np.asarray(values, dtype=float), (n,)).copy()
        out[out == _INF] = self._inf
        out[out == -_INF] = -self._inf
        return out


#: DAQP solves a program without a quadratic cost by proximal-point iterations, and stops them
#: when an iterate moves less than this (its setting ``eta_prox``). Its automatic choice stopped
#: early on degenerate programs: at TIAGo Pro's home, on the floor, 44 % of the projection's
#: programs came back flagged optimal yet up to 1 % short of HiGHS's optimum, failed the
#: certificate and were solved again by HiGHS; at 1e-10 every one of them is certified, in about
#: the same time a program (``analyze tiago_pro --ground``: 11.1 s of CPU before, 5.5 s after).
_ETA_PROX = 1e-10


class CertifiedProgram:
    """The program of a :class:`LinearProgram` solved by DAQP, certified, else by HiGHS.

    Args:
        A, row_lo, row_hi, col_lo, col_hi: as :class:`LinearProgram`; rows with
            ``row_lo == row_hi`` are equalities.
        fallback: makes the HiGHS program of the same problem (its answers are used as they
            are); called on the first answer DAQP cannot certify.
    """

    _TOL = 1e-9

    def __init__(self, A: np.ndarray, row_lo, row_hi, col_lo, col_hi, fallback: Callable[[], LinearProgram]):
        A = np.asarray(A, dtype=float)
        self.n_rows, self.n_cols = A.shape
        self._fallback = fallback
        big = 1e30  # DAQP's infinity
        lo = np.r_[np.broadcast_to(col_lo, (self.n_cols,)), np.broadcast_to(row_lo, (self.n_rows,))].astype(float)
        hi = np.r_[np.broadcast_to(col_hi, (self.n_cols,)), np.broadcast_to(row_hi, (self.n_rows,))].astype(float)
        self._lo, self._hi = np.maximum(lo, -big), np.minimum(hi, big)
        self._A = A
        self._full = np.vstack([np.eye(self.n_cols), A])  # bounds, then rows: what the multipliers weigh
        self._sense = np.where(lo == hi, 5, 0).astype(np.int32)  # 5: an equality (active and immutable)
        self._sense[: self.n_cols] = np.where(lo[: self.n_cols] == hi[: self.n_cols], 5, 0)
        self._zero = np.zeros((self.n_cols, self.n_cols))
        self._scale_b = 1.0 + float(
            np.max(np.abs(np.r_[self._lo[np.abs(self._lo) < big], self._hi[np.abs(self._hi) < big], 0.0]))
        )
        self.certified = 0
        self.fell_back = 0

    def solve(self, cost, maximize: bool = True) -> tuple[float, np.ndarray] | None:
        """The optimum (value, x), or None when infeasible (as :meth:`LinearProgram.solve`)."""
        import daqp

        c = np.asarray(cost, dtype=float)
        f = -c if maximize else c
        x, _, flag, info = daqp.solve(
            self._zero, f, self._A, self._hi, self._lo, self._sense.copy(), primal_tol=1e-10, eta_prox=_ETA_PROX
        )
        x = np.asarray(x, dtype=float)
        if flag == 1 and self._certify(f, x, np.asarray(info["lam"])):
            self.certified += 1
            return float(c @ x), x  # the objective at x (DAQP's own value includes its proximal term)
        self.fell_back += 1
        return self._fallback().solve(c, maximize)

    def _certify(self, f: np.ndarray, x: np.ndarray, lam: np.ndarray) -> bool:
        """KKT to 1e-9 relative: f + A'lam = 0, lam > 0 only on rows at their upper bound and
        lam < 0 only at their lower, every row and bound within its limits (the multipliers
        recomputed on DAQP's active rows when its own do not balance the objective)."""
        scale = 1.0 + float(np.abs(lam).max(initial=0.0)) + float(np.abs(f).max(initial=0.0))
        if np.abs(f + self._full.T @ lam).max() > self._TOL * scale:
            # DAQP's multipliers carry its proximal term (some 1e-7): recompute them on its active
            # rows by least squares, and keep its active set if they balance the objective
            active = np.flatnonzero(np.abs(lam) > 1e-12 * scale)
            exact = np.linalg.lstsq(self._full[active].T, -f, rcond=None)[0]
            flipped = (exact * lam[active] < 0.0) & (np.abs(exact) > self._TOL * scale)
            if np.any(flipped) or np.abs(f + self._full[active].T @ exact).max() > self._TOL * scale:
                return False
            lam = np.zeros_like(lam)
            lam[active] = exact
        values = self._full @ x
        tol = self._TOL * self._scale_b
        if np.any(values > self._hi + tol) or np.any(values < self._lo - tol):
            return False
        small = 1e-12 * scale
        at_hi, at_lo = lam > small, lam < -small
        return not (
            np.any(np.abs(values[at_hi] - self._hi[at_hi]) > tol)
            or np.any(np.abs(values[at_lo] - self._lo[at_lo]) > tol)
        )
