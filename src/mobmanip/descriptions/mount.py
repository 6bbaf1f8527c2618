"""One URDF from two: an arm mounted on a base by a fixed joint.

:func:`mount_urdf` reads both files as URDFs (so a file mobmanip would refuse is refused here, with
the same message), then writes the base's ``<robot>`` with the arm's top-level elements appended
(links, joints, materials, transmissions, ``<gazebo>`` sections) and one fixed joint,
:data:`MOUNT_JOINT`, from a link of the base (its root link unless named) to the arm's root
link at the pose ``(x, y, z, yaw)`` in that link's frame.

Names: an arm link, joint or material whose name the base already uses is renamed with a prefix
(``arm_`` unless given), and every reference to it in the arm (a joint's parent, child and mimic,
a visual's material, a transmission's joint, a ``<gazebo reference>``) follows; a material that
both files define alike is kept once. Each renaming is reported.

Meshes: a mesh file named by a relative path is copied beside the composed URDF, into
``<meshes>/base/`` or ``<meshes>/arm/`` under its path relative to its URDF's folder (``..``
written as ``_up``), and the filename rewritten to match, so that the composed robot carries its
meshes as a URDF of its own does (the viewer reads meshes only inside a robot's folder,
:mod:`mobmanip.viz.meshes`); a Collada file's textures named by relative paths travel with it.
A ``package://NAME/REST`` mesh found under the package roots (:func:`package_roots`: the
``--package-path`` folders, example-robot-data's, the URDF's own folders) is copied too, into
``<meshes>/<role>/_packages/NAME/REST`` (example-robot-data's UR arms name their meshes so);
one not found, ``file://`` URIs and absolute paths are kept as written.
"""

from __future__ import annotations

import contextlib
import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..errors import ArgumentError, MobmanipError, UrdfError
from .resources import example_robot_data_share

#: Name of the fixed joint that carries the arm (prefixed like the arm's names if the base uses it).
MOUNT_JOINT = "arm_mount_joint"
#: The arm's top-level elements taken over (anything else, e.g. a ``<world>``, is left out and reported).
TAKEN = ("link", "joint", "material", "transmission", "gazebo")


@dataclass(frozen=True)
class Mounted:
    """A composed URDF.

    Attributes:
        text: the URDF text.
        renamed: ``(kind, old name, new name)`` for each arm link, joint or material renamed.
        notes: one line per other decision (a shared material kept once, elements left out).
        copies: ``(source file, path relative to the composed URDF's folder)`` of each mesh
            (and texture) to copy beside it.
        arm_root: the arm's root link, as named in the composed file.
        mount_joint: the fixed joint's name.
    """

    text: str
    renamed: tuple[tuple[str, str, str], ...]
    notes: tuple[str, ...]
    copies: tuple[tuple[Path, Path], ...]
    arm_root: str
    mount_joint: str


def parse_pose(text: str) -> tuple[float, float, float, float]:
    """``X,Y,Z,YAW`` (m, m, m, degrees) as four finite floats, YAW in radians.

    Raises:
        ArgumentError: not four comma-separated finite numbers.
    """
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise ArgumentError(f"--at takes X,Y,Z,YAW (metres, metres, metres, degrees), got {text!r}")
    x, y, z, yaw = values
    return x, y, z, math.radians(yaw)


def _read(path: Path, role: str) -> ET.Element:
    from .formats import read_description

    if path.suffix.lower() != ".urdf":
        raise ArgumentError(
            f"{role} {path}: --mount composes URDF files (.urdf); expand a xacro file first (xacro FILE > FILE.urdf)"
        )
    read_description(path)  # refuses what mobmanip cannot read (missing file, DTD, malformed, no robot)
    try:
        return ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:  # pragma: no cover - read_description refused it already
        raise UrdfError(str(path), str(exc)) from exc


def _names(robot: ET.Element, tag: str) -> list[str]:
    return [e.get("name", "") for e in robot if e.tag == tag]


def _root_link(robot: ET.Element) -> str:
    children = {c.get("link") for j in robot if j.tag == "joint" for c in j if c.tag == "child"}
    roots = [name for name in _names(robot, "link") if name not in children]
    return roots[0]  # read_description checked that there is exactly one


def _relative_parts(filename: str) -> list[str]:
    return ["_up" if part == ".." else part for part in Path(filename).parts if part not in ("", ".")]


