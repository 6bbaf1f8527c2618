"""The ranges of input numbers mobmanip supports, in one place.

Outside them double precision no longer carries the analysis: a wheel speed limit a million
times the arms' makes the rank decisions of the kinematic ellipsoid meaningless (on the paper's
robot its minor semi-axis collapsed from 1.6e5 to 0.74 m/s at a ratio of 1e6), a limit of 1e-300
underflows when squared, a platform 1e13 m from the origin loses the arm's geometry to rounding.
Rather than return such numbers, mobmanip refuses the input and states the range. The ranges are
wide enough for any real robot (the built-in robots use ratios of limits below 700).
"""

from __future__ import annotations

import math

from ..errors import RangeError

#: Velocity limits (rad/s or m/s) of wheels, joints and platform coordinates.
VELOCITY_LIMIT = (1e-6, 1e6)
#: Effort limits (N m or N).
EFFORT_LIMIT = (1e-6, 1e7)
#: Largest ratio of the largest to the smallest limit of one kind of a robot, by kind. The paper's
#: robot, arms stretched (a singular posture), loses its kinematic minor axis at a velocity ratio
#: of 9.6e5 (wheels at 3e6 rad/s); wheels slowed to 1e-6 m/s (ratio 2.4e5) are still exact, and
#: its dynamic ellipsoid converges as it should up to wheel torques of 1e7 N m (ratio 3.3e5).
LIMIT_RATIO = 3e5
LIMIT_RATIOS = {"velocity": LIMIT_RATIO, "effort": 1e7}
#: Wheel radii, half-tracks and wheel offsets (m).
WHEEL_LENGTH = (1e-6, 1e3)
#: Mass of a held object (kg).
OBJECT_MASS = (0.0, 1e6)
#: Mass of a link (kg) and the magnitude of its moments of inertia (kg m^2).
LINK_MASS = (0.0, 1e6)
LINK_INERTIA = 1e6
#: Distance of a joint origin or centre of mass from its parent frame (m).
LINK_OFFSET = 1e4
#: Platform position (m): ``|x|`` and ``|y|``. Results must not depend on it, but the arms' geometry is
#: computed in world coordinates: at 1e13 m rounding changed the ellipsoids by 0.16 %; within this
#: range they agree with those at the origin to 1e-8 (tests/test_hostile_scaling.py).
PLATFORM_POSITION = 1e6
#: Position of a joint (rad or m): its magnitude.
JOINT_POSITION = 1e6
#: How far the norm of a (cos, sin) pair in q (the platform's yaw, a continuous joint) may be
#: from 1: Pinocchio's integrate and neutral give unit pairs to rounding.
UNIT_PAIR_TOLERANCE = 1e-6

#: Links (and joints) a URDF may have: parsing and detection are linear in it, Pinocchio's URDF
#: parser a little worse (20,000 fixed links: 3.4 s).
MAX_URDF_LINKS = 10_000
#: Degrees of freedom of the analysed model (after locking): Pinocchio's data holds a dozen
#: nv x nv matrices, so memory and the mass matrix grow with the square (5,000: gigabytes).
MAX_MODEL_DOF = 500

_LIMITS = {"velocity": (VELOCITY_LIMIT, "rad/s or m/s"), "effort": (EFFORT_LIMIT, "N m or N")}


def check_in_range(what: str, value: float, low: float, high: float, unit: str = "", why: str = "") -> float:
    """``value`` when ``low <= value <= high``, else a :class:`RangeError` naming ``what``."""
    if not (math.isfinite(value) and low <= value <= high):
        raise RangeError(what, value, low, high, unit, why)
    return value


def check_limit(name: str, kind: str, value: float) -> float:
    """A velocity or effort limit within :data:`VELOCITY_LIMIT` / :data:`EFFORT_LIMIT`."""
    (low, high), unit = _LIMITS[kind]
    return check_in_range(f"{kind} limit of {name!r}", value, low, high, unit)


def check_limit_ratio(kind: str, limits: dict[str, float]) -> None:
    """The largest limit of one kind at most :data:`LIMIT_RATIOS` of that kind times the smallest.

    Raises:
        RangeError: naming the two limits and their ratio.
    """
    if not limits:
        return
    largest = max(limits, key=limits.__getitem__)
    smallest = min(limits, key=limits.__getitem__)
    ratio = limits[largest] / limits[smallest]
    bound = LIMIT_RATIOS[kind]
    if ratio > bound:
        raise RangeError(
            f"the ratio of the largest to the smallest {kind} limit ({largest!r} {limits[largest]:g} / "
            f"{smallest!r} {limits[smallest]:g})",
            float(f"{ratio:.3g}"),
            1.0,
            bound,
            why="beyond it the ellipsoids' rank decisions are not reliable in double precision",
        )
