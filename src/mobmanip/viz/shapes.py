"""How the viewer draws each kind of task-space set (:attr:`mobmanip.measure.TaskSet.kind`).

A :class:`SetDrawing` knows one kind: the meshcat objects it loads at a scene path once, how
far a set reaches when drawn (for the scale factors), how to place a set in the scene, and its
keyframe in an animation. :data:`DRAWINGS` maps kinds to drawings; the viewer draws every set
of a registered kind and lists the others in :attr:`mobmanip.viz.scene.EllipsoidViewer.undrawn`.

- ``"ellipsoid"`` (:class:`EllipsoidDrawing`): a group at the scene path whose transform maps the
  unit sphere onto the drawn ellipsoid; it holds ``shape`` (a semi-transparent unit sphere, or
  for the locked platform three unit circles, the principal sections) and ``axes`` (the
  principal axes, unit segments along local x, y, z, in a darker shade). See
  :func:`ellipsoid_frame` for the transform.
- ``"polytope"``: not drawn yet. Its drawing (issue 12) is a :class:`SetDrawing` registered with
  :func:`register_drawing`: a translucent triangle mesh of the drawn part (3-D tasks) or its
  outline (planar tasks), sent with ``set_object`` at each :meth:`SetDrawing.draw` (its shape
  changes with the configuration, so :meth:`SetDrawing.keyframe` returns ``None`` and
  animations show it at its first frame).

Only the *linear* part of a task space is drawn: ``planar`` and ``planar_rigid`` as the (x, y)
set, ``translational`` as it is, ``spatial`` as its projection (shadow) onto (x, y, z), i.e. the
linear velocities (accelerations) reachable with any accompanying angular motion.
"""

from __future__ import annotations

import itertools
from typing import Protocol

import numpy as np

from ..ellipsoids import Ellipsoid
from ..measure import TaskSet
from ..tasks import get_task
from .server import ViewerError

MIN_SEMI_AXIS = 0.002  # m: how a zero (degenerate) semi-axis is drawn
OPACITY = 0.5  # of the robot's own sets; the locked ones are drawn as rings


class SetDrawing(Protocol):
    """How the viewer draws task-space sets of one kind."""

    def load(self, vis, path: str, color: int, locked: bool) -> None:
        """Load what never changes at scene ``path`` (a meshcat ``Visualizer``), once."""

    def extent(self, task_set: TaskSet, task: str) -> float:
        """How far the drawn part reaches from the task point, in task units (0 when empty)."""

    def draw(self, vis, path: str, task_set: TaskSet, task: str, origin: np.ndarray, scale: float, thickness: float):
        """Place a non-empty set at ``path``: task point ``origin`` (m, (3,)), ``scale`` m of
        scene per task unit, ``thickness`` (m) for a planar set drawn in 3-D."""

    def keyframe(
        self,
        task_set: TaskSet,
        task: str,
        origin: np.ndarray,
        scale: float,
        thickness: float,
        previous: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The group's pose (4x4, no scale) and scale (3,) in an animation, following the
        ``previous`` keyframe's rotation (3x3) for smooth motion; ``None``: not animated."""


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

    The columns of the rotation are the world directions of the principal axes (descending
    semi-axes; an axis' sign is free: for a 3-D ellipsoid the last column is negated if needed
    so that it is a rotation, for a 2-D one the second, so that the thin third axis points up).
    A 2-D ellipse is drawn as a flat ellipsoid in the horizontal plane through the task point,
    its third semi-axis ``thickness``.

    Args:
        ellipsoid: the task-space ellipsoid (rows in world axes).
        task: its task space.
        origin: world position of the task point (m), (3,).
        scale: metres of scene per unit of the ellipsoid (m per m/s or per m/s^2).
        thickness: third semi-axis (m) of a 2-D ellipse.

    Returns:
        (p, R, r): centre p = origin + scale * c (3,), rotation R (3, 3) whose columns are the
        principal directions (descending), semi-axes r (3,) in metres (zero semi-axes raised to
        MIN_SEMI_AXIS).
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


class EllipsoidDrawing:
    """Ellipsoids: a unit sphere (or, locked, three unit rings) and its principal axes, placed by
    one group transform (:func:`ellipsoid_matrix`); see the module's docstring."""

    def load(self, vis, path: str, color: int, locked: bool) -> None:
        import meshcat.geometry as mg

        if locked:  # rings only: they never hide the robot's own set, which usually contains them
            vis[f"{path}/shape"].set_object(mg.LineSegments(mg.PointsGeometry(_unit_rings()), _line_material(color)))
            vis[f"{path}/shape/<object>"].set_property("renderOrder", 1)
        else:
            material = mg.MeshLambertMaterial(color=color, opacity=OPACITY, transparent=True, depthWrite=False)
            vis[f"{path}/shape"].set_object(mg.Sphere(1.0), material)
        # Principal axes: +-1 along local x, y, z (the group transform scales them).
        segments = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], dtype=np.float32).T
        vis[f"{path}/axes"].set_object(mg.LineSegments(mg.PointsGeometry(segments), _line_material(_darker(color))))
        vis[f"{path}/axes/<object>"].set_property("renderOrder", 1)

    def extent(self, task_set: Ellipsoid, task: str) -> float:
        return drawn_extent(task_set, task)

    def draw(self, vis, path, task_set, task, origin, scale, thickness) -> None:
        vis[path].set_transform(ellipsoid_matrix(task_set, task, origin, scale, thickness))

    def keyframe(self, task_set, task, origin, scale, thickness, previous):
        p, R, semi = ellipsoid_frame(task_set, task, origin, scale, thickness)
        planar = drawn_ellipsoid(task_set, task)[0].dim == 2
        R, semi = _aligned(R, semi, previous, planar)
        pose = _translation(p)
        pose[:3, :3] = R
        return pose, semi


#: How each kind of set is drawn (see the module's docstring; "polytope" is not drawn yet).
DRAWINGS: dict[str, SetDrawing] = {"ellipsoid": EllipsoidDrawing()}


def register_drawing(kind: str, drawing: SetDrawing) -> None:
    """Draw the sets of ``kind`` with ``drawing`` (replacing any drawing of that kind)."""
    DRAWINGS[kind] = drawing


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
