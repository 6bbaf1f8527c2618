"""Hostile ``--dask`` addresses: a port that accepts and never answers, a web server, junk bytes
(among them a length of exabytes) or a peer that hangs up are refused in one line naming
``--dask`` and the address, within the connection timeout, by ``place --map``, ``team
--sweep-heading``, ``sweep`` and ``site`` alike, never "out of memory", never a hang. The
servers are sockets of this test, on localhost."""

from __future__ import annotations

import signal
import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from hostile_util import assert_one_line_error, run_cli

pytest.importorskip("distributed")

from mobmanip.errors import ClusterError  # noqa: E402
from mobmanip.support import cluster  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT = 1.0  # the connection timeout in these tests (s)

COMMANDS = {
    "place --map": ["place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x",
                    "--map-cells", "3", "--map", "MAP", "--no-progress"],
    "team --sweep-heading": ["team", str(ROOT / "examples" / "beam_team.toml"), "--sweep-heading=-10:10:3",
                             "--no-progress"],
    "sweep": ["sweep", "planar_dual_arm", "--angle", "0:90:2", "--distance", "1", "--no-progress"],
    "site": ["site", str(ROOT / "examples" / "site_planar.toml"), "-o", "SITE", "--no-progress"],
}  # fmt: skip


class Server:
    """A TCP server on localhost whose every connection gets ``reply`` (bytes sent at once,
    None: nothing ever) and is then held open, or closed when ``hang_up``."""

    def __init__(self, reply: bytes | None, hang_up: bool = False):
        self.reply, self.hang_up = reply, hang_up
        self.socket = socket.create_server(("127.0.0.1", 0))
        self.socket.settimeout(0.2)
        self.address = f"tcp://127.0.0.1:{self.socket.getsockname()[1]}"
        self.held: list[socket.socket] = []
        self.accepted = 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)

    def _serve(self):
        while not self.stop.is_set():
            try:
                connection, _ = self.socket.accept()
            except TimeoutError:
                continue
            self.accepted += 1
            if self.reply:
                connection.sendall(self.reply)
            if self.hang_up:
                connection.close()
            else:
                self.held.append(connection)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join(timeout=5)
        for connection in self.held:
            connection.close()
        self.socket.close()


def _frames(length: int, body: bytes = b"") -> bytes:
    return struct.pack("<Q", length) + body


