"""The floor over its resultant wrench: how the contacts share it, and the rows that keep a robot
on it while it moves.

This is the one home of the floor of motion. ``carry``'s steps, ``retime``'s grid points,
``trajectory --ground``'s readings, ``hold``'s replays and ``team-carry``'s steps all take the
floor's resultant wrench on the robot (and what it holds) and read it through this module; the
floor at rest of the capacity sets (:class:`mobmanip.terms.constraints.floor.Floor`) keeps the
contacts' forces as variables of its programs, and shares them by the same two rules
(:func:`~mobmanip.terms.constraints.floor.compliant_sharing`, the least-norm split of the
tangential forces), so standing still both give the same verdict, zero-moment point and loads.

The wrench is (F, M): the floor's force on the robot and its moment, about the platform's origin
in the platform's axes (:func:`to_platform` turns a world wrench about the world origin into it).
With the floor at height z_f, F_z times the zero-moment point is N = (z_f F_x - M_y, M_x + z_f F_y).

- **Normal forces** (:class:`WrenchSharing`): equally stiff contacts (or of the spec's relative
  stiffness) under a rigid platform, so the normal forces are affine in the contacts' positions;
  the balance (F_z, N) and the sharing equations fix them: a linear map of the wrench.
- **Tangential forces**: casters are frictionless, so the contacts the floor may push along
  carry (F_x, F_y, M_z): a wheel with a motor both ways along both floor axes (its rolling force
  is its torque's, its sideways one a constraint force), a mecanum wheel only across its rollers,
  a free-rolling wheel (a tricycle's rear wheels) only across its rolling direction
  (:func:`traction_components`). Equally stiff tyres under a rigid platform share them by the
  least-norm split (a differential drive's two wheels: half the lateral force each).
- **Rows** (:class:`FloorRows`): the zero-moment point a margin inside the support polygon, every
  support at least its reserve's share of the weight, every traction within its friction (the
  pyramid of ``faces`` faces inscribed in the cone for a wheel pushed both ways, the segment for
  one pushed one way), scaled by 1 - reserve. Each row carries its kind: ``"tip-over"``,
  ``"contact"`` or ``"traction"``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...errors import SpecError
from ...platforms.base import BASE_V
from ...robot.support import Support
from .floor import compliant_sharing, pyramid_faces

if TYPE_CHECKING:
    from ...robot.model import Robot

__all__ = [
    "NO_TURN",
    "UNLOADED",
    "FloorRows",
    "WrenchSharing",
    "both_ways",
    "to_platform",
    "traction_components",
    "turning_row",
]

#: A normal force at or below this (N) is a contact that unloads: its traction use is +inf.
UNLOADED = 1e-9

#: Why a base whose wheels scrub as it turns keeps its heading on the floor.
NO_TURN = "no turn: a skid-steer turns only by sliding its wheels sideways, and on the floor no wheel slides"


def to_platform(q: np.ndarray) -> np.ndarray:
    """(6, 6) turning a wrench [force; moment about the world origin] in world axes into the
    platform's: [force; moment about the platform's origin] in its axes, the platform at ``q``
    (x, y, cos, sin first)."""
    c, s = float(q[2]), float(q[3])
    norm = math.hypot(c, s)
    c, s = c / norm, s / norm
    x, y = float(q[0]), float(q[1])
    turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # world to platform axes
    origin = np.array([[0.0, 0.0, y], [0.0, 0.0, -x], [-y, x, 0.0]])  # M_p = M_O - p x F
    T = np.zeros((6, 6))
    T[:3, :3] = turn
    T[3:, 3:] = turn
    T[3:, :3] = -turn @ origin
    return T


def traction_components(robot: Robot, support: Support) -> list[tuple[int, np.ndarray]]:
    """The floor's tangential force components the contacts take, as (contact index, unit
    direction in the platform frame): both axes for a wheel the floor may push any way along the
    floor (a driven wheel's rolling force is its torque's, its sideways one a constraint force);
    only the direction across a free direction for a mecanum wheel's rollers (``[support]
    rollers``) or a wheel rolling free (:meth:`~mobmanip.platforms.base.Platform.free_rolling`,
    a steered base's rear wheels); none for a caster."""
    rolling = robot.platform.free_rolling()
    out = []
    for c, contact in enumerate(support.contacts):
        if not contact.driven:
            continue
        free = contact.free if contact.free is not None else rolling.get(contact.name)
        if free is None:
            out += [(c, np.array([1.0, 0.0])), (c, np.array([0.0, 1.0]))]
        else:
            out.append((c, np.array([-free[1], free[0]]) / math.hypot(free[0], free[1])))
    return out


def both_ways(driven) -> list[tuple[int, np.ndarray]]:
    """Tangential components (as :func:`traction_components`) for contacts pushed any way along
    the floor: both axes of each contact whose flag in ``driven`` (n,) is set, none for the others."""
    axes = (np.array([1.0, 0.0]), np.array([0.0, 1.0]))
    return [(int(c), axis) for c in np.flatnonzero(np.asarray(driven, dtype=bool)) for axis in axes]


def turning_row(robot: Robot, q: np.ndarray) -> np.ndarray | None:
    """The base's turn rate as a row over the reduced velocities (rad/s per unit of x), (nx,),
    for a platform whose wheels scrub as it turns (a skid-steer's); ``None`` for the others, which
    turn on rolling wheels."""
    if not robot.platform.scrubs:
        return None
    return np.asarray(robot.null_space(q)[BASE_V[2]], dtype=float).copy()


@dataclass(frozen=True)
class WrenchSharing:
    """How the contacts share the floor's resultant wrench (see the module's docstring): linear
    maps of the wrench, in the frame of the contacts' points (the platform's for :meth:`build`).

    Attributes:
        points: the contacts' floor points (m), (n, 2).
        normal: (n, 6): every contact's normal force (N) per unit of wrench.
        components: the tangential components, (contact index, unit direction) each
            (:func:`traction_components`).
        traction: (k, 6): each component's force (N) per unit of wrench; ``None`` when the
            contacts cannot carry (F_x, F_y, M_z) together (``problem`` says why).
        problem: why ``traction`` is ``None``, else ``""``.
    """

    points: np.ndarray
    normal: np.ndarray
    components: tuple[tuple[int, np.ndarray], ...]
    traction: np.ndarray | None
    problem: str = ""

    @classmethod
    def build(cls, robot: Robot, support: Support) -> WrenchSharing:
        """The sharing of ``robot`` standing on ``support``, in the platform's frame."""
        names = [contact.name for contact in support.contacts]
        return cls.of(
            support.world_points((0.0, 0.0, 0.0))[:, :2],
            traction_components(robot, support),
            support.floor_z,
            support.stiffness,
            who=f"{robot.name}'s wheels",
            names=names,
        )

    @classmethod
    def of(
        cls,
        points: np.ndarray,
        components: list[tuple[int, np.ndarray]],
        floor_z: float,
        stiffness: np.ndarray | None = None,
        *,
        who: str = "the wheels",
        names: list[str] | None = None,
    ) -> WrenchSharing:
        """The sharing of contacts at ``points`` (m, (n, 2)), the floor at height ``floor_z`` (m),
        taking the tangential ``components`` (contact index, unit direction), of relative vertical
        ``stiffness`` (n,) (default equal); the wrench in the points' frame."""
        xy = np.asarray(points, dtype=float)[:, :2]
        pressure = np.zeros((3, 6))  # (F_z, N_x, N_y) from the wrench
        pressure[0, 2] = 1.0
        pressure[1, 0], pressure[1, 4] = floor_z, -1.0
        pressure[2, 3], pressure[2, 1] = 1.0, floor_z
        n = len(xy)
        system = np.vstack([np.ones(n), xy.T, compliant_sharing(xy, stiffness)])
        normal = np.linalg.inv(system)[:, :3] @ pressure
        components = [(int(c), np.asarray(d, dtype=float)) for c, d in components]
        B = np.zeros((3, len(components)))
        for k, (c, direction) in enumerate(components):
            x, y = xy[c]
            B[:, k] = direction[0], direction[1], x * direction[1] - y * direction[0]
        if len(components) == 0 or np.linalg.matrix_rank(B) < 3:
            which = ", ".join(dict.fromkeys(names[c] if names else str(c) for c, _ in components))
            problem = (
                f"{who} cannot hold the floor's sideways force and turning moment together "
                f"(contacts {which or 'none driven'})"
            )
            return cls(xy, normal, tuple(components), None, problem)
        horizontal = np.zeros((3, 6))  # (F_x, F_y, M_z)
        horizontal[0, 0], horizontal[1, 1], horizontal[2, 5] = 1.0, 1.0, 1.0
        return cls(xy, normal, tuple(components), np.linalg.pinv(B) @ horizontal)

    def require_traction(self) -> np.ndarray:
        """``traction``, or a :class:`~mobmanip.errors.SpecError` saying why there is none."""
        if self.traction is None:
            raise SpecError(self.problem)
        return self.traction

    def wheels(self) -> list[int]:
        """The contacts that take a tangential force, in order (each once)."""
        return list(dict.fromkeys(c for c, _ in self.components))

    def tangential(self, wrench: np.ndarray) -> np.ndarray:
        """Each wheel's (:meth:`wheels`) tangential force in the platform's axes (N), (d, 2), for
        ``wrench`` in the platform's frame (6,)."""
        values = self.require_traction() @ wrench
        out = np.zeros((len(self.wheels()), 2))
        index = {c: w for w, c in enumerate(self.wheels())}
        for value, (c, direction) in zip(values, self.components):
            out[index[c]] += value * direction
        return out

    def loads(self, wrench: np.ndarray, mu: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For a wrench in the platform's frame (6,): (every contact's normal force (n,), each
        wheel's tangential force in the platform's axes (d, 2), each wheel's traction use
        ``|f_t| / (mu f_n)`` (d,), +inf for a wheel at most :data:`UNLOADED`)."""
        normal = self.normal @ wrench
        tangential = self.tangential(wrench)
        weight = mu * normal[self.wheels()]
        use = np.full(len(weight), math.inf)
        loaded = weight > mu * UNLOADED
        use[loaded] = np.linalg.norm(tangential[loaded], axis=1) / weight[loaded]
        return normal, tangential, use


@dataclass(frozen=True)
class FloorRows:
    """The floor's rows over its resultant wrench on the robot and what it holds,
    ``R @ wrench <= r`` (see the module's docstring): the zero-moment point ``zmp_margin`` inside
    the support polygon, every support loaded (its compliant share at least the reserve's part of
    the weight) and each wheel's traction within its friction scaled by 1 - reserve.

    Built once per robot and floor (:meth:`build`) in the platform's frame, where the contacts do
    not move; :meth:`at` turns them to the world at a configuration.

    Attributes:
        R: (r, 6) over the wrench in the platform's axes, its moment about the platform's origin.
        r: (r,).
        labels: what each row keeps, (r,).
        kinds: ``"tip-over"``, ``"contact"`` or ``"traction"`` per row, (r,).
        sharing: how the contacts share the wrench.
    """

    R: np.ndarray
    r: np.ndarray
    labels: tuple[str, ...]
    kinds: tuple[str, ...]
    sharing: WrenchSharing

    @classmethod
    def build(
        cls,
        robot: Robot,
        support: Support,
        mu: float | None,
        faces: int,
        *,
        zmp_margin: float,
        reserve: float,
        weight: float,
    ) -> FloorRows:
        """The rows of ``robot`` on ``support``.

        Args:
            mu: the wheels' friction coefficient; ``None``: no traction rows.
            faces: the faces of the pyramid inscribed in a wheel's friction cone.
            zmp_margin: how far (m) the zero-moment point stays inside the support polygon.
            reserve: a fraction in [0, 1) (each support keeps this share of its equal part of
                ``weight``, each wheel uses at most 1 - reserve of its friction).
            weight: the normal weight the floor carries (N), robot and what it holds.
        """
        sharing = WrenchSharing.build(robot, support)
        z = support.floor_z
        N = np.zeros((2, 6))  # F_z times the zero-moment point: N = (z F_x - M_y, M_x + z F_y)
        N[0, 0], N[0, 4] = z, -1.0
        N[1, 3], N[1, 1] = 1.0, z
        Fz = np.zeros(6)
        Fz[2] = 1.0
        R_rows, r_rows, labels, kinds = [], [], [], []
        polygon = support.polygon((0.0, 0.0, 0.0))
        edges = np.roll(polygon, -1, axis=0) - polygon
        normals = np.c_[edges[:, 1], -edges[:, 0]] / np.linalg.norm(edges, axis=1)[:, None]
        for n_e, p_e in zip(normals, polygon):  # n_e . N <= (n_e . p_e - margin) F_z
            R_rows.append(n_e @ N - (float(n_e @ p_e) - zmp_margin) * Fz)
            r_rows.append(0.0)
            labels.append(f"the zero-moment point {zmp_margin:g} m inside the support polygon")
            kinds.append("tip-over")
        least = reserve * weight / len(support.contacts)
        for c, contact in enumerate(support.contacts):
            R_rows.append(-sharing.normal[c])
            r_rows.append(-least)
            labels.append(f"support {contact.name} loaded")
            kinds.append("contact")
        if mu is not None:
            traction = sharing.require_traction()
            for c in sharing.wheels():
                mine = [k for k, (owner, _) in enumerate(sharing.components) if owner == c]
                fn = sharing.normal[c]
                if len(mine) == 2:  # along the floor both ways: the pyramid inscribed in the cone
                    tilt = mu * math.cos(math.pi / faces) * (1.0 - reserve)
                    rows = [u @ traction[mine] - tilt * fn for u in pyramid_faces(faces, 0.0)]
                else:  # one way only (rollers, or a wheel rolling free): the cone is a segment
                    reach = mu * (1.0 - reserve)
                    rows = [traction[mine[0]] - reach * fn, -traction[mine[0]] - reach * fn]
                R_rows += rows
                r_rows += [0.0] * len(rows)
                labels += [f"traction of {support.contacts[c].name} within friction (mu = {mu:g})"] * len(rows)
                kinds += ["traction"] * len(rows)
        return cls(np.array(R_rows), np.array(r_rows, dtype=float), tuple(labels), tuple(kinds), sharing)

    def at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R, r) over the wrench in world axes, its moment about the world origin (as
        :func:`mobmanip.motion.ground.floor_wrench` gives it), the platform at ``q``."""
        return self.R @ to_platform(q), self.r
