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
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from .errors import (
    ConfigurationError,
    FrameNotFoundError,
    JointNotFoundError,
    LimitError,
    MissingLimitError,
    SpecError,
    UrdfError,
    WheelError,
    _closest_first,
)
from .platforms import DifferentialDrive, LockedPlatform, Omnidirectional, Platform
from .spec import OMNI_COORDINATES, RobotSpec, find_spec
from .urdf import (
    MOVING_JOINT_TYPES,
    check_supported,
    joint_limits,
    link_has_inertia,
    mimic_joints,
    read_urdf,
    subtree_links,
    wheel_radius,
)

#: Units of the omnidirectional base's reduced velocities and efforts, for messages.
_OMNI_UNITS = {
    "velocity": {"base_x": "m/s", "base_y": "m/s", "base_yaw": "rad/s"},
    "effort": {"base_x": "N", "base_y": "N", "base_yaw": "N m"},
}


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
    S: np.ndarray = field(init=False, repr=False)
    B: np.ndarray = field(init=False, repr=False)
    Q: np.ndarray = field(init=False, repr=False)
    velocity_limits: np.ndarray = field(init=False, repr=False)
    effort_limits: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        nv, nx = self.model.nv, self.nx
        S = np.zeros((nv, nx))
        B = np.zeros((nv, nx))
        n_eta = self.platform.n_reduced
        rows, block = self.platform.tangent_block()
        if n_eta:
            S[np.ix_(rows, range(n_eta))] = block
            rows_b, block_b = self.platform.actuation_block()
            B[np.ix_(rows_b, range(n_eta))] = block_b
        for k, v in enumerate(self.torso_v_indices + self.arm_v_indices):
            S[v, n_eta + k] = 1.0
            B[v, n_eta + k] = 1.0
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
            array = np.array(values, dtype=float)
            array.setflags(write=False)
            object.__setattr__(self, attr, array)

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
        """The same robot with both drive wheels' velocity (rad/s) or effort (N m) limit set."""
        wheels = self.wheel_platform.reduced_names if isinstance(self.wheel_platform, DifferentialDrive) else ()
        if not wheels:
            raise WheelError(f"robot {self.name!r} has no drive wheels to set a wheel limit on")
        return self.with_limits(
            velocity=None if velocity is None else dict.fromkeys(wheels, velocity),
            effort=None if effort is None else dict.fromkeys(wheels, effort),
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
        """The spec's hold posture (see :attr:`mobmanip.spec.RobotSpec.hold`), platform at the
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
        return {"platform": [float(q[0]), float(q[1]), math.atan2(q[3], q[2])], "joints": joints}

    def check_configuration(self, q) -> np.ndarray:
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
        return q

    def frame_id(self, name: str) -> int:
        """Pinocchio index of a frame by name.

        Raises:
            FrameNotFoundError: unknown frame (the message lists the closest existing ones).
        """
        if not self.model.existFrame(name):
            raise FrameNotFoundError(name, [f.name for f in self.model.frames], where=f"robot {self.name}")
        return self.model.getFrameId(name)


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
    return value


def _check_spec_against_urdf(spec: RobotSpec, urdf) -> None:
    """The URDF must be a supported tree, and every joint and frame the spec names must exist
    in it with a usable type."""
    check_supported(urdf, spec.urdf)
    joints, links = urdf.joint_map, urdf.link_map
    named_joints = list(spec.active_joint_names)
    missing_joints = [j for j in named_joints if j not in joints]
    missing_frames = [a.end_effector for a in spec.arms if a.end_effector not in links and a.end_effector not in joints]
    if missing_joints or missing_frames:
        parts = []
        for name in missing_joints:
            parts.append(f"joint {name!r} (closest: {', '.join(_closest_first(name, joints, 3))})")
        for name in missing_frames:
            parts.append(f"frame {name!r} (closest: {', '.join(_closest_first(name, links, 3))})")
        raise SpecError(f"spec {spec.name!r} names what URDF {spec.urdf.name} lacks: {'; '.join(parts)}")
    for name in named_joints:
        if joints[name].type not in MOVING_JOINT_TYPES:
            raise SpecError(f"joint {name!r} is {joints[name].type!r}; wheels, torso and arm joints must move")
    if spec.wheels is not None:
        for name in (spec.wheels.right, spec.wheels.left):
            if joints[name].type == "prismatic":
                raise WheelError(f"wheel joint {name!r} is prismatic; a wheel must be revolute or continuous")
    mimics = mimic_joints(urdf)
    for name in named_joints:
        if name in mimics:
            raise UrdfError(
                str(spec.urdf), f"joint {name!r} mimics {mimics[name]!r}; mimic joints cannot be actuated here"
            )
    active = set(named_joints)
    for table, kind in ((spec.velocity_limits, "velocity"), (spec.effort_limits, "effort")):
        for name in table:
            if name not in active and not (spec.platform == "omnidirectional" and name in OMNI_COORDINATES):
                valid = sorted(active) + (list(OMNI_COORDINATES) if spec.platform == "omnidirectional" else [])
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


def _build_model(spec: RobotSpec) -> pin.Model:
    try:
        model = pin.buildModelFromUrdf(str(spec.urdf), pin.JointModelPlanar())
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError on URDFs it cannot build
        raise UrdfError(str(spec.urdf), f"Pinocchio cannot build a model: {exc}") from exc
    locked, q_ref = locked_joints(model, spec.reference, keep=set(spec.active_joint_names))
    unknown_ref = sorted(set(spec.reference) - {model.names[j] for j in range(2, model.njoints)})
    if unknown_ref:
        raise JointNotFoundError(unknown_ref[0], list(model.names[2:]), where=f"[reference] of {spec.name}")
    if locked:
        model = pin.buildReducedModel(model, locked, q_ref)
    return model


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


def _differential_drive(spec: RobotSpec, urdf, model: pin.Model) -> DifferentialDrive:
    """Wheel radius, half-track, axis signs and axle centre from the URDF geometry."""
    data = model.createData()
    q0 = pin.neutral(model)
    pin.computeJointJacobians(model, data, q0)
    centres, signs, v_indices, radii = [], [], [], []
    for side, name in (("right", spec.wheels.right), ("left", spec.wheels.left)):
        joint_id = model.getJointId(name)
        v = model.joints[joint_id].idx_v
        J = pin.getJointJacobian(model, data, joint_id, pin.LOCAL_WORLD_ALIGNED)
        axis = J[3:, v]
        if abs(axis[1]) < 0.99:
            raise WheelError(
                f"{side} wheel {name!r} turns about {np.round(axis, 3).tolist()} in the platform frame; "
                "a drive wheel must turn about the platform's lateral (y) axis"
            )
        signs.append(1.0 if axis[1] > 0 else -1.0)  # rolling forward = positive rotation about +y
        centres.append(data.oMi[joint_id].translation.copy())
        v_indices.append(v)
        radii.append(spec.wheels.radius if spec.wheels.radius is not None else wheel_radius(urdf, name))
    if radii[0] is None or radii[1] is None:
        missing = spec.wheels.right if radii[0] is None else spec.wheels.left
        raise WheelError(
            f"wheel {missing!r} has no cylinder about its axis or sphere to read a radius from; "
            "set [wheels] radius in the spec"
        )
    if spec.wheels.radius is None and abs(radii[0] - radii[1]) > 1e-9:
        raise WheelError(f"wheel radii differ ({radii[0]} and {radii[1]} m); set [wheels] radius in the spec")
    right, left = centres
    if not right[1] < left[1]:
        raise WheelError(
            f"right wheel {spec.wheels.right!r} (y = {right[1]:.3f} m) is not to the right of "
            f"left wheel {spec.wheels.left!r} (y = {left[1]:.3f} m); swap them in the spec"
        )
    half_track = spec.wheels.half_track if spec.wheels.half_track is not None else (left[1] - right[1]) / 2
    if abs(right[0] - left[0]) > 1e-6:
        raise WheelError(f"wheels {spec.wheels.right!r} and {spec.wheels.left!r} are not on one axle (x differs)")
    center = (right + left) / 2
    return DifferentialDrive(
        radius=float(radii[0]),
        half_track=float(half_track),
        wheel_v=(v_indices[0], v_indices[1]),
        signs=(signs[0], signs[1]),
        axle_center=(float(center[0]), float(center[1])),
        wheel_names=(spec.wheels.right, spec.wheels.left),
    )


def load_robot(spec_or_name: RobotSpec | str | Path) -> Robot:
    """Load a robot from a spec, a built-in name (``"planar_dual_arm"``) or a spec path.

    Raises:
        MobmanipError: any subclass, naming what is wrong with the spec or URDF.
    """
    spec = spec_or_name if isinstance(spec_or_name, RobotSpec) else find_spec(spec_or_name)
    urdf = read_urdf(spec.urdf)
    _check_spec_against_urdf(spec, urdf)
    model = _build_model(spec)
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
        arms.append(Arm(arm.name, tuple(arm.joints), v_indices, arm.end_effector, model.getFrameId(arm.end_effector)))

    if spec.platform == "differential_drive":
        platform = _differential_drive(spec, urdf, model)
    elif spec.platform == "omnidirectional":
        platform = Omnidirectional()
    else:
        platform = LockedPlatform()

    velocity, effort = {}, {}
    for name in platform.reduced_names + spec.torso + spec.arm_joint_names:
        omni = spec.platform == "omnidirectional" and name in platform.reduced_names
        vel, eff = (None, None) if omni else joint_limits(urdf, name)
        for table, kind, value in ((velocity, "velocity", vel), (effort, "effort", eff)):
            value = (spec.velocity_limits if kind == "velocity" else spec.effort_limits).get(name, value)
            if value is None:
                if omni:
                    source = "an omnidirectional base takes its limits from the spec only"
                    raise MissingLimitError(name, kind, source, _OMNI_UNITS[kind][name])
                raise MissingLimitError(name, kind, f"the URDF joint has no <limit {kind}=...>")
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
    )
    _check_inertia(robot, urdf)
    return robot


def _check_inertia(robot: Robot, urdf) -> None:
    """Every torso and arm joint must move some inertia, or P = S^T M S is singular.

    The test is the joint's diagonal entry of M at the home configuration: the mass (prismatic)
    or the moment of inertia about the axis (revolute) of everything the joint carries.

    Raises:
        UrdfError: naming the joint and the links it moves that have no mass or inertia.
    """
    M = pin.crba(robot.model, robot.data, robot.neutral())
    for name, v in zip(robot.torso_joint_names, robot.torso_v_indices):
        _require_inertia(robot, urdf, name, M[v, v])
    for arm in robot.arms:
        for name, v in zip(arm.joint_names, arm.v_indices):
            _require_inertia(robot, urdf, name, M[v, v])


def _require_inertia(robot: Robot, urdf, joint: str, diagonal: float) -> None:
    # Below ~1e-12 (kg or kg m^2) the reduced inertia is numerically singular in double precision
    # next to real links of 1e-3 .. 1e2; real robots' smallest links are far above it.
    if diagonal > 1e-12:
        return
    links = subtree_links(urdf, joint)
    empty = [link for link in links if not link_has_inertia(urdf, link)]
    what = f"links with no mass or inertia: {', '.join(empty)}" if empty else "its links' mass lies on the joint axis"
    raise UrdfError(
        str(robot.spec.urdf),
        f"joint {joint!r} moves link {links[0]!r} and what it carries, which have no mass or inertia "
        f"about the joint axis ({what}); give link {links[0]!r} an <inertial> with mass",
    )