HOSTILE = {
    "silent": (None, False, "sends no Dask handshake within 1 s"),
    "http-response": (b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nok", False, "b'HTTP/1.1'"),
    "junk": (b"\xff" * 64, False, "b'\\xff\\xff\\xff\\xff\\xff\\xff\\xff\\xff'"),
    "exabytes": (_frames(2**63 - 1), False, "b'\\xff\\xff\\xff\\xff\\xff\\xff\\xff\\x7f'"),
    "eight-gigabytes": (_frames(8 << 30), False, "not a Dask handshake"),
    "short-junk": (_frames(40, bytes(range(40))), False, "not a Dask handshake"),
    "hang-up": (None, True, "accepted and closed the connection"),
    "half-a-handshake": (_frames(100, b"\x01" * 20), True, "accepted and closed the connection after"),
}


@pytest.fixture(autouse=True)
def short_timeout(monkeypatch):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", TIMEOUT)


@pytest.fixture(autouse=True)
def no_hang():
    """A test that still waits after 10 s fails (SIGALRM interrupts the wait) instead of hanging
    the run, which is what an unbounded wait for a scheduler did."""

    def hung(signum, frame):
        raise TimeoutError("still waiting after 10 s: the wait for the scheduler is not bounded")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.setitimer(signal.ITIMER_REAL, 10.0)
    yield
    signal.setitimer(signal.ITIMER_REAL, 0)
    signal.signal(signal.SIGALRM, previous)


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("kind", ["silent", "http-response", "exabytes"])
def test_the_commands_refuse_what_is_not_a_scheduler_in_one_line_and_in_time(capfd, tmp_path, monkeypatch,
                                                                             command, kind):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    reply, hang_up, needle = HOSTILE[kind]
    with Server(reply, hang_up) as server:
        started = time.monotonic()
        code, out, err = run_cli(capfd, *COMMANDS[command], "--dask", server.address)
        seconds = time.monotonic() - started
    line = assert_one_line_error(code, err, f"--dask {server.address}", needle)
    assert "memory" not in line
    assert server.accepted >= 1
    assert seconds < TIMEOUT + 3.0, seconds
    assert not list(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize("kind", list(HOSTILE))
def test_each_kind_of_impostor_is_named(kind):
    reply, hang_up, needle = HOSTILE[kind]
    with Server(reply, hang_up) as server:
        started = time.monotonic()
        with pytest.raises(ClusterError) as caught:
            with cluster.dask_executor(server.address):
                pass
        seconds = time.monotonic() - started
    message = str(caught.value)
    assert message.startswith(f"--dask {server.address}: "), message
    assert needle in message, message
    assert "\n" not in message and "memory" not in message
    if kind != "silent":
        assert "not a Dask scheduler at that address" in message
    assert seconds < TIMEOUT + 1.0, seconds


def test_a_silent_port_is_refused_after_the_timeout_not_before():
    with Server(None) as server:
        started = time.monotonic()
        with pytest.raises(ClusterError, match="no Dask scheduler answers at that address"):
            cluster.probe_scheduler(server.address, timeout=0.5)
        seconds = time.monotonic() - started
    assert 0.5 <= seconds < 1.5, seconds


def test_a_handshake_sent_slowly_shares_one_deadline():
    """Bytes that trickle in (each within the timeout) do not extend it: the whole handshake has
    one deadline."""
    ready = threading.Event()
    listener = socket.create_server(("127.0.0.1", 0))
    address = f"tcp://127.0.0.1:{listener.getsockname()[1]}"

    def trickle():
        connection, _ = listener.accept()
        ready.set()
        for byte in _frames(64, b"\x00" * 64):
            try:
                connection.sendall(bytes([byte]))
            except OSError:
                break
            time.sleep(0.1)
        connection.close()

    thread = threading.Thread(target=trickle, daemon=True)
    thread.start()
    started = time.monotonic()
    with pytest.raises(ClusterError, match="sends no Dask handshake within 0.5 s"):
        cluster.probe_scheduler(address, timeout=0.5)
    assert time.monotonic() - started < 1.0
    thread.join(timeout=10)
    listener.close()


@pytest.mark.parametrize(
    "address", ["tcp://127.0.0.1:0", "tcp://127.0.0.1:99999", "tcp://127.0.0.1:port", "tcp://:8786"]
)
def test_a_tcp_address_needs_a_host_and_a_port(address):
    with pytest.raises(ClusterError, match="tcp://HOST:PORT with a port from 1 to 65535") as caught:
        cluster.probe_scheduler(address)
    assert str(caught.value).startswith(f"--dask {address}: ")


def test_a_closed_port_is_still_refused_as_unreachable():
    with socket.create_server(("127.0.0.1", 0)) as spare:
        port = spare.getsockname()[1]
    with pytest.raises(ClusterError, match=r"cannot reach the Dask scheduler within 1 s \(.*refused"):
        cluster.probe_scheduler(f"tcp://127.0.0.1:{port}", timeout=1.0)


def test_a_real_handshake_passes_the_probe():
    """A listener of Dask's own comm layer (what a scheduler listens with) passes the probe; a
    whole scheduler is exercised in test_cluster.py."""
    import asyncio

    from distributed.comm import listen

    found: dict = {}
    done = threading.Event()

    async def main():
        async def handler(comm):
            await comm.close()

        listener = listen("tcp://127.0.0.1:0", handler)
        await listener.start()
        found["address"] = listener.contact_address
        while not done.is_set():
            await asyncio.sleep(0.02)
        listener.stop()

    thread = threading.Thread(target=asyncio.run, args=(main(),), daemon=True)
    thread.start()
    while "address" not in found and thread.is_alive():
        time.sleep(0.01)
    try:
        cluster.probe_scheduler(found["address"], timeout=TIMEOUT)
    finally:
        done.set()
        thread.join(timeout=5)


@pytest.mark.parametrize("address", ["tcp://scheduler", "tls://127.0.0.1:8786", "local:2", "tcp://[::1]"])
def test_addresses_dask_resolves_itself_are_not_probed(address):
    """No port (Dask's default applies), another scheme or a local cluster: left to Dask."""
    assert cluster._tcp_host_port(address) is None
    cluster.probe_scheduler(address, timeout=0.1)  # returns at once, opening nothing
