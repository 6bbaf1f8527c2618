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


class LinearProgram:
    """optimise c . x subject to row_lo <= A x <= row_hi and col_lo <= x <= col_hi.

    Infinite bounds are written as +-inf. The model is built once; :meth:`solve` changes the
    objective (and optionally the column bounds) and warm-starts from the last basis. Calls are
    serialised by a lock, so one program may be shared between threads.
    """

    def __init__(self, A: np.ndarray, row_lo, row_hi, col_lo, col_hi):
        A = np.asarray(A, dtype=float)
        self.n_rows, self.n_cols = A.shape
        self._lock = threading.Lock()
        highspy = self._highspy = _highspy()
        h = highspy._Highs()  # the bindings' core class: no banner on standard output
        h.setOptionValue("output_flag", False)
        h.setOptionValue("presolve", "off")
        h.setOptionValue("primal_feasibility_tolerance", 1e-10)
        h.setOptionValue("dual_feasibility_tolerance", 1e-10)
        lp = highspy.HighsLp()
        lp.num_col_ = self.n_cols
        lp.num_row_ = self.n_rows
        lp.col_cost_ = np.zeros(self.n_cols)
        self._inf = highspy.kHighsInf
        lp.col_lower_ = self._finite(col_lo, self.n_cols)
        lp.col_upper_ = self._finite(col_hi, self.n_cols)
        lp.row_lower_ = self._finite(row_lo, self.n_rows)
        lp.row_upper_ = self._finite(row_hi, self.n_rows)
        cols, rows = np.nonzero(A.T)  # column-wise order
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=self.n_cols))]).astype(
            np.int32
        )
        lp.a_matrix_.index_ = rows.astype(np.int32)
        lp.a_matrix_.value_ = A.T[cols, rows]
        h.passModel(lp)
        self._h = h
        self._all = np.arange(self.n_cols, dtype=np.int32)
        #: The rows' dual values (multipliers) at the last optimum: a row whose multiplier is not
        #: zero limits the optimum (its sensitivity to that row's bound).
        self.row_duals = np.zeros(self.n_rows)
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
            ModelError: HiGHS reports neither an optimum nor infeasibility (e.g. unbounded:
                the polytope's description was not bounded).
        """
        h, highspy = self._h, self._highspy
        with self._lock:
            h.changeObjectiveSense(highspy.ObjSense.kMaximize if maximize else highspy.ObjSense.kMinimize)
            h.changeColsCost(self.n_cols, self._all, np.asarray(cost, dtype=float))
            if col_lo is not None:
                h.changeColsBounds(
                    self.n_cols, self._all, self._finite(col_lo, self.n_cols), self._finite(col_hi, self.n_cols)
                )
            if row_lo is not None:
                rows = np.arange(self.n_rows, dtype=np.int32)
                h.changeRowsBounds(
                    self.n_rows, rows, self._finite(row_lo, self.n_rows), self._finite(row_hi, self.n_rows)
                )
            h.run()
            status = h.getModelStatus()
            if status not in (highspy.HighsModelStatus.kOptimal, highspy.HighsModelStatus.kInfeasible):
                # a warm start from the last basis can stall on a badly scaled program (the floor's
                # weights beside radians): once more from scratch, with HiGHS's presolve
                h.clearSolver()
                h.setOptionValue("presolve", "on")
                h.run()
                h.setOptionValue("presolve", "off")
                status = h.getModelStatus()
            if status == highspy.HighsModelStatus.kOptimal:
                solution = h.getSolution()
                x = np.array(solution.col_value)
                self.row_duals = np.array(solution.row_dual)
                return float(h.getInfo().objective_function_value), x
            if status == highspy.HighsModelStatus.kInfeasible:
                return None
            h.clearSolver()  # a failed basis must not seed the next call
            raise ModelError(f"the linear program of a polytope query ended as {h.modelStatusToString(status)}")

    def _finite(self, values, n: int) -> np.ndarray:
        """Bounds with +-inf mapped to HiGHS's infinity, (n,)."""
        out = np.broadcast_to(np.asarray(values, dtype=float), (n,)).copy()
        out[out == _INF] = self._inf
        out[out == -_INF] = -self._inf
        return out


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
        x, _, flag, info = daqp.solve(self._zero, f, self._A, self._hi, self._lo, self._sense.copy(), primal_tol=1e-10)
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
