"""Where the robot touches the floor: its driven wheels and its passive supports (casters).

A *support* is a set of contact points in the platform's root frame, all on the floor plane:

- one per driven wheel, below the wheel's centre by its radius (from the platform's wheels);
- one per driven contact the spec's ``[support] wheels`` gives, for a base whose wheels are not
  joints of the file (an omnidirectional base: its planar joint's efforts are their traction),
  optionally with its rollers' free direction (``[support] rollers``, deg), along which it pushes
  nothing (mecanum and omni wheels);
- one per passive support: the URDF's caster wheels (links named ``*caster*`` with a sphere or
  cylinder collision shape: the contact is below the shape's centre, on the floor) and the
  points the spec's ``[support]`` table gives.

The spec's table (all keys optional)::

    [support]
    mu = 0.5                      # friction coefficient of the driven wheels on the floor
    faces = 8                     # faces of the pyramid inscribed in each wheel's friction cone
    casters = [[0.25, 0.14], ...] # passive supports, [x, y] (on the floor) or [x, y, z] (m, root frame)
    urdf_casters = true           # also take the URDF's caster wheels

    [support.stiffness]           # relative vertical stiffness per contact name (default 1)
    caster_0 = 0.4

:data:`~mobmanip.robot.support_spec.DEFAULT_MU` = 0.5 is a conservative value for rubber wheels on a dry indoor floor
(rubber on concrete is usually quoted at 0.6 to 0.8; a polished or dusty floor is lower).
A support needs at least three contacts that are not on one line, ``mu >= 0`` and ``faces >= 3``;
a point above (or below) the floor is an error that names it. The table itself is read by
:mod:`mobmanip.robot.support_spec` (the spec reads it before any robot is loaded); its names are
re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..errors import SpecError
from .support_spec import (  # noqa: F401  # the spec's [support] table (read before any robot), re-exported
    DEFAULT_FACES,
    DEFAULT_MU,
    SupportSpec,
    check_faces,
    check_mu,
    check_reserve,
    support_spec_from_table,
)

if TYPE_CHECKING:
    from .model import Robot

_FLOOR_TOL = 1e-6  # m: a contact further than this from the floor plane is an error
#: m: a contact farther than this from the platform's origin is a slip of units, not a robot
#: (support points are in metres; [250, 140] is a caster in millimetres)
MAX_REACH = 10.0


@dataclass(frozen=True)
class ContactPoint:
    """One contact with the floor.

    Attributes:
        name: the wheel's joint, the caster's link, or ``caster_<k>`` for a spec row.
        point: where it touches the floor, in the platform's root frame (m), (3,).
        driven: a driven wheel (normal and tangential force) or a passive support (normal only).
        source: where it came from: ``"wheel"`` (a wheel joint), ``"urdf"``, ``"spec"`` (a
            caster of ``[support] casters``) or ``"spec_wheel"`` (``[support] wheels``).
        stiffness: its vertical stiffness relative to the other contacts' (the spec's
            ``[support.stiffness]``; 1 by default): how it shares the weight when the sharing is
            compliant.
        free: the free-rolling direction of a wheel's rollers in the root frame's floor plane
            (unit (2,)): the contact pushes nothing along it; ``None``: no such direction.
    """

    name: str
    point: np.ndarray
    driven: bool
    source: str
    stiffness: float = 1.0
    free: tuple[float, float] | None = None


@dataclass(frozen=True)
class Support:
    """The robot's contacts with the floor (see the module's docstring).

    Attributes:
        contacts: the contact points, driven wheels first.
        floor_z: the floor's height in the root frame (m).
        mu: friction coefficient of the driven wheels.
        faces: faces of the inscribed friction pyramid.
    """

    contacts: tuple[ContactPoint, ...]
    floor_z: float
    mu: float = DEFAULT_MU
    faces: int = DEFAULT_FACES

    def __post_init__(self):
        check_mu(self.mu, "the support's mu")
        check_faces(self.faces, "the support's faces")
        for c in self.contacts:
            gap = float(c.point[2] - self.floor_z)
            if abs(gap) > _FLOOR_TOL:
                where = "above" if gap > 0 else "below"
                raise SpecError(
                    f"support point {c.name!r} at z = {c.point[2]:.6g} m lies {abs(gap):.3g} m {where} the floor "
                    f"(z = {self.floor_z:.6g} m in the root frame, through the driven wheels' contacts)"
                )
            far = float(np.hypot(c.point[0], c.point[1]))
            if far > MAX_REACH:
                raise SpecError(
                    f"support point {c.name!r} at ({c.point[0]:.6g}, {c.point[1]:.6g}) m lies {far:.3g} m from the "
                    f"platform's origin, more than {MAX_REACH:g} m: support points are in metres (millimetres given?)"
                )
        xy = np.array([c.point[:2] for c in self.contacts]).reshape(-1, 2)
        if len(xy) < 3 or np.linalg.matrix_rank(xy - xy.mean(axis=0), tol=1e-6) < 2:
            names = ", ".join(c.name for c in self.contacts) or "none"
            raise SpecError(
                f"a support needs at least three contacts not on one line; got {len(xy)} ({names}): "
                "give the casters in the spec's [support] casters = [[x, y], ...]"
            )

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.contacts)

    @property
    def stiffness(self) -> np.ndarray:
        """The contacts' relative vertical stiffness, (n,)."""
        return np.array([c.stiffness for c in self.contacts], dtype=float)

    def root_points(self) -> np.ndarray:
        """The contact points in the root frame, (n, 3)."""
        return np.array([c.point for c in self.contacts])

    def world_points(self, pose: tuple[float, float, float]) -> np.ndarray:
        """The contact points in the world for the platform at (x, y, yaw), (n, 3)."""
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return self.root_points() @ R.T + np.array([x, y, 0.0])

    def polygon(self, pose: tuple[float, float, float]) -> np.ndarray:
        """The support polygon in the world's floor plane, counter-clockwise vertices (k, 2)."""
        from scipy.spatial import ConvexHull

        xy = self.world_points(pose)[:, :2]
        return xy[ConvexHull(xy).vertices]

    def to_dict(self) -> dict:
        return {
            "mu": self.mu,
            "faces": self.faces,
            "floor_z": self.floor_z,
            "contacts": [
                {
                    "name": c.name,
                    "point": c.point.tolist(),
                    "driven": c.driven,
                    "source": c.source,
                    "stiffness": c.stiffness,
                }
                for c in self.contacts
            ],
        }


