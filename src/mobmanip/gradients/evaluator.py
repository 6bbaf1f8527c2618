"""Analytic gradients of the ellipsoids' measures with respect to the configuration.

The gradient is taken in Pinocchio's tangent space (see :mod:`mobmanip.gradients.derivatives`): entry k
is the derivative of the measure along ``pin.integrate(model, q, e * e_k)``; for the planar root
joint that is the platform's motion in its own frame (v_x, v_y, omega_z), for a joint its angle.
:func:`platform_gradient` turns the root joint's entries into world x, y and heading.

Each ellipsoid is {c + G z : ||z|| <= 1}; the measures depend on its centre c and its shape
C = G G^T (m x m; the semi-axes are the square roots of C's eigenvalues):

- ``log_volume``: log of the volume, log(V_m) + 1/2 log det C (V_m the unit m-ball's volume);
- ``log_isotropy``: a smooth isotropy, 1/m log det C - log(tr C / m) = log of the geometric over
  the arithmetic mean of the squared semi-axes; 0 for a ball, below 0 otherwise;
- ``capacity``: how far the set reaches along a unit direction d, d . c + sqrt(d^T C d) (the
  sweeps' capacity, ``TaskSet.support``);
- ``minor_axis``: the smallest semi-axis, the worst-direction capacity about the centre (smooth
  where the smallest eigenvalue of C is simple).

The ellipsoids, where the unified Jacobian J_u has full row rank (else a measure is not
differentiable; see :attr:`GradientBatch.defined`), are

- kinematic: C = (W (J_hat J_hat^T)^-1 W^T)^-1, J_hat = J_u diag(qdot_max), c = 0;
- dynamic: with L = Z Lambda_o and mu_bar = Z mu_o (:mod:`mobmanip.sets.ellipsoid`),
  ``C = rho^2 (L^T L)^-1`` and ``c = -(L^T L)^-1 L^T mu_bar``, ``rho^2 = 1 - |mu_bar|^2 - mu_bar^T L c``;
  empty (not differentiable) when rho^2 <= 0.

:meth:`GradientEvaluator.batch` (and ``__call__``) run the chain in reverse
(:mod:`mobmanip.gradients.adjoint`, contractions with the configuration in closed form by
:mod:`mobmanip.gradients.tree_adjoint`), where every joint kind has those closed forms; otherwise, and in
:meth:`GradientEvaluator.forward_chunk` and :meth:`GradientEvaluator.shape`, the derivatives follow
forwards by the product rule from dJ_u/dq (frame Hessians), dP/dq = S^T dM/dq S,
dxi/dq = -S^T dg/dq and, for the default object held between the hands, the derivatives of the
grasp matrix W and the object inertia M_o through the hands' positions. S must not depend on q
(every platform kind but ``steered``). An explicit :class:`mobmanip.terms.grasp.HeldObject` is taken
as given (its W, M_o, g_o constant), as :func:`mobmanip.analysis.analyze` takes it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError, MeasureError, ModelError, TaskError
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task
from ..terms.grasp import HeldObject, object_mass_of
from .adjoint import gradient_chunk
from .derivatives import ConfigurationDerivatives, DerivativeWorkspace
from .rank import guarded
from .rank import svd_full_rank as full_rank
from .tree_adjoint import TreeAdjoint

#: The ellipsoids with gradients.
ELLIPSOIDS = ("kinematic", "dynamic")
#: The measures of an ellipsoid with gradients.
INDICES = ("log_volume", "log_isotropy", "capacity", "minor_axis")
#: The blocks of task rows an objective can be taken on (one unit each).
BLOCKS = ("linear", "angular")


@dataclass(frozen=True)
class Objective:
    """A differentiable measure of one ellipsoid.

    Attributes:
        ellipsoid: ``"kinematic"`` or ``"dynamic"``.
        index: one of :data:`INDICES`.
        direction: unit task direction for ``capacity``, (m,); ``None`` otherwise.
        block: ``"linear"`` or ``"angular"``: the index of the set's shadow on those task rows
            (one unit: m/s or rad/s), as ``analyze`` reports per block; ``None``: the whole set.
        rows: the task rows of ``block`` (set by :meth:`parse` from the task), or ``None``.
    """

    ellipsoid: str
    index: str
    direction: tuple[float, ...] | None = None
    text: str | None = field(default=None, compare=False)
    block: str | None = None
    rows: tuple[int, ...] | None = None

    def __post_init__(self):
        if self.ellipsoid not in ELLIPSOIDS:
            raise MeasureError(
                f"objective measure {self.ellipsoid!r} has no gradient; gradients exist for {', '.join(ELLIPSOIDS)}"
            )
        if self.index not in INDICES:
            raise MeasureError(
                f"objective {self.index!r} is not known for the {self.ellipsoid} ellipsoid; "
                f"expected one of {', '.join(INDICES)}"
            )
        if self.index == "capacity":
            if self.direction is None:
                raise ArgumentError("objective 'capacity' needs a direction")
            d = np.asarray(self.direction, dtype=float).reshape(-1)
            norm = float(np.linalg.norm(d))
            if not np.all(np.isfinite(d)) or norm == 0.0:
                raise ArgumentError(f"capacity direction must be finite and nonzero, got {list(self.direction)!r}")
            object.__setattr__(self, "direction", tuple(float(v) for v in d / norm))
        elif self.direction is not None:
            raise ArgumentError(f"objective {self.index!r} takes no direction, got {list(self.direction)!r}")
        if self.block is not None:
            if self.block not in BLOCKS:
                raise ArgumentError(f"block must be one of {', '.join(BLOCKS)}, got {self.block!r}")
            if self.index == "capacity":
                raise ArgumentError("a capacity's direction already picks its rows; it takes no block")
            if not self.rows:
                raise ArgumentError(f"objective block {self.block!r} needs its task rows")
            object.__setattr__(self, "rows", tuple(int(i) for i in self.rows))
        elif self.rows is not None:
            raise ArgumentError("task rows are given by a block (linear or angular)")

    @property
    def measure_name(self) -> str:
        """The measure whose set the objective reads: its ellipsoid."""
        return self.ellipsoid

    def whole(self) -> Objective:
        """The same objective of the whole set (no block)."""
        return Objective(self.ellipsoid, self.index, self.direction)

    @property
    def name(self) -> str:
        """``ellipsoid:index`` (and ``:d1,d2,...`` for a capacity), or the text it was parsed from."""
        if self.text is not None:
            return self.text
        tail = "" if self.direction is None else ":" + ",".join(f"{v:g}" for v in self.direction)
        if self.block is not None:
            tail = f":{self.block}"
        return f"{self.ellipsoid}:{self.index}{tail}"

    @classmethod
    def parse(cls, text: str, task: str | TaskSpace) -> Objective:
        """An objective from ``ELLIPSOID:INDEX[:DIRECTION]`` or ``ELLIPSOID:INDEX:BLOCK``.

        DIRECTION is a signed task axis (``+x``, ``-z``, ``+yaw``; the task's axis labels) or
        comma-separated components (``1,1,0``). BLOCK is ``linear`` or ``angular``: the index of
        the set's shadow on the task's linear (m/s, m/s^2) or angular (rad/s, rad/s^2) rows, as
        ``analyze`` reports per block (``dynamic:minor_axis:linear``).

        Raises:
            MeasureError: an unknown ellipsoid or index (the message lists the known ones).
            ArgumentError: a malformed or missing direction.
        """
        task = get_task(task)
        parts = str(text).split(":")
        if len(parts) not in (2, 3):
            raise ArgumentError(f"objective must be ELLIPSOID:INDEX[:DIRECTION], got {text!r}")
        if len(parts) == 3 and parts[2].strip() in BLOCKS:
            block = parts[2].strip()
            rows = task.linear_rows if block == "linear" else task.angular_rows
            if not rows:
                raise ArgumentError(f"objective {text!r}: task {task.name!r} has no {block} rows")
            if parts[1] == "capacity":
                raise ArgumentError(f"objective {text!r}: a capacity needs a direction, not a block")
            return cls(parts[0], parts[1], None, text=str(text), block=block, rows=tuple(rows))
        direction = None if len(parts) == 2 else _parse_direction(parts[2], task)
        if direction is None and parts[1:2] == ["capacity"]:
            raise ArgumentError(f"objective {text!r}: a capacity needs a direction, e.g. {parts[0]}:capacity:+x")
        return cls(parts[0], parts[1], direction, text=str(text))

    def check_task(self, task: TaskSpace) -> None:
        """Raises ArgumentError when the capacity direction does not have the task's dimension, or
        the block's rows are not the task's rows of that kind."""
        if self.block is not None:
            rows = task.linear_rows if self.block == "linear" else task.angular_rows
            if tuple(rows) != self.rows:
                raise ArgumentError(f"objective {self.name!r}: task {task.name!r} has {self.block} rows {list(rows)}")
        if self.direction is not None and len(self.direction) != task.dim:
            raise ArgumentError(
                f"capacity direction {list(self.direction)!r} has {len(self.direction)} components; "
                f"task {task.name!r} has {task.dim} ({', '.join(task.labels)})"
            )


def _parse_direction(text: str, task: TaskSpace) -> tuple[float, ...]:
    text = text.strip()
    if text[:1] in "+-" and text[1:] in task.labels:
        d = [0.0] * task.dim
        d[task.labels.index(text[1:])] = 1.0 if text[0] == "+" else -1.0
        return tuple(d)
    try:
        return tuple(float(v) for v in text.split(","))
    except ValueError:
        axes = ", ".join(f"{sign}{label}" for label in task.labels for sign in "+-")
        example = ",".join(["1"] + ["0"] * (task.dim - 1))
        raise ArgumentError(
            f"direction {text!r} is neither a signed axis of the {task.name} task ({axes}) nor {task.dim} numbers "
            f"like {example}"
        ) from None


@dataclass(frozen=True)
class GradientBatch:
    """Values and tangent-space gradients of one objective at N configurations.

    Attributes:
        objective: the objective.
        value: its value per configuration, (N,); 0 where not ``defined``.
        gradient: d value / d q in the tangent space, (N, nv); 0 where not ``defined``.
        defined: whether the measure is differentiable there (J_u of full row rank, the dynamic
            ellipsoid not empty), (N,).
    """

    objective: Objective
    value: np.ndarray
    gradient: np.ndarray
    defined: np.ndarray


class GradientEvaluator:
    """Evaluates one objective and its gradient for one robot, task and object.

    Args:
        robot: the loaded robot; its platform's S must not depend on q.
        objective: the objective (an :class:`Objective` or its text form, :meth:`Objective.parse`).
        task: task space; default the spec's.
        object_mass: mass (kg) of the default object held between the hands (defaults to the
            spec's); ignored with ``held_object``.
        held_object: an explicit object, taken as constant.
        decoupled: the decoupled P (no platform-arm interaction) for the dynamic ellipsoid.
        compiled: the reverse chain's compiled row loops (``True``), its NumPy forms
            (``False``), or the loops where Numba is available (``None``); as
            :class:`mobmanip.gradients.tree_adjoint.TreeAdjoint`'s. The two agree to round-off.

    Raises:
        ModelError: a platform whose S depends on the configuration (``steered``).
        MeasureError, ArgumentError: an unknown objective or a bad direction.
    """

    def __init__(
        self,
        robot: Robot,
        objective: Objective | str,
        task: str | TaskSpace | None = None,
        *,
        object_mass: float | None = None,
        held_object: HeldObject | None = None,
        decoupled: bool = False,
        compiled: bool | None = None,
    ):
        if not robot.constant_null_space:
            raise ModelError(
                f"gradients need a constant null-space matrix S; platform {robot.platform.kind!r} "
                "has one that depends on q"
            )
        self.robot = robot
        self.task = get_task(task or robot.spec.default_task)
        self.objective = objective if isinstance(objective, Objective) else Objective.parse(objective, self.task)
        self.objective.check_task(self.task)
        self.decoupled = decoupled
        self.workspace = DerivativeWorkspace(robot, self.task)
        if held_object is not None:
            if held_object.offsets.shape != (len(robot.arms), 3):
                raise TaskError(
                    f"the object needs one grasp offset per arm ({len(robot.arms)}), got {held_object.offsets.shape}"
                )
            mass = held_object.mass
        else:
            mass = object_mass_of(robot, object_mass)
        self.mass = float(mass)
        self.held_object = held_object
        #: W, M_o, g_o of a constant object per chunk size (:meth:`_object_terms`), with its key.
        self._constant_object: tuple | None = None
        self.S = robot.S
        #: S as a C-contiguous float array (the compiled row loops' argument).
        self.S_contiguous = np.ascontiguousarray(robot.S, dtype=float)
        self.Q = robot.Q
        self.Q_identity = bool(np.array_equal(self.Q, np.eye(self.Q.shape[0])))
        self.velocity_limits = np.asarray(robot.velocity_limits, dtype=float)
        self.Z = 1.0 / np.asarray(robot.effort_limits, dtype=float)
        self.evaluations = 0
        self.tree: TreeAdjoint | None
        try:  # the reverse chain's closed forms, where every joint kind has them
            self.tree = TreeAdjoint(robot.model, [arm.frame_id for arm in robot.arms], compiled=compiled)
        except ModelError:
            self.tree = None

    # ----- public -----

    def __call__(self, q: np.ndarray) -> tuple[float, np.ndarray, bool]:
        """(value, gradient (nv,), defined) at configuration q, (nq,)."""
        q = self.robot.check_configuration(q)
        out = self._chunk(q[None, :])
        return float(out[0][0]), out[1][0], bool(out[2][0])

    def batch(self, qs: np.ndarray, chunk_size: int = 256) -> GradientBatch:
        """The objective and its gradient at every row of qs, (N, nq), ``chunk_size`` at a time.

        Raises:
            ConfigurationError: qs is not (N, nq) or has a NaN/infinite entry.
        """
        from ..batch import check_configurations

        qs = check_configurations(self.robot, qs)
        n, nv = qs.shape[0], self.robot.model.nv
        value, grad, ok = np.zeros(n), np.zeros((n, nv)), np.zeros(n, dtype=bool)
        for start in range(0, n, chunk_size):
            stop = min(start + chunk_size, n)
            value[start:stop], grad[start:stop], ok[start:stop] = self._chunk(qs[start:stop])
        return GradientBatch(self.objective, value, grad, ok)

    def shape(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The ellipsoids' shape C (N, m, m), its derivative dC (N, nv, m, m), centre c (N, m),
        dc (N, nv, m) and the mask of configurations where they are differentiable (N,)."""
        self.evaluations += qs.shape[0]
        terms = self._terms(self.workspace.evaluate(qs))
        if self.objective.ellipsoid == "kinematic":
            return _kinematic_shape(terms, self.velocity_limits)
        return _dynamic_shape(terms, None if self.Q_identity else self.Q, self.Z)

    # ----- the chain -----

    def _chunk(self, qs: np.ndarray):
        if self.tree is not None:
            self.evaluations += qs.shape[0]
            return gradient_chunk(self, self.tree, qs)
        return self.forward_chunk(qs)

    def chunk_with_frames(self, qs: np.ndarray):
        """(values, gradients, defined, frames) at qs (n, nq): as the chain's chunk, and the end
        effectors' world positions (n, k, 3), orientations (n, k, 3, 3) and
        ``LOCAL_WORLD_ALIGNED`` Jacobians (n, k, 6, nv) from the same Pinocchio pass; frames is
        ``None`` where the chain has no tree pass (joint kinds without closed forms)."""
        if self.tree is None:
            return (*self.forward_chunk(qs), None)
        self.evaluations += qs.shape[0]
        passes: list = []
        value, grad, ok = gradient_chunk(self, self.tree, qs, passes)
        t = passes[0]
        return value, grad, ok, (t.positions + t.reference[:, None, :], t.frame_rotations, t.frames)

    def forward_chunk(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(values, gradients, defined) at qs (n, nq) by the forward chain (dC along every tangent
        direction from the kinematic Hessians): the reference the reverse chain is tested against."""
        C, dC, c, dc, ok = self.shape(qs)
        value, grad = _index(self.objective, C, dC, c, dc)
        value[~ok] = 0.0
        grad[~ok] = 0.0
        return value, grad, ok

    def _terms(self, d: ConfigurationDerivatives) -> dict:
        """J_u, P, xi, W, M_o, g_o and their derivatives, stacked (configuration, direction k, ...)."""
        S = self.S
        J_u = d.J @ S
        dJ_u = d.dJ @ S
        P = S.T @ d.M @ S
        dP = S.T @ d.dM @ S
        if self.decoupled:
            ne = self.robot.platform.n_reduced
            for X in (P, dP):
                X[..., :ne, ne:] = 0.0
                X[..., ne:, :ne] = 0.0
        xi = -d.g @ S
        dxi = -d.dg @ S
        W, dW, M_o, dM_o, g_o = self._object(d)
        return {"J": J_u, "dJ": dJ_u, "P": P, "dP": dP, "xi": xi, "dxi": dxi, "W": W, "dW": dW, "M_o": M_o,
                "dM_o": dM_o, "g_o": g_o}  # fmt: skip

    def _object_terms(self, positions: np.ndarray):
        """W (n, m, m k), M_o (n, m, m), g_o (m,) at the hands' positions (n, k, 3), and whether
        they move with the hands (the default object held between them, a task with rotations)."""
        task = self.task
        n, k = positions.shape[:2]
        obj = self.held_object
        moving = obj is None and bool(task.angular_rows) and k >= 2
        if not moving:
            # Constant: an explicit object, or one held between the hands whose offsets the task
            # does not see (no rotations) or that has one grasp point (offset p - p = 0): built
            # once per (object, mass, task, chunk size), read-only (the chain never writes them).
            key = (id(obj), self.mass, task)
            if self._constant_object is None or self._constant_object[0] != key:
                self._constant_object = (key, {})
            sizes = self._constant_object[1]
            if n not in sizes:
                held = obj if obj is not None else HeldObject.between(positions[0], self.mass)
                W, M_o = held.grasp_matrix(task), held.inertia_matrix(task)
                W, M_o = np.repeat(W[None], n, axis=0), np.repeat(M_o[None], n, axis=0)
                g_o = held.gravity_vector(task)
                for a in (W, M_o, g_o):
                    a.flags.writeable = False
                sizes[n] = (W, M_o, g_o)
            return (*sizes[n], False)
        obj = HeldObject.between(positions[0], self.mass)
        g_o = obj.gravity_vector(task)
        rows, m = list(task.rows), task.dim
        offsets = positions - positions.mean(axis=1, keepdims=True)
        full = np.zeros((n, 6, 6))
        full[:, np.arange(6), np.arange(6)] = 1.0
        W = np.empty((n, m, k * m))
        for i in range(k):
            full[:, 3:, :3] = _skew_stack(offsets[:, i])
            W[:, :, i * m : (i + 1) * m] = full[:, rows][:, :, rows]
        radius2 = np.max(np.einsum("nij,nij->ni", offsets, offsets), axis=1)
        diag = np.where(task.angular[None, :], 0.4 * self.mass * radius2[:, None], self.mass)
        M_o = np.zeros((n, m, m))
        M_o[:, np.arange(m), np.arange(m)] = diag
        return W, M_o, g_o, True

    def _object(self, d: ConfigurationDerivatives):
        """W, dW, M_o, dM_o, g_o stacked: constant for an explicit object; for the default object
        held between the hands the offsets r_i = p_i - mean(p) move with q."""
        task = self.task
        n, nv = d.J.shape[0], d.J.shape[2]
        obj = self.held_object
        if obj is None:
            obj = HeldObject.between(d.positions[0], self.mass)
        W, M_o, g_o = obj.grasp_matrix(task), obj.inertia_matrix(task), obj.gravity_vector(task)
        W = np.repeat(W[None], n, axis=0)
        M_o = np.repeat(M_o[None], n, axis=0)
        dW = np.zeros((n, nv) + W.shape[1:])
        dM_o = np.zeros((n, nv) + M_o.shape[1:])
        if self.held_object is not None or not task.angular_rows or d.positions.shape[1] < 2:
            return W, dW, M_o, dM_o, g_o
        rows = list(task.rows)
        m = task.dim
        offsets = d.positions - d.positions.mean(axis=1, keepdims=True)  # (n, ka, 3)
        dr = d.J_linear - d.J_linear.mean(axis=1, keepdims=True)  # (n, ka, 3, nv): dr_i/dq
        full = np.zeros((n, 6, 6))
        full[:, :3, :3] = np.eye(3)
        full[:, 3:, 3:] = np.eye(3)
        dfull = np.zeros((n, nv, 6, 6))
        for i in range(offsets.shape[1]):
            full[:, 3:, :3] = _skew_stack(offsets[:, i])
            dfull[:, :, 3:, :3] = _skew_stack(_T(dr[:, i]).reshape(-1, 3)).reshape(n, nv, 3, 3)
            W[:, :, i * m : (i + 1) * m] = full[:, rows][:, :, rows]
            dW[:, :, :, i * m : (i + 1) * m] = dfull[:, :, rows][:, :, :, rows]
        # inertia 2/5 m R^2 I with R the farthest grasp point (HeldObject.between)
        radius2 = np.einsum("nij,nij->ni", offsets, offsets)
        far = np.argmax(radius2, axis=1)
        take = np.arange(n)
        R2 = radius2[take, far]
        dR2 = 2.0 * np.einsum("nx,nxk->nk", offsets[take, far], dr[take, far])  # (n, nv)
        full = np.zeros((n, 6, 6))
        dfull = np.zeros((n, nv, 6, 6))
        for a in range(3):
            full[:, a, a] = self.mass
        for a in range(3, 6):
            full[:, a, a] = 0.4 * self.mass * R2
            dfull[:, :, a, a] = 0.4 * self.mass * dR2
        return W, dW, full[:, rows][:, :, rows], dfull[:, :, rows][:, :, :, rows], g_o


def _skew_stack(r: np.ndarray) -> np.ndarray:
    """skew(r) for each row of r, (n, 3) -> (n, 3, 3)."""
    out = np.zeros((r.shape[0], 3, 3))
    out[:, 0, 1], out[:, 0, 2] = -r[:, 2], r[:, 1]
    out[:, 1, 0], out[:, 1, 2] = r[:, 2], -r[:, 0]
    out[:, 2, 0], out[:, 2, 1] = -r[:, 1], r[:, 0]
    return out


def _T(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _kinematic_shape(t: dict, velocity_limits: np.ndarray):
    """C = (W K^-1 W^T)^-1 with K = J_hat J_hat^T, c = 0, their derivatives and the mask."""
    Jh = t["J"] * velocity_limits
    ok = full_rank(Jh)
    Jh = guarded(Jh, ok)
    dJh = t["dJ"] * velocity_limits
    W, dW = t["W"], t["dW"]
    K = Jh @ _T(Jh)
    dK = dJh @ _T(Jh)[:, None]
    dK = dK + _T(dK)
    X = np.linalg.solve(K, _T(W))  # K^-1 W^T, (n, mk, m)
    A = W @ X
    dWX = dW @ X[:, None]
    dA = dWX + _T(dWX) - _T(X)[:, None] @ dK @ X[:, None]
    C = np.linalg.inv(A)
    C = 0.5 * (C + _T(C))
    dC = -C[:, None] @ dA @ C[:, None]
    n, m = W.shape[0], W.shape[1]
    return C, dC, np.zeros((n, m)), np.zeros((n, dC.shape[1], m)), ok


def _pinv_rows(A: np.ndarray, dA: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A^+ = A^T (A A^T)^-1 of full-row-rank stacked A, (n, r, c), and its derivative, (n, nv, c, r)."""
    G = np.linalg.inv(A @ _T(A))[:, None]
    Ap = _T(A) @ G[:, 0]
    dAAt = dA @ _T(A)[:, None]
    dAAt = dAAt + _T(dAAt)
    dAp = _T(dA) @ G - Ap[:, None] @ dAAt @ G
    return Ap, dAp


def _dynamic_shape(t: dict, Q: np.ndarray | None, Z: np.ndarray):
    """C = rho^2 F^-1, c = -F^-1 L^T mu_bar (F = L^T L), their derivatives and the mask
    (J_u and L of full rank, rho^2 > 0)."""
    J, dJ, W, dW = t["J"], t["dJ"], t["W"], t["dW"]
    ok = full_rank(J)
    J = guarded(J, ok)
    Jp, dJp = _pinv_rows(J, dJ)
    Wp, dWp = _pinv_rows(W, dW)
    P, dP, M_o, dM_o, g_o = t["P"], t["dP"], t["M_o"], t["dM_o"], t["g_o"]
    JpWt = Jp @ _T(W)
    WpM = Wp @ M_o
    Jt = _T(J)[:, None]
    Lam = P @ JpWt + _T(J) @ WpM
    dLam = (
        dP @ JpWt[:, None]
        + P[:, None] @ (dJp @ _T(W)[:, None] + Jp[:, None] @ _T(dW))
        + _T(dJ) @ WpM[:, None]
        + Jt @ (dWp @ M_o[:, None] + Wp[:, None] @ dM_o)
    )
    Wpg = Wp @ g_o  # (n, mk)
    mu = -t["xi"] + np.einsum("nij,nj->ni", _T(J), Wpg)
    dmu = -t["dxi"] + np.einsum("nkij,nj->nki", _T(dJ), Wpg) + np.einsum("nji,nkj->nki", J, dWp @ g_o)
    if Q is not None:
        Qi = np.linalg.inv(Q)
        Lam, dLam, mu, dmu = Qi @ Lam, Qi @ dLam, mu @ Qi.T, dmu @ Qi.T
    L = Z[:, None] * Lam
    dL = Z[:, None] * dLam
    mb = Z * mu
    dmb = Z * dmu
    okL = full_rank(L)
    ok &= okL
    L = guarded(L, okL)
    F = _T(L) @ L
    dF = _T(dL) @ L[:, None]
    dF = dF + _T(dF)
    b = np.einsum("nij,ni->nj", L, mb)
    db = np.einsum("nkij,ni->nkj", dL, mb) + np.einsum("nki,nij->nkj", dmb, L)
    Fi = np.linalg.inv(F)
    Fi = 0.5 * (Fi + _T(Fi))
    c = -np.einsum("nij,nj->ni", Fi, b)
    dc = -np.einsum("nkj,nij->nki", np.einsum("nkij,nj->nki", dF, c) + db, Fi)
    rho2 = 1.0 - np.einsum("ni,ni->n", mb, mb) - np.einsum("ni,ni->n", b, c)
    ok &= rho2 > 1e-12
    drho2 = -2.0 * np.einsum("nki,ni->nk", dmb, mb) - np.einsum("nki,ni->nk", db, c) - np.einsum("nki,ni->nk", dc, b)
    C = rho2[:, None, None] * Fi
    dC = drho2[:, :, None, None] * Fi[:, None] - rho2[:, None, None, None] * (Fi[:, None] @ dF @ Fi[:, None])
    C = guarded(C, ok)  # an empty set's C is not positive definite
    return C, dC, c, dc, ok


def _index(objective: Objective, C, dC, c, dc) -> tuple[np.ndarray, np.ndarray]:
    """The objective's values (n,) and gradients (n, nv) from stacked C, c and their derivatives.
    A block's objective is that of the shadow on its rows: C, c and their derivatives restricted
    to the rows."""
    if objective.rows is not None:
        r = np.asarray(objective.rows)
        return _index(objective.whole(), C[:, r][:, :, r], dC[:, :, r][:, :, :, r], c[:, r], dc[:, :, r])
    m = C.shape[-1]
    index = objective.index
    if index in ("log_volume", "log_isotropy"):
        _, logdet = np.linalg.slogdet(C)
        trace_Ci_dC = np.einsum("nij,nkji->nk", np.linalg.inv(C), dC)
        if index == "log_volume":
            unit = 0.5 * m * math.log(math.pi) - math.lgamma(0.5 * m + 1.0)
            return unit + 0.5 * logdet, 0.5 * trace_Ci_dC
        trace = np.trace(C, axis1=1, axis2=2)
        value = logdet / m - np.log(trace / m)
        return value, trace_Ci_dC / m - np.trace(dC, axis1=2, axis2=3) / trace[:, None]
    if index == "capacity":
        d = np.asarray(objective.direction)
        spread = np.sqrt(np.maximum(np.einsum("i,nij,j->n", d, C, d), 1e-300))
        value = c @ d + spread
        return value, dc @ d + np.einsum("i,nkij,j->nk", d, dC, d) / (2.0 * spread[:, None])
    # minor_axis
    lam, U = np.linalg.eigh(C)
    u = U[:, :, 0]
    s = np.sqrt(np.maximum(lam[:, 0], 1e-300))
    return s, np.einsum("ni,nkij,nj->nk", u, dC, u) / (2.0 * s[:, None])


def measure_gradient(
    robot: Robot,
    q: np.ndarray,
    objective: Objective | str,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
) -> tuple[float, np.ndarray]:
    """An objective's value and tangent-space gradient at one configuration.

    Args:
        robot: the loaded robot.
        q: configuration, (nq,).
        objective: e.g. ``"dynamic:log_volume"``, ``"kinematic:capacity:+x"`` (:meth:`Objective.parse`).
        task, object_mass, held_object, decoupled: as :func:`mobmanip.analysis.analyze`.

    Returns:
        (value, gradient (nv,)).

    Raises:
        MeasureError: the measure is not differentiable there (a singular posture, or an empty
            dynamic ellipsoid: the torques cannot hold the load).
    """
    ev = GradientEvaluator(
        robot, objective, task, object_mass=object_mass, held_object=held_object, decoupled=decoupled
    )
    value, grad, ok = ev(q)
    if not ok:
        raise MeasureError(
            f"{ev.objective.name} is not differentiable at this configuration: the posture is singular"
            + (" or the torques cannot hold the load" if ev.objective.ellipsoid == "dynamic" else "")
        )
    return value, grad


def measure_gradients(
    robot: Robot,
    qs: np.ndarray,
    objective: Objective | str,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
) -> GradientBatch:
    """An objective's values and tangent-space gradients at every row of qs, (N, nq).

    Rows where the measure is not differentiable have ``defined`` False (value and gradient 0).
    """
    ev = GradientEvaluator(
        robot, objective, task, object_mass=object_mass, held_object=held_object, decoupled=decoupled
    )
    return ev.batch(qs)


def platform_gradient(q: np.ndarray, gradient: np.ndarray) -> np.ndarray:
    """The root joint's part of a tangent gradient as d/d(world x, world y, heading), (3,).

    The planar joint's tangent (v_x, v_y) is in the platform frame, so the world gradient is
    R(heading) times it; a pure turn in the tangent space keeps the platform origin.
    """
    c, s = float(q[2]), float(q[3])
    gx, gy, gw = gradient[:3]
    return np.array([c * gx - s * gy, s * gx + c * gy, gw])


def objective_names(task: str | TaskSpace) -> Sequence[str]:
    """Examples of objective texts for a task (for help messages)."""
    task = get_task(task)
    return [f"{e}:{i}" + (f":+{task.labels[0]}" if i == "capacity" else "") for e in ELLIPSOIDS for i in INDICES]
