"""One robot file, read once: the neutral description every layer above works from.

A :class:`RobotDescription` is what a robot file says, whatever its format: the links (their
inertia and their collision and visual shapes) and the joints (type, parent and child links,
origin, axis, limits, mimic) of one kinematic tree, with the questions the rest of mobmanip asks
of that tree (a link's parent joint, the chain from the root, the links a joint moves, every
joint's placement at the zero configuration). It also carries the one thing that stays
format-specific, a :class:`ModelBuilder`, which hands the file's text to Pinocchio's model and
geometry builders. Platform kinds, detection, the model loader, self-collision and the viewer
receive a description, never a parser's object or raw text.

Everything here is immutable: frozen dataclasses, tuples and read-only mappings. A format's
reader (see :mod:`mobmanip.descriptions.formats`) builds the parts and hands them to
:func:`mobmanip.descriptions.checks.assemble`, which checks them and returns the description.
Lengths are in metres, angles in radians, masses in kg, inertias in kg m^2.
"""

from __future__ import annotations

import functools
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar, TypeVar

import numpy as np

if TYPE_CHECKING:
    import pinocchio as pin

    from ..errors import DescriptionError
    from .flaws import Flaw

#: Joint types that move (one degree of freedom each).
MOVING_JOINT_TYPES = ("revolute", "continuous", "prismatic")

#: Every joint type a description knows (URDF's six).
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")

#: Kinds of collision and visual shapes.
SHAPE_KINDS = ("box", "cylinder", "sphere", "mesh")

#: Which shapes a geometry is built from: ``"collision"`` or ``"visual"``.
GEOMETRY_KINDS = ("collision", "visual")

#: ``(link name, mesh file name as written) -> the file to load instead, or None to leave the
#: shape out``; see :meth:`RobotDescription.build_geometry`.
MeshFilter = Callable[[str, str], "str | None"]

_T = TypeVar("_T")


