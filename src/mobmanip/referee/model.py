"""MuJoCo's model of a loaded robot standing on the floor at rest (the referee's builder).

:func:`build` reads the robot's own file with MuJoCo's parser (a URDF, or the URDF a xacro file
expands to: links and joints only, no meshes; or an MJCF file, :func:`mjcf_spec`), fixes the
joints mobmanip locks at its values, repairs the inertias MuJoCo refuses (each listed in
:attr:`Referee.repairs`), puts a free joint at the root link at mobmanip's planar pose and
spheres at the floor contacts, and holds the object to the hands. The model is edited through
``mujoco.MjSpec``, never through MJCF text (``to_xml`` prints 6 digits); every inertial frame
is the file's (``ipos``/``iquat``), and the object's is set explicitly (left unset, MuJoCo would
put its centre of mass at its ``pos``).

Contacts. A contact named after a wheel joint of the platform is a sphere of the wheel's radius
on the wheel's body, centred on its axle: it rolls, and the floor's tangential force at it (within
friction ``mu`` when the contact is driven) is what the wheel's torque and the platform's
constraint make it. Any other contact (a caster, a point of the spec's ``[support]``) is a
frictionless 2 cm sphere on the root body touching the floor at its point: a normal force only.

Efforts. Reduced efforts ``tau`` act on the joints through mobmanip's actuation matrix B
(``Q = B tau``, joint by joint, matched by name): a wheel's torque in mobmanip's sense (positive
drives forward whatever the file's axis), a skid-steer side's torque shared by its wheels, which
are geared together (one MuJoCo joint equality per wheel, in the ratio of their rates in S).

Omnidirectional bases. Their efforts act on the base's own x, y and yaw, and are the floor's
traction: each wheel of the spec's ``[support] wheels`` pushes the base with the force its motor
gives it. MuJoCo's sphere contacts have round friction, so a wheel is a hub: a small body under
the root at the wheel's contact, on two slide joints along the floor, carrying a sphere with the
wheel's friction. Along the rollers' free direction its joint is free (the contact pushes nothing
that way: the rollers turn); along the other its joint carries the wheel's traction (the motor's
torque over the radius) from the hub to the base, so the floor holds the hub by friction while the
base feels the traction. A wheel without rollers carries both components. The traction of each
wheel is not in ``tau`` (three efforts, more wheels): the replay takes it from the floor's
solution (:meth:`Referee.forward`'s ``traction``).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

import mujoco
import numpy as np
import pinocchio as pin

from ..errors import ArgumentError, NotRepresentable

GRAVITY = 9.81  # m/s^2, along -z
#: How the object is held (see :func:`build`).
GRASPS = ("weld", "point", "level")
#: Mass (kg) and radius of gyration (m) of each grip of a ``"level"`` grasp.
GRIP_MASS, GRIP_RADIUS = 1e-3, 0.01
#: Radius of a passive support's contact sphere (m), and of an omnidirectional wheel's hub.
SUPPORT_RADIUS = 0.02
#: Mass (kg) and radius of gyration (m) of an omnidirectional wheel's hub.
HUB_MASS, HUB_RADIUS = 0.01, 0.01


@dataclass(frozen=True)
class Support:
    """One contact with the floor.

    Attributes:
        name: the driven wheel's joint name, or the passive support's name.
        driven: a driven wheel (friction ``mu``), or a passive support (caster).
        body: the MuJoCo body carrying the contact sphere.
        point: contact point in the root link frame (m), (3,).
        mu: friction coefficient (0: normal force only).
    """

    name: str
    driven: bool
    body: str
    point: np.ndarray
    mu: float


class ContactForce(NamedTuple):
    """The floor's force on the robot at one support.

    Attributes:
        normal: along +z (N), >= 0; 0 when the support has no contact.
        tangential: its world x, y components (N), (2,).
    """

    normal: float
    tangential: np.ndarray


@dataclass
class Rollout:
    """What happened while the torques were held; one row per step (N), one column per support (n).

    Attributes:
        supports: the supports, in column order.
        time: (N,) s. normal: (N, n) normal force (N), 0 when lifted.
        tangential: (N, n, 2) world x, y tangential force (N).
        friction_use: (N, n) ``|tangential| / (mu normal)``; 0 for frictionless supports.
        slip_speed: (N, n) speed along the floor of the sphere's material point at its lowest
            point (m/s): a driven wheel's slip, a caster's sliding.
        penetration: (N, n) depth of the sphere in the floor (m); negative when lifted.
        base_position: (N, 3) root link origin (m). base_rpy: (N, 3) its roll, pitch, yaw (rad).
        acceleration: (N, 6) the object's (without object: first hand's) linear, angular
            acceleration, world axes (m/s^2, rad/s^2).
        in_contact: per support: normal force > 0 at every step and penetration bounded.
        slipped: per driven wheel: slip speed or friction use over its threshold at some step.
        feedback: the largest tracking feedback torque applied (N m or N; 0 without feedback).
    """

    supports: tuple[Support, ...]
    time: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    friction_use: np.ndarray
    slip_speed: np.ndarray
    penetration: np.ndarray
    base_position: np.ndarray
    base_rpy: np.ndarray
    acceleration: np.ndarray
    in_contact: dict[str, bool] = field(default_factory=dict)
    slipped: dict[str, bool] = field(default_factory=dict)
    feedback: float = 0.0

    @property
    def lifted(self) -> list[str]:
        """Supports that lost contact at some step."""
        return [name for name, kept in self.in_contact.items() if not kept]

    @property
    def slipping(self) -> list[str]:
        """Driven wheels that slipped at some step."""
        return [name for name, slid in self.slipped.items() if slid]

    def _deepest(self) -> np.ndarray:
        """Each support's largest depth in the floor per row, (N, n) m."""
        return self.penetration

    def judge(self, slip_speed: float, at_limit: float, max_penetration: float) -> None:
        """Fill :attr:`in_contact` and :attr:`slipped` from the rows (thresholds as
        :meth:`Referee.rollout`'s)."""
        deepest = self._deepest()
        for k, s in enumerate(self.supports):
            self.in_contact[s.name] = bool(self.normal[:, k].min() > 0.0 and deepest[:, k].max() <= max_penetration)
            if s.driven:
                self.slipped[s.name] = bool(
                    self.slip_speed[:, k].max() > slip_speed or self.friction_use[:, k].max() >= at_limit
                )


@dataclass
class MotionReplay(Rollout):
    """A whole timed motion replayed in MuJoCo (:meth:`Referee.follow`): one row per sample of the
    plan (N), one column per support (n).

    Row i is taken at the MuJoCo step nearest the plan's sample i (:attr:`Rollout.time`, from the
    plan's first time stamp). The fields that judge the floor hold the extremes over every step
    from the previous row's (excluded) to this one's (included), none skipped: ``normal`` the
    least normal force, ``slip_speed`` and ``friction_use`` the largest, ``penetration`` the least
    depth (the most risen; negative when lifted) and :attr:`deepest` the largest. The others
    (``tangential``, ``base_position``, ``base_rpy``, ``acceleration``, the tracking errors) are
    the state at the row's step.

    Attributes:
        planned_base: the plan's base pose at each row's time: x, y (m), yaw (rad), (N, 3).
        base_error: horizontal distance of MuJoCo's root link origin from the plan's, (N,) m.
        yaw_error: MuJoCo's base yaw minus the plan's, in [-pi, pi), (N,) rad.
        joints: the tracked joints (every actuated one: the wheels and the arms' joints), (j,).
        joint_error: MuJoCo's position minus the plan's per tracked joint, (N, j) rad or m.
        feedback_effort: the largest magnitude of the feedback on each tracked joint over the
            row's steps, (N, j) N m or N (:attr:`Rollout.feedback`: the largest over the replay).
        deepest: each support's largest depth in the floor over the row's steps, (N, n) m.
    """

    planned_base: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    base_error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    yaw_error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    joints: tuple[str, ...] = ()
    joint_error: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    feedback_effort: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    deepest: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def _deepest(self) -> np.ndarray:
        return self.deepest

    @property
    def least_normal(self) -> dict[str, float]:
        """Each support's least normal force over the whole replay (N)."""
        return {s.name: float(self.normal[:, k].min()) for k, s in enumerate(self.supports)}

    @property
    def largest_slide(self) -> dict[str, float]:
        """Each driven wheel's largest slide speed at its contact point over the whole replay (m/s)."""
        return {s.name: float(self.slip_speed[:, k].max()) for k, s in enumerate(self.supports) if s.driven}


def _floats(text: str | None, default: str) -> np.ndarray:
    return np.array([float(v) for v in (text or default).split()])


def _lock(joint: ET.Element, value: float) -> None:
    """Make a moving URDF joint ``fixed`` at ``value`` (rad or m), folded into its origin."""
    if value != 0.0:
        origin = joint.find("origin")
        origin = ET.SubElement(joint, "origin") if origin is None else origin
        p, R = _floats(origin.get("xyz"), "0 0 0"), pin.rpy.rpyToMatrix(_floats(origin.get("rpy"), "0 0 0"))
        axis_element = joint.find("axis")
        axis = _floats(None if axis_element is None else axis_element.get("xyz"), "1 0 0")
        axis /= np.linalg.norm(axis)
        if joint.get("type") == "prismatic":
            p = p + R @ axis * value
        elif joint.get("type") in ("revolute", "continuous"):
            R = R @ pin.exp3(axis * value)
        else:
            raise NotImplementedError(f"cannot lock {joint.get('type')} joint {joint.get('name')!r} at {value}")
        origin.set("xyz", " ".join(repr(float(c)) for c in p))
        origin.set("rpy", " ".join(repr(float(c)) for c in pin.rpy.matrixToRpy(R)))
    joint.set("type", "fixed")


