"""Loading a robot: URDF + spec -> Pinocchio model with a planar root joint, and a Robot.

The :class:`Robot` holds the Pinocchio model and data, the platform constraint layer, the torso
(actuated joints shared by all arms, if any), the arms with their index maps, and the velocity
and effort limits of every reduced velocity. Its reduced velocity ``x`` is ordered
[platform (e.g. eta_r, eta_l), torso joints, arm 1 joints, arm 2 joints, ...] and ``S``
(nv x nx) maps it to Pinocchio's tangent space: ``v = S x``. Every joint that is not a wheel
(of a differential drive), a torso joint or an arm joint is locked at the spec's reference.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..descriptions import MOVING_JOINT_TYPES, RobotDescription, check_supported, read_description
from ..descriptions.flaws import refuse
from ..errors import (
    ConfigurationError,
    FrameNotFoundError,
    JointNotFoundError,
    LimitError,
    MissingLimitError,
    SpecError,
    WheelError,
    closest_first,
)
from ..platforms import LockedPlatform, Platform, get_kind
from ..support.notices import notice
from ..support.ranges import (
    JOINT_POSITION,
    MAX_MODEL_DOF,
    PLATFORM_POSITION,
    UNIT_PAIR_TOLERANCE,
    check_limit,
    check_limit_ratio,
)
from .spec import RobotSpec, find_spec

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Arm:
    """One arm in the loaded model.

    Attributes:
        name: arm name from the spec.
        joint_names: its actuated joints, base to tip.
        v_indices: their tangent indices in the Pinocchio model.
        end_effector: name of the end-effector frame.
        frame_id: Pinocchio frame index of the end effector.
    """

    name: str
    joint_names: tuple[str, ...]
    v_indices: tuple[int, ...]
    end_effector: str
    frame_id: int


@dataclass(frozen=True, eq=False)
class Robot:
    """A loaded mobile manipulator. Build it with :func:`load_robot`.

    Attributes:
        spec: the spec it was loaded from.
        model: Pinocchio model (planar root joint, joints outside wheels and arms locked).
        data: Pinocchio data for ``model`` (a workspace; not thread-safe).
        platform: the platform constraint layer.
        arms: the arms, in spec order.
        velocity_limits: velocity limit of each reduced velocity (rad/s or m/s), shape (nx,).
        effort_limits: effort limit of each reduced velocity (N m or N), shape (nx,).
        wheel_platform: the robot's own moving platform (kept when ``platform`` is locked),
            or ``None`` for a fixed-base robot.
        joint_velocity_limits: per-joint velocity limits by name (all active joints).
        joint_effort_limits: per-joint effort limits by name.
        torso_joint_names: actuated joints shared by all arms, base to tip (may be empty).
        torso_v_indices: their tangent indices in the Pinocchio model.
        description: the robot file as read (see :mod:`mobmanip.descriptions`), the whole tree
            before any joint was locked; ``None`` only for a Robot built by hand (then
            :func:`description_of` reads it from the spec).
        warnings: what was repaired when the robot was loaded, one line per flaw of its file
            (see :mod:`mobmanip.descriptions.flaws`) that the spec does not list in
            ``accepted_repairs``; every analysis of the robot carries them.
    """

    spec: RobotSpec
    model: pin.Model
    data: pin.Data
    platform: Platform
    arms: tuple[Arm, ...]
    joint_velocity_limits: Mapping[str, float]
    joint_effort_limits: Mapping[str, float]
    wheel_platform: Platform | None = None
    torso_joint_names: tuple[str, ...] = ()
    torso_v_indices: tuple[int, ...] = ()
    description: RobotDescription | None = field(default=None, repr=False)
    warnings: tuple[str, ...] = field(default=(), repr=False)
    S: np.ndarray = field(init=False, repr=False)
    B: np.ndarray = field(init=False, repr=False)
    Q: np.ndarray = field(init=False, repr=False)
    velocity_limits: np.ndarray = field(init=False, repr=False)
    effort_limits: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        nv, nx = self.model.nv, self.nx
        B = np.zeros((nv, nx))
        n_eta = self.platform.n_reduced
        if n_eta:
            rows_b, block_b = self.platform.actuation_block()
            B[np.ix_(rows_b, range(n_eta))] = block_b
        for k, v in enumerate(self.torso_v_indices + self.arm_v_indices):
            B[v, n_eta + k] = 1.0
        S = self._assemble_null_space(self.platform.tangent_block(self.neutral()))
        # B acts on wheel and joint coordinates only, where S does not depend on q: Q is constant.
        Q = S.T @ B
        for matrix in (S, B, Q):
            matrix.setflags(write=False)
        object.__setattr__(self, "S", S)
        object.__setattr__(self, "B", B)
        object.__setattr__(self, "Q", Q)
        names = self.reduced_velocity_names
        for attr, table, kind in (
            ("velocity_limits", self.joint_velocity_limits, "velocity"),
            ("effort_limits", self.joint_effort_limits, "effort"),
        ):
            values = []
            for name in names:
                if name not in table:
                    raise LimitError(name, kind, None)
                values.append(table[name])
            check_limit_ratio(kind, dict(zip(names, values)))
            array = np.array(values, dtype=float)
            array.setflags(write=False)
            object.__setattr__(self, attr, array)

    # ----- the constraint layer -----

    def _assemble_null_space(self, platform_rows: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """S (nv, nx) from the platform's rows; torso and arm columns are unit columns."""
        S = np.zeros((self.model.nv, self.nx))
        n_eta = self.platform.n_reduced
        rows, block = platform_rows
        if n_eta:
            S[np.ix_(rows, np.arange(n_eta))] = block
        for k, v in enumerate(self.torso_v_indices + self.arm_v_indices):
            S[v, n_eta + k] = 1.0
        return S

    def __repr__(self) -> str:
        arms = ", ".join(arm.name for arm in self.arms)
        return f"Robot({self.name!r}, platform={self.platform.kind!r}, arms=({arms}), nq={self.model.nq}, nx={self.nx})"

    @property
    def platform_locked(self) -> bool:
        """Whether the platform is held still (a fixed-base robot, or ``with_platform("fixed")``)."""
        return isinstance(self.platform, LockedPlatform)

    @property
    def constant_null_space(self) -> bool:
        """Whether S is the same at every configuration (then :attr:`S` is S(q) for all q)."""
        return not self.platform.varies_with_q

    def null_space(self, q: np.ndarray) -> np.ndarray:
        """S(q), (nv, nx): the joint rates v = S(q) x of the reduced velocities x.

        Equal to :attr:`S` (its value at the home configuration) when
        :attr:`constant_null_space`.
        """
        if self.constant_null_space:
            return self.S
        return self._assemble_null_space(self.platform.tangent_block(self.check_configuration(q)))

    def null_space_rate(self, q: np.ndarray, x: np.ndarray) -> np.ndarray:
        """dS/dt, (nv, nx), along the motion with reduced velocity x at configuration q.

        Zero when :attr:`constant_null_space`. Only platform rows can depend on q.
        """
        out = np.zeros((self.model.nv, self.nx))
        if self.constant_null_space or not self.platform.n_reduced:
            return out
        x = np.asarray(x, dtype=float)
        if x.shape != (self.nx,) or not np.all(np.isfinite(x)):
            raise ConfigurationError(f"reduced velocity must be {self.nx} finite numbers, got shape {x.shape}")
        rows, block = self.platform.tangent_block_rate(self.check_configuration(q), x)
        out[np.ix_(rows, np.arange(self.platform.n_reduced))] = block
        return out

    # ----- sizes and names -----

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def arm_v_indices(self) -> tuple[int, ...]:
        """Tangent indices of all arm joints, arm by arm."""
        return tuple(v for arm in self.arms for v in arm.v_indices)

    @property
    def nx(self) -> int:
        """Number of reduced velocities (platform + torso joints + arm joints)."""
        return self.platform.n_reduced + len(self.torso_v_indices) + len(self.arm_v_indices)

    @property
    def reduced_velocity_names(self) -> tuple[str, ...]:
        """Names of the reduced velocities: platform first, then the torso, then each arm's joints."""
        arms = tuple(j for arm in self.arms for j in arm.joint_names)
        return self.platform.reduced_names + self.torso_joint_names + arms

    @property
    def torso_slice(self) -> slice:
        """Where the torso joints sit in the reduced velocity vector (empty without a torso)."""
        start = self.platform.n_reduced
        return slice(start, start + len(self.torso_v_indices))

    @property
    def arm_slices(self) -> tuple[slice, ...]:
        """Where each arm's own joints sit in the reduced velocity vector (after the torso)."""
        out, start = [], self.torso_slice.stop
        for arm in self.arms:
            out.append(slice(start, start + len(arm.v_indices)))
            start += len(arm.v_indices)
        return tuple(out)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of all joints of the (reduced) model except the root joint."""
        return tuple(self.model.names[j] for j in range(2, self.model.njoints))

    # ----- variants -----

    def with_platform(self, kind: str) -> Robot:
        """The same robot with its platform ``"fixed"`` (locked) or back to its own kind.

        Raises:
            SpecError: an unknown kind, or asking for a moving platform the robot lacks.
        """
        if kind in ("fixed", "locked"):
            platform = LockedPlatform()
        elif self.wheel_platform is not None and kind == self.wheel_platform.kind:
            platform = self.wheel_platform
        else:
            own = self.wheel_platform.kind if self.wheel_platform is not None else "fixed"
            raise SpecError(f"robot {self.name!r} cannot use platform {kind!r}; it has {own!r} or 'fixed'")
        return dataclasses.replace(self, platform=platform)

    def with_limits(
        self,
        velocity: Mapping[str, float] | None = None,
        effort: Mapping[str, float] | None = None,
    ) -> Robot:
        """The same robot with some limits replaced (by reduced-velocity or joint name).

        Raises:
            JointNotFoundError: a name that is not an active joint or platform coordinate.
            LimitError: a non-positive or non-finite value.
        """
        new_v, new_e = dict(self.joint_velocity_limits), dict(self.joint_effort_limits)
        for table, changes, kind in ((new_v, velocity, "velocity"), (new_e, effort, "effort")):
            for name, value in (changes or {}).items():
                if name not in table:
                    raise JointNotFoundError(name, table, where=f"{kind} limits of {self.name}")
                table[name] = _positive_limit(name, kind, value)
        return dataclasses.replace(self, joint_velocity_limits=new_v, joint_effort_limits=new_e)

    def with_wheel_limits(self, velocity: float | None = None, effort: float | None = None) -> Robot:
        """The same robot with every drive wheel's velocity (rad/s) or effort (N m) limit set. A
        drive that turns several wheels together (a skid-steer's side) turns at their rate and
        pushes with the sum of their torques: its effort limit is ``effort`` times its wheels."""
        platform = self.wheel_platform
        drives = platform.drive_names if platform is not None else ()
        if not drives:
            raise WheelError(f"robot {self.name!r} has no drive wheels to set a wheel limit on")
        assert platform is not None
        return self.with_limits(
            velocity=None if velocity is None else dict.fromkeys(drives, velocity),
            effort=None if effort is None else {name: effort * platform.wheels_per_drive(name) for name in drives},
        )

    # ----- configurations -----

    def neutral(self) -> np.ndarray:
        """The home configuration: platform at the origin, joints at zero or at their ``[reference]``.

        A spec may give a moving joint a home position in ``[reference]`` (e.g. when zero lies
        outside the joint's range, or a torso's mid-height); every other joint is at zero.
        """
        q = pin.neutral(self.model)
        for name, value in self.spec.reference.items():
            if self.model.existJointName(name):
                joint = self.model.joints[self.model.getJointId(name)]
                if joint.nq == 2:
                    q[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
                else:
                    q[joint.idx_q] = value
        return q

    def hold_configuration(self) -> np.ndarray:
        """The spec's hold posture (see :attr:`mobmanip.robot.spec.RobotSpec.hold`), platform at the
        origin; the home configuration if the spec gives none."""
        return self.configuration((0.0, 0.0, 0.0), self.spec.hold)

    def configuration(
        self, platform: tuple[float, float, float] = (0.0, 0.0, 0.0), joints: Mapping[str, float] | None = None
    ) -> np.ndarray:
        """Build q from the platform pose (x m, y m, yaw rad) and joint values by name.

        Joints not named stay at their home position (see :meth:`neutral`; zero unless the
        spec's ``[reference]`` says otherwise).

        Raises:
            ConfigurationError: a NaN/infinite value or a malformed platform pose.
            JointNotFoundError: a joint name not in the model.
        """
        try:
            entries = list(platform)
        except TypeError:
            raise ConfigurationError(f"platform pose must be [x, y, yaw], got {platform!r}") from None
        if len(entries) != 3:
            raise ConfigurationError(f"platform pose must be [x, y, yaw], got {entries!r}")
        pose = [_finite_number(v, f"platform {label}") for label, v in zip(("x", "y", "yaw"), entries)]
        q = self.neutral()
        x, y, yaw = pose
        q[:4] = (x, y, math.cos(yaw), math.sin(yaw))
        for name, value in (joints or {}).items():
            if not self.model.existJointName(name) or self.model.getJointId(name) == 1:
                raise JointNotFoundError(name, self.joint_names, where=f"robot {self.name}")
            value = _finite_number(value, f"joint {name!r}")
            joint = self.model.joints[self.model.getJointId(name)]
            if joint.nq == 2:  # continuous joint: (cos, sin)
                q[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
            else:
                q[joint.idx_q] = float(value)
        return q

    def configuration_dict(self, q: np.ndarray) -> dict:
        """The inverse of :meth:`configuration`: ``{"platform": [x, y, yaw], "joints": {...}}``."""
        q = self.check_configuration(q)
        joints = {}
        for j in range(2, self.model.njoints):
            joint = self.model.joints[j]
            if joint.nq == 2:
                value = math.atan2(q[joint.idx_q + 1], q[joint.idx_q])
            else:
                value = float(q[joint.idx_q])
            joints[self.model.names[j]] = value
        return {"platform": list(platform_pose(q)), "joints": joints}

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        """A name for each entry of q, (nq,): ``platform_x``, ``platform_y``, ``platform_cos_yaw``,
        ``platform_sin_yaw``, then each joint's name (``NAME_cos``, ``NAME_sin`` for a continuous
        joint, which Pinocchio stores as a cosine and a sine)."""
        names = ["platform_x", "platform_y", "platform_cos_yaw", "platform_sin_yaw"]
        for j in range(2, self.model.njoints):
            joint, name = self.model.joints[j], self.model.names[j]
            names += [f"{name}_cos", f"{name}_sin"] if joint.nq == 2 else [name]
        return tuple(names)

    def check_configuration(self, q: ArrayLike) -> np.ndarray:
        """Return q as a float array after checking its size and finiteness.

        Raises:
            ConfigurationError: wrong size, or a NaN/infinite entry (named by its joint).
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.model.nq,):
            raise ConfigurationError(f"configuration must have shape ({self.model.nq},), got {q.shape}")
        bad = np.flatnonzero(~np.isfinite(q))
        if bad.size:
            index = int(bad[0])
            joint = next(
                j
                for j in range(1, self.model.njoints)
                if self.model.joints[j].idx_q <= index < self.model.joints[j].idx_q + self.model.joints[j].nq
            )
            raise ConfigurationError(f"configuration entry {index} (joint {self.model.names[joint]!r}) is {q[index]!r}")
        self.check_configuration_values(q[None, :])
        return q

    @functools.cached_property
    def _q_layout(self) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], tuple[str, ...]]:
        """Indices in q of the (cos, sin) pairs (planar root, continuous joints), of the one-entry
        joints, and the names of both."""
        cos_index, pair_names, single_index, single_names = [], [], [], []
        for j in range(1, self.model.njoints):
            joint, name = self.model.joints[j], self.model.names[j]
            if j == 1:  # the planar root: x, y, cos, sin
                cos_index.append(joint.idx_q + 2)
                pair_names.append(f"{name} (platform yaw)")
            elif joint.nq == 2:
                cos_index.append(joint.idx_q)
                pair_names.append(name)
            elif joint.nq == 1:
                single_index.append(joint.idx_q)
                single_names.append(name)
        return (np.array(cos_index), np.array(single_index, dtype=int), tuple(pair_names), tuple(single_names))

    def _values_in_range(self, q: list[float]) -> bool:
        """Whether one configuration passes :meth:`check_configuration_values` (no message)."""
        cos_index, single_index, _, _ = self._q_layout
        if abs(q[0]) > PLATFORM_POSITION or abs(q[1]) > PLATFORM_POSITION:
            return False
        for k in cos_index.tolist():
            if not abs(math.hypot(q[k], q[k + 1]) - 1.0) <= UNIT_PAIR_TOLERANCE:
                return False
        return all(abs(q[k]) <= JOINT_POSITION for k in single_index.tolist())

    def check_configuration_values(self, qs: np.ndarray) -> None:
        """Finite configurations (N, nq) whose values lie in the supported ranges.

        The platform's x and y lie within :data:`mobmanip.support.ranges.PLATFORM_POSITION` m of the
        origin, every (cos, sin) pair (the platform's yaw, continuous joints) is a unit vector to
        1e-6, every other joint within :data:`mobmanip.support.ranges.JOINT_POSITION`.

        Raises:
            ConfigurationError: naming the row, the joint and the value.
        """
        cos_index, single_index, pair_names, single_names = self._q_layout
        if qs.shape[0] == 1 and self._values_in_range(qs[0].tolist()):  # one q (analyze): plain floats
            return
        where = (lambda row: f"configuration row {row}: ") if qs.shape[0] > 1 else (lambda row: "configuration: ")
        xy = np.abs(qs[:, :2])
        if np.any(xy > PLATFORM_POSITION):
            row, axis = (int(i) for i in np.argwhere(xy > PLATFORM_POSITION)[0])
            raise ConfigurationError(
                f"{where(row)}platform {'xy'[axis]} = {float(qs[row, axis])!r} m lies outside the supported range "
                f"[-{PLATFORM_POSITION:g}, {PLATFORM_POSITION:g}] m"
            )
        norms = np.hypot(qs[:, cos_index], qs[:, cos_index + 1])
        off = np.abs(norms - 1.0) > UNIT_PAIR_TOLERANCE
        if np.any(off):
            row, k = (int(i) for i in np.argwhere(off)[0])
            c, s = float(qs[row, cos_index[k]]), float(qs[row, cos_index[k] + 1])
            raise ConfigurationError(
                f"{where(row)}the (cos, sin) pair of {pair_names[k]} is ({c!r}, {s!r}), of norm {norms[row, k]:.6g}; "
                "it must be a unit vector (build q with Robot.configuration, or normalise it)"
            )
        if single_index.size:
            big = np.abs(qs[:, single_index]) > JOINT_POSITION
            if np.any(big):
                row, k = (int(i) for i in np.argwhere(big)[0])
                value = float(qs[row, single_index[k]])
                raise ConfigurationError(
                    f"{where(row)}joint {single_names[k]!r} = {value!r} lies outside the supported "
                    f"range [-{JOINT_POSITION:g}, {JOINT_POSITION:g}]"
                )

    def frame_id(self, name: str) -> int:
        """Pinocchio index of a frame by name.

        Raises:
            FrameNotFoundError: unknown frame (the message lists the closest existing ones).
        """
        if not self.model.existFrame(name):
            raise FrameNotFoundError(name, [f.name for f in self.model.frames], where=f"robot {self.name}")
        return frame_index(self.model, name)


