"""The shapes of a robot that self-collision checks use, the pairs that may meet, and the engine
computing their signed distances and gradients (Pinocchio + hpp-fcl), shared by
:class:`mobmanip.robot.collision.SelfCollision` and the collision matrix's sampling."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import DescriptionError, ModelError
from .model import Robot, description_of, locked_joints


class PairDistances:
    """Signed distances of chosen shape pairs of one geometry model, clipped at an activation
    distance, and their gradients: the engine under :class:`SelfCollision` and the collision
    matrix's sampling.

    Broad phase: each shape's bounding sphere (about its local AABB's centre), placed in one
    vectorised step; a pair whose spheres are at least ``activation`` apart counts as that far
    without an exact distance (its exact distance is larger). Narrow phase: hpp-fcl's GJK/EPA to
    1e-10 m on the pairs left. Gradients only for the pairs closer than ``activation``, all at
    once from the world-frame joint Jacobians (no per-pair Jacobian).

    Args:
        model: the kinematic model the geometry hangs on.
        geometry: its shapes (copied: the copy's collision pairs are ``pairs``).
        pairs: (first, second) geometry indices.
        activation: the clip distance (m).
    """

    def __init__(
        self, model: pin.Model, geometry: pin.GeometryModel, pairs: Sequence[tuple[int, int]], activation: float
    ) -> None:
        geometry = geometry.copy()
        self.model, self.geometry, self.activation = model, geometry, float(activation)
        geometry.removeAllCollisionPairs()
        for a, b in pairs:
            geometry.addCollisionPair(pin.CollisionPair(int(a), int(b)))
        self.data = model.createData()
        self.gdata = pin.GeometryData(geometry)
        for request in self.gdata.distanceRequests:  # hpp-fcl's defaults stop near 1e-6 m: too rough
            request.gjk_tolerance = 1e-10  # for a gradient-based optimiser and for difference checks
            request.epa_tolerance = 1e-10
            request.gjk_max_iterations = 1000
            request.epa_max_iterations = 1000
        self.first = np.array([a for a, _ in pairs], dtype=int)
        self.second = np.array([b for _, b in pairs], dtype=int)
        #: The shapes some pair uses; only these are placed for the broad phase.
        self.shapes = np.unique(np.concatenate([self.first, self.second]))
        slot = np.full(geometry.ngeoms, -1)
        slot[self.shapes] = np.arange(len(self.shapes))
        self._slot_first, self._slot_second = slot[self.first], slot[self.second]
        centers, radii = [], []
        for g in self.shapes:
            shape = geometry.geometryObjects[int(g)].geometry
            shape.computeLocalAABB()
            centers.append(np.asarray(shape.aabb_center, dtype=float))
            radii.append(float(shape.aabb_radius))
        self._centers = np.array(centers).reshape(-1, 3)
        self._reach = np.array(radii)[self._slot_first] + np.array(radii)[self._slot_second] + self.activation
        joints = [geometry.geometryObjects[int(g)].parentJoint for g in range(geometry.ngeoms)]
        self._joint_first = np.array([joints[a] for a in self.first], dtype=int)
        self._joint_second = np.array([joints[b] for b in self.second], dtype=int)
        #: (njoints, nv): which tangent directions move each joint's body.
        self._moves = np.zeros((model.njoints, model.nv))
        for j in range(1, model.njoints):
            for i in model.supports[j]:
                if i > 0:
                    self._moves[j, model.idx_vs[i] : model.idx_vs[i] + model.nvs[i]] = 1.0

    def near(self, q: np.ndarray) -> np.ndarray:
        """Indices of the pairs whose bounding spheres are closer than the activation at q (the
        placements are updated here)."""
        model, data, geometry, gdata = self.model, self.data, self.geometry, self.gdata
        pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, geometry, gdata)
        if len(self.first) == 0:
            return np.zeros(0, dtype=int)
        placements = gdata.oMg
        rotations = np.array([placements[int(g)].rotation for g in self.shapes])
        translations = np.array([placements[int(g)].translation for g in self.shapes])
        world = np.einsum("sij,sj->si", rotations, self._centers) + translations
        gap = np.linalg.norm(world[self._slot_first] - world[self._slot_second], axis=1)
        return np.flatnonzero(gap < self._reach)

    def distances(self, q: np.ndarray, gradients: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """min(signed distance, activation) of every pair (m), (P,), and with ``gradients`` their
        gradients in the tangent space, (P, nv) (zero where clipped); q is not checked."""
        n, nv = len(self.first), self.model.nv
        d = np.full(n, self.activation)
        near = self.near(q)
        close, normals, points1, points2 = [], [], [], []
        geometry, gdata = self.geometry, self.gdata
        for k in near:
            result = pin.computeDistance(geometry, gdata, int(k))
            value = result.min_distance
            if value >= self.activation:
                continue
            d[k] = value
            if gradients:
                close.append(k)
                normals.append(result.normal)
                points1.append(result.getNearestPoint1())
                points2.append(result.getNearestPoint2())
        if not gradients:
            return d, None
        G = np.zeros((n, nv))
        if close:
            pin.computeJointJacobians(self.model, self.data, q)  # data.J: world frame, about the origin
            J = self.data.J
            index = np.array(close)
            N = np.array(normals)
            # velocity of a point p on joint j's body: (J_lin + omega x p) on the columns moving j;
            # n . (omega x p) = (p x n) . omega
            # (K, 3) x (3, nv) products as three broadcast terms: a threaded BLAS call here cost
            # five times the whole placement on a busy machine
            linear = _times(N, J[:3])
            second = (linear + _times(np.cross(np.array(points2), N), J[3:])) * self._moves[self._joint_second[index]]
            first = (linear + _times(np.cross(np.array(points1), N), J[3:])) * self._moves[self._joint_first[index]]
            G[index] = second - first
        return d, G


def _times(rows: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """rows @ matrix for (K, 3) rows and a (3, n) matrix, without BLAS."""
    return rows[:, 0:1] * matrix[0] + rows[:, 1:2] * matrix[1] + rows[:, 2:3] * matrix[2]


def candidate_pairs(robot: Robot, geometry: pin.GeometryModel) -> list[tuple[int, int]]:
    """Geometry index pairs (first < second) that may meet: on different joints that are not
    parent and child, with a joint the analysis moves (torso or arm) between them."""
    model = robot.model
    moving = set(robot.torso_joint_names) | {j for arm in robot.arms for j in arm.joint_names}
    moving_ids = {model.getJointId(name) for name in moving}
    chain = [set(model.supports[j]) for j in range(model.njoints)]
    out = []
    for a in range(geometry.ngeoms):
        for b in range(a + 1, geometry.ngeoms):
            ja, jb = geometry.geometryObjects[a].parentJoint, geometry.geometryObjects[b].parentJoint
            if ja == jb or model.parents[ja] == jb or model.parents[jb] == ja:
                continue  # one body, or adjacent links
            if not (chain[ja] ^ chain[jb]) & moving_ids:
                continue  # no joint the placement moves lies between them: their distance is fixed
            out.append((a, b))
    return out


def vertex_hull(convex: Any) -> Any:
    """The convex hull of a hull's points (an hpp-fcl ``ConvexBase``), rebuilt by qhull: the same
    set, with only its vertices.

    hpp-fcl's hull of a mesh (``buildConvexRepresentation``) keeps points that are not vertices
    (5,100 points for TIAGo++'s 64 meshes, 4,089 vertices); above 32 points its support function
    climbs the hull's neighbour graph, and those points stopped the climb short of the extreme
    vertex: GJK returned distances up to 2e-5 m too large, changing in steps as the robot moved
    (finite differences of 1e3 m per rad), and SLSQP failed on them. On the rebuilt hull GJK
    agrees with a quadratic program over the vertices."""
    try:
        import coal as hppfcl  # hpp-fcl's name from version 3 (Pinocchio 3.3 and later)
    except ImportError:  # pragma: no cover - older Pinocchio
        import hppfcl

    points = np.unique(np.asarray(convex.points(), dtype=float).reshape(-1, 3), axis=0)
    vertices = hppfcl.StdVec_Vec3s()
    for point in points:
        vertices.append(point)
    return hppfcl.ConvexBase.convexHull(vertices, True, "Qt")


def robot_geometry(robot: Robot, source: str) -> pin.GeometryModel:
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
            obj.geometry = vertex_hull(shape.convex)
    locked, q_ref = locked_joints(model, robot.spec.reference, keep=set(robot.model.names))
    if locked:
        model, (merged,) = pin.buildReducedModel(model, [merged], locked, q_ref)
    if list(model.names) != list(robot.model.names):
        raise ModelError(f"the geometry model of {robot.name!r} does not match its analysis model")
    return merged
