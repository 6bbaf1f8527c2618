"""What every platform kind provides: the protocol of the platform family.

Two objects per kind:

- a :class:`PlatformKind` (one instance per kind, in the registry of :mod:`mobmanip.platforms`)
  knows the kind's spec: it reads and writes its ``[wheels]`` table, says which joints the
  platform keeps moving and which limit names it accepts, recognises the kind in a robot's
  description (:class:`mobmanip.descriptions.RobotDescription`, whatever file it was read from),
  and builds the platform of a loaded model;
- a :class:`Platform` (one per loaded robot) is the constraint layer itself: the reduced
  platform velocities ``eta`` and the rows of S(q) and Sdot(q, x) that map them to Pinocchio's
  tangent space, the actuation block of Q, the limits of ``eta`` and how figures draw it.

Pinocchio's planar root joint has velocity (v_x, v_y, omega_z) in the platform's own frame
(tangent indices :data:`BASE_V`); a platform's rows of S cover those and its wheel joints.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

if TYPE_CHECKING:
    import pinocchio as pin

    from ..descriptions import RobotDescription

#: Tangent indices of the planar root joint (v_x, v_y, omega_z in the platform frame).
BASE_V = (0, 1, 2)

#: A default body outline (m, platform frame) for a platform without wheel geometry.
DEFAULT_OUTLINE = ((-0.25, -0.2), (0.25, -0.2), (0.25, 0.2), (-0.25, 0.2))


def positive_length(label: str, value: object) -> float:
    """A wheel length (m) within :data:`mobmanip.support.ranges.WHEEL_LENGTH`, else a WheelError naming
    ``label`` and the value."""
    from ..errors import WheelError
    from ..support.ranges import WHEEL_LENGTH

    low, high = WHEEL_LENGTH
    message = f"{label} must be a length in [{low:g}, {high:g}] m, got {value!r}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise WheelError(message)
    value = float(value)
    if not (math.isfinite(value) and low <= value <= high):
        raise WheelError(message)
    return value


def toml_string(value: str) -> str:
    """A TOML basic string that reads back to ``value`` (see :func:`mobmanip.support.toml.toml_string`)."""
    from ..support.toml import toml_string as string

    return string(value)


def unicycle_rows(radius: float, half_track: float, center) -> np.ndarray:
    """Root-joint rows of S for two wheel rates (right, left) that drive a point like a unicycle.

    The point P at ``center`` = (p_x, p_y) in the platform frame moves forward at
    r/2 (eta_r + eta_l) with no lateral velocity, and the platform turns at
    omega = r / (2 b) (eta_r - eta_l); the platform origin then moves as v_P - omega x p.

    Returns:
        (3, 2) block: (v_x, v_y, omega_z) of the root joint per unit eta_r and eta_l.
    """
    r, c = radius, radius / (2.0 * half_track)
    px, py = center
    return np.array(
        [
            [r / 2 + py * c, r / 2 - py * c],  # v_x of the platform origin
            [-px * c, px * c],  # v_y of the platform origin
            [c, -c],  # omega_z
        ]
    )


class Platform(ABC):
    """The constraint layer of one loaded robot's platform.

    Subclasses are frozen dataclasses; ``kind`` is their registry name.
    """

    kind: ClassVar[str]

    #: Whether S depends on the configuration (then Sdot is not zero along a motion).
    varies_with_q: ClassVar[bool] = False
    #: Whether its wheels' contacts slide sideways along its own motions (a skid-steer's off-axle
    #: wheels scrub when it turns): on the floor their forces are then held to no work along the
    #: platform's reduced velocities at rest; rolling wheels do no work by themselves.
    scrubs: ClassVar[bool] = False

    @property
    @abstractmethod
    def reduced_names(self) -> tuple[str, ...]:
        """Names of the reduced platform velocities eta, in their order in x."""

    @property
    def n_reduced(self) -> int:
        return len(self.reduced_names)

    @property
    def actuated(self) -> tuple[bool, ...]:
        """Whether each reduced platform velocity is driven by a motor."""
        return (True,) * self.n_reduced

    @property
    def drive_names(self) -> tuple[str, ...]:
        """The reduced velocities that are wheel drives: the ones wheel limits and the sweeps'
        wheel-limit scales act on (empty when the platform has no drive wheels)."""
        return ()

    @abstractmethod
    def tangent_block(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The platform's rows of S at configuration q.

        Args:
            q: configuration (nq,); may be ``None`` when ``varies_with_q`` is False.

        Returns:
            ``(v_indices, block)``: tangent indices (root joint, then wheel joints) and the
            (len(v_indices), n_reduced) block mapping eta to their rates.
        """

    def tangent_block_rate(self, q: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The platform's rows of dS/dt along a motion with reduced velocity x (whole x, (nx,)).

        Zero for a platform whose S is constant; same rows as :meth:`tangent_block`.
        """
        rows, block = self.tangent_block(q)
        return rows, np.zeros_like(block)

    @abstractmethod
    def actuation_block(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the platform's efforts enter the generalized forces: ``(v_indices, block)`` of B."""

    def description_limits(self, description: RobotDescription) -> Mapping[str, tuple[float | None, float | None]]:
        """(velocity, effort) of each reduced platform velocity read from the robot's
        description, by name; ``None`` where it gives none. By default each name is a joint."""
        return {name: description.limits(name) for name in self.reduced_names}

    def missing_limit_source(self, name: str, kind: str) -> tuple[str, str]:
        """Why the ``kind`` (velocity/effort) limit of ``name`` is missing, and its unit, for
        the message: ``(reason, unit)``."""
        return f"the URDF joint has no <limit {kind}=...>", ""

    def outline(self) -> np.ndarray:
        """Corners (k, 2) of the platform body seen from above, in the platform frame (m)."""
        return np.array(DEFAULT_OUTLINE)

    def wheels(self) -> tuple[tuple[str, float], ...]:
        """(joint name, radius in m) of each wheel a figure draws."""
        return ()

    def wheels_per_drive(self, name: str) -> int:
        """How many wheels the drive ``name`` (one of :attr:`drive_names`) turns together: its
        effort is their torques' sum, its rate theirs. One by default."""
        return 1

    def free_rolling(self) -> dict[str, tuple[float, float]]:
        """The wheels that roll freely (no motor), by joint name, each with its rolling direction in
        the platform frame's floor plane (unit (2,)): the floor pushes such a wheel across it only
        (along it, only what the wheel's own spin takes). None by default."""
        return {}


@dataclass(frozen=True)
class WheelsSpec:
    """Base of each kind's ``[wheels]`` table, as read from a spec."""

    @property
    def joint_names(self) -> tuple[str, ...]:
        """URDF joints the platform keeps moving (they stay in the Pinocchio model)."""
        return ()

    @staticmethod
    def check_lengths(*lengths: tuple[str, float | None]) -> None:
        """Each (label, value) length the table gives within range (:func:`positive_length`);
        ``None``, read from the robot file instead, passes."""
        for label, value in lengths:
            if value is not None:
                positive_length(label, value)

    @staticmethod
    def refuse_repeated(names: Sequence[str], kind: str) -> None:
        """A SpecError naming the joints the table lists more than once (``kind``: how the
        message names the platform's wheels, e.g. ``"skid-steer"``)."""
        from ..errors import SpecError

        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise SpecError(f"{kind} wheels listed twice: {repeated}")


@dataclass(frozen=True)
class Detected:
    """A platform recognised in a URDF: its ``[wheels]`` spec and notes for the user."""

    wheels: WheelsSpec | None
    notes: tuple[str, ...] = ()


class PlatformKind(ABC):
    """One kind of platform: its spec, its detection and how a loaded model builds it."""

    #: Registry name, as written in specs (``platform = "..."``).
    name: ClassVar[str]
    #: One line for help texts.
    summary: ClassVar[str]
    #: Keys its ``[wheels]`` table accepts; none for a kind that takes no such table.
    wheel_keys: ClassVar[tuple[str, ...]] = ()

    @property
    def takes_wheels(self) -> bool:
        """Whether the spec needs a ``[wheels]`` table: the kind accepts keys in one."""
        return bool(self.wheel_keys)

    def parse_wheels(self, table: Mapping, where: str) -> WheelsSpec:
        """The kind's ``[wheels]`` spec from a parsed TOML table (its keys checked, then
        :meth:`read_wheels`).

        Raises:
            SpecError: a kind without wheels, unknown keys or wrong types (naming ``where``).
        """
        from ..errors import SpecError

        if not self.takes_wheels:
            raise SpecError(f"{where}: a {self.name} platform takes no [wheels] table")
        self.check_wheel_keys(table, where)
        return self.read_wheels(table, where)

    def read_wheels(self, table: Mapping, where: str) -> WheelsSpec:
        """The ``[wheels]`` spec from a table of known keys (a kind with :attr:`wheel_keys`).

        Raises:
            SpecError: missing keys or wrong types (naming ``where``).
        """
        raise NotImplementedError(f"the {self.name} platform kind reads no [wheels] table")

    def check_wheel_keys(self, table: Mapping, where: str) -> None:
        """Refuse keys of a ``[wheels]`` table that the kind does not know.

        Raises:
            SpecError: naming the unknown keys and ``where``.
        """
        from ..errors import SpecError

        extra = sorted(set(table) - set(self.wheel_keys))
        if extra:
            raise SpecError(f"{where}: unknown keys in [wheels]: {extra}; expected some of {list(self.wheel_keys)}")

    def wheels_from_joints(self, joints: Sequence[str]) -> WheelsSpec:
        """The ``[wheels]`` spec from joint names given on the command line (``--wheels``)."""
        from ..errors import WheelError

        if not self.takes_wheels:
            raise WheelError(f"a {self.name} platform takes no wheel joints")
        raise WheelError(
            f"--wheels names a differential drive's RIGHT,LEFT pair; give a {self.name} platform's wheels in "
            f"its spec's [wheels] table ({', '.join(self.wheel_keys)}), or let init-spec detect them"
        )

    def limit_names(self, wheels: WheelsSpec | None) -> tuple[str, ...]:
        """Names, other than URDF joints, that ``[limits.*]`` may set (e.g. ``base_x``)."""
        return ()

    @abstractmethod
    def build(self, wheels: WheelsSpec | None, description: RobotDescription, model: pin.Model) -> Platform:
        """The platform of a loaded model (geometry from the description and the Pinocchio model).

        Args:
            wheels: the spec's ``[wheels]`` (``None`` when the kind takes none).
            description: the robot file as read (its shapes give wheel radii).
            model: the Pinocchio model with its planar root joint (locked joints removed).

        Raises:
            WheelError: geometry that does not fit the kind (naming the joint and value).
        """

    def detect(self, description: RobotDescription, candidates: Sequence, path: str) -> Detected | None:
        """Recognise this kind among a robot's wheel candidates (see
        :func:`mobmanip.platforms.wheels.wheel_candidates`); ``None`` if it does not fit.

        Raises:
            WheelError: the kind fits but is ambiguous (the message says what to add).
        """
        return None

    def toml_lines(self, wheels: WheelsSpec | None) -> list[str]:
        """The spec's ``[wheels]`` section (with comments) for ``init-spec``; empty if none."""
        return []

    @staticmethod
    def wheels_section(
        comment: str, joints: Mapping[str, str | Sequence[str]], lengths: Mapping[str, float | None]
    ) -> list[str]:
        """The lines of :meth:`toml_lines`: ``comment`` (each of its lines commented out), the table's
        header, ``key = joint`` (or a list of joints) for each of ``joints``, then the lengths the
        URDF gives unless set: ``key = value`` for each one set, a commented placeholder for each
        left to the URDF."""
        from ..support.toml import toml_array

        lines = [f"# {line}" for line in comment.split("\n")] + ["[wheels]"]
        lines += [f"{key} = {toml_string(v) if isinstance(v, str) else toml_array(v)}" for key, v in joints.items()]
        return lines + [f"{key} = {float(value)!r}" if value is not None else f"# {key} = ...  # m, overrides the URDF"
                        for key, value in lengths.items()]  # fmt: skip

    #: Whether the wheel joints themselves take limits (False: the kind's own names do).
    limits_by_joint: ClassVar[bool] = True

    def description_limits(
        self, wheels: WheelsSpec | None, description: RobotDescription
    ) -> Mapping[str, tuple[float | None, float | None]]:
        """(velocity, effort) that the robot's description implies for the kind's own
        :meth:`limit_names`."""
        return {}

    def toml_limit_hints(self, wheels: WheelsSpec | None) -> list[tuple[str, str]]:
        """(name, comment) of own limit names the URDF cannot give, for ``init-spec``."""
        return []
