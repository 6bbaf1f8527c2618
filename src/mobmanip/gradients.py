"""Analytic gradients of the ellipsoids' measures with respect to the configuration.

The gradient is taken in Pinocchio's tangent space (see :mod:`mobmanip.derivatives`): entry k
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
- dynamic: with L = Z Lambda_o and mu_bar = Z mu_o (:mod:`mobmanip.ellipsoids`),
  C = rho^2 (L^T L)^-1 and c = -(L^T L)^-1 L^T mu_bar, rho^2 = 1 - |mu_bar|^2 - mu_bar^T L c;
  empty (not differentiable) when rho^2 <= 0.

Their derivatives follow by the product rule from dJ_u/dq (frame Hessians), dP/dq = S^T dM/dq S,
dxi/dq = -S^T dg/dq and, for the default object held between the hands, the derivatives of the
grasp matrix W and the object inertia M_o through the hands' positions. S must not depend on q
(every platform kind but ``steered``). An explicit :class:`mobmanip.grasp.HeldObject` is taken
as given (its W, M_o, g_o constant), as :func:`mobmanip.analysis.analyze` takes it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .analysis import _check_mass
from .derivatives import ConfigurationDerivatives, DerivativeWorkspace
from .dynamics import decouple
from .errors import ArgumentError, MeasureError, ModelError, TaskError
from .grasp import HeldObject
from .model import Robot
from .tasks import TaskSpace, get_task

#: The ellipsoids with gradients.
ELLIPSOIDS = ("kinematic", "dynamic")
#: The measures of an ellipsoid with gradients.
INDICES = ("log_volume", "log_isotropy", "capacity", "minor_axis")

#: A measure is not differentiable where the smallest singular value of J_hat (or L, or J_u) is
#: below this fraction of the largest (a singular posture).
SINGULAR_RTOL = 1e-9


@dataclass(frozen=True)
class Objective:
    """A differentiable measure of one ellipsoid.

    Attributes:
        ellipsoid: ``"kinematic"`` or ``"dynamic"``.
        index: one of :data:`INDICES`.
        direction: unit task direction for ``capacity``, (m,); ``None`` otherwise.
    """

    ellipsoid: str
    index: str
    direction: tuple[float, ...] | None = None

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

    @property
    def name(self) -> str:
        """``ellipsoid:index`` (and ``:d1,d2,...`` for a capacity)."""
        tail = "" if self.direction is None else ":" + ",".join(f"{v:g}" for v in self.direction)
        return f"{self.ellipsoid}:{self.index}{tail}"

    @classmethod
    def parse(cls, text: str, task: str | TaskSpace) -> Objective:
        """An objective from ``ELLIPSOID:INDEX[:DIRECTION]``.

        DIRECTION is a signed task axis (``+x``, ``-z``, ``+yaw``; the task's axis labels) or
        comma-separated components (``1,1,0``).

        Raises:
            MeasureError: an unknown ellipsoid or index (the message lists the known ones).
            ArgumentError: a malformed or missing direction.
        """
        task = get_task(task)
        parts = str(text).split(":")
        if len(parts) not in (2, 3):
            raise ArgumentError(f"objective must be ELLIPSOID:INDEX[:DIRECTION], got {text!r}")
        direction = None if len(parts) == 2 else _parse_direction(parts[2], task)
        if direction is None and parts[1:2] == ["capacity"]:
            raise ArgumentError(f"objective {text!r}: a capacity needs a direction, e.g. {parts[0]}:capacity:+x")
        return cls(parts[0], parts[1], direction)

    def check_task(self, task: TaskSpace) -> None:
        """Raises ArgumentError when the capacity direction does not have the task's dimension."""
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
        raise ArgumentError(
            f"direction {text!r} is neither a signed axis (+{', +'.join(task.labels)}, or -) nor numbers like 1,0,0"
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
            mass = robot.spec.object_mass if object_mass is None else object_mass
            _check_mass(mass)
        self.mass = float(mass)
        self.held_object = held_object
        self.S = robot.S
        self.Q = robot.Q
        self.Q_identity = bool(np.array_equal(self.Q, np.eye(self.Q.shape[0])))
        self.velocity_limits = np.asarray(robot.velocity_limits, dtype=float)
        self.Z = 1.0 / np.asarray(robot.effort_limits, dtype=float)
        self.evaluations = 0

    # ----- public -----

    def __call__(self, q: np.ndarray) -> tuple[float, np.ndarray, bool]:
        """(value, gradient (nv,), defined) at configuration q, (nq,)."""
        self.evaluations += 1
        q = self.robot.check_configuration(q)
        d = self.workspace.evaluate(q)
        return self._from_derivatives(d)

    def batch(self, qs: np.ndarray) -> GradientBatch:
        """The objective and its gradient at every row of qs, (N, nq)."""
        qs = np.asarray(qs, dtype=float)
        nq, nv = self.robot.model.nq, self.robot.model.nv
        if qs.ndim != 2 or qs.shape[1] != nq:
            raise ArgumentError(f"configurations must have shape (N, {nq}), got {qs.shape}")
        n = qs.shape[0]
        value, grad, ok = np.zeros(n), np.zeros((n, nv)), np.zeros(n, dtype=bool)
        for i in range(n):
            value[i], grad[i], ok[i] = self(qs[i])
        return GradientBatch(self.objective, value, grad, ok)

    # ----- the chain -----

    def _from_derivatives(self, d: ConfigurationDerivatives) -> tuple[float, np.ndarray, bool]:
        terms = self._terms(d)
        if self.objective.ellipsoid == "kinematic":
            shape = _kinematic_shape(terms, self.velocity_limits)
        else:
            shape = _dynamic_shape(terms, self.Q if not self.Q_identity else None, self.Z)
        if shape is None:
            return 0.0, np.zeros(self.robot.model.nv), False
        C, dC, c, dc = shape
        value, grad = _index(self.objective, C, dC, c, dc)
        return value, grad, True

    def _terms(self, d: ConfigurationDerivatives) -> dict:
        """J_u, P, xi, W, M_o, g_o and their derivatives (direction k first)."""
        S = self.S
        J_u = d.J @ S
        dJ_u = d.dJ @ S
        P = S.T @ d.M @ S
        dP = np.einsum("vi,kvw,wj->kij", S, d.dM, S, optimize=True)
        if self.decoupled:
            P = decouple(self.robot, P)
            dP = np.array([decouple(self.robot, x) for x in dP])
        xi = -S.T @ d.g
        dxi = -d.dg @ S
        W, dW, M_o, dM_o, g_o = self._object(d)
        return {"J": J_u, "dJ": dJ_u, "P": P, "dP": dP, "xi": xi, "dxi": dxi, "W": W, "dW": dW, "M_o": M_o,
                "dM_o": dM_o, "g_o": g_o}  # fmt: skip

    def _object(self, d: ConfigurationDerivatives):
        """W, dW, M_o, dM_o, g_o: constant for an explicit object; for the default object held
        between the hands the offsets r_i = p_i - mean(p) move with q."""
        task = self.task
        nv = d.J.shape[1]
        if self.held_object is not None:
            obj = self.held_object
            W, M_o = obj.grasp_matrix(task), obj.inertia_matrix(task)
            return W, np.zeros((nv,) + W.shape), M_o, np.zeros((nv,) + M_o.shape), obj.gravity_vector(task)
        obj = HeldObject.between(d.positions, self.mass)
        W, M_o, g_o = obj.grasp_matrix(task), obj.inertia_matrix(task), obj.gravity_vector(task)
        dW = np.zeros((nv,) + W.shape)
        dM_o = np.zeros((nv,) + M_o.shape)
        if not task.angular_rows or len(d.positions) < 2:
            return W, dW, M_o, dM_o, g_o
        rows = list(task.rows)
        m = task.dim
        dr = d.J_linear - d.J_linear.mean(axis=0)  # (k_a, 3, nv): dr_i/dq
        for i in range(len(d.positions)):
            full = np.zeros((nv, 6, 6))
            full[:, 3:, :3] = _skew_stack(dr[i].T)
            dW[:, :, i * m : (i + 1) * m] = full[:, rows][:, :, rows]
        # inertia 2/5 m R^2 I with R the farthest grasp point (HeldObject.between)
        radius2 = np.einsum("ij,ij->i", obj.offsets, obj.offsets)
        far = int(np.argmax(radius2))
        dR2 = 2.0 * obj.offsets[far] @ dr[far]  # (nv,)
        full = np.zeros((nv, 6, 6))
        for a in range(3, 6):
            full[:, a, a] = 0.4 * self.mass * dR2
        dM_o = full[:, rows][:, :, rows]
        return W, dW, M_o, dM_o, g_o


def _skew_stack(r: np.ndarray) -> np.ndarray:
    """skew(r) for each row of r, (n, 3) -> (n, 3, 3)."""
    out = np.zeros((r.shape[0], 3, 3))
    out[:, 0, 1], out[:, 0, 2] = -r[:, 2], r[:, 1]
    out[:, 1, 0], out[:, 1, 2] = r[:, 2], -r[:, 0]
    out[:, 2, 0], out[:, 2, 1] = -r[:, 1], r[:, 0]
    return out


def _T(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _well_conditioned(A: np.ndarray) -> bool:
    """Full rank (min(rows, cols) singular values above SINGULAR_RTOL times the largest)."""
    s = np.linalg.svd(A, compute_uv=False)
    return bool(s.size and s[-1] > SINGULAR_RTOL * s[0])


def _kinematic_shape(t: dict, velocity_limits: np.ndarray):
    """C = (W K^-1 W^T)^-1 with K = J_hat J_hat^T, c = 0, and their derivatives; None if singular."""
    Jh = t["J"] * velocity_limits
    if not _well_conditioned(Jh):
        return None
    dJh = t["dJ"] * velocity_limits
    W, dW = t["W"], t["dW"]
    K = Jh @ Jh.T
    dK = dJh @ Jh.T
    dK = dK + _T(dK)
    X = np.linalg.solve(K, W.T)  # K^-1 W^T, (mk, m)
    A = W @ X
    dWX = dW @ X
    dA = dWX + _T(dWX) - _T(X) @ dK @ X
    C = np.linalg.inv(A)
    C = 0.5 * (C + C.T)
    dC = -C @ dA @ C
    m = W.shape[0]
    return C, dC, np.zeros(m), np.zeros((dC.shape[0], m))


def _pinv_rows(A: np.ndarray, dA: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A^+ = A^T (A A^T)^-1 of a full-row-rank A and its derivative."""
    G = np.linalg.inv(A @ A.T)
    Ap = A.T @ G
    dAAt = dA @ A.T
    dAAt = dAAt + _T(dAAt)
    dAp = _T(dA) @ G - Ap @ dAAt @ G
    return Ap, dAp


def _dynamic_shape(t: dict, Q: np.ndarray | None, Z: np.ndarray):
    """C = rho^2 F^-1, c = -F^-1 L^T mu_bar (F = L^T L) and derivatives; None if singular or empty."""
    J, dJ, W, dW = t["J"], t["dJ"], t["W"], t["dW"]
    if not _well_conditioned(J):
        return None
    Jp, dJp = _pinv_rows(J, dJ)
    Wp, dWp = _pinv_rows(W, dW)
    P, dP, M_o, dM_o, g_o = t["P"], t["dP"], t["M_o"], t["dM_o"], t["g_o"]
    JpWt = Jp @ W.T
    WpM = Wp @ M_o
    Lam = P @ JpWt + J.T @ WpM
    dLam = dP @ JpWt + P @ (dJp @ W.T + Jp @ _T(dW)) + _T(dJ) @ WpM + J.T @ (dWp @ M_o + Wp @ dM_o)
    Wpg = Wp @ g_o
    mu = -t["xi"] + J.T @ Wpg
    dmu = -t["dxi"] + _T(dJ) @ Wpg + (J.T @ (dWp @ g_o).T).T
    if Q is not None:
        Lam, mu = np.linalg.solve(Q, Lam), np.linalg.solve(Q, mu)
        dLam = np.linalg.solve(Q, dLam)
        dmu = np.linalg.solve(Q, dmu.T).T
    L = Z[:, None] * Lam
    dL = Z[:, None] * dLam
    mb = Z * mu
    dmb = Z * dmu
    if not _well_conditioned(L):
        return None
    F = L.T @ L
    dF = _T(dL) @ L
    dF = dF + _T(dF)
    b = L.T @ mb
    db = (_T(dL) @ mb) + dmb @ L  # (nv, m)
    Fi = np.linalg.inv(F)
    Fi = 0.5 * (Fi + Fi.T)
    c = -Fi @ b
    dc = -(dF @ c + db) @ Fi  # Fi symmetric: rows (Fi (dF c + db))^T
    rho2 = 1.0 - mb @ mb - b @ c
    if rho2 <= 1e-12:
        return None
    drho2 = -2.0 * dmb @ mb - db @ c - dc @ b
    C = rho2 * Fi
    dC = drho2[:, None, None] * Fi - rho2 * (Fi @ dF @ Fi)
    return C, dC, c, dc


def _index(objective: Objective, C, dC, c, dc) -> tuple[float, np.ndarray]:
    """The objective's value and gradient from the shape C, centre c and their derivatives."""
    m = C.shape[0]
    index = objective.index
    if index == "log_volume":
        sign, logdet = np.linalg.slogdet(C)
        unit = 0.5 * m * math.log(math.pi) - math.lgamma(0.5 * m + 1.0)
        Ci = np.linalg.inv(C)
        return unit + 0.5 * logdet, 0.5 * np.einsum("ij,kji->k", Ci, dC)
    if index == "log_isotropy":
        _, logdet = np.linalg.slogdet(C)
        trace = float(np.trace(C))
        Ci = np.linalg.inv(C)
        value = logdet / m - math.log(trace / m)
        return value, np.einsum("ij,kji->k", Ci, dC) / m - np.trace(dC, axis1=1, axis2=2) / trace
    if index == "capacity":
        d = np.asarray(objective.direction)
        spread = math.sqrt(max(float(d @ C @ d), 0.0))
        return float(d @ c) + spread, dc @ d + np.einsum("i,kij,j->k", d, dC, d) / (2.0 * spread)
    # minor_axis
    lam, U = np.linalg.eigh(C)
    u = U[:, 0]
    s = math.sqrt(max(float(lam[0]), 0.0))
    return s, np.einsum("i,kij,j->k", u, dC, u) / (2.0 * s)


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
