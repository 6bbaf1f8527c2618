"""The registry of measures (what task-space sets mobmanip computes, and how), and one module per
family of measures: :mod:`.ellipsoids` (the paper's two, computed by default), :mod:`.polytopes`
(the exact capacity polytopes) and :mod:`.force` (force capacity: the wrenches the object exerts on
the environment at rest). A new measure is one module with one :class:`Measure` definition
and one :func:`register_measure` call."""

from . import ellipsoids, polytopes  # noqa: F401  (registers the built-in measures, in this order)

# isort: split
from . import force  # noqa: F401  (the force measures, after the polytopes)
from .ellipsoids import DYNAMIC, KINEMATIC
from .polytopes import DYNAMIC_POLYTOPE, DYNAMIC_POLYTOPE_MIN_NORM, KINEMATIC_POLYTOPE, POLYTOPE_KINDS
from .registry import *  # noqa: F403 - the registry's public names
from .registry import __all__ as _REGISTRY_NAMES

__all__ = [
    *_REGISTRY_NAMES,
    "DYNAMIC",
    "DYNAMIC_POLYTOPE",
    "DYNAMIC_POLYTOPE_MIN_NORM",
    "KINEMATIC",
    "KINEMATIC_POLYTOPE",
    "POLYTOPE_KINDS",
]
