"""Skid steer: two or more wheels per side, each side's wheels turning at one speed.

The usual instantaneous-centre model: the platform moves like a differential drive whose
axle passes through the centroid P_c of the wheels, with an *effective* half-track b (by
default half the distance between the sides' mean lateral positions, read from the URDF;
a spec may set a larger one to account for the wheels' lateral slip when turning). With
side rates ``eta = [eta_right, eta_left]`` (rad/s, forward-driving sense):
v = r/2 (eta_r + eta_l) forward at P_c, no lateral velocity at P_c, omega = r/(2b) (eta_r - eta_l),
and every wheel joint of a side turns at (its axis sign) * eta of its side.

Each side is one actuator input: the total torque of its wheels (N m), shared equally between
them, so Q = S^T B = I. A side's limits default from the URDF: its velocity limit is the
smallest of its wheels', its effort limit the sum of its wheels'. The spec's ``[limits.*]``
may set ``right_side`` and ``left_side`` directly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import SpecError, WheelError
from .base import BASE_V, Detected, Platform, PlatformKind, WheelsSpec, unicycle_rows
from .wheels import radius_of, wheel_geometry

if TYPE_CHECKING:
    import pinocchio as pin

    from ..descriptions import RobotDescription

SIDES = ("right_side", "left_side")


@dataclass(frozen=True)
class SkidSteerWheels(WheelsSpec):
    """The spec's ``[wheels]`` of a skid-steer platform.

    Attributes:
        right: wheel joints of the right side.
        left: wheel joints of the left side.
        radius: wheel radius override (m); ``None`` reads it from the URDF geometry.
        half_track: effective half-track override (m); ``None`` takes it from the wheel positions.
    """

    right: tuple[str, ...]
    left: tuple[str, ...]
    radius: float | None = None
    half_track: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "right", tuple(self.right))
        object.__setattr__(self, "left", tuple(self.left))
        if not self.right or not self.left:
            raise SpecError("a skid-steer platform needs at least one wheel on each side")
        self.refuse_repeated(self.right + self.left, "skid-steer")
        self.check_lengths(("wheel radius", self.radius), ("half_track", self.half_track))

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.right + self.left


@dataclass(frozen=True)
class SkidSteer(Platform):
    """A skid-steer base (see the module docstring for the model).

    Attributes:
        radius: wheel radius r (m).
        half_track: effective half-track b (m).
        center: (p_x, p_y) of the wheels' centroid P_c in the platform frame (m).
        wheel_names: right wheels, then left wheels.
        wheel_v: their tangent indices.
        signs: +1 or -1 per wheel: joint rate = sign * eta of its side.
        n_right: how many of ``wheel_names`` are on the right side.
        extent: (x_min, x_max) of the wheel centres in the platform frame (m), for figures.
    """

    radius: float
    half_track: float
    center: tuple[float, float]
    wheel_names: tuple[str, ...]
    wheel_v: tuple[int, ...]
    signs: tuple[float, ...]
    n_right: int
    extent: tuple[float, float]

    kind = "skid_steer"
    scrubs = True

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return SIDES

    @property
    def drive_names(self) -> tuple[str, ...]:
        return SIDES

    def _side_matrix(self, weights: Sequence[float]) -> np.ndarray:
        """(n_wheels, 2): each wheel's row has ``weights[k]`` in its side's column."""
        out = np.zeros((len(self.wheel_names), 2))
        for k, weight in enumerate(weights):
            out[k, 0 if k < self.n_right else 1] = weight
        return out

    def tangent_block(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        base = unicycle_rows(self.radius, self.half_track, self.center)
        block = np.vstack([base, self._side_matrix(self.signs)])
        return np.array(BASE_V + self.wheel_v), block

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        """Each side's torque is shared equally by its wheels (in their joints' own sense)."""
        n_left = len(self.wheel_names) - self.n_right
        shares = [s / (self.n_right if k < self.n_right else n_left) for k, s in enumerate(self.signs)]
        return np.array(self.wheel_v), self._side_matrix(shares)

    def wheels_per_drive(self, name: str) -> int:
        """A side's wheels, geared together."""
        return len(self.side_wheels(name))

    def side_wheels(self, side: str) -> tuple[str, ...]:
        return self.wheel_names[: self.n_right] if side == SIDES[0] else self.wheel_names[self.n_right :]

    def description_limits(self, description: RobotDescription) -> Mapping[str, tuple[float | None, float | None]]:
        return side_limits(description, self.side_wheels(SIDES[0]), self.side_wheels(SIDES[1]))

    def missing_limit_source(self, name: str, kind: str) -> tuple[str, str]:
        wheels = ", ".join(self.side_wheels(name))
        what = "its smallest wheel speed" if kind == "velocity" else "the sum of its wheel torques"
        unit = "rad/s of the wheels" if kind == "velocity" else "N m, the side's total"
        return f"a skid-steer side takes {what}, and some of its wheels ({wheels}) have no <limit {kind}=...>", unit

    def outline(self) -> np.ndarray:
        x0, x1 = self.extent
        px, py = self.center
        margin, half_width = self.radius, self.half_track - 0.02
        return np.array([[x0 - margin, py - half_width], [x1 + margin, py - half_width],
                         [x1 + margin, py + half_width], [x0 - margin, py + half_width]])  # fmt: skip

    def wheels(self) -> tuple[tuple[str, float], ...]:
        return tuple((name, self.radius) for name in self.wheel_names)


