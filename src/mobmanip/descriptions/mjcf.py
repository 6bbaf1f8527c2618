"""MJCF: MuJoCo's robot files (MuJoCo Menagerie's mobile manipulators, say), read into the same
neutral description as a URDF, with Pinocchio's MJCF builders (``buildModelFromMJCF``,
``buildGeomFromMJCF``) for the model and its geometry.

:func:`read_mjcf` (the ``mjcf`` format, suffixes ``.xml`` and ``.mjcf``; an ``.xml`` file whose
root is ``<robot>`` is read as a URDF) reads what mobmanip needs and says what it skips:

- ``<include>`` files, the ``<compiler>`` (``angle``: degrees unless ``radian``; ``eulerseq``;
  ``meshdir`` / ``assetdir``; ``autolimits``) and ``<default>`` classes (nested, ``childclass``);
- bodies (links) and their placements (``pos`` and ``quat``, ``axisangle``, ``euler``, ``xyaxes``
  or ``zaxis``); ``hinge`` joints (revolute with a ``range``, continuous without) and ``slide``
  joints (prismatic), their axes, and their anchors (``pos``: the link frame is put on the joint
  as in Pinocchio's model); a body with several joints becomes a chain of links, one joint each
  (``BODY__JOINT`` for all but the last), as MuJoCo applies them in order; sites become frames
  (a link ``SITE`` on a fixed joint ``SITE_site``; ``SITE_site`` when a body has the site's name,
  MuJoCo naming the two apart): an end effector may be a site; a geom's shape is named by the
  geom, else by its class (a sphere of class ``caster`` is a caster of the floor model);
- the one body under ``<worldbody>`` is the root link; its ``free`` joint is dropped (mobmanip
  adds the platform's planar joint); a ``ball`` joint or a ``free`` joint elsewhere is refused;
- a planar base: a slide along x, a slide along y and a hinge about z on the root body, or on a
  chain of nested bodies below it (``virtual_x``, ``virtual_y``, then the yaw, as Menagerie's
  mobile FR3 Duo), leaves the tree and becomes the description's ``planar_base`` (an
  omnidirectional platform with those joints' limits; see ``_Tree.nested_base`` for how the
  bodies above the yaw are lumped into the platform and the yaw axis put on its origin);
- armature: Pinocchio's builder reads every joint's ``armature`` into ``model.armature`` (and its
  mass matrix); of the planar base joints', the yaw's goes to the platform joint's yaw rate and the
  slides' become a point mass on the yaw axis (the same kinetic energy as MuJoCo's, so the same
  mass matrix and bias; see :class:`~mobmanip.descriptions.mjcf_builder.MjcfBuilder`);
- inertias: ``<inertial>`` (``diaginertia`` in its ``quat`` frame, or ``fullinertia``); a body
  without one gets its geoms' (``mass``, or ``density`` times volume, for spheres, boxes,
  cylinders, capsules and ellipsoids) as Pinocchio computes them, and its closed mesh geoms'
  integrated as MuJoCo does (:meth:`_Tree.mesh_mass_properties`: volume, or surface for
  ``inertia="shell"``; a mesh's ``scale`` from its class too; the body is then given the
  ``<inertial>`` for Pinocchio, which would give it 1 kg and a unit tensor, and likewise when a
  geom that collides with nothing has mass: Pinocchio leaves such geoms out, MuJoCo weighs them). A mesh whose file is
  missing or not closed is not integrated: the notes name its body, which needs the file or an
  ``<inertial>`` before the dynamic measures mean anything (Menagerie's Stretch without its meshes);
- limits: position from a joint's ``range``; effort from its ``actuatorfrcrange``, else from the
  actuators on it: ``gear`` times the largest ``forcerange`` bound, or for a ``motor`` without
  one, ``gear`` times the largest ``ctrlrange`` bound; velocity from a ``velocity`` actuator's
  ``ctrlrange`` (divided by its ``gear``). MJCF has no velocity limit of its own: a joint without
  such an actuator has none (``init-spec`` asks for it). The joints the actuators drive are the
  description's ``actuated``: a wheel none drives only rolls along (the mobile FR3 Duo's steered
  drive units, whose base the file moves on actuated planar joints);
- keyframes: each ``<key>``'s ``qpos`` read by the file's own joint layout (a free root joint's
  seven numbers included) into the description's ``keyframes``, joint name -> position, which
  ``init-spec`` offers as ``[postures.NAME]``; a key of the wrong size is left out with a note.
  The ``<keyframe>`` section is never handed to Pinocchio (it is sized for the file's joints,
  not for mobmanip's model, and Pinocchio refuses a model whose keyframes do not fit it);
- geometry: geoms are the link's shapes (visual: all of them; collision: those with ``contype``
  or ``conaffinity``); the viewer loads STL and OBJ meshes (Pinocchio's ``buildGeomFromMJCF``).

Skipped, and listed in the description's ``notes`` when the file has them: tendons and the
actuators that act through them or through sites, equality constraints (coupled joints move
independently here), contact settings, sensors, cameras, lights, textures and materials.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING
from xml.etree import ElementTree

import numpy as np

from ..errors import MjcfError
from ..support.reading import MAX_ROBOT_FILE_BYTES, decimal, read_bounded
from .checks import assemble
from .description import (
    Inertial,
    JointDescription,
    JointLimits,
    LinkDescription,
    Origin,
    RobotDescription,
    Shape,
)
from .formats import DescriptionFormat, register_format
from .mjcf_builder import MjcfBuilder

if TYPE_CHECKING:
    pass

#: Actuator elements: all set the attributes of MuJoCo's ``general`` actuator.
ACTUATORS = ("general", "motor", "position", "velocity", "intvelocity", "damper", "cylinder", "muscle", "adhesion")

#: Sections of a MuJoCo file that mobmanip does not read, and what they are, for the notes.
SKIPPED = {
    "tendon": "tendons",
    "equality": "equality constraints (coupled joints move independently here)",
    "contact": "contact pairs and exclusions",
    "sensor": "sensors",
}

_DENSITY = 1000.0  # kg/m^3, MuJoCo's default


def _float(value: str | float) -> float:
    """A number attribute's value, written in decimal notation only: Python's ``float`` also reads
    ``"1_0"`` as ten and digits of other scripts, which MuJoCo and Pinocchio's own MJCF parser
    (which builds the model from the same text) do not; a ValueError otherwise."""
    return decimal(value) if isinstance(value, str) else float(value)


def _floats(text: str | None, what: str, count: int | None = None) -> list[float] | None:
    if text is None:
        return None
    try:
        values = [_float(v) for v in text.split()]
    except ValueError:
        raise MjcfError("", f"{what} is not numeric: {text!r}") from None  # the caller names the file
    if count is not None and len(values) != count:
        raise MjcfError("", f"{what} must be {count} numbers, got {text!r}")
    return values


def _quat_matrix(q: Iterable[float]) -> np.ndarray:
    w, x, y, z = np.asarray(list(q), dtype=float) / np.linalg.norm(list(q))
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw of R = Rz(yaw) Ry(pitch) Rx(roll) (URDF's convention)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-12:  # gimbal lock: put all of the rotation about z into yaw
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


class _Reader:
    """One MJCF file: includes expanded, defaults resolved, the tree walked into description parts."""

    def __init__(self, path: Path, data: bytes) -> None:
        self.path = path
        self.notes: list[str] = []
        #: Bytes read so far, the file's and its includes' (bounded together).
        self.read_bytes = len(data)
        try:
            self.root = ElementTree.fromstring(data)
        except ElementTree.ParseError as exc:
            raise self.fail(f"not well-formed XML: {exc}") from None
        if self.root.tag != "mujoco":
            raise self.fail(f"root element is <{self.root.tag}>, expected <mujoco>")
        self._expand_includes(self.root, path.parent, depth=0)
        compiler: dict[str, str] = {}
        for element in self.root.iter("compiler"):
            compiler.update(element.attrib)
        self.degrees = compiler.get("angle", "degree") != "radian"
        self.eulerseq = compiler.get("eulerseq", "xyz")
        self.autolimits = compiler.get("autolimits", "true") == "true"
        asset_dir = compiler.get("assetdir")
        self.meshdir = path.parent / compiler.get("meshdir", asset_dir or "")
        self.texturedir = path.parent / compiler.get("texturedir", asset_dir or "")
        self.defaults: dict[str, dict[str, dict[str, str]]] = {}
        for top in self.root.findall("default"):
            self._read_defaults(top, {}, top.get("class", "main"))
        self.meshes: dict[str, tuple[Path, tuple[float, float, float] | None]] = {}
        #: Each mesh's ``inertia`` attribute: how MuJoCo integrates its mass (``legacy`` unless said).
        self.mesh_inertia: dict[str, str] = {}
        for asset in self.root.iter("asset"):
            for mesh in asset.findall("mesh"):
                file = mesh.get("file")
                if file is None:
                    continue
                name = mesh.get("name") or Path(file).stem
                attrs = self.attributes(mesh, "mesh", "main")  # a class may give the scale (Robotiq's mm)
                scale = _floats(attrs.get("scale"), f"mesh {name!r} scale", 3)
                factors = None if scale is None else (scale[0], scale[1], scale[2])
                self.meshes[name] = (self.meshdir / file, factors)
                self.mesh_inertia[name] = attrs.get("inertia", "legacy")
        for tag, what in SKIPPED.items():
            if any(len(element) for element in self.root.iter(tag)):
                self.notes.append(f"not read: {what}")

    def fail(self, reason: str) -> MjcfError:
        return MjcfError(str(self.path), reason)

    # ----- the file

    def _expand_includes(self, element: ElementTree.Element, folder: Path, depth: int) -> None:
        if depth > 20:
            raise self.fail("<include> nested more than 20 deep")
        for k, child in enumerate(list(element)):
            if child.tag == "include":
                file = folder / child.get("file", "")
                where = f"<include file={child.get('file')!r}>"

                def refuse(reason: str, where: str = where) -> MjcfError:
                    return self.fail(f"{where}: {reason}")

                data = read_bounded(file, limit=MAX_ROBOT_FILE_BYTES, refuse=refuse)
                self.read_bytes += len(data)
                if self.read_bytes > MAX_ROBOT_FILE_BYTES:
                    raise refuse(
                        f"the file and its includes come to more than the {MAX_ROBOT_FILE_BYTES} bytes this reads"
                    )
                try:
                    included = ElementTree.fromstring(data)
                except ElementTree.ParseError as exc:
                    raise self.fail(f"{where}: {exc}") from None
                self._expand_includes(included, file.parent, depth + 1)
                element.remove(child)
                for offset, item in enumerate(list(included)):
                    element.insert(k + offset, item)
            else:
                self._expand_includes(child, folder, depth)

    def _read_defaults(self, element: ElementTree.Element, inherited: dict, name: str) -> None:
        own = {tag: dict(attrs) for tag, attrs in inherited.items()}
        for child in element:
            if child.tag == "default":
                continue
            tag = "actuator" if child.tag in ACTUATORS else child.tag
            own.setdefault(tag, {}).update(child.attrib)
        self.defaults[name] = own
        for child in element.findall("default"):
            self._read_defaults(child, own, child.get("class", name))

    def attributes(self, element: ElementTree.Element, tag: str, childclass: str) -> dict[str, str]:
        """The element's attributes over its class's defaults."""
        cls = element.get("class", childclass)
        if cls not in self.defaults and cls != "main":
            raise self.fail(f"<{element.tag}> names class {cls!r}, which no <default> defines")
        out = dict(self.defaults.get(cls, {}).get(tag, {}))
        out.update(element.attrib)
        return out

    def angle(self, value: float) -> float:
        return math.radians(value) if self.degrees else value

    def rotation(self, attrs: dict[str, str], what: str) -> np.ndarray:
        """The rotation of an element's orientation attributes (identity without one)."""
        try:
            if "quat" in attrs:
                return _quat_matrix(_floats(attrs["quat"], f"{what} quat", 4))  # type: ignore[arg-type]
            if "axisangle" in attrs:
                x, y, z, a = _floats(attrs["axisangle"], f"{what} axisangle", 4)  # type: ignore[misc]
                return _axis_angle(np.array([x, y, z]), self.angle(a))
            if "euler" in attrs:
                angles = [self.angle(v) for v in _floats(attrs["euler"], f"{what} euler", 3)]  # type: ignore[union-attr]
                R = np.eye(3)
                for axis, angle in zip(self.eulerseq, angles):
                    unit = np.eye(3)["xyz".index(axis.lower())]
                    turn = _axis_angle(unit, angle)
                    R = R @ turn if axis.islower() else turn @ R  # lower case: moving axes
                return R
            if "xyaxes" in attrs:
                v = np.array(_floats(attrs["xyaxes"], f"{what} xyaxes", 6))
                x = v[:3] / np.linalg.norm(v[:3])
                y = v[3:] - (v[3:] @ x) * x
                y /= np.linalg.norm(y)
                return np.column_stack([x, y, np.cross(x, y)])
            if "zaxis" in attrs:
                z = np.array(_floats(attrs["zaxis"], f"{what} zaxis", 3))
                z /= np.linalg.norm(z)
                axis = np.cross([0.0, 0.0, 1.0], z)
                if np.linalg.norm(axis) < 1e-12:
                    return np.eye(3) if z[2] > 0 else np.diag([1.0, -1.0, -1.0])
                return _axis_angle(axis, math.acos(max(-1.0, min(1.0, float(z[2])))))
        except MjcfError as exc:
            raise self.fail(exc.reason) from None
        except (ValueError, ZeroDivisionError) as exc:
            raise self.fail(f"{what}: {exc}") from None
        return np.eye(3)

    def origin(self, attrs: dict[str, str], what: str, shift: np.ndarray | None = None) -> Origin:
        """An element's placement in its body's frame (moved by ``shift``, the link frame's offset)."""
        try:
            pos = np.array(_floats(attrs.get("pos"), f"{what} pos", 3) or (0.0, 0.0, 0.0))
        except MjcfError as exc:
            raise self.fail(exc.reason) from None
        if shift is not None:
            pos = pos - shift
        return Origin(xyz=tuple(float(v) for v in pos), rpy=_rpy(self.rotation(attrs, what)))  # type: ignore[arg-type]


