"""``mobmanip init-spec PATH --ee FRAME ...``: infer a robot spec from a URDF and write it as TOML."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

from ..platforms import KINDS
from ..support.reading import decimal
from .common import add_description_options, add_strict_option, add_urdf_options, read_options_from_args


def register(sub) -> None:
    parser = sub.add_parser(
        "init-spec",
        help="write a robot spec (TOML) inferred from a URDF",
        description="Detect the drive wheels and the arms of a URDF and write a commented spec to edit.",
    )
    parser.add_argument("urdf", metavar="PATH", help="the robot file (URDF, xacro, MJCF)")
    add_urdf_options(parser)
    parser.add_argument(
        "--list-frames", action="store_true", help="list the links that could be end effectors (for --ee) and exit"
    )
    parser.add_argument(
        "--platform",
        choices=list(KINDS),
        help="platform kind (default: the wheeled kind the URDF's wheels fit, else fixed)",
    )
    parser.add_argument(
        "--torso", action="store_true", help="actuate the joints shared by all arms (default: lock them)"
    )
    parser.add_argument("--name", help="robot name (default: the URDF's)")
    parser.add_argument(
        "--posture",
        action="append",
        default=[],
        metavar="NAME=Q.json",
        help="record the arm and torso joints of a configuration file as a named posture "
        "(NAME hold: the [hold] posture); repeat for several",
    )
    parser.add_argument("--out", metavar="SPEC.toml", help="write here (default: standard output)")
    add_strict_option(parser)
    add_description_options(parser)
    given = parser.add_argument_group("values the URDF may lack")
    given.add_argument("--wheel-radius", type=decimal, metavar="M", help="radius of wheels with mesh geometry (m)")
    given.add_argument(
        "--wheel-velocity-limit", type=decimal, metavar="RAD_S", help="each platform wheel's qdot_max the URDF lacks"
    )
    given.add_argument(
        "--wheel-effort-limit", type=decimal, metavar="NM", help="each platform wheel's tau_max the URDF lacks"
    )
    given.add_argument(
        "--velocity-limit", action="append", default=[], metavar="NAME=V", help="a joint's velocity limit (repeat)"
    )
    given.add_argument(
        "--effort-limit", action="append", default=[], metavar="NAME=E", help="a joint's effort limit (repeat)"
    )
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..errors import UsageError
    from ..robot.detect import detect_spec, parse_wheel_list, spec_to_toml
    from ..robot.detect_report import missing_message
    from ..support.files import write_text

    read_options = read_options_from_args(args)
    if args.list_frames:
        return _list_frames(args.urdf, read_options)
    if not args.ee:
        raise UsageError(f"init-spec needs at least one --ee FRAME (`mobmanip init-spec {args.urdf} --list-frames`)")
    for name in ("wheel_radius", "wheel_velocity_limit", "wheel_effort_limit"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0):
            raise UsageError(f"--{name.replace('_', '-')} must be a positive number, got {value!r}")
    limits: dict = {}
    for index, items in ((0, args.velocity_limit), (1, args.effort_limit)):
        for joint, value in _pairs(items, "--velocity-limit" if index == 0 else "--effort-limit"):
            pair = list(limits.get(joint, (None, None)))
            pair[index] = value
            limits[joint] = tuple(pair)
    wheels = None if args.wheels is None else parse_wheel_list(args.wheels)
    found = detect_spec(
        args.urdf,
        args.ee,
        wheels,
        args.platform,
        torso=args.torso,
        name=args.name,
        wheel_radius=args.wheel_radius,
        wheel_limits=(args.wheel_velocity_limit, args.wheel_effort_limit),
        limits=limits,
        strict=args.strict,
        read_options=read_options,
    )

    if args.posture:
        found = dataclasses.replace(found, spec=_with_postures(found.spec, args.posture))
    base_dir = Path(args.out).resolve().parent if args.out else None
    text = spec_to_toml(
        found.spec,
        base_dir,
        notes=found.considered + found.notes,
        urdf_limits=found.urdf_limits,
        shared_joints=found.shared_joints,
    )
    if not args.out:
        print(text, end="")
    else:
        write_text(args.out, text)
        print("detection (also written as comments at the top of the spec):")
        for line in found.considered + found.notes:
            print(f"  {line}")
        spec = found.spec
        print(
            f"wrote {args.out}: {spec.platform}, {len(spec.arms)} arm(s), {len(spec.active_joint_names)} active joints"
        )
    if found.missing:
        print(f"warning: {missing_message(found.missing, args.urdf)}", file=sys.stderr)
    return 0


def _pairs(items, option: str):
    """NAME=VALUE items as (name, positive float) pairs."""
    from ..errors import UsageError

    for item in items:
        name, sep, text = item.partition("=")
        try:
            value = decimal(text)
        except ValueError:
            value = math.nan
        if not sep or not name.strip() or not (math.isfinite(value) and value > 0):
            raise UsageError(f"{option} takes NAME=VALUE with a positive VALUE, got {item!r}")
        yield name.strip(), value


def _list_frames(path, read_options) -> int:
    """Print the candidate end-effector frames of a robot file, the most likely first."""
    from ..descriptions import check_supported, read_description
    from ..platforms.wheels import wheel_candidates
    from ..robot.detect_report import candidate_frames

    description = read_description(path, **read_options)
    check_supported(description)
    rows = candidate_frames(description, exclude=[c.name for c in wheel_candidates(description)])
    print(f"{len(rows)} candidate end-effector frames of {path} (for --ee), the most likely first:")
    for link, count, leaf, tool in rows:
        kind = ", ".join(t for t, flag in (("leaf", leaf), ("named like a tool", tool)) if flag)
        print(f"  {link:<40} {count} actuated joint{'s' if count != 1 else ''} from the root; {kind}")
    return 0


def _with_postures(spec, items):
    """The spec with the postures NAME=Q.json recorded (their arm and torso joints only).

    Raises:
        UsageError: an item not of the form NAME=PATH, or a name given twice or reserved.
    """
    from ..errors import UsageError
    from ..robot.configurations import read_configuration
    from ..robot.model import load_robot

    robot = None
    hold, postures = dict(spec.hold), dict(spec.postures)
    for item in items:
        name, sep, path = item.partition("=")
        name = name.strip()
        if not sep or not name or not path:
            raise UsageError(f"--posture takes NAME=Q.json, got {item!r}")
        if name == "home":
            raise UsageError("--posture home: the home posture is the [reference] one; record another name")
        if name in postures or (name == "hold" and hold):
            raise UsageError(f"--posture {name} is given twice")
        if robot is None:
            robot = load_robot(spec)  # the configuration file is read against the model
        joints = robot.configuration_dict(read_configuration(robot, path))["joints"]
        kept = {j: joints[j] for j in spec.torso + spec.arm_joint_names}
        if name == "hold":
            hold = kept
        else:
            postures[name] = kept
    return dataclasses.replace(spec, hold=hold, postures=postures)
