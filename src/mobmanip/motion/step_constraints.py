"""Constraints of the sets at rest, over one step of motion: the constraint seam's rows compiled
over ``carry``'s step variable.

``carry`` solves one quadratic program a step over the reduced velocities x of the step. A
constraint written for the problems at rest (:mod:`mobmanip.terms.constraints`) gives rows over
their variables at the step's configuration; over one step they are rows over x:

- velocity problem: its ``x`` is the step's x, and the object's velocity ``v`` follows from the
  rigid grasp, ``v = (W^T)^+ J_u x``;
- acceleration problem: ``xdot = (x - x_prev) / dt`` and ``tau = A x + offset``, the efforts of
  the paper's policy with the velocity terms at the previous step's rates (carry's own effort
  rows, :func:`mobmanip.motion.carry_step.effort_rows_of`).

What cannot be written over x alone is refused, naming the constraint and what it asks: rows over
the hands' wrenches ``h`` or the object's acceleration ``a``, variables of its own (the floor's
contact forces: the floor has its own model in motion, :mod:`mobmanip.motion.carry_floor`),
equalities, and terms added to the problem's equations.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..terms.builder import MeasureTerms
from ..terms.constraints.base import Constraint, ConstraintRows

#: The variables of each problem a step's rows may use.
STEP_VARIABLES = {"velocity": ("x", "v"), "acceleration": ("xdot", "tau")}


@dataclass(frozen=True)
class StepRows:
    """Rows ``G x <= h`` over one step's reduced velocities, with one label per row."""

    G: np.ndarray
    h: np.ndarray
    labels: tuple[str, ...]

    @classmethod
    def none(cls, nx: int) -> StepRows:
        return cls(np.zeros((0, nx)), np.zeros(0), ())


def check_constraints(constraints: Sequence[Constraint]) -> tuple[Constraint, ...]:
    """The constraints as a tuple, each a :class:`Constraint` and not the floor.

    Raises:
        ArgumentError: something else, or the floor (given as ``carry``'s ``floor``).
    """
    from ..terms.constraints.floor import Floor

    out = tuple(constraints)
    for constraint in out:
        if not isinstance(constraint, Constraint):
            raise ArgumentError(f"constraints must be Constraint objects, got {type(constraint).__name__}")
        if isinstance(constraint, Floor):
            raise ArgumentError("the floor in motion is carry's floor= (a CarryFloor), not the floor of the sets")
    return out


def joins_a_step(rows: ConstraintRows) -> None:
    """Whether a constraint's rows can be written over one step's x (module docstring).

    Raises:
        ArgumentError: naming the constraint and what keeps it out.
    """
    allowed = STEP_VARIABLES[rows.problem]
    reasons = []
    if rows.variables:
        reasons.append(f"it declares variables of its own ({', '.join(rows.variables)})")
    other = sorted(set(rows.G) - set(allowed))
    if other:
        reasons.append(f"its rows use {', '.join(other)}")
    if rows.E or len(rows.e) or rows.object_E or rows.couplings or rows.shifts:
        reasons.append("it adds equalities or terms to the problem's equations")
    if reasons:
        raise ArgumentError(
            f"constraint {rows.name!r} cannot join a step of motion: {'; '.join(reasons)} (a step's rows are over "
            f"{' and '.join(allowed)} of the {rows.problem} problem)"
        )


def _joining_rows(
    constraints: Sequence[Constraint], terms: MeasureTerms
) -> Iterator[tuple[ConstraintRows, tuple[str, ...]]]:
    """Each constraint's rows at ``terms``, checked to join a step (:func:`joins_a_step`), with
    one label per row (the constraint's own, else its name and the row's index)."""
    for constraint in constraints:
        rows = constraint.rows(terms)
        joins_a_step(rows)
        yield rows, tuple(rows.labels or (f"{rows.name} row {i}" for i in range(len(rows.h))))


