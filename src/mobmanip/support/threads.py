"""BLAS and OpenMP thread pools, limited where small matrices dominate.

mobmanip multiplies and factors small matrices: Jacobians and inertias of a few dozen rows,
SLSQP's subproblems, linear programs of a few hundred rows. A BLAS that spreads such a product
over every core spends longer waking and synchronising its threads than computing, and its
threads spin on cores that other work needs: ``mobmanip place tiago_dual ... --objective
dynamic:log_volume`` used 2 to 4 times the CPU time with OpenBLAS's default pool on a busy
2-core machine than with one thread. Where mobmanip runs in parallel it does so with processes
(a sweep's process pool, Dask's workers), and each of those is best served by one thread too.

:func:`limit_threads` runs a block of code with these pools limited::

    from mobmanip.support.threads import limit_threads

    with limit_threads():  # one thread per pool
        result = mobmanip.placement.place(robot, target, "dynamic:log_volume", object_mass=1.0)

The ``mobmanip`` command runs inside it (:func:`mobmanip.cli.main`), so every command, and every
worker process a command starts (a sweep's process pool, a ``local:N`` Dask cluster), works with
one BLAS thread and one OpenMP thread. Workers started by someone else (``dask worker`` on other
machines) are reached through :class:`LimitedExecutor`, which limits the pools of the process
each task runs in: the same thread settings in the command and its workers give the same results
bit for bit (a BLAS may round differently when it splits a product over threads).

A thread count the user set in the environment wins: with ``OMP_NUM_THREADS`` set, no pool is
touched (every BLAS falls back on it); with a BLAS's own variable set (``OPENBLAS_NUM_THREADS``,
``GOTO_NUM_THREADS``, ``MKL_NUM_THREADS``, ``BLIS_NUM_THREADS``, ``VECLIB_MAXIMUM_THREADS``),
the BLAS pools are left as the environment says and only OpenMP's is limited. Numba's own
threads (``NUMBA_NUM_THREADS``) are not touched: mobmanip's compiled kernels do not use them.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import sys
from collections.abc import Callable, Iterator
from typing import Any

from ..errors import ArgumentError

#: The variables each kind of pool (threadpoolctl's ``user_api``) reads when its library loads;
#: :func:`limit_threads` sets these for the kinds it limits.
VARIABLES: dict[str, tuple[str, ...]] = {
    "blas": ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS"),
    "openmp": ("OMP_NUM_THREADS",),
}

#: Variables a BLAS also reads (OpenBLAS's older name; OpenMP's, which every BLAS falls back on).
_BLAS_FALLBACKS = ("GOTO_NUM_THREADS", "OMP_NUM_THREADS")

#: The variables :func:`limit_threads` set and their values, while its block runs: they are not the user's.
_SET_HERE: dict[str, str] = {}


def _set_by_user(name: str, environ) -> bool:
    return name in environ and _SET_HERE.get(name) != environ[name]


def user_governed(environ=None) -> frozenset[str]:
    """The kinds of pool (``"blas"``, ``"openmp"``) whose thread count the user set in the
    environment (``os.environ`` by default); :func:`limit_threads` leaves those alone."""
    environ = os.environ if environ is None else environ
    governed = set()
    if _set_by_user("OMP_NUM_THREADS", environ):
        governed |= {"openmp", "blas"}
    if any(_set_by_user(name, environ) for name in (*VARIABLES["blas"], *_BLAS_FALLBACKS)):
        governed.add("blas")
    return frozenset(governed)


@contextlib.contextmanager
def limit_threads(limit: int = 1) -> Iterator[frozenset[str]]:
    """Run the block with at most ``limit`` threads in each BLAS and OpenMP pool the user did
    not size in the environment (:func:`user_governed`); yields the kinds of pool limited.

    Libraries already loaded are limited through threadpoolctl and get their thread counts back
    when the block ends. Libraries that load inside the block, and the child processes it
    starts (a sweep's workers, a ``local:N`` Dask cluster), read the limit from the environment
    variables of :data:`VARIABLES`, which the block sets and removes again when it ends; a
    library that loaded inside the block keeps the limit afterwards (it reads them only once).
    The environment is the process's: do not run blocks concurrently in several threads.

    Raises:
        ArgumentError: ``limit`` is not a positive integer.
    """
    kinds = _kinds_to_limit(limit)
    value = str(limit)
    before = {name: (os.environ.get(name), _SET_HERE.get(name)) for kind in kinds for name in VARIABLES[kind]}
    limiter = _apply(kinds, limit)
    try:
        yield kinds
    finally:
        if limiter is not None:
            limiter.restore_original_limits()
        for name, (environ_value, ours) in before.items():
            if os.environ.get(name) != value:  # the block set it itself: its value stays
                _SET_HERE.pop(name, None)
                continue
            if environ_value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = environ_value
            if ours is None:
                _SET_HERE.pop(name, None)
            else:
                _SET_HERE[name] = ours


def limit_process_threads(limit: int = 1) -> frozenset[str]:
    """Limit this process's pools for the rest of its life, as :func:`limit_threads` does for a
    block (the pools the user sized in the environment are left alone); returns the kinds of
    pool limited. For a worker process: calling it again is harmless.

    Raises:
        ArgumentError: ``limit`` is not a positive integer.
    """
    kinds = _kinds_to_limit(limit)
    _apply(kinds, limit)
    return kinds


def _kinds_to_limit(limit: int) -> frozenset[str]:
    if isinstance(limit, bool) or not isinstance(limit, int) or limit < 1:
        raise ArgumentError(f"a thread limit must be a positive integer, got {limit!r}")
    return frozenset(kind for kind in VARIABLES if kind not in user_governed())


def _apply(kinds: frozenset[str], limit: int):
    """Set the variables of ``kinds`` and limit their pools already loaded; threadpoolctl's
    limiter (which can restore them), or None when nothing was loaded."""
    for kind in kinds:
        for name in VARIABLES[kind]:
            os.environ[name] = _SET_HERE[name] = str(limit)
    # Every BLAS and OpenMP runtime this stack loads comes with NumPy (NumPy's own BLAS, SciPy's,
    # Pinocchio's); before NumPy has loaded the variables are enough, and threadpoolctl's import
    # is left out of a command's start.
    if not kinds or "numpy" not in sys.modules:
        return None
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=dict.fromkeys(kinds, limit))


class _Limited:
    """``fn`` called in a process whose pools are limited first (it travels to a worker, pickled,
    with its task: the worker must be able to import mobmanip)."""

    def __init__(self, fn: Callable[..., Any], limit: int):
        self.fn, self.limit = fn, limit

    def __call__(self, *args, **kwargs):
        limit_process_threads(self.limit)
        return self.fn(*args, **kwargs)


class LimitedExecutor(cf.Executor):
    """Another executor's tasks, each run in a worker whose BLAS and OpenMP pools are limited
    (:func:`limit_process_threads`) before it starts: for workers that this process did not start
    and that therefore do not inherit its limit, such as a remote Dask cluster's
    (``LimitedExecutor(client.get_executor())``). Futures are the wrapped executor's own."""

    def __init__(self, executor: cf.Executor, limit: int = 1):
        _kinds_to_limit(limit)  # checks the limit
        self.executor, self.limit = executor, limit

    def submit(self, fn, /, *args, **kwargs):
        return self.executor.submit(_Limited(fn, self.limit), *args, **kwargs)

    def map(self, fn, *iterables, **kwargs):
        return self.executor.map(_Limited(fn, self.limit), *iterables, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.executor.shutdown(wait=wait, cancel_futures=cancel_futures)


def describe_pools() -> str:
    """The thread pools loaded in this process and their threads, as one line (``-vv``)."""
    from threadpoolctl import threadpool_info

    pools = [f"{info['prefix']} ({info['user_api']}) {info['num_threads']}" for info in threadpool_info()]
    return ", ".join(pools) or "none loaded"
