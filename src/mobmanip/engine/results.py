"""What the engine returns: stacks of ellipsoids and the analysis of a batch of configurations."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SetQueryError
from ..robot.model import Robot
from ..sets.ellipsoid import Ellipsoid, straight_line_reaches


@dataclass(frozen=True)
class EllipsoidBatch:
    """N ellipsoids in an m-dimensional task space, as stacked arrays.

    Row n describes the same set as :class:`mobmanip.sets.ellipsoid.Ellipsoid`:
    ``{center[n] + sum_k semi_axes[n, k] z_k axes[n, k] : ||z|| <= 1}``.

    Attributes:
        center: centres, (N, m).
        semi_axes: semi-axis lengths, descending, (N, m); zero where the task cannot move.
        axes: unit directions, ``axes[n, k]`` belongs to ``semi_axes[n, k]``, (N, m, m).
        matrix: A with (p - c)^T A (p - c) <= 1 (pseudo-inverse form when degenerate), (N, m, m).
        degenerate: some semi-axis is zero, (N,).
        empty: the limits cannot even hold the load still, (N,); semi-axes are then zero.
    """

    center: np.ndarray
    semi_axes: np.ndarray
    axes: np.ndarray
    matrix: np.ndarray
    degenerate: np.ndarray
    empty: np.ndarray

    def __len__(self) -> int:
        return int(self.semi_axes.shape[0])

    @property
    def dim(self) -> int:
        """Task dimension m."""
        return int(self.semi_axes.shape[1])

    @property
    def volume(self) -> np.ndarray:
        """Volumes, (N,): pi^(m/2) / Gamma(m/2 + 1) prod_k s_k."""
        m = self.dim
        return math.pi ** (m / 2) / math.gamma(m / 2 + 1) * np.prod(self.semi_axes, axis=1)

    @property
    def manipulability(self) -> np.ndarray:
        """Products of the semi-axes, (N,)."""
        return np.prod(self.semi_axes, axis=1)

    @property
    def isotropy(self) -> np.ndarray:
        """Smallest over largest semi-axis, (N,), 0 when degenerate or empty."""
        largest = self.semi_axes[:, 0]
        safe = np.where(largest > 0.0, largest, 1.0)
        return np.where(largest > 0.0, self.semi_axes[:, -1] / safe, 0.0)

    @property
    def generator(self) -> np.ndarray:
        """G with ellipsoid n = {c_n + G_n z : ||z|| <= 1}, (N, m, m)."""
        return np.swapaxes(self.axes, 1, 2) * self.semi_axes[:, None, :]

    def radius_along(self, direction: np.ndarray) -> np.ndarray:
        """How far each ellipsoid reaches from its centre along a direction (capacity), (N,).

        Args:
            direction: one direction for all rows, (m,), or one per row, (N, m); normalised here.
        """
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        along = np.einsum("nkj,...j->nk", self.axes, d) if d.ndim == 1 else np.einsum("nkj,nj->nk", self.axes, d)
        return np.sqrt(np.sum((along * self.semi_axes) ** 2, axis=1))

    def support(self, direction: np.ndarray) -> np.ndarray:
        """max over ellipsoid n of d . p, (N,), for one direction (m,) or one per row (N, m)."""
        d = np.asarray(direction, dtype=float)
        along = np.einsum("nkj,...j->nk", self.axes, d) if d.ndim == 1 else np.einsum("nkj,nj->nk", self.axes, d)
        offset = self.center @ d if d.ndim == 1 else np.einsum("nj,nj->n", self.center, d)
        return offset + np.sqrt(np.sum((along * self.semi_axes) ** 2, axis=1))

    def straight_line_reach(self, direction: np.ndarray) -> np.ndarray:
        """The largest s >= 0 with ``s d / |d|`` in ellipsoid n, (N,): how far along d from rest
        (the origin), for one direction (m,) or one per row (N, m); 0 where the ray misses the
        set or it is empty (closed form, :func:`mobmanip.sets.ellipsoid.straight_line_reaches`).

        Raises:
            SetQueryError: a direction of the wrong shape, zero or not finite.
        """
        d = np.asarray(direction, dtype=float)
        n, m = len(self), self.dim
        if d.ndim == 1:
            d = np.broadcast_to(d, (n,) + d.shape)
        if d.shape != (n, m) or not np.all(np.isfinite(d)) or not np.all(d.any(axis=1)):
            raise SetQueryError(f"directions must be finite and non-zero, ({m},) or ({n}, {m}), got shape {d.shape}")
        reach = straight_line_reaches(self.center, self.semi_axes, self.axes, d)
        return np.where(self.empty, 0.0, reach) if self.empty.any() else reach

    def rows_view(self, rows: slice) -> EllipsoidBatch:
        """Views (not copies) of rows ``rows`` of every array: writing to them fills this batch."""
        return EllipsoidBatch(
            self.center[rows],
            self.semi_axes[rows],
            self.axes[rows],
            self.matrix[rows],
            self.degenerate[rows],
            self.empty[rows],
        )

    def __getitem__(self, index: int) -> Ellipsoid:
        """Row ``index`` as a single :class:`~mobmanip.sets.ellipsoid.Ellipsoid`."""
        return Ellipsoid(
            center=self.center[index].copy(),
            semi_axes=self.semi_axes[index].copy(),
            axes=self.axes[index].copy(),
            matrix=self.matrix[index].copy(),
            degenerate=bool(self.degenerate[index]),
            empty=bool(self.empty[index]),
        )

    @classmethod
    def allocate(cls, n: int, m: int) -> EllipsoidBatch:
        """N zero ellipsoids (flags False) in an m-dimensional task space, to be filled."""
        return cls(
            center=np.zeros((n, m)),
            semi_axes=np.zeros((n, m)),
            axes=np.zeros((n, m, m)),
            matrix=np.zeros((n, m, m)),
            degenerate=np.zeros(n, dtype=bool),
            empty=np.zeros(n, dtype=bool),
        )

    def put_rows(self, rows: np.ndarray | slice, other: EllipsoidBatch) -> None:
        """Write ``other``'s rows into rows ``rows`` (an index, mask or slice) of this batch."""
        self.center[rows] = other.center
        self.semi_axes[rows] = other.semi_axes
        self.axes[rows] = other.axes
        self.matrix[rows] = other.matrix
        self.degenerate[rows] = other.degenerate
        self.empty[rows] = other.empty


