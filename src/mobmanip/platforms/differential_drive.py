"""Differential drive: two driven wheels on one axle, no lateral and no longitudinal slip.

The reduced velocity is ``eta = [eta_r, eta_l]``, the wheel rates (rad/s) in the sense that drives
the platform forward. In Pinocchio's tangent coordinates (platform-frame velocity) S is constant.
The paper's world-frame form (Eq. 7-11) is kept alongside for reference and testing:
``vq = [x_o, y_o, theta_r, theta_l]``, heading ``phi = c (theta_r - theta_l)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import SpecError, WheelError
from .base import BASE_V, Detected, Platform, PlatformKind, WheelsSpec, unicycle_rows
from .wheels import radius_of, side_by_side_message, wheel_geometry

if TYPE_CHECKING:
    import pinocchio as pin

    from ..descriptions import RobotDescription


@dataclass(frozen=True)
class WheelSpec(WheelsSpec):
    """The two drive wheels of a differential-drive platform (the spec's ``[wheels]``).

    Attributes:
        right: name of the right wheel's joint.
        left: name of the left wheel's joint.
        radius: wheel radius override (m); ``None`` reads it from the URDF geometry.
        half_track: half the distance between the wheels (m); ``None`` reads the URDF.
    """

    right: str
    left: str
    radius: float | None = None
    half_track: float | None = None

    def __post_init__(self):
        if self.right == self.left:
            raise SpecError(f"right and left wheel are the same joint {self.right!r}")
        self.check_lengths(("wheel radius", self.radius), ("half_track", self.half_track))

    @property
    def joint_names(self) -> tuple[str, ...]:
        return (self.right, self.left)


@dataclass(frozen=True)
class DifferentialDrive(Platform):
    """Two driven wheels on one axle; no lateral and no longitudinal slip.

    ``signs`` converts the forward-driving wheel rates eta to the URDF joints' own sense.

    Attributes:
        radius: wheel radius r (m).
        half_track: half the distance between the wheels b (m).
        wheel_v: tangent indices of the right and left wheel joints.
        signs: +1 or -1 per wheel: joint rate = sign * eta.
        axle_center: (p_x, p_y) of P_o, the axle midpoint, in the platform frame (m).
        wheel_names: joint names of the right and left wheel.
    """

    radius: float
    half_track: float
    wheel_v: tuple[int, int]
    signs: tuple[float, float]
    axle_center: tuple[float, float]
    wheel_names: tuple[str, str]

    kind = "differential_drive"

    @property
    def c(self) -> float:
        """The paper's c = r / (2 b): yaw rate per unit wheel-rate difference."""
        return self.radius / (2.0 * self.half_track)

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return self.wheel_names

    @property
    def drive_names(self) -> tuple[str, ...]:
        return self.wheel_names

    def tangent_block(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Rows of S for the platform coordinates.

        Returns:
            ``(v_indices, block)``: the tangent indices (root joint, then wheels) and the
            (5, 2) block that maps eta to them. With P_o at (p_x, p_y) in the platform frame,
            v = r/2 (eta_r + eta_l) forward at P_o, omega = c (eta_r - eta_l), and the platform
            origin moves as v_origin = v_Po - omega x p.
        """
        wheels = np.diag(self.signs)  # joint rate = sign * eta
        block = np.vstack([unicycle_rows(self.radius, self.half_track, self.axle_center), wheels])
        return np.array(BASE_V + self.wheel_v), block

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the wheel torques (in the forward-driving sense) enter the generalized forces."""
        return np.array(self.wheel_v), np.diag(self.signs)

    def outline(self) -> np.ndarray:
        half_width = self.half_track - 0.02
        px, py = self.axle_center
        return np.array([[px - 0.25, py - half_width], [px + 0.25, py - half_width],
                         [px + 0.25, py + half_width], [px - 0.25, py + half_width]])  # fmt: skip

    def wheels(self) -> tuple[tuple[str, float], ...]:
        return tuple((name, self.radius) for name in self.wheel_names)

    # ----- the paper's world-frame coordinates, vq = [x_o, y_o, theta_r, theta_l] -----

    def heading(self, theta_r: float, theta_l: float) -> float:
        """Holonomic relation (Eq. 4): phi = c (theta_r - theta_l)."""
        return self.c * (theta_r - theta_l)

    def constraint_matrix_paper(self, phi: float) -> np.ndarray:
        """A(vq) of Eq. 9 (2 x 4): A vq_dot = 0 is no lateral and no longitudinal slip."""
        s, co, cb = np.sin(phi), np.cos(phi), self.c * self.half_track
        return np.array([[-s, co, 0.0, 0.0], [-co, -s, cb, cb]])

    def null_space_paper(self, phi: float) -> np.ndarray:
        """S(vq) of Eq. 10 (4 x 2): vq_dot = S eta, with A S = 0."""
        half_r = self.radius / 2.0
        s, co = np.sin(phi), np.cos(phi)
        return np.array([[half_r * co, half_r * co], [half_r * s, half_r * s], [1.0, 0.0], [0.0, 1.0]])

    def null_space_rate_paper(self, phi: float, eta: np.ndarray) -> np.ndarray:
        """dS/dt along the motion (Eq. 11): dS/dphi * phi_dot with phi_dot = c (eta_r - eta_l)."""
        half_r = self.radius / 2.0
        phi_dot = self.c * (eta[0] - eta[1])
        s, co = np.sin(phi), np.cos(phi)
        d = np.array([[-half_r * s, -half_r * s], [half_r * co, half_r * co], [0.0, 0.0], [0.0, 0.0]])
        return d * phi_dot


class DifferentialDriveKind(PlatformKind):
    name = "differential_drive"
    summary = "two driven wheels on one axle (the paper's platform)"
    wheel_keys = ("right", "left", "radius", "half_track")

    def read_wheels(self, table: Mapping, where: str) -> WheelSpec:
        names = []
        for key in ("right", "left"):
            if key not in table:
                raise SpecError(f"{where} [wheels]: missing key {key!r}")
            if not isinstance(table[key], str):
                raise SpecError(f"{where} [wheels]: {key!r} must be a str, got {table[key]!r}")
            names.append(table[key])
        return WheelSpec(right=names[0], left=names[1], radius=table.get("radius"), half_track=table.get("half_track"))

    def wheels_from_joints(self, joints: Sequence[str]) -> WheelSpec:
        if len(joints) != 2:
            raise WheelError(f"a differential drive takes two wheels, RIGHT,LEFT; got {list(joints)}")
        return WheelSpec(right=joints[0], left=joints[1])

    def build(self, wheels: WheelSpec, description: RobotDescription, model: pin.Model) -> DifferentialDrive:  # type: ignore[override]
        """Wheel radius, half-track, axis signs and axle centre from the URDF geometry."""
        right, left = wheel_geometry(model, (wheels.right, wheels.left), role="wheel")
        for side, geometry in (("right", right), ("left", left)):
            if abs(geometry.axis[1]) < 0.99:  # pragma: no cover - wheel_geometry refuses these
                raise WheelError(f"{side} wheel {geometry.name!r} does not turn about the lateral axis")
        radius = wheels.radius
        if radius is None:
            radii = [radius_of(description, g.name, None) for g in (right, left)]
            if abs(radii[0] - radii[1]) > 1e-9:
                raise WheelError(f"wheel radii differ ({radii[0]} and {radii[1]} m); set [wheels] radius in the spec")
            radius = radii[0]
        if not right.center[1] < left.center[1]:
            raise WheelError(side_by_side_message(wheels.right, wheels.left, right.center[1], left.center[1]))
        half_track = wheels.half_track if wheels.half_track is not None else (left.center[1] - right.center[1]) / 2
        if abs(right.center[0] - left.center[0]) > 1e-6:
            raise WheelError(f"wheels {wheels.right!r} and {wheels.left!r} are not on one axle (x differs)")
        center = (right.center + left.center) / 2
        return DifferentialDrive(
            radius=float(radius),
            half_track=float(half_track),
            wheel_v=(right.v_index, left.v_index),
            signs=(right.sign, left.sign),
            axle_center=(float(center[0]), float(center[1])),
            wheel_names=(wheels.right, wheels.left),
        )

    def detect(self, description: RobotDescription, candidates: Sequence, path: str) -> Detected | None:
        """Two lateral wheels on no swivel (preferring driven ones when there are more)."""
        drive = [c for c in candidates if c.lateral and not c.carried_by_rotating_joint]
        if len(drive) > 2 and sum(c.driven for c in drive) >= 2:
            drive = [c for c in drive if c.driven]
        if not drive or (not any(c.driven for c in drive) and any(c.driven for c in candidates)):
            return None  # no wheels on an axle, or idle ones while a wheel elsewhere is driven
        if len(drive) != 2:
            what = "only one drive wheel" if len(drive) == 1 else f"{len(drive)} possible drive wheels"
            others = [c for c in candidates if c not in drive]
            also = f"; not drive wheels: {', '.join(c.name for c in others)}" if others else ""
            raise WheelError(
                f"{path}: {what}: {', '.join(c.describe() for c in drive)}{also}; "
                "name the pair explicitly (--wheels RIGHT,LEFT) or choose another platform"
            )
        right, left = sorted(drive, key=lambda c: float(c.position[1]))
        if float(left.position[1] - right.position[1]) < 1e-6:
            raise WheelError(
                f"{path}: wheels {right.name!r} and {left.name!r} sit at the same lateral position; "
                "name the pair explicitly (--wheels RIGHT,LEFT)"
            )
        if right.radius is None or left.radius is None:
            size = "radius unknown: mesh geometry; set [wheels] radius"
        elif right.shape == "mesh":
            size = f"radius {right.radius:g} m as given"
        else:
            size = f"radius {right.radius:g} m from the URDF"
        note = f"drive wheels: right {right.name!r}, left {left.name!r} ({size})"
        return Detected(WheelSpec(right=right.name, left=left.name), (note,))

    def toml_lines(self, wheels: WheelSpec) -> list[str]:  # type: ignore[override]
        return self.wheels_section(
            "Right and left drive wheel; radius and half-track are read from the URDF unless set.",
            {"right": wheels.right, "left": wheels.left},
            {"radius": wheels.radius, "half_track": wheels.half_track},
        )


KIND = DifferentialDriveKind()