def _repair_inertia(link: ET.Element) -> tuple[np.ndarray, np.ndarray] | None:
    """Replace an inertia MuJoCo refuses by its diagonal (all three at their mean if that breaks
    the triangle inequality, as MuJoCo's ``balanceinertia``); ``(old, new)`` (3, 3) kg m^2."""
    element = link.find("inertial/inertia")
    if element is None:
        return None
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    xx, xy, xz, yy, yz, zz = (float(element.get(k, 0.0)) for k in keys)
    old = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    e = np.linalg.eigvalsh(old)
    if not (any((xy, xz, yz)) and e[0] <= 0.0) and e[0] + e[1] >= e[2] * (1 - 1e-9):
        return None
    diagonal = np.diag(old).copy()
    if 2.0 * diagonal.max() > diagonal.sum():
        diagonal[:] = diagonal.mean()
    for key, value in zip(keys, (diagonal[0], 0.0, 0.0, diagonal[1], 0.0, diagonal[2])):
        element.set(key, repr(float(value)))
    return old, np.diag(diagonal)


def check_representable(robot) -> None:
    """Refuse, before any work, a robot whose MuJoCo model :func:`build` cannot make (see the
    module's docstring): a file that is not URDF, xacro or MJCF.

    Raises:
        mobmanip.errors.NotRepresentable: naming what and why, in one line.
    """
    _actuation(robot)
    _file_kind(robot)


def _file_kind(robot) -> str:
    """``"urdf"`` (a URDF or a xacro file) or ``"mjcf"`` (MuJoCo's own, read by its parser)."""
    path = robot.spec.urdf
    name = str(path).lower()
    if name.endswith((".urdf", ".xacro")):
        return "urdf"
    if name.endswith((".xml", ".mjcf")):
        with open(path, "rb") as handle:
            head = handle.read(4096)
        return "urdf" if re.search(rb"<robot[\s>]", head) and not re.search(rb"<mujoco[\s>]", head) else "mjcf"
    raise NotRepresentable(
        f"the referee builds MuJoCo's model from a URDF, xacro or MJCF file; {robot.name}'s is {path.name}"
    )


def _check_format(robot) -> None:
    if _file_kind(robot) != "urdf":
        raise NotRepresentable(f"{robot.name}'s file is MJCF, not URDF: MuJoCo reads it itself (mjcf_spec)")


#: xacro's ``$(optenv NAME DEFAULT...)``, the default captured.
_OPTENV = re.compile(r"\$\(optenv\s+\S+\s+([^)]*)\)")


def robot_file_text(robot) -> str:
    """The URDF text of the robot's file: the file itself, or what its xacro file expands to.

    Raises:
        mobmanip.errors.NotRepresentable: a file of another format (MJCF: MuJoCo's own, but the referee strips and
            edits a URDF tree).
    """
    from ..descriptions.xacro import expand_xacro

    _check_format(robot)
    path = robot.spec.urdf
    if str(path).lower().endswith(".xacro"):
        return expand_xacro(path, robot.spec.xacro_args, robot.spec.package_paths)[0]
    # xacro's $(optenv NAME DEFAULT) leftovers read as their defaults, as mobmanip's reader does
    return _OPTENV.sub(lambda match: match.group(1).strip(), path.read_text())


def stripped_urdf(robot) -> tuple[str, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The robot's URDF for MuJoCo and its inertia repairs (link -> (old, new) (3, 3) kg m^2):
    links and joints only, no visuals or collisions, mobmanip's locked joints fixed."""
    root = ET.fromstring(robot_file_text(robot))
    for child in list(root):
        if child.tag not in ("link", "joint"):
            root.remove(child)
    repairs = {}
    for link in root.findall("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
        if (repair := _repair_inertia(link)) is not None:
            repairs[str(link.get("name"))] = repair
    keep = set(robot.model.names)
    for joint in root.findall("joint"):
        if joint.get("type") != "fixed" and joint.get("name") not in keep:
            _lock(joint, float(robot.spec.reference.get(joint.get("name"), 0.0)))
    options = {"fusestatic": "false", "inertiafromgeom": "false", "discardvisual": "false"}
    ET.SubElement(ET.SubElement(root, "mujoco"), "compiler", options)
    return ET.tostring(root, encoding="unicode"), repairs


def mjcf_spec(robot) -> tuple[mujoco.MjSpec, dict[str, float]]:
    """The robot's MJCF file as MuJoCo's own parser reads it, for the referee: its geoms kept for
    the inertias MuJoCo derives from them but touching nothing; actuators, sensors, tendons,
    equalities, keyframes and contact pairs and exclusions dropped (mobmanip models none of
    them); the root body's joints removed (:func:`build` puts a free joint there); and the joints
    mobmanip's model does not have, returned with the values they are locked at (the spec's
    ``[reference]``, else 0), which :func:`build` holds with joint equalities.

    Raises:
        ValueError: MuJoCo cannot parse the file.
    """
    spec = mujoco.MjSpec.from_file(str(robot.spec.urdf))
    for geom in spec.geoms:
        geom.contype = geom.conaffinity = 0
    for group in (spec.actuators, spec.sensors, spec.tendons, spec.equalities, spec.keys, spec.pairs, spec.excludes):
        for element in list(group):
            spec.delete(element)
    root = spec.worldbody.first_body()
    for joint in list(root.joints):
        spec.delete(joint)
    keep = set(robot.model.names)
    locks: dict[str, float] = {}
    for joint in list(spec.joints):
        if joint.name in keep or joint.type not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            continue
        value = float(robot.spec.reference.get(joint.name, 0.0))
        if _fold(spec, joint, value - float(joint.ref)):
            continue
        if not joint.name:
            joint.name = f"locked_{len(locks)}"
        locks[joint.name] = value
    return spec, locks


def _fold(spec: mujoco.MjSpec, joint, turn: float) -> bool:
    """Lock an MJCF joint by folding ``turn`` (rad or m, from its ``ref``) into its body's pose and
    removing it: rigid, where an equality would be a stiff spring. False (nothing done) for a body
    with other joints or an orientation not given as a quaternion."""
    body = joint.parent
    if len(body.joints) != 1 or (turn != 0.0 and body.alt.type != mujoco.mjtOrientation.mjORIENTATION_QUAT):
        return False
    if turn != 0.0:
        quat = np.asarray(body.quat, dtype=float)
        R = pin.Quaternion(quat[0], quat[1], quat[2], quat[3]).normalized().matrix()
        axis = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
        anchor = np.asarray(joint.pos, dtype=float)
        if joint.type == mujoco.mjtJoint.mjJNT_SLIDE:
            body.pos = np.asarray(body.pos, dtype=float) + R @ axis * turn
        else:  # a turn about the axis through the anchor
            Rj = pin.exp3(axis * turn)
            body.pos = np.asarray(body.pos, dtype=float) + R @ (anchor - Rj @ anchor)
            turned = pin.Quaternion(R @ Rj)
            body.quat = [turned.w, turned.x, turned.y, turned.z]
    spec.delete(joint)
    return True


def urdf_casters(robot) -> dict[str, np.ndarray]:
    """Passive supports of the URDF: every link named ``caster*`` with a sphere collision, by link
    name without ``_link``: the sphere's lowest point in the root link frame (m), (3,)."""
    model, data = robot.model, robot.model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))  # casters are locked: any q
    out = {}
    for link in ET.fromstring(robot_file_text(robot)).findall("link"):
        name, sphere = str(link.get("name")), link.find("collision/geometry/sphere")
        if "caster" in name and sphere is not None and model.existFrame(name):
            origin = link.find("collision/origin")
            centre = data.oMf[model.getFrameId(name)].act(
                _floats(None if origin is None else origin.get("xyz"), "0 0 0")
            )
            out[name.removesuffix("_link")] = centre - [0.0, 0.0, float(sphere.get("radius", "0"))]
    return out


def contacts_of_floor(info: Mapping) -> list[tuple[str, np.ndarray, bool, tuple[float, float] | None]]:
    """The floor constraint's contacts (``set.model["floor"]``: its ``pose`` and its
    ``contacts``' name, world point, driven flag and rollers' free direction) as ``(name, point
    in the root frame (3,) m, driven, free direction in the root frame (2,) or None)``, the form
    :func:`build` takes: whatever contacts the floor models for a platform kind, the referee puts
    a sphere at each."""
    x, y, yaw = info["pose"]
    c, s = math.cos(yaw), math.sin(yaw)
    out = []
    for contact in info["contacts"]:
        dx, dy, z = np.asarray(contact["point"], dtype=float) - [x, y, 0.0]
        free = contact.get("free")
        out.append((
            str(contact["name"]), np.array([c * dx + s * dy, -s * dx + c * dy, z]), bool(contact["driven"]),
            None if free is None else (float(free[0]), float(free[1])),
        ))  # fmt: skip
    return out


