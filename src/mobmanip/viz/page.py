"""What makes the viewer page explain itself: a legend, the scales, the framing camera and the
magnification of sets too small to see at their quantity's scale.

The page (live, served by :mod:`mobmanip.viz.server`, or exported) runs ``page.js`` beside
meshcat's viewer. The Python side stores what the page shows as one property,
:data:`PAGE_PROPERTY`, of the scene node ``/meshcat/mobmanip``; meshcat's server replays it to
every page that connects and into :meth:`~mobmanip.viz.scene.EllipsoidViewer.static_html`, so the
live and the exported page show the same legend and camera. The property is a dict:

- ``title``: the robot, its platform kind and the task;
- ``rows``: one per drawn set and for the held object: ``color`` (``#rrggbb``), ``style``
  (``solid`` for the robot's own sets, ``ring`` for the locked platform's, ``dot`` for the
  object) and ``text`` (the set's name and its scale, e.g. ``1 m/s = 0.227 m``);
- ``notes``: lines under the rows (empty sets, magnified sets, the drawn part of the task);
- ``camera``: ``{"mode": "fit", "box": [lower, upper], "points", "target", "direction",
  "margin", "serial"}`` (the page places the camera along ``direction`` from ``target``, the
  box's centre, at the smallest distance at which all ``points`` fall within ``margin`` of the
  view, for the page's own aspect ratio), ``{"mode": "follow", "box", "times", "targets",
  "frames", "direction", "margin", "serial"}`` (an animation: the camera keeps its direction
  and moves with the target, the centre of each frame's box ``targets[k]`` at the animation's
  time ``times[k]`` s, linear in between; its distance is the smallest at which every frame's
  box corners ``frames[k]`` fall within ``margin`` of the view about their own target; the
  user's orbit and zoom are carried along) or ``{"mode": "look", "position", "target",
  "serial"}``; world coordinates (z up), metres. The page applies each serial once, so a
  user's own camera moves are kept.
- ``captions``: an animation's caption per frame, ``{"times": [s], "texts": [...]}``: the page
  shows ``texts[k]`` at the top of the view from the animation's time ``times[k]`` until the next
  one (what a sweep's frame holds: the object's direction, the wheels' limit);
- ``expect``: the scene paths (under ``/meshcat``) of every part drawn (the robot's meshes, the
  sets, the object): until each holds an object, the page says how many have arrived ("receiving
  the scene: 12 of 40 parts..."). The live page receives them over meshcat's socket, the robot's
  meshes last (they are the heaviest): on a busy machine tens of seconds.
- the legend never covers more than 38 % of the view's width by 50 % of its height (it scrolls
  beyond); its notes fold under one line ("6 notes", a click shows them) when, shown, the legend
  would cover more than 12 % of the view.

Magnification: within one quantity, the sets share one scale (the largest drawn extent is the
viewer's ``size``); a set whose drawn extent is below :data:`MAGNIFY_BELOW` of ``size`` would be
a speck, so it is drawn :func:`magnification` times larger (a 1-2-5 factor), and its legend row
says so with its own scale.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

if TYPE_CHECKING:
    from ..sets.taskset import TaskSet

PAGE_PROPERTY = "mobmanip_page"
SCRIPT = Path(__file__).with_name("page.js")
MAGNIFY_BELOW = 0.1  # of the viewer's size: a set drawn smaller than this is magnified
MAGNIFY_TO = 0.3  # of the viewer's size: at least this long once magnified
CAMERA_ELEVATION_DEG = 25.0  # above the horizon
CAMERA_AZIMUTH_DEG = -50.0  # from the platform heading (front right of the robot)
CAMERA_MARGIN = 0.95  # of the view the framed box may fill
#: An animation whose whole motion spans at most this many times its largest frame is framed
#: whole (within :data:`ANIMATION_MARGIN`); a longer one is followed (:func:`animation_request`).
FOLLOW_ABOVE = 1.5
ANIMATION_MARGIN = 0.8  # of the view a whole animation framed at once may fill (its central 80 %)
FOLLOW_MARGIN = 0.7  # of the view each frame fills, about its own centre, when the camera follows


def page_script() -> str:
    """The page's script, as an inline ``<script>`` element."""
    return "<script>\n" + SCRIPT.read_text(encoding="utf-8") + "\n</script>\n"


