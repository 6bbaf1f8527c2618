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

Before Dask connects to a ``tcp://`` address, :func:`probe_scheduler` opens the socket itself,
with a bounded wait, and reads the handshake a Dask scheduler sends first (a small msgpack
message behind a length): a port that accepts and never answers, or that answers with anything
else (a web server, junk bytes, a length of exabytes), is refused in one line naming ``--dask``
and the address, before Dask would wait forever or allocate what the junk asks for.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import socket
import struct
import time
from collections.abc import Iterator

from ..errors import ClusterError
from .threads import LimitedExecutor

_log = logging.getLogger(__name__)

#: Seconds to wait for a scheduler before refusing the address.
CONNECT_TIMEOUT = 5.0
#: Most bytes a scheduler's handshake may take (a Dask handshake is about a hundred).
MAX_HANDSHAKE_BYTES = 1 << 16
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


def _tcp_host_port(address: str) -> tuple[str, int] | None:
    """``(host, port)`` of a ``tcp://HOST:PORT`` (or ``HOST:PORT``) address; None for other
    schemes, an address without a port (left to Dask) or a local cluster.

    Raises:
        ClusterError: a tcp address without a valid port.
    """
    if parse_local(address) is not None:
        return None
    scheme, _, location = address.rpartition("://")
    if scheme not in ("", "tcp"):
        return None
    host, colon, port = location.rpartition(":")
    if not colon or location.endswith("]"):
        return None  # no port: Dask's own default applies, and Dask connects as before
    host = host.strip("[]")
    try:
        number = int(port)
    except ValueError:
        number = -1
    if not host or not 0 < number < 65536:
        raise ClusterError(address, "a scheduler address looks like tcp://HOST:PORT with a port from 1 to 65535")
    return host, number


def _receive(connection: socket.socket, n: int, deadline: float, address: str, timeout: float) -> bytes:
    """Exactly ``n`` bytes from ``connection`` before ``deadline`` (a monotonic time)."""
    data = bytearray()
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError
        connection.settimeout(left)
        chunk = connection.recv(n - len(data))
        if not chunk:
            shown = f" after {bytes(data[:16])!r}" if data else ""
            raise ClusterError(
                address, f"the port accepted and closed the connection{shown}: not a Dask scheduler at that address"
            )
        data += chunk
    return bytes(data)


def probe_scheduler(address: str, timeout: float | None = None) -> None:
    """Check that a Dask scheduler answers at a ``tcp://`` ``address`` within ``timeout`` seconds
    (default :data:`CONNECT_TIMEOUT`; connecting and its handshake together); other schemes and
    ``local:N`` are not probed.

    Raises:
        ClusterError: nothing listens there, it does not answer in time, or what answers is not
            a Dask scheduler (the first bytes it sent are shown).
    """
    where = _tcp_host_port(address)
    if where is None:
        return
    timeout = CONNECT_TIMEOUT if timeout is None else timeout
    deadline = time.monotonic() + timeout
    try:
        connection = socket.create_connection(where, timeout=timeout)
    except OSError as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ClusterError(address, f"cannot reach the Dask scheduler within {timeout:g} s ({reason})") from None
    with connection:
        try:
            head = _receive(connection, 8, deadline, address, timeout)
            (length,) = struct.unpack("<Q", head)
            if not 16 <= length <= MAX_HANDSHAKE_BYTES:
                raise ClusterError(address, f"what answers sent {head!r}, not a Dask handshake: not a Dask scheduler "
                                            "at that address")  # fmt: skip
            body = _receive(connection, length, deadline, address, timeout)
        except TimeoutError:
            raise ClusterError(
                address,
                f"the port accepts connections but sends no Dask handshake within {timeout:g} s: no Dask scheduler "
                "answers at that address",
            ) from None
        except OSError as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise ClusterError(address, f"cannot reach the Dask scheduler within {timeout:g} s ({reason})") from None
    if not _is_handshake(body):
        raise ClusterError(address, f"what answers sent {(head + body)[:24]!r}, not a Dask handshake: not a Dask "
                                    "scheduler at that address")  # fmt: skip


def _is_handshake(body: bytes) -> bool:
    """Whether ``body`` (the bytes behind the length) decodes to a Dask handshake message."""
    try:
        from distributed.protocol.core import loads
        from distributed.protocol.utils import unpack_frames

        frames = unpack_frames(body)
        message = loads(frames, deserialize=False)
    except Exception:  # junk: any error of the decoders
        return False
    return isinstance(message, dict) and "pickle-protocol" in message and "python" in message


@contextlib.contextmanager
def dask_executor(address: str, timeout: float | None = None) -> Iterator[cf.Executor]:
    """A Dask client's executor for ``address``; the client (and a local cluster) close on exit.

    Args:
        address: ``tcp://HOST:PORT`` (any address ``dask.distributed.Client`` accepts), or
            ``local:N`` for a local cluster of N single-threaded worker processes.
        timeout: seconds to wait for the scheduler (default :data:`CONNECT_TIMEOUT`).

    Raises:
        ClusterError: Dask is not installed, the scheduler does not answer within ``timeout``, or
            what answers is not a Dask scheduler (see :func:`probe_scheduler`).
    """
    check_address(address)
    timeout = CONNECT_TIMEOUT if timeout is None else timeout
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
            probe_scheduler(address, timeout)  # a silent port or another server: refused here, in time
            try:
                client = stack.enter_context(Client(address, timeout=timeout))
            except (OSError, TimeoutError, ValueError) as exc:
                reason = " ".join(str(exc).split()) or type(exc).__name__
                if len(reason) > 160:
                    reason = reason[:157] + "..."
                reason = f"cannot reach the Dask scheduler within {timeout:g} s ({reason})"
                raise ClusterError(address, reason) from None
        _log.info("dask: %s, %d worker(s)", client.scheduler.address, len(client.scheduler_info()["workers"]))
        # workers this process did not start run each task with one BLAS thread, as here: the same
        # numbers whichever process computes them (a remote worker's default pools differ in the
        # last bits, and a map's file would not equal the serial one's)
        yield LimitedExecutor(client.get_executor())