def build(
    robot,
    q: np.ndarray,
    *,
    support_points: Mapping[str, np.ndarray] | None = None,
    contacts: Sequence[tuple] | None = None,
    object=None,
    grasp: str | None = None,
    mu: float | Mapping[str, float] = 0.5,
    timestep: float = 1e-4,
    impratio: float = 100.0,
    penetration: float = 1e-12,
    regularisation: float = 1e-2,
    equal_supports: bool = True,
    stiffness: Mapping[str, float] | None = None,
    gravity: np.ndarray | None = None,
) -> Referee:
    """A MuJoCo model of ``robot`` at configuration ``q`` standing on the floor, at rest.

    Args:
        robot: a loaded mobmanip robot on wheels.
        q: mobmanip configuration, (nq,).
        support_points: passive supports beside the platform's wheels (every wheel of
            ``robot.platform.wheels()`` then a driven contact): name -> point on the floor in the
            root link frame (m), (3,); e.g. :func:`urdf_casters`. Not with ``contacts``.
        contacts: every contact instead, as ``(name, point in the root link frame (3,) m,
            driven)`` or ``(name, point, driven, rollers' free direction (2,) or None)``; e.g.
            :func:`contacts_of_floor` of the floor constraint's report. A name that is a wheel
            joint of the platform is a rolling wheel (its point must be below its axle by its
            radius); any other driven contact an omnidirectional base's wheel (a hub: see the
            module's docstring); any other a passive point.
        object: the held object (an ``Analysis.held_object``: mass kg, inertia (3, 3) kg m^2 in
            world axes, center (3,) m, offsets (k, 3) m from the centre to the hands), or ``None``.
            Its inertia must be positive definite (MuJoCo refuses a point mass; see
            :func:`mobmanip.referee.check.object_for_referee`).
        grasp: ``"weld"`` (hands fixed to the object), ``"point"`` (each hand pinned to the
            object's centre) or ``"level"``: the object of a task without rotations held level
            (``Floor(level=True)``): it moves along the world's axes, tilts only as the hands
            tilt it (each hand welded to a grip that turns about the vertical on the object, so
            the hands carry its weight and its roll and pitch moments and turn freely about the
            vertical), and never turns about the vertical (mobmanip balances no turning moment of
            the object in such a task: MuJoCo's world takes it). Default ``"point"`` for the
            spec's planar and translational tasks, else weld.
        mu: friction coefficient of the driven contacts, or one per contact name (missing: 0.5
            for driven contacts, 0 for passive ones: normal force only).
        timestep: integration step (s); contacts and grasps have time constant 2 timesteps.
        impratio: ratio of frictional to normal stiffness (elliptic cones).
        penetration: initial depth of every contact sphere in the floor (m). MuJoCo drops a
            contact at distance 0 exactly; this one pushes with ~ penetration / (2 timestep)^2
            (2.5e-5 m/s^2).
        regularisation: factor on each constraint's softness R = (1 - d) / d * A_approx, d = 0.9999
            (MuJoCo's cap), through the bodies' ``invweight0`` (A_approx). At 1 the paper robot's
            2 kg object sags at 0.015 m/s^2 at rest, at 1e-2 at 1.3e-4 m/s^2.
        equal_supports: make every support equally stiff. A robot on more than three contacts
            shares its weight by their compliance; MuJoCo's soft contacts are stiffer, in
            proportion, on bodies that are easier to move (R scales with each body's invweight0),
            an artefact of its regularisation, not of a floor: the wheel bodies' weights are set
            to the root's, so that each contact's force is the same function of its depth (the
            model mobmanip's compliant floor assumes). Off: MuJoCo's own sharing.
        stiffness: relative stiffness per contact name (missing: 1), with ``equal_supports``:
            each contact's softness R is divided by it (through its pair's solimp d, (1 - d) / d
            scaled, the stiffest at MuJoCo's cap d = 0.9999). Holding still, MuJoCo's contact
            forces minimise sum_c R_c f_c^2 over the balancing ones, i.e. f_c = k_c (a + b x_c +
            c y_c): springs of stiffness k_c under a rigid platform.
        gravity: gravity in the floor's axes (m/s^2), (3,): a ramp is the level floor with gravity
            leaning; default straight down.

    Raises:
        ValueError: contacts not on one floor, a wheel contact not below its axle, a hand that is
            not a link of the file, an object whose grasp points are not at the hands.
        mobmanip.errors.NotRepresentable: a robot file MuJoCo's model is not built from (see the module's
            docstring).
    """
    actuation, gears = _actuation(robot)  # refuses what MuJoCo cannot drive, before any work
    spec, locks, repairs = _robot_spec(robot)
    base = spec.worldbody.first_body()
    _set_options(spec, timestep, impratio, gravity)
    soft = {"solref": [2.0 * timestep, 1.0], "solimp": [0.9999, 0.9999, 0.001, 0.5, 2.0]}
    q = np.asarray(q, dtype=float)
    contacts, radius, lift = _floor_contacts(robot, q, support_points, contacts)
    supports, drives = _add_supports(spec, base, contacts, radius, lift, mu, penetration)
    _add_floor_pairs(spec, supports, stiffness, soft)
    _add_joint_equalities(spec, locks, gears, soft)
    pose, joints = (q[0], q[1], math.atan2(q[3], q[2])), joint_positions(robot, q)
    joints.update(locks)
    model = spec.compile()
    qpos0, hands = _built_qpos(model, pose, lift, joints), [arm.end_effector for arm in robot.arms]
    grips = 0  # a level grasp's grips
    if object is not None:
        grasp = grasp or ("point" if robot.spec.default_task in ("planar", "translational") else "weld")
        centre = _hold_object(spec, model, qpos0, object, grasp, hands, lift, soft)
        model = spec.compile()
        qpos0 = _built_qpos(model, pose, lift, joints)
        if grasp != "level":  # (its slides start at 0: the body's own position)
            qpos0[model.joint("object_free").qposadr[0] :][:7] = [*centre, 1.0, 0.0, 0.0, 0.0]
        grips = len(hands) if grasp == "level" else 0
    _soften(model, base.name, supports, grips, regularisation, equal_supports)
    referee = Referee(robot, model, qpos0, tuple(supports), hands, object is not None, repairs, lift, actuation)
    referee.drives = tuple((name, int(model.joint(joint).dofadr[0]), axis) for name, joint, axis in drives)
    return referee


#: A floor contact as :func:`build` takes it: name, point in the root link frame (3,) m, driven,
#: rollers' free direction in the root frame (2,) or ``None``.
_Contact = tuple[str, np.ndarray, bool, tuple[float, float] | None]


def _robot_spec(robot) -> tuple[mujoco.MjSpec, dict[str, float], dict[str, tuple[np.ndarray, np.ndarray]]]:
    """MuJoCo's spec of the robot's own file (:func:`mjcf_spec` for MJCF, :func:`stripped_urdf`
    for a URDF or xacro file), its root body on a free joint ``floating_base`` and every hinge
    and slide moving freely: no damping, stiffness, friction loss or limits (an MJCF joint mobmanip
    keeps moving keeps its armature, which mobmanip's mass matrix has too).

    Returns:
        ``(spec, locks, repairs)``: the spec; the MJCF joints mobmanip locks, by name, with their
        values (rad or m; none for a URDF, whose locked joints are fixed); the inertia repairs,
        link -> (old, new) (3, 3) kg m^2.

    Raises:
        mobmanip.errors.NotRepresentable: a file MuJoCo's model is not built from.
    """
    mjcf = _file_kind(robot) == "mjcf"
    if mjcf:  # MuJoCo's own format: its parser reads the file itself
        spec, locks = mjcf_spec(robot)
        repairs: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    else:
        text, repairs = stripped_urdf(robot)
        spec, locks = mujoco.MjSpec.from_string(text), {}
    spec.worldbody.first_body().add_freejoint(name="floating_base")
    for joint in spec.joints:
        if joint.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            # an MJCF joint's armature is in mobmanip's mass matrix too (Pinocchio's MJCF builder reads it)
            armature = float(joint.armature) if mjcf and joint.name not in locks else 0.0
            joint.damping, joint.stiffness, joint.frictionloss = np.zeros(3), np.zeros(3), 0.0
            joint.armature = armature
            joint.limited = joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
    return spec, locks, repairs


def _set_options(spec: mujoco.MjSpec, timestep: float, impratio: float, gravity: np.ndarray | None) -> None:
    """The simulation's options: ``timestep`` (s), ``impratio``, ``gravity`` (3,) m/s^2 (default
    straight down), elliptic friction cones and the Newton solver run to a tight tolerance."""
    option = spec.option
    down = [0.0, 0.0, -GRAVITY] if gravity is None else [float(v) for v in gravity]
    option.timestep, option.impratio, option.gravity = timestep, impratio, down
    option.cone, option.solver = mujoco.mjtCone.mjCONE_ELLIPTIC, mujoco.mjtSolver.mjSOL_NEWTON
    option.iterations, option.tolerance, option.ls_iterations = 1000, 1e-12, 100


def _floor_contacts(
    robot, q: np.ndarray, support_points: Mapping[str, np.ndarray] | None, contacts: Sequence[tuple] | None
) -> tuple[list[_Contact], dict[str, float], float]:
    """The contacts :func:`build` puts spheres at, checked: the ones given, else a driven one
    below each wheel of the platform and a passive one at each of ``support_points``.

    Args:
        robot: the robot; ``q`` its configuration (nq,) (only its joints matter: the wheels'
            axles are taken with the platform at the origin, as in mobmanip's model).
        support_points, contacts: as :func:`build`'s.

    Returns:
        ``(contacts, radius, lift)``: each contact as ``(name, point (3,), driven, free
        direction or None)``; each platform wheel's radius (m) by joint name; the height of the
        root link's origin above the floor (m).

    Raises:
        ArgumentError: both kinds of contacts given, none at all, a wheel's contact not below its
            axle by its radius, or wheels not on one floor.
    """
    # The wheels' axles at the platform's origin (mobmanip's model) give each wheel's contact.
    home, data = q.copy(), robot.model.createData()
    home[:4] = (0.0, 0.0, 1.0, 0.0)
    pin.forwardKinematics(robot.model, data, home)
    radius = dict(robot.platform.wheels()) if robot.wheel_platform is not None else {}
    axles = {name: data.oMi[robot.model.getJointId(name)].translation.copy() for name in radius}
    if contacts is None:
        contacts = [(name, axles[name] - [0.0, 0.0, radius[name]], True) for name in radius]
        contacts += [(name, point, False) for name, point in (support_points or {}).items()]
    elif support_points:
        raise ArgumentError("give the contacts or the passive support points, not both")
    out = [(str(c[0]), np.asarray(c[1], dtype=float), bool(c[2]), c[3] if len(c) > 3 else None) for c in contacts]
    wheels = [name for name, _, _, _ in out if name in radius]
    for name, point, _, _ in out:
        if name in radius and np.linalg.norm(point - axles[name] + [0.0, 0.0, radius[name]]) > 1e-6:
            raise ArgumentError(f"contact {name!r} at {point} m is not below its wheel's axle by its radius")
    if not out:
        raise ArgumentError(f"{robot.name} has no contacts with the floor")
    # the floor's height in the root frame: the wheels' contacts (else the first contact)
    heights = [-point[2] for name, point, _, _ in out if name in wheels] or [-out[0][1][2]]
    if max(heights) - min(heights) > 1e-6:
        raise ArgumentError(f"wheels {wheels} do not stand on one floor (root heights {heights} m)")
    return out, radius, heights[0]


