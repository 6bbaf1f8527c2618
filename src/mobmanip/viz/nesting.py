"""Which drawn sets contain which: the viewer draws a set that holds another as an outline, so
that the inner one stays in sight.

The sets of one analysis share the task point but not their scale (metres of scene per m/s and
per m/s^2 differ), so containment is decided on the sets *as drawn*: the drawn part
(:func:`mobmanip.viz.shapes.drawn_linear_part`) times its scale. For convex sets, B lies in A
iff A's support function is at least B's in every direction; it is checked on a fixed set of
directions (:func:`directions`), which is exact up to the sampling (a set that pokes out of
another by less than the gap between sampled directions can be missed).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping
from typing import TypeVar

import numpy as np

from ..errors import TaskError
from ..sets.taskset import TaskSet
from .shapes import drawn_linear_part

Key = TypeVar("Key", bound=Hashable)

#: Relative slack of the comparison (of the larger set's reach): sets that touch count as nested.
RELATIVE_TOL = 1e-9


def directions(k: int, n: int = 720) -> np.ndarray:
    """``n`` unit directions in ``k`` = 2 or 3 dimensions, (n, k): evenly spaced angles in the
    plane, a Fibonacci lattice on the sphere."""
    if k == 2:
        t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
        return np.column_stack([np.cos(t), np.sin(t)])
    if k == 3:
        i = np.arange(n) + 0.5
        z = 1.0 - 2.0 * i / n
        r = np.sqrt(1.0 - z * z)
        phi = np.pi * (1.0 + 5.0**0.5) * i
        return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    raise TaskError(f"directions in {k} dimensions are not drawn")


def drawn_supports(task_set: TaskSet, task: str, scale: float, D: np.ndarray) -> np.ndarray:
    """Support of the drawn part of a set, in metres from the task point, along each row of
    ``D`` (n, k) (k the drawn dimension)."""
    linear, _ = drawn_linear_part(task_set, task)
    return scale * linear.supports(D)


def nested(
    sets: Mapping[Key, TaskSet], task: str, scale: Callable[[Key], float], n: int = 720
) -> dict[Key, tuple[Key, ...]]:
    """For each non-empty set, the other non-empty sets its drawing contains (in ``sets``' order).

    Args:
        sets: the sets of one analysis (one task point), by key.
        task: their task space.
        scale: metres of scene per task unit of the set with a key, as drawn.
        n: how many directions are compared.
    """
    shown = {key: s for key, s in sets.items() if not s.empty}
    if not shown:
        return {}
    k = drawn_linear_part(next(iter(shown.values())), task)[0].dim
    D = directions(k, n)
    support = {key: drawn_supports(s, task, scale(key), D) for key, s in shown.items()}
    out: dict[Key, tuple[Key, ...]] = {}
    for a, ha in support.items():
        tol = RELATIVE_TOL * max(float(np.max(np.abs(ha))), 1e-12)
        out[a] = tuple(b for b, hb in support.items() if b != a and bool(np.all(hb <= ha + tol)))
    return out


def outlined(contains: Mapping[Key, tuple[Key, ...]]) -> dict[Key, tuple[Key, ...]]:
    """The sets drawn as outlines: those that contain another, with what they contain. Of two
    sets drawn the same (each contains the other), only the first listed is outlined."""
    out: dict[Key, tuple[Key, ...]] = {}
    keys = list(contains)
    for i, a in enumerate(keys):
        inner = tuple(b for b in contains[a] if not (a in contains.get(b, ()) and keys.index(b) < i))
        if inner:
            out[a] = inner
    return out