def _write_inertial(body, inertial: Inertial, shift: np.ndarray | None) -> None:
    """Give ``body`` the ``<inertial>`` (its frame's axes, ``fullinertia``) mobmanip computed."""
    xyz = np.asarray(inertial.origin.xyz, dtype=float) + (shift if shift is not None else 0.0)
    I = np.asarray(inertial.inertia, dtype=float)
    full = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
    ElementTree.SubElement(body, "inertial", {
        "pos": " ".join(repr(float(v)) for v in xyz),
        "mass": repr(float(inertial.mass)),
        "fullinertia": " ".join(repr(float(v)) for v in full),
    })  # fmt: skip


def _geom_mass_properties(kind: str, size: list[float], attrs: dict[str, str]) -> tuple[float, np.ndarray] | None:
    """Mass and rotational inertia (3, 3) about the geom's centre in its frame, for primitives."""
    volume: float
    if kind == "sphere":
        r = size[0]
        volume, shape = 4 / 3 * math.pi * r**3, np.full(3, 2 / 5 * r * r)
    elif kind == "box":
        a, b, c = (2 * s for s in size[:3])
        volume, shape = a * b * c, np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 12
    elif kind == "cylinder":
        r, h = size[0], 2 * size[1]
        volume, shape = math.pi * r * r * h, np.array([(3 * r * r + h * h) / 12, (3 * r * r + h * h) / 12, r * r / 2])
    elif kind == "capsule":
        r, h = size[0], 2 * size[1]
        volume = math.pi * r * r * (h + 4 / 3 * r)
        shape = np.array([(3 * r * r + h * h) / 12, (3 * r * r + h * h) / 12, r * r / 2])  # as a cylinder
    elif kind == "ellipsoid":
        a, b, c = size[:3]
        volume, shape = 4 / 3 * math.pi * a * b * c, np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 5
    else:
        return None
    mass = _float(attrs["mass"]) if "mass" in attrs else _float(attrs.get("density", _DENSITY)) * volume
    return mass, np.diag(mass * shape)


