"""Analyse one configuration: reduced dynamics, unified Jacobian, grasp and the measures.

:func:`analyze` is the single entry point behind ``mobmanip analyze`` and the Python API;
:meth:`Analysis.to_dict` gives the JSON document the command writes. The measures computed
(by default the paper's kinematic and dynamic ellipsoids) come from :mod:`mobmanip.measures`.
"""

from __future__ import annotations

import copy
import functools
import types
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from ..engine import evaluate_one
from ..engine.compiled import kernel_ready
from ..errors import ArgumentError, MeasureError, MobmanipError
from ..measures import DYNAMIC, KINEMATIC, Measure, get_measure, resolve_measures
from ..robot.model import Robot
from ..robot.tasks import get_task
from ..sets.ellipsoid import Ellipsoid
from ..sets.taskset import TaskSet
from ..terms.builder import MeasureTerms, assemble_terms, terms_at
from ..terms.constraints.base import Constraint
from ..terms.dynamics import decouple, placed_end_effectors
from ..terms.grasp import HeldObject, held_mass, object_mass_of


@dataclass(frozen=True)
class Analysis:
    """Everything computed at one configuration (robot and object at rest).

    Attributes:
        robot: the robot analysed (with its platform and limits).
        q: configuration, (nq,).
        task: task-space name.
        decoupled: whether the dynamic ellipsoid used the decoupled P.
        unified_jacobian: J_u, (m * n_arms, nx).
        reduced_inertia: P (coupled), (nx, nx).
        reduced_inertia_decoupled: P with platform-arm blocks zeroed, (nx, nx).
        input_matrix: Q, (nx, nx).
        bias: xi at rest (= -S^T g), (nx,).
        end_effector_positions: world positions of the end effectors, (n_arms, 3).
        held_object: the object (its centre is the task point), or the end effector itself.
        grasp_matrix: W, (m, m * n_arms).
        measures: the task-space sets computed, by measure name, in the registry's order
            (read-only); see :mod:`mobmanip.measures`. By default ``kinematic`` and ``dynamic``.
        object_given: whether the object was given (``held_object=``) rather than the default
            one between the hands.
        given_terms: the terms the measures were computed from, when they were assembled
            (see :attr:`terms`).

    ``warnings`` (computed on first access) says what makes the numbers doubtful: the robot file's
    flaws repaired at load (:attr:`mobmanip.robot.model.Robot.warnings`), placeholder limits,
    torques that cannot hold the robot up, hands further apart than the object's grasp points
    (see :mod:`mobmanip.analysis.plausibility`).
    """

    robot: Robot
    q: np.ndarray
    task: str
    decoupled: bool
    unified_jacobian: np.ndarray
    reduced_inertia: np.ndarray
    reduced_inertia_decoupled: np.ndarray
    input_matrix: np.ndarray
    bias: np.ndarray
    end_effector_positions: np.ndarray
    held_object: HeldObject
    grasp_matrix: np.ndarray
    measures: Mapping[str, TaskSet]
    object_given: bool = False
    given_terms: MeasureTerms | None = field(default=None, repr=False)

    @functools.cached_property
    def terms(self) -> MeasureTerms:
        """What the measures were computed from (:class:`mobmanip.terms.builder.MeasureTerms`),
        with the constraints beyond the joint boxes they honour; assembled on first access when
        the compiled engine gave every set asked for."""
        if self.given_terms is not None:
            return self.given_terms
        return assemble_terms(
            self.robot, self.q, self.task, self.decoupled, self.unified_jacobian, self.reduced_inertia,
            self.bias, self.end_effector_positions, self.held_object, self.grasp_matrix,
        )  # fmt: skip

    @property
    def constraints(self) -> tuple[Constraint, ...]:
        """The constraints beyond the joint boxes that the sets were asked to honour."""
        return () if self.given_terms is None else self.given_terms.constraints

    def ignored_constraints(self, name: str) -> tuple[str, ...]:
        """The names of the constraints measure ``name`` ignored: those on its quantity's problem
        when it cannot honour constraints (an ellipsoid); empty for a polytope."""
        measure = get_measure(name)
        if measure.honours_constraints:
            return ()
        problem = "velocity" if measure.quantity.limits == "velocity" else "acceleration"
        return tuple(c.name for c in self.constraints if c.problem == problem)

    def measure(self, name: str) -> TaskSet:
        """The set of measure ``name``.

        Raises:
            UnknownMeasureError: no measure of that name is registered.
            MeasureError: it is registered but was not computed for this analysis.
        """
        get_measure(name)
        try:
            return self.measures[name]
        except KeyError:
            raise MeasureError(
                f"measure {name!r} was not computed in this analysis ({', '.join(self.measures)}); "
                f"ask analyze(..., measures=(..., {name!r}))"
            ) from None

    @functools.cached_property
    def warnings(self) -> tuple[str, ...]:
        """Plausibility warnings of this configuration (:func:`mobmanip.analysis.plausibility.analysis_warnings`)."""
        from .plausibility import analysis_warnings, rest_warnings

        explicit = self.held_object if self.object_given else None
        found = analysis_warnings(self.robot, self.end_effector_positions, self.bias, explicit)
        return tuple(self.robot.warnings) + found + tuple(rest_warnings(self))

    @property
    def kinematic(self) -> Ellipsoid:
        """The unified kinematic ellipsoid (m/s, rad/s): ``measures["kinematic"]``."""
        return cast(Ellipsoid, self.measure(KINEMATIC.name))

    @property
    def dynamic(self) -> Ellipsoid:
        """The unified dynamic ellipsoid (m/s^2, rad/s^2): ``measures["dynamic"]``."""
        return cast(Ellipsoid, self.measure(DYNAMIC.name))

    def _set_summaries(self) -> list[tuple[str, str, str]]:
        """(measure name, units, one-line summary) of each set, for the two representations below."""
        rows = []
        for name, task_set in self.measures.items():
            units = get_measure(name).quantity.units_for(self.task)
            if task_set.empty:
                rows.append((name, units, "empty"))
                continue
            semi_axes = getattr(task_set, "semi_axes", None)
            shape = "" if semi_axes is None else "semi-axes " + ", ".join(f"{v:.4g}" for v in semi_axes) + "; "
            flag = " (degenerate)" if task_set.degenerate else ""
            rows.append(
                (
                    name,
                    units,
                    f"{shape}volume {_number(task_set, 'volume')}, isotropy {_number(task_set, 'isotropy')}{flag}",
                )
            )
        return rows

    def __repr__(self) -> str:
        sets = "; ".join(f"{name}: {text} [{units}]" for name, units, text in self._set_summaries())
        coupling = ", decoupled" if self.decoupled else ""
        return f"Analysis(robot={self.robot.name!r}, task={self.task!r}{coupling}, {sets})"

    def _repr_html_(self) -> str:
        """A table of the measures, for Jupyter."""
        from html import escape

        rows = "".join(
            f"<tr><td>{escape(name)}</td><td>{escape(units)}</td><td>{escape(text)}</td></tr>"
            for name, units, text in self._set_summaries()
        )
        coupling = " (decoupled)" if self.decoupled else ""
        return (
            f"<p><b>Analysis</b> of {escape(self.robot.name)}, task {escape(self.task)}{coupling}</p>"
            f"<table><tr><th>measure</th><th>units</th><th>set</th></tr>{rows}</table>"
        )

    def to_dict(self) -> dict:
        """A JSON-ready dictionary (matrices as lists of rows); each measure under its JSON key
        (``kinematic_ellipsoid``, ``dynamic_ellipsoid``, ...)."""
        robot = self.robot
        obj = self.held_object
        return {
            "robot": robot.name,
            "platform": robot.platform.kind,
            "task": self.task,
            "task_axes": list(get_task(self.task).labels),
            "decoupled": self.decoupled,
            "q": robot.configuration_dict(self.q),
            "reduced_velocity_names": list(robot.reduced_velocity_names),
            "arms": [
                {"name": arm.name, "end_effector": arm.end_effector, "position": pos.tolist()}
                for arm, pos in zip(robot.arms, self.end_effector_positions)
            ],
            "object": {"center": obj.center.tolist(), "mass": obj.mass, "grasp_offsets": obj.offsets.tolist()},
            "unified_jacobian": self.unified_jacobian.tolist(),
            "reduced_inertia": self.reduced_inertia.tolist(),
            "reduced_inertia_decoupled": self.reduced_inertia_decoupled.tolist(),
            "input_matrix": self.input_matrix.tolist(),
            "bias": self.bias.tolist(),
            "velocity_limits": robot.velocity_limits.tolist(),
            "effort_limits": robot.effort_limits.tolist(),
            "grasp_matrix": self.grasp_matrix.tolist(),
            "warnings": list(self.warnings),
            **self._block_document(),
            **({"constraints": [c.describe() for c in self.constraints]} if self.constraints else {}),
            **{get_measure(name).json_key: self._set_document(name, s) for name, s in self.measures.items()},
        }

    def _set_document(self, name: str, task_set: TaskSet) -> dict:
        from .reaches import axis_reaches

        out = task_set.to_dict()
        if self.constraints:
            out["ignored_constraints"] = list(self.ignored_constraints(name))
        reaches = axis_reaches(task_set, self.task)
        if reaches is not None:
            ideal = self._ideal_reaches(name) if self.constraints and get_measure(name).honours_constraints else None
            for entry, free in zip(reaches, ideal or ()):  # the same reading without the constraints
                entry["ideal_straight_line"] = free["straight_line"]
            out["reaches"] = reaches
        return out

    def _ideal_reaches(self, name: str) -> list[dict] | None:
        """The per-axis readings of measure ``name`` without the constraints (the ideal set)."""
        from .reaches import axis_reaches

        free = analyze(
            self.robot, self.q, self.task, held_object=self.held_object, decoupled=self.decoupled, measures=(name,)
        )
        return axis_reaches(free.measures[name], self.task)

    def block_indices(self) -> dict | None:
        """Unit-consistent indices per block (linear, angular) of each set, for a task that mixes
        m and rad (``None`` otherwise): see :func:`mobmanip.analysis.plausibility.block_indices`.
        Computed once (a grounded set's shadows take seconds); each call returns its own copy."""
        return copy.deepcopy(self._block_indices)

    @functools.cached_property
    def _block_indices(self) -> dict | None:
        from .plausibility import block_indices

        return block_indices(get_task(self.task), self.measures)

    def _block_document(self) -> dict:
        blocks = self.block_indices()
        if blocks is None:
            return {}
        return {"block_indices": {get_measure(name).json_key: value for name, value in blocks.items()}}


