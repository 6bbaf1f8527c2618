"""The compiled path: whether the kernel can run here, and running it on a chunk.

:mod:`mobmanip.engine.kernel` needs Numba, an optional dependency (``pip install
mobmanip[fast]``); it is imported on first use, and :func:`kernel_available` says whether that
worked. Without it, ``analyze_batch`` takes the stacked NumPy fast path and ``analyze`` the
reference path.

The kernel is compiled once per (number of end effectors, task dimension) and kept in Numba's
on-disk cache; a compile costs tens of seconds. So only work that pays for it compiles it
(batches, sweeps, grids): one configuration (``analyze``) takes the kernel only where it is
already compiled in this process (:func:`kernel_ready`), else the NumPy fast path. The first
call of a pair in a process announces a compile on standard error, with its expected
duration, unless the disk cache holds it (:func:`kernel_cached`); :func:`warm_kernel` lets a
caller pay it before a progress bar starts.
"""

from __future__ import annotations

import contextlib
import functools
import logging
from typing import NamedTuple

import numpy as np

from ..support import tolerances
from ..support.compile_notice import compiling, up_to
from .results import EllipsoidBatch
from .setup import BatchSetup
from .terms import ChunkTerms

_log = logging.getLogger(__name__)


def kernel_available() -> bool:
    """Whether the compiled kernel (:mod:`mobmanip.engine.kernel`, needs Numba) can run here."""
    return kernel_module() is not None


@functools.cache
def kernel_module():
    """The compiled kernel's module, or ``None`` where Numba is missing or unusable."""
    _log.debug("loading the compiled kernel (the first run in an environment compiles it)")
    try:
        from . import kernel
    except ImportError:  # Numba missing or unusable on this platform: the NumPy paths remain
        _log.info("the compiled kernel is not available (Numba missing or unusable): NumPy paths are used")
        return None
    return kernel


#: (end effectors, task dimension) pairs whose kernel has run in this process.
_READY: set[tuple[int, int]] = set()

#: The most a compile of one pair may take (s), by its number of end effectors (the task dimension
#: barely matters; :data:`mobmanip.support.compile_notice.UP_TO`): one arm's, and what each further
#: arm adds. Only printed.
_COMPILE_SECONDS_BASE = up_to("batch, 1 end effector")
_COMPILE_SECONDS_PER_ARM = up_to("batch, 2 end effectors") - _COMPILE_SECONDS_BASE


def kernel_ready(k: int, m: int) -> bool:
    """Whether the kernel for k end effectors and task dimension m has already run in this
    process (a further call costs no compile and no load from disk)."""
    return (k, m) in _READY


def kernel_cached(k: int, m: int) -> bool | None:
    """Whether Numba's on-disk cache holds the kernel for k end effectors and task dimension m.

    Returns:
        True or False; ``None`` where it cannot tell (no Numba, or a Numba whose cache is laid
        out differently).
    """
    module = kernel_module()
    if module is None:
        return None
    try:  # Numba's cache index: {(signature, target, code hashes): data file}
        index = module.run_chunk._cache._cache_file._load_index()
        sizes = {(sig[0].count, sig[1].count) for sig, *_ in index}
    except Exception:  # noqa: BLE001 - a private layout: any change means "cannot tell"
        return None
    return (k, m) in sizes


def expected_compile_seconds(k: int) -> float:
    """The most one kernel compile for k end effectors may take (s), printed."""
    return _COMPILE_SECONDS_BASE + _COMPILE_SECONDS_PER_ARM * (k - 1)


def kernel_name(k: int, m: int) -> str:
    """The batch kernel of a pair, in words (its compile's notice names it so)."""
    return f"the batch kernel for {k} end effector{'s' if k != 1 else ''} and a {m}-D task"


def _first_call(k: int, m: int, stream=None):
    """A context for the first call of the pair in this process: a compile announced on ``stream``
    (standard error; :func:`mobmanip.support.compile_notice.compiling`) unless the pair is cached
    on disk; the pair is ready after it."""
    notice = (
        contextlib.nullcontext()
        if kernel_cached(k, m)
        else compiling(kernel_name(k, m), expected_compile_seconds(k), stream)
    )
    return _readied(k, m, notice)