def inject(html: str) -> str:
    """``html`` with :func:`page_script` before its last ``</body>`` (appended if it has none)."""
    at = html.rfind("</body>")
    return html + page_script() if at < 0 else html[:at] + page_script() + html[at:]


def magnification(extent: float, size: float) -> float:
    """How many times larger a set is drawn: 1 when its drawn extent (m) is at least
    :data:`MAGNIFY_BELOW` ``size`` (or zero: nothing to show), else the smallest factor of the
    1-2-5 series that draws it at least :data:`MAGNIFY_TO` ``size`` long."""
    if not (extent > 0.0) or extent >= MAGNIFY_BELOW * size:
        return 1.0
    need = MAGNIFY_TO * size / extent
    decade = 10.0 ** math.floor(math.log10(need))
    for step in (1.0, 2.0, 5.0, 10.0):
        if step * decade >= need * (1.0 - 1e-12):
            return step * decade
    return 10.0 * decade  # pragma: no cover - the loop always returns


def color_hex(color: int) -> str:
    """``0xRRGGBB`` as ``#rrggbb``."""
    return f"#{int(color):06x}"


def format_factor(factor: float) -> str:
    """``20`` for 20.0, ``0.5`` for 0.5."""
    return f"{factor:g}"


# --------------------------------------------------------------------------- framing