class NameMap(Mapping[str, _T]):
    """A read-only mapping by name that keeps the file's order (and pickles, unlike
    :class:`types.MappingProxyType`)."""

    __slots__ = ("_items",)

    def __init__(self, items: Iterable[tuple[str, _T]] = ()) -> None:
        self._items: dict[str, _T] = dict(items)

    def __getitem__(self, name: str) -> _T:
        return self._items[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __hash__(self) -> int:
        return hash(tuple(self._items.items()))

    def __repr__(self) -> str:
        return f"NameMap({list(self._items)})"

    def __getstate__(self) -> dict[str, _T]:
        return self._items

    def __setstate__(self, state: dict[str, _T]) -> None:
        self._items = state


def rpy_matrix(rpy: Iterable[float]) -> np.ndarray:
    """The rotation (3, 3) of roll, pitch, yaw (rad) about the fixed x, y, z axes:
    ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``, URDF's convention (NaN entries for non-finite angles)."""
    with np.errstate(invalid="ignore"):
        cr, cp, cy = np.cos(np.asarray(tuple(rpy), dtype=float))
        sr, sp, sy = np.sin(np.asarray(tuple(rpy), dtype=float))
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


@dataclass(frozen=True)
class Origin:
    """A placement relative to a parent frame.

    Attributes:
        xyz: translation (m), (3,).
        rpy: roll, pitch, yaw about the parent's fixed x, y, z axes (rad), (3,).
    """

    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @functools.cached_property
    def rotation(self) -> np.ndarray:
        """The rotation matrix (3, 3), read-only."""
        out = rpy_matrix(self.rpy)
        out.setflags(write=False)
        return out

    @functools.cached_property
    def matrix(self) -> np.ndarray:
        """The homogeneous transform (4, 4), read-only."""
        out = np.eye(4)
        out[:3, :3] = self.rotation
        out[:3, 3] = self.xyz
        out.setflags(write=False)
        return out


@dataclass(frozen=True)
class JointLimits:
    """A joint's limits as written; ``None`` where the file gives none.

    Attributes:
        lower: lower position (rad or m).
        upper: upper position (rad or m).
        velocity: speed (rad/s or m/s).
        effort: torque or force (N m or N).
    """

    lower: float | None = None
    upper: float | None = None
    velocity: float | None = None
    effort: float | None = None


@dataclass(frozen=True)
class Mimic:
    """A joint that follows another: ``q = multiplier * q_joint + offset``."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class JointDescription:
    """One joint.

    Attributes:
        name: joint name.
        type: one of :data:`JOINT_TYPES`.
        parent: the link it hangs from.
        child: the link it carries.
        origin: its frame in the parent link's frame (the child link's frame at zero).
        axis: its axis in its own frame, (3,) (not normalised; URDF's default is x).
        limits: its ``<limit>``, or ``None`` when it has none.
        mimic: the joint it mimics, or ``None``.
        damping: viscous damping as written (N m s/rad or N s/m), or ``None``.
        friction: Coulomb friction as written (N m or N), or ``None``.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: Origin = Origin()
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    limits: JointLimits | None = None
    mimic: Mimic | None = None
    damping: float | None = None
    friction: float | None = None

    @property
    def moves(self) -> bool:
        """Whether it is revolute, continuous or prismatic."""
        return self.type in MOVING_JOINT_TYPES

    @property
    def unit_axis(self) -> np.ndarray:
        """Its axis normalised, (3,), in its own frame."""
        axis = np.asarray(self.axis, dtype=float)
        return axis / np.linalg.norm(axis)

    @property
    def velocity_limit(self) -> float | None:
        """The velocity limit (rad/s or m/s) as written, or ``None``."""
        return None if self.limits is None else self.limits.velocity

    @property
    def effort_limit(self) -> float | None:
        """The effort limit (N m or N) as written, or ``None``."""
        return None if self.limits is None else self.limits.effort


@dataclass(frozen=True)
class Inertial:
    """A link's mass properties.

    Attributes:
        mass: kg.
        origin: the centre of mass and the inertia's axes, in the link frame.
        inertia: the inertia tensor about the centre of mass (kg m^2), rows of (3, 3), or
            ``None`` when the file gives none.
    """

    mass: float = 0.0
    origin: Origin = Origin()
    inertia: tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]] | None = None

    @property
    def inertia_matrix(self) -> np.ndarray:
        """The inertia tensor (3, 3) (zeros when none is given)."""
        return np.zeros((3, 3)) if self.inertia is None else np.array(self.inertia, dtype=float)

    @property
    def has_inertia(self) -> bool:
        """Whether the mass is positive or the inertia tensor not zero."""
        return self.mass > 0.0 or bool(np.any(self.inertia_matrix != 0.0))


@dataclass(frozen=True)
class Shape:
    """A collision or visual shape of a link.

    Attributes:
        kind: one of :data:`SHAPE_KINDS`.
        origin: its placement in the link frame.
        size: a box's edge lengths (m), (3,); ``None`` for other kinds.
        radius: a cylinder's or sphere's radius (m).
        length: a cylinder's length along its own z axis (m).
        filename: a mesh's file as written (a path or a ``package://`` URI).
        scale: a mesh's scale per axis, (3,), or ``None`` (unscaled).
        name: the shape's name, if the file gives one.
    """

    kind: str
    origin: Origin = Origin()
    size: tuple[float, float, float] | None = None
    radius: float | None = None
    length: float | None = None
    filename: str | None = None
    scale: tuple[float, float, float] | None = None
    name: str | None = None


@dataclass(frozen=True)
class LinkDescription:
    """One link: its mass properties and its shapes.

    Attributes:
        name: link name.
        inertial: its mass properties, or ``None`` when the file gives none.
        collisions: its collision shapes, in file order.
        visuals: its visual shapes, in file order.
    """

    name: str
    inertial: Inertial | None = None
    collisions: tuple[Shape, ...] = ()
    visuals: tuple[Shape, ...] = ()

    @property
    def has_inertia(self) -> bool:
        """Whether it has a positive mass or a non-zero inertia tensor."""
        return self.inertial is not None and self.inertial.has_inertia