def step_rows(
    constraints: Sequence[Constraint],
    terms: MeasureTerms,
    x_prev: np.ndarray,
    dt: float,
    effort_map: tuple[np.ndarray, np.ndarray],
    *,
    columns: slice | None = None,
    width: int | None = None,
) -> StepRows:
    """The constraints' rows over the step's x (see the module's docstring).

    Args:
        constraints: the constraints (:func:`check_constraints`).
        terms: the terms at rest at the step's configuration.
        x_prev: the previous step's reduced velocities, (nx,).
        dt: the step (s).
        effort_map: (A, offset) with the step's efforts tau = A x + offset, A (nx, width).
        columns, width: for one robot of a team, where its own x sits in the team's step
            variable and how wide that is (its efforts, through the shared object, depend on
            every robot's); default the robot's x alone.

    Raises:
        ArgumentError: a constraint that cannot join a step (:func:`joins_a_step`).
    """
    nx = len(x_prev)
    width = nx if width is None else width
    columns = slice(0, nx) if columns is None else columns
    if not constraints:
        return StepRows.none(width)
    A, offset = effort_map
    G_rows: list[np.ndarray] = []
    h_rows: list[np.ndarray] = []
    labels: list[str] = []
    for rows, names in _joining_rows(constraints, terms):
        G = np.zeros((len(rows.h), width))
        h = np.asarray(rows.h, dtype=float).copy()
        for name, block in rows.G.items():
            block = np.asarray(block, dtype=float)
            if name == "x":
                G[:, columns] += block
            elif name == "v":
                G[:, columns] += block @ np.linalg.pinv(terms.W.T) @ terms.J_u
            elif name == "xdot":
                G[:, columns] += block / dt
                h += block @ x_prev / dt
            else:  # tau
                G += block @ A
                h -= block @ offset
        G_rows.append(G)
        h_rows.append(h)
        labels.extend(names)
    return StepRows(np.vstack(G_rows), np.concatenate(h_rows), tuple(labels))


def path_timing_rows(
    constraints: Sequence[Constraint],
    terms: MeasureTerms,
    x_s: np.ndarray,
    x_ss: np.ndarray,
    efforts: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[str, ...]]:
    """The constraints' rows at one grid point of a path's timing, over (a, b) = (s'', s'^2)
    (:mod:`mobmanip.motion.retime`): ``ca a + cb b <= d``.

    With x = x_s s' and xdot = x_s a + x_ss b, and the efforts tau = T_a a + T_b b + T_0:

    - rows over ``xdot`` and ``tau`` (the acceleration problem) are linear in (a, b);
    - a row ``g . x <= h`` over ``x`` (and ``v``, through the rigid grasp) of the velocity
      problem reads ``(g . x_s) s' <= h`` with s' >= 0: for g . x_s > 0 and h >= 0 it is
      ``(g . x_s)^2 b <= h^2``; for g . x_s < 0 and h < 0 it is ``-b <= -(h / g . x_s)^2``; for
      g . x_s <= 0 and h >= 0 it always holds (no row); for g . x_s >= 0 and h < 0 no timing
      keeps it (the row ``0 <= h``).

    Args:
        constraints: as :func:`step_rows`.
        terms: the terms at rest at the grid point's configuration.
        x_s, x_ss: the path's reduced velocities and accelerations in its own parameter, (nx,).
        efforts: (T_a, T_b, T_0), each (nx,).

    Raises:
        ArgumentError: a constraint that cannot join a step (:func:`joins_a_step`).
    """
    T_a, T_b, T_0 = efforts
    ca: list[np.ndarray] = []
    cb: list[np.ndarray] = []
    d: list[np.ndarray] = []
    labels: list[str] = []
    for rows, names in _joining_rows(constraints, terms):
        h = np.asarray(rows.h, dtype=float)
        if rows.problem == "acceleration":
            G_xdot = np.asarray(rows.G.get("xdot", np.zeros((len(h), len(x_s)))), dtype=float)
            G_tau = np.asarray(rows.G.get("tau", np.zeros((len(h), len(x_s)))), dtype=float)
            ca.append(G_xdot @ x_s + G_tau @ T_a)
            cb.append(G_xdot @ x_ss + G_tau @ T_b)
            d.append(h - G_tau @ T_0)
            labels.extend(names)
            continue
        g = np.zeros(len(h))
        for name, block in rows.G.items():
            block = np.asarray(block, dtype=float)
            g += block @ x_s if name == "x" else block @ (np.linalg.pinv(terms.W.T) @ terms.J_u @ x_s)
        for k in range(len(h)):
            if g[k] > 0.0 and h[k] >= 0.0:
                row = (0.0, g[k] ** 2, h[k] ** 2)  # s' <= h / g
            elif g[k] < 0.0 and h[k] < 0.0:
                row = (0.0, -1.0, -((h[k] / g[k]) ** 2))  # s' >= h / g
            elif h[k] < 0.0:
                row = (0.0, 0.0, h[k])  # no timing keeps it
            else:
                continue  # every timing keeps it
            ca.append(np.array([row[0]]))
            cb.append(np.array([row[1]]))
            d.append(np.array([row[2]]))
            labels.append(names[k])
    if not labels:
        return np.zeros(0), np.zeros(0), np.zeros(0), ()
    return np.concatenate(ca), np.concatenate(cb), np.concatenate(d), tuple(labels)
