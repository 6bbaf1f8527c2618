"""What stays constant over a batch: :class:`BatchSetup`, built once per robot, task and object.

Everything the engine knows about the platform's null-space matrix S is derived here, in
:meth:`BatchSetup._constant_null_space`: the projections of the NumPy path, S column-compressed
and the congruence plan P = S^T M S of the compiled kernel, the reduced coordinates that can
move each end effector, and Q = S^T B. A platform whose S depends on q is refused.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import ModelError, TaskError
from ..platforms import a_platform
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task
from ..support.tolerances import RANK_RTOL
from ..terms.grasp import GRAVITY, checked_object_mass, object_mass_of
from .probed import ProbedModel


class Projection:
    """Products with a constant S (nv, nx): its unit columns (one entry 1, e.g. arm joints) are
    copied as slices, the others (the platform's) go through their nonzero rows only."""

    def __init__(self, S: np.ndarray):
        nv, nx = S.shape
        self.nx = nx
        unit, dense = [], []
        for j in range(nx):
            nz = np.flatnonzero(S[:, j])
            if len(nz) == 1 and S[nz[0], j] == 1.0:
                unit.append((j, int(nz[0])))
            else:
                dense.append(j)
        # runs of consecutive columns mapped to consecutive rows -> slice copies
        self.runs: list[tuple[int, int, int, int]] = []
        for j, v in unit:
            if self.runs and self.runs[-1][1] == j and self.runs[-1][3] == v:
                c0, _, r0, _ = self.runs[-1]
                self.runs[-1] = (c0, j + 1, r0, v + 1)
            else:
                self.runs.append((j, j + 1, v, v + 1))
        self.dense_cols = np.array(dense, dtype=int)
        rows = sorted({int(v) for j in dense for v in np.flatnonzero(S[:, j])})
        self.dense_rows = np.array(rows, dtype=int)
        self.S_dense = S[np.ix_(self.dense_rows, self.dense_cols)].copy()

    def right(self, A: np.ndarray) -> np.ndarray:
        """A S for A (..., nv) -> (..., nx)."""
        out = np.empty(A.shape[:-1] + (self.nx,))
        for c0, c1, r0, r1 in self.runs:
            out[..., c0:c1] = A[..., r0:r1]
        if self.dense_cols.size:
            out[..., self.dense_cols] = A[..., self.dense_rows] @ self.S_dense
        return out

    def left_transpose(self, A: np.ndarray) -> np.ndarray:
        """S^T A for A (n, nv, c) -> (n, nx, c)."""
        out = np.empty((A.shape[0], self.nx, A.shape[2]))
        for c0, c1, r0, r1 in self.runs:
            out[:, c0:c1, :] = A[:, r0:r1, :]
        if self.dense_cols.size:
            out[:, self.dense_cols, :] = self.S_dense.T @ A[:, self.dense_rows, :]
        return out


class BatchSetup:
    """Everything about a robot, task and object that does not depend on the configuration.

    Built once per batch (or once per sweep worker) and reused for every chunk: what follows
    from the constant S, Q^-1, the grasp matrix and its pseudo-inverses when the grasp does not
    move with the configuration, the object's inertia and gravity wrench, and the probed model
    of the Pinocchio pass.

    Args:
        robot: the loaded robot.
        task: task-space name or object; defaults to the spec's ``default_task``.
        object_mass: object mass (kg); defaults to the spec's.
        positions: also collect end-effector positions when the grasp does not need them.

    Raises:
        TaskError: unknown task, bad object mass, a robot without arms, or a task whose angular
            rows come before its linear ones.
    """

    def __init__(
        self,
        robot: Robot,
        task: str | TaskSpace | None = None,
        object_mass: float | None = None,
        positions: bool = False,
    ):
        task = get_task(task or robot.spec.default_task)
        mass = object_mass_of(robot, object_mass)
        mass = checked_object_mass(mass)  # a number within mobmanip.support.ranges.OBJECT_MASS
        self.robot = robot
        self.task = task
        self.mass = float(mass)
        self.rows = np.array(task.rows)
        self.m = task.dim
        self.k = len(robot.arms)
        if self.k == 0:
            raise TaskError(f"robot {robot.name!r} has no arms to analyse")
        self.nv = robot.model.nv
        self.nx = robot.nx
        self.n_eta = robot.platform.n_reduced
        rows = task.rows
        contiguous = tuple(rows) == tuple(range(rows[0], rows[0] + len(rows)))
        self.row_slice = slice(rows[0], rows[0] + len(rows)) if contiguous else None
        self.frame_ids = tuple(arm.frame_id for arm in robot.arms)
        self.probed = ProbedModel(robot.model, self.frame_ids)
        # Pinocchio 3 fills both triangles of M (the lower copied from the upper); older
        # versions fill only the upper one, which mass_matrix() reads.
        M0 = pin.crba(robot.model, robot.data, robot.neutral())
        self.crba_symmetric = bool(np.array_equal(M0, M0.T))
        model = robot.model
        self.frame_supports = []
        for f in self.frame_ids:
            support = np.zeros(self.nv)
            for j in model.supports[model.frames[f].parentJoint]:
                if j > 0:
                    joint = model.joints[j]
                    support[joint.idx_v : joint.idx_v + joint.nv] = 1.0
            self.frame_supports.append(support)
        # for the compiled kernel: supports (k, nv), task rows (linear first)
        self.supports = np.array(self.frame_supports, dtype=float).reshape(self.k, self.nv)
        self._constant_null_space(robot)
        self.task_rows = np.array(task.rows, dtype=np.int64)
        self.n_linear = int(np.sum(self.task_rows < 3))
        if np.any(self.task_rows[: self.n_linear] >= 3):
            raise TaskError(f"task {task.name!r} must list its linear rows before its angular rows")
        angular = task.angular
        self.angular = angular
        self.n_angular = int(angular.sum())
        self.linear_rows = np.array([r for r in task.rows if r < 3], dtype=int)
        self.angular_rows3 = np.array([r - 3 for r in task.rows if r >= 3], dtype=int)
        # The grasp moves with the configuration only if the task has rotation rows and several
        # end effectors (grasp blocks are the identity otherwise, and a single grasp has no offset).
        self.moving_grasp = bool(angular.any()) and self.k > 1
        self.need_positions = self.moving_grasp or positions
        g_full = np.zeros(6)
        g_full[:3] = -self.mass * GRAVITY
        self.g_o = g_full[self.rows]
        if self.moving_grasp:
            self.W = self.T = self.C = None
            self.Mo = None
        else:
            W = np.hstack([np.eye(self.m)] * self.k)
            self.W = W
            self.T = np.linalg.pinv(W.T)  # (W^T)^+, exactly as the single path
            self.W_pinv = np.linalg.pinv(W)
            self.C = null_basis(W)
            # No rotation rows, or one arm (offset 0, so the default object has no inertia).
            self.Mo = np.where(angular, 0.0, self.mass)

    def _constant_null_space(self, robot: Robot) -> None:
        """Everything derived from the platform's null-space matrix S (nv, nx) and Q = S^T B.

        This is the only place of the engine that reads S: S is the same at every
        configuration for every platform today, so it is compiled once into the products below.
        A platform whose S depends on q (a steered base) would compute these per row instead:
        the projections and ``S_csc`` per configuration, and the congruence plan over the
        structural nonzeros of S(q) (its pattern does not change with q).

        Raises:
            ModelError: the robot's S depends on q (not batched yet; ``analyze`` handles it).
        """
        if not robot.constant_null_space:
            raise ModelError(
                f"robot {robot.name!r} has {a_platform(robot.platform.kind)} whose S depends on q; batches and "
                "sweeps freeze S, so analyse its configurations one by one with mobmanip.analyze"
            )
        S = np.ascontiguousarray(robot.S, dtype=float)
        self.S = S
        self.projection = Projection(S)  # the NumPy path's J S and S^T M S
        Q = S.T @ robot.B
        self.Q_inv = None if np.array_equal(Q, np.eye(self.nx)) else np.linalg.inv(Q)
        self.Q_inv_kernel = np.zeros((0, 0)) if self.Q_inv is None else np.ascontiguousarray(self.Q_inv)
        # the compiled kernel's J S and S^T g: S column-compressed
        ptr, idx = [0], []
        for j in range(self.nx):
            idx.extend(np.flatnonzero(S[:, j]).tolist())
            ptr.append(len(idx))
        idx = np.array(idx, dtype=np.int64)
        # Index arrays are unsigned: Numba then skips the negative-index wraparound check on
        # every indirect access (it halves the cost of these gathers).
        self.S_csc = (
            np.array(ptr, dtype=np.uint64),
            idx.astype(np.uint64),
            S[idx, np.repeat(np.arange(self.nx), np.diff(ptr))],
        )
        # reduced coordinates that can move each end effector (J_u is zero elsewhere in its rows)
        moves = (self.supports @ (S != 0.0)) > 0.0  # (k, nx)
        self.arm_cols = np.zeros((self.k, self.nx), dtype=np.uint64)
        self.n_arm_cols = moves.sum(axis=1).astype(np.uint64)
        for a in range(self.k):
            self.arm_cols[a, : self.n_arm_cols[a]] = np.flatnonzero(moves[a])
        # ... and those that move two end effectors (the Gram's off-diagonal blocks)
        self.pair_cols = np.zeros((self.k, self.k, self.nx), dtype=np.uint64)
        self.n_pair_cols = np.zeros((self.k, self.k), dtype=np.uint64)
        for a in range(self.k):
            for b in range(self.k):
                both = np.flatnonzero(moves[a] & moves[b])
                self.pair_cols[a, b, : len(both)] = both
                self.n_pair_cols[a, b] = len(both)
        # the kernel's P = S^T M S: terms over M's structural nonzeros, indexed as the probed M
        ptr, p_rows, p_cols, p_u, p_w, *rest = congruence_plan(S, mass_matrix_pattern(robot.model))
        vmap = self.probed.vmap
        self.P_plan = (ptr, p_rows, p_cols, vmap[p_u.astype(int)], vmap[p_w.astype(int)], *rest)


def mass_matrix_pattern(model: pin.Model) -> np.ndarray:
    """Where M(q) may be nonzero, (nv, nv) bool: between degrees of freedom of joints one of
    which supports the other (M couples no two branches of the kinematic tree)."""
    pattern = np.zeros((model.nv, model.nv), dtype=bool)
    for j in range(1, model.njoints):
        dofs = slice(model.joints[j].idx_v, model.joints[j].idx_v + model.joints[j].nv)
        for i in model.supports[j]:
            if i > 0:
                ancestor = slice(model.joints[i].idx_v, model.joints[i].idx_v + model.joints[i].nv)
                pattern[dofs, ancestor] = pattern[ancestor, dofs] = True
    return pattern


def congruence_plan(S: np.ndarray, pattern: np.ndarray):
    """S^T M S as a list of terms over M's upper triangle where ``pattern`` (M's structural
    nonzeros) allows, for the kernel: listed entry e of P (row ``rows[e]`` <= column ``cols[e]``)
    is the sum over t in ptr[e] .. ptr[e+1] of coef[t] M[u[t], w[t]]; entries not listed are
    zero. Then P's nonzero columns per row, ``zidx[zptr[j]:zptr[j + 1]]``."""
    nx = S.shape[1]
    nz = [np.flatnonzero(S[:, j]) for j in range(nx)]
    ptr, rows, cols, us, ws, coefs = [0], [], [], [], [], []
    nonzero = np.zeros((nx, nx), dtype=bool)
    for a in range(nx):
        for b in range(a, nx):
            terms = [(u, w) for u in nz[a] for w in nz[b] if pattern[u, w]]
            if not terms:
                continue
            for u, w in terms:
                us.append(min(u, w))
                ws.append(max(u, w))
                coefs.append(S[u, a] * S[w, b])
            rows.append(a)
            cols.append(b)
            ptr.append(len(us))
            nonzero[a, b] = nonzero[b, a] = True
    zptr = np.concatenate([[0], np.cumsum(nonzero.sum(axis=1))])
    zidx = np.flatnonzero(nonzero.ravel()) % nx
    ints = (np.array(x, dtype=np.uint64) for x in (ptr, rows, cols, us, ws))
    return (*ints, np.array(coefs, dtype=float), zptr.astype(np.uint64), zidx.astype(np.uint64))


def null_basis(W: np.ndarray) -> np.ndarray:
    """Orthonormal basis of null(W), (cols, cols - rank)."""
    _, s, vt = np.linalg.svd(W)
    rank = int(np.sum(s > RANK_RTOL * max(s[0] if s.size else 0.0, 1.0)))
    return vt[rank:].T.copy()
