"""Force capacity from arrays: the wrenches the object (or one hand) can exert on the environment.

Robot and object at rest (xdot = 0, a = 0), gravity included. The object exerts the wrench f ON
the environment, so the environment pushes back with -f and the object's equation reads
``W h = g_o + f`` (h: what the hands apply on the object, g_o = +m g along up). The reduced
dynamics at rest give the efforts: ``-Q tau + J_u^T h = xi``, i.e. ``tau = Q^-1 (J_u^T h - xi)``
(xi = -S^T g at rest, so ``-xi`` are the efforts that hold the robot up against its own weight).

Exact set (box limits, any internal force): with h = W^+ (f + g_o) + N n (N a basis of null(W),
n the internal forces)::

    K_f = {f : exists n with |A f + B n + mu| <= tau_max},
    A = Q^-1 J_u^T W^+,  B = Q^-1 J_u^T N,  mu = Q^-1 (J_u^T W^+ g_o - xi),

the preimage under A of the box around -mu, the directions of range(B) quotiented out: with
P_B an orthonormal basis of range(B)'s complement, K_f = {f : P_B^T A f in -P_B^T mu +
P_B^T diag(tau_max) [-1, 1]^n}, a :class:`~mobmanip.sets.polytope.Polytope` (zonotope section).
With one hand (W = I, no internal force) and no object this is pycapacity's force polytope
``{f : J^T f = tau - g(q), tau in the box}`` (``pycapacity.robot.force_polytope(J, tau_max,
-tau_max, t_bias=g(q))``, with g(q) = -xi the gravity torques): f is the force the robot
applies on the environment in both.

Force ellipsoid (the paper's Euclidean counterpart, minimum-norm internal force, h = W^+ (f +
g_o)): ``{f : ||Z (A f + mu)|| <= 1}``, Z = diag(1 / tau_max). It is the paper's dynamic
ellipsoid (Eq. 33-38) of a robot without inertia (P = 0) holding an object of unit inertia
(M_o = I), with a in place of f: built by :func:`mobmanip.sets.ellipsoid.dynamic_ellipsoid`,
which handles its offset, emptiness and degeneracy. It lies inside the minimum-norm polytope
(``||.||_inf <= ||.||_2``), hence inside K_f.

Both sets are bounded unless a wrench the object can exert reaches the hands through
null(J_u^T): a posture where the structure bears it without any effort (an arm stretched along
the push). There the capacity is unbounded and :func:`unbounded_force_direction` names the
direction; the functions below raise :class:`~mobmanip.errors.TaskError` rather than return a
set that is not the answer.
"""

from __future__ import annotations

import numpy as np

from ..errors import TaskError
from .ellipsoid import _RANK_RTOL, Ellipsoid, _is_identity, _null_space, _torque_offset, dynamic_ellipsoid
from .polytope import Polytope


def unbounded_force_direction(J_u: np.ndarray, W: np.ndarray) -> np.ndarray | None:
    """A unit wrench direction along which the object pushes without any effort, or ``None``.

    It exists when some hand wrench h0 with J_u^T h0 = 0 (no effort at all) moves the object,
    W h0 != 0; then every multiple of W h0 is in the force set.

    Args:
        J_u: unified Jacobian, (m k, nx).
        W: grasp matrix, (m, m k).
    """
    U, s, _ = np.linalg.svd(J_u, full_matrices=True)
    rank = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1e-300)))
    free = W @ U[:, rank:]  # object wrenches of the effortless hand wrenches
    if not free.size:
        return None
    Uf, sf, _ = np.linalg.svd(free)
    if sf[0] <= _RANK_RTOL * max(float(np.linalg.norm(W, 2)), 1e-300):
        return None
    return Uf[:, 0]


def _check_bounded(J_u: np.ndarray, W: np.ndarray) -> None:
    direction = unbounded_force_direction(J_u, W)
    if direction is not None:
        direction = direction * np.sign(direction[np.argmax(np.abs(direction))])  # its largest entry positive
        shown = ", ".join(f"{v:.3f}" for v in np.round(direction, 3) + 0.0)  # no "-0.000"
        raise TaskError(
            f"the force capacity is unbounded along +-({shown}): at this posture the structure bears that "
            "wrench with no effort at all (a singular posture)"
        )


def _force_map(J_u, W, Q, xi, g_o) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A = Q^-1 J_u^T W^+, B = Q^-1 J_u^T N (N: internal forces, null(W)) and mu = Q^-1 (J_u^T W^+ g_o - xi)."""
    Q_or_none = None if _is_identity(Q) else Q
    W_pinv = np.linalg.pinv(W)
    A, B = J_u.T @ W_pinv, J_u.T @ _null_space(W, W.shape[1])
    if Q_or_none is not None:
        A, B = np.linalg.solve(Q, A), np.linalg.solve(Q, B)
    return A, B, _torque_offset(J_u, W_pinv, Q_or_none, xi, g_o)


def force_polytope(
    J_u: np.ndarray, W: np.ndarray, Q: np.ndarray, xi: np.ndarray, g_o: np.ndarray, effort_limits: np.ndarray
) -> Polytope:
    """The exact set of wrenches the object exerts on the environment at rest, every effort in its box.

    Args:
        J_u: unified Jacobian, (m k, nx).
        W: grasp matrix, (m, m k), of full row rank.
        Q: reduced input matrix, invertible, (nx, nx).
        xi: reduced bias at rest (-S^T g), (nx,).
        g_o: object gravity wrench (+m g up), (m,).
        effort_limits: tau_max per reduced velocity (N m or N), (nx,).

    Returns:
        A polytope in N (and N m for moment rows); its :meth:`~Polytope.inputs` are efforts tau
        (with some internal force); ``empty`` when no wrench lets the efforts hold robot and
        object still.

    Raises:
        TaskError: the set is unbounded (see :func:`unbounded_force_direction`).
    """
    J_u, W = np.asarray(J_u, dtype=float), np.asarray(W, dtype=float)
    limits = np.asarray(effort_limits, dtype=float)
    _check_bounded(J_u, W)
    A, B, mu = _force_map(J_u, W, Q, np.asarray(xi, dtype=float), np.asarray(g_o, dtype=float))
    P_B = _null_space(B.T, B.shape[0])  # the complement of range(B): internal forces quotiented out
    return Polytope(P_B.T @ A, -(P_B.T @ mu), P_B.T * limits, limits)


def force_ellipsoid(
    J_u: np.ndarray, W: np.ndarray, Q: np.ndarray, xi: np.ndarray, g_o: np.ndarray, effort_limits: np.ndarray
) -> Ellipsoid:
    """The force ellipsoid {f : ||Z Q^-1 (J_u^T W^+ (g_o + f) - xi)|| <= 1} (arguments as
    :func:`force_polytope`).

    Returns:
        The ellipsoid of object wrenches on the environment (N, N m), centred at the wrench of
        least normalised effort; ``empty`` when no wrench lets the efforts (in this Euclidean
        norm) hold robot and object still.

    Raises:
        TaskError: the set is unbounded (see :func:`unbounded_force_direction`).
    """
    J_u, W = np.asarray(J_u, dtype=float), np.asarray(W, dtype=float)
    _check_bounded(J_u, W)
    nx, m = J_u.shape[1], W.shape[0]
    # Bounded: W^T f is in range(J_u) for every f, so the dynamic ellipsoid's restriction to the
    # accelerations the hands can follow keeps every f.
    return dynamic_ellipsoid(J_u, W, np.zeros((nx, nx)), Q, xi, np.eye(m), g_o, effort_limits)
