"""Grasp matrix and object dynamics (paper Eq. 17-22) for rigid grasps.

An object is held at grasp points p_i (one per end effector). With r_i = p_i - c the offset from
the object centre c, each end effector moves as v_i = W_i^T v_o and the object feels
h_o = sum_i W_i h_i. Rows of W_i: force, then moment = r_i x f_i + n_i, restricted to the task.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import TaskError
from ..robot.tasks import TaskSpace, get_task
from ..support.ranges import OBJECT_MASS, check_in_range

if TYPE_CHECKING:
    from ..robot.model import Robot

GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2, world frame (z up), as Pinocchio's default


def skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def wrench_shift(r: np.ndarray) -> np.ndarray:
    """[[I, 0], [skew(r), I]], (6, 6): a wrench [force; moment] applied at ``r`` (m, from a point)
    as the wrench about that point, [f; m + r x f]."""
    out = np.eye(6)
    out[3:, :3] = skew(np.asarray(r, dtype=float))
    return out


def grasp_block(task: str | TaskSpace, offset: np.ndarray) -> np.ndarray:
    """W_i for one rigid grasp at ``offset`` r_i (m) from the object centre, (m, m).

    The full spatial block is [[I, 0], [skew(r_i), I]] (force rows, then moment rows); a task
    keeps the rows and columns of its own coordinates. For ``planar`` and ``translational`` (no
    rotation in the task) this is the identity.
    """
    task = get_task(task)
    return task.restrict(wrench_shift(offset))


def grasp_matrix(task: str | TaskSpace, offsets: np.ndarray) -> np.ndarray:
    """W = [W_1 W_2 ...] for grasps at ``offsets`` (k, 3) from the object centre, (m, m k)."""
    task = get_task(task)
    offsets = np.atleast_2d(np.asarray(offsets, dtype=float))
    if not task.angular_rows:  # no rotation in the task: every W_i is the identity
        return np.tile(np.eye(task.dim), (1, len(offsets)))
    return np.hstack([grasp_block(task, r) for r in offsets])


@dataclass(frozen=True)
class HeldObject:
    """A rigid object held by the end effectors.

    Attributes:
        mass: object mass (kg).
        inertia: rotational inertia about its centre, world axes (kg m^2), (3, 3).
        center: position of its centre in the world (m), (3,).
        offsets: grasp points relative to the centre, one row per end effector (m), (k, 3).
    """

    mass: float
    inertia: np.ndarray
    center: np.ndarray
    offsets: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "mass", checked_object_mass(self.mass))
        inertia, center, offsets = self.inertia, self.center, self.offsets
        arrays = all(type(a) is np.ndarray and a.dtype == np.float64 for a in (inertia, center, offsets))
        if arrays and inertia.shape == (3, 3) and center.shape == (3,) and offsets.ndim == 2 and offsets.shape[1] == 3:
            # the common case (analyze builds one per call): one cheap test, the exact one if it fails
            if math.isfinite(float(inertia.sum()) + float(center.sum()) + float(offsets.sum())):
                return
        for name, value, shape in (
            ("inertia", inertia, "(3, 3)"),
            ("center", center, "(3,)"),
            ("offsets", offsets, "(k, 3)"),
        ):
            try:
                array = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise TaskError(f"object {name} must be numbers of shape {shape}, got {value!r}") from None
            good_shape = array.shape == {"inertia": (3, 3), "center": (3,)}.get(name, (len(array), 3))
            if array.ndim != (1 if name == "center" else 2) or not good_shape or not np.all(np.isfinite(array)):
                raise TaskError(f"object {name} must be finite numbers of shape {shape}, got {value!r}")

    @classmethod
    def between(cls, grasp_points: np.ndarray, mass: float, inertia: np.ndarray | None = None) -> HeldObject:
        """An object centred at the centroid of the grasp points.

        Without an explicit inertia, the object is taken as a uniform solid sphere whose
        radius reaches the farthest grasp point (I = 2/5 m R^2), a neutral default for a box held
        between the hands. Coincident grasp points give a point mass.
        """
        mass = checked_object_mass(mass)
        points = np.asarray(grasp_points, dtype=float).reshape(-1, 3)
        center = np.add.reduce(points, axis=0) / points.shape[0]
        offsets = points - center
        if inertia is None:  # per-call cost matters here: analyze builds one per configuration
            radius2 = float(np.maximum.reduce(np.einsum("ij,ij->i", offsets, offsets)))
            inertia = np.zeros((3, 3))
            inertia.flat[::4] = 0.4 * mass * radius2
        return cls(float(mass), np.asarray(inertia, dtype=float), center, offsets)

    def inertia_matrix(self, task: str | TaskSpace) -> np.ndarray:
        """M_o in the task space: mass on linear rows, rotational inertia on angular rows, (m, m)."""
        task = get_task(task)
        if not task.angular_rows:
            return self.mass * np.eye(task.dim)
        full = np.zeros((6, 6))
        full[:3, :3] = self.mass * np.eye(3)
        full[3:, 3:] = self.inertia
        return task.restrict(full)

    def gravity_vector(self, task: str | TaskSpace, gravity: np.ndarray = GRAVITY) -> np.ndarray:
        """g_o in Eq. 22: the wrench the grasps must supply to hold the object still, (m,).

        At rest M_o a_o + g_o = h_o, so g_o = -m g on the linear rows; the centre of mass is the
        object centre, so gravity adds no moment.
        """
        task = get_task(task)
        full = np.zeros(6)
        full[:3] = -self.mass * np.asarray(gravity, dtype=float)
        return full[task.index]

    def grasp_matrix(self, task: str | TaskSpace) -> np.ndarray:
        """W for this object's grasp points, (m, m k)."""
        return grasp_matrix(task, self.offsets)


def object_mass_of(robot: Robot, object_mass: object = None) -> float:
    """The mass of the object a call holds (kg): ``object_mass``, else the robot's spec's
    ``[object] mass``; checked (:func:`checked_object_mass`). The one place a call's object mass
    is defaulted.

    Raises:
        TaskError, RangeError: as :func:`checked_object_mass`.
    """
    return checked_object_mass(robot.spec.object_mass if object_mass is None else object_mass)


def held_mass(robot: Robot, object_mass: object = None, held_object: HeldObject | None = None) -> float:
    """The mass of the object a call holds (kg): ``held_object``'s, which must have one grasp
    offset per arm of ``robot``, else :func:`object_mass_of`'s.

    Raises:
        TaskError: a held object with another number of grasp offsets; as :func:`object_mass_of`.
    """
    if held_object is None:
        return object_mass_of(robot, object_mass)
    if held_object.offsets.shape != (len(robot.arms), 3):
        raise TaskError(
            f"the object needs one grasp offset per arm ({len(robot.arms)}), got {held_object.offsets.shape}"
        )
    return held_object.mass


def checked_object_mass(value: object) -> float:
    """An object mass (kg): a real number in :data:`mobmanip.support.ranges.OBJECT_MASS`.

    Raises:
        TaskError: not a number, not finite or negative; RangeError: above the supported range.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TaskError(f"object mass must be a finite non-negative number of kg, got {value!r}")
    try:
        mass = float(value)
    except OverflowError:
        mass = math.inf
    if not math.isfinite(mass) or mass < 0.0:
        raise TaskError(f"object mass must be a finite non-negative number of kg, got {value!r}")
    return check_in_range("object mass", mass, *OBJECT_MASS, unit="kg")