def _shell_mass_properties(mesh, attrs: dict[str, str]) -> tuple[float, np.ndarray, np.ndarray] | None:
    """A mesh's mass, centre and inertia about it (mesh frame) with the mass spread evenly over
    its surface (MuJoCo's ``inertia="shell"``): ``mass``, or the density (per m^2 here) times
    the area; the centre is the area-weighted mean of the triangles' centroids, and each
    triangle (vertices a, b, c, area A) adds its exact second moment
    ``A / 12 (a a^T + b b^T + c c^T + s s^T)``, s = a + b + c. ``None`` for a mesh of no area."""
    triangles = np.asarray(mesh.triangles, dtype=float)
    areas = np.asarray(mesh.area_faces, dtype=float)
    area = float(areas.sum())
    if area <= 0.0:
        return None
    mass = _float(attrs["mass"]) if "mass" in attrs else _float(attrs.get("density", _DENSITY)) * area
    if mass == 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    if mass < 0.0:
        return None
    centre = (areas[:, None] * triangles.mean(axis=1)).sum(axis=0) / area
    sums = triangles.sum(axis=1)
    second = np.einsum("t,tki,tkj->ij", areas, triangles, triangles) + np.einsum("t,ti,tj->ij", areas, sums, sums)
    second = second / 12.0 / area - np.outer(centre, centre)  # per unit mass, about the centre
    return mass, centre, mass * (np.trace(second) * np.eye(3) - second)


