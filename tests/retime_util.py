"""The Panda's sine path and TOPP-RA's own fastest timing of it: the reference that
``tests/test_retime.py`` checks ``mobmanip.motion.retime`` against, and that
``scripts/benchmark_retime.py`` times beside it (the same problem both ways).
"""

from __future__ import annotations

import math

import numpy as np

#: Amplitude of each of the Panda's seven joints on the sine path (rad).
AMPLITUDE = np.array([0.8, 0.5, 0.6, 0.5, 0.9, 0.6, 1.0])


def arm_indices(robot) -> tuple[list[int], list[int]]:
    """The configuration and velocity indices of the robot's reduced velocities' joints."""
    model = robot.model
    ids = [model.getJointId(name) for name in robot.reduced_velocity_names]
    return [model.joints[j].idx_q for j in ids], [model.joints[j].idx_v for j in ids]


def sine_path(robot, n: int):
    """q(s) = home + A sin(pi s) on the arm's joints, s in [0, 1] (n samples), with its exact
    derivatives: s, q, dx/ds, d2x/ds2."""
    iq, _ = arm_indices(robot)
    home = robot.hold_configuration()
    s = np.linspace(0.0, 1.0, n)
    w = math.pi
    q = np.tile(home, (n, 1))
    q[:, iq] = home[iq] + AMPLITUDE * np.sin(w * s)[:, None]
    x_s = AMPLITUDE * (w * np.cos(w * s))[:, None]
    x_ss = AMPLITUDE * (-w * w * np.sin(w * s))[:, None]
    return s, q, x_s, x_ss


def toppra_duration(home, s, velocity, effort, inverse_dynamics, discretization: str = "interpolation") -> float:
    """TOPP-RA's fastest timing of x(s) = home + A sin(pi s) on the grid s, within the joint
    velocity and effort limits, its torque rows from ``inverse_dynamics(x, xdot, xddot)``."""
    import toppra
    from toppra import algorithm, constraint

    class SinePath(toppra.interpolator.AbstractGeometricPath):
        def __call__(self, ss, order=0):
            ss = np.atleast_1d(np.asarray(ss, dtype=float))
            w = math.pi
            if order == 0:
                return home + AMPLITUDE * np.sin(w * ss)[:, None]
            if order == 1:
                return AMPLITUDE * (w * np.cos(w * ss))[:, None]
            return AMPLITUDE * (-w * w * np.sin(w * ss))[:, None]

        @property
        def dof(self):
            return len(AMPLITUDE)

        @property
        def path_interval(self):
            return np.array([0.0, 1.0])

        @property
        def waypoints(self):
            return None

    limits = [
        constraint.JointVelocityConstraint(np.c_[-velocity, velocity]),
        constraint.JointTorqueConstraint(
            inverse_dynamics,
            np.c_[-effort, effort],
            np.zeros(len(AMPLITUDE)),
            discretization_scheme=getattr(constraint.DiscretizationType, discretization.capitalize()),
        ),
    ]
    solver = algorithm.TOPPRA(limits, SinePath(), gridpoints=s, parametrizer="ParametrizeConstAccel")
    return solver.compute_trajectory(0, 0).duration
