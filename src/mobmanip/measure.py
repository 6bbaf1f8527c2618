"""What every task-space measure answers: the common interface of ellipsoids and polytopes.

A *measure* is a convex set of object (or end-effector) velocities or accelerations in an
m-dimensional task space: the unified ellipsoids of the paper and the exact capacity polytopes
they summarise. Users and the rest of the toolkit (sweeps, the command line, JSON, the viewer)
ask the same questions of each, through :class:`TaskSet`:

- ``support(d)``: max of d . p over the set (how far it reaches along d, from the origin);
- ``radius_along(d)``: how far it reaches from its :attr:`TaskSet.center` along a unit d
  (the *capacity* along d);
- ``contains(points)``: membership;
- ``project(dims)`` / ``slice(dims)``: the shadow on, or the cut through the centre in, a few
  task coordinates (e.g. the linear part of a spatial task);
- ``volume``, ``isotropy`` and :meth:`TaskSet.indices` for sweeps;
- ``empty`` (no point satisfies the limits, e.g. an overload) and ``degenerate`` (the set is
  flat: some direction cannot be moved in);
- ``to_dict()``: its JSON form.

An empty set never yields NaN or infinity from these queries: ``support``, ``radius_along``,
``volume`` and ``isotropy`` are 0 and ``contains`` is all False; callers that must tell "no
capacity" from "empty" look at ``empty``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np

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

    @abstractmethod
    def radius_along(self, direction: np.ndarray) -> float:
        """How far the set reaches from :attr:`center` along the unit direction of d; 0 when empty."""

    @abstractmethod
    def contains(self, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
        """Whether points, (n, m) or (m,), lie in the set (within ``tol``); bool array (n,)."""

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
