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
    parser.add_argument("urdf", metavar="PATH", nargs="?", help="the robot file (URDF, xacro, MJCF)")
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
    mount = parser.add_argument_group(
        "an arm mounted on a base",
        "compose two URDFs into one (written beside --out SPEC.toml as SPEC.urdf) and infer its spec; instead of PATH",
    )
    mount.add_argument("--mount", metavar="ARM.urdf", help="the arm's URDF")
    mount.add_argument("--on", metavar="BASE.urdf", help="the base's URDF")
    mount.add_argument(
        "--at",
        metavar="X,Y,Z,YAW",
        help="the arm's root link in the frame of --on-link: metres and degrees about z (a fixed joint)",
    )
    mount.add_argument("--on-link", metavar="LINK", help="the base's link the arm is fixed to (default: its root link)")
    mount.add_argument(
        "--prefix",
        default="arm_",
        help="put before arm names the base already uses (default: link_1 becomes arm_link_1)",
    )
    given = parser.add_argument_group("values the URDF may lack")
    given.add_argument("--wheel-radius", type=decimal, metavar="M", help="radius of wheels with mesh geometry (m)")
    given.add_argument(
        "--wheel-velocity-limit", type=decimal, metavar="RAD_S", help="each platform wheel's qdot_max the URDF lacks"
    )
    given.add_argument(
        "--wheel-effort-limit", type=decimal, metavar="NM", help="each platform wheel's tau_max the URDF lacks"
    )
    given.add_argument(
        "--velocity-limit",
        action="append",
        default=[],
        metavar="NAME=V",
        help="a joint's velocity limit (repeat); NAME may be a pattern such as 'arm_*_joint' for every joint it "
        "matches (a joint named exactly keeps its own)",
    )
    given.add_argument(
        "--effort-limit",
        action="append",
        default=[],
        metavar="NAME=E",
        help="a joint's effort limit (repeat; NAME may be a pattern, as for --velocity-limit)",
    )
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..errors import UsageError

    read_options = read_options_from_args(args)
    mounting = args.mount is not None or args.on is not None or args.at is not None
    if mounting:
        return _run_mounted(args, read_options)
    if args.on_link is not None:
        raise UsageError("--on-link goes with --mount ARM.urdf --on BASE.urdf --at X,Y,Z,YAW")
    if args.urdf is None:
        raise UsageError("init-spec needs a robot file PATH, or --mount ARM.urdf --on BASE.urdf --at X,Y,Z,YAW")
    if args.list_frames:
        return _list_frames(args.urdf, read_options)
    return _write_spec(args, args.urdf, read_options)


