"""The meshcat scene: the robot with its meshes, the held object and the task-space ellipsoids.

Scene paths (under meshcat's root ``/meshcat``; the control panel toggles each by path, and
``set_property("visible", ...)`` does the same from Python):

============================== =================================================================
``mobmanip/robot/visuals/G``   the robot's visual geometry ``G`` (Pinocchio's ``MeshcatVisualizer``)
``mobmanip/object``            the held object: a small white sphere at the task point
``mobmanip/ellipsoids/K``      ``K`` = ``kinematic`` (velocity) or ``dynamic`` (acceleration):
                               a group whose transform maps the unit sphere onto the drawn
                               ellipsoid; it holds ``shape`` (a semi-transparent unit sphere) and
                               ``axes`` (its principal axes: unit line segments along the local x,
                               y and z axes, scaled by the same transform)
``mobmanip/locked``            the same pair for the locked platform (arms only), ``locked/K``,
                               whose ``shape`` is three unit circles (the principal sections)
============================== =================================================================

Colours: kinematic green ``#1fbf3f``, dynamic magenta ``#d81bd8`` (semi-transparent, opacity 0.5,
Lambert shading without specular highlights); the locked pair as rings, its three principal
sections drawn as lines, kinematic yellow ``#f2d21b`` and dynamic red ``#e0301e`` (in the
paper's case the locked pair lies inside, or nearly on, the robot's own, which a solid would hide).
Principal axes are drawn in a darker shade of the same colour.

What is drawn, and how
- Only the *linear* part of a task space is drawn: ``planar`` and ``planar_rigid`` as the (x, y)
  ellipse, ``translational`` as it is, ``spatial`` as its projection (shadow) onto (x, y, z),
  i.e. the linear velocities (accelerations) reachable with any accompanying angular motion.
  That is the ellipsoid of the linear rows of the Jacobian, as usually plotted.
- A 2-D ellipse is drawn as a flat ellipsoid in the horizontal plane through the task point,
  its third semi-axis a fixed thickness (:data:`PLANAR_THICKNESS`, a few millimetres, slightly
  different per ellipsoid so the discs do not z-fight).
- The group transform is ``[R diag(k s) | p]``: the columns of ``R`` are the world directions of
  the principal axes (descending semi-axes; an axis' sign is free: for a 3-D ellipsoid the last
  column is negated if needed so that ``R`` is a rotation, for a 2-D one the second, so that the
  thin third axis points up), ``s`` the semi-axes, ``k`` the scale factor of the ellipsoid's unit, and
  ``p = task point + k c`` with ``c`` the ellipsoid's centre (zero for velocities; the dynamic
  centre is shifted by gravity). A zero semi-axis (degenerate) is drawn :data:`MIN_SEMI_AXIS`
  long; an empty dynamic ellipsoid (the torques cannot hold the load) is hidden.
- Scale factors (:class:`ScaleFactors`): metres of scene per m/s and per m/s^2, chosen so that
  the largest drawn extent (|centre| + largest semi-axis, over the robot's and the locked
  ellipsoid) is ``size`` = 0.5 m; fixed at the first :meth:`EllipsoidViewer.show` (or over all
  frames of an animation) so that later updates stay comparable.

Camera: meshcat 0.3.2 always aims its camera at the world origin (see
:meth:`EllipsoidViewer.set_camera`); the first :meth:`EllipsoidViewer.show` places it far enough
to see the robot and the ellipsoids from 30 deg above the ground.

The viewer loads every mesh once (``set_object``) when it is created; :meth:`EllipsoidViewer.show`
and :meth:`EllipsoidViewer.update` send only transforms and visibility, and
:meth:`EllipsoidViewer.animate` sends one meshcat animation.
"""

from __future__ import annotations

import contextlib
import io
import itertools
import math
import warnings
import webbrowser
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..analysis import Analysis, analyze
from ..ellipsoids import Ellipsoid
from ..errors import ModelError
from ..io import write_text
from ..model import Robot, locked_joints
from ..tasks import get_task
from .server import MeshcatServer, ViewerError

