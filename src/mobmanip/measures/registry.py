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
(the same under the paper's minimum-norm policy), each under the JSON key of its name. All five
are sweepable; a polytope's sweep indices add ``width_1`` .. ``width_m``, its extent along each
task axis. A measure registered at run
time exists in the processes that register it: a sweep on a process pool that does not fork
needs it registered at import of a module the workers import.
"""

from __future__ import annotations

import types
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..batch import BatchSetup, EllipsoidBatch, ellipsoids_from_terms
from ..errors import MeasureError, UnknownMeasureError
from ..sets.ellipsoid import dynamic_ellipsoid, kinematic_ellipsoid
from ..sets.taskset import TaskSet, TaskSetBatch

if TYPE_CHECKING:  # analysis imports this module
    from ..analysis.single import Analysis


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


VELOCITY = Quantity("velocity", "kinematic", "m/s", "m/s, rad/s", limits="velocity", inertial=False)
ACCELERATION = Quantity("acceleration", "dynamic", "m/s^2", "m/s^2, rad/s^2", limits="effort", inertial=True)


@dataclass(frozen=True)
class MeasureTerms:
    """What a measure is computed from at one configuration (robot and object at rest).

    The names are the paper's; :mod:`mobmanip.sets.ellipsoid` takes the same arrays.

    Attributes:
        task: task-space name.
        J_u: unified Jacobian J S, (m k, nx).
        W: grasp matrix, (m, m k).
        P: reduced inertia, coupled or decoupled as ``decoupled`` says, (nx, nx).
        Q: reduced input matrix, (nx, nx).
        xi: reduced bias at rest (-S^T g), (nx,).
        M_o: object inertia in the task space, (m, m).
        g_o: object gravity wrench (Eq. 22), (m,).
        velocity_limits: qdot_max per reduced velocity (rad/s or m/s), (nx,).
        effort_limits: tau_max per reduced velocity (N m or N), (nx,).
        decoupled: whether P is the decoupled one.
    """

    task: str
    J_u: np.ndarray
    W: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    xi: np.ndarray
    M_o: np.ndarray
    g_o: np.ndarray
    velocity_limits: np.ndarray
    effort_limits: np.ndarray
    decoupled: bool

    @classmethod
    def of(cls, analysis: Analysis) -> MeasureTerms:
        """The terms of an :class:`mobmanip.analysis.Analysis` (its P as its ``decoupled`` says)."""
        obj, robot = analysis.held_object, analysis.robot
        return cls(
            task=analysis.task,
            J_u=analysis.unified_jacobian,
            W=analysis.grasp_matrix,
            P=analysis.reduced_inertia_decoupled if analysis.decoupled else analysis.reduced_inertia,
            Q=analysis.input_matrix,
            xi=analysis.bias,
            M_o=obj.inertia_matrix(analysis.task),
            g_o=obj.gravity_vector(analysis.task),
            velocity_limits=robot.velocity_limits,
            effort_limits=robot.effort_limits,
            decoupled=analysis.decoupled,
        )


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
    """

    setup: BatchSetup
    terms: Any
    limits: Mapping[str, np.ndarray]
    decoupled: bool


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
        results = form(BatchRequest(request.setup, request.terms, limits, request.decoupled))
        for name in limits:
            if name not in results:
                raise MeasureError(f"the batch form of measure {name!r} did not compute it")
            out[name] = results[name]
    return out


# ----------------------------------------------------------------------------------------------
# the paper's two ellipsoids


def _kinematic(terms: MeasureTerms) -> TaskSet:
    return kinematic_ellipsoid(terms.J_u, terms.W, terms.velocity_limits)


def _dynamic(terms: MeasureTerms) -> TaskSet:
    return dynamic_ellipsoid(terms.J_u, terms.W, terms.P, terms.Q, terms.xi, terms.M_o, terms.g_o, terms.effort_limits)


def _ellipsoids_batch(request: BatchRequest) -> Mapping[str, TaskSetBatch]:
    """Both ellipsoids of a chunk in one pass of :func:`mobmanip.batch.ellipsoids_from_terms`
    (one compiled-kernel call for the two)."""
    n, m = len(request.terms), request.setup.m
    velocity = request.limits.get(KINEMATIC.name)
    effort = request.limits.get(DYNAMIC.name)
    kin = EllipsoidBatch.allocate(n, m) if velocity is not None else None
    dyn = EllipsoidBatch.allocate(n, m) if effort is not None else None
    ellipsoids_from_terms(
        request.setup,
        request.terms,
        velocity_limits=velocity,
        effort_limits=effort,
        decoupled=request.decoupled,
        kinematic=kin,
        dynamic=dyn,
    )
    out: dict[str, TaskSetBatch] = {}
    if kin is not None:
        out[KINEMATIC.name] = kin
    if dyn is not None:
        out[DYNAMIC.name] = dyn
    return out


_ELLIPSOID_AXES = (("semi_axes", "semi_axis"),)

KINEMATIC = register_measure(
    Measure(
        name="kinematic",
        json_key="kinematic_ellipsoid",
        quantity=VELOCITY,
        label="kinematic ellipsoid",
        set_kind="ellipsoid",
        color=0x1FBF3F,  # green
        locked_color=0xF2D21B,  # yellow
        compute=_kinematic,
        default=True,
        batch=_ellipsoids_batch,
        axis_indices=_ELLIPSOID_AXES,
        description="unified kinematic ellipsoid of object velocities (Eq. 23-26, consistent form)",
    )
)
DYNAMIC = register_measure(
    Measure(
        name="dynamic",
        json_key="dynamic_ellipsoid",
        quantity=ACCELERATION,
        label="dynamic ellipsoid",
        set_kind="ellipsoid",
        color=0xD81BD8,  # magenta
        locked_color=0xE0301E,  # red
        compute=_dynamic,
        default=True,
        batch=_ellipsoids_batch,
        axis_indices=_ELLIPSOID_AXES,
        description="unified dynamic ellipsoid of object accelerations at rest (Eq. 27-38)",
    )
)


# ----------------------------------------------------------------------------------------------
# the exact capacity polytopes (mobmanip.sets.capacity): box limits instead of the unit sphere

#: Polytope measures by name -> the kind :func:`mobmanip.sets.capacity.polytopes` builds.
POLYTOPE_KINDS = {
    "kinematic_polytope": "kinematic",
    "dynamic_polytope": "dynamic",
    "dynamic_polytope_min_norm": "dynamic_min_norm",
}


def _polytope_compute(kind: str) -> Compute:
    def compute(terms: MeasureTerms) -> TaskSet:
        from ..sets.capacity import polytopes

        if kind == "kinematic":
            return polytopes(kind, J_u=terms.J_u, W=terms.W, velocity_limits=terms.velocity_limits)
        return polytopes(
            kind,
            J_u=terms.J_u,
            W=terms.W,
            P=terms.P,
            Q=terms.Q,
            xi=terms.xi,
            M_o=terms.M_o,
            g_o=terms.g_o,
            effort_limits=terms.effort_limits,
        )

    return compute


def _polytopes_batch(request: BatchRequest) -> dict[str, TaskSetBatch]:
    """The polytopes of a chunk, one configuration at a time from the chunk's terms (the
    engine's J_u, P, xi and grasp; the same arrays :class:`MeasureTerms` holds)."""
    from ..engine.terms import ChunkTerms, numpy_terms
    from ..sets.capacity import polytope_batch

    setup, t = request.setup, request.terms
    # The compiled kernel fills the terms only of the rows it does not certify: compute them all
    # here, from the chunk's Pinocchio outputs, on a fresh copy.
    t = ChunkTerms(t.n, t.Ja, t.Ma, t.positions.copy())
    numpy_terms(setup, t)
    W = setup.W if t.W is None else t.W
    M_o = np.diag(setup.Mo) if t.Mo is None else np.einsum("ni,ij->nij", t.Mo, np.eye(setup.m))  # type: ignore[arg-type]
    P = t.P
    if request.decoupled:
        e = setup.n_eta
        P = P.copy()
        P[:, :e, e:] = 0.0
        P[:, e:, :e] = 0.0
    out: dict[str, TaskSetBatch] = {}
    for name, limits in request.limits.items():
        kind = POLYTOPE_KINDS[name]
        if kind == "kinematic":
            out[name] = polytope_batch(kind, J_u=t.J_u, W=W, velocity_limits=limits)
        else:
            out[name] = polytope_batch(
                kind, J_u=t.J_u, W=W, P=P, Q=setup.robot.Q, xi=t.xi, M_o=M_o, g_o=setup.g_o, effort_limits=limits
            )
    return out


_POLYTOPE_AXES = (("widths", "width"),)

KINEMATIC_POLYTOPE = register_measure(
    Measure(
        name="kinematic_polytope",
        json_key="kinematic_polytope",
        quantity=VELOCITY,
        label="kinematic polytope",
        set_kind="polytope",
        color=0x0B7A75,  # teal
        locked_color=0xB8860B,  # dark gold
        compute=_polytope_compute("kinematic"),
        batch=_polytopes_batch,
        axis_indices=_POLYTOPE_AXES,
        description="exact set of object velocities, every wheel and joint within its own speed limit",
    )
)
DYNAMIC_POLYTOPE = register_measure(
    Measure(
        name="dynamic_polytope",
        json_key="dynamic_polytope",
        quantity=ACCELERATION,
        label="dynamic polytope",
        set_kind="polytope",
        color=0x6A3FB5,  # violet
        locked_color=0xA0522D,  # sienna
        compute=_polytope_compute("dynamic"),
        batch=_polytopes_batch,
        axis_indices=_POLYTOPE_AXES,
        description="exact set of object accelerations at rest, every torque within its own limit",
    )
)
DYNAMIC_POLYTOPE_MIN_NORM = register_measure(
    Measure(
        name="dynamic_polytope_min_norm",
        json_key="dynamic_polytope_min_norm",
        quantity=ACCELERATION,
        label="dynamic polytope, minimum-norm policy",
        set_kind="polytope",
        color=0xE0559F,  # pink
        locked_color=0xFF8C1A,  # orange
        compute=_polytope_compute("dynamic_min_norm"),
        batch=_polytopes_batch,
        axis_indices=_POLYTOPE_AXES,
        description="object accelerations at rest of the paper's minimum-norm policy under box torque limits",
    )
)


def measure_help() -> str:
    """One line per registered measure, for help texts."""
    lines = []
    for m in _REGISTRY.values():
        flags = ", ".join(f for f in ("default" if m.default else "", "sweepable" if m.sweepable else "") if f)
        lines.append(f"  {m.name:<26} {m.description or m.label} ({m.quantity.units}{'; ' + flags if flags else ''})")
    return "\n".join(lines)


__all__ = [
    "ACCELERATION",
    "DYNAMIC",
    "DYNAMIC_POLYTOPE",
    "DYNAMIC_POLYTOPE_MIN_NORM",
    "KINEMATIC",
    "KINEMATIC_POLYTOPE",
    "MEASURES",
    "POLYTOPE_KINDS",
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
