"""What :func:`mobmanip.robot.detect.detect_spec` considered, why it chose a platform kind, what is
still missing, and which frames could be end effectors.

``mobmanip init-spec`` prints these on standard error (and writes them as comments into the
spec): every wheel-like continuous joint (wheel-shaped, or named like a wheel) with its shape,
axis and what became of it; each wheeled platform kind and whether the wheels fit it; the wheel
radii and limits neither the URDF nor the command line gives, in one message with the flags
that supply them; and, with ``--list-frames``, the links that could be end effectors.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from ..descriptions import RobotDescription
from ..errors import WheelError
from ..platforms import KINDS

#: Words in a link name that mark a tool or end-effector frame (strongly, then weakly).
TOOL_WORDS = ("tool", "tcp", "ee", "end_effector", "endeffector", "grasp", "pinch")
HAND_WORDS = ("gripper", "hand", "flange", "tip", "finger", "wrist", "attachment")


def _tool_score(link: str) -> int:
    """2 for a tool-like name, 1 for a hand-like one, else 0."""
    parts = [p for p in link.lower().replace("-", "_").split("_") if p]
    text = link.lower()
    if any(p in TOOL_WORDS for p in parts) or any(w in text for w in TOOL_WORDS if len(w) > 3):
        return 2
    return 1 if any(w in text for w in HAND_WORDS) else 0


def _is_site(description: RobotDescription, link: str) -> bool:
    """Whether ``link`` is an MJCF site (its reader hangs a site ``S`` on a fixed joint ``S_site``)."""
    joint = description.parent_joint(link)
    return description.format == "mjcf" and joint is not None and joint.type == "fixed" and joint.name == f"{link}_site"


def _actuation(description: RobotDescription, steer: str, wheel: str) -> str:
    """What the file's own actuators do to a steered drive unit's two joints ("" when the format
    does not say: a URDF)."""
    if description.actuated is None:
        return ""
    driven = [name for name in (steer, wheel) if name in description.actuated]
    if not driven:
        return "the file actuates neither its steering nor its rolling joint"
    if len(driven) == 2:
        return "the file actuates both its joints"
    return f"the file actuates only {driven[0]}"


def explain_wheels(
    description: RobotDescription,
    candidates: Sequence,
    drive: Iterable[str],
    on_arms: Mapping[str, str],
    contacts: Mapping[str, int] | None = None,
) -> list[str]:
    """One line per wheel-like joint: what it is and what became of it.

    Args:
        description: the robot file as read.
        candidates: the wheel candidates (off the arms' paths).
        drive: the joints the platform drives.
        on_arms: wheel-like joints on an arm's path -> that arm's end effector.
        contacts: wheel joints whose floor contact is a row of the spec's ``[support] wheels``
            -> that row (a steered drive unit of a base the file moves on planar joints).
    """
    drive = set(drive)
    contacts = contacts or {}
    lines = []
    for c in candidates:
        if c.name in drive:
            fate = "platform wheel"
        elif c.steered_unit:
            acted = _actuation(description, c.steering_joint, c.name)
            if description.planar_base:
                base = ", ".join(j.name for j in description.planar_base)
                why = f"{acted}: it" if acted else "the file"
                fate = f"a steered drive unit, not the platform's ({why} moves the base on its planar joints {base})"
            else:
                fate = "a steered drive unit this platform does not drive" + (f" ({acted})" if acted else "")
            fate += ": locked"
            if c.name in contacts:
                k = contacts[c.name]
                fate += f"; its floor contact is row {k} of [support] wheels (contact wheel_{k})"
        elif c.steering_joint:
            fate = "not driven by the platform model: a caster, locked"
        else:
            fate = "not a drive wheel of this platform: locked (extra wheel)"
        lines.append(f"wheel-like joint {c.explain()} -> {fate}")
    for joint, ee in on_arms.items():
        lines.append(f"wheel-like joint {joint}: on the path to end effector {ee!r} -> an arm joint")
    return lines


def platform_reasons(description: RobotDescription, candidates: Sequence, path: str) -> list[str]:
    """How each wheeled platform kind judges the candidates: fits, does not fit, or ambiguous."""
    lines = []
    for kind in KINDS.values():
        if not kind.takes_wheels:
            continue
        try:
            found = kind.detect(description, candidates, path)
        except WheelError as exc:
            lines.append(f"{kind.name}: fits ambiguously ({exc})")
            continue
        if found is None:
            lines.append(f"{kind.name}: the wheel-like joints do not fit it")
        else:
            lines.append(f"{kind.name}: fits ({'; '.join(found.notes)})")
    return lines


def choice_reason(kind_name: str, how: str, candidates: Sequence) -> str:
    """Why the platform kind was chosen: ``how`` is "platform" (--platform), "wheels"
    (--wheels) or "detected"."""
    if how == "platform":
        return f"platform {kind_name}: asked for (--platform)"
    if how == "wheels":
        return f"platform {kind_name}: the wheels were named (--wheels)"
    if kind_name == "fixed":
        if not candidates:
            return "platform fixed: no wheel-like continuous joint (wheel-shaped or named like a wheel) off the arms"
        listed = ", ".join(c.name for c in candidates)
        return f"platform fixed: no wheeled kind fits the wheel-like joints {listed} (choose one with --platform)"
    return f"platform {kind_name}: the only wheeled kind the wheel-like joints fit"


@dataclass(frozen=True)
class Missing:
    """A value the spec needs that neither the URDF nor the command line gives.

    Attributes:
        what: e.g. ``"velocity limit"``.
        names: the joints or platform coordinates concerned.
        flag: the command-line option that gives it.
    """

    what: str
    names: tuple[str, ...]
    flag: str

    def describe(self) -> str:
        return f"{self.what} of {', '.join(self.names)} ({self.flag})"


def missing_message(missing: Sequence[Missing], path: str) -> str:
    """One message naming everything missing and the flags that supply it."""
    return (
        f"{path}: the spec is incomplete; it needs "
        + "; ".join(m.describe() for m in missing)
        + ". Rerun init-spec with those options, or fill in the lines marked REQUIRED"
    )


def candidate_frames(description: RobotDescription, exclude: Iterable[str] = ()) -> list[tuple[str, int, bool, bool]]:
    """Links that could be end effectors: moved by at least one actuated joint (``exclude``,
    the wheels, left out), and a leaf of the tree or named like a tool.

    Returns:
        ``(link, actuated joints from the root, leaf, tool-like name)`` rows, the most likely
        first: leaves named like a tool (tool, tcp, ee, grasp, pinch), then like a hand
        (gripper, finger, tip...), then other leaves, then inner links so named; deeper chains
        first. An MJCF site named like either ranks one step higher: a point the file's author
        placed (TidyBot's ``pinch_site`` comes before its gripper's deeper links).
    """
    exclude = set(exclude)
    rows = []
    for link in description.links:
        if link == description.root_link:
            continue
        chain = [j for j in description.chain(link) if j.moves]
        if any(j.name in exclude for j in chain):
            continue  # a wheel's own link, or under one
        count = len(chain)
        if count == 0:
            continue
        leaf = description.is_leaf(link)
        score = _tool_score(link)
        if score and _is_site(description, link):
            score += 1
        if leaf or score:
            rows.append((link, count, leaf, score))
    rows.sort(key=lambda r: (-(r[3] + 2 * r[2]), -r[1], r[0]))
    return [(link, count, leaf, score > 0) for link, count, leaf, score in rows]
