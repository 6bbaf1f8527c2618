"""The public API is typed: every function and method reachable from ``mobmanip.__all__`` (and
from the documented modules' own public names) annotates each parameter and its return value,
and the package ships the ``py.typed`` marker so type checkers read those annotations."""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import pytest

import mobmanip

#: Modules whose public names (no leading underscore, defined in the module) are the API.
PUBLIC_MODULES = [
    "mobmanip",
    "mobmanip.analysis",
    "mobmanip.terms.dynamics",
    "mobmanip.sets.ellipsoid",
    "mobmanip.sets.taskset",
    "mobmanip.measures",
    "mobmanip.sets.polytope",
    "mobmanip.sets.capacity",
    "mobmanip.sets.capacity_batch",
    "mobmanip.robot.model",
    "mobmanip.robot.spec",
    "mobmanip.sweep",
    "mobmanip.sweep.results",
    "mobmanip.casestudy",
    "mobmanip.errors",
    "mobmanip.batch",
    "mobmanip.terms.grasp",
    "mobmanip.robot.tasks",
    "mobmanip.robot.detect",
    "mobmanip.gradients",
    "mobmanip.placement",
    "mobmanip.postures.inverse_kinematics",
    "mobmanip.descriptions",
    "mobmanip.descriptions.description",
    "mobmanip.descriptions.checks",
    "mobmanip.descriptions.formats",
    "mobmanip.descriptions.urdf",
    "mobmanip.descriptions.resources",
    "mobmanip.viz.scene",
    "mobmanip.viz.sweeps",
    "mobmanip.viz.figures",
    "mobmanip.team",
    "mobmanip.team.analysis",
    "mobmanip.team.sweep",
    "mobmanip.motion",
    "mobmanip.coordination",
    "mobmanip.coordination.carry",
    "mobmanip.coordination.capacity",
    "mobmanip.coordination.effort",
    "mobmanip.coordination.platform_task",
    "mobmanip.motion.trajectory",
    "mobmanip.motion.trajectory_analysis",
    "mobmanip.motion.carry",
    "mobmanip.placement.maps",
    "mobmanip.robot.collision",
    "mobmanip.robot.collision_matrix",
    "mobmanip.robot.shape_pairs",
    "mobmanip.viz.placement",
    "mobmanip.viz.motion_figures",
    "mobmanip.commands.outputs",
    "mobmanip.cli",
    "mobmanip.old_paths",
    "mobmanip.placement.grid",
    "mobmanip.platforms",
    "mobmanip.postures.named",
    "mobmanip.robot.configurations",
    "mobmanip.sets.polytope_vertices",
    "mobmanip.sets.zonotope",
    "mobmanip.support.files",
    "mobmanip.support.ranges",
    "mobmanip.support.tolerances",
    "mobmanip.viz.sweep_plot",
    "mobmanip.viz.team_figure",
    "mobmanip.viz.labels",
    "mobmanip.viz.nesting",
    "mobmanip.robot.support",
    "mobmanip.robot.support_spec",
    "mobmanip.terms.constraints.base",
    "mobmanip.terms.constraints.joint_limits",
    "mobmanip.terms.problems",
    "mobmanip.terms.builder",
    "mobmanip.measures.ellipsoids",
    "mobmanip.measures.polytopes",
    "mobmanip.analysis.reaches",
    "mobmanip.sweep.spec",
    "mobmanip.postures.planar",
    "mobmanip.sets.force",
    "mobmanip.terms.force",
    "mobmanip.measures.force",
]


def _public_callables():
    seen = set()
    for module_name in PUBLIC_MODULES:
        module = importlib.import_module(module_name)
        names = getattr(module, "__all__", None) or [n for n in vars(module) if not n.startswith("_")]
        for name in names:
            obj = getattr(module, name)
            if module_name != "mobmanip" and getattr(obj, "__module__", None) != module_name:
                continue  # imported from elsewhere: checked where it is defined
            if inspect.isclass(obj):
                if issubclass(obj, BaseException) or getattr(obj, "_is_protocol", False):
                    continue  # exceptions (documented by their messages) and protocols (no constructor)
                for attr, member in vars(obj).items():
                    if attr.startswith("_") and attr != "__init__":
                        continue
                    func = member.__func__ if isinstance(member, (classmethod, staticmethod)) else member
                    if isinstance(func, property):
                        func = func.fget
                    if inspect.isfunction(func) and func not in seen:
                        seen.add(func)
                        yield f"{obj.__module__}.{obj.__qualname__}.{attr}", func
            elif inspect.isfunction(obj) and obj not in seen:
                seen.add(obj)
                yield f"{obj.__module__}.{name}", obj


CALLABLES = sorted(_public_callables(), key=lambda item: item[0])


def _missing(func) -> list[str]:
    signature = inspect.signature(func)
    missing = [
        p.name
        for p in signature.parameters.values()
        if p.name not in ("self", "cls") and p.annotation is inspect.Parameter.empty
    ]
    if func.__name__ != "__init__" and signature.return_annotation is inspect.Signature.empty:
        missing.append("return")
    return missing


def test_there_is_an_api_to_check():
    assert len(CALLABLES) > 100


@pytest.mark.parametrize("name, func", CALLABLES, ids=[name for name, _ in CALLABLES])
def test_annotated(name, func):
    assert _missing(func) == [], f"{name} lacks annotations for {_missing(func)}"


def test_py_typed_marker_ships_with_the_package():
    assert (Path(mobmanip.__file__).parent / "py.typed").is_file()