class _Tree:
    """The body tree walked into links and joints, and the text handed to Pinocchio."""

    def __init__(self, reader: _Reader) -> None:
        self.r = reader
        self.links: list[LinkDescription] = []
        self.joints: list[JointDescription] = []
        self.limits: dict[str, dict[str, float]] = {}
        #: Bodies without <inertial> whose mesh geoms' mass could not be integrated (their files missing).
        self.mesh_notes: list[str] = []
        self.counter = 0
        #: Links whose inertia is their geoms' (no <inertial>): not judged for plausibility.
        self.from_geometry: list[str] = []
        #: The file's body names (a site of the same name is renamed: see :meth:`walk`).
        self.body_names = {body.get("name") for body in reader.root.iter("body") if body.get("name")}
        self.planar_base: tuple[JointDescription, ...] = ()
        #: Armature (kg or kg m^2) of the file's planar base joints, by role (x, y, yaw).
        self.base_armature: dict[str, float] = {}
        #: Bodies above a nested planar base's yaw joint, lumped into the platform: (name, mass
        #: kg, slides along x, slides along y), for the notes.
        self.lumped: list[tuple[str, float, bool, bool]] = []
        #: The joints an actuator of the file drives (its ``joint`` attribute).
        self.actuated: set[str] = set()

    def name(self, element: ElementTree.Element, prefix: str) -> str:
        name = element.get("name")
        if not name:
            self.counter += 1
            name = f"{prefix}{self.counter}"
            element.set("name", name)  # Pinocchio's model then uses the same name
        return name

    def walk(self, body: ElementTree.Element, parent: str | None, childclass: str, root: bool) -> None:
        r = self.r
        name = self.name(body, "body")
        childclass = body.get("childclass", childclass)
        where = f"body {name!r}"
        joints = [j for j in body if j.tag in ("joint", "freejoint")]
        if root:
            free = [
                j for j in joints if j.tag == "freejoint" or r.attributes(j, "joint", childclass).get("type") == "free"
            ]
            for j in free:
                body.remove(j)
                self.r.notes.append(
                    f"the free joint of the root body {name!r} is dropped (mobmanip adds the platform's)"
                )
            joints = [j for j in joints if j not in free]
        body_origin = r.origin(dict(body.attrib), where)
        described = []
        for j in joints:
            attrs = r.attributes(j, "joint", childclass)
            kind = "free" if j.tag == "freejoint" else attrs.get("type", "hinge")
            jname = self.name(j, f"{name}_joint")
            if kind in ("free", "ball"):
                raise r.fail(
                    f"joint {jname!r} of {where} is a {kind} joint; mobmanip models one-degree-of-freedom joints only"
                )
            if kind not in ("hinge", "slide"):
                raise r.fail(f"joint {jname!r} has an unknown type {kind!r}")
            described.append((j, jname, kind, attrs))
        anchors = {tuple(_floats(a.get("pos"), "joint pos", 3) or (0.0, 0.0, 0.0)) for _, _, _, a in described}
        if len(anchors) > 1:
            raise r.fail(f"{where} has several joints with different anchors (pos); mobmanip reads one anchor per body")
        shift = np.array(anchors.pop()) if anchors else np.zeros(3)
        if root and self.nested_base(body, name, described, childclass):
            described = []
        if root and described:
            self.planar_base = self.base_joints(name, described)
            for element, _, _, _ in described:
                body.remove(element)
            described = []
        if root:
            moved = any(key in body.attrib for key in ("pos", "quat", "axisangle", "euler", "xyaxes", "zaxis"))
            for key in ("pos", "quat", "axisangle", "euler", "xyaxes", "zaxis"):
                body.attrib.pop(key, None)
            if moved:
                r.notes.append(
                    f"the root body {name!r}'s placement in the world is dropped (the platform pose is mobmanip's)"
                )
        # a chain: one link per joint, the body's own link last
        previous, origin = parent, body_origin
        if described and np.any(shift):
            R = body_origin.rotation
            origin = Origin(xyz=tuple(float(v) for v in np.asarray(body_origin.xyz) + R @ shift), rpy=body_origin.rpy)  # type: ignore[arg-type]
        for k, (_, jname, kind, attrs) in enumerate(described):
            link_name = name if k == len(described) - 1 else f"{name}__{jname}"
            if k < len(described) - 1:
                self.links.append(LinkDescription(link_name))
            self.joints.append(self.joint(jname, kind, attrs, previous, link_name, origin))
            previous, origin = link_name, Origin()
        if not described and parent is not None:
            self.joints.append(JointDescription(f"{name}_fixed", "fixed", parent, name, body_origin))
        self.links.append(self.link(body, name, childclass, shift if described else None))
        for site in body.findall("site"):
            sname = self.name(site, f"{name}_site")
            if sname in self.body_names:  # MuJoCo names bodies and sites apart; a link name is one of both
                renamed = f"{sname}_site"
                r.notes.append(f"site {sname!r} shares its name with a body: its frame is called {renamed!r}")
                sname = renamed
                site.set("name", sname)  # Pinocchio's model then uses the same name
            attrs = r.attributes(site, "site", childclass)
            self.links.append(LinkDescription(sname))
            self.joints.append(
                JointDescription(
                    f"{sname}_site",
                    "fixed",
                    name,
                    sname,
                    r.origin(attrs, f"site {sname!r}", shift if described else None),
                )
            )
        for child in body.findall("body"):
            self.walk(child, name, childclass, root=False)
        if len(described) > 1:
            self.split(body, described)

    def base_joints(self, body: str, described) -> tuple[JointDescription, ...]:
        """The root body's own joints as a planar base: a slide along x, a slide along y and a
        hinge about z (any order, anchors at the body's origin), returned as (x, y, yaw).

        Raises:
            MjcfError: the root has other joints (mobmanip moves the root with the platform).
        """
        found: dict[str, JointDescription] = {}
        for _, jname, kind, attrs in described:
            axis = np.array(_floats(attrs.get("axis"), f"joint {jname!r} axis", 3) or (0.0, 0.0, 1.0))
            axis = axis / np.linalg.norm(axis)
            anchor = _floats(attrs.get("pos"), f"joint {jname!r} pos", 3) or (0.0, 0.0, 0.0)
            role = None
            if kind == "slide" and abs(abs(axis[0]) - 1.0) < 1e-9:
                role = "x"
            elif kind == "slide" and abs(abs(axis[1]) - 1.0) < 1e-9:
                role = "y"
            elif kind == "hinge" and abs(abs(axis[2]) - 1.0) < 1e-9 and not any(anchor):
                role = "yaw"
            if role is None or role in found:
                listed = ", ".join(f"{j} ({k})" for _, j, k, _ in described)
                raise self.r.fail(
                    f"the root body {body!r} has joints {listed}: mobmanip moves the root with the platform's own "
                    "joint, and reads a root's joints only as a planar base (a slide along x, a slide along y and a "
                    "hinge about z)"
                )
            found[role] = self.joint(jname, kind, attrs, body, body, Origin())
            self.base_armature[role] = _float(attrs.get("armature", 0.0))
        if set(found) != {"x", "y", "yaw"}:
            raise self.r.fail(
                f"the root body {body!r} has joints {', '.join(j.name for j in found.values())}: a planar base "
                "needs a slide along x, a slide along y and a hinge about z"
            )
        self.r.notes.append(
            f"the root body {body!r} moves on planar joints {found['x'].name}, {found['y'].name}, "
            f"{found['yaw'].name}: an omnidirectional platform replaces them (their limits are the base's)"
        )
        return found["x"], found["y"], found["yaw"]

    @staticmethod
    def role(kind: str, attrs: dict[str, str], name: str) -> str | None:
        """``"x"``, ``"y"`` or ``"yaw"`` for a slide along x, a slide along y or a hinge about z
        (axes in the body's frame, either sign), else ``None``."""
        axis = np.array(_floats(attrs.get("axis"), f"joint {name!r} axis", 3) or (0.0, 0.0, 1.0))
        norm = float(np.linalg.norm(axis))
        if norm == 0.0:
            return None
        axis = axis / norm
        if kind == "slide" and abs(abs(axis[0]) - 1.0) < 1e-9:
            return "x"
        if kind == "slide" and abs(abs(axis[1]) - 1.0) < 1e-9:
            return "y"
        if kind == "hinge" and abs(abs(axis[2]) - 1.0) < 1e-9:
            return "yaw"
        return None

    def nested_base(self, root: ElementTree.Element, root_name: str, described, childclass: str) -> bool:
        """Recognise a planar base whose joints sit on nested bodies below the root (MuJoCo
        Menagerie's mobile FR3 Duo: a slide along x on ``virtual_x``, a slide along y on its child
        ``virtual_y``, a hinge about z on the body below), and take it out of the tree.

        The pattern: from the root down, each body with exactly one child body and no rotation
        (below the root), the joints met are a slide along x and a slide along y (either order),
        then a hinge about z, and no other joint; the chain spans more than the root (the root's
        own joints are :meth:`base_joints`'s). Then, as stated in the notes:

        - the three joints leave the tree and become :attr:`planar_base` (an omnidirectional
          platform with their limits; their armature is the platform's);
        - mobmanip's platform turns about its root link's origin: when the hinge's axis passes
          elsewhere (``(cx, cy)`` in the root's frame), the body below the root is moved by
          ``(-cx, -cy)``, which only renames the platform's position (x = x_file + cx);
        - the bodies above the hinge slide but do not turn in MuJoCo (the root does not even
          slide when it has none of the joints): each is lumped into the platform as a point
          of its mass on the yaw axis at its centre of mass's height, its rotational inertia
          dropped (MuJoCo never turns it). For a body that slides along x and y this is exact;
          one that slides along one of them (or neither) is counted along both here.

        Returns:
            Whether the pattern was found (and the tree rewritten).
        """
        r = self.r
        chain = [(root, root_name, childclass, list(described))]
        roles: dict[str, tuple] = {}
        body, cls = root, childclass
        while True:
            for element, jname, kind, attrs in chain[-1][3]:
                role = self.role(kind, attrs, jname)
                if role is None or role in roles or "yaw" in roles or (role == "yaw" and len(roles) < 2):
                    return False
                roles[role] = (element, jname, kind, attrs, len(chain) - 1)
            if len(roles) == 3:
                break
            children = body.findall("body")
            if len(children) != 1:
                return False
            body = children[0]
            cls = body.get("childclass", cls)
            bname = self.name(body, "body")
            if not np.allclose(r.rotation(dict(body.attrib), f"body {bname!r}"), np.eye(3), rtol=0, atol=1e-12):
                return False
            own: list = []
            for element in body:
                if element.tag == "freejoint":
                    return False
                if element.tag == "joint":
                    attrs = r.attributes(element, "joint", cls)
                    own.append((element, self.name(element, f"{bname}_joint"), attrs.get("type", "hinge"), attrs))
            chain.append((body, bname, cls, own))
        if len(chain) == 1:
            return False  # the root's own joints: base_joints reads them
        # the yaw axis in the root's frame: the bodies' offsets below the root and the hinge's anchor
        yaw_element, yaw_name, _, yaw_attrs, _ = roles["yaw"]
        anchor = np.array(_floats(yaw_attrs.get("pos"), f"joint {yaw_name!r} pos", 3) or (0.0, 0.0, 0.0))
        offsets = [np.array(_floats(b.get("pos"), f"body {n!r} pos", 3) or (0.0, 0.0, 0.0)) for b, n, _, _ in chain]
        offsets[0] = np.zeros(3)  # the root's placement is mobmanip's platform pose
        axis = sum(offsets[1:], np.zeros(3)) + anchor
        axis[2] = 0.0
        if np.any(axis):
            first = chain[1][0]
            first.set("pos", " ".join(repr(float(v)) for v in offsets[1] - axis))
            offsets[1] = offsets[1] - axis
            r.notes.append(
                f"the planar base's hinge {yaw_name!r} turns about ({axis[0]:.6g}, {axis[1]:.6g}) m in the root "
                f"body {root_name!r}: mobmanip's platform turns about its root's origin, so body {chain[1][1]!r} is "
                "moved by the opposite (the platform's x and y are the file's plus that offset)"
            )
        joints = {}
        for role, (element, jname, kind, attrs, k) in roles.items():
            holder = chain[k][0]
            holder.remove(element)
            joints[role] = self.joint(jname, kind, attrs, chain[k][1], chain[k][1], Origin())
            self.base_armature[role] = _float(attrs.get("armature", 0.0))
        self.planar_base = (joints["x"], joints["y"], joints["yaw"])
        # the bodies above the hinge: point masses on the yaw axis
        where = np.zeros(3)
        for k, (holder, bname, cls, _) in enumerate(chain[:-1]):
            where = where + offsets[k]
            inertial = self.link(holder, bname, cls, None).inertial
            for old in holder.findall("inertial"):
                holder.remove(old)
            if inertial is None or inertial.mass <= 0.0:
                continue
            point = ElementTree.Element(
                "inertial",
                {
                    "pos": f"{-float(where[0])!r} {-float(where[1])!r} {float(inertial.origin.xyz[2])!r}",
                    "mass": repr(float(inertial.mass)),
                    "diaginertia": "0 0 0",
                },
            )
            holder.insert(0, point)
            slides_x, slides_y = roles["x"][4] <= k, roles["y"][4] <= k
            self.lumped.append((bname, float(inertial.mass), slides_x, slides_y))
        names = ", ".join(joints[role].name for role in ("x", "y", "yaw"))
        r.notes.append(
            f"planar joints {names} on nested bodies below the root body {root_name!r} "
            f"({', '.join(n for _, n, _, _ in chain[1:])}) move the robot in the plane: an omnidirectional "
            "platform replaces them (their limits and armature are the base's)"
        )
        if self.lumped:
            parts = []
            for bname, mass, sx, sy in self.lumped:
                moves = {(True, True): "slides along x and y", (False, False): "does not move"}.get(
                    (sx, sy), f"slides along {'x' if sx else 'y'} only"
                )
                parts.append(f"{bname} ({mass:.6g} kg, {moves} in MuJoCo)")
            r.notes.append(
                "bodies above the planar base's yaw joint do not turn in MuJoCo: "
                + "; ".join(parts)
                + "; each is lumped into the platform as a point mass on its yaw axis (its rotational inertia "
                "dropped), counted along x and y"
            )
        return True

    def split(self, body: ElementTree.Element, described) -> None:
        """Rewrite a body with several joints as nested bodies, one joint each (Pinocchio would
        make one composite joint of them)."""
        name = body.get("name")
        outer_attrs = {
            k: v for k, v in body.attrib.items() if k in ("pos", "quat", "axisangle", "euler", "xyaxes", "zaxis")
        }
        for key in outer_attrs:
            del body.attrib[key]
        parent = self.parent_of(body)
        index = list(parent).index(body)
        parent.remove(body)
        container = parent
        for k, (j, jname, _, _) in enumerate(described[:-1]):
            virtual = ElementTree.Element("body", {"name": f"{name}__{jname}", **(outer_attrs if k == 0 else {})})
            if "childclass" in body.attrib:
                virtual.set("childclass", body.get("childclass", ""))
            body.remove(j)
            virtual.append(j)
            container.insert(index if container is parent else 0, virtual)
            container = virtual
        container.append(body)

    def parent_of(self, element: ElementTree.Element) -> ElementTree.Element:
        for candidate in self.r.root.iter():
            if element in list(candidate):
                return candidate
        raise self.r.fail("a body without a parent")  # pragma: no cover

    def joint(self, name, kind, attrs, parent, child, origin) -> JointDescription:
        r = self.r
        axis = tuple(_floats(attrs.get("axis"), f"joint {name!r} axis", 3) or (0.0, 0.0, 1.0))
        range_ = _floats(attrs.get("range"), f"joint {name!r} range", 2)
        limited = attrs.get("limited", "auto")
        bounded = range_ is not None and (limited == "true" or (limited == "auto" and r.autolimits))
        lower = upper = None
        if bounded and range_ is not None:
            lower, upper = (r.angle(v) if kind == "hinge" else v for v in range_)
        effort = None
        force = _floats(attrs.get("actuatorfrcrange"), f"joint {name!r} actuatorfrcrange", 2)
        flimited = attrs.get("actuatorfrclimited", "auto")
        if force is not None and (flimited == "true" or (flimited == "auto" and r.autolimits)):
            effort = max(abs(force[0]), abs(force[1]))
        from_actuators = self.limits.get(name, {})
        if effort is None:
            effort = from_actuators.get("effort")
        urdf_type = "prismatic" if kind == "slide" else ("revolute" if bounded else "continuous")
        limits = JointLimits(lower, upper, from_actuators.get("velocity"), effort)
        damping = _float(attrs["damping"]) if "damping" in attrs else None
        friction = _float(attrs["frictionloss"]) if "frictionloss" in attrs else None
        return JointDescription(name, urdf_type, parent, child, origin, axis, limits, None, damping, friction)  # type: ignore[arg-type]

    def link(self, body, name: str, childclass: str, shift: np.ndarray | None) -> LinkDescription:
        r = self.r
        inertial = None
        element = body.find("inertial")
        collisions, visuals = [], []
        geom_masses = []
        for geom in body.findall("geom"):
            attrs = r.attributes(geom, "geom", childclass)
            shape = self.shape(geom, attrs, name, shift)
            if shape is None:
                continue
            visuals.append(shape)
            if attrs.get("contype", "1") != "0" or attrs.get("conaffinity", "1") != "0":
                collisions.append(shape)
            geom_masses.append((shape, attrs))
        if element is not None:
            attrs = dict(element.attrib)
            mass = _float(attrs.get("mass", 0.0))
            where = f"link {name!r} <inertial>"
            if "fullinertia" in attrs:
                xx, yy, zz, xy, xz, yz = _floats(attrs["fullinertia"], f"{where} fullinertia", 6)  # type: ignore[misc]
                tensor = ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))
            else:
                d = _floats(attrs.get("diaginertia"), f"{where} diaginertia", 3) or (0.0, 0.0, 0.0)
                tensor = ((d[0], 0.0, 0.0), (0.0, d[1], 0.0), (0.0, 0.0, d[2]))
            inertial = Inertial(mass, r.origin(attrs, where, shift), tensor)
        elif geom_masses:
            inertial, meshed = self.geom_inertial(name, geom_masses)
            self.from_geometry.append(name)
            visual_mass = any(
                a.get("contype", "1") == "0" and a.get("conaffinity", "1") == "0" and _float(a.get("mass", 1.0)) > 0
                for _, a in geom_masses
            )
            # Pinocchio builds from the file: it reads this one. It integrates no mesh, and leaves out
            # a geom that collides with nothing (contype = conaffinity = 0), which MuJoCo weighs
            # (Stretch's gripper slider is such a 50 g box).
            if (meshed or visual_mass) and inertial is not None:
                _write_inertial(body, inertial, shift)
        return LinkDescription(name, inertial, tuple(collisions), tuple(visuals))

    def geom_inertial(self, name: str, geoms) -> tuple[Inertial | None, bool]:
        """The bodies' geoms' mass properties, as one inertial about their centre of mass, and
        whether a mesh's mass is in it."""
        parts = []
        meshed = False
        for shape, attrs in geoms:
            kind = attrs.get("type", "sphere")
            if shape.kind == "box":
                size = [v / 2 for v in shape.size]
            elif shape.kind == "cylinder":
                size = [shape.radius, shape.length / 2]
            else:
                size = [shape.radius or 0.0] * 3
            if kind == "ellipsoid":
                size = [_float(v) for v in (attrs.get("size") or "0 0 0").split()][:3]
            R = shape.origin.rotation
            if kind == "mesh":
                found = self.mesh_mass_properties(name, shape, attrs)
                if found is not None:
                    mass, centre, inertia = found
                    if mass > 0.0:
                        parts.append((mass, np.asarray(shape.origin.xyz) + R @ centre, R @ inertia @ R.T))
                        meshed = True
                    continue
            props = _geom_mass_properties(kind, size, attrs) if kind != "mesh" else None
            if props is None:
                mass = _float(attrs.get("mass", 0.0))
                if kind == "mesh":
                    self.mesh_notes.append(name)
                props = (mass, np.zeros((3, 3)))
            if props[0] > 0.0:
                parts.append((props[0], np.asarray(shape.origin.xyz), R @ props[1] @ R.T))
        total = sum(m for m, _, _ in parts)
        if total <= 0.0:
            return None, False
        com = sum(m * p for m, p, _ in parts) / total
        tensor = np.zeros((3, 3))
        for m, p, inertia in parts:
            d = p - com
            tensor += inertia + m * (float(d @ d) * np.eye(3) - np.outer(d, d))
        x, y, z = (float(v) for v in np.asarray(com))
        rows = tuple((float(row[0]), float(row[1]), float(row[2])) for row in tensor)
        return Inertial(total, Origin(xyz=(x, y, z)), (rows[0], rows[1], rows[2])), meshed

    def mesh_mass_properties(self, body: str, shape: Shape, attrs) -> tuple[float, np.ndarray, np.ndarray] | None:
        """A mesh geom's mass, centre of mass and inertia about it (geom frame) as MuJoCo computes
        them: the closed mesh's volume at the geom's density (1000 kg/m^3 unless set) or its
        ``mass``, integrated exactly (trimesh); ``None`` when the file is missing or not closed.

        MuJoCo's own default for a mesh (``inertia="legacy"``) over-counts a non-convex mesh's
        volume; the exact integral is used and a note says so (``inertia="exact"`` in the
        ``<mesh>`` makes MuJoCo agree). ``"convex"`` integrates the convex hull; ``"shell"`` spreads
        the mass over the surface (density per m^2 times the area, or ``mass``), integrated exactly
        over each triangle (:func:`_shell_mass_properties`), as MuJoCo does. A geom of zero mass
        (``mass="0"``, as a class may give every visual geom) gives ``(0, 0, 0)``: nothing to add.
        """
        mesh_name = attrs.get("mesh")
        mode = self.r.mesh_inertia.get(mesh_name, "legacy")
        try:
            import trimesh

            loaded = trimesh.load(shape.filename, force="mesh", process=True)
        except Exception:  # a missing or unreadable file: the notes name the body
            return None
        if not isinstance(loaded, trimesh.Trimesh):
            return None
        mesh = loaded
        if shape.scale is not None:
            mesh.apply_scale(shape.scale)
        if mode == "shell":
            return _shell_mass_properties(mesh, attrs)
        if not mesh.is_volume:
            return None
        if mode == "convex":
            mesh = mesh.convex_hull
        elif mode == "legacy" and not mesh.is_convex:
            self.r.notes.append(
                f"mesh {mesh_name!r} of body {body!r} is not convex: its mass is integrated exactly "
                f'({mesh.volume:.6g} m^3), where MuJoCo\'s default (inertia="legacy") over-counts its volume; '
                'inertia="exact" in its <mesh> makes MuJoCo agree'
            )
        volume = float(mesh.volume)
        mass = _float(attrs["mass"]) if "mass" in attrs else _float(attrs.get("density", _DENSITY)) * volume
        if mass == 0.0:
            return 0.0, np.zeros(3), np.zeros((3, 3))
        if mass < 0.0 or volume <= 0.0:
            return None
        # trimesh's moment of inertia is about the centre of mass at unit density
        inertia = np.asarray(mesh.moment_inertia, dtype=float) * (mass / volume) / float(mesh.density)
        return mass, np.asarray(mesh.center_mass, dtype=float), inertia

    def shape(self, geom, attrs, body: str, shift) -> Shape | None:
        r = self.r
        kind = attrs.get("type", "sphere")
        where = f"a geom of body {body!r}"
        # the geom's name, else its class's: what it is (Stretch's caster is a geom of class "caster")
        label = geom.get("name") or geom.get("class")
        size = _floats(attrs.get("size") or "0 0 0", f"{where} size") or []
        along = "fromto" in attrs and kind in ("capsule", "cylinder", "box", "ellipsoid")
        needed = 1 if along else {"sphere": 1, "cylinder": 2, "capsule": 2, "box": 3, "ellipsoid": 3}.get(kind, 0)
        if len(size) < needed:
            article = "an" if kind[0] in "aeiou" else "a"
            raise r.fail(f"{where}: {article} {kind} needs {needed} size numbers, got size={attrs.get('size')!r}")
        if along:
            a, b = np.split(np.array(_floats(attrs["fromto"], f"{where} fromto", 6)), 2)
            axis = b - a
            length = float(np.linalg.norm(axis))
            z = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
            rot = np.cross([0.0, 0.0, 1.0], z)
            R = (
                _axis_angle(rot, math.acos(max(-1.0, min(1.0, float(z[2])))))
                if np.linalg.norm(rot) > 1e-12
                else np.eye(3)
            )
            center = (a + b) / 2 - (shift if shift is not None else 0.0)
            origin = Origin(xyz=tuple(float(v) for v in center), rpy=_rpy(R))  # type: ignore[arg-type]
            size = [size[0], length / 2, size[0]]
        else:
            origin = r.origin(attrs, where, shift)
        if kind == "sphere":
            return Shape("sphere", origin, radius=size[0], name=label)
        if kind in ("cylinder", "capsule"):
            return Shape("cylinder", origin, radius=size[0], length=2 * size[1], name=label)
        if kind == "box":
            return Shape("box", origin, size=(2 * size[0], 2 * size[1], 2 * size[2]), name=label)
        if kind == "ellipsoid":
            return Shape("sphere", origin, radius=max(size[:3]), name=label)
        if kind == "mesh":
            mesh = attrs.get("mesh")
            if mesh not in r.meshes:
                raise r.fail(f"{where} uses mesh {mesh!r}, which no <asset> <mesh> defines")
            file, scale = r.meshes[mesh]
            return Shape("mesh", origin, filename=str(file), scale=scale, name=label)
        return None  # planes, height fields: not the robot's

    def actuators(self) -> None:
        """Velocity and effort limits from the actuators that drive a joint directly."""
        r = self.r
        through = 0
        for section in r.root.iter("actuator"):
            for actuator in section:
                if actuator.tag not in ACTUATORS:
                    continue
                attrs = r.attributes(actuator, "actuator", "main")
                joint = attrs.get("joint")
                if joint is None:
                    through += 1
                    continue
                self.actuated.add(joint)
                gear = abs((_floats(attrs.get("gear"), f"actuator on {joint!r} gear") or [1.0])[0]) or 1.0
                entry = self.limits.setdefault(joint, {})
                force = _floats(attrs.get("forcerange"), f"actuator on {joint!r} forcerange", 2)
                ctrl = _floats(attrs.get("ctrlrange"), f"actuator on {joint!r} ctrlrange", 2)
                forced = attrs.get("forcelimited", "auto")
                if force is not None and (forced == "true" or (forced == "auto" and r.autolimits)):
                    entry["effort"] = max(entry.get("effort", 0.0), gear * max(abs(force[0]), abs(force[1])))
                elif actuator.tag == "motor" and ctrl is not None:
                    entry["effort"] = max(entry.get("effort", 0.0), gear * max(abs(ctrl[0]), abs(ctrl[1])))
                if actuator.tag == "velocity" and ctrl is not None:
                    entry["velocity"] = max(entry.get("velocity", 0.0), max(abs(ctrl[0]), abs(ctrl[1])) / gear)
        if through:
            r.notes.append(
                f"not read: {through} actuator(s) acting through tendons or sites (no joint limit from them)"
            )


