"""The paper's two measures: the unified kinematic (Eq. 23-26) and dynamic (Eq. 27-38) ellipsoids.

Both are computed from the terms' arrays by :mod:`mobmanip.sets.ellipsoid` (one configuration)
or by the compiled engine (a sweep's chunk, both in one pass). An ellipsoid bounds the joints in
the Euclidean norm; it cannot honour constraints beyond the joint boxes (contact forces,
traction), and an analysis with such constraints reports that the ellipsoids ignored them.
"""

from __future__ import annotations

from collections.abc import Mapping

from ..batch import EllipsoidBatch, ellipsoids_from_terms
from ..sets.ellipsoid import dynamic_ellipsoid, kinematic_ellipsoid
from ..sets.taskset import TaskSet, TaskSetBatch
from ..terms.builder import MeasureTerms
from .registry import ACCELERATION, VELOCITY, BatchRequest, Compute, Measure, Quantity, register_measure


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


def _register_ellipsoid(
    name: str, quantity: Quantity, colors: tuple[int, int], compute: Compute, description: str
) -> Measure:
    """Register one of the paper's ellipsoids (JSON key ``<name>_ellipsoid``), computed by default,
    both swept by :func:`_ellipsoids_batch`; ``colors``: its own and its locked counterpart's in
    the viewer."""
    return register_measure(
        Measure(
            name=name,
            json_key=f"{name}_ellipsoid",
            quantity=quantity,
            label=f"{name} ellipsoid",
            set_kind="ellipsoid",
            color=colors[0],
            locked_color=colors[1],
            compute=compute,
            default=True,
            batch=_ellipsoids_batch,
            axis_indices=_ELLIPSOID_AXES,
            description=description,
        )
    )


KINEMATIC = _register_ellipsoid(
    "kinematic",
    VELOCITY,
    (0x1FBF3F, 0xF2D21B),  # green, yellow
    _kinematic,
    "unified kinematic ellipsoid of object velocities (Eq. 23-26, consistent form)",
)
DYNAMIC = _register_ellipsoid(
    "dynamic",
    ACCELERATION,
    (0xD81BD8, 0xE0301E),  # magenta, red
    _dynamic,
    "unified dynamic ellipsoid of object accelerations at rest (Eq. 27-38)",
)