def _textures(mesh: Path) -> list[str]:
    """The relative texture paths a Collada file names (``<init_from>`` under ``<library_images>``)."""
    if mesh.suffix.lower() != ".dae":
        return []
    try:
        root = ET.parse(mesh).getroot()
    except (OSError, ET.ParseError):
        return []
    found = []
    for library in root.iter():
        if library.tag.endswith("library_images"):
            for element in library.iter():
                text = (element.text or "").strip()
                if element.tag.endswith("init_from") and text and "://" not in text and not Path(text).is_absolute():
                    found.append(text)
    return found


def package_roots(urdf: Path, package_paths: Sequence[str | Path] = ()) -> list[Path]:
    """Where a URDF's ``package://NAME/REST`` meshes are looked for, as ``ROOT/NAME/REST``: the
    folders given (``--package-path``), example-robot-data's share folder when the file lies in
    it (its URDFs name ``package://example-robot-data/robots/...``), then the file's folder and
    the folders above it (a package's own folder holds its URDF a level or two down)."""
    roots = [Path(p) for p in package_paths]
    here = urdf.resolve()
    with contextlib.suppress(MobmanipError):
        share = example_robot_data_share().resolve()
        if share in here.parents:
            roots.append(share)
    roots += list(here.parents)[:4]
    return list(dict.fromkeys(roots))


def _source(filename: str, source_dir: Path, roots: Sequence[Path]) -> tuple[Path | None, list[str]]:
    """The file a mesh reference names and the path parts it is copied under, or ``(None, [])``
    (a URI of another scheme, an absolute path, a file not found: left as written)."""
    if filename.startswith("package://"):
        rest = filename[len("package://") :]
        for root in roots:
            candidate = root / rest
            if candidate.is_file():
                return candidate, ["_packages", *_relative_parts(rest)]
        return None, []
    if "://" in filename or Path(filename).is_absolute():
        return None, []
    source = source_dir / filename
    return (source, _relative_parts(filename)) if source.is_file() else (None, [])


def _rewrite_meshes(
    robot: ET.Element, source_dir: Path, folder: Path, copies: dict[Path, Path], roots: Sequence[Path] = ()
) -> None:
    """Mesh filenames of ``robot`` (relative, or ``package://`` found under ``roots``) rewritten
    into ``folder`` (relative to the composed URDF), each existing file (and its Collada
    textures) recorded in ``copies``."""
    for mesh in robot.iter("mesh"):
        filename = mesh.get("filename")
        if not filename:
            continue
        source, parts = _source(filename, source_dir, roots)
        if source is None:
            continue  # left as written: the viewer says it is missing
        target = folder.joinpath(*parts)
        copies[source] = target
        mesh.set("filename", target.as_posix())
        for texture in _textures(source):
            if (source.parent / texture).is_file():
                copies[source.parent / texture] = target.parent.joinpath(*_relative_parts(texture))