def _number(task_set: TaskSet, index: str) -> str:
    """An index of a set for printing, ``n/a`` where it cannot be computed (a 6-D polytope's volume)."""
    try:
        value = getattr(task_set, index)
    except MobmanipError:
        return "n/a"
    return f"{value:.4g}" if value is not None and np.isfinite(value) else "n/a"


def default_object(robot: Robot, q: np.ndarray, mass: float | None = None) -> HeldObject:
    """The object held by all end effectors, centred at their centroid.

    With one arm the end effector itself is the task point (W = I).
    """
    return HeldObject.between(_end_effectors(robot, q), object_mass_of(robot, mass))


def _end_effectors(robot: Robot, q: np.ndarray) -> np.ndarray:
    import pinocchio as pin

    pin.framesForwardKinematics(robot.model, robot.data, robot.check_configuration(q))
    return placed_end_effectors(robot)


def analyze(
    robot: Robot,
    q: np.ndarray,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
    method: str = "auto",
    measures: Iterable[str] | None = None,
    constraints: Iterable[Constraint] = (),
) -> Analysis:
    """Analyse the robot at configuration q (robot and object at rest).

    Args:
        robot: the loaded robot (``robot.with_platform("fixed")`` locks the platform;
            ``robot.with_wheel_limits(...)`` changes the wheel limits).
        q: configuration, (nq,); see :meth:`Robot.configuration`.
        task: task space name; defaults to the spec's ``default_task``.
        object_mass: mass of the default object (kg); defaults to the spec's.
        held_object: an explicit object (overrides ``object_mass``); its offsets must have one
            row per arm.
        decoupled: use the decoupled P (no platform-arm interaction) for the dynamic ellipsoid
            (and every measure of accelerations).
        measures: the measures to compute, by name (:func:`mobmanip.measures.measure_names`);
            default: the default ones, ``("kinematic", "dynamic")``. They come out in the
            registry's order.
        constraints: constraints beyond the joint boxes (:mod:`mobmanip.terms.constraints`, e.g.
            the floor's contacts): every polytope honours them; an ellipsoid cannot, and the
            analysis says so (:meth:`Analysis.ignored_constraints`, ``"ignored_constraints"`` in
            its JSON).
        method: ``"auto"``: the compiled kernel of :mod:`mobmanip.engine` (closed forms with an
            a-priori error certificate; an ellipsoid it cannot certify to 1e-9 of its size, e.g.
            at a singularity, is computed by the exact path) where this process has already
            compiled it for this robot's number of arms and task dimension (a batch or a sweep
            did, or :func:`mobmanip.batch.warm_kernel`), else the exact path: one configuration
            never waits tens of seconds for a compile to save a fraction of a millisecond.
            ``"exact"``: always the SVD-based :mod:`mobmanip.sets.ellipsoid` (the reference; about
            4x slower than the kernel, a fraction of a millisecond).

    Raises:
        UnknownMeasureError: a measure name that is not registered (the message lists them).
    """
    wanted = resolve_measures(measures)
    constraints = tuple(constraints)
    if method not in ("auto", "exact"):
        raise ArgumentError(f"method must be 'auto' or 'exact', got {method!r}")
    q = robot.check_configuration(q)
    task = get_task(task or robot.spec.default_task)
    mass = held_mass(robot, object_mass, held_object)
    fast = method == "auto" and robot.constant_null_space  # the fast paths freeze S
    ellipsoids = any(m.name in (KINEMATIC.name, DYNAMIC.name) for m in wanted)
    if fast and ellipsoids and kernel_ready(len(robot.arms), task.dim):
        return _analyze_compiled(robot, q, task, float(mass), held_object, decoupled, wanted, constraints)
    return _analyze_exact(robot, q, task, float(mass), held_object, decoupled, wanted, constraints)


