"""The engine on one configuration: :func:`evaluate_one`, the fast path behind ``analyze``."""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np

from ..errors import ModelError, TaskError
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task
from ..sets.ellipsoid import Ellipsoid
from ..terms.grasp import HeldObject, object_mass_of
from .compiled import kernel_available, run_kernel
from .numpy_path import dynamic_fast, kinematic_fast
from .probed import Workspace
from .results import EllipsoidBatch
from .setup import BatchSetup
from .terms import chunk_terms, numpy_terms

#: Ways :func:`evaluate_one` can compute the ellipsoids.
ONE_ROW_METHODS = ("auto", "kernel", "numpy")


class OneRow(NamedTuple):
    """The engine's terms and certified ellipsoids at one configuration (robot and object at rest).

    A named tuple (immutable, and cheap to build on the path every ``analyze`` call takes).

    Attributes:
        J_u: unified Jacobian J S, (m k, nx).
        P: reduced inertia S^T M S (coupled), (nx, nx).
        xi: reduced bias at rest, -S^T g, (nx,).
        positions: world positions of the end effectors, (k, 3).
        W: grasp matrix, (m, m k).
        kinematic: the kinematic ellipsoid, or ``None`` where the fast path's certificate
            refused it (the caller computes it by the reference path).
        dynamic: the dynamic ellipsoid (decoupled P if asked), or ``None`` likewise.
        kinematic_bound: the certificate's a-priori error bound for the kinematic ellipsoid,
            relative to its size (inf where the closed forms do not apply; the ellipsoid is
            given exactly where it is at most :data:`mobmanip.support.tolerances.FAST_PATH_TOLERANCE`);
            ``None`` on the NumPy route, which does not report it.
        dynamic_bound: the same for the dynamic ellipsoid.
        method: the route taken, ``"kernel"`` or ``"numpy"``.
    """

    J_u: np.ndarray
    P: np.ndarray
    xi: np.ndarray
    positions: np.ndarray
    W: np.ndarray
    kinematic: Ellipsoid | None
    dynamic: Ellipsoid | None
    kinematic_bound: float | None
    dynamic_bound: float | None
    method: str


def evaluate_one(
    robot: Robot,
    q: np.ndarray,
    task: str | TaskSpace | None = None,
    mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
    *,
    method: str = "auto",
    validate: bool = True,
) -> OneRow:
    """Terms and fast-path ellipsoids at one configuration, with the batch engine.

    One Pinocchio pass of the probed model, then the compiled kernel (``"kernel"``) or the
    stacked NumPy fast path on one row (``"numpy"``). An ellipsoid the certificate does not
    accept to :data:`mobmanip.support.tolerances.FAST_PATH_TOLERANCE` of its size is ``None``:
    :func:`mobmanip.analysis.analyze` then computes it by the reference path. The set-up for
    (robot, task, mass) is built on first use and kept as long as the robot lives.

    Args:
        robot: the loaded robot.
        q: configuration, (nq,).
        task: task-space name or object; defaults to the spec's ``default_task``.
        mass: mass of the default object (kg), held by all end effectors at their centroid;
            defaults to the spec's. Ignored when ``held_object`` is given.
        held_object: an explicit object (one grasp offset per arm) instead of the default one.
        decoupled: compute the dynamic ellipsoid with the decoupled P.
        method: ``"auto"`` (the kernel where Numba is installed, else ``"numpy"``),
            ``"kernel"`` or ``"numpy"``. The NumPy route computes ellipsoids for the default
            object only (an explicit object's are left ``None``) and reports no bounds.
        validate: check q, task, mass and object; ``False`` where the caller has already
            checked them (``analyze`` does).

    Raises:
        ConfigurationError: q is not (nq,) or not finite.
        TaskError: unknown task, bad mass, or an object without one grasp offset per arm.
        ModelError: ``method="kernel"`` where Numba is not installed.
    """
    if method not in ONE_ROW_METHODS:
        raise TaskError(f"method must be one of {', '.join(ONE_ROW_METHODS)}, got {method!r}")
    if method == "auto":
        method = "kernel" if kernel_available() else "numpy"
    elif method == "kernel" and not kernel_available():
        raise ModelError("the compiled kernel needs Numba: pip install 'mobmanip[fast]'")
    if validate:
        q = robot.check_configuration(q)
        task = get_task(task or robot.spec.default_task)
        if held_object is not None and held_object.offsets.shape != (len(robot.arms), 3):
            raise TaskError(
                f"the object needs one grasp offset per arm ({len(robot.arms)}), got {held_object.offsets.shape}"
            )
    mass = held_object.mass if held_object is not None else object_mass_of(robot, mass)
    setup, ws = _single_setup(robot, task, mass)
    t = chunk_terms(setup, q[None, :], ws)
    m = setup.m
    kin_b, dyn_b = EllipsoidBatch.allocate(1, m), EllipsoidBatch.allocate(1, m)
    vlim, elim = robot.velocity_limits, robot.effort_limits
    if method == "kernel":
        offsets = Mo = None
        if held_object is not None:
            offsets = np.ascontiguousarray(held_object.offsets, dtype=float)
            Mo = np.ascontiguousarray(held_object.inertia_matrix(task), dtype=float)
        out = run_kernel(setup, t, vlim, elim, decoupled, kin_b, dyn_b, slice(0, 1), offsets, Mo, all_terms=True)
        refused_kin, refused_dyn, W = out.refused_kinematic[0], out.refused_dynamic[0], out.W[0]
        bounds = out.bounds[0].tolist()
    else:
        numpy_terms(setup, t)
        bounds = None, None
        if held_object is not None:
            W = held_object.grasp_matrix(task)
            refused_kin = refused_dyn = True
        else:
            W = setup.W.copy() if t.W is None else t.W[0]
            refused_kin = bool(kinematic_fast(setup, t, vlim, kin_b, slice(0, 1))[0])
            P = t.P.copy()
            if decoupled:
                e = setup.n_eta
                P[:, :e, e:] = P[:, e:, :e] = 0.0
            refused_dyn = bool(dynamic_fast(setup, t, P, elim, dyn_b, slice(0, 1))[0])
    # J_u, P, xi and W are new arrays of this call; the positions live in the reused workspace
    return OneRow(
        J_u=t.J_u[0],
        P=t.P[0],
        xi=t.xi[0],
        positions=t.positions[0].copy(),
        W=W,
        kinematic=None if refused_kin else kin_b[0],
        dynamic=None if refused_dyn else dyn_b[0],
        kinematic_bound=bounds[0],
        dynamic_bound=bounds[1],
        method=method,
    )


_SETUPS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _single_setup(robot: Robot, task: TaskSpace, mass: float) -> tuple[BatchSetup, Workspace]:
    """The batch set-up and a one-row workspace for (robot, task, mass), built once and kept as
    long as the robot lives."""
    per_robot = _SETUPS.setdefault(robot, {})
    key = (task.name, tuple(task.rows), mass)
    if key not in per_robot:
        if len(per_robot) > 64:  # e.g. a sweep over masses: do not grow without bound
            per_robot.clear()
        setup = BatchSetup(robot, task, mass)
        per_robot[key] = (setup, Workspace(setup.probed, 1))
    return per_robot[key]
