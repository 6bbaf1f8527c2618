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
    xy = np.asarray(points, dtype=float)[:, :2]
    driven = np.asarray(driven, dtype=bool)
    n = len(xy)
    balance = np.vstack([np.ones(n), xy.T])
    rhs = float(force[2]) * np.array([1.0, zmp[0], zmp[1]])
    sharing = compliant_sharing(xy, stiffness)
    normal = np.linalg.solve(np.vstack([balance, sharing]), np.concatenate([rhs, np.zeros(len(sharing))]))

    w = xy[driven]
    d = len(w)
    B = np.zeros((3, 2 * d))
    B[0, 0::2] = 1.0
    B[1, 1::2] = 1.0
    B[2, 0::2], B[2, 1::2] = -w[:, 1], w[:, 0]
    target = np.array([force[0], force[1], moment[2]])
    particular, *_ = np.linalg.lstsq(B, target, rcond=None)
    _, sigma, vt = np.linalg.svd(B)
    rank = int(np.sum(sigma > 1e-12 * sigma[0]))
    if np.linalg.norm(B @ particular - target) > 1e-9 * max(1.0, float(np.linalg.norm(target))):
        raise SpecError("the driven wheels cannot carry the floor's horizontal force and moment (one wheel?)")
    if 2 * d - rank > 1:
        raise SpecError(f"traction along a motion covers two driven wheels on one axle; this support has {d}")
    weight = mu * normal[driven]
    loaded = weight > mu * UNLOADED
    tangential = particular.reshape(d, 2)  # each tyre of the axle half of its lateral force
    use = np.full(d, math.inf)
    use[loaded] = np.linalg.norm(tangential[loaded], axis=1) / weight[loaded]
    return normal, tangential, use


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
    mu = support.mu if mu is None else mu
    if isinstance(mu, bool) or not isinstance(mu, (int, float)) or not (math.isfinite(mu) and mu > 0.0):
        raise ArgumentError(f"the traction along a motion needs a friction coefficient mu > 0, got {mu!r}")
    if ground.force is None or ground.moment is None:
        raise ArgumentError("the floor along the motion has no resultant forces (from ground_along)")
    driven = np.array([c.driven for c in support.contacts])
    n, d = len(trajectory), int(driven.sum())
    normal, tangential, use = np.zeros((n, len(driven))), np.zeros((n, d, 2)), np.zeros((n, d))
    for i in range(n):
        q = trajectory.q[i]
        points = support.world_points((float(q[0]), float(q[1]), math.atan2(float(q[3]), float(q[2]))))
        normal[i], tangential[i], use[i] = contact_forces(
            points, driven, ground.force[i], ground.moment[i], ground.zmp[i], float(mu), support.stiffness
        )
    names = tuple(c.name for c in support.contacts)
    wheels = tuple(c.name for c in support.contacts if c.driven)
    return TractionAlong(float(mu), names, wheels, normal, tangential, use)
