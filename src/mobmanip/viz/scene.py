"""The meshcat scene: the robot with its meshes, the held object and the task-space sets.

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
``mobmanip/polytopes/K``       ``K`` = ``kinematic_polytope``, ``dynamic_polytope`` or
                               ``dynamic_polytope_min_norm`` (when analysed): a group at the task
                               point holding ``shape`` (3-D tasks: a translucent triangle mesh)
                               and ``edges`` (its edges; the outline of a planar set)
``mobmanip/locked``            the same for the locked platform (arms only), ``locked/K``,
                               whose ``shape`` is three unit circles (the principal sections);
                               a locked polytope is its ``edges`` only
============================== =================================================================

Every measure of :mod:`mobmanip.measures` an analysis holds is drawn the same way: at its
:attr:`~mobmanip.measures.Measure.scene_path` (``ellipsoids/<name>`` for an ellipsoid) and
``locked/<name>``, in its colours, at the scale of its quantity, by the drawing of its set kind
(:mod:`mobmanip.viz.shapes`; sets of a kind without a drawing are left out and listed in
:attr:`EllipsoidViewer.undrawn`). Polytopes are sent whole (``set_object``) at each show, as
their shape changes with the configuration; an animation shows them as at its first frame.

Colours (from the registry): kinematic green ``#1fbf3f``, dynamic magenta ``#d81bd8``
(semi-transparent, opacity 0.5, Lambert shading without specular highlights); the locked pair as
rings, its three principal sections drawn as lines, kinematic yellow ``#f2d21b`` and dynamic red
``#e0301e`` (in the paper's case the locked pair lies inside, or nearly on, the robot's own,
which a solid would hide). Principal axes are drawn in a darker shade of the same colour.

What is drawn, and how:

- Only the *linear* part of a task space is drawn: ``planar`` and ``planar_rigid`` as the (x, y)
  ellipse, ``translational`` as it is, ``spatial`` as its projection (shadow) onto (x, y, z),
  i.e. the linear velocities (accelerations) reachable with any accompanying angular motion.
  That is the ellipsoid of the linear rows of the Jacobian, as usually plotted.
- A 2-D ellipse is drawn as a flat ellipsoid in the horizontal plane through the task point,
  its third semi-axis a fixed thickness (:func:`planar_thickness`, a few millimetres, slightly
  different per measure so the discs do not z-fight).
- The group transform is ``[R diag(k s) | p]``: the columns of ``R`` are the world directions of
  the principal axes (descending semi-axes; an axis' sign is free: for a 3-D ellipsoid the last
  column is negated if needed so that ``R`` is a rotation, for a 2-D one the second, so that the
  thin third axis points up), ``s`` the semi-axes, ``k`` the scale factor of the ellipsoid's unit, and
  ``p = task point + k c`` with ``c`` the ellipsoid's centre (zero for velocities; the dynamic
  centre is shifted by gravity). A zero semi-axis (degenerate) is drawn :data:`MIN_SEMI_AXIS`
  long; an empty set (e.g. the torques cannot hold the load) is hidden.
- Nested sets: a set of the robot's own whose drawing contains another of its sets (as drawn,
  each at its scale; :mod:`mobmanip.viz.nesting`) is drawn as an outline -- an ellipsoid's three
  principal rings (``outline``) instead of its surface (``shape``), a polytope's edges without
  its mesh -- so that the inner set stays in sight; the legend marks it and names what it holds
  (:attr:`EllipsoidViewer.outlined`). An animation decides this over all its frames.
- Scale factors (:class:`ScaleFactors`): metres of scene per m/s and per m/s^2 (one per
  quantity, shared by the measures of that quantity), chosen so that the largest drawn extent
  (``|centre|`` + largest semi-axis for an ellipsoid, over the robot's and the locked sets) is
  ``size`` = 0.5 m; fixed at the first :meth:`EllipsoidViewer.show` (or over all frames of an
  animation) so that later updates stay comparable.

The page explains itself (:mod:`mobmanip.viz.page`): a legend names each drawn set by its
colour with its scale (``1 m/s = 0.227 m``), the first :meth:`EllipsoidViewer.show` frames the
robot's visual geometry, the object and the sets, and a set too small to see at its quantity's
scale is drawn larger by a factor the legend states (:attr:`EllipsoidViewer.magnified`).

The viewer loads every mesh once (``set_object``): those of the measures it is created for when
it is created, those of another measure the first time an analysis brings it;
:meth:`EllipsoidViewer.show` and :meth:`EllipsoidViewer.update` send only transforms and
visibility (and the polytopes' meshes, which change shape), and :meth:`EllipsoidViewer.animate`
sends one meshcat animation.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..analysis.single import Analysis, analyze
from ..measures import default_measures, get_measure, measure_names, resolve_measures
from ..robot.model import Robot, platform_pose
from ..sets.taskset import TaskSet
from . import page as _page
from .animation import CAMERA_FRAMES as CAMERA_FRAMES
from .animation import FOLLOW_FRAMES, camera_samples, geometry_paths, robot_poses, set_extent, set_pose, write_keyframe
from .meshcat_scene import MeshcatScene
from .meshes import visual_model as visual_model
from .nesting import nested, outlined
from .scales import DEFAULT_SIZE as DEFAULT_SIZE
from .scales import ScaleFactors as ScaleFactors
from .server import ViewerError
from .shapes import DRAWINGS, MIN_SEMI_AXIS, drawn_ellipsoid, drawn_extent, ellipsoid_frame, line_material, translation
from .shapes import aligned as aligned  # noqa: F401 - re-exported: the animation tests use it
from .shapes import ellipsoid_matrix as ellipsoid_matrix

ROOT = "mobmanip"
ROBOT_PATH = f"{ROOT}/robot"
OBJECT_PATH = f"{ROOT}/object"
ELLIPSOIDS_PATH = f"{ROOT}/ellipsoids"
LOCKED_PATH = f"{ROOT}/locked"
OBJECT_COLOR = 0xF0F0F0
OBJECT_RADIUS = 0.035  # m

__all__ = [
    "COLORS",
    "ELLIPSOID_PATHS",
    "MIN_SEMI_AXIS",
    "PLANAR_THICKNESS",
    "EllipsoidViewer",
    "Frame",
    "ScaleFactors",
    "analyze_pair",
    "drawn_ellipsoid",
    "drawn_extent",
    "ellipsoid_frame",
    "ellipsoid_matrix",
    "planar_thickness",
    "scene_color",
    "scene_path",
    "visual_model",
]


#: Where the floor's support polygon and zero-moment point are drawn, and their colour.
FLOOR_PATH = "mobmanip/floor"
FLOOR_COLOR = 0x333333


def scene_path(name: str, locked: bool = False) -> str:
    """Scene path of measure ``name``'s set (``locked``: its locked-platform counterpart)."""
    measure = get_measure(name)
    return f"{ROOT}/{measure.locked_scene_path if locked else measure.scene_path}"