def _friction(mu: float | Mapping[str, float], name: str, driven: bool) -> float:
    """Contact ``name``'s friction coefficient from :func:`build`'s ``mu``."""
    default = 0.5 if driven else 0.0
    return float(mu.get(name, default) if isinstance(mu, Mapping) else (mu if driven else 0.0))


def _add_supports(
    spec: mujoco.MjSpec,
    base,
    contacts: list[_Contact],
    radius: Mapping[str, float],
    lift: float,
    mu: float | Mapping[str, float],
    penetration: float,
) -> tuple[list[Support], list[tuple[str, str, np.ndarray]]]:
    """The floor (a plane in the world body) and a contact sphere for each contact, touching
    nothing by itself (each touches the floor through its own pair: :func:`_add_floor_pairs`):
    on its wheel's body for a platform wheel; on a hub under the root body ``base`` for an
    omnidirectional base's wheel (:func:`_add_hub`); on ``base`` for a passive support.

    Args:
        spec: the robot's spec, edited.
        contacts: from :func:`_floor_contacts`; ``radius`` its wheel radii and ``lift`` the floor's
            depth below the root link's origin (m).
        mu, penetration: as :func:`build`'s.

    Returns:
        ``(supports, drives)``: the supports, wheels first; each hub's driven slide as ``(contact
        name, slide joint name, axis in the root frame (2,))``.

    Raises:
        ArgumentError: a contact that is not a wheel and not on the floor.
    """
    wheels = [name for name, _, _, _ in contacts if name in radius]
    sphere, free = mujoco.mjtGeom.mjGEOM_SPHERE, {"contype": 0, "conaffinity": 0}
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.1], **free)
    supports, drives = [], []
    for name, point, driven, rollers in sorted(contacts, key=lambda c: c[0] not in wheels):  # wheels first
        if name in wheels:  # the wheel link's frame is its joint's: the sphere at its origin
            body, anchor = (
                spec.joint(name).parent,
                spec.joint(name).pos,
            )  # (an MJCF joint may sit off its body's origin)
            size = [radius[name] + penetration, 0, 0]
            body.add_geom(name=f"contact_{name}", type=sphere, size=size, pos=anchor, **free)
            supports.append(Support(name, driven, body.name, point, _friction(mu, name, driven)))
            continue
        if abs(point[2] + lift) > 1e-6:
            raise ArgumentError(f"support {name!r} at z = {point[2]:.6g} m is not on the floor (z = {-lift:.6g} m)")
        centre = [point[0], point[1], -lift + SUPPORT_RADIUS - penetration]
        if driven:  # an omnidirectional base's wheel: a hub on two slides (see the module's docstring)
            hub, slides = _add_hub(base, name, centre, rollers)
            drives += slides
            supports.append(Support(name, driven, hub.name, point, _friction(mu, name, driven)))
            continue
        base.add_geom(name=f"contact_{name}", type=sphere, size=[SUPPORT_RADIUS, 0, 0], pos=centre, **free)
        supports.append(Support(name, driven, base.name, point, _friction(mu, name, driven)))
    return supports, drives


def _add_hub(
    base, name: str, centre: list[float], rollers: tuple[float, float] | None
) -> tuple[mujoco.MjsBody, list[tuple[str, str, np.ndarray]]]:
    """An omnidirectional base's wheel ``name``: a hub body under the root body ``base`` at
    ``centre`` (root frame, m) on two slides along the floor, carrying the contact sphere.

    Returns:
        ``(hub, drives)``: the hub's body, and the slides that pass the wheel's traction to the
        base (the one across the rollers' free direction ``rollers`` (2,); both without rollers),
        each as ``(name, slide joint name, axis in the root frame (2,))``.
    """
    sphere, free = mujoco.mjtGeom.mjGEOM_SPHERE, {"contype": 0, "conaffinity": 0}
    drives = []
    hub = base.add_body(name=f"hub_{name}", pos=centre, mass=HUB_MASS, explicitinertial=True)
    hub.ipos, hub.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    hub.fullinertia = [HUB_MASS * HUB_RADIUS**2] * 3 + [0.0, 0.0, 0.0]
    along = np.array([1.0, 0.0]) if rollers is None else np.asarray(rollers, dtype=float)
    along = along / np.linalg.norm(along)
    for k, axis in enumerate((along, np.array([-along[1], along[0]]))):
        joint = f"hub_{name}_{k}"
        hub.add_joint(name=joint, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[axis[0], axis[1], 0.0])
        if k == 1 or rollers is None:  # the rollers' free direction carries nothing
            drives.append((name, joint, axis))
    hub.add_geom(name=f"contact_{name}", type=sphere, size=[SUPPORT_RADIUS, 0, 0], **free)
    return hub, drives


def _add_floor_pairs(
    spec: mujoco.MjSpec, supports: list[Support], stiffness: Mapping[str, float] | None, soft: Mapping[str, list]
) -> None:
    """The floor's contact with each support's sphere: with the support's friction (round, none
    for a frictionless one), as soft as ``soft`` says for the stiffest contacts, softer for the
    others in proportion to their relative ``stiffness`` (by contact name, missing: 1)."""
    k = {s.name: float((stiffness or {}).get(s.name, 1.0)) for s in supports}
    stiffest = max(k.values())
    for s in supports:
        friction_5 = [s.mu, s.mu, 0.0, 0.0, 0.0]
        condim = 3 if s.mu > 0 else 1
        pair = dict(soft)
        if k[s.name] != stiffest:  # (1 - d) / d grows as the contact is softer
            ratio = (1.0 - soft["solimp"][0]) / soft["solimp"][0] * stiffest / k[s.name]
            d = 1.0 / (1.0 + ratio)
            pair["solimp"] = [d, d, *soft["solimp"][2:]]
        spec.add_pair(geomname1="floor", geomname2=f"contact_{s.name}", condim=condim, friction=friction_5, **pair)


def _add_joint_equalities(
    spec: mujoco.MjSpec, locks: Mapping[str, float], gears: Sequence[tuple[str, str, float]], soft: Mapping[str, list]
) -> None:
    """Joint equalities, as soft as ``soft`` says: each joint mobmanip locks held at its value
    (``locks``, rad or m), and each wheel one effort drives together with another geared to it
    (``gears``: ``(follower, leader, ratio)``, from :func:`_actuation`)."""
    for name, value in locks.items():  # the joints mobmanip locks, held at their values
        lock = spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=name, **soft)
        lock.data[:5] = [value - float(spec.joint(name).ref), 0.0, 0.0, 0.0, 0.0]  # from its qpos0 (its ref)
    for follower, leader, ratio in gears:  # wheels one effort drives together turn together
        gear = spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=follower, name2=leader, **soft)
        gear.data[:5] = [0.0, ratio, 0.0, 0.0, 0.0]  # follower - its qpos0 = ratio (leader - its qpos0)


def _built_qpos(model, pose: tuple[float, float, float], lift: float, joints: Mapping[str, float]) -> np.ndarray:
    """MuJoCo's configuration (model.nq,) of the built robot: the root link at the planar
    ``pose`` (x, y m; yaw rad) ``lift`` (m) above the floor, the named ``joints`` at their values
    (rad or m), everything else at the model's ``qpos0``."""
    x, y, yaw = pose
    qpos = model.qpos0.copy()
    qpos[model.joint("floating_base").qposadr[0] :][:7] = [x, y, lift, math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]
    for name, value in joints.items():
        qpos[model.joint(name).qposadr[0]] = value
    return qpos


