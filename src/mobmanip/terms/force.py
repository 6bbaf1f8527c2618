"""The force problem: the wrenches the held object (or one hand) can exert ON the environment at rest.

Robot and object at rest, gravity included; the environment pushes back with -f. The problem is
the acceleration problem (:mod:`mobmanip.terms.constraints.base`) with the motion held still and
one more variable, the wrench ``f`` (m, N and N m), which is the set's::

    dynamics  P xdot - Q tau + J_u^T h = xi   (+ the constraints' couplings)
    grasp     J_u xdot - W^T a = 0
    object    W h - M_o a - f = g_o
    at rest   xdot = 0, a = 0

and every constraint of the acceleration problem still applies (the joint boxes, the floor's
contacts, tip-over and traction, a user's): :func:`force_problem` stacks them with
:func:`mobmanip.terms.problems.capacity_polytope`. With only the joint boxes it equals the
closed form :func:`mobmanip.sets.force.force_polytope` (the tests compare them), which stays the
fast path there.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError, TaskError
from ..sets.lifted import LiftedPolytope
from .builder import MeasureTerms
from .constraints.base import ConstraintRows
from .problems import capacity_polytope

#: The name of the wrench variable of the force problem.
FORCE = "f"


def force_statement(terms: MeasureTerms) -> ConstraintRows:
    """The rows that turn the acceleration problem into the force problem at ``terms``: the
    wrench f (free) enters the object equation as -f, and xdot = 0, a = 0."""
    nx, m = terms.J_u.shape[1], terms.W.shape[0]
    still = np.eye(nx + m)
    return ConstraintRows(
        name="at_rest_pushing",
        problem="acceleration",
        variables={FORCE: (m, -np.inf, np.inf)},
        E={"xdot": still[:, :nx], "a": still[:, nx:]},
        e=np.zeros(nx + m),
        couplings={"object": {FORCE: -np.eye(m)}},
        info={"problem": "force", "set": "the wrench f the object exerts on the environment, at rest"},
    )


def force_problem(terms: MeasureTerms) -> LiftedPolytope:
    """The set of wrenches f the object exerts on the environment at rest, under every constraint
    of ``terms`` on the acceleration problem (see the module's docstring).

    Its :meth:`~mobmanip.sets.lifted.LiftedPolytope.witness` gives, with f, the efforts ``tau``,
    the hands' wrenches ``h`` and every constraint's own variables (contact forces) that reach
    it, and the rows that bind there.

    Raises:
        TaskError: the set is unbounded (a posture where the structure bears some wrench with
            no effort, and no constraint limits it).
    """
    try:
        return capacity_polytope(terms, "acceleration", task=FORCE, extra=(force_statement(terms),))
    except ModelError as error:
        if "unbounded" not in str(error).lower():
            raise
        # a support along a task axis has no finite optimum
        raise TaskError(
            "the force capacity is unbounded at this posture: the structure bears some wrench with no effort "
            "and no constraint limits it"
        ) from error
