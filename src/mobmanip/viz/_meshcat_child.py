"""The child process of :class:`mobmanip.viz.server.MeshcatServer`: meshcat's bridge on 127.0.0.1.

Run by file path (no ``mobmanip`` import, so it starts fast). Prints ``zmq_url=...`` and
``web_url=...`` on standard output, then serves until terminated or until ``--parent-pid`` has gone.
Exit code 3: the ``--port`` asked for is in use.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

# Run by path, this file's folder heads sys.path; keep its sibling modules from shadowing others.
if sys.path and os.path.abspath(sys.path[0]) == os.path.dirname(os.path.abspath(__file__)):
    del sys.path[0]

LOOPBACK = "127.0.0.1"
PORT_BUSY_EXIT = 3
PAGE_SCRIPT = Path(__file__).with_name("page.js")  # mobmanip's part of the page (mobmanip.viz.page)


#: Host names a request to the viewer may carry (with the server's port): a page of any other
#: origin, e.g. a DNS-rebinding attacker's name resolving to 127.0.0.1, is refused.
LOCAL_HOSTS = ("127.0.0.1", "localhost", "[::1]")
#: The HTTP port once the server listens (set in :func:`main`).
_SERVER: dict[str, int | None] = {"port": None}


def local_request(host: str | None, origin: str | None) -> bool:
    """Whether a request's Host (and Origin, if any) header names this server on loopback."""
    port = _SERVER["port"]
    allowed = {f"{name}:{port}" for name in LOCAL_HOSTS}
    if host is None or host.lower() not in allowed:
        return False
    if origin is None:
        return True
    return origin.lower() in {f"http://{name}" for name in allowed}


def _bridge_class():
    import tornado.web
    from meshcat.servers import zmqserver

    class LoopbackApplication(tornado.web.Application):
        def listen(self, port, address=LOOPBACK, **kwargs):
            return super().listen(port, address=address, **kwargs)

    class LocalStaticFiles(zmqserver.StaticFileHandlerNoCache):
        """The viewer's files, for requests naming this server only."""

        def prepare(self):
            if not local_request(self.request.headers.get("Host"), self.request.headers.get("Origin")):
                raise tornado.web.HTTPError(403, "foreign Host or Origin")
            return super().prepare()

    class Page(tornado.web.RequestHandler):
        """meshcat's page with mobmanip's script (legend, camera; see ``page.js``) before ``</body>``."""

        def prepare(self):
            if not local_request(self.request.headers.get("Host"), self.request.headers.get("Origin")):
                raise tornado.web.HTTPError(403, "foreign Host or Origin")

        def get(self, _name=None):
            html = Path(zmqserver.VIEWER_ROOT, zmqserver.VIEWER_HTML).read_text(encoding="utf-8")
            script = "<script>\n" + PAGE_SCRIPT.read_text(encoding="utf-8") + "\n</script>\n"
            at = html.rfind("</body>")
            self.set_header("Content-Type", "text/html; charset=utf-8")
            self.set_header("Cache-Control", "no-store, no-cache, must-revalidate, max-age=0")
            self.write(html[:at] + script + html[at:] if at >= 0 else html + script)

    class LocalWebSocket(zmqserver.WebSocketHandler):
        """The scene's websocket, for pages served by this server only."""

        def prepare(self):
            if not local_request(self.request.headers.get("Host"), self.request.headers.get("Origin")):
                raise tornado.web.HTTPError(403, "foreign Host or Origin")
            return super().prepare()

        def check_origin(self, origin):
            return local_request(self.request.headers.get("Host"), origin)

    class LoopbackBridge(zmqserver.ZMQWebSocketBridge):
        """meshcat's bridge with its web server bound to 127.0.0.1, answering local pages only."""

        def make_app(self):
            return LoopbackApplication(
                [
                    (r"/static/(index\.html)?", Page),
                    (
                        r"/static/(.*)",
                        LocalStaticFiles,
                        {"path": zmqserver.VIEWER_ROOT, "default_filename": zmqserver.VIEWER_HTML},
                    ),
                    (r"/", LocalWebSocket, {"bridge": self}),
                ]
            )

    return LoopbackBridge


def _watch_parent(bridge, parent_pid: int) -> None:
    import tornado.ioloop

    def check():
        try:
            os.kill(parent_pid, 0)
        except ProcessLookupError:
            bridge.ioloop.stop()
            return
        except PermissionError:  # pid reused by another user's process: the parent is gone
            bridge.ioloop.stop()
            return

    tornado.ioloop.PeriodicCallback(check, 1000).start()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="meshcat server on 127.0.0.1 (started by mobmanip)")
    parser.add_argument("--port", type=int, default=None, help="HTTP port (default: first free from 7000)")
    parser.add_argument("--parent-pid", type=int, default=None, help="stop when this process has gone")
    args = parser.parse_args(argv)
    bridge_class = _bridge_class()
    try:
        bridge = bridge_class(host=LOOPBACK, port=args.port)
    except OSError as exc:  # only with an explicit --port: without it meshcat scans on
        print(f"port {args.port} is in use: {exc}", file=sys.stderr)
        return PORT_BUSY_EXIT
    _SERVER["port"] = int(bridge.web_url.rsplit(":", 1)[1].split("/", 1)[0])
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}")
    sys.stdout.flush()
    # Nobody reads our stdout after the two lines: send later output to the log.
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    if args.parent_pid is not None:
        _watch_parent(bridge, args.parent_pid)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
