"""mobmanip: what a wheeled mobile manipulator can do at the end effector.

Unified kinematic and dynamic task-space ellipsoids for mobile manipulators whose platform is
subject to nonholonomic constraints, built on Pinocchio.

The public API is what this package exports (below) and the documented modules the README
names: :mod:`mobmanip.sweep` (grids), :mod:`mobmanip.casestudy` (the paper's Section 4),
:mod:`mobmanip.measures` (the registry of measures), :mod:`mobmanip.errors` (every exception)
and :mod:`mobmanip.viz` (the viewer and figures).
"""

import logging

from . import old_paths
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
from .robot.model import Robot, load_robot
from .robot.spec import RobotSpec, load_spec
from .sets.ellipsoid import Ellipsoid
from .sets.polytope import Polytope
from .sets.taskset import TaskSet, TaskSetBatch
from .support.version import installed_version
from .sweep.runner import SweepGrid, SweepResult, SweepSpec, run_sweep
from .terms.dynamics import ReducedDynamics, reduced_dynamics, unified_jacobian

__all__ = [
    "ACCELERATION",
    "VELOCITY",
    "Analysis",
    "BatchAnalysis",
    "BatchRequest",
    "Ellipsoid",
    "EllipsoidBatch",
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
    "analyze",
    "analyze_batch",
    "default_measures",
    "get_measure",
    "load_robot",
    "load_spec",
    "measure_names",
    "reduced_dynamics",
    "register_measure",
    "run_sweep",
    "unified_jacobian",
    "unregister_measure",
]


__version__ = installed_version()
old_paths.install()  # the module paths before the layers, for one more release
logging.getLogger(__name__).addHandler(logging.NullHandler())  # quiet unless the application configures logging
