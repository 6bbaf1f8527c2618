"""The registry of measures: which task-space sets mobmanip computes, and how.

A *measure* is one kind of task-space set computed at a configuration, e.g. the paper's
unified kinematic ellipsoid. Its :class:`Measure` definition says everything the rest of the
toolkit needs to know about it: its name, its JSON key, the quantity it bounds (velocity or
acceleration, with units), a label for printing, its colours in the viewer, whether
:func:`mobmanip.analyze` computes it by default, how to compute it from one configuration's
terms (the reference path, :class:`MeasureTerms`) and, where one exists, how to compute it for
a chunk of configurations (sweeps, :class:`BatchRequest`). The sets themselves follow
:class:`mobmanip.sets.taskset.TaskSet`.

Analyses (:attr:`mobmanip.analysis.Analysis.measures`), their JSON, the command line's summary,
sweeps and the viewer loop over the registered measures; nothing else compares measure names.
Adding a measure is one :class:`Measure` definition and one :func:`register_measure` call::

    import mobmanip
    from mobmanip.measures import VELOCITY, Measure, register_measure

    def doubled(terms):  # MeasureTerms -> TaskSet
        k = mobmanip.get_measure("kinematic").compute(terms)
        return mobmanip.Ellipsoid.from_generator(2.0 * k.center, 2.0 * k.generator)

    register_measure(Measure("doubled", "doubled_ellipsoid", VELOCITY, "doubled ellipsoid", "ellipsoid",
                             color=0x3366FF, locked_color=0x99BBFF, compute=doubled))
    mobmanip.analyze(robot, q, measures=("kinematic", "doubled")).to_dict()["doubled_ellipsoid"]

Registered measures (in order): ``kinematic`` (the unified kinematic ellipsoid, Eq. 23-26,
JSON ``kinematic_ellipsoid``) and ``dynamic`` (the unified dynamic ellipsoid, Eq. 27-38, JSON
``dynamic_ellipsoid``), both computed by default; then the exact capacity polytopes of
:mod:`mobmanip.sets.capacity`, computed when asked for: ``kinematic_polytope`` (object velocities,
every wheel and joint within its own speed limit), ``dynamic_polytope`` (object accelerations
at rest, every torque within its own limit, any internal force) and ``dynamic_polytope_min_norm``
(the same under the paper's minimum-norm policy), each under the JSON key of its name; then the
force measures of :mod:`mobmanip.measures.force` (quantity ``force``, in N and N m): ``force_ellipsoid``
and ``force_polytope``, the wrenches the object exerts on the environment at rest. All seven
are sweepable; a polytope's sweep indices add ``width_1`` .. ``width_m``, its extent along each
task axis. A measure registered at run
time exists in the processes that register it: a sweep on a process pool that does not fork
needs it registered at import of a module the workers import.
"""

from __future__ import annotations

import dataclasses
import types
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..batch import BatchSetup
from ..errors import MeasureError, UnknownMeasureError
from ..sets.taskset import TaskSet, TaskSetBatch
from ..terms.builder import MeasureTerms
from ..terms.constraints.base import Constraint

if TYPE_CHECKING:
    from ..robot.tasks import TaskSpace


@dataclass(frozen=True)
class Quantity:
    """What a measure's sets bound: object velocities or object accelerations.

    Attributes:
        name: ``"velocity"`` or ``"acceleration"``.
        label: the adjective the toolkit prints for it: ``"kinematic"`` or ``"dynamic"`` (e.g.
            the viewer's scale ``kinematic: 1 m/s = 0.227 m``).
        unit: unit of the linear task coordinates, drawn in the viewer (``"m/s"``, ``"m/s^2"``).
        units: units of all task coordinates, printed (``"m/s, rad/s"``).
        limits: the limits that bound it, ``"velocity"`` (qdot_max) or ``"effort"`` (tau_max):
            a sweep's wheel velocity or wheel effort scale acts on it.
        inertial: it depends on the inertia, so on the choice of coupled or decoupled P.
    """

    name: str
    label: str
    unit: str
    units: str
    limits: str
    inertial: bool

    def __post_init__(self):
        if self.limits not in ("velocity", "effort"):
            raise MeasureError(f"quantity {self.name!r}: limits must be 'velocity' or 'effort', got {self.limits!r}")

    def units_for(self, task: str | TaskSpace) -> str:
        """The units of a task's coordinates, printed: the linear unit alone for a task of linear
        rows only (``"m/s"`` for ``translational``), the angular one alone for angular rows only,
        both (:attr:`units`) for a task that mixes them (``spatial``, ``planar_rigid``).

        Args:
            task: a task space or its name.
        """
        from ..robot.tasks import get_task

        space = get_task(task)
        linear, _, angular = self.units.partition(", ")
        n_angular = len(space.angular_rows)
        if n_angular == 0:
            return linear
        if n_angular == space.dim:
            return angular or linear
        return self.units


VELOCITY = Quantity("velocity", "kinematic", "m/s", "m/s, rad/s", limits="velocity", inertial=False)
ACCELERATION = Quantity("acceleration", "dynamic", "m/s^2", "m/s^2, rad/s^2", limits="effort", inertial=True)


