"""mobmanip: what a wheeled mobile manipulator can do at the end effector.

Unified kinematic and dynamic task-space ellipsoids for mobile manipulators whose platform is
subject to nonholonomic constraints, built on Pinocchio.
"""

from .analysis import Analysis, analyze
from .batch import BatchAnalysis, analyze_batch
from .dynamics import ReducedDynamics, reduced_dynamics, unified_jacobian
from .ellipsoids import Ellipsoid
from .errors import MobmanipError
from .model import Robot, load_robot
from .polytope import Polytope
from .spec import RobotSpec, load_spec

__all__ = [
    "Analysis",
    "BatchAnalysis",
    "Ellipsoid",
    "MobmanipError",
    "Polytope",
    "ReducedDynamics",
    "Robot",
    "RobotSpec",
    "analyze",
    "analyze_batch",
    "load_robot",
    "load_spec",
    "reduced_dynamics",
    "unified_jacobian",
]
__version__ = "0.1.0"
