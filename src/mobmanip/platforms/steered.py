"""Steered: a tricycle (forklift-style) base, one steered drive wheel ahead of a rear axle.

The drive wheel turns about its own lateral axis and is steered about a vertical axis through
its centre; the rear wheels roll freely on one axle. No wheel slips. With the drive rate eta
(rad/s, forward-driving sense), its rim speed u = r eta along its heading delta, the steering
point s = (s_x, s_y) and the rear axle at x = a in the platform frame, and the wheelbase
L = s_x - a:

    omega = u sin(delta) / L,   v_x = u cos(delta) + omega s_y,   v_y = -omega a

(the steering point moves at u along its heading; the rear axle line has no lateral velocity),
and each rear wheel turns at its forward speed at its centre over its radius. The reduced
platform velocities are ``[eta, steering joint rate]``; both are driven (Q = I). S depends on
the steering angle delta (a joint of the model), so Sdot = dS/ddelta * ddelta/dt is not zero
while steering: this kind exercises the paper's general constraint layer (Eq. 10-12).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..errors import SpecError, WheelError
from .base import BASE_V, Detected, Platform, PlatformKind, WheelsSpec
from .wheels import LATERAL, ON_AXIS, radius_of, wheel_geometry

if TYPE_CHECKING:
    from ..descriptions import RobotDescription


@dataclass(frozen=True)
class SteeredWheels(WheelsSpec):
    """The spec's ``[wheels]`` of a steered base.

    Attributes:
        drive: the driven wheel's joint (it spins about its lateral axis).
        steer: the steering joint above it (vertical axis through the wheel's centre).
        rear: the free-rolling rear wheels' joints, on one axle.
        radius: drive wheel radius override (m); ``None`` reads the URDF geometry.
        rear_radius: rear wheel radius override (m); ``None`` reads the URDF geometry.
    """

    drive: str
    steer: str
    rear: tuple[str, ...]
    radius: float | None = None
    rear_radius: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "rear", tuple(self.rear))
        if not self.rear:
            raise SpecError("a steered base needs its rear wheels ([wheels] rear = [...])")
        self.refuse_repeated(self.joint_names, "steered-base")
        self.check_lengths(("wheel radius", self.radius), ("rear wheel radius", self.rear_radius))

    @property
    def joint_names(self) -> tuple[str, ...]:
        return (self.drive, self.steer) + self.rear


@dataclass(frozen=True)
class Steered(Platform):
    """A tricycle base (see the module docstring for the model).

    Attributes:
        radius: drive wheel radius r (m).
        rear_radius: rear wheel radius (m).
        steer_point: (s_x, s_y), the steering axis in the platform frame (m).
        rear_x: x of the rear axle in the platform frame (m).
        rear_y: lateral positions of the rear wheels (m).
        drive_name, steer_name: the drive wheel's and the steering joint's names.
        rear_names: the rear wheels' joint names.
        drive_v, steer_v, rear_v: their tangent indices.
        steer_q: index of the steering angle in q (its cosine for a continuous joint).
        steer_continuous: whether the steering joint is continuous ((cos, sin) in q).
        drive_sign: +1 if a positive drive joint rate rolls forward at delta = 0, else -1.
        steer_sign: +1 if the steering joint turns about +z, else -1 (delta = sign * angle).
        rear_signs: +1 or -1 per rear wheel.
    """

    radius: float
    rear_radius: float
    steer_point: tuple[float, float]
    rear_x: float
    rear_y: tuple[float, ...]
    drive_name: str
    steer_name: str
    rear_names: tuple[str, ...]
    drive_v: int
    steer_v: int
    rear_v: tuple[int, ...]
    steer_q: int
    steer_continuous: bool
    drive_sign: float
    steer_sign: float
    rear_signs: tuple[float, ...]

    kind = "steered"
    varies_with_q = True

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return (self.drive_name, self.steer_name)

    @property
    def drive_names(self) -> tuple[str, ...]:
        return (self.drive_name,)

    @property
    def wheelbase(self) -> float:
        return self.steer_point[0] - self.rear_x

    def steering_angle(self, q: np.ndarray) -> float:
        """delta: the drive wheel's heading from the platform's x axis (rad)."""
        if self.steer_continuous:
            angle = math.atan2(q[self.steer_q + 1], q[self.steer_q])
        else:
            angle = float(q[self.steer_q])
        return self.steer_sign * angle

    def _rows(self) -> np.ndarray:
        return np.array(BASE_V + (self.drive_v, self.steer_v) + self.rear_v)

    def _drive_column(self, c: float, s: float) -> np.ndarray:
        """Rates of (v_x, v_y, omega, drive, steer, rear...) per unit eta at cos/sin of delta
        (the same formula, with the derivative's c, s, gives dS/ddelta when ``linear``)."""
        r, L = self.radius, self.wheelbase
        sx, sy = self.steer_point
        omega = r * s / L
        vx = r * c + omega * sy
        rear = [sign * (vx - omega * y) / self.rear_radius for sign, y in zip(self.rear_signs, self.rear_y)]
        return np.array([vx, -omega * self.rear_x, omega, self.drive_sign, 0.0, *rear])

    def tangent_block(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        if q is None:
            raise WheelError("a steered base's S depends on the configuration; give q")
        delta = self.steering_angle(q)
        block = np.zeros((len(self._rows()), 2))
        block[:, 0] = self._drive_column(math.cos(delta), math.sin(delta))
        block[4, 1] = 1.0  # the steering joint turns at its own reduced rate
        return self._rows(), block

    def tangent_block_rate(self, q: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """dS/dt = dS/ddelta * ddelta/dt, ddelta/dt = steer_sign * (steering rate, x[1])."""
        delta = self.steering_angle(q)
        delta_rate = self.steer_sign * float(x[1])
        block = np.zeros((len(self._rows()), 2))
        derivative = self._drive_column(-math.sin(delta), math.cos(delta))
        derivative[3] = 0.0  # the drive joint's row is constant
        block[:, 0] = derivative * delta_rate
        return self._rows(), block

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([self.drive_v, self.steer_v]), np.diag([self.drive_sign, 1.0])

    def outline(self) -> np.ndarray:
        sx, _ = self.steer_point
        half = max(abs(y) for y in self.rear_y) - 0.02
        return np.array([[self.rear_x - 0.1, -half], [sx + 0.1, -half], [sx + 0.1, half], [self.rear_x - 0.1, half]])

    def wheels(self) -> tuple[tuple[str, float], ...]:
        return ((self.drive_name, self.radius),) + tuple((n, self.rear_radius) for n in self.rear_names)

    def free_rolling(self) -> dict[str, tuple[float, float]]:
        """The rear wheels, rolling along the platform's x axis (their axle is across it)."""
        return {name: (1.0, 0.0) for name in self.rear_names}


def _name(table: Mapping, key: str, where: str) -> str:
    value = table.get(key)
    if not isinstance(value, str):
        raise SpecError(f"{where} [wheels]: {key!r} must be a joint name, got {value!r}")
    return value


class SteeredKind(PlatformKind):
    name = "steered"
    summary = "a tricycle: one steered drive wheel ahead of a free rear axle (S depends on q)"
    wheel_keys = ("drive", "steer", "rear", "radius", "rear_radius")

    def read_wheels(self, table: Mapping, where: str) -> SteeredWheels:
        rear = table.get("rear")
        if not isinstance(rear, list) or not rear or not all(isinstance(v, str) for v in rear):
            raise SpecError(f"{where} [wheels]: 'rear' must be a non-empty list of wheel joint names, got {rear!r}")
        return SteeredWheels(
            drive=_name(table, "drive", where),
            steer=_name(table, "steer", where),
            rear=tuple(rear),
            radius=table.get("radius"),
            rear_radius=table.get("rear_radius"),
        )

    def build(self, wheels: SteeredWheels, description: RobotDescription, model: pin.Model) -> Steered:  # type: ignore[override]
        drive, *rear = wheel_geometry(model, (wheels.drive, *wheels.rear), role="steered-base wheel")
        steer_id = model.getJointId(wheels.steer)
        steer_joint = model.joints[steer_id]
        if steer_joint.nv != 1:
            raise WheelError(f"steering joint {wheels.steer!r} has {steer_joint.nv} degrees of freedom; expected 1")
        data = model.createData()
        pin.computeJointJacobians(model, data, pin.neutral(model))
        axis = pin.getJointJacobian(model, data, steer_id, pin.LOCAL_WORLD_ALIGNED)[3:, steer_joint.idx_v]
        if abs(axis[2]) < LATERAL:
            raise WheelError(f"steering joint {wheels.steer!r} turns about {np.round(axis, 3).tolist()}; expected +-z")
        pivot = data.oMi[steer_id].translation
        if float(np.linalg.norm(pivot[:2] - drive.center[:2])) > ON_AXIS:
            raise WheelError(
                f"drive wheel {wheels.drive!r} is not on the steering axis of {wheels.steer!r} "
                f"(offset {np.round(drive.center[:2] - pivot[:2], 4).tolist()} m); a caster offset is not modelled"
            )
        xs = [g.center[0] for g in rear]
        if max(xs) - min(xs) > 1e-6:
            raise WheelError(f"rear wheels {', '.join(wheels.rear)} are not on one axle (x differs: {xs})")
        if abs(drive.center[0] - xs[0]) < 1e-6:
            raise WheelError(f"drive wheel {wheels.drive!r} is on the rear axle; a steered base needs a wheelbase")
        rear_radii = {g.name: radius_of(description, g.name, wheels.rear_radius) for g in rear}
        if max(rear_radii.values()) - min(rear_radii.values()) > 1e-9:
            raise WheelError(f"rear wheel radii differ ({rear_radii}); set [wheels] rear_radius in the spec")
        return Steered(
            radius=radius_of(description, wheels.drive, wheels.radius),
            rear_radius=next(iter(rear_radii.values())),
            steer_point=(float(drive.center[0]), float(drive.center[1])),
            rear_x=float(xs[0]),
            rear_y=tuple(float(g.center[1]) for g in rear),
            drive_name=wheels.drive,
            steer_name=wheels.steer,
            rear_names=tuple(wheels.rear),
            drive_v=drive.v_index,
            steer_v=steer_joint.idx_v,
            rear_v=tuple(g.v_index for g in rear),
            steer_q=steer_joint.idx_q,
            steer_continuous=steer_joint.nq == 2,
            drive_sign=drive.sign,
            steer_sign=1.0 if axis[2] > 0 else -1.0,
            rear_signs=tuple(g.sign for g in rear),
        )

    def detect(self, description: RobotDescription, candidates: Sequence, path: str) -> Detected | None:
        """One driven wheel on a vertical steering joint through its centre (a steered drive unit,
        not a caster), and free lateral wheels on one axle."""
        steered = [c for c in candidates if c.steered_unit and c.driven]
        rear = [c for c in candidates if c.lateral and not c.carried_by_rotating_joint and not c.driven]
        if len(steered) != 1 or len(rear) < 1:
            return None
        if len({round(float(c.position[0]), 6) for c in rear}) != 1:
            return None
        drive = steered[0]
        wheels = SteeredWheels(drive=drive.name, steer=drive.steering_joint, rear=tuple(c.name for c in rear))
        note = f"steered base: drive wheel {drive.name!r} on steering joint {drive.steering_joint!r}; rear wheels " + (
            ", ".join(wheels.rear)
        )
        return Detected(wheels, (note,))

    def toml_lines(self, wheels: SteeredWheels) -> list[str]:  # type: ignore[override]
        return self.wheels_section(
            "Steered base: the drive wheel, its steering joint and the free rear wheels (one axle).",
            {"drive": wheels.drive, "steer": wheels.steer, "rear": wheels.rear},
            {"radius": wheels.radius, "rear_radius": wheels.rear_radius},
        )


KIND = SteeredKind()
