"""The heaviest object a team can hold still, or give an acceleration: the payload program of
:mod:`mobmanip.analysis.payload` on the team's stacked terms.

The team's rows (every robot's reduced dynamics and limits, one object whose wrench all the
hands share, each robot's constraints on its own terms, e.g. its own floor) are those of its
capacity sets (:func:`mobmanip.team.analysis.analyze_team`), and they are linear in the object's
mass the same way: the object's inertia scales with its mass (its shape per kilogram is the
team's object's), its centre and grasps stay. So the largest mass is one linear program, and
what stops it is named per robot (``"robot: joint"``, each robot's floor rows under its name).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

from ..analysis.payload import Payload, checked_acceleration, heaviest, scaled_object, unit_object
from ..measures import MeasureTerms
from ..robot.tasks import get_task
from ..terms.constraints.base import Constraint
from .analysis import _stacked_constraints, member_terms, stack_terms
from .members import Team


def team_payload(
    team: Team,
    *,
    acceleration: Iterable[float] | None = None,
    constraints: Iterable[Constraint] = (),
    static: bool = False,
) -> Payload:
    """The heaviest object ``team`` can hold still, or give ``acceleration``, where it stands.

    Args:
        team: the team; its object gives the shape (centre, grasps, inertia per kilogram), its
            mass is what is found.
        acceleration: the object's acceleration in the team's task (m/s^2, rad/s^2), (m,);
            ``None``: held still.
        constraints: constraints applied to every robot on its own terms (e.g. ``Floor(mu=0.5)``:
            every robot on its own wheels and casters).
        static: every robot static too (every reduced acceleration zero).

    Raises:
        ArgumentError: as :func:`mobmanip.analysis.payload.payload`.
    """
    task = get_task(team.task)
    a = checked_acceleration(acceleration, task.dim, task.name)
    constraints = tuple(constraints)
    shape = unit_object(team.held_object)
    parts = member_terms(team)  # the robots' own terms do not depend on the object

    def terms_of(mass: float) -> MeasureTerms:
        holding = replace(team, held_object=scaled_object(shape, mass))
        terms = stack_terms(holding, parts)
        return terms.with_constraints(_stacked_constraints(holding, parts, constraints)) if constraints else terms

    return heaviest(
        terms_of,
        a,
        name=team.name if team.name.startswith("team") else f"team {team.name}",
        task=task.name,
        reduced_names=tuple(f"{m.name}: {n}" for m in team.members for n in m.robot.reduced_velocity_names),
        constraints=constraints,
        static=static,
    )
