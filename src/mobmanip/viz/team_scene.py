"""A team in the meshcat viewer: every robot with its meshes, the object and the team's sets.

Scene paths (under meshcat's root ``/meshcat``):

================================== ==============================================================
``mobmanip/team/robots/NAME``      robot ``NAME``'s visual geometry (Pinocchio's
                                   ``MeshcatVisualizer``), at its configuration
``mobmanip/team/object``           the object: a white sphere at its centre, a brown segment
                                   from it to each grasping hand and, when the team's description
                                   gives its solid (:class:`~mobmanip.team.members.ObjectShape`),
                                   that box or cylinder (``body``) at the object's pose
``mobmanip/team/sets/K``           the team's set of measure ``K``, drawn at the object's centre
                                   by the drawing of its kind (:mod:`mobmanip.viz.shapes`), in the
                                   measure's colour, at the scale of its quantity
================================== ==============================================================

Only the linear part of a task is drawn (as for one robot). Scales: metres of scene per unit of
each quantity, so that the largest drawn extent of that quantity's sets is ``size`` (over every
frame of an animation).

The page explains itself as the single robot's does (:mod:`mobmanip.viz.page`): a legend names
the team, each drawn set by its colour with its scale and the object; the camera frames every
robot, the object and the sets (in an animation, at up to
:data:`~mobmanip.viz.animation.CAMERA_FRAMES` of its frames, so the whole team stays in view
while it moves). :meth:`TeamViewer.animate` plays a team's motion (:class:`TeamFrame`): each
robot at its own configuration, the object (its grasp segments turned with it) and the sets
moving along (:mod:`mobmanip.viz.animation`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..measures import get_measure
from ..robot.model import platform_pose
from ..team.analysis import TeamAnalysis
from ..team.members import ObjectShape
from . import page as _page
from .animation import FOLLOW_FRAMES, camera_samples, geometry_paths, robot_poses, set_extent, set_pose, write_keyframe
from .meshcat_scene import MeshcatScene
from .nesting import nested, outlined
from .scene import DEFAULT_SIZE, FLOOR_COLOR, OBJECT_COLOR, OBJECT_RADIUS, planar_thickness, scene_color, visual_model
from .server import ViewerError
from .shapes import DRAWINGS, line_material, translation

__all__ = ["TEAM_PATH", "TeamFrame", "TeamViewer", "team_scales"]

TEAM_PATH = "mobmanip/team"
OBJECT_LINK_COLOR = 0x8C6D31
#: The object's solid: see-through, so that the sets drawn at its centre stay visible.
OBJECT_BODY_COLOR = 0xC49A5A
OBJECT_BODY_OPACITY = 0.45


def object_body(shape: ObjectShape, yaw: float):
    """The meshcat geometry of an object's solid and its pose (4x4) about the object's centre,
    ``yaw`` (rad) its heading: a box of its size, or a cylinder (meshcat's along its y axis,
    turned onto the object's x)."""
    import meshcat.geometry as mg

    pose = np.eye(4)
    pose[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
    if shape.kind == "box":
        return mg.Box(list(shape.size)), pose
    pose[:3, :3] = pose[:3, :3] @ pin.rpy.rpyToMatrix(0.0, 0.0, -0.5 * math.pi)
    return mg.Cylinder(shape.size[0], 0.5 * shape.size[1]), pose


@dataclass(frozen=True)
class TeamFrame:
    """One state of a team's animation.

    Attributes:
        analysis: the team analysed there: its members' configurations, its object (centre and
            grasp offsets) and the sets drawn.
        turn: the object's turn about the vertical (rad) from the team's start; the object's grasp
            segments turn with it.
        label: what the frame shows.
    """

    analysis: TeamAnalysis
    turn: float = 0.0
    label: str = ""


def team_scales(analyses: Iterable[TeamAnalysis], size: float = DEFAULT_SIZE) -> dict[str, float]:
    """Metres of scene per unit of each quantity (by quantity name) that draw the largest extent
    of that quantity's drawable sets, over all ``analyses``, ``size`` long (1 when it is zero)."""
    largest: dict[str, float] = {}
    for analysis in analyses:
        for name, task_set in analysis.measures.items():
            if task_set.kind in DRAWINGS:
                quantity = get_measure(name).quantity.name
                extent = DRAWINGS[task_set.kind].extent(task_set, analysis.team.task)
                largest[quantity] = max(largest.get(quantity, 0.0), extent)
    return {q: (size / e if e > 0.0 else 1.0) for q, e in largest.items()}


class TeamViewer(MeshcatScene):
    """The team's scene on a meshcat server of its own (closed by :meth:`close`).

    Args:
        analysis: the analysed team (its measures are drawn).
        port: HTTP port of the viewer page; ``None`` takes the first free one from 7000.
        open_browser: open the page in the default browser.
        size: the largest drawn extent of each quantity's sets (m).
        timeout: seconds to wait for the server to answer a command.
        scales: metres of scene per unit by quantity name (as :func:`team_scales`); default:
            fitted to ``analysis`` and ``size``.

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
        scales: Mapping[str, float] | None = None,
    ):
        self.analysis = analysis
        self.mesh_notes: list[str] = []
        self.undrawn: dict[str, str] = {}
        #: The team's sets drawn as outlines (they contain, as drawn, the sets listed).
        self.outlined: dict[str, tuple[str, ...]] = {}
        with self._starting(port, timeout), self._commands():
            self._draw_robots()
            self._draw_object()
            self.scales = self._draw_sets(team_scales([analysis], size) if scales is None else dict(scales))
            self.floor_notes = self._draw_floors()
            self._legend(self._title(), self.floor_notes)
            self.frame_camera([TeamFrame(analysis)])
        if open_browser:
            self.open()

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
        shape = self.analysis.team.object_shape
        if shape is not None:
            geometry, pose = object_body(shape, self.analysis.team.object_yaw)
            material = mg.MeshLambertMaterial(color=OBJECT_BODY_COLOR, opacity=OBJECT_BODY_OPACITY, transparent=True)
            self._vis[f"{path}/body"].set_object(geometry, material)
            self._vis[f"{path}/body"].set_transform(pose)
        self._vis[path].set_transform(translation(obj.center))

    def _draw_sets(self, scales: dict[str, float]) -> dict[str, float]:
        task = self.analysis.team.task
        sets = {}
        for name, task_set in self.analysis.measures.items():
            if task_set.kind in DRAWINGS:
                sets[name] = task_set
            else:
                self.undrawn[name] = task_set.kind
        self._sets = sets
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

    def _draw_floors(self) -> list[str]:
        """On the floor: each robot's support polygon (a dark line loop) and its zero-moment point
        with the object held still (a dot), from the first grounded set drawn; a note per robot."""
        import meshcat.geometry as mg

        from ..analysis.reaches import floors_at_rest

        found = next((f for f in (floors_at_rest(s) for s in self._sets.values()) if f), {})
        notes = []
        for name, floor in found.items():
            path = f"{TEAM_PATH}/floor/{name}"
            z = floor["floor_z"] + 0.002  # just above the floor grid
            ring = np.array([[x, y, z] for x, y in floor["polygon"]] + [[*floor["polygon"][0], z]])
            self._vis[f"{path}/polygon"].set_object(mg.Line(mg.PointsGeometry(ring.T), line_material(FLOOR_COLOR)))
            if floor["zmp"] is None:
                continue
            self._vis[f"{path}/zmp"].set_object(
                mg.Sphere(0.015), mg.MeshLambertMaterial(color=FLOOR_COLOR, opacity=1.0)
            )
            self._vis[f"{path}/zmp"].set_transform(translation([floor["zmp"][0], floor["zmp"][1], z]))
            notes.append(
                f"{name}: support polygon (dark line), zero-moment point "
                f"{'at rest' if floor['still'] else 'with the object still (the arms accelerating)'} (dot), "
                f"margin {floor['margin']:.3f} m"
            )
        return notes

    def _set_scale(self, name: str) -> float:
        return self.scales[get_measure(name).quantity.name]

    # ----- legend and camera (mobmanip.viz.page)

    def _title(self) -> str:
        team = self.analysis.team
        robots = ", ".join(f"{m.name} ({m.robot.name})" for m in team.members)
        title = f"team {team.name}: {robots}; {team.task} task"
        return title + (" (linear part drawn)" if team.task in ("spatial", "planar_rigid") else "")

    def _legend(self, title: str, more: Sequence[str] = ()) -> None:
        """The legend: the team, each drawn set's colour and scale, the object; ``more`` notes."""
        scales = {name: self._set_scale(name) for name in self._sets}
        inner = {(False, name): tuple((False, n) for n in held) for name, held in self.outlined.items()}
        rows, notes = _page.legend_rows(
            {(False, name): s for name, s in self._sets.items()}, scales, {}, OBJECT_COLOR, inner
        )
        shape = self.analysis.team.object_shape
        if shape is not None:
            rows.append(
                {"color": _page.color_hex(OBJECT_BODY_COLOR), "style": "solid", "text": f"object: {shape.describe()}"}
            )
        with self._commands():
            self._send_page(title=title, rows=rows, notes=[*notes, *more])

    def frame_camera(self, frames: Sequence[TeamFrame], times: Sequence[float] | None = None) -> dict:
        """Frame every robot (its visual geometry), the object and the drawn sets of the frames (up
        to :data:`~mobmanip.viz.animation.CAMERA_FRAMES` of them, evenly spread, the last
        included), seen as the single robot's page sees its robot, from the first robot's platform
        heading in the first frame. Given the frames' ``times`` (s) in an animation, a motion
        that travels far is followed instead (:func:`mobmanip.viz.page.animation_request`, up to
        :data:`~mobmanip.viz.animation.FOLLOW_FRAMES` frames).

        Returns:
            The camera request sent (see :mod:`mobmanip.viz.page`).
        """
        first = frames[0].analysis.team.members[0]
        heading = platform_pose(first.q)[2] if first.robot.model.nq >= 4 else 0.0
        if times is not None and len(frames) > 1:
            picked = camera_samples(len(frames), FOLLOW_FRAMES)
            extents = [self._frame_extent(frames[i]) for i in picked]
            return self._send_animation_camera(extents, [[float(times[i])] for i in picked], heading)
        return self._send_fit(
            np.vstack([self._frame_extent(frames[i]) for i in camera_samples(len(frames))]), [], heading
        )

    def _frame_extent(self, frame: TeamFrame) -> np.ndarray:
        """Points (n, 3) whose box holds what one frame draws: the robots, the object, the sets."""
        points, boxes = [np.zeros((0, 3))], []
        analysis = frame.analysis
        team = analysis.team
        for member in team.members:
            viz = self._robots[member.name]
            points.append(_page.visual_points(viz.model, viz.visual_model, member.q))
        center = team.held_object.center
        points.append(center + team.held_object.offsets)  # the grasp segments' ends
        if team.object_shape is not None:
            points.append(team.object_shape.corners(center, team.object_yaw))
        boxes.append(_page.sphere_box(center, OBJECT_RADIUS))
        for name, task_set in analysis.measures.items():
            if name in self._sets and not task_set.empty:
                more, around = set_extent(task_set, team.task, center, self._set_scale(name), planar_thickness(name))
                points.append(more)
                boxes.extend(around)
        return np.vstack([*points, *(_page.box_corners(*box) for box in boxes)])

    # ----- animation

    def animate(
        self,
        frames: Sequence[TeamFrame],
        times: ArrayLike,
        *,
        fps: int = 30,
        play: bool = True,
        notes: Sequence[str] = (),
    ) -> None:
        """Send the frames as one meshcat animation (play / pause / time slider in the panel),
        frame ``k`` at ``times[k]`` s: every robot at its configuration, the object at its centre
        turned with it, the sets at the object; meshcat interpolates between frames. The scene as
        created shows the first frame; the camera frames them all; ``notes`` go under the legend.
        """
        import meshcat.animation as ma

        times = [float(t) for t in np.asarray(times, dtype=float).reshape(-1)]
        if not frames or len(frames) != len(times):
            raise ViewerError(f"an animation needs one time per frame, got {len(frames)} frames, {len(times)} times")
        self._legend(f"{self._title()}, {len(frames)} frames (play them in Animations)", notes)
        self.frame_camera(frames, times)
        animation = ma.Animation(default_framerate=fps)
        paths = {name: geometry_paths(viz, viz.visual_model) for name, viz in self._robots.items()}
        previous: dict = {}  # set name -> (pose, semi-axes) of the last frame drawn
        turn0 = frames[0].turn
        for frame, time_s in zip(frames, times):
            team = frame.analysis.team
            poses = []
            for member in team.members:
                viz = self._robots[member.name]
                poses.extend(robot_poses(viz.model, viz.visual_model, paths[member.name], member.q))
            center = team.held_object.center
            placed = translation(center)
            placed[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, frame.turn - turn0)
            poses.append((f"{TEAM_PATH}/object", placed, None))
            for name in self._sets:
                pose = set_pose(
                    self.scene_path(name), frame.analysis.measures.get(name), team.task, center,
                    self._set_scale(name), planar_thickness(name), previous, name,
                )  # fmt: skip
                if pose is not None:
                    poses.append(pose)
            write_keyframe(animation, self._vis, time_s, fps, poses)
        with self._commands():
            for name in self._sets:  # a set empty in the first frame may appear later: its scale hides it
                self._vis[self.scene_path(name)].set_property("visible", True)
            self._vis.set_animation(animation, play=play)

    @staticmethod
    def scene_path(name: str) -> str:
        """Where the team's set of measure ``name`` is drawn."""
        return f"{TEAM_PATH}/sets/{get_measure(name).name}"