def _qpos_layout(
    reader: _Reader, body: ElementTree.Element, childclass: str
) -> list[tuple[ElementTree.Element, int, float]]:
    """The file's joints in MuJoCo's ``qpos`` order, each with its number of positions and, for
    a hinge or a slide, its ``qpos0`` (its ``ref``: rad or m; 0 for the others).

    MuJoCo lays ``qpos`` out body by body, depth first in file order, a body's joints in file
    order: 7 numbers for a free joint, 4 for a ball joint, 1 for a hinge or a slide. Read before
    mobmanip rewrites the tree (it drops the root's free joint and a planar base's joints).
    """
    childclass = body.get("childclass", childclass)
    out: list[tuple[ElementTree.Element, int, float]] = []
    for element in body:
        if element.tag == "freejoint":
            out.append((element, 7, 0.0))
        elif element.tag == "joint":
            attrs = reader.attributes(element, "joint", childclass)
            kind = attrs.get("type", "hinge")
            ref = _float(attrs.get("ref", 0.0))
            out.append((element, {"free": 7, "ball": 4}.get(kind, 1), reader.angle(ref) if kind == "hinge" else ref))
    for child in body.findall("body"):
        out += _qpos_layout(reader, child, childclass)
    return out


def _keyframes(reader: _Reader, layout: list[tuple[ElementTree.Element, int, float]]) -> dict[str, dict[str, float]]:
    """The file's ``<key>`` elements as postures: name -> (joint -> position, rad or m).

    ``qpos`` is MuJoCo's raw joint positions (radians whatever the compiler's ``angle``), which
    are Pinocchio's for a hinge or a slide (its MJCF builder turns a joint's ``ref`` into the
    joint's placement, as MuJoCo does). The rules, each stated in the notes:

    - a key with fewer positions than the file's ``nq``: the others are MuJoCo's ``qpos0`` (a
      joint's ``ref``), as MuJoCo fills them;
    - a key with more positions than ``nq`` (MuJoCo refuses such a file), or one that is not
      numeric or not finite: left out;
    - a key without ``qpos`` (only controls, say): not a posture, left out;
    - an unnamed key is called ``keyframe<K>`` (K its index from 0); a name given twice keeps its
      first key.

    Args:
        reader: the file.
        layout: ``(joint element, positions, qpos0)`` in ``qpos`` order (see :func:`_qpos_layout`);
            the elements carry the names the walk gave them.
    """
    nq = sum(size for _, size, _ in layout)
    keys = [key for section in reader.root.iter("keyframe") for key in section if key.tag == "key"]
    out: dict[str, dict[str, float]] = {}
    for k, key in enumerate(keys):
        name = key.get("name") or f"keyframe{k}"
        text = key.get("qpos")
        if text is None:
            reader.notes.append(f"keyframe {name!r} gives no qpos: not a posture, left out")
            continue
        try:
            qpos = [_float(v) for v in text.split()]
        except ValueError:
            qpos = [math.nan]
        if not all(math.isfinite(v) for v in qpos):
            reader.notes.append(f"keyframe {name!r} has a qpos that is not finite numbers ({text[:40]!r}): left out")
            continue
        if len(qpos) > nq:
            reader.notes.append(
                f"keyframe {name!r} gives {len(qpos)} positions but the file's joints have {nq} (MuJoCo refuses "
                "it): left out"
            )
            continue
        if name in out:
            reader.notes.append(f"keyframe name {name!r} is given twice: the first one is kept")
            continue
        if len(qpos) < nq:
            reader.notes.append(
                f"keyframe {name!r} gives {len(qpos)} of the file's {nq} positions: the others are their joints' "
                "qpos0 (ref), as MuJoCo fills them"
            )
        values, offset = {}, 0
        for element, size, qpos0 in layout:
            if size == 1 and element.get("name"):
                values[element.get("name", "")] = qpos[offset] if offset < len(qpos) else qpos0
            offset += size
        out[name] = values
    if out:
        reader.notes.append(
            f"keyframes read as named postures: {', '.join(out)} (init-spec offers their arm and torso joints as "
            "[postures.NAME])"
        )
    return out


