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
from .registry import ACCELERATION, VELOCITY, BatchRequest, Measure, register_measure


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
