"""The capacity problems as linear programs: the terms' equations and every constraint's rows.

:func:`capacity_polytope` stacks, for the velocity or the acceleration problem (see
:mod:`mobmanip.terms.constraints.base`), the problem's own equations (with the terms that
constraints add to them) and every constraint's rows, and returns the task-space shadow as a
:class:`~mobmanip.sets.lifted.LiftedPolytope`. With only the joint boxes it equals the exact
polytopes of :mod:`mobmanip.sets.capacity` (the tests compare them); those closed forms stay the
fast path when nothing else constrains the set.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ArgumentError, TaskError
from ..sets.lifted import LiftedPolytope, LiftedRows
from .builder import MeasureTerms
from .constraints.base import PROBLEMS, ConstraintRows

_RANK_RTOL = 1e-10


def capacity_polytope(
    terms: MeasureTerms,
    problem: str,
    *,
    policy: bool = False,
    task: str | None = None,
    extra: Sequence[ConstraintRows] = (),
) -> LiftedPolytope:
    """The set of object velocities (``"velocity"``) or accelerations (``"acceleration"``) that
    satisfy the problem's equations and every constraint of ``terms``.

    Args:
        terms: the terms at one configuration, with their constraints.
        problem: ``"velocity"`` or ``"acceleration"``.
        policy: the paper's minimum-norm policy (acceleration only): xdot = J_u^+ W^T a and
            h = W^+ (M_o a + g_o) instead of the grasp and object equations.
        task: the variable whose shadow the set is (default the problem's own: ``v`` or ``a``);
            e.g. a variable that ``extra`` declares.
        extra: rows stacked like a constraint's but belonging to the problem's statement, not
            to its limits (they are not listed among the constraints; :mod:`mobmanip.terms.force`
            states the force problem with them).

    Raises:
        TaskError: the policy at a posture where J_u or W loses row rank.
    """
    stacked = capacity_rows(terms, problem, policy=policy, task=task, extra=extra)
    r = stacked.rows
    return LiftedPolytope(
        r.task, r.A_eq, r.b_eq, r.A_ub, r.b_ub, r.lower, r.upper, stacked.columns, stacked.model,
        labels=stacked.labels, kinds=stacked.kinds, scales=stacked.scales,
    )  # fmt: skip


@dataclass(frozen=True)
class CapacityRows:
    """The stacked rows of a capacity problem, before its set is built (see :func:`capacity_rows`).

    Attributes:
        rows: the equalities, inequalities and bounds over z, with the task's columns.
        columns: the named slices of z (``"xdot"``, ``"tau"``, ``"h"``, ``"a"``, and every
            variable a constraint declares), in column order.
        model: what produced the rows (JSON-ready), as the set's ``model``.
        labels: one label per inequality row (what binds when it is tight), (r,).
        kinds: what each inequality row limits (:data:`~mobmanip.terms.constraints.base.ROW_KINDS`), (r,).
        scales: the size of the limit each inequality row stands for, (r,) (see
            :attr:`~mobmanip.terms.constraints.base.ConstraintRows.scales`).
    """

    rows: LiftedRows
    columns: Mapping[str, slice]
    model: Mapping[str, Any]
    labels: tuple[str, ...]
    kinds: tuple[str, ...] = ()
    scales: tuple[float, ...] = ()


def capacity_rows(
    terms: MeasureTerms,
    problem: str,
    *,
    policy: bool = False,
    task: str | None = None,
    extra: Sequence[ConstraintRows] = (),
) -> CapacityRows:
    """The rows :func:`capacity_polytope` projects, stacked (its arguments and errors): for
    programs that add rows or variables of their own to the problem (the payload's object mass)
    without building the set."""
    if problem not in PROBLEMS:
        raise ArgumentError(f"problem must be one of {sorted(PROBLEMS)}, got {problem!r}")
    rows = terms.rows(problem) + tuple(extra)
    nx, (mk, m) = terms.J_u.shape[1], (terms.W.shape[1], terms.W.shape[0])
    sizes = {"x": nx, "v": m} if problem == "velocity" else {"xdot": nx, "tau": nx, "h": mk, "a": m}
    lower: dict[str, np.ndarray] = {}
    upper: dict[str, np.ndarray] = {}
    for r in rows:
        for name, (size, lo, hi) in r.variables.items():
            if name in sizes:
                raise ArgumentError(f"constraint {r.name!r} declares variable {name!r}, which another one declared")
            sizes[name] = int(size)
            lower[name] = np.broadcast_to(np.asarray(lo, dtype=float), (size,))
            upper[name] = np.broadcast_to(np.asarray(hi, dtype=float), (size,))
    columns, start = {}, 0
    for name, size in sizes.items():
        columns[name] = slice(start, start + size)
        start += size
    n = start

    T = terms
    own: dict[str, tuple[dict[str, np.ndarray], np.ndarray]] = {}  # the problem's equations by name
    if problem == "velocity":
        own["grasp"] = ({"x": T.J_u, "v": -T.W.T}, np.zeros(mk))
    else:
        own["dynamics"] = ({"xdot": T.P, "tau": -T.Q, "h": T.J_u.T}, T.xi)
        if policy:
            J_pinv, blocked, W_pinv = _policy_inverses(T.J_u, T.W)
            own["grasp"] = ({"xdot": np.eye(nx), "a": -J_pinv @ T.W.T}, np.zeros(nx))
            own["object"] = ({"h": np.eye(mk), "a": -W_pinv @ T.M_o}, W_pinv @ T.g_o)
            if len(blocked):  # at a singular posture the hands cannot follow these directions
                own["blocked"] = ({"a": blocked @ T.W.T}, np.zeros(len(blocked)))
        else:
            own["grasp"] = ({"xdot": T.J_u, "a": -T.W.T}, np.zeros(mk))
            own["object"] = ({"h": T.W, "a": -T.M_o}, T.g_o)
    for r in rows:
        for equation, shift in r.shifts.items():
            if policy and equation == "grasp":
                raise ArgumentError(f"constraint {r.name!r} shifts the grasp equation, which the policy fixes")
            blocks, rhs = own[equation]
            shift = np.asarray(shift, dtype=float)
            if shift.shape != rhs.shape and not (policy and equation == "object"):
                raise ArgumentError(f"constraint {r.name!r}: its {equation} shift has {shift.shape}, not {rhs.shape}")
            # the policy's object equation is h = W^+ (M_o a + g_o): the object's own load through W^+
            own[equation] = (blocks, rhs + (W_pinv @ shift if policy and equation == "object" else shift))
        for equation, blocks in r.couplings.items():
            if policy and equation in ("grasp", "object"):
                raise ArgumentError(f"constraint {r.name!r} adds to the {equation} equation, which the policy fixes")
            parts = own[equation][0]
            for name, block in blocks.items():
                parts[name] = parts[name] + block if name in parts else np.asarray(block, dtype=float)
    equalities = list(own.values())
    equalities += [(dict(r.E), np.asarray(r.e, dtype=float)) for r in rows if len(r.e)]
    equalities += [(dict(r.object_E), np.asarray(r.object_e, dtype=float)) for r in rows if len(r.object_e)]
    inequalities = [(dict(r.G), np.asarray(r.h, dtype=float)) for r in rows if len(r.h)]
    labels = [label for r in rows if len(r.h) for label in r.row_labels()]
    kinds = tuple(kind for r in rows if len(r.h) for kind in r.row_kinds())
    scales = tuple(float(v) for r in rows if len(r.h) for v in r.row_scales())

    def stack(blocks: list[tuple[dict[str, np.ndarray], np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
        A = np.zeros((sum(len(b) for _, b in blocks), n))
        at = 0
        for parts, rhs in blocks:
            for name, block in parts.items():
                if name not in columns:
                    raise ArgumentError(f"a constraint's rows name the unknown variable {name!r}")
                A[at : at + len(rhs), columns[name]] = block
            at += len(rhs)
        return A, np.concatenate([b for _, b in blocks]) if blocks else np.zeros(0)

    A_eq, b_eq = stack(equalities)
    A_ub, b_ub = stack(inequalities)
    lo, hi = np.full(n, -np.inf), np.full(n, np.inf)
    for name in lower:
        lo[columns[name]], hi[columns[name]] = lower[name], upper[name]
    task = task or ("v" if problem == "velocity" else "a")
    if task not in columns:
        raise ArgumentError(f"the set's variable {task!r} is not one of the problem's: {sorted(columns)}")
    task_columns = np.arange(n)[columns[task]]
    model = {
        "problem": problem,
        "policy": "minimum_norm" if policy else "any",
        "constraints": [c.describe() for c in (T.all_constraints) if c.problem == problem],
        **{key: value for r in rows for key, value in r.info.items()},
    }
    return CapacityRows(
        LiftedRows(task_columns, A_eq, b_eq, A_ub, b_ub, lo, hi), columns, model, tuple(labels), kinds, scales
    )


def _policy_inverses(J_u: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """J_u^+ (rank-revealing), the directions of the hands' space J_u cannot reach (rows), W^+.

    Raises:
        TaskError: W without full row rank (the hands do not hold the object rigidly).
    """
    s_w = np.linalg.svd(W, compute_uv=False)
    if not len(s_w) or W.shape[0] > W.shape[1] or s_w[-1] <= _RANK_RTOL * s_w[0]:
        raise TaskError("the minimum-norm policy needs a grasp matrix W of full row rank")
    U, s, Vt = np.linalg.svd(J_u, full_matrices=True)
    rank = int(np.sum(s > _RANK_RTOL * max(s[0] if s.size else 0.0, 1e-300)))
    J_pinv = (Vt[:rank].T / s[:rank]) @ U[:, :rank].T
    return J_pinv, U[:, rank:].T, np.linalg.pinv(W)