def mount_urdf(
    arm: str | Path,
    base: str | Path,
    at: tuple[float, float, float, float],
    meshes: str = "meshes",
    *,
    on_link: str | None = None,
    prefix: str = "arm_",
    name: str | None = None,
    package_paths: Sequence[str | Path] = (),
) -> Mounted:
    """Compose ``arm`` mounted on ``base`` into one URDF text (see the module's description).

    Args:
        arm: the arm's URDF.
        base: the base's URDF (its ``<robot>`` attributes and elements come first).
        at: ``(x, y, z, yaw)``: the arm's root link in the frame of ``on_link`` (m, rad about z).
        meshes: the folder, beside the composed file, its meshes are copied to.
        on_link: the base's link the arm is fixed to (default: the base's root link).
        prefix: put before an arm name the base already uses.
        name: the composed robot's name (default ``<base>_<arm>``, from their ``<robot name>``).
        package_paths: folders where ``package://`` meshes are looked for first
            (:func:`package_roots`); each one found is copied as a relative mesh is.

    Raises:
        ArgumentError: a file that is not a URDF, ``on_link`` not a link of the base, a prefixed
            name that still clashes, or a non-finite pose.
        DescriptionError: a file mobmanip cannot read.
    """
    arm, base = Path(arm), Path(base)
    if not all(math.isfinite(v) for v in at):
        raise ArgumentError(f"--at must be finite numbers, got {at!r}")
    base_robot, arm_robot = _read(base, "--on"), _read(arm, "--mount")
    base_links = _names(base_robot, "link")
    link = on_link if on_link is not None else _root_link(base_robot)
    if link not in base_links:
        shown = ", ".join(base_links[:12]) + (", ..." if len(base_links) > 12 else "")
        raise ArgumentError(f"--on-link {link!r} is not a link of {base}; its links: {shown}")
    arm_root = _root_link(arm_robot)

    taken = {kind: set(_names(base_robot, kind)) for kind in ("link", "joint", "material")}
    base_materials = {e.get("name"): ET.tostring(e) for e in base_robot if e.tag == "material"}
    renamed: list[tuple[str, str, str]] = []
    notes: list[str] = []
    rename: dict[str, dict[str, str]] = {"link": {}, "joint": {}, "material": {}}
    dropped: list[ET.Element] = []
    for element in arm_robot:
        kind, old = element.tag, element.get("name", "")
        if kind not in rename:
            continue
        if kind == "material" and old in base_materials:
            if ET.tostring(element) == base_materials[old]:
                notes.append(f"material {old!r} is defined alike in both files: kept once")
                dropped.append(element)
                continue
        if old in taken[kind]:
            new = prefix + old
            if new in taken[kind] or new in _names(arm_robot, kind):
                raise ArgumentError(
                    f"the arm's {kind} {old!r} clashes with the base's, and so does {new!r}: choose another --prefix"
                )
            rename[kind][old] = new
            renamed.append((kind, old, new))
    mount = MOUNT_JOINT
    if mount in taken["joint"] or mount in _names(arm_robot, "joint"):
        mount = prefix + MOUNT_JOINT
        if mount in taken["joint"] or mount in _names(arm_robot, "joint"):
            raise ArgumentError(f"the joint name {MOUNT_JOINT!r} is taken in both files: choose another --prefix")

    def apply(element: ET.Element) -> None:
        if element.tag in rename and element.get("name") in rename[element.tag]:
            element.set("name", rename[element.tag][element.get("name", "")])
        for child in element.iter():
            if child.tag in ("parent", "child") and child.get("link") in rename["link"]:
                child.set("link", rename["link"][child.get("link", "")])
            elif child.tag == "mimic" and child.get("joint") in rename["joint"]:
                child.set("joint", rename["joint"][child.get("joint", "")])
            elif child.tag == "material" and child is not element and child.get("name") in rename["material"]:
                child.set("name", rename["material"][child.get("name", "")])
            elif child.tag == "joint" and element.tag == "transmission" and child.get("name") in rename["joint"]:
                child.set("name", rename["joint"][child.get("name", "")])
        if element.tag == "gazebo" and element.get("reference") in rename["link"]:
            element.set("reference", rename["link"][element.get("reference", "")])

    copies: dict[Path, Path] = {}
    _rewrite_meshes(base_robot, base.parent, Path(meshes, "base"), copies, package_roots(base, package_paths))
    _rewrite_meshes(arm_robot, arm.parent, Path(meshes, "arm"), copies, package_roots(arm, package_paths))
    skipped = sorted({e.tag for e in arm_robot if e.tag not in TAKEN})
    if skipped:
        notes.append(f"the arm's {', '.join(f'<{t}>' for t in skipped)} left out (only its robot's parts are taken)")
    for element in arm_robot:
        if element.tag in TAKEN and element not in dropped:
            apply(element)
            base_robot.append(element)
    root = rename["link"].get(arm_root, arm_root)
    x, y, z, yaw = at
    joint = ET.SubElement(base_robot, "joint", {"name": mount, "type": "fixed"})
    ET.SubElement(joint, "parent", {"link": link})
    ET.SubElement(joint, "child", {"link": root})
    ET.SubElement(joint, "origin", {"xyz": f"{x!r} {y!r} {z!r}", "rpy": f"0 0 {yaw!r}"})
    base_name, arm_name = base_robot.get("name") or base.stem, arm_robot.get("name") or arm.stem
    base_robot.set("name", name or f"{base_name}_{arm_name}")
    ET.indent(base_robot)
    text = '<?xml version="1.0"?>\n<!-- an arm mounted on a base, composed by mobmanip init-spec (mount) -->\n'
    text += ET.tostring(base_robot, encoding="unicode") + "\n"
    return Mounted(text, tuple(renamed), tuple(notes), tuple(copies.items()), root, mount)
