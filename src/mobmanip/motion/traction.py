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
- tangential forces: the casters are frictionless, so the wheels carry the resultant's
  horizontal force and its moment about the vertical, each along the floor where its mechanism
  lets it (a wheel with a motor both ways, a mecanum wheel across its rollers, a free-rolling
  wheel across its rolling direction), shared as equally stiff tyres under a rigid platform share
  them: the least-norm split (a differential drive's two wheels: half the lateral force each, as
  the floor constraint's :func:`~mobmanip.terms.constraints.floor.lateral_sharing` gives).

Both rules are :class:`mobmanip.terms.constraints.floor_wrench.WrenchSharing`'s, the one home of
the floor of motion (``carry``, ``retime`` and ``hold`` read the floor through it too).

A wheel's *traction use* is ``|f_t| / (mu f_n)`` (the friction cone itself; the floor constraint's
inscribed pyramid is conservative by 1 - cos(pi / faces)): above 1 the wheel slips; an unloaded
wheel (f_n <= 0) has use +inf.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..terms.constraints.floor_wrench import UNLOADED, FloorRows, WrenchSharing, both_ways, to_platform
from ..terms.grasp import object_mass_of
from .ground import GroundAlong
from .trajectory import Trajectory


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
    """The contacts' forces for one resultant (see the module's docstring), every driven contact
    taking a tangential force both ways along the floor.

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

    Raises:
        SpecError: the driven wheels cannot carry the horizontal force and moment (one wheel).
    """
    force, moment = np.asarray(force, dtype=float), np.asarray(moment, dtype=float)
    # the same wrench about the floor point under the origin: its horizontal moments F_z * zmp
    about_floor = np.array([force[2] * float(zmp[1]), -force[2] * float(zmp[0]), moment[2]])
    sharing = WrenchSharing.of(np.asarray(points, dtype=float)[:, :2], both_ways(driven), 0.0, stiffness)
    return sharing.loads(np.r_[force, about_floor], mu)


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
    mu, force, moment = _checked_floor(ground, mu, "the traction along a motion")
    sharing = _sharing(ground)
    wheels = sharing.wheels()
    n = len(trajectory)
    normal = np.zeros((n, len(ground.support.contacts)))
    tangential, use = np.zeros((n, len(wheels), 2)), np.zeros((n, len(wheels)))
    for i in range(n):
        q = trajectory.q[i]
        normal[i], along, use[i] = sharing.loads(to_platform(q) @ np.r_[force[i], moment[i]], mu)
        c, s = float(q[2]), float(q[3])
        turn = np.array([[c, -s], [s, c]]) / math.hypot(c, s)  # the platform's axes to the world's
        tangential[i] = along @ turn.T
    names = tuple(c.name for c in ground.support.contacts)
    return TractionAlong(float(mu), names, tuple(names[c] for c in wheels), normal, tangential, use)


def _sharing(ground: GroundAlong) -> WrenchSharing:
    """How ``ground``'s contacts share its wrench: the robot's own (:func:`ground_along` keeps it),
    else every driven contact pushed both ways along the floor."""
    if ground.sharing is not None:
        return ground.sharing
    support = ground.support
    components = both_ways([contact.driven for contact in support.contacts])
    return WrenchSharing.of(support.world_points((0.0, 0.0, 0.0)), components, support.floor_z, support.stiffness)


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
    from .ground import rest_wrench

    support = ground.support
    mu, force, moment = _checked_floor(ground, mu, "the floor's time-scaling")
    mass = object_mass_of(robot, object_mass)
    sharing = _sharing(ground)
    rows = FloorRows.build(robot, support, None, support.faces, zmp_margin=zmp_margin, reserve=0.0, weight=0.0)
    wheels = sharing.wheels()
    best, where, limit = math.inf, -1, ""
    for i in range(len(trajectory)):
        q = trajectory.q[i]
        rest = rest_wrench(robot, q, mass)
        T = to_platform(q)
        W0, W1 = T @ rest, T @ (np.r_[force[i], moment[i]] - rest)
        # the zero-moment point's and the supports' rows, R (W0 + b W1) <= r: linear in b = k^2
        bounds = [(_linear_bound(float(r - R @ W0), float(-R @ W1)), label)
                  for R, r, label in zip(rows.R, rows.r, rows.labels)]  # fmt: skip
        normal0, normal1 = sharing.normal @ W0, sharing.normal @ W1
        tangential0, tangential1 = sharing.tangential(W0), sharing.tangential(W1)
        for w, c in enumerate(wheels):
            bound = _cone_bound(tangential0[w], tangential1[w], mu * normal0[c], mu * normal1[c])
            bounds.append((bound, f"traction of {support.contacts[c].name} within friction (mu = {mu:g})"))
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