def _analyze_exact(robot, q, task, mass, held_object, decoupled, wanted, constraints) -> Analysis:
    """The reference path: the terms from :func:`mobmanip.terms.builder.terms_at`, every measure
    from them by its definition."""
    terms = terms_at(
        robot, q, task.name, object_mass=mass, held_object=held_object, decoupled=decoupled,
        constraints=constraints, check=False,
    )  # fmt: skip
    return _assemble(terms, wanted, {}, given_object=held_object is not None)


def _analyze_compiled(robot, q, task, mass, held_object, decoupled, wanted, constraints) -> Analysis:
    """The batch engine on one configuration (:func:`mobmanip.engine.evaluate_one`) for the two
    ellipsoids; an ellipsoid its certificate does not accept is computed by the reference path
    instead, and any other measure from the terms by its definition."""
    row = evaluate_one(robot, q, task, mass, held_object, decoupled, method="kernel", validate=False)
    obj = held_object if held_object is not None else HeldObject.between(row.positions, mass)
    given: dict[str, TaskSet | None] = {KINEMATIC.name: row.kinematic, DYNAMIC.name: row.dynamic}
    computed = {m.name: given.get(m.name) for m in wanted}
    if constraints or any(s is None for s in computed.values()):
        terms = assemble_terms(
            robot, q, task.name, decoupled, row.J_u, row.P, row.xi, row.positions, obj, row.W, constraints
        )
        return _assemble(terms, wanted, given, given_object=held_object is not None)
    # the engine gave every set asked for: the terms are assembled only if asked for (Analysis.terms)
    return Analysis(
        robot=robot,
        q=q,
        task=task.name,
        decoupled=decoupled,
        unified_jacobian=row.J_u,
        reduced_inertia=row.P,
        reduced_inertia_decoupled=decouple(robot, row.P),
        input_matrix=robot.Q,
        bias=row.xi,
        end_effector_positions=row.positions,
        held_object=obj,
        grasp_matrix=row.W,
        measures=types.MappingProxyType(cast(dict[str, TaskSet], computed)),
        object_given=held_object is not None,
    )


def _assemble(terms: MeasureTerms, wanted: Iterable[Measure], given: Mapping[str, TaskSet | None], given_object: bool):
    """The Analysis holding the measures ``wanted``: each taken from ``given`` (the compiled
    ellipsoids) where there, else computed from the terms by its definition."""
    sets = {}
    for measure in wanted:
        found = given.get(measure.name)
        sets[measure.name] = measure.compute(terms) if found is None else found
    robot = terms.robot
    assert terms.q is not None and terms.positions is not None and terms.held_object is not None  # terms_at's
    P = terms.P if terms.P_coupled is None else terms.P_coupled
    return Analysis(
        robot=robot,
        q=terms.q,
        task=terms.task,
        decoupled=terms.decoupled,
        unified_jacobian=terms.J_u,
        reduced_inertia=P,
        reduced_inertia_decoupled=decouple(robot, P),
        input_matrix=robot.Q,
        bias=terms.xi,
        end_effector_positions=terms.positions,
        held_object=terms.held_object,
        grasp_matrix=terms.W,
        measures=types.MappingProxyType(sets),
        object_given=given_object,
        given_terms=terms,
    )