ROOT = "mobmanip"
ROBOT_PATH = f"{ROOT}/robot"
OBJECT_PATH = f"{ROOT}/object"
ELLIPSOIDS_PATH = f"{ROOT}/ellipsoids"
LOCKED_PATH = f"{ROOT}/locked"
KINDS = ("kinematic", "dynamic")

#: Scene path of each drawn ellipsoid, by (locked, kind).
ELLIPSOID_PATHS = {
    (False, "kinematic"): f"{ELLIPSOIDS_PATH}/kinematic",
    (False, "dynamic"): f"{ELLIPSOIDS_PATH}/dynamic",
    (True, "kinematic"): f"{LOCKED_PATH}/kinematic",
    (True, "dynamic"): f"{LOCKED_PATH}/dynamic",
}
#: Colour (0xRRGGBB) of each ellipsoid, by (locked, kind).
COLORS = {
    (False, "kinematic"): 0x1FBF3F,
    (False, "dynamic"): 0xD81BD8,
    (True, "kinematic"): 0xF2D21B,
    (True, "dynamic"): 0xE0301E,
}
OPACITY = 0.5  # of the robot's own pair; the locked pair is drawn as rings
OBJECT_COLOR = 0xF0F0F0
OBJECT_RADIUS = 0.035  # m
#: Third semi-axis (m) of a 2-D ellipse drawn as a flat ellipsoid, by (locked, kind).
PLANAR_THICKNESS = {
    (False, "kinematic"): 0.010,
    (False, "dynamic"): 0.012,
    (True, "kinematic"): 0.014,
    (True, "dynamic"): 0.016,
}
MIN_SEMI_AXIS = 0.002  # m: how a zero (degenerate) semi-axis is drawn
DEFAULT_SIZE = 0.5  # m: the largest drawn extent of each kind of ellipsoid
UNITS = {"kinematic": "m/s", "dynamic": "m/s^2"}


# --------------------------------------------------------------------------- visual model


def visual_model(robot: Robot) -> tuple[pin.Model, pin.GeometryModel]:
    """The visual geometry of ``robot`` on a model that matches ``robot.model`` joint for joint.

    The URDF is built again with the planar root joint and its visual geometry (meshes resolved
    in ``spec.package_dirs``), and both are reduced with the joints the robot locks (those not in
    ``robot.model.names``) at the spec's reference positions, as :func:`mobmanip.load_robot` does.

    Raises:
        ModelError: the reduced model does not match ``robot.model`` (names or sizes differ).
    """
    spec = robot.spec
    package_dirs = [str(p) for p in spec.package_dirs]
    model, geometry = pin.buildModelsFromUrdf(
        str(spec.urdf),
        package_dirs=package_dirs,
        root_joint=pin.JointModelPlanar(),
        geometry_types=pin.GeometryType.VISUAL,
    )
    locked, q_ref = locked_joints(model, spec.reference, keep=set(robot.model.names))
    if locked:
        model, (geometry,) = pin.buildReducedModel(model, [geometry], locked, q_ref)
    if list(model.names) != list(robot.model.names) or model.nq != robot.model.nq:
        raise ModelError(
            f"the visual model of {robot.name!r} does not match its analysis model: joints "
            f"{list(model.names)} vs {list(robot.model.names)}"
        )
    return model, geometry


# --------------------------------------------------------------------------- ellipsoid math


