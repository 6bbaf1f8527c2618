"""How the viewer draws each kind of task-space set (:attr:`mobmanip.sets.taskset.TaskSet.kind`).

A :class:`SetDrawing` knows one kind: the meshcat objects it loads at a scene path once, how
far a set reaches when drawn (for the scale factors), how to place a set in the scene, and its
keyframe in an animation. :data:`DRAWINGS` maps kinds to drawings; the viewer draws every set
of a registered kind and lists the others in :attr:`mobmanip.viz.scene.EllipsoidViewer.undrawn`.

- ``"ellipsoid"`` (:class:`EllipsoidDrawing`): a group at the scene path whose transform maps the
  unit sphere onto the drawn ellipsoid; it holds ``shape`` (a semi-transparent unit sphere, or
  for the locked platform three unit circles, the principal sections) and ``axes`` (the
  principal axes, unit segments along local x, y, z, in a darker shade). See
  :func:`ellipsoid_frame` for the transform.
- ``"polytope"`` (:class:`PolytopeDrawing`): a group at the scene path, translated to the task
  point, holding ``shape`` (3-D tasks: a translucent triangle mesh of the drawn part, from its
  :attr:`~mobmanip.sets.polytope.Polytope.triangles`; not for the locked platform) and ``edges`` (its
  edges as line segments: the outline of a planar set, drawn ``thickness`` above the task point
  so that it lies on the ellipses' discs). Both are sent with ``set_object`` at each
  :meth:`SetDrawing.draw`, in metres relative to the task point (its shape changes with the
  configuration, so :meth:`SetDrawing.keyframe` returns ``None`` and animations show it at its
  first frame). See :func:`polytope_geometry`.

Only the *linear* part of a task space is drawn: ``planar`` and ``planar_rigid`` as the (x, y)
set, ``translational`` as it is, ``spatial`` as its projection (shadow) onto (x, y, z), i.e. the
linear velocities (accelerations) reachable with any accompanying angular motion.
"""

from __future__ import annotations

import itertools
from typing import Protocol

import numpy as np

from ..robot.tasks import get_task
from ..sets.ellipsoid import Ellipsoid
from ..sets.taskset import TaskSet
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

    def set_outlined(self, vis, path: str, outlined: bool) -> None:
        """Draw the set at ``path`` as an outline (it contains another set, which its surface
        would hide) or as a solid; takes effect now or, for a drawing that sends its meshes at
        each :meth:`draw`, at the next draw."""


# --------------------------------------------------------------------------- ellipsoid math


