"""Analyse many configurations at once: the unified ellipsoids over an (N, nq) stack.

:func:`analyze_batch` gives the same ellipsoids as :func:`mobmanip.analysis.analyze` (to 1e-10
of each ellipsoid's size) for every row of a configuration array, several times faster per
configuration than the single path. Pinocchio is called once per configuration, for one CRBA
of the robot's model with massless probe joints added (:class:`ProbedModel`), which gives the
joint Jacobians, M, generalized gravity and the end-effector positions at once; everything else
runs stacked over the batch (in a compiled kernel or in NumPy), with constant
things (S, Q, W and its pseudo-inverses for grasps that do not move, the object's inertia and
gravity, the limits) computed once per batch in :class:`BatchSetup`.

Two stacked algorithms compute the ellipsoids:

* the *fast path*, for every row it can certify, uses the closed forms that hold when the
  unified Jacobian J has full row rank (the branch the single path takes too). Kinematic: with
  G_k = J_hat J_hat^T, T = (W^T)^+ and C a basis of null(W), the generator Z J_hat with
  Z = T - Y^T C^T, Y = (C^T G_k C)^-1 C^T G_k T^T, spans the ellipsoid (its Gram is the Schur
  complement that keeps the joint motions a rigid object can follow, stationary in Y). Dynamic:
  J^+ W^T = J^T (J J^T)^-1 W^T by Cholesky with one refinement step, L = Z Lambda_o, semi-axes
  from the eigenvectors of L^T L with Rayleigh quotients ||L v||^2, the centre -L^+ mu_bar with
  one least-squares refinement step. What remains per row is small: m x m eigenproblems and
  (m k) x (m k) Cholesky factors, vectorised over the stack.
* the *SVD path* mirrors :mod:`mobmanip.ellipsoids` branch by branch with stacked SVDs and
  pseudo-inverses (null spaces as masks over full SVD bases, so ranks may differ from row to
  row). It takes every row the fast path cannot certify: rank-deficient or ill-conditioned
  Jacobians (degenerate ellipsoids), dynamic ellipsoids at the edge of emptiness, and rows whose
  estimated fast-path error exceeds ``FAST_PATH_TOLERANCE``.

The split shows in the results only through :attr:`BatchAnalysis.svd_path`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .ellipsoids import Ellipsoid
from .errors import ConfigurationError, ModelError, TaskError
from .grasp import GRAVITY
from .model import Robot
from .tasks import TaskSpace, get_task

_RANK_RTOL = 1e-10  # the rank tolerance of mobmanip.ellipsoids
_FAST_RTOL = 1e-8  # its full-rank branches run while sigma_min > _FAST_RTOL sigma_max
_EPS = np.finfo(float).eps

#: Largest estimated fast-path error, relative to the ellipsoid's size, before a row is sent to
#: the SVD path. The estimate is a first-order worst-case bound from the condition numbers
#: involved (pessimistic by 10^2 .. 10^4). Over 20,000 random configurations per case (TIAGo++
#: and the paper's robot, several tasks, moving and locked platform, light and heavy objects),
#: the rows accepted at this setting differed from the SVD path by at most 1e-11 of the
#: ellipsoid's size, with identical flags; the tests check 1e-10 against the single path.
FAST_PATH_TOLERANCE = 1e-9

#: Ways to compute the ellipsoids (see :func:`analyze_batch`).
METHODS = ("auto", "numpy", "svd")

#: Configurations per internal chunk for the stacked NumPy paths: large enough to amortise
#: NumPy's per-call overhead, small enough for the workspaces to stay in cache.
DEFAULT_CHUNK = 2048

#: ... and for the compiled kernel, which runs right after Pinocchio on each chunk: small
#: enough for Pinocchio's outputs (M alone is 2.9 kB per TIAGo++ configuration) to stay in the
#: core's cache until the kernel reads them (about 1 us per configuration faster than 2048).
KERNEL_CHUNK = 256


def default_chunk(method: str = "auto") -> int:
    """Configurations per internal chunk for ``method`` (see :func:`analyze_batch`)."""
    return KERNEL_CHUNK if method == "auto" and kernel_available() else DEFAULT_CHUNK


# ----------------------------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class EllipsoidBatch:
    """N ellipsoids in an m-dimensional task space, as stacked arrays.

    Row n describes the same set as :class:`mobmanip.ellipsoids.Ellipsoid`:
    ``{center[n] + sum_k semi_axes[n, k] z_k axes[n, k] : ||z|| <= 1}``.

    Attributes:
        center: centres, (N, m).
        semi_axes: semi-axis lengths, descending, (N, m); zero where the task cannot move.
        axes: unit directions, ``axes[n, k]`` belongs to ``semi_axes[n, k]``, (N, m, m).
        matrix: A with (p - c)^T A (p - c) <= 1 (pseudo-inverse form when degenerate), (N, m, m).
        degenerate: some semi-axis is zero, (N,).
        empty: the limits cannot even hold the load still, (N,); semi-axes are then zero.
    """

    center: np.ndarray
    semi_axes: np.ndarray
    axes: np.ndarray
    matrix: np.ndarray
    degenerate: np.ndarray
    empty: np.ndarray

    def __len__(self) -> int:
        return int(self.semi_axes.shape[0])

    @property
    def dim(self) -> int:
        """Task dimension m."""
        return int(self.semi_axes.shape[1])

    @property
    def volume(self) -> np.ndarray:
        """Volumes, (N,): pi^(m/2) / Gamma(m/2 + 1) prod_k s_k."""
        m = self.dim
        return math.pi ** (m / 2) / math.gamma(m / 2 + 1) * np.prod(self.semi_axes, axis=1)

    @property
    def manipulability(self) -> np.ndarray:
        """Products of the semi-axes, (N,)."""
        return np.prod(self.semi_axes, axis=1)

    @property
    def isotropy(self) -> np.ndarray:
        """Smallest over largest semi-axis, (N,), 0 when degenerate or empty."""
        largest = self.semi_axes[:, 0]
        safe = np.where(largest > 0.0, largest, 1.0)
        return np.where(largest > 0.0, self.semi_axes[:, -1] / safe, 0.0)

    @property
    def generator(self) -> np.ndarray:
        """G with ellipsoid n = {c_n + G_n z : ||z|| <= 1}, (N, m, m)."""
        return np.swapaxes(self.axes, 1, 2) * self.semi_axes[:, None, :]

    def radius_along(self, direction: np.ndarray) -> np.ndarray:
        """How far each ellipsoid reaches from its centre along a direction (capacity), (N,).

        Args:
            direction: one direction for all rows, (m,), or one per row, (N, m); normalised here.
        """
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        along = np.einsum("nkj,...j->nk", self.axes, d) if d.ndim == 1 else np.einsum("nkj,nj->nk", self.axes, d)
        return np.sqrt(np.sum((along * self.semi_axes) ** 2, axis=1))

    def support(self, direction: np.ndarray) -> np.ndarray:
        """max over ellipsoid n of d . p, (N,), for one direction (m,) or one per row (N, m)."""
        d = np.asarray(direction, dtype=float)
        along = np.einsum("nkj,...j->nk", self.axes, d) if d.ndim == 1 else np.einsum("nkj,nj->nk", self.axes, d)
        offset = self.center @ d if d.ndim == 1 else np.einsum("nj,nj->n", self.center, d)
        return offset + np.sqrt(np.sum((along * self.semi_axes) ** 2, axis=1))

    def __getitem__(self, index: int) -> Ellipsoid:
        """Row ``index`` as a single :class:`~mobmanip.ellipsoids.Ellipsoid`."""
        return Ellipsoid(
            center=self.center[index].copy(),
            semi_axes=self.semi_axes[index].copy(),
            axes=self.axes[index].copy(),
            matrix=self.matrix[index].copy(),
            degenerate=bool(self.degenerate[index]),
            empty=bool(self.empty[index]),
        )

    @classmethod
    def allocate(cls, n: int, m: int) -> EllipsoidBatch:
        return cls(
            center=np.zeros((n, m)),
            semi_axes=np.zeros((n, m)),
            axes=np.zeros((n, m, m)),
            matrix=np.zeros((n, m, m)),
            degenerate=np.zeros(n, dtype=bool),
            empty=np.zeros(n, dtype=bool),
        )

    def _put(self, rows, other: EllipsoidBatch) -> None:
        self.center[rows] = other.center
        self.semi_axes[rows] = other.semi_axes
        self.axes[rows] = other.axes
        self.matrix[rows] = other.matrix
        self.degenerate[rows] = other.degenerate
        self.empty[rows] = other.empty


@dataclass(frozen=True)
class BatchAnalysis:
    """The ellipsoids at every configuration of a batch (robot and object at rest).

    Attributes:
        robot: the robot analysed (with its platform and limits).
        qs: configurations, (N, nq).
        task: task-space name.
        decoupled: whether the dynamic ellipsoids used the decoupled P.
        object_mass: mass of the held object (kg).
        kinematic: the unified kinematic ellipsoids (m/s, rad/s).
        dynamic: the unified dynamic ellipsoids (m/s^2, rad/s^2).
        end_effector_positions: world positions of the end effectors, (N, n_arms, 3), when the
            grasp needed them (tasks with rotation and several arms) or they were asked for;
            otherwise ``None``.
        svd_path: rows whose kinematic or dynamic ellipsoid took the SVD path, (N,).
    """

    robot: Robot
    qs: np.ndarray
    task: str
    decoupled: bool
    object_mass: float
    kinematic: EllipsoidBatch
    dynamic: EllipsoidBatch
    end_effector_positions: np.ndarray | None
    svd_path: np.ndarray

    def __len__(self) -> int:
        return int(self.qs.shape[0])

    @property
    def object_centers(self) -> np.ndarray | None:
        """Object centres (the centroid of the end effectors), (N, 3), or ``None``."""
        p = self.end_effector_positions
        return None if p is None else p.mean(axis=1)


# ----------------------------------------------------------------------------------------------
# what stays constant over a batch


class _Projection:
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
        self.runs = []
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

    Built once per batch (or once per sweep worker) and reused for every chunk: the constant
    S, Q^-1, the grasp matrix and its pseudo-inverses when the grasp does not move with the
    configuration, the object's inertia and gravity wrench, and reusable Pinocchio workspaces.

    Args:
        robot: the loaded robot.
        task: task-space name or object; defaults to the spec's ``default_task``.
        object_mass: object mass (kg); defaults to the spec's.
        positions: also collect end-effector positions when the grasp does not need them.
    """

    def __init__(
        self,
        robot: Robot,
        task: str | TaskSpace | None = None,
        object_mass: float | None = None,
        positions: bool = False,
    ):
        task = get_task(task or robot.spec.default_task)
        mass = robot.spec.object_mass if object_mass is None else object_mass
        if isinstance(mass, bool) or not isinstance(mass, (int, float)) or not np.isfinite(mass) or mass < 0:
            raise TaskError(f"object mass must be a finite non-negative number of kg, got {mass!r}")
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
        self.S = np.ascontiguousarray(robot.S, dtype=float)
        self.projection = _Projection(self.S)
        rows = task.rows
        contiguous = tuple(rows) == tuple(range(rows[0], rows[0] + len(rows)))
        self.row_slice = slice(rows[0], rows[0] + len(rows)) if contiguous else None
        self.frame_ids = tuple(arm.frame_id for arm in robot.arms)
        self.probed = ProbedModel(robot.model, self.frame_ids)
        # Pinocchio 3 fills both triangles of M (the lower copied from the upper); older
        # versions fill only the upper one, which mass_matrix() reads.
        M0 = pin.crba(robot.model, robot.data, robot.neutral())
        self.crba_symmetric = bool(np.array_equal(M0, M0.T))
        Q = robot.S.T @ robot.B
        self.Q_inv = None if np.array_equal(Q, np.eye(self.nx)) else np.linalg.inv(Q)
        model = robot.model
        self.frame_supports = []
        for f in self.frame_ids:
            support = np.zeros(self.nv)
            for j in model.supports[model.frames[f].parentJoint]:
                if j > 0:
                    joint = model.joints[j]
                    support[joint.idx_v : joint.idx_v + joint.nv] = 1.0
            self.frame_supports.append(support)
        # for the compiled kernel: supports (k, nv), S column-compressed, task rows (linear first)
        self.supports = np.array(self.frame_supports, dtype=float).reshape(self.k, self.nv)
        ptr, idx = [0], []
        for j in range(self.nx):
            idx.extend(np.flatnonzero(self.S[:, j]).tolist())
            ptr.append(len(idx))
        idx = np.array(idx, dtype=np.int64)
        # Index arrays are unsigned: Numba then skips the negative-index wraparound check on
        # every indirect access (it halves the cost of these gathers).
        self.S_csc = (
            np.array(ptr, dtype=np.uint64),
            idx.astype(np.uint64),
            self.S[idx, np.repeat(np.arange(self.nx), np.diff(ptr))],
        )
        # reduced coordinates that can move each end effector (J_u is zero elsewhere in its rows)
        moves = (self.supports @ (self.S != 0.0)) > 0.0  # (k, nx)
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
        # P's terms index M over the robot's degrees of freedom; the kernel reads the probed M
        ptr, p_rows, p_cols, p_u, p_w, *rest = _congruence_plan(self.S, _mass_matrix_pattern(model))
        vmap = self.probed.vmap
        self.P_plan = (ptr, p_rows, p_cols, vmap[p_u.astype(int)], vmap[p_w.astype(int)], *rest)
        self.task_rows = np.array(task.rows, dtype=np.int64)
        self.n_linear = int(np.sum(self.task_rows < 3))
        if np.any(self.task_rows[: self.n_linear] >= 3):
            raise TaskError(f"task {task.name!r} must list its linear rows before its angular rows")
        self.Q_inv_kernel = np.zeros((0, 0)) if self.Q_inv is None else np.ascontiguousarray(self.Q_inv)
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
            self.C = _null_basis(W)
            # No rotation rows, or one arm (offset 0, so the default object has no inertia).
            self.Mo = np.where(angular, 0.0, self.mass)