def _hold_object(
    spec: mujoco.MjSpec,
    model,
    qpos0: np.ndarray,
    object,
    grasp: str,
    hands: Sequence[str],
    lift: float,
    soft: Mapping[str, list],
) -> np.ndarray:
    """Add the held object to the spec: a body at its centre with its mass and inertia, free
    (on a free joint; a ``"level"`` grasp's on slides and the roll and pitch hinges), held by each
    hand as the ``grasp`` says (see :func:`build`) through an equality as soft as ``soft``.

    Args:
        spec: the robot's spec, edited; ``model`` compiled from it without the object, and
            ``qpos0`` its built configuration (where the hands are).
        object: as :func:`build`'s; its centre is taken ``lift`` (m) above the floor's origin.
        hands: the end effectors' links, in the object's grasp points' order.

    Returns:
        The object's centre in MuJoCo's world, (3,) m.

    Raises:
        ArgumentError: an unknown grasp, a hand that is not a link of the file, or a grasp point
            of the object not at its hand.
    """
    if grasp not in GRASPS:
        raise ArgumentError(f"grasp must be one of {', '.join(GRASPS)}, got {grasp!r}")
    placed = mujoco.MjData(model)
    placed.qpos[:] = qpos0
    mujoco.mj_kinematics(model, placed)
    centre, inertia = np.asarray(object.center, dtype=float) + [0.0, 0.0, lift], np.asarray(object.inertia)
    body = spec.worldbody.add_body(name="object", pos=centre, mass=float(object.mass), explicitinertial=True)
    body.ipos, body.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]  # the centre of mass at the centre
    body.fullinertia = [*np.diag(inertia), inertia[0, 1], inertia[0, 2], inertia[1, 2]]
    if grasp == "level":  # it moves, tilts as the hands tilt it, never turns about the vertical
        for axis, name in zip(np.eye(3), ("x", "y", "z")):
            body.add_joint(name=f"object_{name}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
        for axis, name in zip(np.eye(3)[:2], ("roll", "pitch")):
            body.add_joint(name=f"object_{name}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    else:
        body.add_freejoint(name="object_free")
    for k, hand in enumerate(hands):
        if spec.body(hand) is None:
            raise ArgumentError(f"end effector {hand!r} is not a link of the URDF")
        p, R = placed.body(hand).xpos.copy(), placed.body(hand).xmat.reshape(3, 3).copy()
        if np.linalg.norm(p - centre - np.asarray(object.offsets[k])) > 1e-6:
            raise ArgumentError(f"grasp point {k} of the object is not at hand {hand!r} (hand - centre {p - centre})")
        _add_grasp_sites(spec, body, k, hand, p, R, centre, grasp)
        kind = mujoco.mjtEq.mjEQ_CONNECT if grasp == "point" else mujoco.mjtEq.mjEQ_WELD
        site = mujoco.mjtObj.mjOBJ_SITE
        spec.add_equality(type=kind, objtype=site, name1=f"grasp_{k}", name2=f"hand_{k}", **soft)
    return centre


def _add_grasp_sites(
    spec: mujoco.MjSpec, body, k: int, hand: str, p: np.ndarray, R: np.ndarray, centre: np.ndarray, grasp: str
) -> None:
    """The sites that grasp ``k`` ties together: ``grasp_k`` on the object ``body`` (or on a
    level grasp's grip) and ``hand_k`` on the ``hand``'s body, for a hand at ``p`` (3,) m with
    orientation ``R`` (3, 3) in the world and the object's centre at ``centre`` (3,) m.

    ``"weld"``: both sites at the hand frame; ``"point"``: both at the object's centre; ``"level"``:
    both at the hand frame, the object's on a grip that turns about the vertical on the object,
    at the hand's origin."""
    if grasp == "weld":  # a site at the hand frame on both
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, R.ravel())
        body.add_site(name=f"grasp_{k}", pos=p - centre, quat=quat)
        spec.body(hand).add_site(name=f"hand_{k}")
    elif grasp == "point":  # a site at the object's centre on both
        body.add_site(name=f"grasp_{k}")
        spec.body(hand).add_site(name=f"hand_{k}", pos=R.T @ (centre - p))
    else:  # welded to a grip that turns about the vertical on the object, at the hand's origin
        grip = body.add_body(name=f"grip_{k}", pos=p - centre, mass=GRIP_MASS, explicitinertial=True)
        grip.ipos, grip.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
        grip.fullinertia = [GRIP_MASS * GRIP_RADIUS**2] * 3 + [0.0, 0.0, 0.0]
        grip.add_joint(name=f"grip_{k}_yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0])
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, R.ravel())
        grip.add_site(name=f"grasp_{k}", quat=quat)
        spec.body(hand).add_site(name=f"hand_{k}")


def _soften(
    model, root: str, supports: Sequence[Support], grips: int, regularisation: float, equal_supports: bool
) -> None:
    """Set the constraints' softness through the bodies' ``invweight0`` (see :func:`build`'s
    ``regularisation`` and ``equal_supports``): a level grasp's ``grips`` as stiff as the
    object's own constraints, every body's scaled by ``regularisation``, and with
    ``equal_supports`` each support's body weighted as the ``root`` body."""
    for k in range(grips):  # as stiff as the object's own constraints
        model.body_invweight0[model.body(f"grip_{k}").id] = model.body_invweight0[model.body("object").id]
    model.body_invweight0[:] *= regularisation
    if equal_supports:
        root_id = model.body(root).id
        for s in supports:
            model.body_invweight0[model.body(s.body).id, 0] = model.body_invweight0[root_id, 0]


def _constraint_jacobian(model, data) -> np.ndarray:
    """The constraints' Jacobian at the current state, dense, (nefc, nv)."""
    if not mujoco.mj_isSparse(model):
        return data.efc_J.reshape(data.nefc, model.nv).copy()
    dense = np.zeros((data.nefc, model.nv))
    mujoco.mju_sparse2dense(dense, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind)
    return dense


class TimedMotion(Protocol):
    """What :meth:`Referee.follow` reads of a plan: a
    :class:`mobmanip.motion.trajectory.Trajectory` (whose layer the referee does not import)."""

    @property
    def t(self) -> np.ndarray:
        """Time stamps (s), (N,)."""

    @property
    def q(self) -> np.ndarray:
        """Configurations, (N, nq)."""

    @property
    def x(self) -> np.ndarray:
        """Reduced velocities, (N, nx)."""


def _hermite(t: np.ndarray, p: np.ndarray, v: np.ndarray, i: int, time: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and rate at ``time`` of the cubic through samples i and i + 1 of positions ``p``
    (N, k) with rates ``v`` (N, k) at time stamps ``t`` (N,)."""
    h = t[i + 1] - t[i]
    u = (time - t[i]) / h
    u2, u3 = u * u, u * u * u
    position = (2 * u3 - 3 * u2 + 1) * p[i] + (u3 - 2 * u2 + u) * h * v[i] + (3 * u2 - 2 * u3) * p[i + 1]
    position += (u3 - u2) * h * v[i + 1]
    rate = (6 * u2 - 6 * u) / h * (p[i] - p[i + 1]) + (3 * u2 - 4 * u + 1) * v[i] + (3 * u2 - 2 * u) * v[i + 1]
    return position, rate


def joint_positions(robot, q: np.ndarray) -> dict[str, float]:
    """mobmanip's joints (all but the platform's root) at configuration ``q`` (nq,) as MuJoCo's
    joint positions: name -> angle (rad) or distance (m); a continuous joint's (cos, sin) as its
    angle in (-pi, pi]."""
    out = {}
    for j in range(2, robot.model.njoints):
        joint = robot.model.joints[j]
        value = math.atan2(q[joint.idx_q + 1], q[joint.idx_q]) if joint.nq == 2 else q[joint.idx_q]
        out[robot.model.names[j]] = float(value)
    return out


def _actuation(robot) -> tuple[list[tuple[str, np.ndarray]], list[tuple[str, str, float]]]:
    """Where the reduced efforts act, joint by joint: ``(joint name, its row of B (nx,))`` for
    every joint B drives (``Q = B tau``: a joint's generalized force is its row times ``tau``),
    and the gears: ``(follower, leader, ratio)`` for each wheel one effort drives together with
    another (a skid-steer side), the follower's rate ``ratio`` times the leader's (from S).
    Efforts on the platform's planar coordinates themselves (an omnidirectional base's) are the
    floor's traction: they act through the wheels' hubs (:meth:`Referee.forward`)."""
    model, B, S = robot.model, np.asarray(robot.B), np.asarray(robot.S)
    rows: list[tuple[str, np.ndarray]] = []
    driven_by: dict[int, list[tuple[str, int]]] = {}
    for j in range(1, model.njoints):
        joint = model.joints[j]
        for v in range(joint.idx_v, joint.idx_v + joint.nv):
            if not np.any(B[v]):
                continue
            if j == 1:  # the planar root joint: the floor's traction, replayed at the wheels' hubs
                continue
            rows.append((model.names[j], B[v].copy()))
            for k in np.flatnonzero(B[v]):
                driven_by.setdefault(int(k), []).append((model.names[j], v))
    gears = []
    for k, joints in driven_by.items():
        (leader, v0), *others = joints
        for name, v in others:
            if S[v0, k] != 0.0:
                gears.append((name, leader, float(S[v, k] / S[v0, k])))
    return rows, gears


class _TrackedPlan(NamedTuple):
    """A plan per tracked joint, for :meth:`Referee.follow` (:meth:`Referee._tracked_plan`).

    Attributes:
        names: the tracked joints (every actuated one), (j,).
        dofs: their MuJoCo dofs, (j,); addresses: their MuJoCo positions' addresses, (j,).
        planned: their positions per sample, unwound, in MuJoCo's sense, (N, j) rad or m.
        rates: their rates per sample, (N, j).
        forces: the plan's efforts as their generalized forces per sample, (N, j) N m or N.
    """

    names: tuple[str, ...]
    dofs: np.ndarray
    addresses: np.ndarray
    planned: np.ndarray
    rates: np.ndarray
    forces: np.ndarray


def _planned_base(robot, qs: np.ndarray, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plan's base at each sample of configurations ``qs`` (N, nq) and reduced velocities
    ``xs`` (N, nx): its pose, x, y (m) and yaw unwound (rad), (N, 3), and its velocity in world
    axes, (N, 3) m/s and rad/s."""
    n = qs.shape[0]
    yaw = np.unwrap(np.arctan2(qs[:, 3], qs[:, 2]))
    base = np.c_[qs[:, :2], yaw]
    base_rate = np.zeros((n, 3))
    for i in range(n):
        v = robot.null_space(qs[i])[:3] @ xs[i]
        c, s = math.cos(yaw[i]), math.sin(yaw[i])
        base_rate[i] = (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])
    return base, base_rate


