"""Each platform follows the object: a soft task of the team's carry QP.

A differential drive cannot move sideways, and a one-step QP does not plan ahead: when the
object turns, the hands of a robot at its far end move across that robot's heading, and with
only the hands constrained the arms take that motion until a joint reaches the end of its range
(the beam example failed this way 4 s into its turn). So each robot's platform is given a task
of its own, weighted below the hands' equality: a *control point* at distance ``l`` from the
wheel axle's midpoint along the heading, on the side the robot travels towards, follows where
the object would carry it if the point were fixed to the object::

    p_i* (t) = c(t) + R(t) (p_i(0) - c(0))      (c, R: the object's centre and turn along the path)

with feedback, v_i* = (p_i*(t_k+1) - p_i*(t_k)) / dt + K (p_i*(t_k) - p_i(t_k)); the QP's cost gains
``beta / 2 |J_p,i x_i - v_i*|^2``. An off-axle point of a differential drive moves in any
direction (its velocity is R(theta) (v, omega l) with forward speed v and turning rate omega),
and a platform whose leading point follows a path turns with it like a trailer, so the heading
follows the path's curvature and the arms absorb only the difference between the robot's
heading and the object's. beta is :data:`PLATFORM_WEIGHT` over the platform's top forward speed
squared: a control point off its velocity by that speed costs :data:`PLATFORM_WEIGHT` times a
wheel at its velocity limit. The task only asks the platforms to move with the object; the hands'
equality, the limits and the capacity term are unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..team import Team

__all__ = ["CONTROL_DISTANCE", "PLATFORM_GAIN", "PLATFORM_WEIGHT", "PlatformTask"]

#: Distance of each platform's control point from its axle's midpoint (m).
CONTROL_DISTANCE = 0.5
#: Weight of the platform task relative to a wheel at its velocity limit.
PLATFORM_WEIGHT = 1.0
#: Feedback gain of the control point's position error (1/s).
PLATFORM_GAIN = 2.0


def _pose(robot, q: np.ndarray) -> tuple[np.ndarray, float, int]:
    root = robot.model.joints[1]
    block = q[root.idx_q : root.idx_q + 4]
    return block[:2].copy(), float(np.arctan2(block[3], block[2])), root.idx_v


class PlatformTask:
    """The platforms' soft task along one run (see the module's docstring).

    Args:
        team: the team; qs0: each robot's configuration at the run's start.
        center: the object's centre at each step, (N, 3); turns: its turn from the start, (N,).
    """

    def __init__(self, team: Team, qs0: Sequence[np.ndarray], center: np.ndarray, turns: np.ndarray):
        self.team = team
        self.center = np.asarray(center, dtype=float)[:, :2]
        self.turns = np.asarray(turns, dtype=float)
        self.active: list[bool] = []
        self.distance: list[float] = []
        self.start: list[np.ndarray] = []
        self.beta: list[float] = []
        for member, q in zip(team.members, qs0):
            robot = member.robot
            planar = robot.model.joints[1].shortname() == "JointModelPlanar" and robot.platform.n_reduced > 0
            if not planar:
                self.active.append(False)
                self.distance.append(0.0)
                self.start.append(np.zeros(2))
                self.beta.append(0.0)
                continue
            position, heading, idx_v = _pose(robot, q)
            # the side the robot travels towards: where the axle's midpoint, carried with the object, goes first
            axle = self._carried(position, 0)
            moved = [self._carried(position, k) - axle for k in range(len(self.turns))]
            far = next((d for d in moved if np.linalg.norm(d) > 1e-3), None)
            forward = np.array([np.cos(heading), np.sin(heading)])
            sign = 1.0 if far is None or float(forward @ far) >= 0.0 else -1.0
            distance = sign * CONTROL_DISTANCE
            self.distance.append(distance)
            self.start.append(position + distance * forward)
            S = robot.null_space(q)
            speed = float(np.abs(S[idx_v]) @ np.asarray(robot.velocity_limits, dtype=float))
            self.beta.append(PLATFORM_WEIGHT / speed**2 if speed > 0 else 0.0)
            self.active.append(far is not None and speed > 0)

    def _carried(self, point: np.ndarray, k: int) -> np.ndarray:
        c, s = np.cos(self.turns[k]), np.sin(self.turns[k])
        R = np.array([[c, -s], [s, c]])
        return self.center[k] + R @ (point - self.center[0])

    def target(self, i: int, k: int) -> np.ndarray:
        """Robot i's control point target at step k (m), (2,)."""
        return self._carried(self.start[i], k)

    def point(self, i: int, q: np.ndarray) -> np.ndarray:
        """Robot i's control point at configuration q (m), (2,)."""
        position, heading, _ = _pose(self.team.members[i].robot, q)
        return position + self.distance[i] * np.array([np.cos(heading), np.sin(heading)])

    def cost(self, qs: Sequence[np.ndarray], k: int, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(H_p, c_p): the task's quadratic and linear cost over the team's x at step k."""
        nx = self.team.nx
        H = np.zeros((nx, nx))
        c = np.zeros(nx)
        for i, (member, q, s) in enumerate(zip(self.team.members, qs, self.team.member_slices())):
            if not self.active[i]:
                continue
            robot = member.robot
            _, heading, idx_v = _pose(robot, q)
            S = robot.null_space(q)
            local = np.vstack([S[idx_v], self.distance[i] * S[idx_v + 2]])  # (v, omega l) in the platform's frame
            ch, sh = np.cos(heading), np.sin(heading)
            J = np.array([[ch, -sh], [sh, ch]]) @ local
            goal = self.target(i, k)
            wanted = (self.target(i, k + 1) - goal) / h + PLATFORM_GAIN * (goal - self.point(i, q))
            H[s, s] += self.beta[i] * J.T @ J
            c[s] -= self.beta[i] * J.T @ wanted
        return H, c
