"""The exact capacity polytopes as measures: box limits instead of the paper's unit sphere.

With only the joint boxes, the closed forms of :mod:`mobmanip.sets.capacity` (zonotope sections)
compute them; with constraints beyond the boxes (the floor's contacts, a user's), the linear
programs of :mod:`mobmanip.terms.problems` do, so every polytope honours every constraint.
"""

from __future__ import annotations

import numpy as np

from ..sets.taskset import TaskSet, TaskSetBatch
from ..terms.builder import MeasureTerms
from .registry import ACCELERATION, VELOCITY, BatchRequest, Compute, Measure, Quantity, get_measure, register_measure

#: Polytope measures by name -> the kind :func:`mobmanip.sets.capacity.polytopes` builds.
POLYTOPE_KINDS = {
    "kinematic_polytope": "kinematic",
    "dynamic_polytope": "dynamic",
    "dynamic_polytope_min_norm": "dynamic_min_norm",
}


#: The problem of each polytope kind (:mod:`mobmanip.terms.problems`).
_PROBLEM = {"kinematic": "velocity", "dynamic": "acceleration", "dynamic_min_norm": "acceleration"}


def _polytope_compute(kind: str) -> Compute:
    def compute(terms: MeasureTerms) -> TaskSet:
        from ..sets.capacity import POLYTOPE_TERMS, polytopes

        problem = _PROBLEM[kind]
        if terms.constrained(problem):  # constraints beyond the joint boxes: the linear programs
            from ..terms.problems import capacity_polytope

            return capacity_polytope(terms, problem, policy=kind == "dynamic_min_norm")
        return polytopes(kind, **{name: getattr(terms, name) for name in POLYTOPE_TERMS[kind]})

    return compute


def _constrained_batch(request: BatchRequest) -> dict[str, TaskSetBatch]:
    """Polytopes under constraints beyond the joint boxes, one configuration at a time: the terms
    are built again at each (a constraint may need the whole model, e.g. the floor's contacts)."""
    from ..sets.capacity import PolytopeBatch

    return {name: PolytopeBatch(found) for name, found in sets_one_at_a_time(request).items()}


def sets_one_at_a_time(request: BatchRequest) -> dict[str, list[TaskSet]]:
    """The sets of ``request``'s measures at each of its configurations, from terms built again at
    each (with the request's constraints), each measure under its own quantity's scaled limits."""
    import dataclasses

    from ..terms.builder import terms_at

    setup = request.setup
    if request.configurations is None:
        from ..errors import MeasureError

        raise MeasureError("constraints beyond the joint boxes need the chunk's configurations")
    sets: dict[str, list[TaskSet]] = {name: [] for name in request.limits}
    for q in request.configurations:
        terms = terms_at(
            setup.robot,
            q,
            setup.task.name,
            object_mass=setup.mass,
            decoupled=request.decoupled,
            constraints=request.constraints,
            check=False,
        )
        for name, limits in request.limits.items():
            if get_measure(name).quantity.limits == "velocity":
                scaled = dataclasses.replace(terms, velocity_limits=limits)
            else:
                scaled = dataclasses.replace(terms, effort_limits=limits)
            sets[name].append(get_measure(name).compute(scaled))
    return sets


def _polytopes_batch(request: BatchRequest) -> dict[str, TaskSetBatch]:
    """The polytopes of a chunk from the chunk's terms (the engine's J_u, P, xi and grasp; the
    same arrays :class:`MeasureTerms` holds): stacked and measured in one compiled pass where
    :mod:`mobmanip.sets.capacity_batch` covers the set, else one configuration at a time."""
    from ..engine.terms import ChunkTerms, numpy_terms
    from ..sets.capacity import polytope_batch

    if any(c.problem == _PROBLEM[POLYTOPE_KINDS[name]] for c in request.constraints for name in request.limits):
        return _constrained_batch(request)
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


def _register_polytope(name: str, quantity: Quantity, label: str, colors: tuple[int, int], description: str) -> Measure:
    """Register one capacity polytope of :data:`POLYTOPE_KINDS` (its name also its JSON key):
    computed by its kind's closed form or linear programs, swept by :func:`_polytopes_batch`,
    every constraint honoured; ``colors``: its own and its locked counterpart's in the viewer."""
    return register_measure(
        Measure(
            name=name,
            json_key=name,
            quantity=quantity,
            label=label,
            set_kind="polytope",
            color=colors[0],
            locked_color=colors[1],
            compute=_polytope_compute(POLYTOPE_KINDS[name]),
            batch=_polytopes_batch,
            axis_indices=_POLYTOPE_AXES,
            honours_constraints=True,
            description=description,
        )
    )


KINEMATIC_POLYTOPE = _register_polytope(
    "kinematic_polytope",
    VELOCITY,
    "kinematic polytope",
    (0x0B7A75, 0xB8860B),  # teal, dark gold
    "exact set of object velocities, every wheel and joint within its own speed limit",
)
DYNAMIC_POLYTOPE = _register_polytope(
    "dynamic_polytope",
    ACCELERATION,
    "dynamic polytope",
    (0x6A3FB5, 0xA0522D),  # violet, sienna
    "exact set of object accelerations at rest, every torque within its own limit",
)
DYNAMIC_POLYTOPE_MIN_NORM = _register_polytope(
    "dynamic_polytope_min_norm",
    ACCELERATION,
    "dynamic polytope, minimum-norm policy",
    (0xE0559F, 0xFF8C1A),  # pink, orange
    "object accelerations at rest of the paper's minimum-norm policy under box torque limits",
)
