"""Which mesh files the viewer may read: only those inside the robot's package roots.

A URDF's ``<mesh filename=...>`` can name any file: an absolute path, ``file:///etc/...``, or a
relative one climbing out with ``../``. The viewer embeds every mesh it loads into the scene,
and an exported page is meant to be shared, so a mesh is read only when it resolves (symlinks
followed) to a file inside one of the spec's package directories (``RobotSpec.package_dirs``:
the URDF's own folder for a local robot, the share folder of example-robot-data for its robots).
Every other mesh, and every mesh that cannot be found, is left out of the drawing with a note.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING
from xml.etree import ElementTree

from ..descriptions.urdf import urdf_text
from ..errors import UrdfError

if TYPE_CHECKING:
    import pinocchio as pin

    from ..robot.model import Robot


@dataclass
class VisualUrdf:
    """A URDF's text with every drawable mesh given by its resolved absolute path.

    Attributes:
        text: the URDF, visuals with disallowed or missing meshes removed.
        skipped: one note per mesh left out (``mesh 'x.stl' of link 'l': reason``).
        meshes: the files the viewer may read, by link.
    """

    text: str
    skipped: list[str] = field(default_factory=list)
    meshes: dict[str, list[Path]] = field(default_factory=dict)


def _inside(path: str, roots: Sequence[str]) -> bool:
    return any(os.path.commonpath([path, root]) == root for root in roots)


def resolve_mesh(filename: str, urdf_dir: Path, roots: Sequence[Path]) -> tuple[Path | None, str]:
    """The file a mesh URI names, if it lies inside ``roots``; else ``None`` and the reason.

    ``package://NAME/REST`` is looked up as ``ROOT/NAME/REST`` in each root; ``file://`` URIs,
    absolute paths and paths relative to the URDF's folder are taken as they are. Symlinks are
    followed before the check, so a link inside a root that points outside is refused too.
    """
    real_roots = [os.path.realpath(root) for root in roots]
    if filename.startswith("package://"):
        candidates = [Path(root) / filename[len("package://") :] for root in roots]
    elif "://" in filename and not filename.startswith("file://"):
        return None, f"the URI scheme of {filename.split('://', 1)[0]!r} is not supported"
    else:
        path = Path(filename[len("file://") :] if filename.startswith("file://") else filename)
        candidates = [path if path.is_absolute() else urdf_dir / path]
    outside = False
    for candidate in candidates:
        real = os.path.realpath(candidate)
        if not _inside(real, real_roots):
            outside = outside or os.path.exists(real) or not filename.startswith("package://")
            continue
        if os.path.isfile(real):
            return Path(real), ""
    roots_text = ", ".join(str(r) for r in roots) or "none"
    if outside:
        return None, f"it lies outside the robot's package directories ({roots_text})"
    return None, f"no such file in the robot's package directories ({roots_text})"


def visual_urdf(urdf_path: Path, package_dirs: Sequence[Path]) -> VisualUrdf:
    """The URDF with each ``<visual>`` mesh resolved by :func:`resolve_mesh` and the visuals whose
    mesh may not be read removed (noted in ``skipped``). Texture files are dropped the same way.

    Raises:
        UrdfError: the URDF cannot be read or parsed.
    """
    urdf_path = Path(urdf_path)
    text = urdf_text(urdf_path)
    try:
        root = ElementTree.fromstring(text) if text is not None else ElementTree.parse(urdf_path).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise UrdfError(str(urdf_path), f"cannot read its visuals: {exc}") from exc
    out = VisualUrdf(text="")
    urdf_dir = urdf_path.resolve().parent
    for link in root.iter("link"):
        name = link.get("name", "?")
        for visual in list(link.findall("visual")):
            mesh = visual.find("geometry/mesh")
            if mesh is None:
                continue
            filename = mesh.get("filename", "")
            path, reason = resolve_mesh(filename, urdf_dir, package_dirs)
            if path is None:
                link.remove(visual)
                out.skipped.append(f"mesh {filename!r} of link {name!r} not drawn: {reason}")
            else:
                mesh.set("filename", str(path))
                out.meshes.setdefault(name, []).append(path)
        for collision in list(link.findall("collision")):  # the viewer draws visuals only
            link.remove(collision)
    for texture in list(root.iter("texture")):
        texture.attrib.pop("filename", None)
    out.text = ElementTree.tostring(root, encoding="unicode")
    return out


def strip_meshes(text: str) -> str:
    """The URDF text without any mesh visual (primitive shapes stay)."""
    root = ElementTree.fromstring(text)
    for link in root.iter("link"):
        for visual in list(link.findall("visual")):
            if visual.find("geometry/mesh") is not None:
                link.remove(visual)
    return ElementTree.tostring(root, encoding="unicode")


def visual_model(robot: Robot, notes: list[str] | None = None) -> tuple[pin.Model, pin.GeometryModel]:
    """The visual geometry of ``robot`` on a model that matches ``robot.model`` joint for joint.

    The URDF is built again with the planar root joint and its visual geometry, and both are
    reduced with the joints the robot locks (those not in ``robot.model.names``) at the spec's
    reference positions, as :func:`mobmanip.load_robot` does. Meshes are read only from inside
    the spec's package directories (:mod:`mobmanip.viz.meshes`); those outside, missing or
    unreadable are left out, with a line appended to ``notes`` for each.

    Raises:
        ModelError: the reduced model does not match ``robot.model`` (names or sizes differ).
    """
    import pinocchio as pin

    from ..errors import ModelError
    from ..robot.model import locked_joints
    from ..support.native_stderr import call_with_large_stack, captured_native_stderr

    spec = robot.spec
    notes = [] if notes is None else notes
    visual = visual_urdf(spec.urdf, spec.package_dirs)
    notes.extend(visual.skipped)
    package_dirs = [str(p) for p in spec.package_dirs]
    model = call_with_large_stack(pin.buildModelFromXML, visual.text, pin.JointModelPlanar())
    with captured_native_stderr() as native:
        try:
            geometry = call_with_large_stack(
                pin.buildGeomFromUrdfString, model, visual.text, pin.GeometryType.VISUAL, None, package_dirs
            )
        except Exception as exc:  # a mesh file Pinocchio cannot load: draw without meshes
            reason = native.first_error() or (str(exc).splitlines() or [type(exc).__name__])[0]
            notes.append(f"the meshes of {robot.name!r} could not be loaded ({reason}); drawn without them")
            geometry = None
    if geometry is None:
        geometry = call_with_large_stack(
            pin.buildGeomFromUrdfString, model, strip_meshes(visual.text), pin.GeometryType.VISUAL
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