def _mass_matrix_pattern(model: pin.Model) -> np.ndarray:
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


def _congruence_plan(S: np.ndarray, pattern: np.ndarray):
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


def _null_basis(W: np.ndarray) -> np.ndarray:
    """Orthonormal basis of null(W), (cols, cols - rank)."""
    _, s, vt = np.linalg.svd(W)
    rank = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1.0)))
    return vt[rank:].T.copy()


# ----------------------------------------------------------------------------------------------
# Pinocchio: once per configuration


class ProbedModel:
    """The robot's model with massless *probe* joints, so that one CRBA call per configuration
    gives everything the batch needs from Pinocchio.

    CRBA in the world convention leaves the world joint Jacobians in ``data.J`` beside M. Two
    kinds of probes, which carry no mass and sit at q = 0, make the other per-configuration
    calls unnecessary:

    * a prismatic joint along -g at the root, carrying the whole robot: its row of M is
      sum_b m_b dc_b/dq (the robot's momentum along it), so generalized gravity is
      ``g = |g| M[0, v]``;
    * two revolute joints at each end-effector frame, about its x and y axes: a revolute
      joint's world Jacobian column is (p x w, w) for its position p and unit axis w, and
      w x (p x w) = p - w (w . p), so the two columns give the frame's position (see
      :func:`_frame_positions`).

    Probes change neither the robot's Jacobians nor its M: its degrees of freedom are columns
    ``vmap`` of the probed model's (the probes go right after their parent's subtree, keeping
    every subtree contiguous as CRBA requires), its configuration entries ``qmap``.
    """

    def __init__(self, model: pin.Model, frame_ids):
        gravity = np.asarray(model.gravity.linear, dtype=float)
        self.gravity = float(np.linalg.norm(gravity))
        axis = -gravity / self.gravity if self.gravity > 0.0 else np.array([0.0, 0.0, 1.0])
        probed = pin.Model()
        probed.name = model.name
        root = probed.addJoint(0, pin.JointModelPrismaticUnaligned(axis), pin.SE3.Identity(), "mobmanip_gravity_probe")
        # each frame's probes follow the last joint of its parent joint's subtree
        after: dict[int, list[int]] = {}
        for a, f in enumerate(frame_ids):
            parent = model.frames[f].parentJoint
            after.setdefault(max(model.subtrees[parent]) if parent > 0 else model.njoints - 1, []).append(a)
        new_id = {0: root}
        probe_ids = [None] * len(frame_ids)

        def add_probes(last: int) -> None:
            for a in after.get(last, ()):
                frame = model.frames[frame_ids[a]]
                probe_ids[a] = [
                    probed.addJoint(new_id[frame.parentJoint], joint, frame.placement, f"mobmanip_probe_{a}_{axis}")
                    for axis, joint in (("x", pin.JointModelRX()), ("y", pin.JointModelRY()))
                ]

        add_probes(0)
        for j in range(1, model.njoints):
            parent = new_id[model.parents[j]]
            try:
                new_id[j] = probed.addJoint(parent, model.joints[j], model.jointPlacements[j], model.names[j])
            except Exception as error:  # a joint type Pinocchio's bindings cannot copy
                name, kind = model.names[j], model.joints[j].shortname()
                raise ModelError(f"joint {name!r} ({kind}) cannot be copied for the batch pass: {error}") from None
            probed.appendBodyToJoint(new_id[j], model.inertias[j], pin.SE3.Identity())
            add_probes(j)
        self.vmap = np.zeros(model.nv, dtype=np.uint64)
        self.qmap = np.zeros(model.nq, dtype=np.int64)
        for j in range(1, model.njoints):
            old, new = model.joints[j], probed.joints[new_id[j]]
            self.vmap[old.idx_v : old.idx_v + old.nv] = np.arange(new.idx_v, new.idx_v + new.nv)
            self.qmap[old.idx_q : old.idx_q + old.nq] = np.arange(new.idx_q, new.idx_q + new.nq)
        armature = np.zeros(probed.nv)
        armature[self.vmap.astype(int)] = model.armature
        probed.armature = armature
        self.probe_cols = np.array([[probed.joints[j].idx_v for j in ids] for ids in probe_ids], dtype=np.uint64)
        self.model = probed
        self.data = probed.createData()
        self.nv = model.nv

    def robot_jacobians(self, Jw: np.ndarray) -> np.ndarray:
        """The robot's world joint Jacobians (n, 6, nv) from the probed model's."""
        return Jw[..., self.vmap.astype(int)]

    def robot_mass_matrices(self, M: np.ndarray) -> np.ndarray:
        """The robot's M (n, nv, nv) from the probed model's."""
        v = self.vmap.astype(int)
        return M[:, v[:, None], v]

    def gravity_torques(self, M: np.ndarray) -> np.ndarray:
        """Generalized gravity (n, nv) from the probed model's M."""
        return self.gravity * M[:, 0, self.vmap.astype(int)]

    def frame_positions(self, Jw: np.ndarray) -> np.ndarray:
        """End-effector positions (n, k, 3) from the probe columns of the world Jacobians."""
        return _frame_positions(Jw[..., self.probe_cols[:, 0].astype(int)], Jw[..., self.probe_cols[:, 1].astype(int)])


