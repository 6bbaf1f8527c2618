"""Exceptions raised by mobmanip: every one of them, in this one module.

Every error the toolkit raises on bad input derives from :class:`MobmanipError`, so callers
(and the command line, which prints one ``mobmanip: error: ...`` line for it) can catch one
type. Library code raises :class:`ArgumentError` for a bad argument value; :class:`UsageError`
is the command line's own. Subclasses carry the offending value in attributes
and, where it helps, the list of valid alternatives.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any


class MobmanipError(Exception):
    """Root of every error mobmanip raises on bad input or impossible requests."""


def closest_first(name: str, candidates: Iterable[str], limit: int = 8) -> list[str]:
    """Return candidates ordered by similarity to ``name`` (closest first), at most ``limit``."""
    candidates = list(candidates)
    ranked = difflib.get_close_matches(name, candidates, n=limit, cutoff=0.0)
    return ranked[:limit]


class UnknownRobotError(MobmanipError):
    """A robot name is neither a built-in robot nor an existing spec file."""

    def __init__(self, name: str, builtins: Iterable[str]):
        self.name = name
        self.builtins = sorted(builtins)
        super().__init__(
            f"unknown robot {name!r}: not a built-in robot ({', '.join(self.builtins)}) and no spec file at that path"
        )


class SpecError(MobmanipError):
    """A robot spec (TOML) is unreadable, malformed or inconsistent with its URDF."""


class UnknownPostureError(SpecError):
    """A posture name the spec does not define (``--posture``); lists the ones it does."""

    def __init__(self, robot: str, name: object, available: Iterable[str]):
        self.name = name
        self.available = list(available)
        super().__init__(f"robot {robot!r} has no posture {name!r}; its postures: {', '.join(self.available)}")


class FileError(MobmanipError):
    """A file that cannot be used as what it should be. Carries the file's ``path`` and the
    ``reason``; the message is ``"<label> <path>: <reason>"``."""

    #: How the message names the file.
    label = "file"

    def __init__(self, path: str, reason: str):
        self.path = path
        self.reason = reason
        super().__init__(f"{self.label} {path}: {reason}")


class DescriptionError(FileError):
    """A robot description file is missing, unreadable, malformed, of no known format, or
    describes no physical robot. Carries the file's ``path`` and the ``reason``; each format's
    own error (:class:`UrdfError`) names the file's language in the message."""

    label = "robot description"


class UrdfError(DescriptionError):
    """A URDF file is missing, unreadable, malformed or uses a construct mobmanip cannot model."""

    label = "URDF"


class XacroError(DescriptionError):
    """A xacro file that cannot be expanded: missing, malformed, an argument without a value or a
    ``$(find PKG)`` package found nowhere (the message names it and the option that supplies it)."""

    label = "xacro"


class MjcfError(DescriptionError):
    """An MJCF (MuJoCo) file that cannot be read, or that uses what mobmanip cannot model (a ball
    joint, several robots under ``<worldbody>``), naming it."""

    label = "MJCF"


class UnknownFormatError(DescriptionError):
    """A robot file whose suffix no registered description format reads; lists the known suffixes."""

    def __init__(self, path: str, suffix: str, known: Iterable[str]):
        self.suffix = suffix
        self.known = tuple(known)
        what = f"suffix {suffix!r}" if suffix else "no suffix"
        super().__init__(
            path, f"{what}: no robot-description format reads it (known suffixes: {', '.join(self.known)})"
        )


class RecordingError(FileError):
    """A recording (a ROS bag) that cannot be read as a trajectory: missing, unreadable, a topic
    missing or of another message type, too little data. Carries the ``path`` and the ``reason``."""

    label = "recording"


class NameNotFoundError(MobmanipError):
    """A joint or frame name does not exist; lists the names that do (closest first)."""

    kind = "name"

    def __init__(self, name: str, available: Iterable[str], where: str = ""):
        self.name = name
        self.available = closest_first(name, available)
        suffix = f" in {where}" if where else ""
        hint = f"; closest: {', '.join(self.available)}" if self.available else ""
        super().__init__(f"unknown {self.kind} {name!r}{suffix}{hint}")


class JointNotFoundError(NameNotFoundError):
    """A joint name does not exist in the model or URDF."""

    kind = "joint"


class FrameNotFoundError(NameNotFoundError):
    """A frame (link) name does not exist in the model or URDF."""

    kind = "frame"


class WheelError(MobmanipError):
    """The drive wheels are missing, ambiguous or geometrically unusable."""


class LimitError(MobmanipError):
    """A velocity or effort limit is missing, non-positive or not finite."""

    def __init__(self, name: str, kind: str, value: object):
        self.name = name
        self.kind = kind
        self.value = value
        super().__init__(f"{kind} limit of {name!r} must be a positive finite number, got {value!r}")