def geometry_type(kind: str) -> pin.GeometryType:
    """Pinocchio's geometry type of a kind of shapes (``"collision"`` or ``"visual"``)."""
    import pinocchio as pin

    return pin.GeometryType.COLLISION if kind == "collision" else pin.GeometryType.VISUAL


class ModelBuilder(ABC):
    """How Pinocchio builds a model and geometry from a description's source: the one part of
    a description that depends on the file's language (URDF's builder is
    :class:`mobmanip.descriptions.urdf.UrdfBuilder`).

    Attributes:
        language: the source language, for messages (e.g. ``"URDF"``).
        text: the text handed to Pinocchio.
    """

    language: ClassVar[str]
    text: str

    @abstractmethod
    def build_model(self, source: str, root_joint: pin.JointModel | None = None) -> pin.Model:
        """Pinocchio's model of the source, under ``root_joint`` (none: fixed base).

        Raises:
            DescriptionError: Pinocchio cannot build it (naming ``source`` and its reason).
        """

    def build_geometry(
        self,
        source: str,
        model: pin.Model,
        kind: str,
        package_dirs: tuple[Path, ...],
        meshes: MeshFilter | None = None,
    ) -> pin.GeometryModel:
        """The ``kind`` (``"collision"`` or ``"visual"``) shapes on ``model``; meshes resolved
        in ``package_dirs`` and, with ``meshes``, replaced or left out as it says.

        A builder gives the two steps that depend on its language: :meth:`with_meshes` (the
        text with the meshes replaced or left out) and :meth:`load_geometry` (Pinocchio's shapes
        of a text).

        Raises:
            DescriptionError: Pinocchio cannot load them (naming ``source`` and its reason).
        """
        text = self.text if meshes is None else self.with_meshes(kind, meshes)
        return self.load_geometry(source, model, kind, text, [str(p) for p in package_dirs])

    def with_meshes(self, kind: str, meshes: MeshFilter) -> str:
        """The text with each ``kind`` mesh replaced by the file ``meshes`` gives, or its shape
        left out (see :meth:`build_geometry`)."""
        raise NotImplementedError(f"{type(self).__name__} does not filter {self.language} meshes")

    def load_geometry(self, source: str, model: pin.Model, kind: str, text: str, dirs: list[str]) -> pin.GeometryModel:
        """Pinocchio's ``kind`` shapes of ``text`` on ``model``, meshes resolved in ``dirs``
        (see :meth:`build_geometry`).

        Raises:
            DescriptionError: Pinocchio cannot load them (naming ``source`` and its reason).
        """
        raise NotImplementedError(f"{type(self).__name__} does not load {self.language} geometry")

    def error(self, source: str, reason: str) -> DescriptionError:
        """The error for a problem in the source, in its language's own error class."""
        from ..errors import DescriptionError

        return DescriptionError(source, reason)