def deepest_margin(polygon: np.ndarray) -> float:
    """The largest margin (m) any point of a convex polygon keeps to its boundary: the radius of
    the largest circle inside it (an LP over the centre and the radius)."""
    from scipy.optimize import linprog

    P = np.asarray(polygon, dtype=float)
    edges = np.roll(P, -1, axis=0) - P
    normals = np.c_[edges[:, 1], -edges[:, 0]] / np.linalg.norm(edges, axis=1)[:, None]  # outward (ccw)
    # max r: n_i . c + r <= n_i . p_i
    found = linprog([0.0, 0.0, -1.0], A_ub=np.c_[normals, np.ones(len(P))],
                    b_ub=np.einsum("ij,ij->i", normals, P), bounds=[(None, None)] * 3, method="highs")  # fmt: skip
    return float(-found.fun) if found.status == 0 else 0.0


def polygon_margin(polygon: np.ndarray, point: np.ndarray) -> float:
    """Signed distance (m) from a point to a convex polygon's boundary, positive inside."""
    P = np.asarray(polygon, dtype=float)
    edges = np.roll(P, -1, axis=0) - P
    normals = np.c_[edges[:, 1], -edges[:, 0]] / np.linalg.norm(edges, axis=1)[:, None]  # outward (ccw)
    return float(np.min(np.einsum("ij,ij->i", normals, P) - normals @ np.asarray(point, dtype=float)[:2]))