def _frame_positions(x_cols: np.ndarray, y_cols: np.ndarray) -> np.ndarray:
    """Positions p (n, k, 3) from the world Jacobian columns (n, 6, k) of revolute joints at p
    about two orthogonal unit axes w_x, w_y: a = w_x x v_x = p - w_x (w_x . p) lacks only p's
    component along w_x, which b = w_y x v_y keeps: p = a + w_x (w_x . b)."""
    vx, wx = np.swapaxes(x_cols[:, :3], 1, 2), np.swapaxes(x_cols[:, 3:], 1, 2)
    vy, wy = np.swapaxes(y_cols[:, :3], 1, 2), np.swapaxes(y_cols[:, 3:], 1, 2)
    a = np.cross(wx, vx)
    b = np.cross(wy, vy)
    return a + wx * np.sum(wx * b, axis=-1, keepdims=True)


class _Terms:
    """One chunk's per-configuration quantities.

    Pinocchio's outputs for the probed model (views into the chunk's workspace, valid until the
    next chunk): world joint Jacobians ``Ja`` (n, 6, nv_p) and mass matrices ``Ma``. The
    end-effector positions ``positions`` (n, k, 3) and the derived terms -- J_u, P, xi and the
    grasp (W, T, C, M_o diagonal; ``None`` for a grasp that does not move) -- come either from
    the compiled kernel (rows it could not certify are all that is needed after it) or from
    stacked NumPy (:func:`_numpy_terms`), whichever ran first.
    """

    __slots__ = ("n", "Ja", "Ma", "positions", "J_u", "P", "xi", "W", "T", "C", "Mo", "_gram")

    def __init__(self, n, Ja, Ma, positions):
        self.n, self.Ja, self.Ma, self.positions = n, Ja, Ma, positions
        self.J_u = self.P = self.xi = self.W = self.T = self.C = self.Mo = self._gram = None

    def __len__(self) -> int:
        return self.n

    def gram(self):
        """(J^T contiguous, solver B -> (J J^T)^-1 B, an upper bound on kappa_2(J J^T)), cached."""
        if self._gram is None:
            Jt = np.ascontiguousarray(np.swapaxes(self.J_u, 1, 2))
            Gu = self.J_u @ Jt
            solve, inv_norm = _spd_solver(Gu)
            self._gram = (Jt, solve, _fro(Gu) * inv_norm)
        return self._gram


def _pinocchio_pass(setup: BatchSetup, qs: np.ndarray, ws: _Workspace, n: int) -> None:
    """Fill the workspace's first n rows from Pinocchio: one CRBA call per configuration of the
    probed model (:class:`ProbedModel`), in the world convention, which also leaves the world
    joint Jacobians in ``data.J``."""
    probed = setup.probed
    model, data = probed.model, probed.data
    ws.q[:n, probed.qmap] = qs[:n]
    rows = zip(ws.q_rows[:n], ws.M_rows[:n], ws.J_rows[:n])  # views made once: cheaper than indexing
    crba = pin.crba
    if _WORLD is None:  # an older Pinocchio: one more call
        jacobians = pin.computeJointJacobians
        for q, M, Jw in rows:
            M[...] = crba(model, data, q)
            Jw[...] = jacobians(model, data, q)
        return
    J = data.J  # a view of Pinocchio's buffer, refreshed by every crba call below
    world = _WORLD
    for q, M, Jw in rows:
        M[...] = crba(model, data, q, world)
        Jw[...] = J


_WORLD = getattr(getattr(pin, "Convention", None), "WORLD", None)


def _frame_jacobians(setup: BatchSetup, Jw: np.ndarray, pos: np.ndarray, out: np.ndarray) -> None:
    """LOCAL_WORLD_ALIGNED frame Jacobians from world joint Jacobians (n, 6, nv) and frame
    positions (n, k, 3): linear rows v_O + omega x p, columns outside the frame's support zeroed
    (as ``pin.getFrameJacobian``)."""
    w = Jw[:, 3:, :]
    for a, support in enumerate(setup.frame_supports):
        p = pos[:, a, :, None]
        out[:, a, 0] = Jw[:, 0] + w[:, 1] * p[:, 2] - w[:, 2] * p[:, 1]
        out[:, a, 1] = Jw[:, 1] + w[:, 2] * p[:, 0] - w[:, 0] * p[:, 2]
        out[:, a, 2] = Jw[:, 2] + w[:, 0] * p[:, 1] - w[:, 1] * p[:, 0]
        out[:, a, 3:] = w
        out[:, a] *= support


class _Workspace:
    """Reusable buffers for the Pinocchio pass of one chunk size."""

    def __init__(self, setup: BatchSetup, n: int):
        probed = setup.probed.model
        self.n = n
        self.q = np.zeros((n, probed.nq))  # the probes' entries stay 0
        self.Ma = np.zeros((n, probed.nv, probed.nv))
        self.Ja = np.zeros((n, 6, probed.nv))
        self.pos = np.zeros((n, setup.k, 3))
        self.q_rows, self.M_rows, self.J_rows = list(self.q), list(self.Ma), list(self.Ja)


def _terms(setup: BatchSetup, qs: np.ndarray, ws: _Workspace) -> _Terms:
    n = qs.shape[0]
    _pinocchio_pass(setup, qs, ws, n)
    return _Terms(n, ws.Ja[:n], ws.Ma[:n], ws.pos[:n])


