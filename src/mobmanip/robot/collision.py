"""Self-collision distances of a robot and their configuration gradients (Pinocchio + hpp-fcl).

:class:`SelfCollision` reads the robot's geometry from its description (collision shapes, or the
visual ones where a file draws links it gives no collision shape, as the paper's robot) on a
model that matches ``robot.model`` joint for joint, and keeps the pairs that can meet:

- geometries on different joints that are not parent and child (adjacent links always touch);
- minus the pairs closer than the margin in the reference posture (the robot's hold): they
  touch by design, as the paper's two arms mounted at one point and grasping at one point
  (MoveIt's "default" disabled pairs follow the same rule).

Meshes are replaced by their convex hulls (conservative, and GJK on a hull is far cheaper than
a mesh's BVH traversal). Pairs whose bounding spheres are farther apart than :attr:`SelfCollision.activation` count as
that far without an exact distance (continuous: the exact distance is larger there). The signed
distance d of a pair (negative when the shapes overlap, hpp-fcl's GJK/EPA) changes
along a tangent direction as n . (v_2 - v_1), the normal n from shape 1 to shape 2 and v_i the
velocity of the nearest point of shape i; :meth:`SelfCollision.distances` returns d and this
Jacobian, (P,) and (P, nv).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import ArgumentError, DescriptionError, ModelError
from .model import Robot, description_of, locked_joints

#: Default clearance kept between shapes that may meet (m).
DEFAULT_MARGIN = 0.02


@dataclass(frozen=True)
class Pair:
    """A geometry pair that may meet: names and parent joints of its two shapes."""

    first: str
    second: str
    joints: tuple[int, int]


class SelfCollision:
    """Distances between a robot's shapes that may meet, and their gradients.

    Args:
        robot: the loaded robot.
        margin: the clearance a placement keeps (m), also the threshold below which a pair
            touching in the reference posture is left out.
        source: ``"collision"``, ``"visual"`` or ``"auto"`` (collision shapes, and the visual ones
            of links that have none).
        reference: the posture whose touching pairs are left out (nq,); default the robot's hold.

    Raises:
        ArgumentError: a bad margin or source.
        ModelError: no shapes, or a geometry that Pinocchio cannot load.
    """

    def __init__(
        self, robot: Robot, margin: float = DEFAULT_MARGIN, source: str = "auto", reference: np.ndarray | None = None
    ) -> None:
        if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not 0.0 <= margin < 1.0:
            raise ArgumentError(f"collision margin must be between 0 and 1 m, got {margin!r}")
        if source not in ("collision", "visual", "auto"):
            raise ArgumentError(f"collision source must be collision, visual or auto, got {source!r}")
        self.robot = robot
        self.margin = float(margin)
        self.model = robot.model
        self.geometry = _geometry(robot, source)
        if self.geometry.ngeoms == 0:
            raise ModelError(f"robot {robot.name!r} has no {source} geometry to check for self-collision")
        model, geometry = self.model, self.geometry
        #: Pairs farther apart than this (m) by their bounding spheres count as this far (no
        #: exact distance computed): the constraint d >= margin is then far from active.
        self.activation = self.margin + 0.1
        moving = set(robot.torso_joint_names) | {j for arm in robot.arms for j in arm.joint_names}
        moving_ids = {model.getJointId(name) for name in moving}
        chain = [set(model.supports[j]) for j in range(model.njoints)]
        candidates = []
        for a in range(geometry.ngeoms):
            for b in range(a + 1, geometry.ngeoms):
                ja, jb = geometry.geometryObjects[a].parentJoint, geometry.geometryObjects[b].parentJoint
                if ja == jb or model.parents[ja] == jb or model.parents[jb] == ja:
                    continue  # one body, or adjacent links
                if not (chain[ja] ^ chain[jb]) & moving_ids:
                    continue  # no joint the placement moves lies between them: their distance is fixed
                candidates.append((a, b))
        for a, b in candidates:
            geometry.addCollisionPair(pin.CollisionPair(a, b))
        self.data = model.createData()
        self.gdata = pin.GeometryData(geometry)
        self._precise()
        self._spheres()
        q_ref = robot.hold_configuration() if reference is None else robot.check_configuration(reference)
        touching = self._raw(q_ref)[0] < self.margin
        geometry.removeAllCollisionPairs()
        self.pairs: list[Pair] = []
        for (a, b), touch in zip(candidates, touching):
            if not touch:
                geometry.addCollisionPair(pin.CollisionPair(a, b))
                ga, gb = geometry.geometryObjects[a], geometry.geometryObjects[b]
                self.pairs.append(Pair(ga.name, gb.name, (ga.parentJoint, gb.parentJoint)))
        self.gdata = pin.GeometryData(geometry)
        self._precise()
        self._spheres()

    def _spheres(self) -> None:
        """Each shape's bounding sphere (centre in its own frame, radius) and the pairs' indices."""
        centers, radii = [], []
        for obj in self.geometry.geometryObjects:
            shape = obj.geometry
            shape.computeLocalAABB()
            centers.append(np.asarray(shape.aabb_center, dtype=float))
            radii.append(float(shape.aabb_radius))
        self._centers, self._radii = np.array(centers).reshape(-1, 3), np.array(radii)
        pairs = self.geometry.collisionPairs
        self._first = np.array([p.first for p in pairs], dtype=int)
        self._second = np.array([p.second for p in pairs], dtype=int)

    def _precise(self) -> None:
        """GJK and EPA to 1e-10 m (hpp-fcl's defaults stop near 1e-6), so that distances are
        smooth enough for a gradient-based optimiser and for difference checks."""
        for request in self.gdata.distanceRequests:
            request.gjk_tolerance = 1e-10
            request.epa_tolerance = 1e-10
            request.gjk_max_iterations = 1000
            request.epa_max_iterations = 1000

    def _raw(self, q: np.ndarray):
        """min(signed distance, activation) of every pair and its gradient (zero where clipped)."""
        model, data, geometry, gdata = self.model, self.data, self.geometry, self.gdata
        pin.computeJointJacobians(model, data, q)
        pin.updateGeometryPlacements(model, data, geometry, gdata)
        n = len(self._first)
        d = np.full(n, self.activation)
        G = np.zeros((n, model.nv))
        if n == 0:
            return d, G
        placements = gdata.oMg
        world = np.array([placements[g].act(c) for g, c in enumerate(self._centers)])
        gap = np.linalg.norm(world[self._first] - world[self._second], axis=1)
        gap -= self._radii[self._first] + self._radii[self._second]
        jacobians = {}
        for k in np.flatnonzero(gap < self.activation):
            result = pin.computeDistance(geometry, gdata, int(k))
            if result.min_distance >= self.activation:
                continue
            d[k] = result.min_distance
            normal = np.asarray(result.normal, dtype=float)
            for sign, index, point in ((-1.0, self._first[k], result.getNearestPoint1()),
                                       (1.0, self._second[k], result.getNearestPoint2())):  # fmt: skip
                joint = geometry.geometryObjects[int(index)].parentJoint
                if joint not in jacobians:
                    jacobians[joint] = pin.getJointJacobian(model, data, joint, pin.LOCAL_WORLD_ALIGNED)
                J = jacobians[joint]
                lever = np.asarray(point) - data.oMi[joint].translation
                v = J[:3] + np.cross(J[3:].T, lever).T  # velocity of the nearest point
                G[k] += sign * normal @ v
        return d, G

    def distances(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Signed distances of the pairs that may meet (m), (P,), clipped at :attr:`activation`
        (pairs at least that far apart count as that far), and their gradients in the tangent
        space, (P, nv) (zero where clipped)."""
        return self._raw(self.robot.check_configuration(q))

    def clearance(self, q: np.ndarray) -> float:
        """The smallest signed distance over the pairs (m); inf without pairs."""
        d, _ = self.distances(q)
        return float(d.min()) if d.size else float("inf")


def _geometry(robot: Robot, source: str) -> pin.GeometryModel:
    """The robot's shapes on a model built like ``robot.model`` (planar root, locked joints)."""
    description = description_of(robot)
    model = description.build_model(pin.JointModelPlanar())
    kinds = {"collision": ["collision"], "visual": ["visual"]}.get(source, ["collision", "visual"])
    merged = pin.GeometryModel()
    covered: set[str] = set()
    for kind in kinds:
        try:
            geometry = description.build_geometry(model, kind)
        except DescriptionError as exc:
            raise ModelError(f"robot {robot.name!r}: {exc}") from None  # names the file and Pinocchio's reason
        bodies = set()
        for obj in geometry.geometryObjects:
            body = model.frames[obj.parentFrame].name if obj.parentFrame < model.nframes else obj.name
            if body in covered:
                continue
            bodies.add(body)
            merged.addGeometryObject(obj)
        covered |= bodies
    for obj in merged.geometryObjects:  # meshes by their convex hulls: GJK instead of BVH traversal
        shape = obj.geometry
        if hasattr(shape, "buildConvexRepresentation"):
            shape.buildConvexRepresentation(False)
            obj.geometry = shape.convex
    locked, q_ref = locked_joints(model, robot.spec.reference, keep=set(robot.model.names))
    if locked:
        model, (merged,) = pin.buildReducedModel(model, [merged], locked, q_ref)
    if list(model.names) != list(robot.model.names):
        raise ModelError(f"the geometry model of {robot.name!r} does not match its analysis model")
    return merged