def missing_limit_reason(kind: str) -> str:
    """Why an MJCF joint has no ``kind`` (``"velocity"`` or ``"effort"``) limit, and where the
    file would give one, for a message."""
    if kind == "velocity":
        return (
            "the MJCF file gives the joint none (MJCF has no velocity limit; a velocity actuator's ctrlrange gives one)"
        )
    return "the MJCF file gives the joint none (no actuatorfrcrange, and no actuator on it with a forcerange)"


def _platform_armature(reader: _Reader, armature: dict[str, float]) -> tuple[float, float, float] | None:
    """The platform joint's armature from the file's planar base joints' (x, y: kg; yaw: kg m^2).

    MuJoCo adds a slide's armature along its own axis, fixed in the world; mobmanip's platform
    velocities are along the platform's turning axes, where a constant armature is the same
    only when x's and y's are equal. When they differ both get their mean (the mass matrix is
    then off by half their difference along each axis), said in a note.
    """
    if set(armature) != {"x", "y", "yaw"}:
        return None
    ax, ay, yaw = armature["x"], armature["y"], armature["yaw"]
    if ax != ay:
        reader.notes.append(
            f"the planar base's armature differs along x ({ax:.6g} kg) and y ({ay:.6g} kg), which a platform "
            f"that turns cannot keep: both get their mean, {(ax + ay) / 2:.6g} kg"
        )
    mean = (ax + ay) / 2
    return (mean, mean, yaw)