class Referee:
    """A MuJoCo model of a mobmanip robot on the floor; build it with :func:`build`.

    Attributes:
        model: MuJoCo's model. data: its data (the state of the last replay).
        supports: the floor contacts, driven wheels first.
        qpos0: the configuration every replay starts from, at rest, (model.nq,).
        repairs: link name -> (old, new) inertia (3, 3) kg m^2 of each link repaired for MuJoCo.
        lift: height of the root link's origin above the floor (m).
    """

    def __init__(self, robot, model, qpos0, supports, hands, has_object, repairs, lift, actuation=None):
        self.robot, self.model, self.data, self.qpos0 = robot, model, mujoco.MjData(model), qpos0
        self.supports, self.hands, self.has_object, self.repairs, self.lift = supports, hands, has_object, repairs, lift
        self._body = model.body("object" if has_object else hands[0]).id
        self._base = int(model.joint("floating_base").bodyid[0])
        self._root_qpos = int(model.joint("floating_base").qposadr[0])
        self._support_geoms = [model.geom(f"contact_{s.name}").id for s in supports]
        self._support_of = np.full(model.ngeom, -1, dtype=int)  # geom id -> support index, -1: none
        self._support_of[self._support_geoms] = np.arange(len(supports))
        self._is_support = self._support_of >= 0
        # (MuJoCo dof, row of B: the joint's generalized force per reduced effort) per driven joint
        pairs = _actuation(robot)[0] if actuation is None else actuation
        self._nx = robot.nx
        self._actuation = [(int(model.joint(name).dofadr[0]), row) for name, row in pairs]
        self._actuated = tuple(name for name, _ in pairs)
        # each driven joint's largest force: its row of B against the limits of the efforts in it
        # (only those: an unlimited effort elsewhere, inf times 0, is no term)
        limits = np.asarray(robot.effort_limits, dtype=float)
        self._force_limits = np.array([float(np.abs(row[row != 0]) @ limits[row != 0]) for _, row in pairs])
        self.reset()

    #: Per omnidirectional wheel's driven slide: (contact name, MuJoCo dof, axis in the root frame (2,)).
    drives: tuple[tuple[str, int, np.ndarray], ...] = ()

    @property
    def weight(self) -> float:
        """Total weight of the robot and the object (N)."""
        return float(self.model.body_subtreemass[0]) * GRAVITY

    def generalized_force(self, tau: np.ndarray, traction: Mapping[str, np.ndarray] | None = None) -> np.ndarray:
        """MuJoCo joint forces (nv,) of reduced efforts ``tau`` (nx,) N m or N, and of an
        omnidirectional base's wheels' ``traction`` (contact name -> the floor's force on the
        wheel along the floor, world x, y (2,) N, at the built pose): each hub's driven slide
        passes it to the base.

        Raises:
            ArgumentError: ``tau`` of the wrong shape; efforts on an omnidirectional base's own
                coordinates without the traction that is theirs.
        """
        tau = np.asarray(tau, dtype=float)
        if tau.shape != (self._nx,):
            raise ArgumentError(f"tau must have shape ({self._nx},), got {tau.shape}")
        out = np.zeros(self.model.nv)
        for dof, row in self._actuation:
            out[dof] += float(row @ tau)
        if self.drives and traction is None and np.any(np.asarray(self.robot.B)[:3] @ tau):
            raise ArgumentError(
                f"{self.robot.name}'s base efforts are its wheels' traction: give each wheel's (traction=)"
            )
        yaw = math.atan2(self.qpos0[self._root_qpos + 6], self.qpos0[self._root_qpos + 3]) * 2.0
        c, s = math.cos(yaw), math.sin(yaw)
        if traction is None:
            return out
        if missing := sorted({name for name, _, _ in self.drives} - set(traction)):
            raise ArgumentError(f"no traction given for wheel(s) {', '.join(missing)}")
        for name, dof, axis in self.drives:
            force = np.asarray(traction[name], dtype=float)[:2]
            # the floor holds the hub against the slide's push: the push is minus the traction
            out[dof] -= float(force @ [c * axis[0] - s * axis[1], s * axis[0] + c * axis[1]])
        return out

    def _held_joints(self) -> np.ndarray:
        """The MuJoCo dofs of mobmanip's joints that are not the platform's (its arms, torso)."""
        platform = {name for name, _ in self.robot.platform.wheels()} if self.robot.wheel_platform else set()
        model = self.robot.model
        names = [model.names[j] for j in range(2, model.njoints) if model.names[j] not in platform]
        return np.array([int(self.model.joint(name).dofadr[0]) for name in names], dtype=int)

    def _yaw0(self) -> float:
        """The built base's yaw (rad)."""
        return math.atan2(self.qpos0[self._root_qpos + 6], self.qpos0[self._root_qpos + 3]) * 2.0

    def configuration(self) -> np.ndarray:
        """mobmanip's configuration (nq,) the model was built at: the base's planar pose and every
        joint of mobmanip's model at its built position."""
        robot, m = self.robot, self.model
        q = robot.neutral()
        root = self.qpos0[self._root_qpos : self._root_qpos + 2]
        yaw = self._yaw0()
        q[:4] = (root[0], root[1], math.cos(yaw), math.sin(yaw))
        for j in range(2, robot.model.njoints):  # the built configuration's joints
            joint = robot.model.joints[j]
            value = float(self.qpos0[m.joint(robot.model.names[j]).qposadr[0]])
            q[joint.idx_q : joint.idx_q + joint.nq] = (math.cos(value), math.sin(value)) if joint.nq == 2 else value
        return q

    def _set_velocity(self, q: np.ndarray, x: np.ndarray) -> None:
        """Set the velocities of the built state (at configuration ``q``, the built one) to reduced
        velocity ``x`` (nx,): the base's planar velocity (world axes) and every joint's rate
        ``S x``; the bodies mobmanip does not model (the object, a level grasp's grips, an
        omnidirectional base's hubs) move as the model's equality constraints (the grasp) ask, at
        velocity level, by least squares."""
        robot, m, d = self.robot, self.model, self.data
        v = robot.null_space(q) @ x
        yaw = math.atan2(q[3], q[2])
        c, s = math.cos(yaw), math.sin(yaw)
        d.qvel[:] = 0.0
        base = int(m.joint("floating_base").dofadr[0])
        # a free joint's linear velocity is in world axes, its angular one in the body's (here level)
        d.qvel[base : base + 6] = [c * v[0] - s * v[1], s * v[0] + c * v[1], 0.0, 0.0, 0.0, v[2]]
        known = list(range(base, base + 6))
        for j in range(2, robot.model.njoints):
            dof = int(m.joint(robot.model.names[j]).dofadr[0])
            d.qvel[dof] = v[robot.model.joints[j].idx_v]
            known.append(dof)
        mujoco.mj_forward(m, d)
        rows = np.flatnonzero(d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
        rest = np.setdiff1d(np.arange(m.nv), known)
        if len(rows) and len(rest):
            J = _constraint_jacobian(m, d)[rows]
            d.qvel[rest] = np.linalg.lstsq(J[:, rest], -J[:, known] @ d.qvel[known], rcond=None)[0]
        mujoco.mj_forward(m, d)

    def _set_run(self, x: np.ndarray) -> None:
        """Start from reduced velocity ``x`` (nx,) of a translating robot (see :meth:`rollout`)."""
        robot = self.robot
        if x.shape != (robot.nx,) or not np.all(np.isfinite(x)):
            raise ArgumentError(f"the run's velocity must be {robot.nx} finite reduced velocities, got {x.shape}")
        q = self.configuration()
        v = robot.null_space(q) @ x
        if abs(v[2]) > 1e-12 * max(1.0, float(np.abs(v).max())):
            raise ArgumentError("a run from a velocity covers a translating robot: its base must not turn")
        self._set_velocity(q, x)

    def reset(self) -> None:
        """Back to the built configuration, at rest, no applied force."""
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = self.qpos0
        mujoco.mj_forward(self.model, self.data)

    def _body_acceleration(self, body: int) -> np.ndarray:
        """Linear (of the body frame's origin) then angular acceleration, world axes, (6,)."""
        m, d = self.model, self.data
        jac, jac_dot = np.zeros((6, m.nv)), np.zeros((6, m.nv))
        mujoco.mj_jac(m, d, jac[:3], jac[3:], d.xpos[body], body)
        mujoco.mj_jacDot(m, d, jac_dot[:3], jac_dot[3:], d.xpos[body], body)
        return jac @ d.qacc + jac_dot @ d.qvel

    def acceleration(self) -> np.ndarray:
        """Linear (at its centre) then angular acceleration of the object (without object: of the
        first hand frame), world axes, (6,) m/s^2 and rad/s^2, at the current state."""
        return self._body_acceleration(self._body)

    def hand_accelerations(self) -> np.ndarray:
        """Linear then angular acceleration of every hand frame, world axes, (k, 6)."""
        return np.array([self._body_acceleration(self.model.body(hand).id) for hand in self.hands])

    def contact_forces(self) -> dict[str, ContactForce]:
        """The floor's force on the robot at each support, by name, at the current state."""
        forces = self._floor_forces()
        return {s.name: ContactForce(float(f[2]), f[:2]) for s, f in zip(self.supports, forces)}

    def _floor_forces(self) -> np.ndarray:
        """The floor's force on each support (in order), world x, y then normal, (n, 3) N.

        The model's cones are elliptic (:func:`build`): a contact's force in its frame (on its
        second geom; normal first) is its rows of ``efc_force`` (as ``mj_contactForce`` reads it).
        """
        d = self.data
        forces = np.zeros((len(self.supports), 3))
        if d.ncon == 0:
            return forces
        contact = d.contact
        pairs, frames = contact.geom.reshape(-1, 2), contact.frame.reshape(-1, 3, 3)
        address, dim = contact.efc_address.reshape(-1), contact.dim.reshape(-1)
        local = np.zeros((len(address), 3))
        kept = address >= 0  # (an excluded contact has no rows and no force)
        local[kept, 0] = d.efc_force[address[kept]]
        rough = kept & (dim >= 3)
        local[rough, 1] = d.efc_force[address[rough] + 1]
        local[rough, 2] = d.efc_force[address[rough] + 2]
        second = self._is_support[pairs[:, 1]]
        local[~second] *= -1.0  # the force on the support when it is the first geom
        world = (frames * local[:, :, None]).sum(axis=1)  # the frame's rows are the contact's axes
        index = self._support_of[np.where(second, pairs[:, 1], pairs[:, 0])]
        for axis in range(3):
            forces[:, axis] = np.bincount(index, world[:, axis], minlength=len(forces))
        return forces

    def _support_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At the current state, per support (in order): the floor's force on it, world x, y then
        normal, (n, 3) N; the speed along the floor of its sphere's material point at its lowest
        point, (n,) m/s (a driven wheel's slip, a caster's sliding); the sphere's depth in the
        floor, (n,) m (negative: lifted)."""
        m, d = self.model, self.data
        slip, depth = np.zeros(len(self.supports)), np.zeros(len(self.supports))
        velocity = np.zeros(6)
        for k, geom in enumerate(self._support_geoms):
            radius = m.geom_size[geom, 0]
            # angular then linear velocity at the sphere's centre, world axes
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, geom, velocity, 0)
            # the lowest point, -radius e_z from the centre: v + w x (-radius e_z)
            slip[k] = math.hypot(velocity[3] - radius * velocity[1], velocity[4] + radius * velocity[0])
            depth[k] = radius - d.geom_xpos[geom, 2]
        return self._floor_forces(), slip, depth

    def _friction_use(self, normal: np.ndarray, tangential: np.ndarray) -> np.ndarray:
        """``|tangential| / (mu normal)`` per support, (..., n); 0 for frictionless ones."""
        mu = np.array([s.mu for s in self.supports])
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.nan_to_num(np.where(mu > 0, np.linalg.norm(tangential, axis=-1) / (mu * normal), 0.0), nan=0.0)

    def forward(
        self, tau: np.ndarray, traction: Mapping[str, np.ndarray] | None = None
    ) -> tuple[np.ndarray, dict[str, ContactForce]]:
        """Apply reduced efforts ``tau`` (nx,) from rest at the built configuration (t = 0).

        Args:
            tau: in ``robot.reduced_velocity_names`` order and mobmanip's sense (N m or N).
            traction: an omnidirectional base's wheels' traction (see :meth:`generalized_force`).

        Returns:
            ``(acceleration, contacts)``: the object's linear (at its centre) and angular
            acceleration, world axes, (6,) m/s^2 and rad/s^2 (without object: each hand's,
            (k, 6)); the floor's force on the robot at each support, by name.
        """
        self.reset()
        self.data.qfrc_applied[:] = self.generalized_force(tau, traction)
        mujoco.mj_forward(self.model, self.data)
        return (self.acceleration() if self.has_object else self.hand_accelerations()), self.contact_forces()

    def rollout(
        self,
        tau: np.ndarray,
        duration: float = 0.02,
        *,
        slip_speed: float = 1e-3,
        at_limit: float = 0.999,
        max_penetration: float = 1e-3,
        traction: Mapping[str, np.ndarray] | None = None,
        velocity: np.ndarray | None = None,
        feedback: tuple[float, float] | None = None,
        clamp: bool = False,
    ) -> Rollout:
        """Hold reduced efforts ``tau`` (nx,) for ``duration`` (s) from rest (semi-implicit Euler).

        Args:
            tau: in ``robot.reduced_velocity_names`` order and mobmanip's sense (N m or N).
            traction: an omnidirectional base's wheels' traction (see :meth:`generalized_force`),
                held in each wheel's own axes as its motor holds it.
            velocity: start from this reduced velocity (nx,) instead of rest: a run in which the
                whole robot translates (no joint of the arms moving, the base not turning; the
                object moves as the base does). Its wheels turn at the rates S gives.
            feedback: ``(kp, kd)``: a joint-space tracking feedback on every joint but the
                platform's, ``-kp (q - q_0) - kd qdot`` (N m/rad, N m s/rad), added to the efforts;
                its largest torque is :attr:`Rollout.feedback`.
            clamp: the motors give no more than their limits: at every step, each joint B drives
                gets at most its effort limit (efforts and feedback together, clipped; a joint
                driven by one effort ``tau_k`` with ``Q_j = b tau_k`` gets at most ``|b|`` times
                its limit). Off: whatever ``tau`` and the feedback ask.
            duration: how long (s).
            slip_speed: contact-point speed along the floor above which a driven wheel slips (m/s).
            at_limit: friction use at or above which a driven wheel slides.
            max_penetration: depth in the floor beyond which a support is not kept (m).
        """
        m, d = self.model, self.data
        self.reset()
        if velocity is not None:
            self._set_run(np.asarray(velocity, dtype=float))
        applied = self.generalized_force(tau, traction)
        held = self._held_joints() if feedback is not None else np.zeros(0, dtype=int)
        kp, kd = feedback if feedback is not None else (0.0, 0.0)
        q_held = np.array([d.qpos[m.jnt_qposadr[m.dof_jntid[dof]]] for dof in held])
        driven = np.array([dof for dof, _ in self._actuation], dtype=int) if clamp else np.zeros(0, dtype=int)
        largest = 0.0
        rows: dict[str, list] = {k: [] for k in ("t", "f", "slip", "pen", "pos", "rpy", "acc")}
        for _ in range(int(round(duration / m.opt.timestep)) + 1):
            d.qfrc_applied[:] = applied
            if len(held):
                positions = np.array([d.qpos[m.jnt_qposadr[m.dof_jntid[dof]]] for dof in held])
                push = -kp * (positions - q_held) - kd * d.qvel[held]
                d.qfrc_applied[held] += push
                largest = max(largest, float(np.abs(push).max()))
            if len(driven):
                d.qfrc_applied[driven] = np.clip(d.qfrc_applied[driven], -self._force_limits, self._force_limits)
            mujoco.mj_forward(m, d)
            forces, slip, pen = self._support_state()
            rows["t"].append(d.time)
            rows["f"].append(forces)
            rows["slip"].append(slip)
            rows["pen"].append(pen)
            rows["pos"].append(d.xpos[self._base].copy())
            rows["rpy"].append(pin.rpy.matrixToRpy(d.xmat[self._base].reshape(3, 3)))
            rows["acc"].append(self.acceleration())
            mujoco.mj_Euler(m, d)
        f = np.array(rows["f"])
        fn, ft = f[:, :, 2], f[:, :, :2]
        use = self._friction_use(fn, ft)
        slip, pen, pos, rpy, acc = (np.array(rows[k]) for k in ("slip", "pen", "pos", "rpy", "acc"))
        out = Rollout(self.supports, np.array(rows["t"]), fn, ft, use, slip, pen, pos, rpy, acc, feedback=largest)
        out.judge(slip_speed, at_limit, max_penetration)
        return out

    def follow(
        self,
        trajectory: TimedMotion,
        efforts: np.ndarray,
        *,
        feedback: tuple[float, float],
        slip_speed: float = 1e-3,
        at_limit: float = 0.999,
        max_penetration: float = 1e-3,
    ) -> MotionReplay:
        """Replay a whole timed motion: from its first configuration and velocity, apply its
        planned efforts and track its planned joints (semi-implicit Euler at the model's step).

        At every step, at time t: the feed-forward, the plan's reduced efforts interpolated
        linearly in time between its samples and mapped to the joints as
        :meth:`generalized_force` does; plus a joint-space feedback on every actuated joint
        (each wheel and each joint of the arms, torso or head that B drives),
        ``-kp (q_j - q_j*(t)) - kd (qdot_j - qdot_j*(t))`` with q_j* the plan's position (a
        wheel's angle unwound from its start) and qdot_j* its rate ``(S x)_j``, both from the
        cubic through the neighbouring samples' positions and rates. Nothing acts on the floating
        base: the wheels drive it through the floor, and where it goes is reported
        (:attr:`MotionReplay.base_error`), not corrected.

        Args:
            trajectory: the plan: time stamps ``t`` (N,) s, configurations ``q`` (N, nq) and
                reduced velocities ``x`` (N, nx) (a :class:`mobmanip.motion.trajectory.Trajectory`);
                its first configuration the one the model was built at, its configurations
                moving every tracked joint (the wheels too) as its velocities do.
            efforts: the plan's reduced efforts per sample, (N, nx), in
                ``robot.reduced_velocity_names`` order and mobmanip's sense (N m or N), e.g.
                :attr:`mobmanip.motion.trajectory_analysis.TrajectoryAnalysis.efforts`.
            feedback: ``(kp, kd)`` (N m/rad, N m s/rad; N/m, N s/m on a prismatic joint), >= 0.
            slip_speed, at_limit, max_penetration: as :meth:`rollout`'s.

        Raises:
            ArgumentError: a plan of the wrong shape, not starting at the built configuration,
                with samples closer than the model's step, or whose configurations do not move a
                tracked joint as its velocities do (over the whole plan, by half or more); negative
                gains.
            mobmanip.errors.NotRepresentable: an omnidirectional base (its efforts are its wheels' traction,
                which the plan does not give).
        """
        t, qs, xs, tau, kp, kd = self._checked_plan(trajectory, efforts, feedback)
        tracked = self._tracked_plan(t, qs, xs, tau)
        base, base_rate = _planned_base(self.robot, qs, xs)
        a = self._replay(t, qs[0], xs[0], tracked, base, base_rate, kp, kd)
        out = MotionReplay(
            self.supports, a["t"], a["fn"], a["ft"], a["use"], a["slip"], a["pen"], a["pos"], a["rpy"], a["acc"],
            feedback=float(a["push"].max(initial=0.0)), planned_base=a["base"], base_error=a["base_error"],
            yaw_error=a["yaw_error"], joints=tracked.names, joint_error=a["joint_error"], feedback_effort=a["push"],
            deepest=a["deep"],
        )  # fmt: skip
        out.judge(slip_speed, at_limit, max_penetration)
        return out

    def _checked_plan(
        self, trajectory: TimedMotion, efforts: np.ndarray, feedback: tuple[float, float]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]:
        """A plan :meth:`follow` can replay, checked: ``(t, q, x, efforts, kp, kd)``, the arrays as
        floats, (N,), (N, nq), (N, nx), (N, nx), and the feedback's gains.

        Raises:
            ArgumentError, mobmanip.errors.NotRepresentable: as :meth:`follow` says, but for a
                plan whose configurations do not move its joints as its velocities do
                (:meth:`_tracked_plan`).
        """
        robot, m = self.robot, self.model
        if self.drives:
            raise NotRepresentable(
                f"{robot.name}'s base efforts are its wheels' traction: a motion replay covers bases its wheels' "
                "joints drive"
            )
        try:
            t, qs, xs = (np.asarray(getattr(trajectory, k), dtype=float) for k in ("t", "q", "x"))
        except AttributeError:
            raise ArgumentError(f"expected a trajectory (t, q, x), got {type(trajectory).__name__}") from None
        n = t.shape[0]
        tau = np.asarray(efforts, dtype=float)
        shapes = {"q": (qs, robot.model.nq), "x": (xs, robot.nx), "efforts": (tau, robot.nx)}
        for name, (array, width) in shapes.items():
            got, want = array.shape, (n, width)
            if got != want:
                raise ArgumentError(f"the plan's {name} must have shape {want}, got {got}")
        if n < 2 or not all(np.all(np.isfinite(a)) for a in (t, qs, xs, tau)):
            raise ArgumentError("the plan needs at least 2 samples of finite numbers")
        step = float(m.opt.timestep)
        if np.any(np.diff(t) < step):
            k = int(np.flatnonzero(np.diff(t) < step)[0])
            raise ArgumentError(
                f"the plan's samples {k} and {k + 1} are {t[k + 1] - t[k]:.3g} s apart, closer than MuJoCo's step "
                f"{step:g} s"
            )
        kp, kd = (float(g) for g in feedback)
        if not (math.isfinite(kp) and math.isfinite(kd) and kp >= 0.0 and kd >= 0.0):
            raise ArgumentError(f"the feedback's gains must be finite and >= 0, got {feedback!r}")
        built = self.configuration()
        off = float(np.abs(pin.difference(robot.model, built, qs[0])).max())
        if off > 1e-9:
            raise ArgumentError(
                f"the plan starts {off:.3g} (m or rad) away from the configuration the model was built at: "
                "build it at the plan's first configuration"
            )
        return t, qs, xs, tau, kp, kd

    def _tracked_plan(self, t: np.ndarray, qs: np.ndarray, xs: np.ndarray, tau: np.ndarray) -> _TrackedPlan:
        """The plan per tracked joint (every actuated one), from its time stamps ``t`` (N,),
        configurations ``qs`` (N, nq), reduced velocities ``xs`` (N, nx) and efforts ``tau``
        (N, nx): the joints' positions (unwound: the sum of the configurations' steps, from the
        built ones), their rates ``S x`` and their feed-forward forces.

        Raises:
            ArgumentError: configurations that do not move a tracked joint as the velocities do
                (over the whole plan, by half or more).
        """
        robot, m, n = self.robot, self.model, t.shape[0]
        model = robot.model
        names = self._actuated
        columns = [model.joints[model.getJointId(name)].idx_v for name in names]
        dofs = np.array([int(m.joint(name).dofadr[0]) for name in names], dtype=int)
        addresses = np.array([int(m.jnt_qposadr[m.dof_jntid[dof]]) for dof in dofs], dtype=int)
        steps = np.array([pin.difference(model, qs[i], qs[i + 1])[columns] for i in range(n - 1)])
        planned = self.qpos0[addresses] + np.vstack([np.zeros(len(dofs)), np.cumsum(steps, axis=0)])
        rates = np.array([(robot.null_space(qs[i]) @ xs[i])[columns] for i in range(n)])
        travel = 0.5 * np.diff(t)[:, None] * (rates[:-1] + rates[1:])  # what the rates move (trapezoid)
        mismatch = np.abs(steps - travel).sum(axis=0)
        scale = np.maximum(np.abs(steps).sum(axis=0), np.abs(travel).sum(axis=0))
        if np.any(mismatch > 0.5 * scale):
            k = int(np.argmax(mismatch / np.where(scale > 0.0, scale, 1.0)))
            raise ArgumentError(
                f"the plan's configurations move {names[k]} by {np.abs(steps[:, k]).sum():.4g} in all, its velocities "
                f"by {np.abs(travel[:, k]).sum():.4g}: give configurations that carry every tracked joint's position "
                "(a trajectory file needs the wheels' columns)"
            )
        forces = np.array([self.generalized_force(tau[i])[dofs] for i in range(n)])
        return _TrackedPlan(names, dofs, addresses, planned, rates, forces)

    def _replay(
        self,
        t: np.ndarray,
        q0: np.ndarray,
        x0: np.ndarray,
        tracked: _TrackedPlan,
        base: np.ndarray,
        base_rate: np.ndarray,
        kp: float,
        kd: float,
    ) -> dict[str, np.ndarray]:
        """Run the replay :meth:`follow` describes from the plan's first configuration ``q0`` and
        reduced velocity ``x0``, one row per time stamp of ``t`` (N,).

        Args:
            tracked: the plan per tracked joint (:meth:`_tracked_plan`).
            base, base_rate: the plan's base pose and its world velocity per sample, (N, 3)
                (:func:`_planned_base`).
            kp, kd: the feedback's gains.

        Returns:
            The rows by key (:meth:`_record_row`), each an array with one row per sample.
        """
        m, d = self.model, self.data
        n, step = t.shape[0], float(m.opt.timestep)
        dofs, addresses, forces = tracked.dofs, tracked.addresses, tracked.forces
        self.reset()
        self._set_velocity(q0, x0)
        record = np.round((t - t[0]) / step).astype(int)  # the step of each sample's row
        keys = "t ft pos rpy acc base base_error yaw_error joint_error fn use slip pen deep push"
        rows: dict[str, list] = {key: [] for key in keys.split()}
        steps_since: list[tuple] = []  # (floor forces, slip, depth, feedback) at each step of the row
        i = 0  # the plan's interval [t_i, t_i+1] holding the step
        for k in range(int(record[-1]) + 1):
            now = t[0] + d.time
            while i < n - 2 and now > t[i + 1]:
                i += 1
            w = min(max((now - t[i]) / (t[i + 1] - t[i]), 0.0), 1.0)
            target, target_rate = _hermite(t, tracked.planned, tracked.rates, i, t[i] + w * (t[i + 1] - t[i]))
            push = -kp * (d.qpos[addresses] - target) - kd * (d.qvel[dofs] - target_rate)
            d.qfrc_applied[:] = 0.0
            d.qfrc_applied[dofs] = (1.0 - w) * forces[i] + w * forces[i + 1] + push
            mujoco.mj_forward(m, d)
            f, slip, depth = self._support_state()
            steps_since.append((f, slip, depth, np.abs(push)))
            r = len(rows["t"])
            if k == record[r]:  # sample r's row: the state now, the extremes since the last row
                plan, _ = _hermite(t, base, base_rate, min(r, n - 2), now)
                self._record_row(rows, steps_since, now, plan, d.qpos[addresses] - target)
                steps_since = []
            mujoco.mj_Euler(m, d)
        return {key: np.array(value) for key, value in rows.items()}

    def _record_row(
        self, rows: dict[str, list], steps: list[tuple], now: float, plan: np.ndarray, joint_error: np.ndarray
    ) -> None:
        """Add one row of a replay (:meth:`follow`) to ``rows``, by key.

        Args:
            rows: the rows so far, by key, each a list: ``fn`` ``use`` ``slip`` ``pen`` ``deep``
                ``push`` the extremes over the row's ``steps``, ``t`` ``ft`` ``pos`` ``rpy`` ``acc``
                ``base`` ``base_error`` ``yaw_error`` ``joint_error`` the state now.
            steps: each MuJoCo step since the last row, the last one now: ``(floor forces (n, 3)
                N, slide speed (n,) m/s, depth (n,) m, feedback magnitude (j,))``.
            now: the time (s, from the plan's first time stamp).
            plan: the plan's base pose now, x, y (m), yaw (rad), (3,).
            joint_error: MuJoCo's tracked joints' positions minus the plan's now, (j,).
        """
        fs, slides, depths, pushes = (np.array(column) for column in zip(*steps))
        rows["fn"].append(fs[:, :, 2].min(axis=0))
        rows["use"].append(self._friction_use(fs[:, :, 2], fs[:, :, :2]).max(axis=0))
        rows["slip"].append(slides.max(axis=0))
        rows["pen"].append(depths.min(axis=0))
        rows["deep"].append(depths.max(axis=0))
        rows["push"].append(pushes.max(axis=0))
        rows["t"].append(now)
        rows["ft"].append(steps[-1][0][:, :2])
        d = self.data
        position, R = d.xpos[self._base].copy(), d.xmat[self._base].reshape(3, 3)
        rows["pos"].append(position)
        rows["rpy"].append(pin.rpy.matrixToRpy(R))
        rows["acc"].append(self.acceleration())
        rows["base"].append(plan)
        rows["base_error"].append(float(np.hypot(*(position[:2] - plan[:2]))))
        turn = math.atan2(R[1, 0], R[0, 0]) - plan[2]
        rows["yaw_error"].append((turn + math.pi) % (2.0 * math.pi) - math.pi)
        rows["joint_error"].append(joint_error)
