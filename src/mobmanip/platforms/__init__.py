"""The platform family: one module per kind, one protocol, one registry.

A kind (see :mod:`mobmanip.platforms.base`) gives its reduced velocity names, S(q) and
Sdot(q, x) in Pinocchio's tangent space, its actuation block of Q, its limits and how they
scale, how detection recognises it in a URDF, how its spec reads and writes, and how figures
draw it. The spec, loader, detection, sweeps and figures consult :data:`KINDS`; nothing else
compares kind names. Adding a kind is a new module here and one line in :data:`KINDS`.
"""

from __future__ import annotations

from ..errors import SpecError
from . import differential_drive, fixed, omnidirectional, skid_steer, steered
from .base import BASE_V, Detected, Platform, PlatformKind, WheelsSpec
from .differential_drive import DifferentialDrive, WheelSpec
from .fixed import LockedPlatform
from .omnidirectional import OMNI_COORDINATES, Omnidirectional

#: Every platform kind by its spec name; detection tries them in this order.
KINDS: dict[str, PlatformKind] = {
    kind.name: kind
    for kind in (
        differential_drive.KIND,
        fixed.KIND,
        omnidirectional.KIND,
        skid_steer.KIND,
        steered.KIND,
    )
}


def get_kind(name: str) -> PlatformKind:
    """The platform kind registered under ``name``.

    Raises:
        SpecError: an unknown kind (the message lists the registered ones).
    """
    try:
        return KINDS[name]
    except (KeyError, TypeError):
        raise SpecError(f"unknown platform {name!r}; expected one of {', '.join(KINDS)}") from None


def a_platform(kind: str) -> str:
    """``"a differential_drive platform"``, ``"an omnidirectional platform"``: for messages."""
    return f"{'an' if kind[:1] in 'aeiou' else 'a'} {kind} platform"


__all__ = [
    "BASE_V",
    "a_platform",
    "KINDS",
    "OMNI_COORDINATES",
    "Detected",
    "DifferentialDrive",
    "LockedPlatform",
    "Omnidirectional",
    "Platform",
    "PlatformKind",
    "WheelSpec",
    "WheelsSpec",
    "get_kind",
]
