"""``mobmanip init-spec PATH --ee FRAME ...``: infer a robot spec from a URDF and write it as TOML."""

from __future__ import annotations

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
    parser.add_argument("--out", metavar="SPEC.toml", help="write here (default: standard output)")
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..detect import detect_spec, parse_wheel_list, spec_to_toml
    from ..io import write_text

    wheels = None if args.wheels is None else parse_wheel_list(args.wheels)
    found = detect_spec(args.urdf, args.ee, wheels, args.platform, torso=args.torso, name=args.name)
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