class ConfigurationError(MobmanipError):
    """A configuration (or velocity) is malformed: wrong shape, unknown joint, NaN or infinite."""


class TaskError(MobmanipError):
    """An unknown task space or an inconsistent task/object request."""


class ModelError(MobmanipError):
    """The loaded model cannot support the requested analysis (e.g. massless moving links)."""


class MissingLimitError(LimitError):
    """A velocity or effort limit is given neither by the URDF nor by the spec."""

    def __init__(self, name: str, kind: str, source: str, unit: str = ""):
        self.name = name
        self.kind = kind
        self.value = None
        self.source = source
        unit = f" ({unit})" if unit else ""
        MobmanipError.__init__(
            self, f"no {kind} limit for {name!r}: {source}; set it in [limits.{kind}] of the spec{unit}"
        )


class ArgumentError(MobmanipError):
    """An argument of a library call has a value it cannot take (an unknown method, a
    non-positive count, a malformed direction, ...); the message names it and the value."""


class NotDecimalError(ArgumentError, ValueError):
    """A number not written in decimal notation (``"1_0"``, digits of other scripts). Also a
    ``ValueError``, as ``float``'s own refusal is, so that argparse reports it as an invalid value
    of its option."""


class UsageError(ArgumentError):
    """Command-line arguments that contradict each other or miss a required choice.

    Raised by :mod:`mobmanip.commands` only; library code raises :class:`ArgumentError`.
    """


class GridError(ArgumentError):
    """A sweep grid that cannot be parsed or makes no sense."""


class UnreachableGridError(GridError):
    """No grid point is within the arms' reach: the message names the grid's distances and angles."""


class UnreachableObjectError(ArgumentError):
    """No platform pose and posture hold the object at the requested point (within the region):
    the message names the point and the region."""


class OutputError(MobmanipError):
    """An output file cannot be written."""


class ViewerError(MobmanipError):
    """The meshcat viewer cannot start, or its server stopped answering."""


class PortBusyError(ViewerError):
    """The port asked for with ``--port`` is in use."""

    def __init__(self, port: int, scan_start: int = 7000):
        self.port = port
        super().__init__(
            f"port {port} is in use; choose another --port or omit --port to take the first free one from {scan_start}"
        )


class MeasureError(MobmanipError):
    """A measure cannot be registered or computed as asked (e.g. swept without a batch form)."""


class UnknownMeasureError(MeasureError):
    """A measure name that is not registered; lists the names that are."""

    def __init__(self, name: object, available: Iterable[str]):
        self.name = name
        self.available = list(available)
        super().__init__(f"unknown measure {name!r}; expected one of {', '.join(self.available)}")


class SetQueryError(MeasureError, ValueError):
    """A query on a task-space set that makes no sense: a zero or non-finite direction, points
    or coordinates of the wrong dimension, task coordinates out of range. Also a ``ValueError``,
    as bad arguments to a function usually are."""


class RangeError(ArgumentError):
    """A finite number outside the range where mobmanip's results are certified (a limit of
    1e-300 or 1e12, a platform 1e13 m from the origin, ...); the message states the range."""

    def __init__(self, what: str, value: object, low: float, high: float, unit: str = "", why: str = ""):
        self.what = what
        self.value = value
        self.low = low
        self.high = high
        unit = f" {unit}" if unit else ""
        why = f" ({why})" if why else ""
        super().__init__(f"{what} = {value!r} is outside the supported range [{low:g}, {high:g}]{unit}{why}")


class NumericalError(MobmanipError):
    """A result that is not finite: mobmanip reports it instead of printing or writing NaN or inf."""


class CarryFailed(NumericalError):
    """The carry QP (:func:`mobmanip.motion.carry.carry`) has no solution at some step.

    Attributes:
        diagnosis: what binds (:class:`mobmanip.motion.carry.CarryDiagnosis`).
        partial: the motion up to the failing step (:class:`mobmanip.motion.carry.CarryRun`).
        preparation: the self-motion before the path, when the path's motion failed after one.
    """

    def __init__(self, message: str, diagnosis: Any, partial: Any, preparation: Any = None):
        super().__init__(message)
        self.diagnosis = diagnosis
        self.partial = partial
        self.preparation = preparation


class TeamError(SpecError):
    """A team description (several robots holding one object) is malformed or inconsistent: an
    unknown robot or arm, a duplicate name, a hand too far from its grasp point, ..."""


class NotRepresentable(ModelError):
    """A robot (or a part of it) that the physics referee cannot build in MuJoCo; the message
    says why (:mod:`mobmanip.referee`)."""


class ClusterError(MobmanipError):
    """``--dask`` is malformed, its scheduler cannot be reached, or Dask is missing.

    Attributes:
        address: the ``--dask`` value.
    """

    def __init__(self, address: str, reason: str):
        self.address = address
        super().__init__(f"--dask {address}: {reason}")