@dataclass(frozen=True)
class BatchRequest:
    """One chunk of a sweep, and the measures to compute on it at one setting of the limits.

    Attributes:
        setup: what stays constant over the batch (robot, task, grasp), a
            :class:`mobmanip.batch.BatchSetup`.
        terms: the chunk's per-configuration terms, as :func:`mobmanip.batch.iter_terms` yields
            them (``len(terms)`` configurations).
        limits: the measures to compute, by name, each with its limits (the velocity or effort
            limits its quantity names), (nx,).
        decoupled: use the decoupled P for the measures whose quantity is inertial.
        configurations: the chunk's configurations, (len(terms), nq) (constraints beyond the
            joint boxes are evaluated at each).
        constraints: constraints beyond the joint boxes (:mod:`mobmanip.terms.constraints`);
            a measure that honours constraints computes its sets under them, the others ignore
            them (and the sweep says so).
    """

    setup: BatchSetup
    terms: Any
    limits: Mapping[str, np.ndarray]
    decoupled: bool
    configurations: np.ndarray | None = None
    constraints: tuple[Constraint, ...] = ()


#: Computes a measure from one configuration's terms (the reference path).
Compute = Callable[[MeasureTerms], TaskSet]
#: Computes measures for a chunk: the results by name, for every name in ``request.limits``.
BatchForm = Callable[[BatchRequest], Mapping[str, TaskSetBatch]]


@dataclass(frozen=True)
class Measure:
    """The definition of one measure (see the module's docstring).

    Attributes:
        name: how users ask for it (``analyze(..., measures=(name, ...))``), the key of
            :attr:`mobmanip.analysis.Analysis.measures` and the prefix of its sweep indices
            (``kinematic.volume``); letters, digits and underscores.
        json_key: its key in :meth:`mobmanip.analysis.Analysis.to_dict`.
        quantity: what its sets bound (:data:`VELOCITY` or :data:`ACCELERATION`).
        label: how it is printed, e.g. ``"kinematic ellipsoid"``.
        set_kind: the :attr:`mobmanip.sets.taskset.TaskSet.kind` of its sets (the viewer draws by it).
        color: its colour in the viewer, 0xRRGGBB.
        locked_color: the colour of its locked-platform counterpart in the viewer.
        compute: its sets from one configuration's terms (the reference path).
        default: computed when no measures are asked for.
        batch: its sets for a chunk of configurations, or ``None`` (then it cannot be swept).
            Measures that share one batch function are computed by one call.
        axis_indices: per-task-axis arrays its batch sets carry, as (attribute, index stem)
            pairs: ``("semi_axes", "semi_axis")`` gives the sweep indices ``semi_axis_1`` ..
            ``semi_axis_m`` from ``batch.semi_axes`` (N, m).
        scene_path: where the viewer draws it, under ``mobmanip/``; default
            ``"<set_kind>s/<name>"``. Its locked-platform counterpart is ``locked/<name>``.
        description: one line for help texts.
        honours_constraints: whether its sets honour every constraint of the terms beyond the
            joint boxes (:mod:`mobmanip.terms.constraints`); a measure that does not is reported
            as ignoring them (``Analysis.ignored_constraints``, ``"ignored_constraints"`` in JSON).
    """

    name: str
    json_key: str
    quantity: Quantity
    label: str
    set_kind: str
    color: int
    locked_color: int
    compute: Compute
    default: bool = False
    batch: BatchForm | None = None
    axis_indices: tuple[tuple[str, str], ...] = ()
    scene_path: str = ""
    description: str = ""
    honours_constraints: bool = False

    def __post_init__(self):
        if not (isinstance(self.name, str) and self.name.isidentifier() and self.name.isascii()):
            raise MeasureError(f"a measure's name must be letters, digits and underscores, got {self.name!r}")
        if not isinstance(self.quantity, Quantity):
            raise MeasureError(f"measure {self.name!r}: quantity must be a Quantity, got {self.quantity!r}")
        if not callable(self.compute) or (self.batch is not None and not callable(self.batch)):
            raise MeasureError(f"measure {self.name!r}: compute (and batch, when given) must be callable")
        for color in (self.color, self.locked_color):
            if isinstance(color, bool) or not isinstance(color, int) or not 0 <= color <= 0xFFFFFF:
                raise MeasureError(f"measure {self.name!r}: colours must be integers 0xRRGGBB, got {color!r}")
        if not self.scene_path:
            object.__setattr__(self, "scene_path", f"{self.set_kind}s/{self.name}")

    @property
    def sweepable(self) -> bool:
        """Whether it has a batch form (sweeps need one)."""
        return self.batch is not None

    @property
    def locked_scene_path(self) -> str:
        """Where the viewer draws its locked-platform counterpart, under ``mobmanip/``."""
        return f"locked/{self.name}"


_REGISTRY: dict[str, Measure] = {}
_DEFAULTS: list[tuple[Measure, ...]] = []  # the resolved default measures, while the registry is unchanged
#: The registered measures by name, in registration order (read-only; see :func:`register_measure`).
MEASURES: Mapping[str, Measure] = types.MappingProxyType(_REGISTRY)