def read_mjcf(path: str | Path, *, package_dirs: Iterable[str | Path] | None = None) -> RobotDescription:
    """Read an MJCF file into its checked description (see the module docstring).

    Args:
        path: the ``.xml`` / ``.mjcf`` file (an ``.xml`` file whose root is ``<robot>`` is read as
            a URDF).
        package_dirs: where mesh files resolve besides the compiler's ``meshdir`` (default: the
            file's folder).

    Raises:
        MjcfError: the file is missing, malformed, or uses what mobmanip cannot model (a ball
            joint, several robots under ``<worldbody>``), naming it.
        DescriptionError: the robot it describes is not physical (as for a URDF).
    """
    from ..support.files import note_input

    path = Path(path)
    data = read_bounded(path, limit=MAX_ROBOT_FILE_BYTES, refuse=lambda reason: MjcfError(str(path), reason))
    note_input(path)
    with contextlib.suppress(ElementTree.ParseError):
        if ElementTree.fromstring(data).tag == "robot":  # a URDF that calls itself .xml
            from .urdf import read_urdf

            return read_urdf(path, package_dirs=package_dirs)
    reader = _Reader(path, data)
    tree = _Tree(reader)
    world = reader.root.find("worldbody")
    bodies = [] if world is None else world.findall("body")
    if len(bodies) != 1:
        names = ", ".join(repr(b.get("name", "?")) for b in bodies) or "none"
        raise reader.fail(f"<worldbody> must hold one robot body (the root link); it holds {names}")
    try:
        layout = _qpos_layout(reader, bodies[0], "main")
        tree.actuators()
        tree.walk(bodies[0], None, "main", root=True)
        keyframes = _keyframes(reader, layout)
    except MjcfError as exc:
        raise exc if exc.path else reader.fail(exc.reason) from None
    except ValueError as exc:  # a number attribute that is not one
        raise reader.fail(str(exc)) from None
    if tree.mesh_notes:
        bodies = ", ".join(repr(name) for name in dict.fromkeys(tree.mesh_notes))
        reader.notes.append(
            f"mesh geom(s) of bodies without <inertial> whose files are missing or not closed: {bodies}; MuJoCo gives "
            "them the mass of their meshes' volume, mobmanip cannot integrate them (Pinocchio would give such a body "
            "1 kg and a unit tensor), so the dynamic measures are not the robot's: give them the mesh files or an "
            "<inertial>"
        )
    for parent in list(reader.root.iter()):  # keyframes are sized for the file's joints, not mobmanip's model
        for section in parent.findall("keyframe"):
            parent.remove(section)
    for element in reader.root.iter("compiler"):  # Pinocchio reads the copy from a temporary folder
        for key in ("meshdir", "assetdir", "texturedir"):
            element.attrib.pop(key, None)
    compiler = reader.root.find("compiler")
    if compiler is None:
        compiler = ElementTree.Element("compiler")
        reader.root.insert(0, compiler)
    compiler.set("meshdir", str(reader.meshdir))
    compiler.set("texturedir", str(reader.texturedir))
    text = ElementTree.tostring(reader.root, encoding="unicode")
    builder = MjcfBuilder(text, tuple(reader.notes), _platform_armature(reader, tree.base_armature))
    dirs = tuple(Path(p) for p in package_dirs) if package_dirs is not None else (path.parent,)
    description = assemble(
        reader.root.get("model") or path.stem,
        path,
        "mjcf",
        tree.links,
        tree.joints,
        builder,
        dirs,
        inertia_from_geometry=tree.from_geometry,
    )
    import dataclasses

    return dataclasses.replace(
        description,
        notes=tuple(reader.notes),
        planar_base=tree.planar_base,
        keyframes=keyframes,
        actuated=frozenset(tree.actuated),
    )


def _read(path: Path, *, package_dirs: Iterable[str | Path] | None = None) -> RobotDescription:
    return read_mjcf(path, package_dirs=package_dirs)


#: The MJCF format (suffixes ``.xml``, ``.mjcf``), registered at import.
FORMAT = register_format(DescriptionFormat("mjcf", (".xml", ".mjcf"), _read))
