"""The meshcat server, run as a child process that listens on the loopback interface only.

meshcat 0.3.2's own ``meshcat-server`` (``meshcat.servers.zmqserver``) scans for a free HTTP port
from 7000 upwards (and a free ZeroMQ port from 6000), printing ``Port: N in use, trying
another...`` for each busy one, but it has no option to ask for a port, and although it prints a
``127.0.0.1`` URL its web server listens on every interface. This module runs the same bridge
(``ZMQWebSocketBridge``) with two changes: the web server binds to 127.0.0.1, and ``--port N``
asks for exactly port N and fails with a clear message when N is busy (without ``--port`` it
scans from 7000 like meshcat). It also stops by itself when the process that started it has
gone (a parent killed with SIGKILL cannot clean up after itself).

:class:`MeshcatServer` starts and stops the child, :mod:`._meshcat_child`.
"""

from __future__ import annotations

import atexit
import os
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

from ..errors import PortBusyError, ViewerError

LOOPBACK = "127.0.0.1"
DEFAULT_PORT = 7000  # meshcat's DEFAULT_FILESERVER_PORT: the scan starts here
_PORT_BUSY_EXIT = 3  # the child's exit code when --port is in use
_CHILD = Path(__file__).with_name("_meshcat_child.py")


class MeshcatServer:
    """A meshcat server in a child process, bound to 127.0.0.1.

    Args:
        port: HTTP port of the viewer page; ``None`` takes the first free one from 7000.
        startup_timeout: seconds to wait for the server to report its URLs.

    Attributes:
        web_url: the viewer page, e.g. ``http://127.0.0.1:7000/static/``.
        zmq_url: where the Python side sends scene commands.
        port: the HTTP port in use.
        pid: process id of the server.

    Raises:
        PortBusyError: ``port`` is in use.
        ViewerError: the server did not start.
    """

    def __init__(self, port: int | None = None, startup_timeout: float = 30.0):
        if port is not None and not (0 < int(port) < 65536):
            raise ViewerError(f"--port must be in 1..65535, got {port}")
        self._log = tempfile.TemporaryFile(mode="w+b")
        args = [sys.executable, "-u", str(_CHILD), "--parent-pid", str(os.getpid())]
        if port is not None:
            args += ["--port", str(int(port))]
        # A session of its own: Ctrl-C in the terminal reaches only us, and close() stops the child.
        self._proc = subprocess.Popen(
            args, stdout=subprocess.PIPE, stderr=self._log, stdin=subprocess.DEVNULL, start_new_session=True
        )
        self.pid = self._proc.pid
        atexit.register(self.stop)
        lines = self._read_lines(2, startup_timeout)
        urls = dict(line.split("=", 1) for line in lines if "=" in line)
        if "zmq_url" not in urls or "web_url" not in urls:
            try:  # its stdout closed: it is exiting; otherwise it is stuck
                code = self._proc.wait(2.0)
            except subprocess.TimeoutExpired:
                code = None
            log = self._log_tail()
            self.stop()
            if code == _PORT_BUSY_EXIT and port is not None:
                raise PortBusyError(int(port), DEFAULT_PORT)
            what = "did not answer in time" if code is None else f"exited with code {code}"
            raise ViewerError(f"the meshcat server did not start ({what}): {log}")
        self.zmq_url = urls["zmq_url"]
        self.web_url = urls["web_url"]
        self.port = int(self.web_url.rsplit(":", 1)[1].split("/", 1)[0])

    def _read_lines(self, count: int, timeout: float) -> list[str]:
        lines: list[str] = []

        def reader():
            for _ in range(count):
                line = self._proc.stdout.readline()
                if not line:
                    return
                lines.append(line.decode("utf-8").strip())

        thread = threading.Thread(target=reader, daemon=True)
        thread.start()
        thread.join(timeout)
        return list(lines)

    def _log_tail(self) -> str:
        try:
            self._log.seek(0)
            text = self._log.read().decode("utf-8", "replace").strip()
        except (OSError, ValueError):
            return "no log"
        return " | ".join(text.splitlines()[-3:]) or "no output"

    @property
    def running(self) -> bool:
        return self._proc.poll() is None

    def stop(self, timeout: float = 5.0) -> None:
        """Stop the server (SIGTERM, then SIGKILL after ``timeout`` s). Safe to call twice."""
        proc = self._proc
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if proc.stdout is not None and not proc.stdout.closed:
            proc.stdout.close()
        if not self._log.closed:
            self._log.close()
        atexit.unregister(self.stop)