def _numpy_terms(setup: BatchSetup, t: _Terms) -> None:
    """J_u, P, xi and the grasp of a chunk, stacked in NumPy (when the kernel has not run)."""
    if t.J_u is not None:
        return
    n, proj, nv, m, k, probed = t.n, setup.projection, setup.nv, setup.m, setup.k, setup.probed
    t.positions[...] = probed.frame_positions(t.Ja)
    J6 = np.empty((n, k, 6, nv))
    _frame_jacobians(setup, probed.robot_jacobians(t.Ja), t.positions, J6)
    M = probed.robot_mass_matrices(t.Ma)
    J = J6[:, :, setup.row_slice, :] if setup.row_slice is not None else J6[:, :, setup.rows, :]
    t.J_u = proj.right(J.reshape(n, k * m, nv))
    if not setup.crba_symmetric:  # M from the upper triangle, as mobmanip.dynamics.mass_matrix
        M = np.triu(M) + np.swapaxes(np.triu(M, 1), 1, 2)
    P = proj.left_transpose(proj.right(M))
    t.P = 0.5 * (P + np.swapaxes(P, 1, 2))
    t.xi = -proj.right(probed.gravity_torques(t.Ma))
    if setup.moving_grasp:
        t.W, t.T, t.C, t.Mo = _moving_grasp(setup, t.positions)


def _moving_grasp(setup: BatchSetup, pos: np.ndarray):
    """W, (W^T)^+, a basis of null(W) and diag(M_o) per configuration, for grasps with offsets.

    The object is centred at the centroid of the end effectors (as
    :meth:`mobmanip.grasp.HeldObject.between`), a uniform sphere reaching the farthest grasp.
    Task rows are ordered linear then angular, so each grasp block is W_i = [[I, 0], [K_i, I]]
    with K_i the angular-by-linear part of skew(r_i); W_k^-1 = [[I, 0], [-K_k, I]] gives the
    null-space basis in closed form, and W W^T = [[k I, S^T], [S, k I + sum K_i K_i^T]]
    (S = sum K_i, zero up to rounding) is inverted blockwise.
    """
    n, k, m = pos.shape[0], setup.k, setup.m
    nl = m - setup.n_angular
    center = pos.mean(axis=1)
    offsets = pos - center[:, None, :]
    rx, ry, rz = offsets[..., 0], offsets[..., 1], offsets[..., 2]
    skew = np.zeros((n, k, 3, 3))
    skew[:, :, 0, 1], skew[:, :, 0, 2] = -rz, ry
    skew[:, :, 1, 0], skew[:, :, 1, 2] = rz, -rx
    skew[:, :, 2, 0], skew[:, :, 2, 1] = -ry, rx
    K = skew[:, :, setup.angular_rows3][:, :, :, setup.linear_rows]  # (n, k, na, nl)
    blocks = np.zeros((n, k, m, m))
    blocks[:, :, np.arange(m), np.arange(m)] = 1.0
    blocks[:, :, nl:, :nl] = K
    W = np.swapaxes(blocks, 1, 2).reshape(n, m, k * m)
    # (W W^T)^-1 by blocks
    Ks = K.sum(axis=1)  # (n, na, nl)
    D = k * np.eye(m - nl) + np.einsum("nkal,nkbl->nab", K, K) - (Ks @ np.swapaxes(Ks, 1, 2)) / k
    Di = np.linalg.inv(D)
    E = -(Di @ Ks) / k  # (n, na, nl)
    WWt_inv = np.empty((n, m, m))
    WWt_inv[:, :nl, :nl] = np.eye(nl) / k - (np.swapaxes(Ks, 1, 2) @ E) / k
    WWt_inv[:, :nl, nl:] = np.swapaxes(E, 1, 2)
    WWt_inv[:, nl:, :nl] = E
    WWt_inv[:, nl:, nl:] = Di
    T = WWt_inv @ W
    # null(W): h_k = -W_k^-1 (W_1 h_1 + ... + W_{k-1} h_{k-1}); W_k^-1 W_i = [[I, 0], [K_i - K_k, I]]
    C = np.zeros((n, k * m, (k - 1) * m))
    C[:, : (k - 1) * m, :] = np.eye((k - 1) * m)
    for i in range(k - 1):
        C[:, (k - 1) * m + np.arange(m), i * m + np.arange(m)] = -1.0
        C[:, (k - 1) * m + nl : k * m, i * m : i * m + nl] = -(K[:, i] - K[:, k - 1])
    radius2 = np.max(np.sum(offsets**2, axis=2), axis=1)
    Mo = np.where(setup.angular[None, :], 0.4 * setup.mass * radius2[:, None], setup.mass)
    return W, T, C, Mo


# ----------------------------------------------------------------------------------------------
# fast path


def _pick(mask: np.ndarray):
    """Index for the rows of a mask: everything (a cheap view) when all are set."""
    return Ellipsis if mask.all() else mask


def _rows_view(out: EllipsoidBatch, rows: slice) -> EllipsoidBatch:
    """Views of rows ``rows`` (a slice) of every array of ``out``."""
    return EllipsoidBatch(
        out.center[rows], out.semi_axes[rows], out.axes[rows], out.matrix[rows], out.degenerate[rows], out.empty[rows]
    )


def _sym_eigh(A: np.ndarray):
    """Stacked eigh of the symmetric part; rows with non-finite entries give NaN."""
    A = 0.5 * (A + np.swapaxes(A, 1, 2))
    finite = np.isfinite(A).all(axis=(1, 2))
    if finite.all():
        return np.linalg.eigh(A)
    A[~finite] = np.eye(A.shape[-1])
    lam, V = np.linalg.eigh(A)
    lam[~finite] = np.nan
    return lam, V


