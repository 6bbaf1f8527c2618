"""What the robot's viewer (:mod:`mobmanip.viz.scene`) and the team's
(:mod:`mobmanip.viz.team_scene`) share: a meshcat scene on a server of its own.

:class:`MeshcatScene` starts the server (:mod:`mobmanip.viz.server`) and connects to it, turns a
server that stopped answering into a :class:`~mobmanip.errors.ViewerError`, keeps what the page
shows (:mod:`mobmanip.viz.page`), writes the scene as one HTML page and stops the server.
"""

from __future__ import annotations

import contextlib
import io
import warnings
import webbrowser
from collections.abc import Iterator
from pathlib import Path
from typing import Self

import numpy as np

from ..support.files import write_text
from . import page as _page
from .compact_page import compact
from .server import MeshcatServer, ViewerError

__all__ = ["PAGE_PATH", "MeshcatScene"]

#: The scene path whose property carries what the page's script shows (legend, camera).
PAGE_PATH = "mobmanip"


class MeshcatScene:
    """A meshcat scene on a server of its own (a child process on 127.0.0.1), closed by
    :meth:`close` or by leaving a ``with`` block. A viewer's constructor draws its scene inside
    :meth:`_starting`."""

    _closed: bool
    _server: MeshcatServer

    @contextlib.contextmanager
    def _starting(self, port: int | None, timeout: float) -> Iterator[None]:
        """Start the server on ``port`` (``None``: the first free one from 7000) and connect to
        it, each command waiting at most ``timeout`` s for an answer; the block draws the scene.
        If the block fails, the server is stopped and the error raised."""
        import zmq

        with warnings.catch_warnings():  # meshcat 0.3.2 imports pyzmq's deprecated zmq.eventloop.ioloop
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat

        self._closed = False
        self._page: dict = {}  # what page.js shows (see mobmanip.viz.page)
        self._camera_serial = 0
        self._server = MeshcatServer(port)
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL; we print ours
                self._vis = meshcat.Visualizer(zmq_url=self._server.zmq_url)
            socket = self._vis.window.zmq_socket
            socket.setsockopt(zmq.LINGER, 0)
            socket.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
            socket.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
            yield
        except BaseException:
            self._server.stop()
            raise

    @contextlib.contextmanager
    def _commands(self) -> Iterator[None]:
        """Turn a silent server (zmq timeout) into a ViewerError."""
        import zmq

        if self._closed:
            raise ViewerError("the viewer is closed")
        try:
            yield
        except zmq.error.Again:  # the request socket cannot be used again: give up on this viewer
            exited = "" if self._server.running else " (it has exited)"
            self.close()
            raise ViewerError(
                f"the meshcat server (pid {self._server.pid}) stopped answering{exited}; the viewer is closed"
            ) from None

    def __getitem__(self, path: str):
        """The meshcat ``Visualizer`` at a scene path (e.g. ``viewer["mobmanip/locked"]``)."""
        return self._vis[path]

    @property
    def url(self) -> str:
        """The viewer page, e.g. ``http://127.0.0.1:7000/static/``."""
        return self._server.web_url

    @property
    def port(self) -> int:
        return self._server.port

    @property
    def server_pid(self) -> int:
        """Process id of the meshcat server."""
        return self._server.pid

    @property
    def server_running(self) -> bool:
        return self._server.running

    def open(self) -> None:
        """Open the viewer page in the default web browser."""
        webbrowser.open(self.url, new=2)

    # ----- the page (mobmanip.viz.page)

    def _send_page(self, **changes) -> None:
        """Update what the page shows (legend, camera) if it changed."""
        page = {**self._page, **changes}
        if page != self._page:
            self._vis[PAGE_PATH].set_property(_page.PAGE_PROPERTY, page)
            self._page = page

    def _send_fit(self, points: np.ndarray, boxes: list, heading: float) -> dict:
        """Ask the page to frame ``points`` (n, 3) and ``boxes``, seen from ``heading`` (rad);
        returns the camera request sent."""
        self._camera_serial += 1
        request = _page.fit_request(points, boxes, heading, self._camera_serial)
        with self._commands():
            self._send_page(camera=request)
        return request

    def _send_animation_camera(self, frames: list[np.ndarray], times: list, heading: float) -> dict:
        """Ask the page to frame an animation whose frames draw ``frames`` (points (n_k, 3) each)
        at ``times`` (each frame's keyframe times, s), framed whole or followed
        (:func:`mobmanip.viz.page.animation_request`); returns the camera request sent."""
        self._camera_serial += 1
        request = _page.animation_request(frames, times, heading, self._camera_serial)
        with self._commands():
            self._send_page(camera=request)
        return request

    # ----- output and shutdown

    def static_html(self) -> str:
        """The scene (with its animation, if any) as one self-contained HTML page: meshcat's
        ``static_html`` with each mesh file kept once, compressed (:mod:`mobmanip.viz.compact_page`)."""
        with self._commands():
            return _page.inject(compact(self._vis.static_html()))

    def export_html(self, path: str | Path) -> Path:
        """Write the scene (with its animation, if any) as a self-contained HTML page."""
        path = Path(path)
        write_text(path, self.static_html())
        return path

    def close(self) -> None:
        """Disconnect and stop the meshcat server. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(Exception):
            self._vis.window.zmq_socket.close(linger=0)
        self._server.stop()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