@dataclass(frozen=True)
class RobotDescription:
    """A robot file read once: one kinematic tree of links and joints (see the module docstring).

    Build one with :func:`mobmanip.descriptions.read_description`; it is checked on the way
    (names unique, one tree, physical masses and inertias, finite origins, usable axes and
    limits).

    Attributes:
        name: the robot's name as the file gives it (may be empty).
        source: the file it was read from.
        format: the name of the format that read it (e.g. ``"urdf"``).
        root_link: the one link no joint carries.
        joints: every joint by name, in file order.
        links: every link by name, in file order.
        package_dirs: directories where ``package://`` mesh URIs resolve.
        builder: hands the source to Pinocchio (see :class:`ModelBuilder`).
        flaws: what the file gets wrong that a stated rule repairs (non-physical inertias, see
            :mod:`mobmanip.descriptions.flaws`), in file order; :meth:`build_model` applies the
            repairs, a strict load refuses them.
        notes: what the format's reader skipped or approximated (e.g. an MJCF file's tendons),
            one line each; ``init-spec`` writes them into the spec's comments.
        planar_base: the joints with which the file itself moves its root link in the plane
            (along x, along y, about z, in that order; e.g. an MJCF mobile base), taken out of
            the tree: the platform's own coordinates replace them (an ``omnidirectional``
            platform, with these joints' limits); empty when the file has none.
        keyframes: the file's own named postures (an MJCF file's ``<keyframe>``), name ->
            (joint -> position, rad or m) for every one-degree-of-freedom joint the file moves;
            empty when it has none.
        actuated: the joints the file's own actuators drive (an MJCF file's ``<actuator>`` on a
            joint, the planar base's included), ``None`` when the format does not say (a URDF):
            what tells a wheel the file drives from one that only rolls along.
    """

    name: str
    source: Path
    format: str
    root_link: str
    joints: Mapping[str, JointDescription]
    links: Mapping[str, LinkDescription]
    package_dirs: tuple[Path, ...]
    builder: ModelBuilder = field(compare=False, repr=False)
    flaws: tuple[Flaw, ...] = field(default=(), compare=False, repr=False)
    notes: tuple[str, ...] = field(default=(), compare=False, repr=False)
    planar_base: tuple[JointDescription, ...] = field(default=(), compare=False, repr=False)
    keyframes: Mapping[str, Mapping[str, float]] = field(default_factory=dict, compare=False, repr=False)
    actuated: frozenset[str] | None = field(default=None, compare=False, repr=False)

    # ----- the tree -----

    @functools.cached_property
    def _parent_joints(self) -> dict[str, JointDescription]:
        return {joint.child: joint for joint in self.joints.values()}

    @functools.cached_property
    def _child_joints(self) -> dict[str, tuple[JointDescription, ...]]:
        below: dict[str, list[JointDescription]] = {}
        for joint in self.joints.values():
            below.setdefault(joint.parent, []).append(joint)
        return {link: tuple(joints) for link, joints in below.items()}

    def parent_joint(self, link: str) -> JointDescription | None:
        """The joint that carries ``link`` (``None`` for the root)."""
        return self._parent_joints.get(link)

    def child_joints(self, link: str) -> tuple[JointDescription, ...]:
        """The joints that hang from ``link``, in file order."""
        return self._child_joints.get(link, ())

    def children(self, link: str) -> tuple[str, ...]:
        """The links carried directly by ``link``'s joints."""
        return tuple(joint.child for joint in self.child_joints(link))

    def is_leaf(self, link: str) -> bool:
        """Whether no joint hangs from ``link``."""
        return not self.child_joints(link)

    def chain(self, link: str) -> tuple[JointDescription, ...]:
        """The joints from the root link down to ``link``, root first (empty for the root)."""
        out = []
        joint = self.parent_joint(link)
        while joint is not None:
            out.append(joint)
            joint = self.parent_joint(joint.parent)
        return tuple(reversed(out))

    def subtree_links(self, joint: str) -> list[str]:
        """The links ``joint`` moves: its child link and every link below it (depth first)."""
        out, stack = [], [self.joints[joint].child]
        while stack:
            link = stack.pop()
            out.append(link)
            stack.extend(self.children(link))
        return out

    def frame_link(self, frame: str) -> str | None:
        """The link that carries a frame named like a link or a joint (a joint's child link);
        ``None`` when neither exists."""
        if frame in self.links:
            return frame
        if frame in self.joints:
            return self.joints[frame].child
        return None

    @property
    def frame_names(self) -> list[str]:
        """Every link and joint name (the frames a spec may name), links first."""
        return list(self.links) + list(self.joints)

    @functools.cached_property
    def _zero_placements(self) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        stack = [(self.root_link, np.eye(4))]
        while stack:
            link, pose = stack.pop()
            for joint in self.child_joints(link):
                placement = pose @ joint.origin.matrix
                placement.setflags(write=False)
                out[joint.name] = placement
                stack.append((joint.child, placement))
        return out

    def zero_configuration_placements(self) -> Mapping[str, np.ndarray]:
        """Placement (4, 4) of every joint frame in the root link's frame with all joints at
        zero (then the child link's frame is the joint frame). Read-only arrays, by joint name."""
        return self._zero_placements

    def axis_in_root(self, joint: str) -> np.ndarray:
        """A joint's unit axis in the root link's frame at the zero configuration, (3,)."""
        return self._zero_placements[joint][:3, :3] @ self.joints[joint].unit_axis

    # ----- joints and links -----

    def limits(self, joint: str) -> tuple[float | None, float | None]:
        """``(velocity, effort)`` limits of a joint as written (``None`` where absent)."""
        description = self.joints[joint]
        return description.velocity_limit, description.effort_limit

    @property
    def mimics(self) -> dict[str, str]:
        """Joints that mimic another: ``{mimicking joint: mimicked joint}``."""
        return {j.name: j.mimic.joint for j in self.joints.values() if j.mimic is not None}

    def moving_joints(self) -> list[JointDescription]:
        """The revolute, continuous and prismatic joints, in file order."""
        return [j for j in self.joints.values() if j.moves]

    def link_has_inertia(self, link: str) -> bool:
        """Whether ``link`` has a positive mass or a non-zero inertia tensor."""
        return self.links[link].has_inertia

    # ----- Pinocchio -----

    @property
    def model_text(self) -> str:
        """The text handed to Pinocchio's model and geometry builders."""
        return self.builder.text

    def build_model(self, root_joint: pin.JointModel | None = None, *, repaired: bool = True) -> pin.Model:
        """Pinocchio's model of the whole description (nothing locked) under ``root_joint``
        (e.g. ``pin.JointModelPlanar()``; ``None``: a fixed base).

        Args:
            root_joint: the joint the root link hangs on (``None``: fixed).
            repaired: apply the repairs of :attr:`flaws` (default); ``False`` gives the model
                exactly as the file says (for comparisons).

        Raises:
            DescriptionError: Pinocchio cannot build it (its reason in one line).
        """
        model = self.builder.build_model(str(self.source), root_joint)
        if repaired and self.flaws:
            from .flaws import repair_inertias

            inertials = {name: link.inertial for name, link in self.links.items() if link.inertial is not None}
            repair_inertias(model, self.flaws, inertials)
        return model

    def build_geometry(self, model: pin.Model, kind: str, meshes: MeshFilter | None = None) -> pin.GeometryModel:
        """The ``kind`` (``"collision"`` or ``"visual"``) shapes on ``model`` (a model built by
        :meth:`build_model`), meshes resolved in :attr:`package_dirs`.

        Args:
            model: the model the shapes hang on.
            kind: ``"collision"`` or ``"visual"``.
            meshes: ``(link, filename) -> file to load or None``: each mesh of that kind is
                loaded from the file it returns, or left out when it returns ``None``. Without
                it, meshes load as the file names them.

        Raises:
            ArgumentError: a ``kind`` other than ``"collision"`` or ``"visual"``.
            DescriptionError: Pinocchio cannot load the shapes (its reason in one line).
        """
        if kind not in GEOMETRY_KINDS:
            from ..errors import ArgumentError

            raise ArgumentError(f"geometry kind must be one of {', '.join(GEOMETRY_KINDS)}, got {kind!r}")
        return self.builder.build_geometry(str(self.source), model, kind, self.package_dirs, meshes)

    def error(self, reason: str) -> DescriptionError:
        """The error naming this description's file and ``reason`` (e.g. a
        :class:`~mobmanip.errors.UrdfError` for a URDF)."""
        return self.builder.error(str(self.source), reason)