def drawn_ellipsoid(ellipsoid: Ellipsoid, task: str) -> tuple[Ellipsoid, np.ndarray]:
    """The part of a task-space ellipsoid that is drawn, and where its coordinates point.

    Returns:
        (linear, E): ``linear`` is the ellipsoid itself when the task is all linear
        (``planar``, ``translational``), else its projection onto the linear coordinates
        (``planar_rigid`` -> (x, y), ``spatial`` -> (x, y, z)); ``E`` (3, k) maps its k
        coordinates to world directions.
    """
    space = get_task(task)
    linear = space.linear_rows
    if not linear:
        raise ViewerError(f"task {task!r} has no linear rows to draw")
    E = np.zeros((3, len(linear)))
    for column, i in enumerate(linear):
        E[space.rows[i], column] = 1.0
    if len(linear) == space.dim:
        return ellipsoid, E
    return ellipsoid.project(tuple(linear)), E


def drawn_extent(ellipsoid: Ellipsoid, task: str) -> float:
    """|centre| + largest semi-axis of the drawn part (task units; 0 when empty)."""
    if ellipsoid.empty:
        return 0.0
    linear, _ = drawn_ellipsoid(ellipsoid, task)
    return float(np.linalg.norm(linear.center) + (linear.semi_axes[0] if linear.dim else 0.0))


