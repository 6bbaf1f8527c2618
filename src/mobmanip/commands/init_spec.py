"""``mobmanip init-spec PATH --ee FRAME ...``: infer a robot spec from a URDF and write it as TOML."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..platforms import KINDS
from .common import add_urdf_options


def register(sub) -> None:
    parser = sub.add_parser(
        "init-spec",
        help="write a robot spec (TOML) inferred from a URDF",
        description="Detect the drive wheels and the arms of a URDF and write a commented spec to edit.",
    )
    parser.add_argument("urdf", metavar="PATH", help="the URDF file")
    add_urdf_options(parser, ee_required=True)
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
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..detect import detect_spec, parse_wheel_list, spec_to_toml
    from ..io import write_text

    wheels = None if args.wheels is None else parse_wheel_list(args.wheels)
    found = detect_spec(args.urdf, args.ee, wheels, args.platform, torso=args.torso, name=args.name)
    if args.posture:
        found = dataclasses.replace(found, spec=_with_postures(found.spec, args.posture))
    base_dir = Path(args.out).resolve().parent if args.out else None
    text = spec_to_toml(
        found.spec,
        base_dir,
        notes=found.notes,
        urdf_limits=found.urdf_limits,
        shared_joints=found.shared_joints,
    )
    if not args.out:
        print(text, end="")
        return 0
    write_text(args.out, text)
    spec = found.spec
    print(f"wrote {args.out}: {spec.platform}, {len(spec.arms)} arm(s), {len(spec.active_joint_names)} active joints")
    return 0


def _with_postures(spec, items):
    """The spec with the postures NAME=Q.json recorded (their arm and torso joints only).

    Raises:
        UsageError: an item not of the form NAME=PATH, or a name given twice or reserved.
    """
    from ..errors import UsageError
    from ..io import read_configuration
    from ..model import load_robot

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