def robot_support(robot: Robot, mu: float | None = None, faces: int | None = None) -> Support:
    """The robot's support: its driven wheels, its URDF casters and its spec's ``[support]``.

    Args:
        robot: a robot with a wheeled platform.
        mu: friction coefficient (default: the spec's, else :data:`~mobmanip.robot.support_spec.DEFAULT_MU`).
        faces: pyramid faces (default: the spec's, else :data:`~mobmanip.robot.support_spec.DEFAULT_FACES`).

    Raises:
        SpecError: no wheels, fewer than three contacts not on one line, a bad mu.
    """
    spec: SupportSpec = getattr(robot.spec, "support", None) or SupportSpec()
    wheels = robot.platform.wheels() if robot.wheel_platform is not None else ()
    if not wheels and not (spec.wheels and robot.wheel_platform is not None):
        hint = (
            "give its driven contacts in the spec's [support] wheels = [[x, y], ...] (m, root frame)"
            if robot.wheel_platform is not None
            else "the floor model needs a platform that moves on the floor"
        )
        raise SpecError(f"robot {robot.name!r} has no wheels on the floor ({robot.platform.kind} platform): {hint}")
    if wheels and spec.wheels:
        raise SpecError(
            f"[support] wheels are the driven contacts of a base without wheel joints; {robot.name!r}'s "
            f"{robot.platform.kind} platform has its own ({', '.join(name for name, _ in wheels)})"
        )
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.neutral())
    contacts = []
    for joint, radius in wheels:
        center = data.oMi[model.getJointId(joint)].translation
        contacts.append(ContactPoint(joint, center - np.array([0.0, 0.0, radius]), True, "wheel"))
    for k, row in enumerate(spec.wheels):
        free = None
        if spec.rollers:
            angle = math.radians(spec.rollers[k])
            free = (math.cos(angle), math.sin(angle))
        z = row[2] if len(row) == 3 else 0.0
        point = np.array([row[0], row[1], z], dtype=float)
        contacts.append(ContactPoint(f"wheel_{k}", point, True, "spec_wheel", free=free))
    floor_z = float(np.mean([c.point[2] for c in contacts]))
    if spec.urdf_casters:
        for name, xy in _urdf_casters(robot, data):
            contacts.append(ContactPoint(name, np.array([xy[0], xy[1], floor_z]), False, "urdf"))
    for k, row in enumerate(spec.casters):
        z = row[2] if len(row) == 3 else floor_z
        contacts.append(ContactPoint(f"caster_{k}", np.array([row[0], row[1], z], dtype=float), False, "spec"))
    unknown = sorted(set(spec.stiffness) - {c.name for c in contacts})
    if unknown:
        raise SpecError(
            f"[support] stiffness names {', '.join(map(repr, unknown))}, which {'is' if len(unknown) == 1 else 'are'} "
            f"not among {robot.name}'s contacts: {', '.join(c.name for c in contacts)}"
        )
    contacts = [replace(c, stiffness=spec.stiffness.get(c.name, 1.0)) for c in contacts]
    check_mu(mu)
    if faces is not None:
        check_faces(faces)
    chosen = mu if mu is not None else spec.mu
    return Support(
        tuple(contacts),
        floor_z,
        mu=DEFAULT_MU if chosen is None else float(chosen),
        faces=spec.faces if faces is None else faces,
    )


def _urdf_casters(robot: Robot, data: pin.Data) -> list[tuple[str, np.ndarray]]:
    """(name, (x, y) in the root frame) of each caster wheel of the robot's description: a link
    named ``*caster*`` with a sphere or cylinder collision shape, at that shape's centre (named by
    the link), or a sphere or cylinder collision shape named ``*caster*`` on any link, at its
    centre (named ``LINK/SHAPE``: an MJCF geom of class ``caster`` on the base, as Stretch's)."""
    from .model import description_of

    description = description_of(robot)
    model = robot.model
    found = []
    for name, link in description.links.items():
        if not model.existFrame(name):
            continue
        shapes = [s for s in link.collisions if s.kind in ("sphere", "cylinder")]
        if "caster" in name.lower():
            chosen = [(name, shapes[0])] if shapes else []
        else:
            chosen = [(f"{name}/{s.name}", s) for s in shapes if s.name and "caster" in s.name.lower()]
        frame = data.oMf[model.getFrameId(name)]
        for label, shape in chosen:
            center = frame.rotation @ np.asarray(shape.origin.xyz, dtype=float) + frame.translation
            found.append((label, center[:2].copy()))
    return found