def ellipsoid_frame(
    ellipsoid: Ellipsoid, task: str, origin: np.ndarray, scale: float, thickness: float = 0.01
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the drawn ellipsoid sits in the world: centre, rotation and semi-axes (m).

    Args:
        ellipsoid: the task-space ellipsoid (rows in world axes).
        task: its task space.
        origin: world position of the task point (m), (3,).
        scale: metres of scene per unit of the ellipsoid (m per m/s or per m/s^2).
        thickness: third semi-axis (m) of a 2-D ellipse.

    Returns:
        (p, R, r): centre p (3,), rotation R (3, 3) whose columns are the principal directions
        (descending), semi-axes r (3,) in metres (zero semi-axes raised to MIN_SEMI_AXIS).
    """
    linear, E = drawn_ellipsoid(ellipsoid, task)
    k = linear.dim
    directions = E @ linear.axes.T  # (3, k): world direction of each principal axis
    semi = np.maximum(scale * linear.semi_axes, MIN_SEMI_AXIS)
    if k == 3:
        R = directions.copy()
    elif k == 2:
        normal = np.cross(directions[:, 0], directions[:, 1])
        if normal @ np.ones(3) < 0:  # keep the thin axis pointing +z (up) for a horizontal ellipse
            directions[:, 1] *= -1.0
            normal = -normal
        R = np.column_stack([directions, normal / np.linalg.norm(normal)])
        semi = np.append(semi, thickness)
    else:
        raise ViewerError(f"cannot draw a {k}-dimensional ellipsoid")
    if np.linalg.det(R) < 0:
        R[:, -1] *= -1.0
    p = np.asarray(origin, dtype=float) + scale * (E @ linear.center)
    return p, R, semi


def ellipsoid_matrix(
    ellipsoid: Ellipsoid, task: str, origin: np.ndarray, scale: float, thickness: float = 0.01
) -> np.ndarray:
    """The 4x4 transform that maps the unit sphere onto the drawn ellipsoid: [R diag(r) | p].

    See :func:`ellipsoid_frame`. For a 3-D ellipsoid with matrix A, every unit vector u maps to a
    point x with ((x - o) / k - c)^T A ((x - o) / k - c) = 1 (o the task point, k the scale,
    c the centre); for a 2-D ellipse the same holds for the horizontal unit vectors.
    """
    p, R, semi = ellipsoid_frame(ellipsoid, task, origin, scale, thickness)
    T = np.eye(4)
    T[:3, :3] = R * semi
    T[:3, 3] = p
    return T


def _aligned(R: np.ndarray, semi: np.ndarray, previous: np.ndarray | None, planar: bool):
    """R and semi with their columns permuted and signs flipped to follow ``previous`` (for
    smooth animations); the ellipsoid drawn is the same."""
    if previous is None:
        return R, semi
    k = 2 if planar else 3
    best, best_score = (R, semi), -np.inf
    for perm in itertools.permutations(range(k)):
        for signs in itertools.product((1.0, -1.0), repeat=k):
            cols = R[:, list(perm)] * np.array(signs)
            if planar:
                normal = np.cross(cols[:, 0], cols[:, 1])
                candidate = np.column_stack([cols, normal])
                semis = np.append(semi[list(perm)], semi[2])
            else:
                candidate = cols
                semis = semi[list(perm)]
            if np.linalg.det(candidate) < 0:
                continue
            score = float(np.trace(previous.T @ candidate))
            if score > best_score:
                best, best_score = (candidate, semis), score
    return best


# --------------------------------------------------------------------------- scales


@dataclass(frozen=True)
class ScaleFactors:
    """How long 1 unit of each ellipsoid is drawn.

    Attributes:
        kinematic: metres of scene per m/s.
        dynamic: metres of scene per m/s^2.
    """

    kinematic: float
    dynamic: float

    def __getitem__(self, kind: str) -> float:
        return {"kinematic": self.kinematic, "dynamic": self.dynamic}[kind]

    @classmethod
    def fit(cls, analyses: Sequence[Analysis | None], size: float = DEFAULT_SIZE) -> ScaleFactors:
        """Scales that draw the largest extent (|centre| + largest semi-axis) of each kind,
        over all given analyses, ``size`` metres long (1 when everything is zero or empty)."""
        values = {}
        for kind in KINDS:
            extent = max(
                (drawn_extent(getattr(a, kind), a.task) for a in analyses if a is not None),
                default=0.0,
            )
            values[kind] = size / extent if extent > 0.0 else 1.0
        return cls(**values)

    def describe(self) -> str:
        """E.g. ``kinematic: 1 m/s = 0.0974 m; dynamic: 1 m/s^2 = 0.0190 m``."""
        return "; ".join(f"{kind}: 1 {UNITS[kind]} = {self[kind]:.4g} m" for kind in KINDS)


# --------------------------------------------------------------------------- frames


@dataclass(frozen=True)
class Frame:
    """One state of an animation.

    Attributes:
        q: configuration of the robot, (nq,).
        analysis: the analysis drawn (its task point carries the object and ellipsoids).
        locked: the same configuration with the platform locked, or ``None``.
        hold: seconds the animation stays on this frame before moving on.
        label: what the frame shows (printed with the animation's schedule).
    """

    q: np.ndarray
    analysis: Analysis
    locked: Analysis | None = None
    hold: float = 0.0
    label: str = ""


def analyze_pair(
    robot: Robot, q: np.ndarray, task: str | None = None, *, locked: bool = True, **options
) -> tuple[Analysis, Analysis | None]:
    """``analyze`` the robot and, if it has a moving platform and ``locked``, the same
    configuration with the platform locked (the arms alone)."""
    analysis = analyze(robot, q, task, **options)
    if not locked or robot.platform.kind == "fixed" or robot.wheel_platform is None:
        return analysis, None
    return analysis, analyze(robot.with_platform("fixed"), q, analysis.task, **options)


# --------------------------------------------------------------------------- the viewer


class EllipsoidViewer:
    """A meshcat viewer of a robot, its held object and its ellipsoids.

    The meshcat server runs in a child process on 127.0.0.1 (see :mod:`mobmanip.viz.server`);
    no browser opens unless ``open_browser``. Use it as a context manager or call :meth:`close`.

    Args:
        robot: the robot (its own platform; the locked pair is drawn from ``with_platform("fixed")``).
        port: HTTP port of the viewer page; ``None`` takes the first free one from 7000.
        open_browser: open the page in the default browser.
        scales: fixed scale factors; ``None`` fits them at the first :meth:`show` or :meth:`animate`.
        size: the largest drawn extent when scales are fitted (m).
        timeout: seconds to wait for the server to answer a command.

    Raises:
        PortBusyError: ``port`` is in use.
        ViewerError: the server did not start.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        port: int | None = None,
        open_browser: bool = False,
        scales: ScaleFactors | None = None,
        size: float = DEFAULT_SIZE,
        timeout: float = 60.0,
    ):
        import zmq

        with warnings.catch_warnings():  # meshcat 0.3.2 imports pyzmq's deprecated zmq.eventloop.ioloop
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat
        from pinocchio.visualize import MeshcatVisualizer

        self.robot = robot
        self.scales = scales
        self.size = size
        self._closed = False
        self._server = MeshcatServer(port)
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL; we print ours
                self._vis = meshcat.Visualizer(zmq_url=self._server.zmq_url)
            socket = self._vis.window.zmq_socket
            socket.setsockopt(zmq.LINGER, 0)
            socket.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
            socket.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
            self.model, self.visual_model = visual_model(robot)
            self._pin = MeshcatVisualizer(self.model, None, self.visual_model)
            with self._commands():
                self._pin.initViewer(viewer=self._vis)
                self._pin.loadViewerModel(rootNodeName=ROBOT_PATH)
                self._load_static()
        except BaseException:
            self._server.stop()
            raise
        self._visible: dict[tuple[bool, str], bool | None] = dict.fromkeys(ELLIPSOID_PATHS)  # as last sent
        self._locked_visible: bool | None = None
        self._camera_set = False
        self.last: Frame | None = None
        if open_browser:
            self.open()

    # ----- plumbing

    @contextlib.contextmanager
    def _commands(self):
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

    def _load_static(self) -> None:
        import meshcat.geometry as mg

        self._vis[OBJECT_PATH].set_object(mg.Sphere(OBJECT_RADIUS), mg.MeshPhongMaterial(color=OBJECT_COLOR))
        for key, path in ELLIPSOID_PATHS.items():
            locked, kind = key
            if locked:  # rings only: they never hide the robot's own pair, which usually contains them
                self._vis[f"{path}/shape"].set_object(
                    mg.LineSegments(mg.PointsGeometry(_unit_rings()), _line_material(COLORS[key]))
                )
                self._vis[f"{path}/shape/<object>"].set_property("renderOrder", 1)
            else:
                material = mg.MeshLambertMaterial(
                    color=COLORS[key], opacity=OPACITY, transparent=True, depthWrite=False
                )
                self._vis[f"{path}/shape"].set_object(mg.Sphere(1.0), material)
            # Principal axes: +-1 along local x, y, z (the group transform scales them).
            segments = np.array(
                [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], dtype=np.float32
            ).T
            self._vis[f"{path}/axes"].set_object(
                mg.LineSegments(mg.PointsGeometry(segments), _line_material(_darker(COLORS[key])))
            )
            self._vis[f"{path}/axes/<object>"].set_property("renderOrder", 1)

    # ----- camera

    def set_camera(self, distance: float, elevation_deg: float = 30.0, azimuth_deg: float = -120.0) -> None:
        """Place meshcat's camera ``distance`` m from the world origin, ``elevation_deg`` above
        the horizon, in the horizontal direction ``azimuth_deg`` from +x.

        meshcat 0.3.2's orbit controls always aim the camera at the world origin (they call
        ``lookAt`` with their target, the origin, in world coordinates, whatever the transform of
        ``/Cameras/default``), so the camera is placed through its position property at
        ``/Cameras/default/rotated/<object>`` (a y-up frame) and ``/Cameras/default`` is left at
        the identity. Drag with the right mouse button to pan to another point.
        """
        el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
        offset = distance * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        with self._commands():
            # world (x, y, z) = rotated-frame (x, -z, y)
            local = [float(offset[0]), float(offset[2]), float(-offset[1])]
            self._vis["/Cameras/default/rotated/<object>"].set_property("position", local)
        self._camera_set = True

    def _fit_camera(self, frame: Frame) -> None:
        """A camera distance that shows everything within reach of the origin (where meshcat's
        camera looks): the robot's joints, the task point and the ellipsoids around it."""
        data = self.model.createData()
        pin.forwardKinematics(self.model, data, frame.q)
        points = np.array([data.oMi[j].translation for j in range(1, self.model.njoints)])
        reach = max(float(np.max(np.linalg.norm(points, axis=1))), 0.5)
        reach = max(reach, float(np.linalg.norm(frame.analysis.held_object.center)) + self.size)
        self.set_camera(1.35 * reach)

    # ----- showing one configuration

    def show(self, q: np.ndarray | None, analysis: Analysis, locked: Analysis | None = None) -> None:
        """Draw the robot at ``q`` (default ``analysis.q``) with the analysis' object and
        ellipsoids, and the locked pair if ``locked`` is given (hidden otherwise).

        Only transforms and visibility are sent: the meshes were loaded when the viewer was
        created. Scales are fitted at the first call when none were given.
        """
        q = self.robot.check_configuration(analysis.q if q is None else q)
        frame = Frame(q, analysis, locked)
        if self.scales is None:
            self.scales = ScaleFactors.fit([analysis, locked], self.size)
        with self._commands():
            self._pin.display(q)
            self._vis[OBJECT_PATH].set_transform(_translation(analysis.held_object.center))
            for key, path in ELLIPSOID_PATHS.items():
                source = locked if key[0] else analysis
                if source is None:
                    continue
                visible = not getattr(source, key[1]).empty
                if visible:
                    self._vis[path].set_transform(self.placement(source, key))
                if self._visible[key] != visible:
                    self._vis[path].set_property("visible", visible)
                    self._visible[key] = visible
            if self._locked_visible != (locked is not None):
                self.set_locked_visible(locked is not None)
        if not self._camera_set:
            self._fit_camera(frame)
        self.last = frame

    def update(self, q: np.ndarray | None, analysis: Analysis, locked: Analysis | None = None) -> None:
        """Same as :meth:`show`: move everything to the new configuration in place."""
        self.show(q, analysis, locked)

    def placement(self, analysis: Analysis, key: tuple[bool, str]) -> np.ndarray:
        """The 4x4 transform of the ellipsoid ``key`` = (locked, kind) for ``analysis``."""
        locked, kind = key
        return ellipsoid_matrix(
            getattr(analysis, kind),
            analysis.task,
            analysis.held_object.center,
            self.scales[kind],
            PLANAR_THICKNESS[key],
        )

    def set_locked_visible(self, visible: bool) -> None:
        """Show or hide the locked-platform pair (``mobmanip/locked``)."""
        with self._commands():
            self._vis[LOCKED_PATH].set_property("visible", bool(visible))
        self._locked_visible = bool(visible)

    # ----- animations

    def animate(
        self, frames: Sequence[Frame], *, step: float = 0.1, fps: int = 30, play: bool = True, repetitions: int = 1
    ) -> list[tuple[float, float, str]]:
        """Send the frames as one meshcat animation (play / pause / time slider in the panel).

        Each frame is a keyframe ``step`` s after the previous one ends; a frame with ``hold``
        stays for that long. Between keyframes meshcat interpolates positions, rotations and
        scales linearly. The scene is first shown at the first frame, with scales fitted over all
        frames unless given.

        Returns:
            The schedule: (start s, end s, label) of each labelled frame.
        """
        import meshcat.animation as ma

        if not frames:
            raise ViewerError("an animation needs at least one frame")
        if self.scales is None:
            self.scales = ScaleFactors.fit([a for f in frames for a in (f.analysis, f.locked)], self.size)
        any_locked = any(f.locked is not None for f in frames)
        first = frames[0]
        self.show(first.q, first.analysis, first.locked)
        if any_locked and not self._locked_visible:
            self.set_locked_visible(True)
        with self._commands():  # an ellipsoid empty in the first frame may appear later: scale hides it
            for key, path in ELLIPSOID_PATHS.items():
                if self._visible[key] is False:
                    self._vis[path].set_property("visible", True)
                    self._visible[key] = True
        animation = ma.Animation(default_framerate=fps)
        data, geometry_data = self.model.createData(), self.visual_model.createData()
        geometry_paths = [
            self._pin.getViewerNodeName(geom, pin.GeometryType.VISUAL) for geom in self.visual_model.geometryObjects
        ]
        hidden = np.full(3, 1e-6)  # an empty (or absent) ellipsoid shrinks to nothing
        previous: dict = {}  # key -> (pose 4x4 without scale, semi-axes) of the last frame drawn
        schedule, t = [], 0.0
        for frame in frames:
            pin.forwardKinematics(self.model, data, frame.q)
            pin.updateGeometryPlacements(self.model, data, self.visual_model, geometry_data)
            poses = [(path, geometry_data.oMg[g].homogeneous, None) for g, path in enumerate(geometry_paths)]
            poses.append((OBJECT_PATH, _translation(frame.analysis.held_object.center), None))
            for key, path in ELLIPSOID_PATHS.items():
                source = frame.locked if key[0] else frame.analysis
                ellipsoid = None if source is None else getattr(source, key[1])
                if ellipsoid is None or ellipsoid.empty:
                    if source is not None or any_locked:
                        poses.append((path, previous.get(key, (np.eye(4), None))[0], hidden))
                    continue
                p, R, semi = ellipsoid_frame(
                    ellipsoid, source.task, source.held_object.center, self.scales[key[1]], PLANAR_THICKNESS[key]
                )
                planar = drawn_ellipsoid(ellipsoid, source.task)[0].dim == 2
                last = previous.get(key)
                R, semi = _aligned(R, semi, None if last is None else last[0][:3, :3], planar)
                pose = _translation(p)
                pose[:3, :3] = R
                previous[key] = (pose, semi)
                poses.append((path, pose, semi))
            times = [t] if frame.hold <= 0 else [t, t + frame.hold]
            for time_s in times:
                with animation.at_frame(self._vis, time_s * fps) as at:
                    for path, pose, scale in poses:
                        at[path].set_transform(pose)  # position and rotation tracks
                        if scale is not None:
                            at[path].set_property("scale", "vector3", [float(s) for s in scale])
            if frame.label:
                schedule.append((t, times[-1], frame.label))
            t = times[-1] + step
        with self._commands():
            self._vis.set_animation(animation, play=play, repetitions=repetitions)
        return schedule

    # ----- output and shutdown

    def static_html(self) -> str:
        """The scene as one self-contained HTML page (meshcat's ``static_html``)."""
        with self._commands():
            return self._vis.static_html()

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

    def __enter__(self) -> EllipsoidViewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _unit_rings(n: int = 96) -> np.ndarray:
    """Line segments (3, 6 n) of the unit circles in the xy, yz and zx planes."""
    t = np.linspace(0.0, 2.0 * np.pi, n + 1)
    c, s, z = np.cos(t), np.sin(t), np.zeros_like(t)
    points = []
    for ring in (np.stack([c, s, z]), np.stack([z, c, s]), np.stack([s, z, c])):
        points.append(np.repeat(ring, 2, axis=1)[:, 1:-1])  # p0 p1 p1 p2 ... as segment pairs
    return np.hstack(points).astype(np.float32)


def _line_material(color: int):
    """Lines drawn after the semi-transparent shapes (transparent pass, renderOrder 1), so that
    rings and axes inside a shape keep their colour instead of being tinted by its surface."""
    import meshcat.geometry as mg

    return mg.LineBasicMaterial(color=color, transparent=True, opacity=1.0)


def _darker(color: int, factor: float = 0.45) -> int:
    r, g, b = ((color >> shift) & 0xFF for shift in (16, 8, 0))
    return (int(r * factor) << 16) | (int(g * factor) << 8) | int(b * factor)


def _translation(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = np.asarray(p, dtype=float)
    return T
