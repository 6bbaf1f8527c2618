"""Robot files at the edge: where they live, which format reads them, and the one neutral
description every layer above works from.

:func:`read_description` reads a robot file (URDF, xacro, MJCF; a format is one module and one
:func:`register_format` line) into a :class:`RobotDescription`: links, joints, shapes and the
text for Pinocchio's builders, checked once. :mod:`mobmanip.descriptions.resources` says where
the built-in and packaged robots live.
"""

from . import (
    mjcf,  # noqa: F401  (registers the MJCF format)
    urdf,  # noqa: F401  (registers the URDF format)
    xacro,  # noqa: F401  (registers the xacro format)
)
from .checks import INERTIA_SLACK, UNSUPPORTED_JOINT_TYPES, assemble, check_supported
from .description import (
    JOINT_TYPES,
    MOVING_JOINT_TYPES,
    Inertial,
    JointDescription,
    JointLimits,
    LinkDescription,
    Mimic,
    ModelBuilder,
    Origin,
    RobotDescription,
    Shape,
)
from .flaws import INERTIA_RULE, Flaw, InertiaFlaw
from .formats import (
    DescriptionFormat,
    format_for,
    formats,
    known_suffixes,
    read_description,
    register_format,
    unregister_format,
)
from .mjcf import MjcfBuilder, read_mjcf
from .urdf import UrdfBuilder, read_urdf, urdf_description
from .xacro import expand_xacro, find_package, read_xacro

__all__ = [
    "INERTIA_RULE",
    "INERTIA_SLACK",
    "JOINT_TYPES",
    "MOVING_JOINT_TYPES",
    "UNSUPPORTED_JOINT_TYPES",
    "DescriptionFormat",
    "Flaw",
    "InertiaFlaw",
    "Inertial",
    "JointDescription",
    "JointLimits",
    "LinkDescription",
    "Mimic",
    "MjcfBuilder",
    "ModelBuilder",
    "Origin",
    "RobotDescription",
    "Shape",
    "UrdfBuilder",
    "assemble",
    "check_supported",
    "expand_xacro",
    "find_package",
    "format_for",
    "formats",
    "known_suffixes",
    "read_description",
    "read_mjcf",
    "read_urdf",
    "read_xacro",
    "register_format",
    "unregister_format",
    "urdf_description",
]
