"""A team in the meshcat viewer: every robot with its meshes, the object and the team's sets.

Scene paths (under meshcat's root ``/meshcat``):

================================== ==============================================================
``mobmanip/team/robots/NAME``      robot ``NAME``'s visual geometry (Pinocchio's
                                   ``MeshcatVisualizer``), at its configuration
``mobmanip/team/object``           the object: a white sphere at its centre and a brown segment
                                   from it to each grasping hand
``mobmanip/team/sets/K``           the team's set of measure ``K``, drawn at the object's centre
                                   by the drawing of its kind (:mod:`mobmanip.viz.shapes`), in the
                                   measure's colour, at the scale of its quantity
================================== ==============================================================

Only the linear part of a task is drawn (as for one robot). Scales: metres of scene per unit of
each quantity, so that the largest drawn extent of that quantity's sets is ``size``.
"""

from __future__ import annotations

import contextlib
import io
import warnings
import webbrowser
from pathlib import Path

import numpy as np

from ..measures import get_measure
from ..support.files import write_text
from ..team.analysis import TeamAnalysis
from .nesting import nested, outlined
from .scene import DEFAULT_SIZE, OBJECT_COLOR, OBJECT_RADIUS, planar_thickness, scene_color, visual_model
from .server import MeshcatServer, ViewerError
from .shapes import DRAWINGS, line_material, translation

__all__ = ["TEAM_PATH", "TeamViewer"]

TEAM_PATH = "mobmanip/team"
OBJECT_LINK_COLOR = 0x8C6D31


class TeamViewer:
    """The team's scene on a meshcat server of its own (closed by :meth:`close`).

    Args:
        analysis: the analysed team (its measures are drawn).
        port: HTTP port of the viewer page; ``None`` takes the first free one from 7000.
        open_browser: open the page in the default browser.
        size: the largest drawn extent of each quantity's sets (m).
        timeout: seconds to wait for the server to answer a command.

    Attributes:
        scales: metres of scene per task unit, by quantity name (``"velocity"``, ...).
        mesh_notes: one line per mesh left out of the drawing.
        undrawn: measures whose sets have no drawing, by name: set kind.

    Raises:
        PortBusyError: ``port`` is in use; ViewerError: the server did not start or answer.
    """

    def __init__(
        self,
        analysis: TeamAnalysis,
        *,
        port: int | None = None,
        open_browser: bool = False,
        size: float = DEFAULT_SIZE,
        timeout: float = 60.0,
    ):
        import zmq

        with warnings.catch_warnings():  # meshcat 0.3.2 imports pyzmq's deprecated zmq.eventloop.ioloop
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat
        self.analysis = analysis
        self.mesh_notes: list[str] = []
        self.undrawn: dict[str, str] = {}
        #: The team's sets drawn as outlines (they contain, as drawn, the sets listed).
        self.outlined: dict[str, tuple[str, ...]] = {}
        self._closed = False
        self._server = MeshcatServer(port)
        try:
            with contextlib.redirect_stdout(io.StringIO()):
                self._vis = meshcat.Visualizer(zmq_url=self._server.zmq_url)
            socket = self._vis.window.zmq_socket
            socket.setsockopt(zmq.LINGER, 0)
            socket.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
            socket.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
            with self._commands():
                self._draw_robots()
                self._draw_object()
                self.scales = self._draw_sets(size)
        except BaseException:
            self._server.stop()
            raise
        if open_browser:
            webbrowser.open(self.url, new=2)

    # ----- drawing

    def _draw_robots(self) -> None:
        from pinocchio.visualize import MeshcatVisualizer

        self._robots = {}
        for member in self.analysis.team.members:
            model, geometry = visual_model(member.robot, self.mesh_notes)
            viz = MeshcatVisualizer(model, None, geometry)
            viz.initViewer(viewer=self._vis)
            viz.loadViewerModel(rootNodeName=f"{TEAM_PATH}/robots/{member.name}")
            viz.display(member.q)
            self._robots[member.name] = viz

    def _draw_object(self) -> None:
        import meshcat.geometry as mg

        obj = self.analysis.team.held_object
        path = f"{TEAM_PATH}/object"
        self._vis[f"{path}/center"].set_object(mg.Sphere(OBJECT_RADIUS), mg.MeshPhongMaterial(color=OBJECT_COLOR))
        segments = np.zeros((3, 2 * len(obj.offsets)), dtype=np.float32)
        segments[:, 1::2] = obj.offsets.T
        self._vis[f"{path}/grasps"].set_object(
            mg.LineSegments(mg.PointsGeometry(segments), line_material(OBJECT_LINK_COLOR))
        )
        self._vis[path].set_transform(translation(obj.center))

    def _draw_sets(self, size: float) -> dict[str, float]:
        task = self.analysis.team.task
        sets = {}
        for name, task_set in self.analysis.measures.items():
            if task_set.kind in DRAWINGS:
                sets[name] = task_set
            else:
                self.undrawn[name] = task_set.kind
        largest: dict[str, float] = {}
        for name, task_set in sets.items():
            quantity = get_measure(name).quantity.name
            extent = DRAWINGS[task_set.kind].extent(task_set, task)
            largest[quantity] = max(largest.get(quantity, 0.0), extent)
        scales = {q: (size / e if e > 0.0 else 1.0) for q, e in largest.items()}
        center = self.analysis.team.held_object.center
        self.outlined = outlined(nested(sets, task, lambda name: scales[get_measure(name).quantity.name]))
        for name, task_set in sets.items():
            drawing, path = DRAWINGS[task_set.kind], self.scene_path(name)
            drawing.load(self._vis, path, scene_color(name), False)
            set_outlined = getattr(drawing, "set_outlined", None)
            if set_outlined is not None:
                set_outlined(self._vis, path, name in self.outlined)
            if task_set.empty:
                self._vis[path].set_property("visible", False)
                continue
            scale = scales[get_measure(name).quantity.name]
            drawing.draw(self._vis, path, task_set, task, center, scale, planar_thickness(name))
        return scales

    @staticmethod
    def scene_path(name: str) -> str:
        """Where the team's set of measure ``name`` is drawn."""
        return f"{TEAM_PATH}/sets/{get_measure(name).name}"

    # ----- plumbing

    @contextlib.contextmanager
    def _commands(self):
        import zmq

        if self._closed:
            raise ViewerError("the viewer is closed")
        try:
            yield
        except zmq.error.Again:
            self.close()
            raise ViewerError(f"the meshcat server (pid {self._server.pid}) stopped answering; closed") from None

    def __getitem__(self, path: str):
        """The meshcat ``Visualizer`` at a scene path."""
        return self._vis[path]

    @property
    def url(self) -> str:
        """The viewer page."""
        return self._server.web_url

    def static_html(self) -> str:
        """The scene as one self-contained HTML page, each mesh file kept once, compressed
        (:mod:`mobmanip.viz.compact_page`)."""
        from .compact_page import compact

        with self._commands():
            return compact(self._vis.static_html())

    def export_html(self, path: str | Path) -> Path:
        """Write the scene as a self-contained HTML page."""
        path = Path(path)
        write_text(path, self.static_html())
        return path

    def close(self) -> None:
        """Disconnect and stop the server. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(Exception):
            self._vis.window.zmq_socket.close(linger=0)
        self._server.stop()

    def __enter__(self) -> TeamViewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