def side_limits(
    description: RobotDescription, right: Sequence[str], left: Sequence[str]
) -> dict[str, tuple[float | None, float | None]]:
    """A side turns no faster than its slowest wheel (rad/s) and pushes with all its wheels'
    torque (N m); ``None`` where some wheel of the side has no such limit in the description."""
    out = {}
    for side, wheels in zip(SIDES, (right, left)):
        limits = [description.limits(name) for name in wheels]
        velocities, efforts = [v for v, _ in limits], [e for _, e in limits]
        out[side] = (
            None if None in velocities else min(velocities),  # type: ignore[type-var]
            None if None in efforts else float(sum(efforts)),  # type: ignore[arg-type]
        )
    return out


def _names(table: Mapping, key: str, where: str) -> tuple[str, ...]:
    value = table.get(key)
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise SpecError(f"{where} [wheels]: {key!r} must be a non-empty list of wheel joint names, got {value!r}")
    return tuple(value)


class SkidSteerKind(PlatformKind):
    name = "skid_steer"
    summary = "two or more wheels per side, each side at one speed (e.g. Clearpath's Husky)"
    wheel_keys = ("right", "left", "radius", "half_track")

    def read_wheels(self, table: Mapping, where: str) -> SkidSteerWheels:
        return SkidSteerWheels(
            right=_names(table, "right", where),
            left=_names(table, "left", where),
            radius=table.get("radius"),
            half_track=table.get("half_track"),
        )

    def limit_names(self, wheels) -> tuple[str, ...]:
        return SIDES

    def build(self, wheels: SkidSteerWheels, description: RobotDescription, model: pin.Model) -> SkidSteer:  # type: ignore[override]
        geometry = wheel_geometry(model, wheels.joint_names, role="skid-steer wheel")
        right, left = geometry[: len(wheels.right)], geometry[len(wheels.right) :]
        if max(g.center[1] for g in right) >= min(g.center[1] for g in left):
            raise WheelError(
                f"skid-steer wheels: the right side ({', '.join(wheels.right)}) is not to the right of "
                f"the left side ({', '.join(wheels.left)}); swap them in the spec"
            )
        radius = wheels.radius
        if radius is None:
            radii = {g.name: radius_of(description, g.name, None) for g in geometry}
            if max(radii.values()) - min(radii.values()) > 1e-9:
                raise WheelError(f"skid-steer wheel radii differ ({radii}); set [wheels] radius in the spec")
            radius = next(iter(radii.values()))
        mean_right = float(np.mean([g.center[1] for g in right]))
        mean_left = float(np.mean([g.center[1] for g in left]))
        half_track = wheels.half_track if wheels.half_track is not None else (mean_left - mean_right) / 2
        centres = np.array([g.center[:2] for g in geometry])
        centroid = centres.mean(axis=0)
        return SkidSteer(
            radius=float(radius),
            half_track=float(half_track),
            center=(float(centroid[0]), float(centroid[1])),
            wheel_names=wheels.joint_names,
            wheel_v=tuple(g.v_index for g in geometry),
            signs=tuple(g.sign for g in geometry),
            n_right=len(wheels.right),
            extent=(float(centres[:, 0].min()), float(centres[:, 0].max())),
        )

    def detect(self, description: RobotDescription, candidates: Sequence, path: str) -> Detected | None:
        """Four or more lateral wheels on no swivel, at least two on each side of their centroid,
        each side's on one line along x (lateral positions within 5 % of the track).

        Exactly two driven wheels among them is a differential drive with idle wheels instead.
        """
        lateral = [c for c in candidates if c.lateral and not c.carried_by_rotating_joint]
        if len(lateral) < 4 or sum(c.driven for c in lateral) == 2:
            return None
        middle = float(np.mean([c.position[1] for c in lateral]))
        right = [c for c in lateral if c.position[1] < middle]
        left = [c for c in lateral if c.position[1] > middle]
        if len(right) < 2 or len(left) < 2 or len(right) + len(left) != len(lateral):
            return None
        track = float(np.mean([c.position[1] for c in left]) - np.mean([c.position[1] for c in right]))
        for side in (right, left):  # each side's wheels on one line along x, at distinct x
            ys, xs = [float(c.position[1]) for c in side], [float(c.position[0]) for c in side]
            if max(ys) - min(ys) > 0.05 * track or len({round(x, 6) for x in xs}) != len(xs):
                return None
        radii = {None if c.radius is None else round(c.radius, 9) for c in lateral}
        if len(radii) != 1:
            raise WheelError(
                f"{path}: {len(lateral)} lateral wheels of different radii "
                f"({', '.join(c.describe() for c in lateral)}); set [wheels] radius for a skid_steer platform"
            )
        order = sorted(right, key=lambda c: -float(c.position[0])), sorted(left, key=lambda c: -float(c.position[0]))
        wheels = SkidSteerWheels(right=tuple(c.name for c in order[0]), left=tuple(c.name for c in order[1]))
        note = f"skid-steer wheels: right {', '.join(wheels.right)}; left {', '.join(wheels.left)} " + (
            "(radius unknown: mesh geometry; set [wheels] radius)"
            if lateral[0].radius is None
            else f"(radius {lateral[0].radius:g} m from the URDF)"
        )
        return Detected(wheels, (note,))

    def toml_lines(self, wheels: SkidSteerWheels) -> list[str]:  # type: ignore[override]
        return self.wheels_section(
            "Skid steer: each side's wheels turn at one speed. Radius and the effective half-track are\n"
            "read from the URDF (half the distance between the sides) unless set.",
            {"right": wheels.right, "left": wheels.left},
            {"radius": wheels.radius, "half_track": wheels.half_track},
        )

    limits_by_joint = False

    def description_limits(  # type: ignore[override]
        self, wheels: SkidSteerWheels, description: RobotDescription
    ) -> Mapping[str, tuple[float | None, float | None]]:
        return side_limits(description, wheels.right, wheels.left)


KIND = SkidSteerKind()
