"""Task spaces: which rows of a 6-D frame velocity (linear, then angular) a task keeps."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import TaskError


@dataclass(frozen=True)
class TaskSpace:
    """A task space.

    Attributes:
        name: its name.
        rows: indices into a 6-D twist [v_x, v_y, v_z, w_x, w_y, w_z] (world-aligned axes).
        labels: one label per kept row.
        angular: for each kept row, whether it is angular (rad/s) rather than linear (m/s).
    """

    name: str
    rows: tuple[int, ...]
    labels: tuple[str, ...]

    @property
    def dim(self) -> int:
        """Task dimension m."""
        return len(self.rows)

    @property
    def index(self) -> np.ndarray:
        """``rows`` as an integer array, for fancy indexing."""
        return np.array(self.rows)

    def restrict(self, full: np.ndarray) -> np.ndarray:
        """The task's rows and columns of a 6 x 6 matrix (``full`` itself for the 6-D task)."""
        if self.rows == (0, 1, 2, 3, 4, 5):
            return full
        return full[np.ix_(self.rows, self.rows)]

    @property
    def angular(self) -> np.ndarray:
        return np.array([r >= 3 for r in self.rows])

    @property
    def linear_rows(self) -> tuple[int, ...]:
        """Positions (within this task) of the linear rows."""
        return tuple(i for i, r in enumerate(self.rows) if r < 3)

    @property
    def angular_rows(self) -> tuple[int, ...]:
        """Positions (within this task) of the angular rows."""
        return tuple(i for i, r in enumerate(self.rows) if r >= 3)


TASKS: dict[str, TaskSpace] = {
    "planar": TaskSpace("planar", (0, 1), ("x", "y")),
    "planar_rigid": TaskSpace("planar_rigid", (0, 1, 5), ("x", "y", "yaw")),
    "translational": TaskSpace("translational", (0, 1, 2), ("x", "y", "z")),
    "spatial": TaskSpace("spatial", (0, 1, 2, 3, 4, 5), ("x", "y", "z", "roll", "pitch", "yaw")),
}


def get_task(name: str | TaskSpace) -> TaskSpace:
    """Look a task space up by name.

    Raises:
        TaskError: unknown name (the message lists the valid ones).
    """
    if isinstance(name, TaskSpace):
        return name
    try:
        return TASKS[name]
    except KeyError:
        raise TaskError(f"unknown task {name!r}; expected one of {', '.join(TASKS)}") from None
