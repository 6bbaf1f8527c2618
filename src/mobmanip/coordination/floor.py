"""A team on its floor while it carries: every robot's floor rows over the team's step.

Robot i's floor wrench (force, and moment about the world origin, world axes) is what the floor
must supply for its own motion and for what its hands do to the object: its momentum rate less
its weight (:func:`mobmanip.motion.ground.floor_wrench` with no object of its own) plus the
wrenches its hands apply to the object (the object pushes back on the hands as hard; the floor
holds that too). The hands' wrenches are the team's least-norm share of the object's load
(:func:`mobmanip.coordination.effort.team_step_maps`), affine in the team's reduced velocities;
where the task leaves the vertical row out (a planar task), the object's weight is shared equally
by the hands as a vertical force. Each robot's wrench is therefore affine in the team's step x,
and its rows are the floor of motion's own
(:class:`mobmanip.terms.constraints.floor_wrench.FloorRows`, through
:meth:`mobmanip.motion.carry_floor.CarryFloor.rows`): the zero-moment point a margin inside its
support polygon, every support at least its reserve (a share of the robot's weight and an equal
share of the object's), every wheel within friction; a skid-steer keeps its heading.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..motion.carry_floor import NO_TURN, CarryFloor, turning_row
from ..motion.ground import floor_wrench
from ..robot.support import Support, polygon_margin
from ..robot.tasks import TaskSpace
from ..team import Team
from ..terms.constraints.floor_wrench import FloorRows, to_platform
from ..terms.grasp import GRAVITY, HeldObject, wrench_shift

__all__ = ["TeamFloor"]


@dataclass(frozen=True)
class TeamFloor:
    """The floor every robot of a team keeps (see the module's docstring).

    Attributes:
        floor: the floor's settings, one for every robot (its mu ``"spec"``: each robot's own).
        rows: each robot's rows over its own floor wrench, in the team's order.
        resolved: each robot's (support, friction coefficient, faces) (:meth:`CarryFloor.resolve`).
    """

    floor: CarryFloor
    rows: tuple[FloorRows, ...]
    resolved: tuple[tuple[Support, float | None, int], ...]

    @classmethod
    def build(cls, team: Team, floor: CarryFloor) -> TeamFloor:
        """The rows of every robot of ``team`` on ``floor``.

        Raises:
            ArgumentError: a ramp (a team's object and its weight are modelled on a level floor).
            SpecError, ArgumentError: a robot that does not stand on wheels, or whose support
                polygon cannot keep the margin (:meth:`CarryFloor.resolve`).
        """
        if not isinstance(floor, CarryFloor):
            raise ArgumentError(f"floor must be a CarryFloor, got {type(floor).__name__}")
        if floor.slope:
            raise ArgumentError(
                f"a team carries on a level floor: the slope {floor.slope:g} deg is modelled for one robot "
                "(carry, retime), not for a team's shared object"
            )
        share = team.held_object.mass / len(team.members)
        resolved = tuple(floor.resolve(m.robot) for m in team.members)
        rows = tuple(floor.rows(m.robot, share, r) for m, r in zip(team.members, resolved))
        return cls(floor, rows, resolved)

    def wrenches(
        self,
        team: Team,
        qs: Sequence[np.ndarray],
        x_prev: np.ndarray,
        h: float,
        task: TaskSpace,
        held: HeldObject,
        hand_wrenches: tuple[np.ndarray, np.ndarray],
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """Each robot's floor wrench over the team's step, (w0 (6,), w1 (6, nx)) with
        wrench = w0 + w1 x (see the module's docstring).

        Args:
            team, qs: the team and each robot's configuration.
            x_prev: the team's reduced velocity over the previous step, (nx,); h: the step (s).
            task: the team's task; held: the object as it is held now.
            hand_wrenches: the hands' wrenches on the object over the step, (F, f0)
                (:attr:`mobmanip.coordination.effort.TeamStepMaps.hand_wrenches`).
        """
        F, f0 = hand_wrenches
        m, nx, rows = task.dim, len(x_prev), list(task.rows)
        place = np.zeros((6, m))  # a hand's wrench on the task's rows, as a 6-D one
        place[rows, np.arange(m)] = 1.0
        hands = held.center + held.offsets
        weight = np.zeros(6)
        if 2 not in rows:  # the object's weight, shared equally by the hands
            weight[2] = -held.mass * GRAVITY[2] / len(hands)
        out, hand = [], 0
        for member, q, s in zip(team.members, qs, team.member_slices()):
            robot = member.robot
            offset, linear = floor_wrench(robot, q, x_prev[s], 0.0, np.zeros(6), np.zeros((6, robot.nx)))
            w1 = np.zeros((6, nx))
            w1[:, s] = linear / h
            w0 = offset - linear @ x_prev[s] / h
            for _ in member.arms:  # the hand's wrench on the object, its moment about the world origin
                about = wrench_shift(hands[hand])
                block = slice(hand * m, (hand + 1) * m)
                w1 += about @ place @ F[block]
                w0 += about @ (place @ f0[block] + weight)
                hand += 1
            out.append((w0, w1))
        return out

    def step_rows(
        self, team: Team, qs: Sequence[np.ndarray], wrenches: list[tuple[np.ndarray, np.ndarray]]
    ) -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
        """Every robot's floor rows over the team's step, ``G x <= g``, with one label per row
        (``"ROBOT: what it keeps"``) and its kind (``"tip-over"``, ``"contact"``, ``"traction"`` or
        ``"no turn"``)."""
        G, g, labels, kinds = [], [], [], []
        for member, q, s, rows, (w0, w1) in zip(team.members, qs, team.member_slices(), self.rows, wrenches):
            R, r = rows.at(q)
            G.append(R @ w1)
            g.append(r - R @ w0)
            labels += [f"{member.name}: {label}" for label in rows.labels]
            kinds += list(rows.kinds)
            turn = turning_row(member.robot, q)
            if turn is not None:  # a skid-steer keeps its heading: both senses of its turn rate at zero
                row = np.zeros((2, w1.shape[1]))
                row[0, s], row[1, s] = turn, -turn
                G.append(row)
                g.append(np.zeros(2))
                labels += [f"{member.name}: {NO_TURN}"] * 2
                kinds += ["no turn"] * 2
        return np.vstack(G), np.concatenate(g), labels, kinds

    def readings(
        self, team: Team, qs: Sequence[np.ndarray], wrenches: list[tuple[np.ndarray, np.ndarray]], x: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each robot's zero-moment point margin to its support polygon (m; negative outside) and
        its wheels' largest traction use ``|f_t| / (mu f_n)`` (NaN without a friction
        coefficient) over a step x, (k,) each."""
        margin, use = np.zeros(len(qs)), np.full(len(qs), np.nan)
        for i, (q, rows, (support, mu, _), (w0, w1)) in enumerate(zip(qs, self.rows, self.resolved, wrenches)):
            wrench = w0 + w1 @ x
            force, moment, z = wrench[:3], wrench[3:], support.floor_z
            zmp = np.array([(z * force[0] - moment[1]) / force[2], (moment[0] + z * force[1]) / force[2]])
            pose = (float(q[0]), float(q[1]), float(np.arctan2(q[3], q[2])))
            margin[i] = polygon_margin(support.polygon(pose), zmp)
            if mu is not None and rows.sharing.traction is not None:
                use[i] = float(np.max(rows.sharing.loads(to_platform(q) @ wrench, mu)[2], initial=0.0))
        return margin, use
