"""Which mesh files the viewer may read: only those inside the robot's package roots.

A URDF's ``<mesh filename=...>`` can name any file: an absolute path, ``file:///etc/...``, or a
relative one climbing out with ``../``. The viewer embeds every mesh it loads into the scene,
and an exported page is meant to be shared, so a mesh is read only when it resolves (symlinks
followed) to a file inside one of the spec's package directories (``RobotSpec.package_dirs``:
the URDF's own folder for a local robot, the share folder of example-robot-data for its robots).
Every other mesh, and every mesh that cannot be found, is left out of the drawing with a note.

The boundary holds for every file a mesh references too: a Collada mesh's textures
(``<library_images><image><init_from>``), which the viewer embeds in the page beside the mesh,
must lie inside the package roots as well, or the mesh is left out (:func:`mesh_references`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pinocchio as pin

    from ..descriptions import RobotDescription
    from ..robot.model import Robot


@dataclass
class VisualMeshes:
    """Which visual meshes of a description the viewer may read.

    Attributes:
        files: ``(link, mesh file name as written) -> resolved absolute path`` of each mesh
            inside the package roots.
        skipped: one note per mesh left out (``mesh 'x.stl' of link 'l' not drawn: reason``).
        meshes: the files the viewer may read, by link.
    """

    files: dict[tuple[str, str], Path] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)
    meshes: dict[str, list[Path]] = field(default_factory=dict)

    def resolve(self, link: str, filename: str) -> str | None:
        """The file to load for a mesh (see :meth:`mobmanip.descriptions.RobotDescription.build_geometry`),
        or ``None`` to leave it out."""
        path = self.files.get((link, filename))
        return None if path is None else str(path)


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
    hint = ""
    if filename.startswith("package://"):
        package = filename[len("package://") :].split("/", 1)[0]
        hint = f"; give the folder that holds package {package!r} with --package-path DIR (or the spec's package_paths)"
    if outside:
        return None, f"it lies outside the robot's package directories ({roots_text}){hint}"
    return None, f"no such file in the robot's package directories ({roots_text}){hint}"


#: Largest mesh file whose references are read (bytes).
MAX_MESH_BYTES = 256 * 1024 * 1024


def mesh_references(path: Path) -> tuple[list[str] | None, str]:
    """The files a mesh file references, as written (a Collada file's texture images), or
    ``None`` and the reason when they cannot be read (the mesh is then not drawn).

    Every ``init_from`` under every ``library_images`` of a ``.dae`` file counts, whatever its
    namespace (Pinocchio's viewer reads them and embeds their bytes); OBJ and STL files
    reference nothing the viewer reads.
    """
    if path.suffix.lower() != ".dae":
        return [], ""
    import xml.etree.ElementTree as ET

    try:
        if path.stat().st_size > MAX_MESH_BYTES:
            return None, f"it is larger than {MAX_MESH_BYTES} bytes"
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError, ValueError) as exc:
        return None, f"it cannot be read as Collada ({exc})"
    references = []
    for library in root.iter():
        if not library.tag.endswith("library_images"):
            continue
        for element in library.iter():
            if "init_from" in element.tag:
                text = (element.text or "").strip()
                if not text:
                    return None, "a texture's <init_from> is empty"
                references.append(text)
    return references, ""


def _references_inside(path: Path, roots: Sequence[Path]) -> str:
    """Why a mesh may not be drawn because of a file it references ("" when every one is inside)."""
    references, reason = mesh_references(path)
    if references is None:
        return reason
    real_roots = [os.path.realpath(root) for root in roots]
    for reference in references:
        # as the viewer reads it: a path, absolute or relative to the mesh's folder (no URI schemes)
        written = Path(reference)
        real = os.path.realpath(written if written.is_absolute() else path.parent / written)
        if not _inside(real, real_roots):
            return f"its texture {reference!r} lies outside the robot's package directories"
        if not os.path.isfile(real):
            return f"its texture {reference!r} is not a file in the robot's package directories"
    return ""


def visual_meshes(description: RobotDescription) -> VisualMeshes:
    """Each visual mesh of ``description`` resolved by :func:`resolve_mesh` against its package
    directories (relative paths from the file's folder); those that may not be read are noted
    in ``skipped``, link by link in file order."""
    out = VisualMeshes()
    folder = description.source.resolve().parent
    for link in description.links.values():
        for shape in link.visuals:
            if shape.kind != "mesh":
                continue
            filename = shape.filename or ""
            path, reason = resolve_mesh(filename, folder, description.package_dirs)
            if path is not None:
                reason = _references_inside(path, description.package_dirs)
                path = None if reason else path
            if path is None:
                out.skipped.append(f"mesh {filename!r} of link {link.name!r} not drawn: {reason}")
            else:
                out.files[(link.name, filename)] = path
                out.meshes.setdefault(link.name, []).append(path)
    return out


def visual_model(robot: Robot, notes: list[str] | None = None) -> tuple[pin.Model, pin.GeometryModel]:
    """The visual geometry of ``robot`` on a model that matches ``robot.model`` joint for joint.

    The robot's description builds the model again with the planar root joint and its visual
    geometry, and both are reduced with the joints the robot locks (those not in
    ``robot.model.names``) at the spec's reference positions, as :func:`mobmanip.load_robot` does.
    Meshes are read only from inside the spec's package directories (:mod:`mobmanip.viz.meshes`);
    those outside, missing or unreadable are left out, with a line appended to ``notes`` for each.

    Raises:
        ModelError: the reduced model does not match ``robot.model`` (names or sizes differ).
    """
    import pinocchio as pin

    from ..errors import DescriptionError, ModelError
    from ..robot.model import description_of, locked_joints

    spec = robot.spec
    notes = [] if notes is None else notes
    description = description_of(robot)
    visual = visual_meshes(description)
    notes.extend(visual.skipped)
    model = description.build_model(pin.JointModelPlanar())
    try:
        geometry = description.build_geometry(model, "visual", visual.resolve)
    except DescriptionError as exc:  # a mesh file Pinocchio cannot load: draw without meshes
        reason = exc.reason.split(": ", 1)[-1]
        notes.append(f"the meshes of {robot.name!r} could not be loaded ({reason}); drawn without them")
        geometry = description.build_geometry(model, "visual", lambda link, filename: None)
    locked, q_ref = locked_joints(model, spec.reference, keep=set(robot.model.names))
    if locked:
        model, (geometry,) = pin.buildReducedModel(model, [geometry], locked, q_ref)
    if list(model.names) != list(robot.model.names) or model.nq != robot.model.nq:
        raise ModelError(
            f"the visual model of {robot.name!r} does not match its analysis model: joints "
            f"{list(model.names)} vs {list(robot.model.names)}"
        )
    return model, geometry
