"""An allowed-collision matrix: the shape pairs a robot's self-collision checks leave out, computed
once per robot from sampled configurations (as MoveIt's setup assistant does) and stored beside
the robot's spec as ``NAME.collision.json``.

Over ``samples`` configurations drawn uniformly within the joint limits (seeded; continuous
joints over a full turn; the platform's pose does not change any distance), with the shapes that
:class:`mobmanip.robot.collision.SelfCollision` checks (meshes by their convex hulls), each pair
that may meet (:func:`mobmanip.robot.shape_pairs.candidate_pairs`) is classified:

- ``always``: in contact (signed distance < 0) in every sample: no placement can separate them;
  left out at every margin;
- ``never``: no shape of the pair's two rigid bodies (the shapes on one joint of the analysis
  model: a hand with its locked fingers is one body) came closer than ``never_closer_than``
  (default 0.10 m) to one of the other in any sample; left out only while the checked margin is
  below that distance (for a 0.02 m margin the samples must have missed a configuration 8 cm
  closer than any they saw); for a larger margin such pairs are kept;
- every other pair is kept.

Why per body and why 0.10 m, measured on TIAGo++ with 10,000 samples: per pair of shapes (as
MoveIt's per-link rule would be here) and 0.05 m, 1,550 pairs were left out, and 1,000 fresh
samples brought 18 of them within 0.05 m and a finger 6 mm into the other arm's shoulder (small
fingers near a link are rare in samples, their hand near it is not); per body and 0.05 m, 148
were left out, and 1,000 fresh samples brought the two forearms 5.6 mm apart; per body and
0.10 m, 54 are left out, and 3,000 fresh samples brought none closer than 0.096 m.

Shapes on adjacent links (parent and child) are never checked; the file lists them too, for the
record, as MoveIt's does. What the matrix claims is what it saw: a pair left out as ``never`` kept
``never_closer_than`` in the samples, not in every configuration;
:meth:`mobmanip.robot.collision.SelfCollision.left_out_clearance` checks the pairs it left out at
one configuration (``place`` reports it for its result).

The file records the rule, the shape names (pairs are index pairs into them) and a fingerprint of
the shapes and joint limits it was made for; a matrix whose fingerprint differs from the robot's
is refused with the command that regenerates it (``mobmanip collision-matrix ROBOT``).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ArgumentError, ModelError
from ..support.reading import read_user_text
from .model import Robot
from .shape_pairs import PairDistances, candidate_pairs, robot_geometry

#: The format line of a matrix file.
FORMAT = "mobmanip collision matrix 1"
#: Defaults of the sampling rule: configurations (MoveIt's setup assistant samples 10,000 too), seed
#: and the never-closer-than distance (m).
DEFAULT_SAMPLES = 10000
DEFAULT_SEED = 0
DEFAULT_NEVER_CLOSER_THAN = 0.10

#: Most bytes the sampled configurations may take together (they are drawn at once, so that a
#: seed gives the same samples whatever the count's chunking).
MAX_SAMPLE_BYTES = 1 << 30

Pairs = tuple[tuple[int, int], ...]


@dataclass(frozen=True)
class CollisionMatrix:
    """A robot's allowed-collision matrix (see the module's rule).

    Attributes:
        robot: the robot's name.
        source: the shapes it was made from: ``"collision"``, ``"visual"`` or ``"auto"``.
        shapes: the geometry names, in the geometry model's order.
        fingerprint: a digest of the shapes and joint limits it was made for.
        samples, seed, never_closer_than: the sampling rule.
        checked: how many pairs may meet (the all-pairs count).
        always, never, adjacent: disabled pairs, (first, second) indices into ``shapes``, first < second.
    """

    robot: str
    source: str
    shapes: tuple[str, ...]
    fingerprint: str
    samples: int
    seed: int
    never_closer_than: float
    checked: int
    always: Pairs
    never: Pairs
    adjacent: Pairs

    def check_fits(self, robot: Robot, geometry: pin.GeometryModel, where: Path | None = None) -> None:
        """Raise ModelError unless this matrix was made for these shapes and joint limits
        (``where``: the file it was read from, named in the message)."""
        if tuple(obj.name for obj in geometry.geometryObjects) != self.shapes or self.fingerprint != fingerprint(
            robot, geometry
        ):
            what = f"collision matrix {where}" if where is not None else f"the collision matrix of {self.robot!r}"
            raise ModelError(
                f"{what} was made for other shapes or joint limits than "
                f"{robot.name!r} has; regenerate it with `mobmanip collision-matrix {robot.name}`"
            )

    def disabled_for(self, margin: float) -> set[tuple[int, int]]:
        """The pairs a check with this margin (m) leaves out: ``always``, and ``never`` while the
        margin is below ``never_closer_than``."""
        disabled = set(self.always)
        if margin < self.never_closer_than:
            disabled |= set(self.never)
        return disabled

    def document(self) -> dict:
        """The JSON form written to a matrix file."""
        return {
            "format": FORMAT,
            "robot": self.robot,
            "source": self.source,
            "fingerprint": self.fingerprint,
            "rule": {
                "samples": self.samples,
                "seed": self.seed,
                "never_closer_than": self.never_closer_than,
                "always": "in contact (signed distance < 0) in every sample",
                "never": "no shape of either body closer than never_closer_than to the other body in any sample; "
                "left out for margins below it",
                "shapes": "collision shapes (visual ones for links without), meshes by their convex hulls",
            },
            "checked": self.checked,
            "shapes": list(self.shapes),
            "always": [list(p) for p in self.always],
            "never": [list(p) for p in self.never],
            "adjacent": [list(p) for p in self.adjacent],
        }

    def text(self) -> str:
        """The file's text: JSON, one line per key and per 12 pairs (diff-friendly, deterministic)."""
        lines = ["{"]
        items = list(self.document().items())
        for n, (key, value) in enumerate(items):
            end = "," if n < len(items) - 1 else ""
            if key in ("always", "never", "adjacent", "shapes") and value:
                per = 6 if key == "shapes" else 12
                chunks = [value[i : i + per] for i in range(0, len(value), per)]
                body = ",\n".join("  " + ", ".join(json.dumps(v) for v in chunk) for chunk in chunks)
                lines.append(f"{json.dumps(key)}: [\n{body}\n]{end}")
            else:
                lines.append(f"{json.dumps(key)}: {json.dumps(value)}{end}")
        return "\n".join(lines) + "\n}\n"


