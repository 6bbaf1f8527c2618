"""The driven wheels' traction along a motion: how much of its friction each wheel uses per sample.

The floor's resultant wrench on the robot and its object at each sample
(:func:`mobmanip.motion.ground.ground_along`, velocity terms included) is shared by the contacts
as the floor constraint (:class:`mobmanip.terms.constraints.floor.Floor`) shares it:

- normal forces, compliant: equally stiff contacts under a rigid platform, so the normal forces
  are affine in the contacts' floor positions, f_n,c = a + b x_c + c y_c; the resultant's
  normal force and its zero-moment point fix a, b and c (n - 3 equations of
  :func:`~mobmanip.terms.constraints.floor.compliant_sharing` beside the three of the balance;
  with three contacts every sharing is this one). A normal force of 0 or less is a support that
  unloads (the compliant model keeps every support loaded; the robot may still stand, on fewer
  supports);
- tangential forces: the casters are frictionless, so the driven wheels carry the resultant's
  horizontal force and its moment about the vertical: three equations over two components per
  wheel. For a differential drive (two wheels on one axle) the longitudinal forces are fixed;
  the split of the lateral force between the two wheels is not (both act along the axle's
  line): the floor constraint's compliant sharing gives each tyre half (equal tyres under a
  rigid platform, :func:`~mobmanip.terms.constraints.floor.lateral_sharing`), and so does this
  reading (the least-squares share, which splits an axle's lateral force equally).

A wheel's *traction use* is ``|f_t| / (mu f_n)`` (the friction cone itself; the floor constraint's
inscribed pyramid is conservative by 1 - cos(pi / faces)): above 1 the wheel slips; an unloaded
wheel (f_n <= 0) has use +inf.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, SpecError
from ..terms.constraints.floor import compliant_sharing
from ..terms.grasp import object_mass_of
from .ground import GroundAlong
from .trajectory import Trajectory

#: A normal force at most this (N) counts as unloaded.
UNLOADED = 1e-9


@dataclass(frozen=True)
class TractionAlong:
    """The contacts' forces along a motion (see the module's docstring).

    Attributes:
        mu: the driven wheels' friction coefficient.
        contacts: every contact's name (driven wheels first), (n,).
        wheels: the driven wheels' names, (d,).
        normal: each contact's normal force per sample (N), (N, n).
        tangential: each driven wheel's tangential force per sample (N, world x, y), (N, d, 2).
        use: each driven wheel's traction use ``|f_t| / (mu f_n)`` per sample, (N, d) (+inf unloaded).
    """

    mu: float
    contacts: tuple[str, ...]
    wheels: tuple[str, ...]
    normal: np.ndarray
    tangential: np.ndarray
    use: np.ndarray

    def worst(self) -> tuple[int, int]:
        """(sample, wheel index) of the largest traction use."""
        i, k = np.unravel_index(int(np.argmax(self.use)), self.use.shape)
        return int(i), int(k)

    def slipping(self) -> np.ndarray:
        """The samples where some wheel's use exceeds 1 (it slips)."""
        return np.flatnonzero((self.use > 1.0).any(axis=1))

    def unloaded(self) -> np.ndarray:
        """The samples where some contact's normal force is at most :data:`UNLOADED`."""
        return np.flatnonzero((self.normal <= UNLOADED).any(axis=1))


