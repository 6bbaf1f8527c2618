"""The MuJoCo referee's builder for the tests: the installed package's (:mod:`mobmanip.referee`),
with the paper robot's casters, which its URDF does not have."""

from __future__ import annotations

from mobmanip.referee.model import (  # noqa: F401  # re-exported for the tests
    GRAVITY,
    ContactForce,
    Referee,
    Rollout,
    Support,
    build,
    contacts_of_floor,
    stripped_urdf,
    urdf_casters,
)

#: The paper robot has no casters in its URDF: four at its base box's corners, on the floor
#: (base_link frame, m; its wheel radius below the axle).
PAPER_CASTERS = {
    f"caster_{end}_{side}": (sx * 0.25, sy * 0.14, -0.075)
    for end, sx in (("front", 1.0), ("back", -1.0))
    for side, sy in (("right", -1.0), ("left", 1.0))
}
