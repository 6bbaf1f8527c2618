"""mobmanip: what a wheeled mobile manipulator can do at the end effector.

Unified kinematic and dynamic task-space ellipsoids for mobile manipulators whose platform is
subject to nonholonomic constraints, built on Pinocchio.

The public API is what this package exports (below) and the documented modules the docs
name: :mod:`mobmanip.sweep` (grids), :mod:`mobmanip.casestudy` (the paper's Section 4),
:mod:`mobmanip.measures` (the registry of measures), :mod:`mobmanip.errors` (every exception)
and :mod:`mobmanip.viz` (the viewer and figures).
"""

from __future__ import annotations

import importlib
import logging
from typing import TYPE_CHECKING, Any

from . import old_paths

#: Public name -> the module (relative to this package) that defines it. The names are imported
#: when first used, so that importing the package (and the ``mobmanip`` command's module) is
#: quick and a Ctrl-C while NumPy or Pinocchio loads reaches the command's own handler.
_EXPORTS: dict[str, str] = {
    "Analysis": ".analysis.single",
    "analyze": ".analysis.single",
    "BatchAnalysis": ".batch",
    "EllipsoidBatch": ".batch",
    "analyze_batch": ".batch",
    "MobmanipError": ".errors",
    **dict.fromkeys(
        (
            "ACCELERATION",
            "VELOCITY",
            "BatchRequest",
            "Measure",
            "MeasureTerms",
            "Quantity",
            "default_measures",
            "get_measure",
            "measure_names",
            "register_measure",
            "unregister_measure",
        ),
        ".measures",
    ),
    "Robot": ".robot.model",
    "load_robot": ".robot.model",
    "RobotSpec": ".robot.spec",
    "load_spec": ".robot.spec",
    "Ellipsoid": ".sets.ellipsoid",
    "Polytope": ".sets.polytope",
    "TaskSet": ".sets.taskset",
    "TaskSetBatch": ".sets.taskset",
    **dict.fromkeys(("SweepGrid", "SweepResult", "SweepSpec", "run_sweep"), ".sweep.runner"),
    **dict.fromkeys(("ReducedDynamics", "reduced_dynamics", "unified_jacobian"), ".terms.dynamics"),
    **dict.fromkeys(("Constraint", "ConstraintRows", "EffortBox", "VelocityBox"), ".terms.constraints"),
    "Floor": ".terms.constraints.floor",
    "named_configuration": ".postures.named",
}

if TYPE_CHECKING:
    from .analysis.single import Analysis, analyze
    from .batch import BatchAnalysis, EllipsoidBatch, analyze_batch
    from .errors import MobmanipError
    from .measures import (
        ACCELERATION,
        VELOCITY,
        BatchRequest,
        Measure,
        MeasureTerms,
        Quantity,
        default_measures,
        get_measure,
        measure_names,
        register_measure,
        unregister_measure,
    )
    from .postures.named import named_configuration
    from .robot.model import Robot, load_robot
    from .robot.spec import RobotSpec, load_spec
    from .sets.ellipsoid import Ellipsoid
    from .sets.polytope import Polytope
    from .sets.taskset import TaskSet, TaskSetBatch
    from .sweep.runner import SweepGrid, SweepResult, SweepSpec, run_sweep
    from .terms.constraints import Constraint, ConstraintRows, EffortBox, VelocityBox
    from .terms.constraints.floor import Floor
    from .terms.dynamics import ReducedDynamics, reduced_dynamics, unified_jacobian


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (PEP 562)."""
    if name == "__version__":
        from .support.version import installed_version

        globals()[name] = installed_version()
        return globals()[name]
    module = _EXPORTS.get(name)
    if module is None:
        moved = old_paths.moved_module(__name__, name)  # a module path of the last release, e.g. mobmanip.grasp
        if moved is not None:
            return moved
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS, "__version__"})


__all__ = [
    "ACCELERATION",
    "VELOCITY",
    "Analysis",
    "BatchAnalysis",
    "BatchRequest",
    "Constraint",
    "ConstraintRows",
    "EffortBox",
    "Ellipsoid",
    "EllipsoidBatch",
    "Floor",
    "Measure",
    "MeasureTerms",
    "MobmanipError",
    "Polytope",
    "Quantity",
    "ReducedDynamics",
    "Robot",
    "RobotSpec",
    "SweepGrid",
    "SweepResult",
    "SweepSpec",
    "TaskSet",
    "TaskSetBatch",
    "VelocityBox",
    "analyze",
    "analyze_batch",
    "default_measures",
    "get_measure",
    "load_robot",
    "load_spec",
    "measure_names",
    "named_configuration",
    "reduced_dynamics",
    "register_measure",
    "run_sweep",
    "unified_jacobian",
    "unregister_measure",
]


old_paths.install()  # the module paths before the layers, for one more release
logging.getLogger(__name__).addHandler(logging.NullHandler())  # quiet unless the application configures logging
