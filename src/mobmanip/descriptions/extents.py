"""The bounding box of a link's geometry, in the link's frame: what the inertia-plausibility rule
(:func:`mobmanip.descriptions.flaws.implausible_inertia`) measures a link's mass against."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .description import LinkDescription, Shape


@functools.lru_cache(maxsize=512)
def _mesh_bounds(path: str) -> tuple[tuple[float, ...], tuple[float, ...]] | None:
    """A mesh file's (lower, upper) vertex corners (m, unscaled), or ``None`` when unreadable."""
    try:
        import trimesh

        mesh = trimesh.load(path, force="mesh", process=False)
        lower, upper = np.asarray(mesh.bounds, dtype=float)
    except Exception:  # a missing, unreadable or empty file: that shape is not measured
        return None
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        return None
    return tuple(lower), tuple(upper)


def _mesh_file(filename: str, package_dirs: Sequence[Path]) -> Path | None:
    """Where a mesh reference resolves: an absolute path, ``file://``, ``package://PKG/REST``
    under a package directory (``DIR/PKG/REST`` or ``DIR/REST``), or a path relative to one."""
    if filename.startswith("file://"):
        filename = filename[len("file://") :]
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://") :].partition("/")
        candidates = [d / package / rest for d in package_dirs] + [d / rest for d in package_dirs]
        candidates += [d.parent / package / rest for d in package_dirs]
    elif Path(filename).is_absolute():
        candidates = [Path(filename)]
    else:  # as written (an MJCF's meshdir under the working folder), else under a package folder
        candidates = [Path(filename)] + [d / filename for d in package_dirs]
    return next((c for c in candidates if c.is_file()), None)


def _corners(shape: Shape, package_dirs: Sequence[Path]) -> np.ndarray | None:
    """The corners (8, 3) of a shape's own bounding box in the link frame, or ``None``."""
    if shape.kind == "box" and shape.size is not None:
        half = np.asarray(shape.size, dtype=float) / 2
        lower, upper = -half, half
    elif shape.kind == "sphere" and shape.radius:
        lower, upper = -np.full(3, shape.radius), np.full(3, shape.radius)
    elif shape.kind == "cylinder" and shape.radius and shape.length is not None:
        upper = np.array([shape.radius, shape.radius, shape.length / 2])
        lower = -upper
    elif shape.kind == "mesh" and shape.filename:
        file = _mesh_file(shape.filename, package_dirs)
        bounds = _mesh_bounds(str(file)) if file is not None else None
        if bounds is None:
            return None
        scale = np.asarray(shape.scale if shape.scale is not None else (1.0, 1.0, 1.0), dtype=float)
        ends = np.array(bounds) * scale
        lower, upper = ends.min(axis=0), ends.max(axis=0)
    else:
        return None
    box = np.array(
        [[x, y, z] for x in (lower[0], upper[0]) for y in (lower[1], upper[1]) for z in (lower[2], upper[2])]
    )
    return box @ shape.origin.rotation.T + np.asarray(shape.origin.xyz, dtype=float)


def geometry_extents(link: LinkDescription, package_dirs: Sequence[Path]) -> np.ndarray | None:
    """The edges (m, (3,)) of the box in the link frame that holds the link's collision shapes
    (its visual ones when it has none), or ``None`` when none of them can be measured (no
    shapes, or mesh files that cannot be read)."""
    shapes = link.collisions or link.visuals
    corners = [c for c in (_corners(shape, package_dirs) for shape in shapes) if c is not None]
    if not corners:
        return None
    points = np.vstack(corners)
    return points.max(axis=0) - points.min(axis=0)
