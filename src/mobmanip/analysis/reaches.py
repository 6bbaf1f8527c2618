"""How far a set reaches along each task axis, read two ways, and what stops it there.

"How far along x" has two readings, and they differ (by 42 % for TIAGo++ holding a box along +y):

- the **straight-line reach**: the largest s such that s e (exactly along e, nothing else moving
  the object) is in the set: what a motion straight along x can reach from rest;
- the **support**: max e . a over the set, the other components free (the object may pitch or
  drift sideways to get there).

For a set computed by linear programs (a polytope with constraints beyond the joint boxes, e.g.
on the floor) each reading also names what binds at its maximum (a joint's effort, a wheel's
traction, a support lifting off), and, on the floor, where the zero-moment point is and its
distance to the support polygon's edge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import MobmanipError
from ..robot.tasks import get_task
from ..sets.lifted import GAIN_STEP, Limit
from ..sets.taskset import TaskSet
from ..terms.constraints.floor import CONTACT_FORCES, ground_reaction


def axis_reaches(task_set: TaskSet, task: str) -> list[dict] | None:
    """Both readings along +-each task axis, with what binds where the set can tell.

    Returns:
        One dict per axis and sense (``axis``, ``straight_line``, ``support`` and, for a set of
        linear programs, ``binding`` at the straight-line maximum and ``limits``, the binding
        limits ranked by what 1 % more of each is worth (:func:`limit_entry` each; on the floor
        :func:`floor_limits`), plus ``floor`` (ZMP, margin, contact forces) on the floor, or for
        a team ``floors``, robot name -> its floor's);
        ``None`` for an ellipsoid, a set without straight-line reach or an empty set.
    """
    # an ellipsoid has a straight-line reach too (sweeps record it) but the paper's ellipsoids
    # are summarised by their axes here: the per-axis readings are the polytopes'
    if task_set.empty or task_set.kind == "ellipsoid" or not hasattr(task_set, "straight_line_reach"):
        return None
    labels = get_task(task).labels
    # a reading within the set's rounding of zero is zero (a collapsed set's "support -2.5e-14")
    noise = 1e-9 * max(
        (abs(float(task_set.support(s * e))) for e in np.eye(task_set.dim) for s in (1.0, -1.0)), default=0.0
    )
    noise = max(noise, 1e-10)
    out = []
    for k, label in enumerate(labels):
        for sign in (1.0, -1.0):
            e = np.zeros(task_set.dim)
            e[k] = sign
            entry: dict = {
                "axis": f"{'+' if sign > 0 else '-'}{label}",
                "straight_line": _snap(float(task_set.straight_line_reach(e)), noise),
                "support": _snap(float(task_set.support(e)), noise),
            }
            witness = getattr(task_set, "straight_line_witness", None)
            if witness is not None and entry["straight_line"] > 0.0:
                try:
                    w = witness(e)
                except MobmanipError:
                    w = None
                if w is not None:
                    entry["binding"] = sorted(set(w.binding))
                    entry["limits"] = [limit_entry(lim.label, lim.kind, lim.gain) for lim in w.limits]
                    model = getattr(task_set, "model", {})
                    floor = model.get("floor")
                    if floor is not None and CONTACT_FORCES in w.variables:
                        entry["floor"] = ground_reaction(floor, w.variables[CONTACT_FORCES])
                        entry["binding"] = tip_over_reading(entry["binding"], floor, entry["floor"])
                        entry["limits"] = floor_limits(w.limits, floor, entry["floor"])
                        near = near_edge(floor, entry["floor"])
                        if near is not None:
                            entry["floor"]["next_tip_over_edge"] = list(near)
                    floors = {  # a team: each robot on its own floor, its forces under its name
                        name: ground_reaction(info["floor"], w.variables[f"{name}.{CONTACT_FORCES}"])
                        for name, info in model.items()
                        if isinstance(info, dict) and "floor" in info and f"{name}.{CONTACT_FORCES}" in w.variables
                    }
                    if floors:
                        entry["floors"] = floors
            out.append(entry)
    return out


#: A zero-moment point this close to the support polygon's edge (m) is on it; a contact whose normal
#: force is below this share of all of them (robot and object weight) carries nothing.
_ON_EDGE, _UNLOADED = 1e-6, 1e-6


def tip_over_reading(binding: list[str], info: dict, reaction: dict) -> list[str]:
    """What stops a maximum on the floor, with tip-over named as such: where the zero-moment point
    is on the support polygon's edge and contacts carry nothing, the robot is about to tip about
    that edge (the unloaded contacts lift), whatever else the program's multipliers say: an
    unloaded wheel's friction rows are all tight at zero force, which read as "slips"."""
    tipping = _tipping(info, reaction)
    if tipping is None:
        return binding
    unloaded, label = tipping
    # an unloaded wheel's friction rows and its lifting row are that same tip-over (not its
    # joint's effort rows: a wheel's contact is named as its joint)
    kept = [lab for lab in binding if _contact_row_of(lab, unloaded) is None]
    return sorted({*kept, label})


def _contact_row_of(label: str, names) -> str | None:
    """The contact among ``names`` whose lifting or friction row ``label`` is, else ``None``."""
    return next((n for n in names if label.startswith((f"{n} slips ", f"{n} lifts off "))), None)


def limit_entry(label: str, kind: str, gain: float) -> dict:
    """One limit that binds, JSON-ready: its ``label``, ``kind`` and ``gain`` (the maximum's growth,
    in the task's units, per 1 % more of that limit; see :class:`mobmanip.sets.lifted.Limit`)."""
    return {"label": label, "kind": kind, "gain": float(gain)}


def floor_limits(limits: Sequence[Limit], info: dict, reaction: dict) -> list[dict]:
    """The limits that bind at a maximum on the floor, ranked by what 1 % more of each is worth
    (:func:`limit_entry` each, the largest gain first), read as the floor does:

    - a loaded wheel's traction: the gain of 1 % more friction at that wheel, at the load it
      carries there (its pyramid's rows relaxed by 1 % of ``mu cos(pi / faces) (1 - reserve)``
      times its normal force);
    - a robot about to tip (the zero-moment point on the support's edge, contacts unloaded: see
      :func:`tip_over_reading`): one tip-over limit, named with its edge, in place of the
      unloaded contacts' lifting and friction rows; its gain is that of ballast of 1 % of a
      contact's equal share of the weight over each contact lifting (their rows relaxed by their
      scales: the lifting row by that share, the friction rows by the friction it gives);
    - every other limit as the set ranks it (1 % more of its own limit).

    Args:
        limits: the set's ranked limits at the maximum (:attr:`mobmanip.sets.lifted.Witness.limits`).
        info: the floor's entry of the set's model; ``reaction``: :func:`ground_reaction` there.
    """
    tipping = _tipping(info, reaction)
    unloaded, tip_label = tipping if tipping is not None else ([], "")
    tilt = (info.get("mu") or 0.0) * math.cos(math.pi / info.get("faces", 8)) * (1.0 - info.get("reserve", 0.0))
    contacts = reaction.get("contacts", {})
    out, tip_gain = [], 0.0
    for lim in limits:
        owner = _contact_row_of(lim.label, contacts)
        if owner is not None and owner in unloaded:
            tip_gain += lim.gain
            continue
        gain = lim.gain
        if lim.kind == "traction" and owner is not None:
            gain = GAIN_STEP * lim.multiplier * tilt * max(contacts[owner]["normal"], 0.0)
        out.append(limit_entry(lim.label, lim.kind, gain))
    if tipping is not None:
        out.append(limit_entry(tip_label, "tip-over", tip_gain))
    return sorted(out, key=lambda entry: (-entry["gain"], entry["label"]))


def _tipping(info: dict, reaction: dict) -> tuple[list[str], str] | None:
    """Where a solution on the floor is about to tip (its zero-moment point on the support
    polygon's edge, contacts carrying nothing): the unloaded contacts and the tip-over's label,
    naming the edge (or the one contact still loaded); ``None`` otherwise."""
    margin = reaction.get("margin")
    contacts = reaction.get("contacts", {})
    total = sum(max(c["normal"], 0.0) for c in contacts.values())
    if margin is None or total <= 0.0 or abs(margin) > _ON_EDGE:
        return None
    unloaded = [name for name, c in contacts.items() if c["normal"] <= _UNLOADED * total]
    if not unloaded:
        return None
    loaded = [name for name in contacts if name not in unloaded]
    edge = _edge_of(info, reaction["zmp"]) if len(loaded) != 1 else None
    if len(loaded) == 1:  # every weight on one contact: the zero-moment point at that corner
        about = f"about {loaded[0]}, the one contact still loaded"
    else:
        about = f"about the edge {edge[0]} to {edge[1]}" if edge else "about the support's edge"
    return unloaded, f"the robot tips over {about} ({', '.join(unloaded)} lifting off)"


#: A zero-moment point closer than this to the support polygon's edge (m), the robot not tipping
#: yet, is named with that edge: tip-over is the next limit, millimetres away.
NEAR_EDGE = 0.01


def near_edge(info: dict, reaction: dict) -> tuple[str, str] | None:
    """The support polygon's edge nearest the zero-moment point where the robot is within
    :data:`NEAR_EDGE` of tipping over about it but not yet tipping (every contact loaded, or the
    point inside); ``None`` otherwise (far inside, or tipping: :func:`tip_over_reading` names it)."""
    margin = reaction.get("margin")
    if margin is None or not 0.0 <= margin < NEAR_EDGE or _tipping(info, reaction) is not None:
        return None
    return _edge_of(info, reaction["zmp"])


def _edge_of(info: dict, zmp) -> tuple[str, str] | None:
    """The two contacts at the ends of the support polygon's edge nearest ``zmp`` (m, floor)."""
    points = {c["name"]: np.asarray(c["point"][:2], dtype=float) for c in info["contacts"]}
    polygon = np.asarray(info["polygon"], dtype=float)
    if len(polygon) < 2:
        return None

    def name_of(vertex: np.ndarray) -> str:
        return min(points, key=lambda n: float(np.linalg.norm(points[n] - vertex)))

    p = np.asarray(zmp, dtype=float)[:2]
    best, edge = np.inf, None
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
        t = float(np.clip(np.dot(p - a, b - a) / max(float(np.dot(b - a, b - a)), 1e-300), 0.0, 1.0))
        distance = float(np.linalg.norm(p - a - t * (b - a)))
        if distance < best:
            best, edge = distance, (name_of(a), name_of(b))
    return edge


def _at_rest(task_set: TaskSet):
    """(a solution with the object still and, where the robot can, nothing moving at all (its
    reduced accelerations zero); whether nothing moves), with the most slack in every limit; None
    when the object cannot be held still."""
    still = ("xdot",) if "xdot" in getattr(task_set, "variables", {}) else ()
    witness_at = getattr(task_set, "witness_at", None)  # a set of linear programs (LiftedPolytope)
    if witness_at is None:
        return None
    for held in (still, ()) if still else ((),):
        try:
            return witness_at(np.zeros(task_set.dim), still=held), bool(held)
        except MobmanipError:
            continue  # it holds the object still only with its joints accelerating
    return None


def floor_at_rest(task_set: TaskSet) -> dict | None:
    """The floor under a grounded set with the object held still: the support polygon, the
    zero-moment point of a solution with the most slack in every limit and nothing moving
    (statics: below the centre of mass along gravity) where the robot can stand perfectly still,
    else with its joints accelerating, and its margin.

    Returns:
        ``{"polygon": (k, 2) world x, y (m), "floor_z": m, "zmp": (x, y) m, "margin": m, "still":
        bool}`` (``still``: nothing moves); ``None`` when the set is not on the floor or rest is
        outside it.
    """
    floor = getattr(task_set, "model", {}).get("floor") if not task_set.empty else None
    if floor is None or not hasattr(task_set, "witness_at"):
        return None
    found = _at_rest(task_set)
    if found is None:
        return None
    w, still = found
    reaction = ground_reaction(floor, w.variables[CONTACT_FORCES])
    return {
        "polygon": floor["polygon"],
        "floor_z": float(np.mean([c["point"][2] for c in floor["contacts"]])),
        "zmp": reaction["zmp"],
        "margin": reaction["margin"],
        "still": still,
    }


def floors_at_rest(task_set: TaskSet) -> dict[str, dict]:
    """A team's set on the floor: each robot's floor with the object held still, as
    :func:`floor_at_rest` gives one robot's (its polygon, floor height, ZMP, margin and whether
    nothing moves), by robot name, from one solution; empty when the set is not a team's on the
    floor or rest is outside it."""
    model = getattr(task_set, "model", {}) if not task_set.empty else {}
    members = {k: v["floor"] for k, v in model.items() if isinstance(v, dict) and "floor" in v}
    if not members or not hasattr(task_set, "witness_at"):
        return {}
    found = _at_rest(task_set)
    if found is None:
        return {}
    w, still = found
    out = {}
    for name, floor in members.items():
        reaction = ground_reaction(floor, w.variables[f"{name}.{CONTACT_FORCES}"])
        out[name] = {
            "polygon": floor["polygon"],
            "floor_z": float(np.mean([c["point"][2] for c in floor["contacts"]])),
            "zmp": reaction["zmp"],
            "margin": reaction["margin"],
            "still": still,
        }
    return out


def _snap(value: float, noise: float) -> float:
    return 0.0 if abs(value) <= noise else value
