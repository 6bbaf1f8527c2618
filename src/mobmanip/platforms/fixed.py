"""A platform that does not move: a fixed-base robot, or the paper's locked-platform comparison."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .base import Platform, PlatformKind, WheelsSpec

if TYPE_CHECKING:
    import pinocchio as pin

    from ..descriptions import RobotDescription


@dataclass(frozen=True)
class LockedPlatform(Platform):
    """A platform that does not move: the fixed multi-arm system the paper compares against."""

    kind = "fixed"

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return ()

    def tangent_block(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(0, dtype=int), np.zeros((0, 0))

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(0, dtype=int), np.zeros((0, 0))


class FixedKind(PlatformKind):
    name = "fixed"
    summary = "the platform does not move (a fixed-base robot; any wheels are locked)"

    def build(self, wheels: WheelsSpec | None, description: RobotDescription, model: pin.Model) -> LockedPlatform:
        return LockedPlatform()


KIND = FixedKind()
