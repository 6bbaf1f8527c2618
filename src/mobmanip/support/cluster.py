"""Dask clusters for the command line: ``--dask ADDRESS`` or ``--dask local:N``.

:func:`dask_executor` connects to a running ``dask scheduler`` (``tcp://host:8786``) or starts a
:class:`dask.distributed.LocalCluster` of N single-threaded worker processes, and yields the
client's :class:`concurrent.futures.Executor`. Work submitted through it runs on Dask's
distributed scheduler: a worker that dies loses no result, because the scheduler runs its tasks
again on the workers left (up to ``distributed.scheduler.allowed-failures`` times per task).

The workers must be able to import mobmanip (the same version as the client) and, for a robot
given by spec path, read that path; the commands pass spec paths as absolute paths. Results equal
a serial run's bit for bit when the workers run the same NumPy and BLAS with the same thread
settings (an optimiser amplifies rounding differences): a ``local:N`` cluster's workers keep this
process's BLAS thread settings (Dask's nanny would otherwise set them to one thread).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
from collections.abc import Iterator

from ..errors import ClusterError

_log = logging.getLogger(__name__)

#: Seconds to wait for a scheduler before refusing the address.
CONNECT_TIMEOUT = 5.0
#: Most worker processes ``local:N`` starts.
MAX_LOCAL_WORKERS = 256


#: Environment variables that set BLAS's threads.
_BLAS_THREADS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def parse_local(address: str) -> int | None:
    """N for ``local:N`` (``local`` alone: 2), None for a scheduler address.

    Raises:
        ClusterError: ``local:`` with something other than a count from 1 to :data:`MAX_LOCAL_WORKERS`.
    """
    if address != "local" and not address.startswith("local:"):
        return None
    text = address.partition(":")[2] or "2"
    try:
        n = int(text)
    except ValueError:
        n = 0
    if not 1 <= n <= MAX_LOCAL_WORKERS:
        raise ClusterError(address, f"local:N needs a worker count N from 1 to {MAX_LOCAL_WORKERS}")
    return n


def check_address(address: str) -> None:
    """Refuse a malformed ``--dask`` value before any work (reachability is checked on connecting).

    Raises:
        ClusterError: empty, or ``local:`` with a bad count.
    """
    if not address or not address.strip():
        raise ClusterError(address, "give a scheduler address (tcp://HOST:PORT) or local:N")
    if parse_local(address) is None and "://" not in address and ":" not in address:
        raise ClusterError(address, "a scheduler address looks like tcp://HOST:PORT (or give local:N)")


@contextlib.contextmanager
def dask_executor(address: str, timeout: float = CONNECT_TIMEOUT) -> Iterator[cf.Executor]:
    """A Dask client's executor for ``address``; the client (and a local cluster) close on exit.

    Args:
        address: ``tcp://HOST:PORT`` (any address ``dask.distributed.Client`` accepts), or
            ``local:N`` for a local cluster of N single-threaded worker processes.
        timeout: seconds to wait for the scheduler.

    Raises:
        ClusterError: Dask is not installed, or the scheduler does not answer within ``timeout``.
    """
    check_address(address)
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ClusterError(address, "needs Dask's distributed scheduler: pip install 'dask[distributed]'") from None
    n = parse_local(address)
    with contextlib.ExitStack() as stack:
        if n is not None:
            import os

            import dask

            keep = {k: os.environ[k] for k in _BLAS_THREADS if k in os.environ}
            environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
                       if k not in _BLAS_THREADS}  # fmt: skip
            stack.enter_context(dask.config.set({"distributed.nanny.pre-spawn-environ": {**environ, **keep}}))
            cluster = stack.enter_context(
                LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
            )
            client = stack.enter_context(Client(cluster))
        else:
            try:
                client = stack.enter_context(Client(address, timeout=timeout))
            except (OSError, TimeoutError, ValueError) as exc:
                reason = " ".join(str(exc).split()) or type(exc).__name__
                if len(reason) > 160:
                    reason = reason[:157] + "..."
                reason = f"cannot reach the Dask scheduler within {timeout:g} s ({reason})"
                raise ClusterError(address, reason) from None
        _log.info("dask: %s, %d worker(s)", client.scheduler.address, len(client.scheduler_info()["workers"]))
        yield client.get_executor()