def fingerprint(robot: Robot, geometry: pin.GeometryModel) -> str:
    """A digest of what a matrix depends on: each shape's name, parent joint, placement and size,
    and each joint's name and position limits (numbers to 1e-6)."""
    parts = []
    for obj in geometry.geometryObjects:
        shape = obj.geometry
        shape.computeLocalAABB()
        values = [*obj.placement.translation, *obj.placement.rotation.ravel(), shape.aabb_radius]
        parts.append(f"{obj.name}|{obj.parentJoint}|" + ",".join(f"{v:.6f}" for v in values))
    model = robot.model
    for j in range(1, model.njoints):
        lo = model.lowerPositionLimit[model.idx_qs[j] : model.idx_qs[j] + model.nqs[j]]
        hi = model.upperPositionLimit[model.idx_qs[j] : model.idx_qs[j] + model.nqs[j]]
        parts.append(f"{model.names[j]}|" + ",".join(f"{v:.6f}" for v in (*lo, *hi) if math.isfinite(v)))
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def sample_configurations(robot: Robot, count: int, seed: int) -> np.ndarray:
    """``count`` configurations, (count, nq): the platform at the origin, each joint uniform
    within its position limits (a full turn for continuous joints), from ``numpy``'s default
    generator with ``seed``."""
    model = robot.model
    rng = np.random.default_rng(seed)
    out = np.tile(pin.neutral(model), (count, 1))
    for j in range(2, model.njoints):  # joint 1 is the planar root
        i, nq = model.idx_qs[j], model.nqs[j]
        if nq == 1:
            lo, hi = model.lowerPositionLimit[i], model.upperPositionLimit[i]
            if not (math.isfinite(lo) and math.isfinite(hi)):
                lo, hi = -math.pi, math.pi
            out[:, i] = rng.uniform(lo, hi, count)
        elif nq == 2:  # continuous: (cos, sin)
            angle = rng.uniform(-math.pi, math.pi, count)
            out[:, i], out[:, i + 1] = np.cos(angle), np.sin(angle)
    return out


def check_samples(robot: Robot, samples: int, name: str = "collision matrix samples") -> None:
    """Refuse a sample count below 1, or one whose configurations do not fit in
    :data:`MAX_SAMPLE_BYTES` (``name``: what the message calls the count).

    Raises:
        ArgumentError: naming the count and the most that fit.
    """
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ArgumentError(f"{name} must be a positive integer, got {samples!r}")
    most = MAX_SAMPLE_BYTES // (8 * robot.model.nq)
    if samples > most:
        raise ArgumentError(
            f"{name}: {samples:,} configurations of {robot.name} ({robot.model.nq} numbers each) "
            f"are more than the {most:,} that fit in {MAX_SAMPLE_BYTES >> 20} MiB"
        )


