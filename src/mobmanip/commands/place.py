"""``mobmanip place ROBOT --object X,Y,Z --objective ...``: where the platform should stand."""

from __future__ import annotations

import argparse
import math

PLACE_HELP = """\
objective: ELLIPSOID:INDEX[:DIRECTION], ELLIPSOID kinematic or dynamic, INDEX one of
  log_volume    log of the ellipsoid's volume
  log_isotropy  log of the geometric over the arithmetic mean of the squared semi-axes (0: a ball)
  capacity      how far the set reaches along DIRECTION (from the origin: gravity's shift counts)
  minor_axis    the smallest semi-axis (worst-direction capacity about the centre)
DIRECTION is a signed task axis (+x, -z, +yaw) or components (1,1,0).

The hands keep the grasp of the reference posture (the spec's [hold], else home), turned about
the vertical; the object's centre is put at --object. Joint limits hold; --region keeps the
platform origin in a rectangle. Self-collision is not checked: look at the result with
`mobmanip view ROBOT --q Q.json` (written by --save-q).

examples:
  mobmanip place planar_dual_arm --object 1,0.5,0.35 --objective kinematic:capacity:+x
  mobmanip place tiago_dual --object 2,1,0.85 --mass 3 --objective dynamic:log_volume --json out.json
"""


def register(sub) -> None:
    parser = sub.add_parser(
        "place",
        help="optimal platform pose and arm posture holding an object at a point",
        description="Find the platform pose and arm posture that hold the object at a world point and "
        "maximise a measure (gradient-based, several starts).",
        epilog=PLACE_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("robot", help="built-in robot name or path of a robot spec (.toml)")
    parser.add_argument("--object", required=True, metavar="X,Y,Z", help="object centre in the world (m)")
    parser.add_argument("--objective", required=True, metavar="ELLIPSOID:INDEX[:DIR]", help="what to maximise")
    parser.add_argument("--mass", type=float, metavar="KG", help="object mass (default: the spec's)")
    parser.add_argument("--task", help="task space (default: the spec's default_task)")
    parser.add_argument("--region", metavar="XMIN,XMAX,YMIN,YMAX", help="rectangle for the platform origin (m)")
    parser.add_argument("--starts", type=int, default=8, help="number of starts (default 8)")
    parser.add_argument("--decoupled", action="store_true", help="neglect platform-arm dynamic interaction")
    parser.add_argument(
        "--posture",
        metavar="NAME",
        help="the posture whose grasp the hands keep: home, hold or a [postures.NAME] of the spec "
        "(default: hold where the spec gives one, else home)",
    )
    parser.add_argument("--json", metavar="OUT.json", help="write the result and its analysis as JSON")
    parser.add_argument("--save-q", metavar="Q.json", help="write the configuration for `analyze --q`")
    parser.set_defaults(func=run)


def _parse_point(text: str):
    from ..errors import UsageError

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise UsageError(f"--object must be X,Y,Z in metres, got {text!r}") from None
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise UsageError(f"--object must be three finite numbers X,Y,Z in metres, got {text!r}")
    return values


def run(args) -> int:
    from ..analysis import analyze
    from ..io import write_json
    from ..model import load_robot
    from ..named_postures import named_configuration
    from ..placement import Region, place, placement_document
    from ..spec import find_spec
    from .common import print_warnings

    robot = load_robot(find_spec(args.robot))
    target = _parse_point(args.object)
    reference = None if args.posture is None else named_configuration(robot, args.posture)
    region = None if args.region is None else Region.parse(args.region)
    result = place(
        robot,
        target,
        args.objective,
        args.task,
        object_mass=args.mass,
        decoupled=args.decoupled,
        region=region,
        starts=args.starts,
        reference=reference,
    )
    x, y, heading = result.platform
    print(f"robot {robot.name}: object at ({target[0]:g}, {target[1]:g}, {target[2]:g}) m, {result.objective.name}")
    print(f"platform: x {x:.4f} m, y {y:.4f} m, heading {math.degrees(heading):.2f} deg")
    joints = robot.configuration_dict(result.q)["joints"]
    print("joints: " + ", ".join(f"{name} {value:.4f}" for name, value in joints.items()))
    print(f"{result.objective.name} = {result.value:.6g}")
    if result.start_value is not None:
        print(f"best start (reference hold placed at the object): {result.start_value:.6g}")
    print(
        f"{result.evaluations} measure evaluations, {len(result.runs)} starts, hold error {result.residual:.1e}, "
        f"{result.seconds:.2f} s"
    )
    if args.save_q:
        write_json(args.save_q, robot.configuration_dict(result.q))
        print(f"wrote {args.save_q}")
    if args.json:
        analysis = analyze(  # as `mobmanip analyze` computes it: the reference path
            robot, result.q, args.task, object_mass=args.mass, decoupled=args.decoupled, method="exact"
        )
        write_json(args.json, placement_document(robot, result, analysis))
        print_warnings(analysis)
        print(f"wrote {args.json}")
    return 0
