"""The module paths of mobmanip before its layers, importable for one more release.

Version 0.2 moved the flat modules into one subpackage per layer (see the CHANGELOG). Importing
an old path, e.g. ``mobmanip.ellipsoids``, gives the module at its new path,
``mobmanip.sets.ellipsoid`` (the same object, so attributes set on one are set on the other),
with a :class:`DeprecationWarning` that names the new path. The one module that was split,
``mobmanip.io``, gives a module holding the names of both of its successors.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import sys
import types
import warnings

#: Old module path -> its successor(s).
MOVED: dict[str, tuple[str, ...]] = {
    "mobmanip._native_stderr": ("mobmanip.support.native_stderr",),
    "mobmanip.carry": ("mobmanip.motion.carry",),
    "mobmanip.collision": ("mobmanip.robot.collision",),
    "mobmanip.derivatives": ("mobmanip.gradients.derivatives",),
    "mobmanip.detect": ("mobmanip.robot.detect",),
    "mobmanip.detect_report": ("mobmanip.robot.detect_report",),
    "mobmanip.dynamics": ("mobmanip.terms.dynamics",),
    "mobmanip.ellipsoids": ("mobmanip.sets.ellipsoid",),
    "mobmanip.gradient_adjoint": ("mobmanip.gradients.adjoint",),
    "mobmanip.grasp": ("mobmanip.terms.grasp",),
    "mobmanip.hull": ("mobmanip.sets.hull",),
    "mobmanip.io": (
        "mobmanip.support.files",
        "mobmanip.robot.configurations",
    ),
    "mobmanip.linear_programs": ("mobmanip.sets.linear_programs",),
    "mobmanip.measure": ("mobmanip.sets.taskset",),
    "mobmanip.model": ("mobmanip.robot.model",),
    "mobmanip.named_postures": ("mobmanip.postures.named",),
    "mobmanip.placement_grid": ("mobmanip.placement.grid",),
    "mobmanip.placement_map": ("mobmanip.placement.maps",),
    "mobmanip.planar_postures": ("mobmanip.postures.planar",),
    "mobmanip.plausibility": ("mobmanip.analysis.plausibility",),
    "mobmanip.polytope": ("mobmanip.sets.polytope",),
    "mobmanip.polytopes": ("mobmanip.sets.capacity",),
    "mobmanip.posture": ("mobmanip.postures.inverse_kinematics",),
    "mobmanip.ranges": ("mobmanip.support.ranges",),
    "mobmanip.resources": ("mobmanip.descriptions.resources",),
    "mobmanip.spec": ("mobmanip.robot.spec",),
    "mobmanip.sweep_budget": ("mobmanip.sweep.budget",),
    "mobmanip.sweep_results": ("mobmanip.sweep.results",),
    "mobmanip.tasks": ("mobmanip.robot.tasks",),
    "mobmanip.team_analysis": ("mobmanip.team.analysis",),
    "mobmanip.team_sweep": ("mobmanip.team.sweep",),
    "mobmanip.tolerances": ("mobmanip.support.tolerances",),
    "mobmanip.trajectory": ("mobmanip.motion.trajectory",),
    "mobmanip.trajectory_analysis": ("mobmanip.motion.trajectory_analysis",),
    "mobmanip.tree_adjoint": ("mobmanip.gradients.tree_adjoint",),
    "mobmanip.tree_kernel": ("mobmanip.gradients.tree_kernel",),
    "mobmanip.urdf": ("mobmanip.descriptions.urdf",),
    "mobmanip.zonotope": ("mobmanip.sets.zonotope",),
    "mobmanip.zonotope_kernel": ("mobmanip.sets.zonotope_kernel",),
}


class _MovedModules:
    """Finds an old path of :data:`MOVED` and loads it as its successor: a meta path finder and
    its loader by their methods (not subclassing :mod:`importlib.abc`, whose import costs more
    than the rest of importing the package's top level)."""

    def __init__(self) -> None:
        self._specs: dict[str, importlib.machinery.ModuleSpec | None] = {}

    def find_spec(self, fullname, path=None, target=None):
        if fullname not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec):
        targets = MOVED[spec.name]
        warnings.warn(
            f"{spec.name} moved to {' and '.join(targets)}; the old path will be removed in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        modules = [importlib.import_module(t) for t in targets]
        if len(modules) == 1:
            self._specs[spec.name] = modules[0].__spec__  # the import system overwrites it: restored below
            return modules[0]
        merged = types.ModuleType(spec.name, f"{spec.name}: the names of {' and '.join(targets)}")
        for module in reversed(modules):
            merged.__dict__.update({k: v for k, v in vars(module).items() if not k.startswith("__")})
        return merged

    def exec_module(self, module) -> None:
        if module.__spec__.name in self._specs:  # an alias of a real module: give it back its own spec
            module.__spec__ = self._specs.pop(module.__spec__.name)


def moved_module(package: str, name: str) -> types.ModuleType | None:
    """The module an old path stands for when it is reached as an attribute of its package
    (``mobmanip.grasp.HeldObject`` without ``import mobmanip.grasp``), with the same
    :class:`DeprecationWarning` as importing it, attributed to the caller's line.

    Args:
        package: the package's name (``"mobmanip"``).
        name: the attribute asked for.

    Returns:
        The module (for a split one, the module holding the names of its successors), or
        ``None`` when ``package.name`` is no old path.
    """
    full = f"{package}.{name}"
    if full not in MOVED:
        return None
    if full in sys.modules:
        return sys.modules[full]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # said below, at the caller's line
        module = importlib.import_module(full)
    warnings.warn(
        f"{full} moved to {' and '.join(MOVED[full])}; the old path will be removed in the next release",
        DeprecationWarning,
        stacklevel=3,  # moved_module, the package's __getattr__, the caller
    )
    return module


def install() -> None:
    """Put the finder on ``sys.meta_path`` (once)."""
    if not any(isinstance(finder, _MovedModules) for finder in sys.meta_path):
        sys.meta_path.append(_MovedModules())
