"""Checking a description as it is assembled: one tree of physical links, whatever the format.

A format's reader builds :class:`~mobmanip.descriptions.description.JointDescription` and
:class:`~mobmanip.descriptions.description.LinkDescription` parts and hands them to
:func:`assemble`, which refuses, naming the link or joint and the value:

- more links or joints than :data:`mobmanip.support.ranges.MAX_URDF_LINKS`, a name used twice;
- a mass that is not finite or outside :data:`mobmanip.support.ranges.LINK_MASS`, an inertia
  tensor that is not finite or larger than :data:`mobmanip.support.ranges.LINK_INERTIA`;
- an origin that is not finite or lies farther than :data:`mobmanip.support.ranges.LINK_OFFSET`
  from its parent frame; a moving joint's zero or non-finite axis; a limit that is not finite,
  a negative velocity or effort, ``lower > upper``; non-finite dynamics or mimic coefficients;
- joints that name missing links, a link carried by two joints, no root or several, links not
  connected to the root.

An inertia tensor that is finite but no rigid body can have (not positive semi-definite, or its
principal moments break the triangle inequality, beyond :data:`INERTIA_SLACK`) is a vendor flaw,
not a refusal: it is recorded in the description's ``flaws`` with its repair (see
:mod:`mobmanip.descriptions.flaws`), and refused only when the robot is loaded strictly.

Whether mobmanip can *model* the tree (no floating or planar joint inside it) is a separate
question, :func:`check_supported`, asked by the robot layer.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from ..errors import DescriptionError
from ..support.ranges import LINK_INERTIA, LINK_MASS, LINK_OFFSET, MAX_URDF_LINKS
from .description import JointDescription, LinkDescription, ModelBuilder, NameMap, Origin, RobotDescription
from .extents import geometry_extents
from .flaws import INERTIA_SLACK, PLAUSIBLE_MIN_SHARE, Flaw, implausible_inertia, inertia_flaw

__all__ = ["INERTIA_SLACK", "UNSUPPORTED_JOINT_TYPES", "assemble", "check_supported"]


_IDENTITY = Origin()

#: Joint types mobmanip cannot model inside a robot (it adds the planar root joint itself).
UNSUPPORTED_JOINT_TYPES = ("floating", "planar")


def assemble(
    name: str,
    source: str | Path,
    format: str,
    links: Sequence[LinkDescription],
    joints: Sequence[JointDescription],
    builder: ModelBuilder,
    package_dirs: Iterable[str | Path] | None = None,
    inertia_from_geometry: Iterable[str] = (),
) -> RobotDescription:
    """The description of checked parts (see the module docstring for what is checked).

    Args:
        name: the robot's name.
        source: the file read.
        format: the name of the format that read it.
        links: every link, in file order.
        joints: every joint, in file order.
        builder: hands the source to Pinocchio.
        package_dirs: where ``package://`` URIs resolve (default: the file's folder).
        inertia_from_geometry: links whose inertia the reader computed from their own geometry
            (an MJCF body without ``<inertial>``): not judged by the plausibility rule, which
            measures a stated tensor against the geometry.

    Raises:
        DescriptionError: the first problem found (the format's own subclass, e.g.
            :class:`~mobmanip.errors.UrdfError`, naming the file).
    """
    source = Path(source)
    path = str(source)

    def fail(reason: str) -> DescriptionError:
        return builder.error(path, reason)

    if not links:
        raise fail("no links")
    for kind, items in (("links", links), ("joints", joints)):
        if len(items) > MAX_URDF_LINKS:
            raise fail(f"{len(items):,} {kind}; mobmanip reads URDFs of at most {MAX_URDF_LINKS:,}")
    for kind, names in (("link", [link.name for link in links]), ("joint", [j.name for j in joints])):
        repeated = _duplicates(names)
        if repeated:
            raise fail(f"{kind} name {repeated[0]!r} is defined more than once")
    flaws: list[Flaw] = []  # repaired when the model is built, refused by a strict load
    dirs = tuple(Path(p) for p in package_dirs) if package_dirs is not None else (source.parent,)
    derived = set(inertia_from_geometry)
    total = sum(float(link.inertial.mass) for link in links if link.inertial is not None)
    judged = {
        link.name
        for link in links
        if link.inertial is not None and link.inertial.mass >= PLAUSIBLE_MIN_SHARE * total and link.name not in derived
    }
    for link in links:
        flaw = _check_inertial(link, fail)
        if flaw is None and link.name in judged:
            flaw = _check_plausible(link, dirs)
        if flaw is not None:
            flaws.append(flaw)
    for joint in joints:
        _check_joint(joint, fail)
    root = _check_tree(links, joints, fail)
    return RobotDescription(
        name=name,
        source=source,
        format=format,
        root_link=root,
        joints=NameMap((j.name, j) for j in joints),
        links=NameMap((link.name, link) for link in links),
        package_dirs=tuple(Path(p) for p in package_dirs) if package_dirs is not None else (source.parent,),
        builder=builder,
        flaws=tuple(flaws),
    )


def check_supported(description: RobotDescription) -> None:
    """Refuse a tree mobmanip cannot model: a ``floating`` or ``planar`` joint inside it.

    Raises:
        DescriptionError: naming the first such joint.
    """
    for joint in description.joints.values():
        if joint.type in UNSUPPORTED_JOINT_TYPES:
            raise description.error(
                f"joint {joint.name!r} is of type {joint.type!r}, which mobmanip cannot model "
                "(it adds the platform's planar root joint itself)"
            )


def _duplicates(names: Iterable[str]) -> list[str]:
    seen, repeated = set(), []
    for name in names:
        if name in seen and name not in repeated:
            repeated.append(name)
        seen.add(name)
    return repeated


def _finite_array(value: object, what: str, fail) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise fail(f"{what} is not numeric: {value!r}") from None
    if not np.all(np.isfinite(array)):
        raise fail(f"{what} is not finite: {np.array2string(array, separator=', ')}")
    return array


def _check_placement(origin: Origin, what: str, fail) -> None:
    """An origin: finite, its translation within :data:`mobmanip.support.ranges.LINK_OFFSET`."""
    if origin == _IDENTITY:
        return
    if not all(math.isfinite(v) for v in origin.xyz + origin.rpy):
        _finite_array(origin.matrix, f"{what} <origin>", fail)  # raises, showing the placement
    offset = math.hypot(*origin.xyz)
    if offset > LINK_OFFSET:
        raise fail(f"{what} <origin> lies {offset:g} m from its parent frame (at most {LINK_OFFSET:g} m)")


def _check_inertial(link: LinkDescription, fail) -> Flaw | None:
    """Mass finite, non-negative and at most :data:`LINK_MASS`; the inertia tensor finite and
    at most :data:`LINK_INERTIA`. Returns the tensor's flaw (not positive semi-definite, or the
    triangle inequality broken, beyond :data:`INERTIA_SLACK`), ``None`` when it is physical."""
    inertial = link.inertial
    if inertial is None:
        return None
    where = f"link {link.name!r}"
    _check_placement(inertial.origin, f"{where} <inertial>", fail)
    mass = float(_finite_array(inertial.mass, f"{where} mass", fail))
    if not LINK_MASS[0] <= mass <= LINK_MASS[1]:
        raise fail(f"{where} has mass {mass:g} kg; a mass must lie in [0, {LINK_MASS[1]:g}] kg")
    if inertial.inertia is None:
        return None
    inertia = _finite_array(inertial.inertia, f"{where} inertia", fail)
    scale = float(np.max(np.abs(inertia)))
    if scale > LINK_INERTIA:
        raise fail(f"{where} has a moment of inertia of {scale:g} kg m^2 (at most {LINK_INERTIA:g})")
    return inertia_flaw(link.name, inertia)


def _check_plausible(link: LinkDescription, package_dirs: Sequence[Path]) -> Flaw | None:
    """The link's :class:`~mobmanip.descriptions.flaws.ImplausibleInertia`, if its (physical)
    tensor is far below what its mass has in its geometry's bounding box; ``None`` when it is not,
    or when the link has no mass, no tensor or no geometry mobmanip can measure."""
    inertial = link.inertial
    if inertial is None or inertial.inertia is None or inertial.mass <= 0.0:
        return None
    extents = geometry_extents(link, package_dirs)
    if extents is None:
        return None
    return implausible_inertia(link.name, float(inertial.mass), np.asarray(inertial.inertia, dtype=float), extents)


def _check_joint(joint: JointDescription, fail) -> None:
    """Origin finite; axis finite and not zero; limits finite, lower <= upper, velocity and
    effort not negative; dynamics and mimic coefficients finite."""
    where = f"joint {joint.name!r}"
    _check_placement(joint.origin, where, fail)
    axis = _finite_array(joint.axis, f"{where} <axis>", fail)
    if joint.type not in ("fixed", "floating", "planar") and not np.linalg.norm(axis) > 1e-9:
        raise fail(f"{where} has a zero <axis xyz=...> ({np.array2string(axis, separator=' ')})")
    limit = joint.limits
    if limit is not None:
        for attribute in ("lower", "upper", "velocity", "effort"):
            value = getattr(limit, attribute)
            if value is not None:
                _finite_array(value, f"{where} <limit {attribute}>", fail)
        for attribute in ("velocity", "effort"):
            value = getattr(limit, attribute)
            if value is not None and float(value) < 0.0:
                raise fail(f"{where} has a negative <limit {attribute}={float(value):g}>")
        lower, upper = limit.lower, limit.upper
        if joint.type in ("revolute", "prismatic") and lower is not None and upper is not None and lower > upper:
            raise fail(f"{where} has <limit lower={lower:g}> above upper={upper:g}")
    for part, values in (
        ("dynamics", (("damping", joint.damping), ("friction", joint.friction))),
        (
            "mimic",
            () if joint.mimic is None else (("multiplier", joint.mimic.multiplier), ("offset", joint.mimic.offset)),
        ),
    ):
        for attribute, value in values:
            if value is not None:
                _finite_array(value, f"{where} <{part} {attribute}>", fail)


def _check_tree(links: Sequence[LinkDescription], joints: Sequence[JointDescription], fail) -> str:
    """The joints form one tree over the links: every joint names existing links, no link is
    carried twice, one root, every link reached from it. Returns the root link."""
    names = {link.name for link in links}
    carried_by: dict[str, str] = {}
    for joint in joints:
        for role, link in (("parent", joint.parent), ("child", joint.child)):
            if link not in names:
                raise fail(f"joint {joint.name!r} names a {role} link {link!r} that does not exist")
        if joint.child in carried_by:
            raise fail(
                f"link {joint.child!r} is the child of two joints, {carried_by[joint.child]!r} and {joint.name!r}: "
                "closed kinematic loops are not supported"
            )
        carried_by[joint.child] = joint.name
    roots = [link.name for link in links if link.name not in carried_by]
    if len(roots) != 1:
        if not roots:
            raise fail("every link has a parent joint: the joints form a closed loop")
        raise fail(f"several root links ({', '.join(roots)}): the URDF is not one connected tree")
    below: dict[str, list[str]] = {}
    for joint in joints:
        below.setdefault(joint.parent, []).append(joint.child)
    reached, stack = {roots[0]}, [roots[0]]
    while stack:
        for child in below.get(stack.pop(), ()):
            if child not in reached:
                reached.add(child)
                stack.append(child)
    unreached = [link.name for link in links if link.name not in reached]
    if unreached:
        raise fail(
            f"links {', '.join(unreached)} are not connected to the root {roots[0]!r}: their joints form a closed loop"
        )
    return roots[0]