def register_measure(measure: Measure, *, replace: bool = False) -> Measure:
    """Add a measure to the registry (at the end of its order) and return it.

    Args:
        measure: the definition.
        replace: allow replacing a registered measure of the same name (it keeps its place).

    Raises:
        MeasureError: not a :class:`Measure`, its name is taken (without ``replace``), or its
            JSON key is another measure's.
    """
    if not isinstance(measure, Measure):
        raise MeasureError(f"register_measure needs a Measure, got {type(measure).__name__}")
    if measure.name in _REGISTRY and not replace:
        raise MeasureError(f"a measure named {measure.name!r} is already registered (use replace=True)")
    for other in _REGISTRY.values():
        if other.name != measure.name and other.json_key == measure.json_key:
            raise MeasureError(f"JSON key {measure.json_key!r} of {measure.name!r} is taken by {other.name!r}")
    _REGISTRY[measure.name] = measure
    _DEFAULTS.clear()
    return measure


def unregister_measure(name: str) -> Measure:
    """Remove a measure from the registry and return its definition.

    Raises:
        UnknownMeasureError: no measure of that name.
    """
    get_measure(name)
    _DEFAULTS.clear()
    return _REGISTRY.pop(name)


def get_measure(name: str) -> Measure:
    """The registered measure ``name``.

    Raises:
        UnknownMeasureError: no measure of that name (the message lists the registered ones).
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise UnknownMeasureError(name, _REGISTRY) from None


def measure_names() -> tuple[str, ...]:
    """Names of the registered measures, in order."""
    return tuple(_REGISTRY)


def default_measures() -> tuple[str, ...]:
    """Names of the measures computed when none are asked for, in order."""
    return tuple(name for name, m in _REGISTRY.items() if m.default)


def resolve_measures(names: Iterable[str] | str | None = None, *, sweep: bool = False) -> tuple[Measure, ...]:
    """The definitions of the measures ``names`` (``None``: the default ones), in registry order,
    each once.

    Args:
        names: measure names (a single name is one measure), or ``None``.
        sweep: they are for a sweep: each needs a batch form.

    Raises:
        UnknownMeasureError: an unregistered name (the message lists the registered ones).
        MeasureError: no measure asked for, or (``sweep``) one without a batch form.
    """
    if names is None:
        if not _DEFAULTS:  # analyze asks for these on every call: resolve them once
            _DEFAULTS.append(_resolve(default_measures()))
        out = _DEFAULTS[0]
    else:
        out = _resolve((names,) if isinstance(names, str) else names)
    if sweep:
        missing = [m.name for m in out if not m.sweepable]
        if missing:
            able = [name for name, m in _REGISTRY.items() if m.sweepable]
            raise MeasureError(
                f"measure {', '.join(map(repr, missing))} has no batch form yet and cannot be swept; "
                f"sweepable: {', '.join(able)}"
            )
    return out


def _resolve(names: Iterable[str]) -> tuple[Measure, ...]:
    wanted = {get_measure(name).name for name in names}
    if not wanted:
        raise MeasureError(f"no measure asked for; registered: {', '.join(_REGISTRY)}")
    return tuple(m for name, m in _REGISTRY.items() if name in wanted)


def evaluate_batch(request: BatchRequest) -> dict[str, TaskSetBatch]:
    """Compute the measures of ``request.limits`` on one chunk; measures sharing a batch function
    are computed by one call of it.

    Raises:
        UnknownMeasureError: an unregistered name.
        MeasureError: a measure without a batch form, or a batch form that did not return it.
    """
    groups: dict[int, tuple[BatchForm, dict[str, np.ndarray]]] = {}
    for name, limits in request.limits.items():
        measure = get_measure(name)
        if measure.batch is None:
            raise MeasureError(f"measure {name!r} has no batch form and cannot be swept")
        groups.setdefault(id(measure.batch), (measure.batch, {}))[1][name] = limits
    out: dict[str, TaskSetBatch] = {}
    for form, limits in groups.values():
        results = form(dataclasses.replace(request, limits=limits))
        for name in limits:
            if name not in results:
                raise MeasureError(f"the batch form of measure {name!r} did not compute it")
            out[name] = results[name]
    return out


def measure_help() -> str:
    """One line per registered measure, for help texts."""
    lines = []
    for m in _REGISTRY.values():
        flags = ", ".join(f for f in ("default" if m.default else "", "sweepable" if m.sweepable else "") if f)
        lines.append(f"  {m.name:<26} {m.description or m.label} ({m.quantity.units}{'; ' + flags if flags else ''})")
    return "\n".join(lines)


__all__ = [
    "ACCELERATION",
    "MEASURES",
    "VELOCITY",
    "BatchForm",
    "BatchRequest",
    "Compute",
    "Measure",
    "MeasureTerms",
    "Quantity",
    "default_measures",
    "evaluate_batch",
    "get_measure",
    "measure_help",
    "measure_names",
    "register_measure",
    "resolve_measures",
    "unregister_measure",
]
