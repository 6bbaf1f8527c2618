"""The top level of the engine: chunks of configurations through the Pinocchio pass, then the
compiled kernel (or the NumPy fast path), then the SVD path for the rows they do not certify.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigurationError, TaskError
from ..robot.model import Robot
from .compiled import kernel_available, kernel_ready, run_kernel
from .numpy_path import dynamic_fast, kinematic_fast
from .probed import Workspace
from .results import BatchAnalysis, EllipsoidBatch
from .setup import BatchSetup
from .svd_path import SvdBacklog, dynamic_svd, kinematic_svd
from .terms import ChunkTerms, chunk_terms, numpy_terms

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
    robot.check_configuration_values(qs)
    return qs


def _decouple(setup: BatchSetup, P: np.ndarray) -> np.ndarray:
    """P (n, nx, nx) with its platform-arm blocks zeroed (a copy)."""
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
    t: ChunkTerms,
    *,
    velocity_limits: np.ndarray | None = None,
    effort_limits: np.ndarray | None = None,
    decoupled: bool = False,
    kinematic: EllipsoidBatch | None = None,
    dynamic: EllipsoidBatch | None = None,
    offset: int = 0,
    method: str = "auto",
    backlog: SvdBacklog | None = None,
) -> np.ndarray:
    """Fill ``kinematic``/``dynamic`` rows ``offset .. offset + n`` from one chunk's terms.

    Either output may be ``None`` to skip that ellipsoid. ``method``: ``"auto"`` (the compiled
    kernel when Numba is available, else the stacked NumPy fast path; rows neither certifies go
    to the SVD path), ``"numpy"`` (stacked NumPy fast path, then SVD path) or ``"svd"``.
    With a ``backlog``, the SVD path's rows are queued there instead of computed now (its
    :meth:`SvdBacklog.flush` computes them, for every chunk at once). Returns the chunk's
    SVD-path mask (n,).
    """
    n = t.n
    rows = np.arange(offset, offset + n)
    block = slice(offset, offset + n)
    vlim = _limits(velocity_limits, setup.robot.velocity_limits, "velocity")
    elim = _limits(effort_limits, setup.robot.effort_limits, "effort")
    bad_kin = bad_dyn = None
    if method == "auto" and kernel_available():
        outcome = run_kernel(setup, t, vlim, elim, decoupled, kinematic, dynamic, block)
        bad_kin, bad_dyn = outcome.refused_kinematic, outcome.refused_dynamic
    else:
        numpy_terms(setup, t)
    svd_rows = np.zeros(n, dtype=bool)
    if kinematic is not None:
        if bad_kin is None:
            bad_kin = np.ones(n, dtype=bool) if method == "svd" else kinematic_fast(setup, t, vlim, kinematic, block)
        if bad_kin.any():
            W = setup.W if t.W is None else t.W[bad_kin]
            if backlog is not None:
                backlog.add_kinematic(rows[bad_kin], t.J_u[bad_kin], W, vlim)
            else:
                kinematic.put_rows(rows[bad_kin], kinematic_svd(t.J_u[bad_kin], W, vlim))
        svd_rows |= bad_kin
    if dynamic is not None:
        if bad_dyn is None:
            if method == "svd":
                bad_dyn = np.ones(n, dtype=bool)
            else:
                P = _decouple(setup, t.P) if decoupled else t.P
                bad_dyn = dynamic_fast(setup, t, P, elim, dynamic, block)
        if bad_dyn.any():
            W = setup.W if t.W is None else t.W[bad_dyn]
            Mo = setup.Mo if t.Mo is None else t.Mo[bad_dyn]
            P = _decouple(setup, t.P[bad_dyn]) if decoupled else t.P[bad_dyn]
            J_u, xi = t.J_u[bad_dyn], t.xi[bad_dyn]
            if backlog is not None:
                backlog.add_dynamic(rows[bad_dyn], J_u, W, P, xi, Mo, elim)
            else:
                result = dynamic_svd(J_u, W, P, setup.Q_inv, xi, Mo, setup.g_o, elim, rows[bad_dyn])
                dynamic.put_rows(rows[bad_dyn], result)
        svd_rows |= bad_dyn
    return svd_rows


def warm_kernel(robot: Robot, task: str | None = None, object_mass: float | None = None) -> bool:
    """Compile the kernel for the robot's arms and task now, or load it from Numba's disk cache
    (the first compile announces itself on standard error), so that what follows -- a sweep
    and its progress bar, a pool of worker processes forked from this one -- does not pay it.

    Args:
        robot: the robot (its number of end effectors and the task fix the kernel).
        task: task-space name; defaults to the spec's ``default_task``.
        object_mass: mass of the default object (kg); defaults to the spec's.

    Returns:
        Whether the kernel is ready in this process (False without Numba).
    """
    if not kernel_available():
        return False
    setup = BatchSetup(robot, task, object_mass)
    if not kernel_ready(setup.k, setup.m):
        analyze_batch(robot, robot.neutral()[None, :], setup.task.name, object_mass=setup.mass)
    return kernel_ready(setup.k, setup.m)


def iter_terms(setup: BatchSetup, qs: np.ndarray, chunk_size: int = DEFAULT_CHUNK):
    """Yield ``(start, terms)`` for consecutive chunks of a checked (N, nq) array."""
    ws = Workspace(setup.probed, min(chunk_size, max(qs.shape[0], 1)))
    for start in range(0, qs.shape[0], chunk_size):
        yield start, chunk_terms(setup, qs[start : start + chunk_size], ws)


def analyze_batch(
    robot: Robot,
    qs: np.ndarray,
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
        method: ``"auto"`` (the fast path compiled per configuration, see :mod:`mobmanip.engine.kernel`,
            falling back to ``"numpy"`` without Numba; SVD path for the rows it cannot certify),
            ``"numpy"`` (the same fast path stacked in NumPy, then the SVD path) or ``"svd"``
            (SVD path for every row, the stacked mirror of :mod:`mobmanip.sets.ellipsoid`).

    Raises:
        ConfigurationError: ``qs`` is not (N, nq) or has a NaN/infinite entry (named by row and
            joint).
        TaskError: unknown task, bad object mass, unknown method or bad chunk size.
        ModelError: a configuration where an object acceleration needs no torque (massless links).
    """
    if method not in METHODS:
        raise TaskError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if chunk_size is None:
        chunk_size = default_chunk(method)
    if not isinstance(chunk_size, int) or chunk_size < 1:
        raise TaskError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    qs = check_configurations(robot, qs)
    setup = BatchSetup(robot, task, object_mass, positions=positions)
    n, m = qs.shape[0], setup.m
    kin, dyn = EllipsoidBatch.allocate(n, m), EllipsoidBatch.allocate(n, m)
    svd_rows = np.zeros(n, dtype=bool)
    pos = np.zeros((n, setup.k, 3)) if setup.need_positions else None
    backlog = SvdBacklog(setup)
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
