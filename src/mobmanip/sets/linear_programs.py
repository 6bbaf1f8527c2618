"""Small dense linear programs on HiGHS, kept between calls.

A polytope's support queries solve the same program with a different objective each time;
HiGHS (through its own Python bindings, ``highspy``) keeps the model and the last optimal basis,
so a new direction starts from the previous vertex. ``scipy.optimize.linprog`` would rebuild
and re-validate the model on every call (about five times slower for these sizes).
"""

from __future__ import annotations

import threading

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

    def solve(self, cost, maximize: bool = True, col_lo=None, col_hi=None) -> tuple[float, np.ndarray] | None:
        """The optimum (value, x), or None when infeasible.

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
