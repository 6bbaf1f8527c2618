"""Axis and colour-bar labels of the figures: what is plotted, in words, with its unit in
parentheses, in mathtext (``kinematic minor semi-axis (m/s)``), never a raw token such as
``kinematic:minor_axis``.

A label carries one unit. Where a quantity mixes metres and radians (the minor semi-axis of a
``spatial`` set, a capacity along a direction with linear and angular parts) the label says
``mixed`` before the two units, as the sweep plots do.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..gradients.evaluator import Objective
    from ..gradients.readings import ReadingObjective
    from ..measures.registry import Quantity
    from ..robot.tasks import TaskSpace

#: How an objective's index reads in a label.
INDEX_WORDS = {
    "minor_axis": "minor semi-axis",
    "capacity": "capacity",
    "log_volume": "ln volume",
    "log_isotropy": "ln isotropy",
    "reach": "reach from rest",
    "support": "support",
}


def mathtext(unit: str) -> str:
    """``m/s^2`` -> ``m/s$^2$``."""
    return unit.replace("^2", "$^2$")


def power(unit: str, n: int) -> str:
    """``(m/s)$^{3}$`` for n = 3; the unit itself for n = 1; empty for n = 0."""
    if n == 0:
        return ""
    base = unit if "/" not in unit else f"({unit})"
    return base if n == 1 else f"{base}$^{{{n}}}$"


def task_unit(quantity: Quantity, task: str | TaskSpace, rows: Sequence[int] | None = None) -> str:
    """The unit (mathtext) of a quantity over a task's coordinates ``rows`` (default all): the
    linear or the angular unit when the rows are of one kind, ``mixed: m/s, rad/s`` otherwise."""
    from ..robot.tasks import get_task

    space = get_task(task)
    rows = range(space.dim) if rows is None else rows
    linear, _, angular = quantity.units.partition(", ")
    kinds = {bool(space.angular[i]) for i in rows}
    if kinds == {False}:
        return mathtext(linear)
    if kinds == {True}:
        return mathtext(angular or linear)
    return f"mixed: {mathtext(linear)}, {mathtext(angular or linear)}"


def objective_words(objective: Objective | ReadingObjective, task: str | TaskSpace) -> str:
    """``kinematic minor semi-axis``, ``dynamic capacity along +z``."""
    from ..robot.tasks import get_task

    words = f"{objective.measure_name} {INDEX_WORDS.get(objective.index, objective.index.replace('_', ' '))}"
    block = getattr(objective, "block", None)
    if block:
        words += f" of the {block} block"
    if objective.direction is not None:
        labels = get_task(task).labels
        nonzero = [(i, v) for i, v in enumerate(objective.direction) if v != 0.0]
        if len(nonzero) == 1:
            i, v = nonzero[0]
            words += f" along {'+' if v > 0 else '-'}{labels[i]}"
        else:
            words += " along (" + ", ".join(f"{v:.3g}" for v in objective.direction) + ")"
    return words


def objective_unit(objective: Objective | ReadingObjective, task: str | TaskSpace) -> str:
    """The unit (mathtext) of an objective's value over a task."""
    from ..measures import get_measure
    from ..robot.tasks import get_task

    space = get_task(task)
    quantity = get_measure(objective.measure_name).quantity
    block = getattr(objective, "block", None)
    if objective.index == "log_isotropy":
        return "1"
    if objective.index == "log_volume":
        linear, _, angular = quantity.units.partition(", ")
        n_angular = len(space.angular_rows)
        volume = " ".join(
            u for u in (power(mathtext(linear), space.dim - n_angular), power(mathtext(angular), n_angular)) if u
        )
        return f"ln of {volume}"
    if block == "linear":
        return task_unit(quantity, space, space.linear_rows)
    if block == "angular":
        return task_unit(quantity, space, space.angular_rows)
    if objective.direction is not None:
        return task_unit(quantity, space, [i for i, v in enumerate(objective.direction) if v != 0.0])
    return task_unit(quantity, space)


def objective_label(objective: Objective | ReadingObjective, task: str | TaskSpace) -> str:
    """``kinematic minor semi-axis (m/s)``: an axis or colour-bar label of an objective."""
    return f"{objective_words(objective, task)} ({objective_unit(objective, task)})"
