"""Self-collision distances of a robot and their configuration gradients (Pinocchio + hpp-fcl).

:class:`SelfCollision` reads the robot's geometry from its description (collision shapes, or the
visual ones where a file draws links it gives no collision shape, as the paper's robot) on a
model that matches ``robot.model`` joint for joint, and keeps the pairs that can meet:

- geometries on different joints that are not parent and child (adjacent links always touch);
- with a joint the analysis moves between them (else their distance is fixed);
- minus the pairs an allowed-collision matrix disables (:mod:`mobmanip.robot.collision_matrix`:
  pairs always in contact, and pairs never near in sampled configurations while the margin is
  below the matrix's distance), the one stored beside the spec by default;
- minus the pairs closer than the margin in the reference posture (the robot's hold): they
  touch by design, as the paper's two arms mounted at one point and grasping at one point
  (MoveIt's "default" disabled pairs follow the same rule).

Meshes are replaced by their convex hulls (conservative, and GJK on a hull is far cheaper than
a mesh's BVH traversal). Pairs whose bounding spheres are farther apart than
:attr:`SelfCollision.activation` count as that far without an exact distance (continuous: the
exact distance is larger there); see :class:`mobmanip.robot.shape_pairs.PairDistances`. The signed
distance d of a pair (negative when the shapes overlap, hpp-fcl's GJK/EPA) changes
along a tangent direction as n . (v_2 - v_1), the normal n from shape 1 to shape 2 and v_i the
velocity of the nearest point of shape i; :meth:`SelfCollision.distances` returns d and this
Jacobian, (P,) and (P, nv).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, ModelError
from .collision_matrix import CollisionMatrix, stored_matrix
from .model import Robot
from .shape_pairs import PairDistances, candidate_pairs, robot_geometry

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
        matrix: an allowed-collision matrix (:class:`mobmanip.robot.collision_matrix.CollisionMatrix`)
            whose disabled pairs are left out; ``"auto"`` (default): the one stored beside the
            robot's spec if there is one for this source, else none; ``None``: every pair that
            may meet (the all-pairs path).

    Raises:
        ArgumentError: a bad margin or source.
        ModelError: no shapes, a geometry that Pinocchio cannot load, or a matrix made for other
            shapes.
    """

    def __init__(
        self,
        robot: Robot,
        margin: float = DEFAULT_MARGIN,
        source: str = "auto",
        reference: np.ndarray | None = None,
        matrix: CollisionMatrix | str | None = "auto",
    ) -> None:
        if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not 0.0 <= margin < 1.0:
            raise ArgumentError(f"collision margin must be between 0 and 1 m, got {margin!r}")
        if source not in ("collision", "visual", "auto"):
            raise ArgumentError(f"collision source must be collision, visual or auto, got {source!r}")
        self.robot = robot
        self.margin = float(margin)
        self.source = source
        self.model = robot.model
        self.geometry = robot_geometry(robot, source)
        if self.geometry.ngeoms == 0:
            raise ModelError(f"robot {robot.name!r} has no {source} geometry to check for self-collision")
        #: Pairs farther apart than this (m) by their bounding spheres count as this far (no
        #: exact distance computed): the constraint d >= margin is then far from active.
        self.activation = self.margin + 0.1
        candidates = candidate_pairs(robot, self.geometry)
        #: How many pairs may meet before the matrix: the all-pairs count.
        self.candidates = len(candidates)
        if isinstance(matrix, str):
            if matrix != "auto":
                raise ArgumentError(f"collision matrix must be a CollisionMatrix, 'auto' or None, got {matrix!r}")
            matrix = stored_matrix(robot, source, self.geometry)
        elif matrix is not None:
            matrix.check_fits(robot, self.geometry)
        #: The allowed-collision matrix used, or None.
        self.matrix = matrix
        left_out: list[tuple[int, int]] = []
        if matrix is not None:
            disabled = matrix.disabled_for(self.margin)
            left_out = [pair for pair in candidates if pair in disabled]
            candidates = [pair for pair in candidates if pair not in disabled]
        #: The pairs the matrix left out, checked only by :meth:`left_out_clearance`.
        self.left_out = PairDistances(self.model, self.geometry, left_out, self.activation)
        q_ref = robot.hold_configuration() if reference is None else robot.check_configuration(reference)
        touching = PairDistances(self.model, self.geometry, candidates, self.activation).distances(q_ref, False)[0]
        kept = [pair for pair, d in zip(candidates, touching) if not d < self.margin]
        self.engine = PairDistances(self.model, self.geometry, kept, self.activation)
        objects = self.geometry.geometryObjects
        self.pairs: list[Pair] = [
            Pair(objects[a].name, objects[b].name, (objects[a].parentJoint, objects[b].parentJoint)) for a, b in kept
        ]

    def distances_unchecked(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`distances` for a q the caller knows to be valid (an optimiser's own iterate)."""
        d, G = self.engine.distances(q)
        assert G is not None
        return d, G

    def distances(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Signed distances of the pairs that may meet (m), (P,), clipped at :attr:`activation`
        (pairs at least that far apart count as that far), and their gradients in the tangent
        space, (P, nv) (zero where clipped)."""
        return self.distances_unchecked(self.robot.check_configuration(q))

    def left_out_clearance(self, q: np.ndarray) -> float:
        """The smallest signed distance over the pairs the matrix left out (m), clipped at
        :attr:`activation`; inf without a matrix. Below the margin, the matrix's sampling missed
        a configuration like q (regenerate it with more samples or a larger distance)."""
        d, _ = self.left_out.distances(self.robot.check_configuration(q), gradients=False)
        return float(d.min()) if d.size else float("inf")

    def clearance(self, q: np.ndarray) -> float:
        """The smallest signed distance over the pairs (m); inf without pairs."""
        d, _ = self.engine.distances(self.robot.check_configuration(q), gradients=False)
        return float(d.min()) if d.size else float("inf")
