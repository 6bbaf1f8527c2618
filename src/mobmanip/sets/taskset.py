"""What every task-space measure answers: the common interface of ellipsoids and polytopes.

A *measure* is a convex set of object (or end-effector) velocities or accelerations in an
m-dimensional task space: the unified ellipsoids of the paper and the exact capacity polytopes
they summarise. Users and the rest of the toolkit (sweeps, the command line, JSON, the viewer)
ask the same questions of each, through :class:`TaskSet`:

- ``support(d)``: max of d . p over the set (how far it reaches along d, from the origin);
- ``radius_along(d)``: how far it reaches from its :attr:`TaskSet.center` along a unit d
  (the *capacity* along d);
- ``contains(points)``: membership (a ``bool`` for one point, a bool array for several);
- ``project(dims)`` / ``slice(dims)``: the shadow on, or the cut through the centre in, a few
  task coordinates (e.g. the linear part of a spatial task);
- ``volume``, ``isotropy`` and :meth:`TaskSet.indices` for sweeps;
- ``empty`` (no point satisfies the limits, e.g. an overload) and ``degenerate`` (the set is
  flat: some direction cannot be moved in);
- ``to_dict()``: its JSON form.

An empty set never yields NaN or infinity from these queries: ``support``, ``radius_along``,
``volume`` and ``isotropy`` are 0 and ``contains`` is False; callers that must tell "no
capacity" from "empty" look at ``empty``. Bad arguments (a zero or non-finite direction, points
of the wrong dimension, coordinates out of range) raise :class:`mobmanip.errors.SetQueryError`;
:func:`check_direction`, :func:`check_points`, :func:`check_membership_points` and
:func:`check_dims` do these checks for every subclass.

Many configurations at once (sweeps) give a *batch* of sets of one kind: see
:class:`TaskSetBatch`. Which measures exist, and how each is computed, is the registry
:mod:`mobmanip.measures`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ..errors import SetQueryError

#: Scalar indices every measure gives for sweeps (see :meth:`TaskSet.indices`).
SCALAR_INDICES = ("volume", "isotropy")


class TaskSet(ABC):
    """A convex set in an m-dimensional task space (an ellipsoid or a polytope).

    Subclasses are immutable value objects; their arrays must not be written to.
    """

    #: What kind of set this is, e.g. ``"ellipsoid"`` or ``"polytope"`` (its JSON tag).
    kind: str = ""

    @property
    @abstractmethod
    def dim(self) -> int:
        """Task dimension m."""

    # Attributes every subclass has (dataclass fields or properties):
    #: The reference point capacities are measured from, (m,): an ellipsoid's centre; for a
    #: polytope the point its class documents (e.g. the origin for a symmetric velocity set).
    #: Meaningless when ``empty``.
    center: np.ndarray
    #: No point satisfies the limits (e.g. the torques cannot even hold the load).
    empty: bool
    #: The set has no interior in the task space (some direction has zero reach).
    degenerate: bool

    @property
    @abstractmethod
    def volume(self) -> float:
        """m-dimensional volume (0 when empty or degenerate)."""

    @property
    @abstractmethod
    def isotropy(self) -> float:
        """Smallest over largest reach from the centre, in [0, 1] (0 when empty or degenerate)."""

    @abstractmethod
    def support(self, direction: np.ndarray) -> float:
        """max over the set of d . p for a direction d, (m,) (not necessarily unit); 0 when empty."""

    def supports(self, directions: ArrayLike) -> np.ndarray:
        """:meth:`support` for each row of ``directions`` (k, m), (k,)."""
        return np.array([self.support(d) for d in np.atleast_2d(np.asarray(directions, dtype=float))])

    @abstractmethod
    def radius_along(self, direction: np.ndarray) -> float:
        """How far the set reaches from :attr:`center` along the unit direction of d; 0 when empty."""

    @abstractmethod
    def contains(self, points: ArrayLike, tol: float = 1e-9) -> bool | np.ndarray:
        """Whether points lie in the set (within ``tol``), as NumPy answers elementwise questions:
        one point, shape (m,), gives a Python ``bool``; n points, shape (n, m), give a bool array
        (n,) (also for n = 1). Any other shape is a :class:`~mobmanip.errors.SetQueryError` naming
        it (:func:`check_membership_points` and :func:`membership` do both for a subclass)."""

    @abstractmethod
    def project(self, dims: Sequence[int] = (0, 1)) -> TaskSet:
        """The shadow of the set on the task coordinates ``dims`` (others free)."""

    @abstractmethod
    def slice(self, dims: Sequence[int] = (0, 1)) -> TaskSet:
        """The cut through :attr:`center` in the coordinates ``dims`` (others at the centre's)."""

    @abstractmethod
    def to_dict(self) -> dict:
        """JSON-ready dictionary; always holds ``"kind"``, ``"empty"`` and ``"degenerate"``."""

    def indices(self) -> dict[str, float]:
        """The scalar indices sweeps record, by name (at least :data:`SCALAR_INDICES`)."""
        return {"volume": self.volume, "isotropy": self.isotropy}


@runtime_checkable
class TaskSetBatch(Protocol):
    """N sets of one kind in an m-dimensional task space, as stacked arrays (a sweep's chunk).

    Row n is the set ``batch[n]`` (a :class:`TaskSet`); the arrays answer for all rows at once.
    :class:`mobmanip.batch.EllipsoidBatch` is one. A measure's batch form returns these, and a
    sweep records ``volume``, ``isotropy``, ``support`` and ``straight_line_reach`` along its
    capacity direction (NaN for a batch without the latter), the
    ``degenerate`` and ``empty`` flags and the per-axis arrays the measure names
    (:attr:`mobmanip.measures.Measure.axis_indices`).
    """

    @property
    def volume(self) -> np.ndarray:
        """Volumes, (N,) (0 where empty or degenerate)."""

    @property
    def isotropy(self) -> np.ndarray:
        """Isotropies in [0, 1], (N,) (0 where empty or degenerate)."""

    @property
    def degenerate(self) -> np.ndarray:
        """Whether each set has a zero extent in some direction, (N,) bool."""

    @property
    def empty(self) -> np.ndarray:
        """Whether each set is empty, (N,) bool."""

    def support(self, direction: np.ndarray) -> np.ndarray:
        """max over set n of d . p, (N,), for one direction (m,) or one per row (N, m)."""

    def straight_line_reach(self, direction: np.ndarray) -> np.ndarray:
        """The largest s >= 0 with ``s d / |d|`` in set n, (N,), for one direction (m,) or one per
        row (N, m); 0 where the ray from the origin misses the set or it is empty."""

    def __len__(self) -> int: ...

    def __getitem__(self, index: int) -> TaskSet: ...


def check_direction(direction: ArrayLike, m: int, where: str = "direction") -> np.ndarray:
    """A direction as a float array (m,), checked: finite and not zero.

    Raises:
        SetQueryError: wrong shape, a NaN or infinite entry, or the zero vector.
    """
    try:
        d = np.asarray(direction, dtype=float)
    except (TypeError, ValueError):
        raise SetQueryError(f"{where} must be {m} numbers, got {direction!r}") from None
    if d.shape != (m,):
        raise SetQueryError(f"{where} must have shape ({m},) in this {m}-dimensional task space, got {d.shape}")
    if not np.all(np.isfinite(d)) or not np.any(d):
        raise SetQueryError(f"{where} must be finite and not zero, got {d.tolist()}")
    return d


def check_membership_points(points: ArrayLike, m: int) -> tuple[np.ndarray, bool]:
    """The points of a :meth:`TaskSet.contains` query as a float array (n, m), checked finite, and
    whether one point was given: shape (m,) (or a scalar when m = 1) is one point, (n, m) is n.

    Raises:
        SetQueryError: any other shape (named), or a NaN or infinite entry.
    """
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise SetQueryError(f"points must be numbers of shape ({m},) or (n, {m}), got {points!r}") from None
    single = p.ndim == 1 or (p.ndim == 0 and m == 1)
    if not (p.shape == (m,) or (p.ndim == 0 and m == 1) or (p.ndim == 2 and p.shape[1] == m)):
        raise SetQueryError(
            f"points must have shape ({m},) for one point or (n, {m}) for n points in this {m}-dimensional "
            f"task space, got shape {p.shape}"
        )
    if not np.all(np.isfinite(p)):
        raise SetQueryError("points must be finite (a NaN or infinite coordinate was given)")
    return p.reshape(-1, m), single


def membership(inside: np.ndarray, single: bool) -> bool | np.ndarray:
    """A :meth:`TaskSet.contains` answer: a Python bool for one point, the bool array (n,) for n."""
    return bool(inside[0]) if single else np.asarray(inside, dtype=bool)


def check_points(points: ArrayLike, m: int) -> np.ndarray:
    """Points as a float array (n, m) (one point (m,) becomes (1, m)), checked finite.

    Raises:
        SetQueryError: wrong shape or a NaN or infinite entry.
    """
    try:
        p = np.atleast_2d(np.asarray(points, dtype=float))
    except (TypeError, ValueError):
        raise SetQueryError(f"points must be numbers of shape (n, {m}), got {points!r}") from None
    if p.ndim != 2 or p.shape[1] != m:
        raise SetQueryError(f"points must have shape (n, {m}) or ({m},), got {np.shape(points)}")
    if not np.all(np.isfinite(p)):
        raise SetQueryError("points must be finite (a NaN or infinite coordinate was given)")
    return p


def check_dims(dims: Sequence[int], m: int) -> list[int]:
    """Task coordinates for :meth:`TaskSet.project` / :meth:`TaskSet.slice`, checked.

    Raises:
        SetQueryError: empty, repeated, not integers, or outside 0 .. m - 1.
    """
    try:
        items: list = list(dims)
    except TypeError:
        items = [dims]
    ok = all(isinstance(i, (int, np.integer)) and not isinstance(i, bool) for i in items)
    out = [int(i) for i in items] if ok else []
    if not ok or not out or len(set(out)) != len(out) or min(out) < 0 or max(out) >= m:
        raise SetQueryError(f"dims must be distinct task coordinates among 0 .. {m - 1}, got {dims!r}")
    return out