@contextlib.contextmanager
def _readied(k: int, m: int, notice):
    with notice:
        yield
    _READY.add((k, m))


class KernelOutcome(NamedTuple):
    """What :func:`run_kernel` returns besides the ellipsoids and terms it fills in.

    Attributes:
        refused_kinematic: rows whose kinematic ellipsoid was not certified, (n,); ``None``
            when the kinematic ellipsoids were not asked for.
        refused_dynamic: the same for the dynamic ellipsoids.
        W: grasp matrices, (n, m, mk), of the refused rows (of every row with ``all_terms``).
        Mo: object inertias in the task space, (n, m, m), of the same rows.
        bounds: the certificate's a-priori error bounds of every row's kinematic (column 0)
            and dynamic (column 1) ellipsoid, relative to its size, (n, 2); inf where the
            closed forms do not apply. A row is certified exactly where its bound is at most
            :data:`mobmanip.support.tolerances.FAST_PATH_TOLERANCE`.
    """

    refused_kinematic: np.ndarray | None
    refused_dynamic: np.ndarray | None
    W: np.ndarray
    Mo: np.ndarray
    bounds: np.ndarray


_NO_OFFSETS = np.zeros((0, 3))
_NO_MO = np.zeros((0, 0))


def _writable(a) -> np.ndarray:
    """A C-contiguous, writable float copy: Numba types a read-only array apart from a writable
    one, so a read-only limit vector (``robot.velocity_limits``) would compile the kernel a
    second time."""
    return np.array(a, dtype=float, order="C")


def run_kernel(
    setup: BatchSetup,
    t: ChunkTerms,
    vlim: np.ndarray,
    elim: np.ndarray,
    decoupled: bool,
    kinematic: EllipsoidBatch | None,
    dynamic: EllipsoidBatch | None,
    block: slice,
    offsets: np.ndarray | None = None,
    Mo: np.ndarray | None = None,
    all_terms: bool = False,
) -> KernelOutcome:
    """Run the compiled kernel on a chunk after its Pinocchio pass.

    Fills rows ``block`` of ``kinematic`` / ``dynamic`` (either may be ``None`` to skip it)
    where the certificates accept them, and t's terms (J_u, P, xi and, for a moving grasp, W
    and M_o's diagonal) for the rows left to the SVD path (the other rows' terms are left
    undefined unless ``all_terms``).

    Args:
        setup: the batch set-up.
        t: the chunk's Pinocchio outputs.
        vlim: velocity limits, (nx,).
        elim: effort limits, (nx,).
        decoupled: use the decoupled P for the dynamic ellipsoids.
        kinematic: output for the kinematic ellipsoids, or ``None``.
        dynamic: output for the dynamic ellipsoids, or ``None``.
        block: the rows of the outputs this chunk fills.
        offsets: grasp offsets (k, 3) of an explicit object instead of the default one (a
            sphere centred between the end effectors); its mass is ``setup.mass``.
        Mo: that object's inertia in the task space, (m, m).
        all_terms: fill the terms of every row, not only of the refused ones.
    """
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
    bounds = np.empty((n, 2))
    ptr, idx, val = setup.S_csc
    probed = setup.probed
    first = _first_call(k, m) if (k, m) not in _READY else contextlib.nullcontext()
    with first:
        kernel_module().run_chunk(
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
            _writable(vlim),
            _writable(elim),
            _NO_OFFSETS if offsets is None else _writable(offsets),
            _NO_MO if Mo is None else _writable(Mo),
            setup.mass,
            _writable(setup.g_o),
            setup.n_eta if decoupled else 0,
            kinematic is not None,
            dynamic is not None,
            all_terms,
            tolerances.kernel_tolerances(),
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
            bounds,
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
    return KernelOutcome(bad_kin, bad_dyn, W, Mo_rows, bounds)
