"""Sweeps: the measures over a grid of object directions, distances, headings and limit scales.

The names the flat module ``mobmanip.sweep`` of 0.1 also exported (index names, the planar
postures, two errors) still resolve here for one release, with a :class:`DeprecationWarning`
naming where each lives now; ``plot_sweep`` is :func:`mobmanip.viz.sweep_plot.plot_sweep`.
"""

import warnings

from .budget import MAX_GRID_POINTS, SweepEstimate
from .results import SweepResult
from .runner import (
    POSTURE_METHODS,
    SweepGrid,
    SweepSpec,
    default_workers,
    parse_grid,
    run_sweep,
    sweep_configurations,
    sweep_postures,
)

__all__ = [
    "MAX_GRID_POINTS",
    "POSTURE_METHODS",
    "SweepEstimate",
    "SweepGrid",
    "SweepResult",
    "SweepSpec",
    "default_workers",
    "parse_grid",
    "run_sweep",
    "sweep_configurations",
    "sweep_postures",
]

#: Names of the 0.1 module ``mobmanip.sweep`` that live elsewhere now: name -> its module.
_MOVED_NAMES = {
    **dict.fromkeys(("AXES", "FLAGS", "SCALAR_INDICES", "check_index_name", "index_names"), "mobmanip.sweep.results"),
    **dict.fromkeys(
        (
            "PlanarArm",
            "PostureTable",
            "ReachPosture",
            "planar_arm",
            "posture_at_reach",
            "posture_table",
            "postures_at_reaches",
        ),
        "mobmanip.postures.planar",
    ),  # fmt: skip
    **dict.fromkeys(("GridError", "UnreachableGridError"), "mobmanip.errors"),
}


def __getattr__(name: str) -> object:
    """The 0.1 names of :data:`_MOVED_NAMES`, with a :class:`DeprecationWarning`."""
    if name == "plot_sweep":
        raise AttributeError("mobmanip.sweep.plot_sweep moved to mobmanip.viz.sweep_plot.plot_sweep")
    if name not in _MOVED_NAMES:
        raise AttributeError(f"module 'mobmanip.sweep' has no attribute {name!r}")
    from .. import errors
    from ..postures import planar
    from . import results

    module = {"mobmanip.sweep.results": results, "mobmanip.postures.planar": planar, "mobmanip.errors": errors}
    warnings.warn(
        f"mobmanip.sweep.{name} moved to {_MOVED_NAMES[name]}.{name}; the old name will be removed in the next release",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(module[_MOVED_NAMES[name]], name)
