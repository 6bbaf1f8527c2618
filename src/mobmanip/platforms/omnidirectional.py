"""A holonomic base: (v_x, v_y, omega_z) in the platform frame are all free and driven.

The reduced platform velocity is the root joint's own velocity, so S is the identity on the
base coordinates. Limits are planar speeds (m/s, rad/s) and forces/torque (N, N m), given in
the spec only (a URDF has no joint for them).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .base import BASE_V, Platform, PlatformKind, WheelsSpec

if TYPE_CHECKING:
    import pinocchio as pin

    from ..descriptions import RobotDescription

#: The reduced velocities of an omnidirectional base, which are not URDF joints.
OMNI_COORDINATES = ("base_x", "base_y", "base_yaw")

_UNITS = {
    "velocity": {"base_x": "m/s", "base_y": "m/s", "base_yaw": "rad/s"},
    "effort": {"base_x": "N", "base_y": "N", "base_yaw": "N m"},
}


@dataclass(frozen=True)
class Omnidirectional(Platform):
    """A holonomic base whose reduced velocity is the platform-frame (v_x, v_y, omega_z)."""

    kind = "omnidirectional"

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return OMNI_COORDINATES

    def tangent_block(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        return np.array(BASE_V), np.eye(3)

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(BASE_V), np.eye(3)

    def description_limits(self, description: RobotDescription) -> Mapping[str, tuple[float | None, float | None]]:
        """No limits, or those of the file's own planar base joints (x, y, yaw) when it has them
        (:attr:`mobmanip.descriptions.description.RobotDescription.planar_base`)."""
        base = getattr(description, "planar_base", ())
        if len(base) == 3:
            return {name: (j.velocity_limit, j.effort_limit) for name, j in zip(OMNI_COORDINATES, base)}
        return dict.fromkeys(OMNI_COORDINATES, (None, None))

    def missing_limit_source(self, name: str, kind: str) -> tuple[str, str]:
        return "an omnidirectional base takes its limits from the spec only", _UNITS[kind][name]


class OmnidirectionalKind(PlatformKind):
    name = "omnidirectional"
    summary = "a holonomic base driven along x, y and in yaw (limits in the spec)"

    def limit_names(self, wheels) -> tuple[str, ...]:
        return OMNI_COORDINATES

    def build(self, wheels: WheelsSpec | None, description: RobotDescription, model: pin.Model) -> Omnidirectional:
        return Omnidirectional()

    def toml_limit_hints(self, wheels) -> list[tuple[str, str]]:
        return [(name, "REQUIRED for an omnidirectional base") for name in OMNI_COORDINATES]


KIND = OmnidirectionalKind()