def _safe_inv(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stacked inverse that does not raise: exactly singular rows get NaN (and True in the mask)."""
    try:
        return np.linalg.inv(A), np.zeros(A.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        singular = ~(np.linalg.det(A) != 0.0)  # LU hit an exact zero pivot (or det under/overflowed)
        B = A.copy()
        B[singular] = np.eye(A.shape[-1])
        inv = np.linalg.inv(B)
        inv[singular] = np.nan
        return inv, singular


def _lower_inverse(L: np.ndarray) -> np.ndarray:
    """Stacked inverse of lower-triangular matrices by forward substitution, vectorised over the
    stack (LAPACK's per-matrix calls cost more than the arithmetic at these sizes)."""
    n = L.shape[-1]
    X = np.zeros_like(L)
    d = 1.0 / np.diagonal(L, axis1=1, axis2=2)
    for i in range(n):
        if i:
            X[:, i, :i] = -(L[:, i : i + 1, :i] @ X[:, :i, :i])[:, 0, :] * d[:, i, None]
        X[:, i, i] = d[:, i]
    return X


def _spd_solver(A: np.ndarray):
    """A solver B -> A^-1 B for a stack of symmetric positive definite A, and ||A^-1||_F (an upper
    bound). Cholesky when every matrix admits it, else a plain inverse (singular rows give NaN)."""
    try:
        Li = _lower_inverse(np.linalg.cholesky(A))
    except np.linalg.LinAlgError:
        Ai, _ = _safe_inv(A)
        return (lambda B: Ai @ B), _fro(Ai)
    LiT = np.ascontiguousarray(np.swapaxes(Li, 1, 2))
    return (lambda B: LiT @ (Li @ B)), np.einsum("nij,nij->n", Li, Li)


def _fro(A: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("nij,nij->n", A, A))


def _kinematic_fast(setup: BatchSetup, t: _Terms, vlim: np.ndarray, out: EllipsoidBatch, rows: slice):
    """Kinematic ellipsoids of the rows it can certify; returns the mask of the other rows.

    With J_hat of full row rank, the object velocities are v_o = T J_hat z for the joint motions
    z whose end-effector velocities a rigid object can follow (C^T J_hat z = 0, C a basis of
    null(W)). The generator G = Z J_hat with Z = T - Y^T C^T, Y = (C^T G_k C)^-1 C^T G_k T^T,
    spans the same ellipsoid (G G^T is the Schur complement of C^T G_k C). G G^T is stationary in
    Y, so the conditioning of C^T G_k C enters only to second order.
    """
    Jh = t.J_u * vlim
    # The single path takes its full-rank branch when sigma_min(J_hat) > 1e-8 sigma_max(J_hat);
    # certify it with margin: kappa(J_hat) <= kappa(J) max(vlim) / min(vlim) < 1e6.
    kappa_J = np.sqrt(t.gram()[2])
    with np.errstate(invalid="ignore"):
        branch = kappa_J * (np.max(vlim) / np.min(vlim)) < 1e-2 / _FAST_RTOL
    if setup.k == 1:
        G = Jh
        hard = ~branch
        z_norm = 1.0
    else:
        Gk = Jh @ np.swapaxes(Jh, 1, 2)
        T = setup.T if t.T is None else t.T
        C = setup.C if t.C is None else t.C
        Tt, Ct = np.swapaxes(T, -1, -2), np.swapaxes(C, -1, -2)
        GC = Gk @ C
        KK = Ct @ GC  # C^T G_k C
        X = np.swapaxes(GC, 1, 2) @ Tt  # C^T G_k T^T
        KKi, _ = _safe_inv(KK)
        Y = KKi @ X
        Z = T - np.swapaxes(Y, 1, 2) @ Ct
        G = Z @ Jh
        kk_norm, kki_norm = _fro(KK), _fro(KKi)
        kappa = kk_norm * kki_norm
        with np.errstate(divide="ignore", invalid="ignore"):
            second_order = kk_norm * (_EPS * kappa * _fro(Y)) ** 2
        hard = ~np.isfinite(kappa) | (kappa > 1e12) | ~branch
        z_norm = _fro(Z)
    B = G @ np.swapaxes(G, 1, 2)
    lam, V = _sym_eigh(B)
    lmin, lmax = lam[:, 0], lam[:, -1]
    with np.errstate(invalid="ignore", divide="ignore"):
        err = 8.0 * _EPS * (z_norm * _fro(Jh) * _fro(G) + _fro(B))
        if setup.k > 1:
            err = err + second_order
        # error of the smallest semi-axis relative to the largest: err / (2 s_min s_max)
        est = err / (2.0 * np.sqrt(np.abs(lmin * lmax)))
        ok = (
            ~hard
            & (lmin > (1e-2 / _FAST_RTOL) ** -2 * lmax)
            & (lmin > 0.0)
            & np.isfinite(est)
            & (est <= FAST_PATH_TOLERANCE)
        )
    o, k = _rows_view(out, rows), _pick(ok)
    lam_ok, V_ok = lam[k], V[k]
    o.semi_axes[k] = np.sqrt(lam_ok[:, ::-1])
    o.axes[k] = np.swapaxes(V_ok[:, :, ::-1], 1, 2)
    o.matrix[k] = (V_ok / lam_ok[:, None, :]) @ np.swapaxes(V_ok, 1, 2)
    o.center[k] = 0.0
    o.degenerate[k] = False
    o.empty[k] = False
    return ~ok


def _dynamic_fast(
    setup: BatchSetup, t: _Terms, P: np.ndarray, elim: np.ndarray, out: EllipsoidBatch, rows: slice
) -> np.ndarray:
    """Dynamic ellipsoids of the rows it can certify; returns the mask of the other rows.

    With J of full row rank, J^+ W^T = J^T (J J^T)^-1 W^T (one step of iterative refinement
    brings its error from eps kappa(J)^2 to about eps kappa(J)), so Lambda_o and mu_o follow
    from small products; the ellipsoid {a : ||L a + mu_bar|| <= 1} (L = Z Lambda_o) has centre
    c = -L^+ mu_bar (normal equations plus one refinement step), rho^2 = 1 - ||L c + mu_bar||^2
    and semi-axes sqrt(rho^2 / lambda_k) along the eigenvectors of L^T L, with lambda_k taken as
    the Rayleigh quotients ||L v_k||^2.
    """
    J_u = t.J_u
    Jt, solve, kappa = t.gram()  # kappa < 1e12: the single path's full-rank branch (1e-8) with margin
    T = setup.T if t.T is None else t.T
    Tt = np.swapaxes(T, -1, -2)  # W^+ = ((W^T)^+)^T for W of full row rank
    Wt = np.swapaxes(setup.W if t.W is None else t.W, -1, -2)
    JpWt = Jt @ solve(Wt)  # J^+ W^T, (n, nx, m)
    JpWt = JpWt + Jt @ solve(Wt - J_u @ JpWt)  # one step of refinement
    Mo = setup.Mo if t.Mo is None else t.Mo
    WpMo = Tt * (Mo[None, :] if Mo.ndim == 1 else Mo[:, None, :])
    Lam = P @ JpWt + Jt @ WpMo
    Wpg = Tt @ setup.g_o  # (km,) or (n, km)
    mu = -t.xi + (np.einsum("nij,j->ni", Jt, Wpg) if Wpg.ndim == 1 else np.einsum("nij,nj->ni", Jt, Wpg))
    if setup.Q_inv is not None:
        Lam = setup.Q_inv @ Lam
        mu = mu @ setup.Q_inv.T
    Z = 1.0 / elim
    L = Lam * Z[:, None]
    mub = mu * Z
    H = np.swapaxes(L, 1, 2) @ L
    lam, V = _sym_eigh(H)
    LV = L @ V
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lam_rq = np.einsum("nij,nij->nj", LV, LV)  # Rayleigh quotients ||L v||^2
        Hinv = (V / lam_rq[:, None, :]) @ np.swapaxes(V, 1, 2)
        y = np.einsum("nij,ni->nj", L, mub)
        c = -np.einsum("nij,nj->ni", Hinv, y)
        r = mub + np.einsum("nij,nj->ni", L, c)
        c = c - np.einsum("nij,nj->ni", Hinv, np.einsum("nij,ni->nj", L, r))  # one refinement step
        r = mub + np.einsum("nij,nj->ni", L, c)
        outside2 = np.einsum("ni,ni->n", r, r)
        rho2 = 1.0 - outside2
        lmin, lmax = np.min(lam_rq, axis=1), np.max(lam_rq, axis=1)
        aniso = np.sqrt(lmax / lmin)
        mub2 = np.einsum("ni,ni->n", mub, mub)
        # error of L relative to its smallest singular value: the relative error of the
        # largest semi-axis; and what it does to rho^2 and to the centre
        err_l = 8.0 * _EPS * (1.0 + np.sqrt(kappa) + _EPS * kappa**2) * aniso
        err_rho2 = 2.0 * np.sqrt(outside2 * mub2) * err_l + 8.0 * _EPS * mub2
        c_norm = np.sqrt(np.einsum("ni,ni->n", c, c))
        scale = np.maximum(np.sqrt(np.abs(rho2) / lmin), c_norm)
        err_c = err_l * (c_norm + np.sqrt(outside2 / lmin)) / scale
        ok = (
            np.isfinite(kappa)
            & (kappa < 1e12)
            & (lmin > 0.0)
            & np.isfinite(aniso)
            & (aniso < 1e-2 / _FAST_RTOL)
            & (err_l <= FAST_PATH_TOLERANCE)
            & (err_c <= FAST_PATH_TOLERANCE)
            & (err_rho2 <= 2.0 * FAST_PATH_TOLERANCE * np.abs(rho2))
        )
        empty = ok & (rho2 <= 0.0)
        full = ok & ~empty
        lam_sorted, V_sorted = lam_rq, V
        if not np.all(lam_rq[:, :-1] <= lam_rq[:, 1:]):  # Rayleigh quotients out of eigh's order
            order = np.argsort(lam_rq, axis=1)  # ascending eigenvalue = descending semi-axis
            lam_sorted = np.take_along_axis(lam_rq, order, axis=1)
            V_sorted = np.take_along_axis(V, order[:, None, :], axis=2)
    o, f = _rows_view(out, rows), _pick(full)
    rho2_full = rho2[f]
    o.semi_axes[f] = np.sqrt(rho2_full[:, None] / lam_sorted[f])
    o.axes[f] = np.swapaxes(V_sorted[f], 1, 2)
    o.matrix[f] = H[f] / rho2_full[:, None, None]
    o.center[_pick(ok)] = c[_pick(ok)]
    o.degenerate[f] = False
    o.empty[f] = False
    if empty.any():
        o.semi_axes[empty] = 0.0
        o.axes[empty] = np.eye(setup.m)
        o.matrix[empty] = 0.0
        o.degenerate[empty] = True
        o.empty[empty] = True
    return ~ok


# ----------------------------------------------------------------------------------------------
# SVD path: mobmanip.ellipsoids, stacked


def _from_generators(center: np.ndarray, G: np.ndarray, empty: np.ndarray) -> EllipsoidBatch:
    """Stacked :meth:`Ellipsoid.from_generator`: centres (n, m), generators (n, m, d >= 1)."""
    n, m = center.shape
    U, s, _ = np.linalg.svd(G, full_matrices=True)
    semi = np.zeros((n, m))
    k = min(m, s.shape[1])
    semi[:, :k] = s[:, :k]
    scale = np.maximum(semi[:, 0], 1e-300)
    semi[semi <= _RANK_RTOL * scale[:, None]] = 0.0
    semi[empty] = 0.0
    positive = semi > 0.0
    inverse = np.where(positive, 1.0 / np.where(positive, semi, 1.0) ** 2, 0.0)
    matrix = (U * inverse[:, None, :]) @ np.swapaxes(U, 1, 2)
    return EllipsoidBatch(
        center=center,
        semi_axes=semi,
        axes=np.swapaxes(U, 1, 2).copy(),
        matrix=matrix,
        degenerate=np.any(~positive, axis=1),
        empty=np.asarray(empty, dtype=bool).copy(),
    )


def _null_mask(A: np.ndarray, n_cols: int):
    """Stacked null spaces of A (n, r, n_cols): the full right basis (n, n_cols, n_cols) with the
    columns outside the null space zeroed, and the rank per row (as ellipsoids._null_space)."""
    _, s, vt = np.linalg.svd(A, full_matrices=True)
    scale = np.maximum(s[:, 0] if s.shape[1] else np.zeros(A.shape[0]), 1.0)
    rank = np.sum(s > _RANK_RTOL * scale[:, None], axis=1)
    mask = np.arange(n_cols)[None, :] >= rank[:, None]
    return np.swapaxes(vt, 1, 2) * mask[:, None, :], rank


def _kinematic_svd(J_u: np.ndarray, W: np.ndarray, vlim: np.ndarray) -> EllipsoidBatch:
    """Stacked :func:`mobmanip.ellipsoids.kinematic_ellipsoid` (both of its branches, row by row);
    W is (m, mk) or (n, m, mk)."""
    n, km, nx = J_u.shape
    m = W.shape[-2]
    J_hat = J_u * vlim
    U, s, _ = np.linalg.svd(J_hat, full_matrices=False)
    out = EllipsoidBatch.allocate(n, m)
    general = np.ones(n, dtype=bool)
    if s.shape[1] == km:
        full = s[:, -1] > _FAST_RTOL * s[:, 0]
        if full.any():
            B = ((W if W.ndim == 2 else W[full]) @ U[full]) / s[full][:, None, :]
            # A = B B^T; its eigenvectors come from the SVD of B, which keeps the large semi-axes
            # (small singular values of B) accurate where eigh(A) would square their conditioning.
            Ub, sb, _ = np.linalg.svd(B, full_matrices=False)
            ok = sb[:, -1] > 0.0
            rows = np.flatnonzero(full)[ok]
            out.semi_axes[rows] = 1.0 / sb[ok][:, ::-1]
            out.axes[rows] = np.swapaxes(Ub[ok][:, :, ::-1], 1, 2)
            out.matrix[rows] = (B @ np.swapaxes(B, 1, 2))[ok]
            general[rows] = False
    if general.any():
        Jg = J_hat[general]
        Wg = W if W.ndim == 2 else W[general]
        Wt = np.swapaxes(Wg, -1, -2)
        Wt_pinv = np.linalg.pinv(Wt)
        inconsistent = Jg - Wt @ (Wt_pinv @ Jg)
        N, _ = _null_mask(inconsistent, nx)
        out._put(general, _from_generators(np.zeros((Jg.shape[0], m)), Wt_pinv @ Jg @ N, np.zeros(len(Jg), bool)))
    return out


def _dynamic_svd(
    J_u: np.ndarray,
    W: np.ndarray,
    P: np.ndarray,
    Q_inv: np.ndarray | None,
    xi: np.ndarray,
    Mo: np.ndarray,
    g_o: np.ndarray,
    elim: np.ndarray,
    row_labels: np.ndarray,
) -> EllipsoidBatch:
    """Stacked :func:`mobmanip.ellipsoids.dynamic_ellipsoid` (both of its branches, row by row);
    W is (m, mk) or (n, m, mk), M_o given by its diagonal (m,) or (n, m)."""
    n, km, nx = J_u.shape
    m = W.shape[-2]
    Z = 1.0 / elim
    U, s, Vt = np.linalg.svd(J_u, full_matrices=False)
    r = s.shape[1]
    out = EllipsoidBatch.allocate(n, m)
    general = np.ones(n, dtype=bool)

    def pick(A, rows):
        return A if A.ndim == 2 else A[rows]

    def lam_mu(rows, J_pinv, W_pinv):
        Jr, Wr = J_u[rows], pick(W, rows)
        Jt = np.swapaxes(Jr, 1, 2)
        M_o = (Mo if Mo.ndim == 1 else Mo[rows])[..., None, :] * np.eye(m)
        Lam = P[rows] @ (J_pinv @ np.swapaxes(Wr, -1, -2)) + Jt @ (W_pinv @ M_o)
        Wpg = W_pinv @ g_o
        mu = -xi[rows] + (np.einsum("nij,j->ni", Jt, Wpg) if Wpg.ndim == 1 else np.einsum("nij,nj->ni", Jt, Wpg))
        if Q_inv is not None:
            Lam, mu = Q_inv @ Lam, mu @ Q_inv.T
        return Lam, Z * mu

    if r == km:
        full = np.flatnonzero(s[:, -1] > _FAST_RTOL * s[:, 0])
        if full.size:
            J_pinv = (np.swapaxes(Vt[full], 1, 2) / s[full][:, None, :]) @ np.swapaxes(U[full], 1, 2)
            Wf = pick(W, full)
            W_pinv = np.swapaxes(np.linalg.solve(Wf @ np.swapaxes(Wf, -1, -2), Wf), -1, -2)
            Lam, mu_bar = lam_mu(full, J_pinv, W_pinv)
            L = Z[:, None] * Lam
            UL, sL, VtL = np.linalg.svd(L, full_matrices=False)
            ok = sL[:, -1] > _FAST_RTOL * sL[:, 0]
            if ok.any():
                along = np.einsum("nij,ni->nj", UL[ok], mu_bar[ok])
                center = -np.einsum("nji,nj->ni", VtL[ok], along / sL[ok])
                mu2 = np.einsum("ni,ni->n", mu_bar[ok], mu_bar[ok])
                rho2 = 1.0 - np.maximum(mu2 - np.einsum("ni,ni->n", along, along), 0.0)
                nonempty = rho2 > 0.0
                rows = full[ok]
                out.center[rows] = center
                semi = np.sqrt(np.maximum(rho2, 0.0))[:, None] / sL[ok]
                out.semi_axes[rows] = np.where(nonempty[:, None], semi[:, ::-1], 0.0)
                out.axes[rows] = np.where(nonempty[:, None, None], VtL[ok][:, ::-1], np.eye(m))
                ratio = np.where(nonempty, (sL[ok] ** 2).T / np.where(nonempty, rho2, 1.0), 0.0).T
                out.matrix[rows] = (np.swapaxes(VtL[ok], 1, 2) * ratio[:, None, :]) @ VtL[ok]
                out.degenerate[rows] = ~nonempty
                out.empty[rows] = ~nonempty
                general[rows] = False
    rows = np.flatnonzero(general)
    if rows.size == 0:
        return out
    # Range of J and J^+ from one SVD with one rank decision (as the single path).
    Ug, sg, Vtg = U[rows], s[rows], Vt[rows]
    rank = np.sum(sg > _RANK_RTOL * np.maximum(sg[:, 0], 1e-300)[:, None], axis=1)
    keep = np.arange(r)[None, :] < rank[:, None]
    s_inv = np.where(keep, 1.0 / np.where(keep, sg, 1.0), 0.0)
    U_r = Ug * keep[:, None, :]
    J_pinv = (np.swapaxes(Vtg, 1, 2) * s_inv[:, None, :]) @ np.swapaxes(Ug, 1, 2)
    Wg = pick(W, rows)
    W_pinv = np.linalg.pinv(Wg)
    Wt = np.swapaxes(Wg, -1, -2)
    N, nrank = _null_mask(Wt - U_r @ (np.swapaxes(U_r, 1, 2) @ Wt), m)
    d = m - nrank
    Lam, mu_bar = lam_mu(rows, J_pinv, W_pinv)
    L = Z[:, None] * (Lam @ N)
    UL, sL, VtL = np.linalg.svd(L, full_matrices=False)
    rL = sL.shape[1]
    dd = np.minimum(d, rL)
    valid = np.arange(rL)[None, :] < dd[:, None]
    has = dd > 0
    last = np.take_along_axis(sL, np.maximum(dd - 1, 0)[:, None], axis=1)[:, 0]
    massless = has & (last <= _RANK_RTOL * np.maximum(sL[:, 0], 1e-300))
    if massless.any():
        row = int(row_labels[rows[np.flatnonzero(massless)[0]]])
        raise ModelError(
            f"configuration row {row}: an object acceleration needs no joint torque: "
            "the model has moving links without mass or inertia"
        )
    along = np.where(valid, np.einsum("nij,ni->nj", UL, mu_bar), 0.0)
    mu2 = np.einsum("ni,ni->n", mu_bar, mu_bar)
    outside2 = np.maximum(mu2 - np.einsum("ni,ni->n", along, along), 0.0)
    sL_inv = np.where(valid, 1.0 / np.where(valid, sL, 1.0), 0.0)
    NV = N @ np.swapaxes(VtL, 1, 2)
    center = -np.einsum("nij,nj->ni", NV, along * sL_inv)
    rho2 = 1.0 - outside2
    empty = np.where(has, rho2 <= 0.0, np.sqrt(mu2) >= 1.0)
    center[~has] = 0.0
    G = NV * (np.sqrt(np.maximum(rho2, 0.0))[:, None] * sL_inv)[:, None, :]
    G[empty | ~has] = 0.0
    out._put(rows, _from_generators(center, G, empty))
    return out


# ----------------------------------------------------------------------------------------------
# public entry points


def check_configurations(robot: Robot, qs) -> np.ndarray:
    """Return qs as a C-contiguous float array (N, nq) after checking its shape and finiteness.

    Raises:
        ConfigurationError: wrong shape, or a NaN/infinite entry (named by row and joint).
    """
    try:
        qs = np.ascontiguousarray(qs, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ConfigurationError(f"configurations must be a numeric (N, {robot.model.nq}) array: {exc}") from None
    nq = robot.model.nq
    if qs.ndim != 2 or qs.shape[1] != nq:
        raise ConfigurationError(f"configurations must have shape (N, {nq}), got {qs.shape}")
    finite = np.isfinite(qs)
    if not finite.all():
        row, index = (int(i) for i in np.argwhere(~finite)[0])
        model = robot.model
        joint = next(
            j
            for j in range(1, model.njoints)
            if model.joints[j].idx_q <= index < model.joints[j].idx_q + model.joints[j].nq
        )
        raise ConfigurationError(
            f"configuration row {row}, entry {index} (joint {model.names[joint]!r}) is {float(qs[row, index])!r}"
        )
    return qs


def _decouple(setup: BatchSetup, P: np.ndarray) -> np.ndarray:
    out = P.copy()
    e = setup.n_eta
    out[:, :e, e:] = 0.0
    out[:, e:, :e] = 0.0
    return out


def _limits(values, default: np.ndarray, kind: str) -> np.ndarray:
    if values is None:
        return np.asarray(default, dtype=float)
    arr = np.asarray(values, dtype=float)
    if arr.shape != default.shape or not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise ConfigurationError(f"{kind} limits must be {default.shape[0]} positive finite numbers, got {values!r}")
    return arr


def ellipsoids_from_terms(
    setup: BatchSetup,
    t: _Terms,
    *,
    velocity_limits: np.ndarray | None = None,
    effort_limits: np.ndarray | None = None,
    decoupled: bool = False,
    kinematic: EllipsoidBatch | None = None,
    dynamic: EllipsoidBatch | None = None,
    offset: int = 0,
    method: str = "auto",
    backlog: _SvdBacklog | None = None,
) -> np.ndarray:
    """Fill ``kinematic``/``dynamic`` rows ``offset .. offset + n`` from one chunk's terms.

    Either output may be ``None`` to skip that ellipsoid. ``method``: ``"auto"`` (the compiled
    kernel when Numba is available, else the stacked NumPy fast path; rows neither certifies go
    to the SVD path), ``"numpy"`` (stacked NumPy fast path, then SVD path) or ``"svd"``.
    With a ``backlog``, the SVD path's rows are queued there instead of computed now (its
    :meth:`_SvdBacklog.flush` computes them, for every chunk at once). Returns the chunk's
    SVD-path mask (n,).
    """
    n = t.n
    rows = np.arange(offset, offset + n)
    block = slice(offset, offset + n)
    vlim = _limits(velocity_limits, setup.robot.velocity_limits, "velocity")
    elim = _limits(effort_limits, setup.robot.effort_limits, "effort")
    bad_kin = bad_dyn = None
    if method == "auto" and kernel_available():
        bad_kin, bad_dyn = _kernel_fast(setup, t, vlim, elim, decoupled, kinematic, dynamic, block)
    else:
        _numpy_terms(setup, t)
    svd_rows = np.zeros(n, dtype=bool)
    if kinematic is not None:
        if bad_kin is None:
            bad_kin = np.ones(n, dtype=bool) if method == "svd" else _kinematic_fast(setup, t, vlim, kinematic, block)
        if bad_kin.any():
            W = setup.W if t.W is None else t.W[bad_kin]
            if backlog is not None:
                backlog.kinematic.append((rows[bad_kin], t.J_u[bad_kin], _per_row(W, int(bad_kin.sum()), 3), vlim))
            else:
                kinematic._put(rows[bad_kin], _kinematic_svd(t.J_u[bad_kin], W, vlim))
        svd_rows |= bad_kin
    if dynamic is not None:
        if bad_dyn is None:
            if method == "svd":
                bad_dyn = np.ones(n, dtype=bool)
            else:
                P = _decouple(setup, t.P) if decoupled else t.P
                bad_dyn = _dynamic_fast(setup, t, P, elim, dynamic, block)
        if bad_dyn.any():
            W = setup.W if t.W is None else t.W[bad_dyn]
            Mo = setup.Mo if t.Mo is None else t.Mo[bad_dyn]
            P = _decouple(setup, t.P[bad_dyn]) if decoupled else t.P[bad_dyn]
            J_u, xi, count = t.J_u[bad_dyn], t.xi[bad_dyn], int(bad_dyn.sum())
            if backlog is not None:
                W, Mo = _per_row(W, count, 3), _per_row(Mo, count, 2)
                backlog.dynamic.append((rows[bad_dyn], J_u, W, P, xi, Mo, elim))
            else:
                result = _dynamic_svd(J_u, W, P, setup.Q_inv, xi, Mo, setup.g_o, elim, rows[bad_dyn])
                dynamic._put(rows[bad_dyn], result)
        svd_rows |= bad_dyn
    return svd_rows


def _per_row(A: np.ndarray, count: int, ndim: int) -> np.ndarray:
    """``count`` rows of A: a per-row array (``ndim`` dimensions) as it is, a constant repeated."""
    return A if A.ndim == ndim else np.broadcast_to(A, (count, *A.shape))


def _same_limits(items: list[tuple]):
    """Concatenate consecutive queued items (tuples of per-row arrays, then their limits) that
    share limits; yields (per-row arrays..., limits)."""
    start = 0
    for end in range(1, len(items) + 1):
        if end == len(items) or not np.array_equal(items[end][-1], items[start][-1]):
            group = items[start:end]
            fields = zip(*(item[:-1] for item in group))
            yield (*(np.concatenate(f) for f in fields), group[0][-1])
            start = end


class _SvdBacklog:
    """Rows of several chunks left to the SVD path, computed together by :meth:`flush`: the
    stacked SVD path costs about as much for one row as for fifty (NumPy's per-call overhead),
    and only a few rows per thousand need it."""

    def __init__(self, setup: BatchSetup):
        self.setup = setup
        self.kinematic: list[tuple] = []
        self.dynamic: list[tuple] = []

    def flush(self, kinematic: EllipsoidBatch | None, dynamic: EllipsoidBatch | None) -> None:
        """Compute the queued rows into ``kinematic`` / ``dynamic`` (one stacked call per run of
        items with the same limits) and empty the queue."""
        setup = self.setup
        for rows, J_u, W, vlim in _same_limits(self.kinematic):
            kinematic._put(rows, _kinematic_svd(J_u, W, vlim))
        for rows, J_u, W, P, xi, Mo, elim in _same_limits(self.dynamic):
            dynamic._put(rows, _dynamic_svd(J_u, W, P, setup.Q_inv, xi, Mo, setup.g_o, elim, rows))
        self.kinematic.clear()
        self.dynamic.clear()


def kernel_available() -> bool:
    """Whether the compiled kernel (:mod:`mobmanip._kernel`, needs Numba) can run here."""
    return _kernel_module() is not None


@functools.cache
def _kernel_module():
    try:
        from . import _kernel
    except ImportError:  # Numba missing or unusable on this platform: the NumPy paths remain
        return None
    return _kernel


def _kernel_fast(
    setup, t, vlim, elim, decoupled, kinematic, dynamic, block, offsets=None, Mo=None, grasp=False, all_terms=False
):
    """Run the compiled kernel on a chunk: fills the accepted rows of the outputs and t's terms
    (J_u, P, xi and, for a moving grasp, W and M_o's diagonal) for the rows left to the SVD
    path (the other rows' terms are left undefined unless ``all_terms``). Returns the
    kinematic and dynamic masks of those rows (``None`` where not asked), then, with
    ``grasp``, W and M_o (of every row only with ``all_terms``).

    ``offsets`` (k, 3) and ``Mo`` (m, m) describe an explicit object instead of the default one
    (a sphere centred between the end effectors); its mass is ``setup.mass``."""
    n, m, k, nx = t.n, setup.m, setup.k, setup.nx
    J_u = np.empty((n, k * m, nx))
    P = np.empty((n, nx, nx))
    xi = np.empty((n, nx))
    W = np.empty((n, m, k * m))
    Mo_rows = np.empty((n, m, m))
    kin = kinematic if kinematic is not None else EllipsoidBatch.allocate(0, m)
    dyn = dynamic if dynamic is not None else EllipsoidBatch.allocate(0, m)
    kin_b = block if kinematic is not None else slice(0, 0)
    dyn_b = block if dynamic is not None else slice(0, 0)
    kin_ok = np.zeros(n, dtype=bool)
    dyn_ok = np.zeros(n, dtype=bool)
    dyn_empty = np.zeros(n if dynamic is not None else 0, dtype=bool)
    ptr, idx, val = setup.S_csc
    probed = setup.probed
    _kernel_module().run_chunk(
        (0,) * k,  # sizes as tuple lengths: compile-time constants for the kernel
        (0,) * m,
        t.Ja,
        t.Ma,
        probed.vmap,
        probed.gravity,
        probed.probe_cols,
        t.positions,
        setup.supports,
        setup.arm_cols,
        setup.n_arm_cols,
        setup.pair_cols,
        setup.n_pair_cols,
        setup.task_rows,
        setup.n_linear,
        ptr,
        idx,
        val,
        *setup.P_plan,
        setup.Q_inv_kernel,
        np.ascontiguousarray(vlim, dtype=float),
        np.ascontiguousarray(elim, dtype=float),
        _NO_OFFSETS if offsets is None else offsets,
        _NO_MO if Mo is None else Mo,
        setup.mass,
        np.ascontiguousarray(setup.g_o, dtype=float),
        setup.n_eta if decoupled else 0,
        kinematic is not None,
        dynamic is not None,
        all_terms,
        J_u,
        P,
        xi,
        W,
        Mo_rows,
        kin.center[kin_b],
        kin.semi_axes[kin_b],
        kin.axes[kin_b],
        kin.matrix[kin_b],
        kin_ok,
        dyn.center[dyn_b],
        dyn.semi_axes[dyn_b],
        dyn.axes[dyn_b],
        dyn.matrix[dyn_b],
        dyn_ok,
        dyn_empty,
    )
    t.J_u, t.P, t.xi = J_u, P, xi
    if setup.moving_grasp:
        t.W, t.Mo = W, np.diagonal(Mo_rows, axis1=1, axis2=2)
    bad_kin = bad_dyn = None
    if kinematic is not None:
        kinematic.degenerate[block][kin_ok] = False
        kinematic.empty[block][kin_ok] = False
        bad_kin = ~kin_ok
    if dynamic is not None:
        dynamic.empty[block][dyn_ok] = dyn_empty[dyn_ok]
        dynamic.degenerate[block][dyn_ok] = dyn_empty[dyn_ok]
        bad_dyn = ~dyn_ok
    if grasp:
        return bad_kin, bad_dyn, W, Mo_rows
    return bad_kin, bad_dyn


_NO_OFFSETS = np.zeros((0, 3))
_NO_MO = np.zeros((0, 0))


def iter_terms(setup: BatchSetup, qs: np.ndarray, chunk_size: int = DEFAULT_CHUNK):
    """Yield ``(start, terms)`` for consecutive chunks of a checked (N, nq) array."""
    ws = _Workspace(setup, min(chunk_size, max(qs.shape[0], 1)))
    for start in range(0, qs.shape[0], chunk_size):
        yield start, _terms(setup, qs[start : start + chunk_size], ws)


def analyze_batch(
    robot: Robot,
    qs,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
    positions: bool = False,
    chunk_size: int | None = None,
    method: str = "auto",
) -> BatchAnalysis:
    """Analyse the robot at every row of ``qs`` (robot and object at rest).

    The results equal :func:`mobmanip.analysis.analyze` row by row (to about 1e-10 of each
    ellipsoid's size; axes up to sign), including the ``degenerate`` and ``empty`` flags.

    Args:
        robot: the loaded robot (``robot.with_platform("fixed")`` locks the platform;
            ``robot.with_wheel_limits(...)`` changes the wheel limits).
        qs: configurations, (N, nq); each row as :meth:`Robot.configuration` builds it.
        task: task space name; defaults to the spec's ``default_task``.
        object_mass: mass of the default object held by all end effectors at their centroid (kg);
            defaults to the spec's.
        decoupled: use the decoupled P (no platform-arm interaction) for the dynamic ellipsoids.
        positions: also return the end-effector positions (always returned when the grasp needs
            them: several arms and a task with rotation).
        chunk_size: configurations per internal chunk (memory use is proportional to it);
            default: :func:`default_chunk` of the method.
        method: ``"auto"`` (the fast path compiled per configuration, see :mod:`mobmanip._kernel`,
            falling back to ``"numpy"`` without Numba; SVD path for the rows it cannot certify),
            ``"numpy"`` (the same fast path stacked in NumPy, then the SVD path) or ``"svd"``
            (SVD path for every row, the stacked mirror of :mod:`mobmanip.ellipsoids`).

    Raises:
        ConfigurationError: ``qs`` is not (N, nq) or has a NaN/infinite entry (named by row and
            joint).
        TaskError: unknown task or bad object mass.
        ModelError: a configuration where an object acceleration needs no torque (massless links).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if chunk_size is None:
        chunk_size = default_chunk(method)
    if not isinstance(chunk_size, int) or chunk_size < 1:
        raise ValueError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    qs = check_configurations(robot, qs)
    setup = BatchSetup(robot, task, object_mass, positions=positions)
    n, m = qs.shape[0], setup.m
    kin, dyn = EllipsoidBatch.allocate(n, m), EllipsoidBatch.allocate(n, m)
    svd_rows = np.zeros(n, dtype=bool)
    pos = np.zeros((n, setup.k, 3)) if setup.need_positions else None
    backlog = _SvdBacklog(setup)
    for start, t in iter_terms(setup, qs, chunk_size):
        stop = start + t.n
        svd_rows[start:stop] = ellipsoids_from_terms(
            setup, t, decoupled=decoupled, kinematic=kin, dynamic=dyn, offset=start, method=method, backlog=backlog
        )
        if pos is not None:
            pos[start:stop] = t.positions
    backlog.flush(kin, dyn)
    return BatchAnalysis(
        robot=robot,
        qs=qs,
        task=setup.task.name,
        decoupled=decoupled,
        object_mass=setup.mass,
        kinematic=kin,
        dynamic=dyn,
        end_effector_positions=pos,
        svd_path=svd_rows,
    )