@dataclass(frozen=True)
class BatchAnalysis:
    """The ellipsoids at every configuration of a batch (robot and object at rest).

    Attributes:
        robot: the robot analysed (with its platform and limits).
        qs: configurations, (N, nq).
        task: task-space name.
        decoupled: whether the dynamic ellipsoids used the decoupled P.
        object_mass: mass of the held object (kg).
        kinematic: the unified kinematic ellipsoids (m/s, rad/s).
        dynamic: the unified dynamic ellipsoids (m/s^2, rad/s^2).
        end_effector_positions: world positions of the end effectors, (N, n_arms, 3), when the
            grasp needed them (tasks with rotation and several arms) or they were asked for;
            otherwise ``None``.
        svd_path: rows whose kinematic or dynamic ellipsoid took the SVD path, (N,).
    """

    robot: Robot
    qs: np.ndarray
    task: str
    decoupled: bool
    object_mass: float
    kinematic: EllipsoidBatch
    dynamic: EllipsoidBatch
    end_effector_positions: np.ndarray | None
    svd_path: np.ndarray

    def __len__(self) -> int:
        return int(self.qs.shape[0])

    @property
    def object_centers(self) -> np.ndarray | None:
        """Object centres (the centroid of the end effectors), (N, 3), or ``None``."""
        p = self.end_effector_positions
        return None if p is None else p.mean(axis=1)