def compute_collision_matrix(
    robot: Robot,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_SEED,
    never_closer_than: float = DEFAULT_NEVER_CLOSER_THAN,
    source: str = "auto",
) -> CollisionMatrix:
    """Sample the robot and classify every pair that may meet (see the module's rule).

    Raises:
        ArgumentError: fewer than 1 sample or more than fit in :data:`MAX_SAMPLE_BYTES`, a
            negative seed, or a distance outside (0, 1) m.
    """
    check_samples(robot, samples)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ArgumentError(f"collision matrix seed must be a whole number of at least 0, got {seed!r}")
    if not isinstance(never_closer_than, (int, float)) or not 0.0 < never_closer_than < 1.0:
        raise ArgumentError(f"never-closer-than distance must be between 0 and 1 m, got {never_closer_than!r}")
    geometry = robot_geometry(robot, source)
    candidates = candidate_pairs(robot, geometry)
    engine = PairDistances(robot.model, geometry, candidates, float(never_closer_than))
    always = np.ones(len(candidates), dtype=bool)
    closest = np.full(len(candidates), float(never_closer_than))
    for q in sample_configurations(robot, samples, seed):
        d, _ = engine.distances(q, gradients=False)
        always &= d < 0.0
        np.minimum(closest, d, out=closest)
    joints = [obj.parentJoint for obj in geometry.geometryObjects]
    bodies = [(min(joints[a], joints[b]), max(joints[a], joints[b])) for a, b in candidates]
    near_bodies = {body for body, value in zip(bodies, closest) if value < never_closer_than}
    never = [body not in near_bodies for body in bodies]
    model = robot.model
    adjacent = []
    for a in range(geometry.ngeoms):
        for b in range(a + 1, geometry.ngeoms):
            ja, jb = geometry.geometryObjects[a].parentJoint, geometry.geometryObjects[b].parentJoint
            if ja != jb and (model.parents[ja] == jb or model.parents[jb] == ja):
                adjacent.append((a, b))
    return CollisionMatrix(
        robot=robot.name,
        source=source,
        shapes=tuple(obj.name for obj in geometry.geometryObjects),
        fingerprint=fingerprint(robot, geometry),
        samples=samples,
        seed=seed,
        never_closer_than=float(never_closer_than),
        checked=len(candidates),
        always=tuple(p for p, flag in zip(candidates, always) if flag),
        never=tuple(p for p, flag in zip(candidates, never) if flag),
        adjacent=tuple(adjacent),
    )


def matrix_path(robot: Robot) -> Path | None:
    """Where a robot's matrix is stored: ``NAME.collision.json`` beside its spec file (None for a
    spec not read from a file)."""
    source = robot.spec.source
    return None if source is None else Path(source).with_name(Path(source).stem + ".collision.json")


def read_collision_matrix(path: str | Path) -> CollisionMatrix:
    """A matrix file. Raises ModelError for a file that is not one."""
    text = read_user_text(path, "collision matrix", error=ModelError)
    try:
        data = json.loads(text)
        if data.get("format") != FORMAT:
            raise ModelError(f"collision matrix {path} is not a matrix file: format is not {FORMAT!r}")
        rule = data["rule"]
        shapes = tuple(str(s) for s in data["shapes"])

        def pairs(key: str) -> Pairs:
            out = tuple((int(a), int(b)) for a, b in data[key])
            if any(not 0 <= a < b < len(shapes) for a, b in out):
                raise ModelError(
                    f"collision matrix {path} is not a matrix file: a pair of {key!r} is not two shape indices, "
                    "first < second"
                )
            return out

        return CollisionMatrix(
            robot=str(data["robot"]),
            source=str(data["source"]),
            shapes=shapes,
            fingerprint=str(data["fingerprint"]),
            samples=int(rule["samples"]),
            seed=int(rule["seed"]),
            never_closer_than=float(rule["never_closer_than"]),
            checked=int(data["checked"]),
            always=pairs("always"),
            never=pairs("never"),
            adjacent=pairs("adjacent"),
        )
    except ModelError:
        raise
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ModelError(f"collision matrix {path} is not a matrix file: {exc}") from None


def stored_matrix(robot: Robot, source: str, geometry: pin.GeometryModel) -> CollisionMatrix | None:
    """The matrix stored beside the robot's spec (:func:`matrix_path`) for this source, or None
    if there is none; ``geometry`` is the robot's (:func:`mobmanip.robot.shape_pairs.robot_geometry`).

    Raises:
        ModelError: the file is not a matrix, or was made for other shapes or joint limits.
    """
    path = matrix_path(robot)
    if path is None or not path.is_file():
        return None
    matrix = read_collision_matrix(path)
    if matrix.source != source:
        return None
    matrix.check_fits(robot, geometry, path)
    return matrix