def scene_color(name: str, locked: bool = False) -> int:
    """Colour (0xRRGGBB) of measure ``name``'s set (``locked``: its locked counterpart)."""
    measure = get_measure(name)
    return measure.locked_color if locked else measure.color


def planar_thickness(name: str, locked: bool = False) -> float:
    """Third semi-axis (m) of measure ``name``'s planar set drawn in 3-D: 10 mm and up in steps
    of 2 mm, in blocks of two measures in the registry's order (own pair, then locked pair), so
    that no two discs z-fight: kinematic 10, dynamic 12, locked kinematic 14, locked dynamic 16."""
    i = measure_names().index(get_measure(name).name)
    return 0.010 + 0.002 * (4 * (i // 2) + i % 2 + 2 * bool(locked))


def _of_defaults(value) -> dict:
    return {(locked, name): value(name, locked) for locked in (False, True) for name in default_measures()}


#: Scene path of each set of the default measures, by (locked, measure name).
ELLIPSOID_PATHS = _of_defaults(scene_path)
#: Colour (0xRRGGBB) of each set of the default measures, by (locked, measure name).
COLORS = _of_defaults(scene_color)
#: Third semi-axis (m) of each planar set of the default measures drawn flat, by (locked, name).
PLANAR_THICKNESS = _of_defaults(planar_thickness)


# --------------------------------------------------------------------------- scales


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
        caption: what the page's caption says while the frame plays; default its label (a frame
            with neither keeps the caption of the frame before it).
    """

    q: np.ndarray
    analysis: Analysis
    locked: Analysis | None = None
    hold: float = 0.0
    label: str = ""
    caption: str = ""


def analyze_pair(
    robot: Robot, q: np.ndarray, task: str | None = None, *, locked: bool = True, **options: Any
) -> tuple[Analysis, Analysis | None]:
    """``analyze`` the robot and, if it has a moving platform and ``locked``, the same
    configuration with the platform locked (the arms alone)."""
    analysis = analyze(robot, q, task, **options)
    if not locked or robot.platform_locked or robot.wheel_platform is None:
        return analysis, None
    options = {**options, "constraints": ()}  # a locked platform has no floor of its own to honour
    return analysis, analyze(robot.with_platform("fixed"), q, analysis.task, **options)


# --------------------------------------------------------------------------- the viewer


class EllipsoidViewer(MeshcatScene):
    """A meshcat viewer of a robot, its held object and its task-space sets (every measure an
    analysis holds, drawn by its set kind; see the module's docstring).

    The meshcat server runs in a child process on 127.0.0.1 (see :mod:`mobmanip.viz.server`);
    no browser opens unless ``open_browser``. Use it as a context manager or call :meth:`close`.

    Args:
        robot: the robot (its own platform; the locked pair is drawn from ``with_platform("fixed")``).
        port: HTTP port of the viewer page; ``None`` takes the first free one from 7000.
        open_browser: open the page in the default browser.
        scales: fixed scale factors; ``None`` fits them at the first :meth:`show` or :meth:`animate`.
        size: the largest drawn extent when scales are fitted (m).
        timeout: seconds to wait for the server to answer a command.
        measures: the measures whose meshes are loaded now (default: the default ones); another
            measure's are loaded the first time an analysis brings it.
        magnify: draw a set too small to see at its quantity's scale larger, by a 1-2-5 factor
            the page's legend states (:func:`mobmanip.viz.page.magnification`); ``False`` draws
            every set of a quantity at one scale.

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
        measures: Iterable[str] | None = None,
        magnify: bool = True,
    ):
        self.robot = robot
        self.scales = scales
        self.size = size
        self.magnify = magnify
        #: How many times larger each magnified set is drawn, by (locked, measure name).
        self.magnified: dict[tuple[bool, str], float] = {}
        self._visible: dict[tuple[bool, str], bool | None] = {}  # loaded sets, visibility as last sent
        #: Measures whose sets were not drawn: no drawing for their set kind yet (by name: kind).
        self.undrawn: dict[str, str] = {}
        #: The robot's own sets drawn as outlines at the last show or animation, by (locked,
        #: measure name): each contains the sets listed (as drawn), which its surface would hide.
        self.outlined: dict[tuple[bool, str], tuple[tuple[bool, str], ...]] = {}
        with self._starting(port, timeout):
            from pinocchio.visualize import MeshcatVisualizer  # imports meshcat: once _starting has, quietly

            #: One line per mesh left out of the drawing (outside the package roots, missing, unreadable).
            self.mesh_notes: list[str] = []
            self.model, self.visual_model = visual_model(robot, self.mesh_notes)
            self._pin = MeshcatVisualizer(self.model, None, self.visual_model)
            with self._commands():
                self._pin.initViewer(viewer=self._vis)
                # the sets and the object first: a page that connects receives the scene in this
                # order, and the robot's meshes (the heaviest part) can take tens of seconds
                self._load_static(resolve_measures(measures))
                self._pin.loadViewerModel(rootNodeName=ROBOT_PATH)
        self._locked_visible: bool | None = None
        self.last: Frame | None = None
        if open_browser:
            self.open()

    # ----- loading

    def _load_static(self, measures) -> None:
        import meshcat.geometry as mg

        self._vis[OBJECT_PATH].set_object(mg.Sphere(OBJECT_RADIUS), mg.MeshPhongMaterial(color=OBJECT_COLOR))
        for locked in (False, True):
            for measure in measures:
                if measure.set_kind in DRAWINGS:
                    self._load((locked, measure.name), measure.set_kind)

    def _load(self, key: tuple[bool, str], kind: str) -> None:
        """Load the meshes of set ``key`` = (locked, measure name), of set kind ``kind``, once."""
        if key not in self._visible:
            locked, name = key
            DRAWINGS[kind].load(self._vis, scene_path(name, locked), scene_color(name, locked), locked)
            self._visible[key] = None

    def _drawn(self, analysis: Analysis | None, locked: bool) -> dict[tuple[bool, str], TaskSet]:
        """The sets of an analysis the viewer draws, by (locked, measure name); the others are
        noted in :attr:`undrawn`."""
        out: dict[tuple[bool, str], TaskSet] = {}
        if analysis is not None:
            for name, task_set in analysis.measures.items():
                if task_set.kind in DRAWINGS:
                    out[locked, name] = task_set
                else:
                    self.undrawn[name] = task_set.kind
        return out

    def scene_paths(self) -> dict[tuple[bool, str], str]:
        """Scene path of every set loaded so far, by (locked, measure name)."""
        return {key: scene_path(key[1], key[0]) for key in self._visible}

    # ----- camera

    def set_camera(
        self,
        distance: float,
        elevation_deg: float = 30.0,
        azimuth_deg: float = -120.0,
        target: ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        """Place the camera ``distance`` m from ``target`` (world, m), ``elevation_deg`` above the
        horizon, in the horizontal direction ``azimuth_deg`` from +x, looking at ``target``.

        meshcat 0.3.2's orbit controls aim the camera at their target, the world origin, and
        meshcat has no command to move it; the page's script (:mod:`mobmanip.viz.page`) sets
        both. The position is also sent as the camera's position property
        (``/Cameras/default/rotated/<object>``, a y-up frame), which a page without the script
        follows. Drag with the right mouse button to pan.
        """
        el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
        offset = distance * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        position = np.asarray(target, dtype=float) + offset
        self._camera_serial += 1
        with self._commands():
            # world (x, y, z) = rotated-frame (x, -z, y)
            local = [float(position[0]), float(position[2]), float(-position[1])]
            self._vis["/Cameras/default/rotated/<object>"].set_property("position", local)
            self._send_page(camera=_page.look_request(position, target, self._camera_serial))

    def frame_camera(self, frame: Frame | Sequence[Frame], times: Sequence[Sequence[float]] | None = None) -> dict:
        """Frame the robot at ``frame.q`` (its visual geometry), the held object and the drawn
        sets: the page places the camera so that their bounding box fills most of its view, seen
        from the front right of the platform and 25 deg above the horizon. Given several frames
        (an animation), the box holds them all (up to :data:`CAMERA_FRAMES` of them, evenly
        spread, the last included), seen from the first frame's platform heading: the camera
        frames the whole path, so the robot stays in view while it moves. Given their
        ``times`` too (each frame's keyframe times in the animation, s), a motion that travels
        far is followed instead (:func:`mobmanip.viz.page.animation_request`, up to
        :data:`~mobmanip.viz.animation.FOLLOW_FRAMES` frames).

        Returns:
            The camera request sent (see :mod:`mobmanip.viz.page`); its ``box`` is the framed
            box (lower, upper), m.
        """
        frames = [frame] if isinstance(frame, Frame) else list(frame)
        if times is not None and len(frames) > 1:
            picked = camera_samples(len(frames), FOLLOW_FRAMES)
            extents = []
            for i in picked:
                points, boxes = self._frame_extent(frames[i])
                extents.append(np.vstack([points, *(_page.box_corners(*box) for box in boxes)]))
            first = frames[0]
            heading = platform_pose(first.q)[2] if self.model.nq >= 4 else 0.0
            return self._send_animation_camera(extents, [times[i] for i in picked], heading)
        frames = [frames[i] for i in camera_samples(len(frames))]
        all_points, all_boxes = [], []
        for one in frames:
            points, boxes = self._frame_extent(one)
            all_points.append(points)
            all_boxes.extend(boxes)
        first = frames[0]
        heading = platform_pose(first.q)[2] if self.model.nq >= 4 else 0.0
        return self._send_fit(np.vstack(all_points), all_boxes, heading)

    def _frame_extent(self, frame: Frame) -> tuple[np.ndarray, list]:
        """Points (n, 3) and boxes of what one frame draws: the robot, the object, the sets."""
        points, boxes = _page.visual_points(self.model, self.visual_model, frame.q), []
        for source, locked in ((frame.analysis, False), (frame.locked, True)):
            if source is None:
                continue
            center = source.held_object.center
            boxes.append(_page.sphere_box(center, OBJECT_RADIUS))
            for (_, name), task_set in self._drawn(source, locked).items():
                if task_set.empty:
                    continue
                scale, thickness = self._set_scale((locked, name)), planar_thickness(name, locked)
                more, around = set_extent(task_set, source.task, center, scale, thickness)
                points = np.vstack([points, more])
                boxes.extend(around)
        return points, boxes

    def _legend(self, sets: dict, title: str, notes: Sequence[str] = (), captions: dict | None = None) -> None:
        """Show the legend of the drawn ``sets`` (by (locked, measure name)), the parts the page
        waits for (the robot's meshes, the sets, the object) and an animation's ``captions``
        (:mod:`mobmanip.viz.page`)."""
        rows, more = _page.legend_rows(sets, self.scales, self.magnified, OBJECT_COLOR, self.outlined)
        expect = [*geometry_paths(self._pin, self.visual_model), OBJECT_PATH]
        expect += [scene_path(name, locked) for (locked, name), task_set in sets.items() if not task_set.empty]
        with self._commands():
            self._send_page(title=title, rows=rows, notes=[*more, *notes], expect=expect, captions=captions)

    def _title(self, analysis: Analysis) -> str:
        title = f"{self.robot.name} ({self.robot.platform.kind.replace('_', ' ')}), {analysis.task} task"
        if analysis.task in ("spatial", "planar_rigid"):
            title += " (linear part drawn)"
        return title

    def _outlined(self, frames: Sequence[Frame]) -> dict[tuple[bool, str], tuple[tuple[bool, str], ...]]:
        """The robot's own sets drawn as outlines: those whose drawing contains another of its
        sets in some frame, with the sets they contain (:func:`mobmanip.viz.nesting.nested`)."""
        out: dict[tuple[bool, str], tuple[tuple[bool, str], ...]] = {}
        for frame in frames:
            own = {key: s for key, s in self._drawn(frame.analysis, False).items() if s.kind in DRAWINGS}
            if len(own) < 2:
                continue
            found = outlined(nested(own, frame.analysis.task, self._set_scale))
            for key, inner in found.items():
                out[key] = tuple(dict.fromkeys((*out.get(key, ()), *inner)))
        return out

    def _set_scale(self, key: tuple[bool, str]) -> float:
        """Metres of scene per task unit of set ``key``: its quantity's scale, magnified."""
        return self.scales[key[1]] * self.magnified.get(key, 1.0)

    def _fit_magnified(self, per_key: Mapping[tuple[bool, str], float]) -> None:
        """Decide the magnification of sets seen for the first time, from their largest extent
        (task units) by key."""
        for key, extent in per_key.items():
            if key not in self.magnified:
                drawn = extent * self.scales[key[1]]
                self.magnified[key] = _page.magnification(drawn, self.size) if self.magnify else 1.0

    @staticmethod
    def _extents(frames: Iterable[Frame]) -> dict[tuple[bool, str], float]:
        out: dict[tuple[bool, str], float] = {}
        for frame in frames:
            for source, locked in ((frame.analysis, False), (frame.locked, True)):
                for name, task_set in ({} if source is None else source.measures).items():
                    if task_set.kind in DRAWINGS:
                        extent = DRAWINGS[task_set.kind].extent(task_set, source.task)
                        out[locked, name] = max(out.get((locked, name), 0.0), extent)
        return out

    # ----- showing one configuration

    def show(self, q: np.ndarray | None, analysis: Analysis, locked: Analysis | None = None) -> None:
        """Draw the robot at ``q`` (default ``analysis.q``) with the analysis' object and
        sets, and the locked ones if ``locked`` is given (hidden otherwise).

        Only transforms and visibility are sent: the meshes were loaded when the viewer was
        created (or, for a measure it was not created for, now). Scales are fitted at the first
        call when none were given (and for a quantity they do not have yet). A set whose drawing
        contains another's is drawn as an outline (:attr:`outlined`).
        """
        self._show(q, analysis, locked)

    def _show(
        self,
        q: np.ndarray | None,
        analysis: Analysis,
        locked: Analysis | None,
        outlined: Mapping[tuple[bool, str], tuple[tuple[bool, str], ...]] | None = None,
    ) -> None:
        """:meth:`show`, with the outlined sets given (an animation decides them over its frames)."""
        q = self.robot.check_configuration(analysis.q if q is None else q)
        frame = Frame(q, analysis, locked)
        self._fit_scales([analysis, locked])
        self._fit_magnified(self._extents([frame]))
        sets = {**self._drawn(analysis, False), **self._drawn(locked, True)}
        self.outlined = dict(self._outlined([frame]) if outlined is None else outlined)
        with self._commands():
            self._pin.display(q)
            self._vis[OBJECT_PATH].set_transform(translation(analysis.held_object.center))
            for key, task_set in sets.items():
                self._load(key, task_set.kind)
                set_outlined = getattr(DRAWINGS[task_set.kind], "set_outlined", None)
                if not key[0] and set_outlined is not None:
                    set_outlined(self._vis, scene_path(key[1], key[0]), key in self.outlined)
                visible = not task_set.empty
                if visible:
                    source = locked if key[0] else analysis
                    DRAWINGS[task_set.kind].draw(
                        self._vis,
                        scene_path(key[1], key[0]),
                        task_set,
                        source.task,
                        source.held_object.center,
                        self._set_scale(key),
                        planar_thickness(key[1], key[0]),
                    )
                self._set_visible(key, visible)
            for key in self._visible:
                if key not in sets and (not key[0] or locked is not None):  # a measure this analysis lacks
                    self._set_visible(key, False)
            if self._locked_visible != (locked is not None):
                self.set_locked_visible(locked is not None)
            notes = self._draw_floor(sets)
        self._legend(sets, self._title(analysis), notes)
        if self._camera_serial == 0:
            self.frame_camera(frame)
        self.last = frame

    def _draw_floor(self, sets: Mapping[tuple[bool, str], TaskSet]) -> list[str]:
        """On the floor: the support polygon (a dark line loop) and the zero-moment point with the
        object held still (a dot), from the first grounded set drawn; hidden otherwise."""
        import meshcat.geometry as mg

        from ..analysis.reaches import floor_at_rest

        found = next((f for f in (floor_at_rest(s) for k, s in sets.items() if not k[0]) if f is not None), None)
        self._vis[FLOOR_PATH].set_property("visible", found is not None)
        if found is None:
            return []
        z = found["floor_z"] + 0.002  # just above the floor grid
        ring = np.array([[x, y, z] for x, y in found["polygon"]] + [[*found["polygon"][0], z]])
        self._vis[f"{FLOOR_PATH}/polygon"].set_object(mg.Line(mg.PointsGeometry(ring.T), line_material(FLOOR_COLOR)))
        zmp = found["zmp"]
        if zmp is not None:
            self._vis[f"{FLOOR_PATH}/zmp"].set_object(
                mg.Sphere(0.015), mg.MeshLambertMaterial(color=FLOOR_COLOR, opacity=1.0)
            )
            self._vis[f"{FLOOR_PATH}/zmp"].set_transform(translation([zmp[0], zmp[1], z]))
            rest = "at rest" if found["still"] else "with the object still (the arms accelerating)"
            return [f"support polygon (dark line) and zero-moment point {rest} (dot): margin {found['margin']:.3f} m"]
        return ["support polygon (dark line)"]

    def _set_visible(self, key: tuple[bool, str], visible: bool) -> None:
        if self._visible[key] != visible:
            self._vis[scene_path(key[1], key[0])].set_property("visible", visible)
            self._visible[key] = visible

    def _fit_scales(self, analyses: Sequence[Analysis | None]) -> None:
        """Fit the scales (when none are set) or add those of quantities they lack."""
        fitted = ScaleFactors.fit(analyses, self.size)
        self.scales = fitted if self.scales is None else self.scales.including(fitted)

    def update(self, q: np.ndarray | None, analysis: Analysis, locked: Analysis | None = None) -> None:
        """Same as :meth:`show`: move everything to the new configuration in place."""
        self.show(q, analysis, locked)

    def placement(self, analysis: Analysis, key: tuple[bool, str]) -> np.ndarray:
        """The 4x4 transform of the ellipsoid ``key`` = (locked, measure name) for ``analysis``."""
        locked, name = key
        return ellipsoid_matrix(
            analysis.measure(name),
            analysis.task,
            analysis.held_object.center,
            self._set_scale(key),
            planar_thickness(name, locked),
        )

    def set_locked_visible(self, visible: bool) -> None:
        """Show or hide the locked-platform pair (``mobmanip/locked``)."""
        with self._commands():
            self._vis[LOCKED_PATH].set_property("visible", bool(visible))
        self._locked_visible = bool(visible)

    # ----- animations

    def animate(
        self,
        frames: Sequence[Frame],
        *,
        step: float = 0.1,
        fps: int = 30,
        play: bool = True,
        repetitions: int = 1,
        notes: Sequence[str] = (),
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
        self._fit_scales([a for f in frames for a in (f.analysis, f.locked)])
        self._fit_magnified(self._extents(frames))
        any_locked = any(f.locked is not None for f in frames)
        per_frame = [{**self._drawn(f.analysis, False), **self._drawn(f.locked, True)} for f in frames]
        order = {name: i for i, name in enumerate(measure_names())}
        keys = sorted({key for sets in per_frame for key in sets}, key=lambda k: (k[0], order[k[1]]))
        kinds = {key: sets[key].kind for sets in per_frame for key in sets}
        first = frames[0]
        self._show(first.q, first.analysis, first.locked, self._outlined(frames))
        if len(frames) > 1:  # frame the whole motion, not only its start, or follow it
            starts, t = [], 0.0
            for frame in frames:
                starts.append([t] if frame.hold <= 0 else [t, t + frame.hold])
                t = starts[-1][-1] + step
            self.frame_camera(frames, starts)
        shown: dict = {}  # each set as drawn in the legend: its first non-empty frame
        for key in keys:
            shown[key] = next((s[key] for s in per_frame if key in s and not s[key].empty), None)
            shown[key] = shown[key] or next(s[key] for s in per_frame if key in s)
        captions = _captions(frames, step)
        title = f"{self._title(first.analysis)}, {len(frames)} frames (play them in Animations)"
        self._legend(shown, title, notes, captions)
        if any_locked and not self._locked_visible:
            self.set_locked_visible(True)
        with self._commands():  # a set empty (or absent) in the first frame may appear later: scale hides it
            for key in keys:
                self._load(key, kinds[key])
                self._set_visible(key, True)
        animation = ma.Animation(default_framerate=fps)
        paths = geometry_paths(self._pin, self.visual_model)
        previous: dict = {}  # key -> (pose 4x4 without scale, semi-axes) of the last frame drawn
        schedule, t = [], 0.0
        for frame, sets in zip(frames, per_frame):
            poses = robot_poses(self.model, self.visual_model, paths, frame.q)
            poses.append((OBJECT_PATH, translation(frame.analysis.held_object.center), None))
            for key in keys:
                source = (frame.locked if key[0] else None) or frame.analysis  # the same task point
                pose = set_pose(
                    scene_path(key[1], key[0]), sets.get(key), source.task, source.held_object.center,
                    self._set_scale(key), planar_thickness(key[1], key[0]), previous, key,
                )  # fmt: skip
                if pose is not None:
                    poses.append(pose)
            times = [t] if frame.hold <= 0 else [t, t + frame.hold]
            for time_s in times:
                write_keyframe(animation, self._vis, time_s, fps, poses)
            if frame.label:
                schedule.append((t, times[-1], frame.label))
            t = times[-1] + step
        with self._commands():
            self._vis.set_animation(animation, play=play, repetitions=repetitions)
        return schedule


def _captions(frames: Sequence[Frame], step: float) -> dict | None:
    """The page's captions of an animation whose frames follow each other ``step`` s apart (a
    held frame stays its ``hold``): each frame's caption (or label; else the one before it) from
    its start; ``None`` when no frame has one."""
    times, texts, t, text = [], [], 0.0, ""
    for frame in frames:
        text = frame.caption or frame.label or text
        times.append(round(t, 6))
        texts.append(text)
        t += frame.hold + step
    return {"times": times, "texts": texts} if any(texts) else None