def platform_pose(q: np.ndarray) -> tuple[float, float, float]:
    """The platform's pose (x m, y m, yaw rad) in configuration q: the planar root joint's block
    (x, y, cos yaw, sin yaw), first in every loaded robot's q."""
    return float(q[0]), float(q[1]), math.atan2(float(q[3]), float(q[2]))


def frame_index(model: pin.Model, name: str) -> int:
    """The index of frame ``name`` (it must exist): its link's frame when a joint (or a site) has the
    same name (Fetch's and Unitree's files name a link like its joint), else the one of that name."""
    for kind in (pin.FrameType.BODY, pin.FrameType.OP_FRAME, pin.FrameType.FIXED_JOINT, pin.FrameType.JOINT):
        if model.existFrame(name, kind):
            return model.getFrameId(name, kind)
    return model.getFrameId(name)


def _finite_number(value, what: str) -> float:
    """``value`` as a finite float (any real number type), else a ConfigurationError naming it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ConfigurationError(f"{what} must be a finite number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise ConfigurationError(f"{what} must be a finite number, got {value!r}")
    return number


def _positive_limit(name: str, kind: str, value) -> float:
    if value is None or isinstance(value, bool):
        raise LimitError(name, kind, value)
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise LimitError(name, kind, value) from None
    if not math.isfinite(value) or value <= 0.0:
        raise LimitError(name, kind, value)
    return check_limit(name, kind, value)


def _check_spec_against_description(spec: RobotSpec, description: RobotDescription) -> None:
    """The robot file must be a supported tree, and every joint and frame the spec names must
    exist in it with a usable type."""
    check_supported(description)
    joints, links = description.joints, description.links
    named_joints = list(spec.active_joint_names)
    missing_joints = [j for j in named_joints if j not in joints]
    missing_frames = [a.end_effector for a in spec.arms if a.end_effector not in links and a.end_effector not in joints]
    if missing_joints or missing_frames:
        parts = []
        for name in missing_joints:
            parts.append(f"joint {name!r} (closest: {', '.join(closest_first(name, joints, 3))})")
        for name in missing_frames:
            parts.append(f"frame {name!r} (closest: {', '.join(closest_first(name, links, 3))})")
        raise SpecError(f"spec {spec.name!r} names what URDF {spec.urdf.name} lacks: {'; '.join(parts)}")
    for name in named_joints:
        if joints[name].type not in MOVING_JOINT_TYPES:
            raise SpecError(f"joint {name!r} is {joints[name].type!r}; wheels, torso and arm joints must move")
    if spec.wheels is not None:
        for name in spec.wheels.joint_names:
            if joints[name].type == "prismatic":
                raise WheelError(f"wheel joint {name!r} is prismatic; a wheel must be revolute or continuous")
    mimics = description.mimics
    for name in named_joints:
        if name in mimics:
            raise description.error(f"joint {name!r} mimics {mimics[name]!r}; mimic joints cannot be actuated here")
    active = set(named_joints)
    own = spec.platform_limit_names
    for table, kind in ((spec.velocity_limits, "velocity"), (spec.effort_limits, "effort")):
        for name in table:
            if name not in active and name not in own:
                valid = sorted(active) + list(own)
                raise JointNotFoundError(name, valid, where=f"[limits.{kind}] of {spec.name}")


def locked_joints(model: pin.Model, reference: Mapping[str, float], keep: set[str]) -> tuple[list[int], np.ndarray]:
    """Joints of a full URDF model (planar root) to lock, and the configuration to lock them at.

    Args:
        model: the model built from the URDF with a planar root joint.
        reference: positions by joint name (rad or m); joints not named sit at zero.
        keep: names of the joints that stay in the model.

    Returns:
        The ids of the joints to lock and the reference configuration for ``pin.buildReducedModel``.
    """
    q_ref = pin.neutral(model)
    locked = []
    for j in range(2, model.njoints):
        name, joint = model.names[j], model.joints[j]
        value = reference.get(name, 0.0)
        if joint.nq == 2:  # continuous joint: (cos, sin)
            q_ref[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
        else:
            q_ref[joint.idx_q] = value
        if name not in keep:
            locked.append(j)
    return locked, q_ref


def _build_model(spec: RobotSpec, description: RobotDescription) -> pin.Model:
    """The description's model with a planar root joint, every joint the spec does not keep
    moving locked at its reference."""
    model = description.build_model(pin.JointModelPlanar())
    moving = sum(1 for name in spec.active_joint_names if model.existJointName(name))
    if moving > MAX_MODEL_DOF:
        raise SpecError(
            f"robot {spec.name!r} has {moving:,} moving joints; mobmanip analyses at most {MAX_MODEL_DOF} "
            "(Pinocchio's data and the mass matrix grow with the square of that number)"
        )
    locked, q_ref = locked_joints(model, spec.reference, keep=set(spec.active_joint_names))
    unknown_ref = sorted(set(spec.reference) - {model.names[j] for j in range(2, model.njoints)})
    if unknown_ref:
        raise JointNotFoundError(unknown_ref[0], list(model.names[2:]), where=f"[reference] of {spec.name}")
    if locked:
        _rename_clashing(model, locked)
        model = pin.buildReducedModel(model, locked, q_ref)
    return model


def _rename_clashing(model: pin.Model, locked: list[int]) -> None:
    """Rename each locked joint that shares its name with another frame (SO-100's ``gripper`` is a
    link and a joint) to ``NAME (joint)``: Pinocchio's reduction looks frames up by name and cannot
    tell the two apart. A locked joint is no longer a joint of the model, so nothing refers to it."""
    names = [frame.name for frame in model.frames]
    for j in locked:
        name = model.names[j]
        if names.count(name) < 2:
            continue
        model.names[j] = f"{name} (joint)"
        for k, frame in enumerate(model.frames):
            if frame.name == name and frame.type == pin.FrameType.JOINT:
                frame.name = f"{name} (joint)"
                model.frames[k] = frame


def _check_hold(spec: RobotSpec, model: pin.Model) -> None:
    """Every position of the spec's ``[hold]`` lies within its joint's range."""
    for name, value in spec.hold.items():
        joint = model.joints[model.getJointId(name)]
        if joint.nq != 1:  # continuous joint: any angle
            continue
        lower, upper = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
        if not lower <= value <= upper:
            raise SpecError(
                f"[hold] of {spec.name}: {name} = {value} lies outside its range [{lower:.6g}, {upper:.6g}]"
            )


def load_robot(spec_or_name: RobotSpec | str | Path, *, strict: bool | None = None) -> Robot:
    """Load a robot from a spec, a built-in name (``"planar_dual_arm"``) or a spec path.

    The robot file's flaws (non-physical inertias) are repaired by the rule of
    :mod:`mobmanip.descriptions.flaws`, each with one warning (in :attr:`Robot.warnings`, and
    said to the user through :func:`mobmanip.support.notices.notice`), unless the load is strict.

    Args:
        spec_or_name: the spec, or a built-in robot's name, or a spec file.
        strict: refuse the file's flaws instead of repairing them (default: the spec's ``strict``).

    Raises:
        MobmanipError: any subclass, naming what is wrong with the spec or URDF (under
            ``strict``, the first flaw, with the way forward).
    """
    spec = spec_or_name if isinstance(spec_or_name, RobotSpec) else find_spec(spec_or_name)
    description = read_description(spec.urdf, **spec.read_options)
    if spec.strict if strict is None else strict:
        refuse(description.flaws, description.error)
    unknown = [link for link in spec.accepted_repairs if link not in description.links]
    if unknown:
        raise SpecError(
            f"accepted_repairs of {spec.name!r} names link {unknown[0]!r}, which {spec.urdf.name} lacks "
            f"(closest: {', '.join(closest_first(unknown[0], description.links, 3))})"
        )
    _check_spec_against_description(spec, description)
    model = _build_model(spec, description)
    _check_hold(spec, model)

    def v_index(name: str, role: str) -> int:
        joint = model.joints[model.getJointId(name)]
        if joint.nv != 1:
            raise SpecError(f"{role} joint {name!r} has {joint.nv} degrees of freedom; expected 1")
        return joint.idx_v

    torso_v = tuple(v_index(name, "torso") for name in spec.torso)
    arms = []
    for arm in spec.arms:
        v_indices = tuple(v_index(name, "arm") for name in arm.joints)
        if not model.existFrame(arm.end_effector):
            raise FrameNotFoundError(arm.end_effector, [f.name for f in model.frames], where=spec.name)
        frame = frame_index(model, arm.end_effector)
        arms.append(Arm(arm.name, tuple(arm.joints), v_indices, arm.end_effector, frame))

    platform = get_kind(spec.platform).build(spec.wheels, description, model)
    from_urdf = dict(platform.description_limits(description))
    velocity: dict[str, float] = {}
    effort: dict[str, float] = {}
    for name in platform.reduced_names + spec.torso + spec.arm_joint_names:
        vel, eff = from_urdf[name] if name in from_urdf else description.limits(name)
        for table, kind, value in ((velocity, "velocity", vel), (effort, "effort", eff)):
            value = (spec.velocity_limits if kind == "velocity" else spec.effort_limits).get(name, value)
            if value is None:
                if name in from_urdf:
                    source, unit = platform.missing_limit_source(name, kind)
                    raise MissingLimitError(name, kind, source, unit)
                reason = f"the URDF joint has no <limit {kind}=...>"
                if description.format == "mjcf":
                    from ..descriptions.mjcf import missing_limit_reason

                    reason = missing_limit_reason(kind)
                raise MissingLimitError(name, kind, reason)
            table[name] = _positive_limit(name, kind, value)

    robot = Robot(
        spec=spec,
        model=model,
        data=model.createData(),
        platform=platform,
        arms=tuple(arms),
        joint_velocity_limits=velocity,
        joint_effort_limits=effort,
        wheel_platform=None if isinstance(platform, LockedPlatform) else platform,
        torso_joint_names=spec.torso,
        torso_v_indices=torso_v,
        description=description,
        warnings=tuple(
            flaw.warning for flaw in description.flaws if getattr(flaw, "link", None) not in spec.accepted_repairs
        ),
    )
    _check_inertia(robot, description)
    for text in robot.warnings:
        notice(text)
    _log.info(
        "loaded %s from %s: %s platform, %d arm(s), nx = %d", spec.name, spec.urdf, spec.platform, len(arms), robot.nx
    )
    return robot


_ROBOTS_IN_PROCESS: dict[str, Robot] = {}


def robot_in_process(name: str) -> Robot:
    """The robot ``name`` (a built-in name or a spec path), loaded once per process: a worker
    process of a map keeps the last one asked for, so its tasks do not load it again."""
    if name not in _ROBOTS_IN_PROCESS:
        _ROBOTS_IN_PROCESS.clear()
        _ROBOTS_IN_PROCESS[name] = load_robot(name)
    return _ROBOTS_IN_PROCESS[name]


def description_of(robot: Robot) -> RobotDescription:
    """The robot's description: the one it was loaded with, else its spec's file read again.

    Raises:
        DescriptionError: the file cannot be read (as in :func:`load_robot`).
    """
    if robot.description is not None:
        return robot.description
    return read_description(robot.spec.urdf, **robot.spec.read_options)


def _check_inertia(robot: Robot, description: RobotDescription) -> None:
    """Every torso and arm joint must move some inertia, or P = S^T M S is singular.

    The test is the joint's diagonal entry of M at the home configuration: the mass (prismatic)
    or the moment of inertia about the axis (revolute) of everything the joint carries.

    Raises:
        UrdfError: naming the joint and the links it moves that have no mass or inertia (the
            error of the description's format: a :class:`~mobmanip.errors.DescriptionError`).
    """
    M = pin.crba(robot.model, robot.data, robot.neutral())
    for name, v in zip(robot.torso_joint_names, robot.torso_v_indices):
        _require_inertia(robot, description, name, M[v, v])
    for arm in robot.arms:
        for name, v in zip(arm.joint_names, arm.v_indices):
            _require_inertia(robot, description, name, M[v, v])


def _require_inertia(robot: Robot, description: RobotDescription, joint: str, diagonal: float) -> None:
    # Below ~1e-12 (kg or kg m^2) the reduced inertia is numerically singular in double precision
    # next to real links of 1e-3 .. 1e2; real robots' smallest links are far above it.
    if diagonal > 1e-12:
        return
    links = description.subtree_links(joint)
    empty = [link for link in links if not description.link_has_inertia(link)]
    what = f"links with no mass or inertia: {', '.join(empty)}" if empty else "its links' mass lies on the joint axis"
    raise description.error(
        f"joint {joint!r} moves link {links[0]!r} and what it carries, which have no mass or inertia "
        f"about the joint axis ({what}); give link {links[0]!r} an <inertial> with mass",
    )
