"""Force capacity as measures: the wrenches the held object (or one hand) exerts ON the environment
at rest, gravity included (issue 24).

- ``force_ellipsoid``: the paper's Euclidean counterpart, minimum-norm internal force
  (:func:`mobmanip.sets.force.force_ellipsoid`); it cannot honour constraints beyond the joint
  boxes and says so.
- ``force_polytope``: the exact set, every effort in its box, any internal force, and every
  constraint of the acceleration problem (the floor's contacts, tip-over and traction when
  given): the closed form :func:`mobmanip.sets.force.force_polytope` with only the joint boxes,
  else the linear programs of :func:`mobmanip.terms.force.force_problem`.

Both are in N (and N m for moment rows) and independent of the robot's inertia (no motion).
Sweeps compute them one configuration at a time.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..batch import EllipsoidBatch
from ..sets.capacity import PolytopeBatch
from ..sets.force import force_ellipsoid, force_polytope
from ..sets.taskset import TaskSet, TaskSetBatch
from ..terms.builder import MeasureTerms
from ..terms.force import force_problem
from .polytopes import sets_one_at_a_time
from .registry import BatchRequest, Compute, Measure, Quantity, get_measure, register_measure

#: Wrenches exerted on the environment: limited by the efforts, independent of the inertia.
FORCE = Quantity("force", "force", "N", "N, N m", limits="effort", inertial=False)


#: The closed forms (only the joint boxes), by the kind of set.
_CLOSED = {"ellipsoid": force_ellipsoid, "polytope": force_polytope}


def _ellipsoid(terms: MeasureTerms) -> TaskSet:
    return force_ellipsoid(terms.J_u, terms.W, terms.Q, terms.xi, terms.g_o, terms.effort_limits)


def _polytope(terms: MeasureTerms) -> TaskSet:
    if terms.constrained("acceleration"):  # constraints beyond the joint boxes: the linear programs
        return force_problem(terms)
    return force_polytope(terms.J_u, terms.W, terms.Q, terms.xi, terms.g_o, terms.effort_limits)


def _from_chunk(request: BatchRequest) -> dict[str, list[TaskSet]]:
    """The closed forms at each configuration of a chunk, from the chunk's terms (J_u, xi, W)."""
    from ..engine.terms import ChunkTerms, numpy_terms

    setup, t = request.setup, request.terms
    t = ChunkTerms(t.n, t.Ja, t.Ma, t.positions.copy())  # every row's terms, on a fresh copy
    numpy_terms(setup, t)
    W = np.asarray(t.W if setup.W is None else setup.W)  # per configuration when the grasp moves
    if W.ndim == 2:
        W = np.broadcast_to(W, (t.n, *W.shape))
    out: dict[str, list[TaskSet]] = {}
    for name, limits in request.limits.items():
        closed = _CLOSED[get_measure(name).set_kind]
        out[name] = [closed(t.J_u[i], W[i], setup.robot.Q, t.xi[i], setup.g_o, limits) for i in range(t.n)]
    return out


def _stacked(ellipsoids: list[TaskSet]) -> EllipsoidBatch:
    batch = EllipsoidBatch.allocate(len(ellipsoids), ellipsoids[0].dim if ellipsoids else 0)
    for field in ("center", "semi_axes", "axes", "matrix", "degenerate", "empty"):
        getattr(batch, field)[:] = np.array([getattr(e, field) for e in ellipsoids])
    return batch


def _force_batch(request: BatchRequest) -> Mapping[str, TaskSetBatch]:
    """The force sets of a chunk, one configuration at a time: the closed forms from the chunk's
    terms, or, under constraints beyond the joint boxes, from terms built again at each
    configuration (:func:`mobmanip.measures.polytopes.sets_one_at_a_time`)."""
    if any(c.problem == "acceleration" for c in request.constraints):
        found = sets_one_at_a_time(request)
    else:
        found = _from_chunk(request)
    out: dict[str, TaskSetBatch] = {}
    for name, sets in found.items():
        out[name] = _stacked(sets) if get_measure(name).set_kind == "ellipsoid" else PolytopeBatch(sets)
    return out


#: The per-axis arrays of each kind of force set's batch (its sweep indices).
_AXES = {"ellipsoid": (("semi_axes", "semi_axis"),), "polytope": (("widths", "width"),)}


def _register_force(kind: str, colors: tuple[int, int], compute: Compute, description: str) -> Measure:
    """Register the force set of one kind (``"ellipsoid"`` or ``"polytope"``, named
    ``force_<kind>``), swept by :func:`_force_batch`; only the polytope honours the constraints;
    ``colors``: its own and its locked counterpart's in the viewer."""
    return register_measure(
        Measure(
            name=f"force_{kind}",
            json_key=f"force_{kind}",
            quantity=FORCE,
            label=f"force {kind}",
            set_kind=kind,
            color=colors[0],
            locked_color=colors[1],
            compute=compute,
            batch=_force_batch,
            axis_indices=_AXES[kind],
            honours_constraints=kind == "polytope",
            description=description,
        )
    )


FORCE_ELLIPSOID = _register_force(
    "ellipsoid",
    (0x1565C0, 0x64B5F6),  # blue, light blue
    _ellipsoid,
    "wrenches the object exerts on the environment at rest, Euclidean norm of the efforts",
)
FORCE_POLYTOPE = _register_force(
    "polytope",
    (0x283593, 0x9E9D24),  # indigo, olive
    _polytope,
    "exact set of wrenches the object exerts on the environment at rest, every effort within its limit",
)