def drawn_linear_part(task_set: TaskSet, task: str) -> tuple[TaskSet, np.ndarray]:
    """The part of a task-space set that is drawn, and where its coordinates point.

    Returns:
        (linear, E): ``linear`` is the set itself when the task is all linear (``planar``,
        ``translational``), else its projection (shadow) onto the linear coordinates
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
        return task_set, E
    return task_set.project(tuple(linear)), E


def drawn_ellipsoid(ellipsoid: Ellipsoid, task: str) -> tuple[Ellipsoid, np.ndarray]:
    """:func:`drawn_linear_part` of an ellipsoid."""
    return drawn_linear_part(ellipsoid, task)  # type: ignore[return-value]


def drawn_extent(ellipsoid: Ellipsoid, task: str) -> float:
    """``|centre|`` + largest semi-axis of the drawn part (task units; 0 when empty)."""
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


def aligned(R: np.ndarray, semi: np.ndarray, previous: np.ndarray | None, planar: bool):
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
            vis[f"{path}/shape"].set_object(mg.LineSegments(mg.PointsGeometry(_unit_rings()), line_material(color)))
            vis[f"{path}/shape/<object>"].set_property("renderOrder", 1)
        else:
            material = mg.MeshLambertMaterial(color=color, opacity=OPACITY, transparent=True, depthWrite=False)
            vis[f"{path}/shape"].set_object(mg.Sphere(1.0), material)
            # The outline drawn instead of the surface when the set holds another (set_outlined).
            vis[f"{path}/outline"].set_object(mg.LineSegments(mg.PointsGeometry(_unit_rings()), line_material(color)))
            vis[f"{path}/outline/<object>"].set_property("renderOrder", 1)
            vis[f"{path}/outline"].set_property("visible", False)
        # Principal axes: +-1 along local x, y, z (the group transform scales them).
        segments = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], dtype=np.float32).T
        vis[f"{path}/axes"].set_object(mg.LineSegments(mg.PointsGeometry(segments), line_material(_darker(color))))
        vis[f"{path}/axes/<object>"].set_property("renderOrder", 1)

    def extent(self, task_set: Ellipsoid, task: str) -> float:
        return drawn_extent(task_set, task)

    def draw(self, vis, path, task_set, task, origin, scale, thickness) -> None:
        vis[path].set_transform(ellipsoid_matrix(task_set, task, origin, scale, thickness))

    def set_outlined(self, vis, path: str, outlined: bool) -> None:
        """The surface, or its three principal sections (rings) when ``outlined``; a locked set
        is always rings."""
        vis[f"{path}/shape"].set_property("visible", not outlined)
        vis[f"{path}/outline"].set_property("visible", outlined)

    def keyframe(self, task_set, task, origin, scale, thickness, previous):
        p, R, semi = ellipsoid_frame(task_set, task, origin, scale, thickness)
        planar = drawn_ellipsoid(task_set, task)[0].dim == 2
        R, semi = aligned(R, semi, previous, planar)
        pose = translation(p)
        pose[:3, :3] = R
        return pose, semi


# --------------------------------------------------------------------------- polytopes

POLYTOPE_OPACITY = 0.3  # of the robot's own 3-D polytopes (they enclose the ellipsoids)


def drawn_polytope(polytope, task: str):
    """:func:`drawn_linear_part` of a polytope (a spatial task's is its shadow on x, y, z)."""
    return drawn_linear_part(polytope, task)


def polytope_geometry(polytope, task: str, scale: float, thickness: float = 0.0):
    """What is drawn of a polytope, in metres relative to the task point.

    Args:
        polytope: the task-space polytope (rows in world axes), not empty.
        task: its task space.
        scale: metres of scene per unit of the polytope.
        thickness: height (m) above the task point of a planar set's outline.

    Returns:
        (points, triangles, segments): the drawn vertices ``points`` (v, 3) = scale E V (lifted by
        ``thickness`` for a 2-D set), the boundary triangles (t, 3) into them (none for a 2-D
        set) and the edges (e, 2) into them (the outline of a 2-D set).
    """
    linear, E = drawn_polytope(polytope, task)
    V = linear.vertices
    points = scale * V @ E.T
    k = linear.dim
    if k == 2:
        points[:, 2] += thickness
    elif k != 3:
        raise ViewerError(f"cannot draw a {k}-dimensional polytope")
    triangles = linear.triangles if k == 3 else np.zeros((0, 3), dtype=int)
    edges: set[tuple[int, int]] = set()
    for face in linear.faces if len(V) > 2 else [np.arange(len(V))]:
        face = np.asarray(face, dtype=int)
        pairs = zip(face, np.roll(face, -1)) if len(face) > 2 else [tuple(face)] if len(face) == 2 else []
        edges.update((int(min(a, b)), int(max(a, b))) for a, b in pairs)
    segments = np.array(sorted(edges), dtype=np.int64).reshape(-1, 2)
    return points, np.asarray(triangles, dtype=int), segments


class PolytopeDrawing:
    """Polytopes: a translucent mesh (3-D, not locked) and the edges, re-sent at each draw; see
    the module's docstring. It remembers, per scene path, the colour and whether it is locked."""

    def __init__(self):
        self._styles: dict[str, tuple[int, bool]] = {}
        self._outlined: set[str] = set()

    def load(self, vis, path: str, color: int, locked: bool) -> None:
        self._styles[path] = (color, locked)

    def extent(self, task_set, task: str) -> float:
        if task_set.empty:
            return 0.0
        linear, _ = drawn_polytope(task_set, task)
        return float(np.max(np.linalg.norm(linear.vertices, axis=1), initial=0.0))

    def draw(self, vis, path, task_set, task, origin, scale, thickness) -> None:
        import meshcat.geometry as mg

        color, locked = self._styles.get(path, (0x888888, False))
        points, triangles, segments = polytope_geometry(task_set, task, scale, thickness)
        vis[path].set_transform(translation(origin))
        if len(triangles) and not locked and path not in self._outlined:
            material = mg.MeshLambertMaterial(color=color, opacity=POLYTOPE_OPACITY, transparent=True, depthWrite=False)
            geometry = mg.TriangularMeshGeometry(points.astype(np.float32), triangles.astype(np.uint32))
            vis[f"{path}/shape"].set_object(geometry, material)
        else:
            vis[f"{path}/shape"].delete()
        lines = points[segments.reshape(-1)].T.astype(np.float32) if len(segments) else np.zeros((3, 0), np.float32)
        meshed = len(triangles) and not locked and path not in self._outlined
        edge_color = _darker(color, 0.7) if meshed else color
        vis[f"{path}/edges"].set_object(mg.LineSegments(mg.PointsGeometry(lines), line_material(edge_color)))
        vis[f"{path}/edges/<object>"].set_property("renderOrder", 1)

    def set_outlined(self, vis, path: str, outlined: bool) -> None:
        """Edges only when ``outlined`` (from the next :meth:`draw`, which sends the mesh)."""
        if outlined:
            self._outlined.add(path)
        else:
            self._outlined.discard(path)

    def keyframe(self, task_set, task, origin, scale, thickness, previous):
        return None  # the mesh changes shape with the configuration: shown as first drawn


#: How each kind of set is drawn (see the module's docstring).
DRAWINGS: dict[str, SetDrawing] = {"ellipsoid": EllipsoidDrawing(), "polytope": PolytopeDrawing()}  # type: ignore[dict-item]


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


def line_material(color: int):
    """Lines drawn after the semi-transparent shapes (transparent pass, renderOrder 1), so that
    rings and axes inside a shape keep their colour instead of being tinted by its surface."""
    import meshcat.geometry as mg

    return mg.LineBasicMaterial(color=color, transparent=True, opacity=1.0)


def _darker(color: int, factor: float = 0.45) -> int:
    r, g, b = ((color >> shift) & 0xFF for shift in (16, 8, 0))
    return (int(r * factor) << 16) | (int(g * factor) << 8) | int(b * factor)


def translation(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = np.asarray(p, dtype=float)
    return T