def _write_spec(args, urdf, read_options, mounted=None, final_urdf=None) -> int:
    """Detect the spec of ``urdf`` and write it (``mounted``: the composed file, moved to
    ``final_urdf`` once the spec is known)."""
    from ..errors import UsageError
    from ..robot.detect import detect_spec, parse_wheel_list, spec_to_toml
    from ..robot.detect_report import missing_message
    from ..support.files import write_text

    shown = final_urdf if final_urdf is not None else urdf
    if not args.ee:
        raise UsageError(f"init-spec needs at least one --ee FRAME (`mobmanip init-spec {_again(args)} --list-frames`)")
    for name in ("wheel_radius", "wheel_velocity_limit", "wheel_effort_limit"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0):
            raise UsageError(f"--{name.replace('_', '-')} must be a positive number, got {value!r}")
    limits = _joint_limits(args, urdf, read_options)
    wheels = None if args.wheels is None else parse_wheel_list(args.wheels)
    found = detect_spec(
        urdf,
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

    if final_urdf is not None:  # detected on a draft: name the file the spec will point to
        spec = dataclasses.replace(found.spec, urdf=Path(final_urdf).resolve())
        renamed = [tuple(n.replace(str(urdf), str(final_urdf)) for n in x) for x in (found.considered, found.notes)]
        considered, notes = renamed
        found = dataclasses.replace(found, spec=spec, considered=considered, notes=notes)
    if args.posture:
        found = dataclasses.replace(found, spec=_with_postures(found.spec, args.posture))
    if mounted is not None:  # the spec is known: the composed URDF and its meshes take their place
        _copy_meshes(mounted, Path(final_urdf).resolve().parent)
        write_text(final_urdf, mounted.text)
        print(f"wrote {final_urdf}: {_describe_mount(args, mounted)}")
    base_dir = Path(args.out).resolve().parent if args.out else None
    text = spec_to_toml(
        found.spec,
        base_dir,
        notes=found.considered + found.notes,
        urdf_limits=found.urdf_limits,
        shared_joints=found.shared_joints,
        source_format=found.source_format,
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
        print(f"warning: {missing_message(found.missing, shown)}", file=sys.stderr)
    return 0


def _again(args) -> str:
    """The robot-file part of the command line, to suggest a next command."""
    if args.urdf is not None:
        return str(args.urdf)
    link = f" --on-link {args.on_link}" if args.on_link else ""
    return f"--mount {args.mount} --on {args.on} --at {args.at}{link}"


def _describe_mount(args, mounted) -> str:
    link = args.on_link or "its root link"
    text = f"{args.mount} mounted on {args.on} ({link}) at {args.at} by the fixed joint {mounted.mount_joint!r}"
    if mounted.renamed:
        text += "; renamed " + ", ".join(f"{kind} {old!r} -> {new!r}" for kind, old, new in mounted.renamed)
    return text


def _copy_meshes(mounted, folder: Path) -> None:
    """Copy the composed robot's meshes (and textures) beside its URDF."""
    import shutil

    for source, target in mounted.copies:
        destination = folder / target
        destination.parent.mkdir(parents=True, exist_ok=True)
        if not (destination.exists() and destination.samefile(source)):
            shutil.copyfile(source, destination)


def _run_mounted(args, read_options) -> int:
    """``--mount ARM --on BASE --at X,Y,Z,YAW``: compose, then list frames or write the spec."""
    import os
    import tempfile

    from ..descriptions.mount import mount_urdf, parse_pose
    from ..errors import UsageError

    missing = [f"--{n}" for n in ("mount", "on", "at") if getattr(args, n) is None]
    if missing:
        raise UsageError(f"--mount ARM.urdf --on BASE.urdf --at X,Y,Z,YAW go together; missing {', '.join(missing)}")
    if args.urdf is not None:
        raise UsageError(f"give either PATH ({args.urdf}) or --mount ARM.urdf --on BASE.urdf, not both")
    pose = parse_pose(args.at)
    if not args.list_frames and not args.out:
        raise UsageError("--mount writes the composed URDF beside the spec: give --out SPEC.toml")
    if not args.list_frames and not args.ee:
        raise UsageError(f"init-spec needs at least one --ee FRAME (`mobmanip init-spec {_again(args)} --list-frames`)")
    out_dir = Path(args.out).resolve().parent if args.out else Path.cwd()
    final = Path(args.out).with_suffix(".urdf") if args.out else None
    if final is not None:
        target = final.resolve()
        for option, given in (("--mount", args.mount), ("--on", args.on), ("--out", args.out)):
            if Path(given).resolve() == target:
                raise UsageError(f"the composed URDF would be written over {option} {given}: choose another --out")
    meshes = f"{final.stem}_meshes" if final is not None else "meshes"
    mounted = mount_urdf(args.mount, args.on, pose, meshes, on_link=args.on_link, prefix=args.prefix,
                         package_paths=read_options["package_paths"])  # fmt: skip
    options = read_options
    with tempfile.TemporaryDirectory(prefix=".mobmanip-mount-", dir=out_dir if final is not None else None) as tmp:
        draft = Path(tmp) / f"{(final.stem if final is not None else 'mounted')}.urdf"
        draft.write_text(mounted.text, encoding="utf-8")
        if args.list_frames:
            for kind, old, new in mounted.renamed:
                print(f"renamed the arm's {kind} {old!r} -> {new!r}")
            return _list_frames(draft, options, shown=f"{args.mount} on {args.on}")
        try:
            return _write_spec(args, draft, options, mounted=mounted, final_urdf=final)
        finally:
            if draft.exists():
                os.unlink(draft)


def _joint_limits(args, urdf, read_options) -> dict[str, tuple[float | None, float | None]]:
    """``--velocity-limit`` and ``--effort-limit`` by joint: (velocity, effort), each ``None``
    where not given. A NAME may be a shell-style pattern (``arm_*_joint``, ``wheel_?_joint``) that
    stands for every joint of the file it matches; a joint named exactly keeps its own value.

    Raises:
        UsageError: a malformed item, or a pattern that matches no joint of the file (named, with
            the closest joints).
    """
    import fnmatch

    from ..errors import UsageError, closest_first

    items = [(0, args.velocity_limit, "--velocity-limit"), (1, args.effort_limit, "--effort-limit")]
    if not any(given for _, given, _ in items):
        return {}
    names: list[str] | None = None
    limits: dict[str, list[float | None]] = {}
    for index, given, option in items:
        exact, patterns = {}, []
        for name, value in _pairs(given, option):
            if any(c in name for c in "*?["):
                patterns.append((name, value))
            else:
                exact[name] = value
        if patterns and names is None:
            from ..descriptions import read_description

            names = list(read_description(urdf, **read_options).joints)
        for pattern, value in patterns:
            matched = [n for n in names or () if fnmatch.fnmatchcase(n, pattern)]
            if not matched:
                close = ", ".join(closest_first(pattern.replace("*", "").replace("?", ""), names or (), 5))
                raise UsageError(f"{option} {pattern}: the pattern matches no joint of the file (closest: {close})")
            for name in matched:
                if name not in exact:
                    limits.setdefault(name, [None, None])[index] = value
        for name, value in exact.items():
            limits.setdefault(name, [None, None])[index] = value
    return {name: (pair[0], pair[1]) for name, pair in limits.items()}


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


def _list_frames(path, read_options, shown=None) -> int:
    """Print the candidate end-effector frames of a robot file (``shown``: its name in the
    output), the most likely first."""
    from ..descriptions import check_supported, read_description
    from ..platforms.wheels import wheel_candidates
    from ..robot.detect_report import candidate_frames

    description = read_description(path, **read_options)
    check_supported(description)
    path = shown if shown is not None else path
    wheels = [c.name for c in wheel_candidates(description)]
    rows = candidate_frames(description, exclude=wheels)
    if not rows:
        moved = "beyond its wheels " if wheels else ""
        print(
            f"no candidate end-effector frames in {path}: no link {moved}is moved by an actuated joint, "
            "so the file has no arm to analyse (a base alone, or an arm with fixed joints only)."
        )
        print("To analyse a base with an arm, mount an arm's URDF on it and list the composed robot's frames:")
        print(f"  mobmanip init-spec --mount ARM.urdf --on {path} --at X,Y,Z,YAW --list-frames")
        return 0
    plural = "s" if len(rows) != 1 else ""
    print(f"{len(rows)} candidate end-effector frame{plural} of {path} (for --ee), the most likely first:")
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
