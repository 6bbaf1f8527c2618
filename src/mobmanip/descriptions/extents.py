"""The bounding box of a link's geometry, in the link's frame: what the inertia-plausibility rule
(:func:`mobmanip.descriptions.flaws.implausible_inertia`) measures a link's mass against."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .description import LinkDescription, Shape

#: The largest mesh file read for its bounds (bytes): a bound on the work of a plausibility check.
MAX_MESH_BYTES = 64 * 2**20


@functools.lru_cache(maxsize=512)
def mesh_bounds(path: str) -> tuple[tuple[float, ...], tuple[float, ...]] | None:
    """A mesh file's (lower, upper) vertex corners (m, unscaled), or ``None`` when it cannot be
    read: STL (binary or text), Wavefront OBJ and COLLADA (its positions, in its own unit; the
    nodes' transforms are not applied) are read here, with NumPy. Importing a mesh library cost
    0.85 s of every robot load for a check that needs a box; other formats are not measured."""
    try:
        file = Path(path)
        if file.stat().st_size > MAX_MESH_BYTES:
            return None
        suffix = file.suffix.lower()
        if suffix == ".stl":
            points = _stl_points(file.read_bytes())
        elif suffix == ".obj":
            points = _obj_points(file.read_text(errors="replace"))
        elif suffix == ".dae":
            points = _collada_points(file.read_bytes())
        else:
            return None
    except (OSError, ValueError, SyntaxError):  # missing, unreadable or malformed (XML: SyntaxError): not measured
        return None
    if points is None or len(points) == 0 or not np.all(np.isfinite(points)):
        return None
    return tuple(points.min(axis=0)), tuple(points.max(axis=0))


def _stl_points(data: bytes) -> np.ndarray | None:
    """The vertices of an STL file, (3 n, 3): binary when its size is that of its triangle count,
    else text (``vertex X Y Z`` lines)."""
    if len(data) >= 84:
        count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        if len(data) == 84 + 50 * count:
            record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
            return np.frombuffer(data, dtype=record, count=count, offset=84)["vertices"].reshape(-1, 3).astype(float)
    words = data.decode("ascii", errors="replace").split()
    found = [words[i + 1 : i + 4] for i, word in enumerate(words) if word == "vertex"]
    return np.array(found, dtype=float).reshape(-1, 3) if found else None


def _obj_points(text: str) -> np.ndarray | None:
    """The ``v X Y Z`` vertices of a Wavefront OBJ file that its faces use (all of them when it
    has no faces)."""
    vertices: list[list[str]] = []
    used: list[int] = []
    for line in text.splitlines():
        if line.startswith("v "):
            vertices.append(line.split()[1:4])
        elif line.startswith("f "):
            used.extend(int(word.split("/")[0]) for word in line.split()[1:])
    if not vertices:
        return None
    points = np.array(vertices, dtype=float).reshape(-1, 3)
    if not used:
        return points
    index = np.array(used, dtype=np.int64)
    index = np.where(index < 0, len(points) + index, index - 1)  # 1-based, negative from the end
    if index.min() < 0 or index.max() >= len(points):
        return None  # a face names a vertex the mesh does not have
    return points[np.unique(index)]


def _collada_points(data: bytes) -> np.ndarray | None:
    """The positions of the meshes a COLLADA file's scene instantiates (every geometry when its
    scene names none), placed by their nodes' ``<matrix>`` transforms and scaled by its
    ``<unit meter>``."""
    from xml.etree import ElementTree

    root = ElementTree.fromstring(data)

    def strip(tag: str) -> str:
        return tag.rsplit("}", 1)[-1]  # the namespace is not needed

    geometries = {el.get("id"): el for el in root.iter() if strip(el.tag) == "geometry"}
    placed: list[tuple[str, np.ndarray]] = []

    def visit(node, transform: np.ndarray) -> None:
        for child in node:  # a node's transforms compose in the order written
            step = _collada_transform(strip(child.tag), (child.text or "").split())
            if step is not None:
                transform = transform @ step
        for child in node:
            tag = strip(child.tag)
            if tag == "instance_geometry":
                placed.append(((child.get("url") or "").lstrip("#"), transform))
            elif tag == "node":
                visit(child, transform)

    for scene in (el for el in root.iter() if strip(el.tag) == "visual_scene"):
        visit(scene, np.eye(4))
    if not placed:
        placed = [(name, np.eye(4)) for name in geometries if name]
    found = []
    for name, transform in placed:
        geometry = geometries.get(name)
        if geometry is None:
            continue
        points = _geometry_positions(geometry, strip)
        if points is not None:
            found.append(points @ transform[:3, :3].T + transform[:3, 3])
    if not found:
        return None
    unit = next((el for el in root.iter() if strip(el.tag) == "unit"), None)
    scale = float(unit.get("meter", 1.0)) if unit is not None else 1.0
    return scale * np.vstack(found)


def _collada_transform(tag: str, words: list[str]) -> np.ndarray | None:
    """The 4 x 4 transform of a COLLADA node's ``matrix``, ``translate``, ``rotate`` (axis and
    degrees) or ``scale`` element, or ``None`` for any other element."""
    if tag not in ("matrix", "translate", "rotate", "scale"):
        return None
    values = np.array(words, dtype=float)
    out = np.eye(4)
    if tag == "matrix":
        return values.reshape(4, 4)
    if tag == "translate":
        out[:3, 3] = values[:3]
    elif tag == "scale":
        out[:3, :3] = np.diag(values[:3])
    else:
        axis, angle = values[:3], np.radians(values[3])
        norm = float(np.linalg.norm(axis))
        if norm > 0.0:
            k = axis / norm
            K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
            out[:3, :3] = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K
    return out


def _geometry_positions(geometry, strip) -> np.ndarray | None:
    """The positions one COLLADA geometry's primitives use, (n, 3): its ``POSITION`` array, at
    the indices its triangles and polygons give their ``VERTEX`` input (an exporter may leave
    vertices no face uses)."""
    sources = {el.get("id"): el for el in geometry.iter() if strip(el.tag) == "source"}
    points = None
    for block in (el for el in geometry.iter() if strip(el.tag) == "vertices"):
        for item in block:
            if strip(item.tag) == "input" and item.get("semantic") == "POSITION":
                source = sources.get((item.get("source") or "").lstrip("#"))
                for child in [] if source is None else source:
                    if strip(child.tag) == "float_array":
                        points = np.array((child.text or "").split(), dtype=float).reshape(-1, 3)
    if points is None:
        return None
    used = []
    for primitive in geometry.iter():
        inputs = [el for el in primitive if strip(el.tag) == "input" and el.get("offset") is not None]
        vertex = [int(el.get("offset")) for el in inputs if el.get("semantic") == "VERTEX"]
        if not vertex:
            continue
        stride = max(int(el.get("offset")) for el in inputs) + 1
        for indices in (el for el in primitive if strip(el.tag) == "p"):
            used.append(np.array((indices.text or "").split(), dtype=np.int64)[vertex[0] :: stride])
    if not used:
        return points
    index = np.unique(np.concatenate(used))
    if len(index) and (index.min() < 0 or index.max() >= len(points)):
        return None  # a face names a vertex the mesh does not have
    return points[index]


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
        bounds = mesh_bounds(str(file)) if file is not None else None
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