def box_corners(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of the box from ``lower`` to ``upper``."""
    return np.array(list(itertools.product(*zip(lower, upper))), dtype=float)


#: 26 unit directions (the cube's faces, edges and corners): samples of a drawn ellipsoid.
DIRECTIONS = np.array([d for d in itertools.product((-1, 0, 1), repeat=3) if any(d)], dtype=float)
DIRECTIONS /= np.linalg.norm(DIRECTIONS, axis=1, keepdims=True)


def visual_points(model: pin.Model, visual: pin.GeometryModel, q: np.ndarray) -> np.ndarray:
    """Points (n, 3), m, world, whose hull holds the robot's visual geometry at ``q``: the corners
    of each geometry's own bounding box, placed, and the joint origins."""
    data, geometry_data = model.createData(), visual.createData()
    pin.forwardKinematics(model, data, q)
    pin.updateGeometryPlacements(model, data, visual, geometry_data)
    points = [data.oMi[j].translation for j in range(1, model.njoints)]
    for index, geom in enumerate(visual.geometryObjects):
        shape = geom.geometry
        shape.computeLocalAABB()
        lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            continue
        placement = geometry_data.oMg[index]
        points.extend(box_corners(lo, hi) @ placement.rotation.T + placement.translation)
    return np.array(points, dtype=float).reshape(-1, 3)


def visual_box(model: pin.Model, visual: pin.GeometryModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned box (lower (3,), upper (3,), m, world) around the robot's visual geometry at
    ``q`` (around :func:`visual_points`)."""
    points = visual_points(model, visual, q)
    return points.min(axis=0), points.max(axis=0)


def fit_request(
    points: np.ndarray,
    boxes: list[tuple[np.ndarray, np.ndarray]],
    heading: float,
    serial: int,
    margin: float = CAMERA_MARGIN,
) -> dict:
    """A ``fit`` camera request for ``points`` (n, 3) and the corners of ``boxes`` (lower,
    upper), seen from :data:`CAMERA_ELEVATION_DEG` above the horizon and
    :data:`CAMERA_AZIMUTH_DEG` from the platform ``heading`` (rad), aimed at the centre of
    their bounding box."""
    every = np.vstack([np.asarray(points, dtype=float).reshape(-1, 3), *(box_corners(*box) for box in boxes)])
    lower, upper = every.min(axis=0), every.max(axis=0)
    el = math.radians(CAMERA_ELEVATION_DEG)
    az = heading + math.radians(CAMERA_AZIMUTH_DEG)
    direction = [math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]
    return {
        "mode": "fit",
        "box": [[float(v) for v in lower], [float(v) for v in upper]],
        "points": np.round(every, 4).tolist(),
        "target": [float(v) for v in 0.5 * (lower + upper)],
        "direction": direction,
        "margin": float(margin),
        "serial": int(serial),
    }


def animation_request(
    frames: Sequence[np.ndarray], times: Sequence[Sequence[float]], heading: float, serial: int
) -> dict:
    """The camera of an animation: the points (n_k, 3) each frame draws, ``frames``, at the
    animation's times ``times`` (each frame's keyframe times, s: one, or two for a frame held).

    A motion that stays within :data:`FOLLOW_ABOVE` times its largest frame is framed whole, its
    points within :data:`ANIMATION_MARGIN` of the view (a ``fit`` request); a longer one (a robot
    driving off) is followed: a ``follow`` request whose targets are the centres of each frame's
    box, the distance such that every frame's box fills at most :data:`FOLLOW_MARGIN` of the
    view about its own centre, so that the robot stays at one readable size in the middle of the
    view. Seen as :func:`fit_request` sees, from the platform ``heading`` (rad).
    """
    boxes = [(np.min(p, axis=0), np.max(p, axis=0)) for p in frames]
    every = np.vstack(frames)
    whole = float(np.linalg.norm(np.ptp(every, axis=0)))
    largest = max(float(np.linalg.norm(hi - lo)) for lo, hi in boxes)
    if whole <= FOLLOW_ABOVE * largest:
        return fit_request(every, [], heading, serial, ANIMATION_MARGIN)
    request = fit_request(np.vstack([box_corners(*box) for box in boxes]), [], heading, serial, FOLLOW_MARGIN)
    stamps, targets, corners = [], [], []
    for (lo, hi), at in zip(boxes, times):
        for t in at:
            stamps.append(float(t))
            targets.append([float(v) for v in 0.5 * (lo + hi)])
            corners.append(np.round(box_corners(lo, hi), 4).tolist())
    del request["points"]
    request.update(mode="follow", times=stamps, targets=targets, frames=corners)
    return request


def look_request(position, target, serial: int) -> dict:
    """A ``look`` camera request: the camera at ``position`` looking at ``target`` (world, m)."""
    return {
        "mode": "look",
        "position": [float(v) for v in position],
        "target": [float(v) for v in target],
        "serial": int(serial),
    }


def sphere_box(center, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The box around a sphere."""
    center = np.asarray(center, dtype=float)
    return center - radius, center + radius


# --------------------------------------------------------------------------- legend


def legend_rows(
    sets: Mapping[tuple[bool, str], TaskSet],
    scales,
    magnified: Mapping[tuple[bool, str], float],
    object_color: int,
    outlined: Mapping[tuple[bool, str], Sequence[tuple[bool, str]]] | None = None,
) -> tuple[list[dict], list[str]]:
    """The legend's rows and notes for the sets drawn, by (locked, measure name).

    Args:
        sets: the sets of one show (own and locked), by key; empty ones get a note, not a row.
        scales: the viewer's :class:`~mobmanip.viz.scene.ScaleFactors`.
        magnified: the factor of each magnified set, by key.
        object_color: colour of the held object's sphere.
        outlined: the sets drawn as outlines, with the sets each contains (a ring key and a note).
    """
    outlined = outlined or {}
    from ..measures import get_measure, measure_names

    order = {name: i for i, name in enumerate(measure_names())}
    rows, notes = [], []
    for locked, name in sorted(sets, key=lambda k: (k[0], order[k[1]])):
        measure, task_set = get_measure(name), sets[locked, name]
        what = f"locked platform, {measure.label}" if locked else measure.label
        if task_set.empty:
            notes.append(f"{what}: EMPTY (the limits cannot hold the load still), not drawn")
            continue
        factor = magnified.get((locked, name), 1.0)
        scale = scales[name] * factor
        unit = measure.quantity.unit.replace("^2", "\u00b2")
        text = f"{what}: 1 {unit} = {scale:.3g} m"
        if factor != 1.0:
            text += f" (drawn \u00d7{format_factor(factor)})"
            notes.append(
                f"{what} is drawn {format_factor(factor)} times larger than the other "
                f"{measure.quantity.label} sets, which would hide it"
            )
        color = measure.locked_color if locked else measure.color
        inner = outlined.get((locked, name), ())
        if inner:
            text += " (outline)"
            held = ", ".join(get_measure(n).label for _, n in inner)
            notes.append(f"{measure.label} is drawn as an outline: it contains {held} as drawn")
        style = "ring" if locked or inner else "solid"
        rows.append({"color": color_hex(color), "style": style, "text": text})
    rows.append({"color": color_hex(object_color), "style": "dot", "text": "held object (the task point)"})
    return rows, notes
