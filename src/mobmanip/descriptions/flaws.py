"""Vendor flaws in a robot file, and the stated rule that repairs each.

Robot files as vendors publish them carry mistakes that do not stop a model from being built:
a link whose inertia tensor no rigid body can have (a principal moment below zero, or the
largest one above the sum of the other two: Fetch's gripper fingers ``ixx=0.002, iyy=izz=0``,
PR2's sensor mount, TIAGo++'s antennas with a moment of -3.5e-8 kg m^2). A kinematic analysis
never depends on inertias, so such a flaw never blocks one; for the dynamic measures mobmanip
repairs it by one stated rule and says so, once per link (:attr:`Flaw.warning`), or refuses it
when asked to be strict (:attr:`Flaw.refusal`, the message of the check plus the way forward).

**The rule for inertias is MuJoCo's** ``balanceinertia``: a tensor whose principal moments break
the triangle inequality (every non-physical tensor does: a negative moment implies it) has its
three principal moments set to their mean, ``trace / 3``, about the same centre of mass; the mass
and the centre of mass are kept. A tensor whose mean is not positive becomes zero (the link a
point mass). Why this rule rather than Drake's (which keeps the mass and zeroes the rotational
inertia):

- it keeps the trace, so the link's moment about an axis of random direction (``trace / 3`` on
  average) is what the file says; zeroing drops it, and a joint that turns such a link (Fetch's
  wrist roll turns both fingers) would lose all of the fingers' rotational inertia;
- MuJoCo, the physics referee of this project, compiles the same vendor file to the same
  repaired tensor, so mobmanip and the referee simulate one robot;
- its effect is bounded by the link's own tensor: each principal moment moves by
  ``|lambda_i - trace / 3|``, at most ``(2/3) (lambda_max - lambda_min)`` (:attr:`InertiaFlaw.change`).

The effect on the results: the kinematic measures (Jacobians, velocity limits) are unchanged;
gravity (mass and centre of mass) is unchanged; the reduced inertia ``P = S^T M S`` changes by
each repaired link's rotational share ``J_w^T R (I_new - I_old) R^T J_w`` and nothing else, so
the dynamic measures move by no more than the repaired links' share of ``P``.

A tensor within rounding of the physical set (:data:`INERTIA_SLACK`, relative to its largest
entry: values printed to six digits) is read as written and is no flaw.

**Implausible inertia** (:class:`ImplausibleInertia`): a physical tensor can still be far too
small for the body it belongs to (MuJoCo Menagerie's TidyBot: a 60 kg base with
``diaginertia="0.001 0.001 0.001"``, whose dynamic polytope then reaches 1,047 m/s^2 sideways).
The rule: a link of mass m whose geometry (its collision shapes, else its visual ones) fills a
bounding box of edges a, b, c in the link's frame would have, as a solid box, the trace
``m (a^2 + b^2 + c^2) / 6``; the link is implausible when its tensor's trace is below
:data:`PLAUSIBLE_TRACE_FRACTION` of that. The trace is the sum of the moments about three
orthogonal axes, so the rule does not depend on how the tensor is turned; a fraction of 1/10
means a radius of gyration under a third of the box's (sqrt(1/10) = 0.32). Real links sit near
or above a solid box (hollow covers, motors at the ends of an arm link); a link whose mass sits
in a small core inside a large cover can reach a few tenths, not a tenth. Only links carrying
at least :data:`PLAUSIBLE_MIN_SHARE` of the robot's mass are judged: vendor files are full of
frames with a placeholder point mass (0.1 kg and a zero tensor on TIAGo's and TALOS's force
sensors, 0.1 g on Baxter's covers), which break the rule without mattering to any measure,
while the bodies the rule is for carry a platform or an arm. There is no repair:
the file's numbers are kept, with one warning naming the link and the numbers, and refused under
``strict``. A link without geometry mobmanip can measure (none, or only mesh files it cannot
read) is not judged.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:
    import pinocchio as pin

#: How far, relative to a tensor's largest entry, its principal moments may miss positivity and
#: the triangle inequality and still be read as written: rounding of values printed to about six
#: significant digits (a thin plate's moments satisfy the inequality with equality). Beyond it
#: the tensor is a flaw, repaired with a warning or refused under ``strict``.
INERTIA_SLACK = 1e-5

#: The fraction of a solid box's trace (the link's mass filling its geometry's bounding box)
#: below which a link's rotational inertia is implausible (see the module docstring).
PLAUSIBLE_TRACE_FRACTION = 0.1

#: The least share of the robot's total mass a link must carry to be judged by the plausibility
#: rule (see the module docstring).
PLAUSIBLE_MIN_SHARE = 0.02

#: What the inertia repair is called in messages.
INERTIA_RULE = "MuJoCo's balanceinertia rule"

#: How a user refuses repairs, or accepts them, for the messages.
STRICT_HINT = "--strict"

_NAMES = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")


def _entries(inertia: np.ndarray) -> str:
    values = (inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2])
    return " ".join(f"{n}={v:g}" for n, v in zip(_NAMES, values))


@dataclass(frozen=True)
class Flaw:
    """A flaw of a robot file that mobmanip repairs by a stated rule (or refuses when strict).

    Attributes:
        subject: what it is in, e.g. ``"link 'r_gripper_finger_link'"``.
        problem: what is wrong, with the values as written (the check's own message).
        repair: what the rule does about it, with the values it gives.
    """

    subject: str
    problem: str
    repair: str

    #: What the messages say happens to it without ``strict`` (``{repair}`` and ``{strict}`` filled
    #: in): after the problem in the warning, as the refusal offers it, as the detection notes say it.
    WITHOUT_STRICT: ClassVar[tuple[str, str, str]] = (
        "repaired by {repair}; kinematic results unaffected ({strict} refuses instead)",
        "have mobmanip repair it by {repair}",
        "repaired at load by {repair}, with a warning",
    )

    def _without_strict(self, which: int) -> str:
        return self.WITHOUT_STRICT[which].format(repair=self.repair, strict=STRICT_HINT)

    @property
    def warning(self) -> str:
        """One line naming the subject, the values and the repair (stderr and the JSON's ``"warnings"``)."""
        return f"{self.subject}: {self.problem}; {self._without_strict(0)}"

    @property
    def refusal(self) -> str:
        """The message under ``strict``: the problem, then the way forward."""
        return (
            f"{self.subject} {self.problem}; correct it in the file, or drop --strict (strict = false in the spec) "
            f"to {self.lenient} with a warning"
        )

    @property
    def note(self) -> str:
        """What ``init-spec`` says of it among the detection notes."""
        return (
            f"{self.subject}: {self.problem}; {self.at_load} (list the link in accepted_repairs once reviewed, "
            "or set strict = true to refuse it)"
        )

    @property
    def lenient(self) -> str:
        """What happens to it without ``strict``, as the refusal offers it."""
        return self._without_strict(1)

    @property
    def at_load(self) -> str:
        """What happens to it at load without ``strict``, as the detection notes say it."""
        return self._without_strict(2)


@dataclass(frozen=True)
class InertiaFlaw(Flaw):
    """A link's inertia tensor no rigid body can have, and its repair (see the module docstring).

    Attributes:
        link: the link's name.
        inertia: the tensor as written (kg m^2), about the centre of mass in the ``<inertial>``
            frame, rows of (3, 3).
        moments: its principal moments, ascending (kg m^2).
        repaired: the tensor the rule gives, in the same frame, rows of (3, 3).
    """

    link: str = ""
    inertia: tuple[tuple[float, ...], ...] = ()
    moments: tuple[float, float, float] = (0.0, 0.0, 0.0)
    repaired: tuple[tuple[float, ...], ...] = ()

    @property
    def change(self) -> float:
        """The largest change of a principal moment (kg m^2): the repair's effect on this link."""
        return float(np.max(np.abs(np.diag(np.array(self.repaired)) - np.array(self.moments))))

    @property
    def delta(self) -> np.ndarray:
        """``repaired - inertia`` (3, 3), in the ``<inertial>`` frame (kg m^2)."""
        return np.array(self.repaired) - np.array(self.inertia)


@dataclass(frozen=True)
class ImplausibleInertia(Flaw):
    """A link's rotational inertia far below what its mass has in its geometry's bounding box
    (see the module docstring); kept as written (no repair), warned, refused when strict.

    Attributes:
        link: the link's name.
        mass: its mass (kg).
        trace: its tensor's trace (kg m^2).
        extents: its geometry's bounding box edges in the link frame (m), (3,).
        box_trace: the trace of a solid box of that mass and those edges (kg m^2).
    """

    link: str = ""
    mass: float = 0.0
    trace: float = 0.0
    extents: tuple[float, float, float] = (0.0, 0.0, 0.0)
    box_trace: float = 0.0

    WITHOUT_STRICT = (
        "kept as written, so the dynamic measures may be far too large (kinematic results unaffected; "
        "{strict} refuses instead)",
        "analyse it as written",
        "kept as written, with a warning at load",
    )


def implausible_inertia(link: str, mass: float, inertia: np.ndarray, extents: np.ndarray) -> ImplausibleInertia | None:
    """The flaw of a link whose tensor's trace is below :data:`PLAUSIBLE_TRACE_FRACTION` of a
    solid box's of its ``mass`` (kg) and its geometry's bounding box ``extents`` (m, (3,)), or
    ``None`` (also for no mass or no extent)."""
    a, b, c = (float(v) for v in extents)
    box = mass * (a * a + b * b + c * c) / 6.0
    trace = float(np.trace(inertia))
    if mass <= 0.0 or box <= 0.0 or trace >= PLAUSIBLE_TRACE_FRACTION * box:
        return None
    moments = ", ".join(f"{m:.3g}" for m in np.linalg.eigvalsh(0.5 * (inertia + inertia.T)))
    ratio = box / trace if trace > 0 else math.inf
    if math.isfinite(ratio):
        than = f"has trace {box:.3g} kg m^2, {ratio:.3g} times more"
    else:  # a geometry of absurd size (1e308 m) or a zero trace: no number to print
        than = "has a trace beyond any float" if not math.isfinite(box) else f"has trace {box:.3g} kg m^2"
    problem = (
        f"rotational inertia implausibly small for its mass: {mass:.4g} kg with principal moments {moments} kg m^2 "
        f"(trace {trace:.3g}), where a solid box of that mass filling its geometry's {a:.3g} x {b:.3g} x {c:.3g} m "
        f"bounding box {than} (below 1/{round(1 / PLAUSIBLE_TRACE_FRACTION)} of it)"
    )
    return ImplausibleInertia(
        subject=f"link {link!r}",
        problem=problem,
        repair="nothing (kept as written)",
        link=link,
        mass=float(mass),
        trace=trace,
        extents=(a, b, c),
        box_trace=box,
    )


def inertia_flaw(link: str, inertia: np.ndarray) -> InertiaFlaw | None:
    """The flaw of a link's finite, symmetric inertia tensor (kg m^2), or ``None`` when it is
    physical within :data:`INERTIA_SLACK` (relative to its largest entry)."""
    scale = float(np.max(np.abs(inertia)))
    if scale == 0.0:
        return None
    moments = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    tolerance = INERTIA_SLACK * scale
    a, b, c = (float(m) for m in moments)
    entries = _entries(inertia)
    if a < -tolerance:
        problem = f"inertia ({entries}) is not positive semi-definite: principal moment {a:g}"
    elif c > a + b + tolerance:
        problem = (
            f"inertia ({entries}) is not physical: principal moments {a:g}, {b:g}, {c:g} violate the triangle "
            "inequality (the largest exceeds the sum of the others)"
        )
    else:
        return None
    mean = max((a + b + c) / 3.0, 0.0)
    repaired = mean * np.eye(3)
    change = float(np.max(np.abs(mean - moments)))
    if mean > 0.0:
        repair = (
            f"{INERTIA_RULE}: principal moments set to their mean, {mean:g} kg m^2 (each moved by at most {change:g})"
        )
    else:
        repair = f"{INERTIA_RULE}: principal moments set to zero (their mean is not positive), a point mass"
    return InertiaFlaw(
        subject=f"link {link!r}",
        problem=problem,
        repair=repair,
        link=link,
        inertia=tuple(tuple(float(v) for v in row) for row in inertia),
        moments=(a, b, c),
        repaired=tuple(tuple(float(v) for v in row) for row in repaired),
    )


def repair_inertias(model: pin.Model, flaws: Iterable[Flaw], inertials: Mapping[str, Any]) -> list[str]:
    """Apply the repairs of ``flaws`` to a Pinocchio model built from the file, in place.

    Pinocchio adds each link's inertia into the body of the joint that moves it (links on fixed
    joints merged in), so each repair adds its change ``R (I_new - I_old) R^T`` (the link's
    ``<inertial>`` frame expressed in that joint's frame) to that body's rotational inertia about
    the joint origin; the mass and the first moment of mass are not touched.

    Args:
        model: the model as built (before any joint is locked).
        flaws: the description's flaws (those that are not inertia flaws are skipped).
        inertials: each link's :class:`~mobmanip.descriptions.description.Inertial` by link name
            (for its frame).

    Returns:
        The links repaired (a link Pinocchio did not keep as a body frame is skipped).
    """
    import pinocchio as pin

    done = []
    for flaw in flaws:
        if not isinstance(flaw, InertiaFlaw) or not model.existFrame(flaw.link, pin.FrameType.BODY):
            continue
        frame = model.frames[model.getFrameId(flaw.link, pin.FrameType.BODY)]
        inertial = inertials[flaw.link]
        rotation = frame.placement.rotation @ inertial.origin.rotation
        change = rotation @ flaw.delta @ rotation.T
        joint = frame.parentJoint
        parameters = np.array(model.inertias[joint].toDynamicParameters(), dtype=float)
        # [m, m c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] about the joint origin: linear in the inertia
        parameters[4:] += (change[0, 0], change[0, 1], change[1, 1], change[0, 2], change[1, 2], change[2, 2])
        model.inertias[joint] = pin.Inertia.FromDynamicParameters(parameters)
        done.append(flaw.link)
    return done


def refuse(flaws: Sequence[Flaw], error) -> None:
    """Raise ``error(reason)`` for the first flaw (the strict policy); nothing when there is none."""
    if flaws:
        more = f" ({len(flaws) - 1} more flaw{'s' if len(flaws) > 2 else ''} after it)" if len(flaws) > 1 else ""
        raise error(flaws[0].refusal + more)
