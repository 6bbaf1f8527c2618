"""Platform constraint layer: the null-space matrix S that maps reduced velocities to joint rates.

A platform contributes the first columns of the whole robot's S (nv x nx): the reduced platform
velocities ``eta`` and how they move the planar root joint and the wheel joints. The arms add
identity columns after them (see :mod:`mobmanip.model`).

Pinocchio's planar root joint has velocity (v_x, v_y, omega_z) expressed in the platform's own
frame, so for a differential drive the no-slip constraints are constant in those coordinates and
S does not depend on q. The paper's world-frame form (Eq. 7-10) is kept alongside for reference
and testing: ``vq = [x_o, y_o, theta_r, theta_l]``, heading ``phi = c (theta_r - theta_l)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Tangent indices of the planar root joint (v_x, v_y, omega_z in the platform frame).
BASE_V = (0, 1, 2)


@dataclass(frozen=True)
class DifferentialDrive:
    """Two driven wheels on one axle; no lateral and no longitudinal slip.

    The reduced velocity is ``eta = [eta_r, eta_l]``, the wheel rates (rad/s) in the sense that
    drives the platform forward; ``signs`` converts them to the URDF joints' own sense.

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
    def n_reduced(self) -> int:
        return 2

    @property
    def actuated(self) -> tuple[bool, ...]:
        """Each reduced platform velocity is driven by a motor."""
        return (True, True)

    def tangent_block(self) -> tuple[np.ndarray, np.ndarray]:
        """Rows of S for the platform coordinates.

        Returns:
            ``(v_indices, block)``: the tangent indices (root joint, then wheels) and the
            (5, 2) block that maps eta to them. With P_o at (p_x, p_y) in the platform frame,
            v = r/2 (eta_r + eta_l) forward at P_o, omega = c (eta_r - eta_l), and the platform
            origin moves as v_origin = v_Po - omega x p.
        """
        r, c = self.radius, self.c
        px, py = self.axle_center
        block = np.array(
            [
                [r / 2 + py * c, r / 2 - py * c],  # v_x of the platform origin
                [-px * c, px * c],  # v_y of the platform origin
                [c, -c],  # omega_z
                [self.signs[0], 0.0],  # right wheel joint rate
                [0.0, self.signs[1]],  # left wheel joint rate
            ]
        )
        return np.array(BASE_V + self.wheel_v), block

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the wheel torques (in the forward-driving sense) enter the generalized forces."""
        return np.array(self.wheel_v), np.diag(self.signs)

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


@dataclass(frozen=True)
class LockedPlatform:
    """A platform that does not move: the fixed multi-arm system the paper compares against."""

    kind = "fixed"

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return ()

    @property
    def n_reduced(self) -> int:
        return 0

    @property
    def actuated(self) -> tuple[bool, ...]:
        return ()

    def tangent_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(0, dtype=int), np.zeros((0, 0))

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(0, dtype=int), np.zeros((0, 0))


@dataclass(frozen=True)
class Omnidirectional:
    """A holonomic base: (v_x, v_y, omega_z) in the platform frame are all free and driven.

    The reduced platform velocity is the root joint's own velocity, so S is the identity on the
    base coordinates. Limits are planar speeds (m/s, rad/s) and forces/torque (N, N m).
    """

    kind = "omnidirectional"

    @property
    def reduced_names(self) -> tuple[str, ...]:
        return ("base_x", "base_y", "base_yaw")

    @property
    def n_reduced(self) -> int:
        return 3

    @property
    def actuated(self) -> tuple[bool, ...]:
        return (True, True, True)

    def tangent_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(BASE_V), np.eye(3)

    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(BASE_V), np.eye(3)


Platform = DifferentialDrive | LockedPlatform | Omnidirectional