def contact_forces(
    points: np.ndarray,
    driven: np.ndarray,
    force: np.ndarray,
    moment: np.ndarray,
    zmp: np.ndarray,
    mu: float,
    stiffness: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contacts' forces for one resultant (see the module's docstring).

    Args:
        points: the contacts' points in the world (m), (n, 2 or 3).
        driven: which contacts are driven wheels, (n,) bool.
        force: the floor's resultant force (N, world), (3,).
        moment: its moment about the world origin (N m), (3,) (only the vertical component is used).
        zmp: the resultant's zero-moment point (m, world x, y), (2,).
        mu: the driven wheels' friction coefficient (> 0).
        stiffness: the contacts' relative vertical stiffness, (n,); default all equal.

    Returns:
        (normal forces (n,), the driven wheels' tangential forces (d, 2), their traction use (d,)).
    """
    driven = np.asarray(driven, dtype=bool)
    pressure = float(force[2]) * np.array([1.0, zmp[0], zmp[1]])
    normal, tangential = contact_shares(points, driven, pressure, np.array([force[0], force[1], moment[2]]), stiffness)
    weight = mu * normal[driven]
    loaded = weight > mu * UNLOADED
    use = np.full(len(tangential), math.inf)
    use[loaded] = np.linalg.norm(tangential[loaded], axis=1) / weight[loaded]
    return normal, tangential, use


def contact_shares(
    points: np.ndarray,
    driven: np.ndarray,
    pressure: np.ndarray,
    horizontal: np.ndarray,
    stiffness: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The contacts' normal forces and the driven wheels' tangential forces, linear in the
    resultant (see the module's docstring).

    Args:
        points, driven, stiffness: as :func:`contact_forces`.
        pressure: the resultant's normal force F_z and its moments F_z x_zmp, F_z y_zmp (N, N m), (3,).
        horizontal: its horizontal force F_x, F_y and its moment about the vertical through the
            world origin M_z (N, N m), (3,).

    Returns:
        (normal forces (n,), tangential forces (d, 2)).
    """
    xy = np.asarray(points, dtype=float)[:, :2]
    driven = np.asarray(driven, dtype=bool)
    n = len(xy)
    balance = np.vstack([np.ones(n), xy.T])
    sharing = compliant_sharing(xy, stiffness)
    normal = np.linalg.solve(np.vstack([balance, sharing]), np.concatenate([pressure, np.zeros(len(sharing))]))

    w = xy[driven]
    d = len(w)
    B = np.zeros((3, 2 * d))
    B[0, 0::2] = 1.0
    B[1, 1::2] = 1.0
    B[2, 0::2], B[2, 1::2] = -w[:, 1], w[:, 0]
    particular, *_ = np.linalg.lstsq(B, horizontal, rcond=None)
    _, sigma, vt = np.linalg.svd(B)
    rank = int(np.sum(sigma > 1e-12 * sigma[0]))
    if np.linalg.norm(B @ particular - horizontal) > 1e-9 * max(1.0, float(np.linalg.norm(horizontal))):
        raise SpecError("the driven wheels cannot carry the floor's horizontal force and moment (one wheel?)")
    if 2 * d - rank > 1:
        raise SpecError(f"traction along a motion covers two driven wheels on one axle; this support has {d}")
    return normal, particular.reshape(d, 2)  # each tyre of the axle half of its lateral force


def _checked_floor(ground: GroundAlong, mu: float | None, what: str) -> tuple[float, np.ndarray, np.ndarray]:
    """The friction coefficient (``mu``, else the support's), checked, and ``ground``'s resultant
    forces and moments, for a reading of the floor along a motion.

    Raises:
        ArgumentError: ``mu`` not a positive finite number; ``ground`` without resultant forces.
    """
    mu = ground.support.mu if mu is None else mu
    if isinstance(mu, bool) or not isinstance(mu, (int, float)) or not (math.isfinite(mu) and mu > 0.0):
        raise ArgumentError(f"{what} needs a friction coefficient mu > 0, got {mu!r}")
    if ground.force is None or ground.moment is None:
        raise ArgumentError("the floor along the motion has no resultant forces (from ground_along)")
    return float(mu), ground.force, ground.moment


def traction_along(ground: GroundAlong, trajectory: Trajectory, mu: float | None = None) -> TractionAlong:
    """Every contact's force and every driven wheel's traction use along a motion.

    Args:
        ground: the floor along the motion (:func:`mobmanip.motion.ground.ground_along`).
        trajectory: the same motion.
        mu: the driven wheels' friction coefficient (> 0); default the support's.

    Raises:
        ArgumentError: ``mu`` not a positive finite number.
    """
    support = ground.support
    mu, force, moment = _checked_floor(ground, mu, "the traction along a motion")
    driven = np.array([c.driven for c in support.contacts])
    n, d = len(trajectory), int(driven.sum())
    normal, tangential, use = np.zeros((n, len(driven))), np.zeros((n, d, 2)), np.zeros((n, d))
    for i in range(n):
        q = trajectory.q[i]
        points = support.world_points((float(q[0]), float(q[1]), math.atan2(float(q[3]), float(q[2]))))
        normal[i], tangential[i], use[i] = contact_forces(
            points, driven, force[i], moment[i], ground.zmp[i], mu, support.stiffness
        )
    names = tuple(c.name for c in support.contacts)
    wheels = tuple(c.name for c in support.contacts if c.driven)
    return TractionAlong(float(mu), names, wheels, normal, tangential, use)


@dataclass(frozen=True)
class FloorScaling:
    """The speed-ups k of a motion that keep it on its floor (see :func:`floor_time_scaling`).

    Attributes:
        k_max: the largest speed-up (``None``: no floor reading bounds it, a motion whose floor
            wrench does not change with its speed; 0: the floor breaks with the robot standing).
        sample: where k_max is decided, or -1.
        limit: what decides it: ``"the zero-moment point M m inside the support polygon"``,
            ``"support NAME loaded"`` or ``"traction of NAME within friction (mu = MU)"``, or ``""``.
    """

    k_max: float | None
    sample: int
    limit: str

    def to_dict(self) -> dict:
        return {"k_max": self.k_max, "sample": self.sample, "limit": self.limit}


def floor_time_scaling(
    robot,
    trajectory: Trajectory,
    ground: GroundAlong,
    mu: float | None = None,
    *,
    object_mass: float | None = None,
    zmp_margin: float = 0.0,
) -> FloorScaling:
    """The largest k for which the motion run k times faster keeps its floor, as this module and
    :func:`~mobmanip.motion.ground.ground_along` read it: the zero-moment point ``zmp_margin``
    inside the support polygon, every contact's compliant normal force positive and every driven
    wheel's traction use at most 1.

    Run k times faster, every velocity and acceleration term of the floor's wrench scales with
    k^2 and the weight stays: ``W(k) = W_0 + k^2 (W_1 - W_0)``, W_1 the wrench ``ground`` read at
    the motion's own speed. The zero-moment point's rows and the normal forces are linear in k^2,
    a wheel's friction cone ``|t| <= mu f_n`` quadratic: each gives the largest k^2 exactly, and
    the least over the samples is the margin.

    Args:
        robot, trajectory: the robot and its motion.
        ground: the floor along it (:func:`~mobmanip.motion.ground.ground_along`, same object mass).
        mu: the driven wheels' friction coefficient (default: the support's).
        object_mass: the held object's mass, as ``ground`` was read (default: the spec's).
        zmp_margin: how far inside the support polygon the zero-moment point must stay (m).
    """
    from .ground import floor_wrench_terms

    support = ground.support
    mu, force, moment = _checked_floor(ground, mu, "the floor's time-scaling")
    mass = object_mass_of(robot, object_mass)
    driven = np.array([c.driven for c in support.contacts])
    wheels = [c.name for c in support.contacts if c.driven]
    z = support.floor_z
    best, where, limit = math.inf, -1, ""

    def parts(wrench: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pressure = np.array([wrench[2], z * wrench[0] - wrench[4], wrench[3] + z * wrench[1]])
        return pressure, np.array([wrench[0], wrench[1], wrench[5]]), pressure[1:]

    for i in range(len(trajectory)):
        q = trajectory.q[i]
        pose = (float(q[0]), float(q[1]), math.atan2(float(q[3]), float(q[2])))
        rest = floor_wrench_terms(robot, q, np.zeros(robot.nx), mass, np.zeros(6), np.zeros((6, robot.nx)))[2]
        moving = np.r_[force[i], moment[i]] - rest
        points = support.world_points(pose)
        bounds: list[tuple[float, str]] = []
        # the zero-moment point: n . N <= (n . p - margin) F_z, linear in b = k^2
        (p0, h0, N0), (p1, h1, N1) = parts(rest), parts(moving)
        polygon = support.polygon(pose)
        edges = np.roll(polygon, -1, axis=0) - polygon
        normals = np.c_[edges[:, 1], -edges[:, 0]] / np.linalg.norm(edges, axis=1)[:, None]
        for n_e, p_e in zip(normals, polygon):
            reach = float(n_e @ p_e) - zmp_margin
            bounds.append((_linear_bound(reach * p0[0] - n_e @ N0, reach * p1[0] - n_e @ N1),
                           f"the zero-moment point {zmp_margin:g} m inside the support polygon"))  # fmt: skip
        normal0, tangential0 = contact_shares(points, driven, p0, h0, support.stiffness)
        normal1, tangential1 = contact_shares(points, driven, p1, h1, support.stiffness)
        for c, contact in enumerate(support.contacts):
            bounds.append((_linear_bound(normal0[c], normal1[c]), f"support {contact.name} loaded"))
        for w, c in enumerate(np.flatnonzero(driven)):
            bound = _cone_bound(tangential0[w], tangential1[w], mu * normal0[c], mu * normal1[c])
            bounds.append((bound, f"traction of {wheels[w]} within friction (mu = {mu:g})"))
        b, label = min(bounds, key=lambda pair: pair[0])
        if b < best:
            best, where, limit = b, i, label
    if math.isinf(best):
        return FloorScaling(None, -1, "")
    return FloorScaling(math.sqrt(max(best, 0.0)), where, limit)


def _linear_bound(at_rest: float, rate: float) -> float:
    """The largest b >= 0 with at_rest + rate b >= 0 (0 when it fails at rest, inf unbounded)."""
    if at_rest < 0.0:
        return 0.0
    return -at_rest / rate if rate < 0.0 else math.inf


def _cone_bound(t0: np.ndarray, t1: np.ndarray, n0: float, n1: float) -> float:
    """The largest b >= 0 with |t0 + b t1| <= n0 + b n1 on all of [0, b] (0 when it fails at rest)."""
    if n0 <= 0.0 or float(np.linalg.norm(t0)) > n0:
        return 0.0
    # f(b) = (n0 + b n1)^2 - |t0 + b t1|^2 >= 0 and n0 + b n1 >= 0
    a = n1 * n1 - float(t1 @ t1)
    half = n0 * n1 - float(t0 @ t1)
    c = n0 * n0 - float(t0 @ t0)
    roots = [_linear_bound(n0, n1)]
    if a == 0.0:
        roots.append(_linear_bound(c, 2.0 * half))
    else:
        disc = half * half - a * c
        if disc >= 0.0:
            for r in ((-half - math.sqrt(disc)) / a, (-half + math.sqrt(disc)) / a):
                if r > 0.0:
                    roots.append(r)
    return min(roots)
