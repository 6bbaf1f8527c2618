"""``mobmanip team-carry TEAM.toml --path PATH.csv``: a team's robots carry their object along a path."""

from __future__ import annotations

import functools

from ..support.reading import decimal
from .common import (
    add_guided_command,
    add_motion_floor_options,
    add_out_dir_option,
    add_page_options,
    add_progress_option,
    add_step_options,
    add_work_option,
    motion_floor,
    print_path_warnings,
    print_self_motion,
    print_shared_start,
    registered_constraints,
    report_partial_carry,
    show_progress,
)

TEAM_CARRY_HELP = """\
TEAM.toml is a team description (as for `mobmanip team`): the robots, where they stand, their
grasps and the object. PATH.csv is the object's path as for `mobmanip carry` (header t,x,y and
optionally z, yaw; s, m, rad), relative to where the team holds the object; --frame object (the
default) reads its x axis along the object's heading, --frame world along the world's x.
--scale multiplies its positions (not its times): a path drawn for one robot, scaled to a team.

Each step solves one QP over every robot's wheel and joint rates (no platform slides sideways):
every hand follows the object, every robot's joint position, velocity and effort limits hold
(the load shared by the least-norm hand wrenches), each platform's control point follows the
object, and the team's capacity is climbed. The baseline tracks the same path with the weighted
pseudo-inverse from the team's posture. As in `carry`, the QP motion first moves to a better
posture with the object held still (--prepare seconds at most; 0: none).

--ground keeps every robot on its floor in the self-motion and the QP motion (a level floor;
--mu, --no-traction, --reserve and --zmp-margin as for `carry`): each robot's zero-moment point
stays inside its support polygon by the margin, every support stays loaded and every wheel within
friction, under the robot's own motion and what its hands push on the object with (the load's
least-norm share; the object's weight shared equally where the task leaves the vertical out). The
least margin and the largest traction use of each robot are printed for both motions (the
baseline only reads the floor).

--out DIR writes trajectory_ROBOT.csv for each robot (t, platform_x, platform_y, platform_yaw,
joints, then the team's capacity, the baseline's and the object's tracking error; a valid
input of `mobmanip trajectory`), baseline_ROBOT.csv, preparation_ROBOT.csv, team_carry.json
(the summary: capacities, tracking, lateral slip, grasp strain, efforts, limits), capacity.png
and paths.png (top view of the platforms and the object).

--export PAGE.html writes a self-contained page that plays the QP motion (the self-motion first):
every robot with its meshes at its own configuration, the object where its hands carry it and
the team's kinematic ellipsoid there (its linear part), the camera framing the whole team along
the whole motion, a legend with the scale; --every K draws every K-th sample (default: about 200
frames).

examples:
  mobmanip team-carry examples/beam_team.toml --path examples/carry_turn.csv --scale 2 --out results/
  mobmanip team-carry examples/beam_team.toml --path examples/carry_turn.csv --scale 2 --export beam.html
"""

#: QP steps times robots a team carry runs without being asked.
MAX_ROBOT_STEPS = 400_000
#: Wall time of one robot over one step, QP motion and baseline together, on the beam example (s),
#: rounded up.
SECONDS_PER_ROBOT_STEP = 3e-3
#: Time steps team-carry accepts (s), as carry's.
STEP_RANGE = (1e-3, 1.0)
#: Largest --scale (a path scaled further leaves the positions mobmanip supports).
MAX_SCALE = 1e3


def register(sub) -> None:
    parser = add_guided_command(
        sub,
        "team-carry",
        "a team's whole-body motions carrying their object along a path with the most capacity",
        "Synthesise every robot's wheel and joint motions so that a team carries its object along a "
        "path within every robot's limits while maximising the team's capacity, and compare with a "
        "pseudo-inverse baseline.",
        TEAM_CARRY_HELP,
    )
    parser.add_argument("description", metavar="TEAM.toml", help="the team description (robots, grasps, object)")
    parser.add_argument("--path", required=True, metavar="PATH.csv", help="the object's path (see below)")
    parser.add_argument(
        "--objective",
        default="kinematic:minor_axis",
        metavar="ELLIPSOID:INDEX[:DIR]",
        help="what to maximise, of the team's set (as for `carry`; default kinematic:minor_axis)",
    )
    parser.add_argument(
        "--frame", choices=("object", "world"), default="object", help="the path's axes (default: the object's)"
    )
    parser.add_argument("--scale", type=decimal, default=1.0, metavar="S", help="multiply the path's positions by S")
    add_step_options(parser)
    add_out_dir_option(parser, "one trajectory per robot, the baseline's, a summary")
    add_page_options(parser, "the team's motion (see below)")
    add_motion_floor_options(parser)
    add_work_option(parser, f"QP steps times robots (default {MAX_ROBOT_STEPS:,})")
    add_progress_option(parser)
    parser.set_defaults(func=run)


def _check(args, path, robots: int) -> None:
    """Refuse a bad step, prepare or scale and more work than the bound, before any work."""
    import math

    from ..errors import UsageError
    from ..support.work import WorkEstimate, check_work
    from ..support.work import bound as _bound

    low, high = STEP_RANGE
    if not (math.isfinite(args.step) and low <= args.step <= high):
        raise UsageError(f"--step must be between {low:g} and {high:g} s, got {args.step!r}")
    if not (math.isfinite(args.prepare) and (args.prepare == 0 or args.prepare >= args.step)):
        raise UsageError(f"--prepare must be 0 (none) or at least one step ({args.step:g} s), got {args.prepare!r} s")
    if not (math.isfinite(args.scale) and 0.0 < args.scale <= MAX_SCALE):
        raise UsageError(f"--scale must be a number in (0, {MAX_SCALE:g}], got {args.scale!r}")
    if args.every is not None and args.export is None:
        raise UsageError("--every thins the frames of --export's page: give --export PAGE.html too")
    if args.every is not None and args.every < 1:
        raise UsageError(f"--every must be a whole number of samples >= 1, got {args.every}")
    duration = float(path.t[-1] - path.t[0])
    steps = (duration + args.prepare) / args.step
    detail = f"{robots} robots x (path {duration:g} s + --prepare {args.prepare:g} s) / step {args.step:g} s"
    work = WorkEstimate("team-carry", "robot-steps", steps * robots, SECONDS_PER_ROBOT_STEP, detail)
    check_work(work, _bound(args.max_work, MAX_ROBOT_STEPS))


def run(args) -> int:
    import numpy as np

    from ..coordination.carry import team_carry
    from ..errors import CarryFailed
    from ..motion.carry import ObjectPath, read_path
    from ..support.files import check_output, note_input, output_directory, require_finite
    from ..team.members import load_team
    from .outputs import team_carry_outputs, team_carry_page, team_carry_partial_outputs, team_carry_paths
    from .team import _read_checked

    constraints, floor_args = registered_constraints(args)
    floor = motion_floor(floor_args, "team-carry")
    note_input(args.path)
    path = read_path(args.path)
    data = _read_checked(args, None)  # the robots counted against their bound before any is loaded
    robots = data.get("robots")
    _check(args, path, len(robots) if isinstance(robots, list) else 0)
    if args.scale != 1.0:
        from ..errors import UsageError
        from ..support.ranges import PLATFORM_POSITION

        z = None if path.z is None else path.z * args.scale
        path = ObjectPath(path.t, path.xy * args.scale, z, path.yaw)
        farthest = max(float(np.abs(path.xy).max()), 0.0 if z is None else float(np.abs(z).max()))
        if farthest > PLATFORM_POSITION:
            raise UsageError(
                f"--scale {args.scale:g} takes the path {farthest:.3g} m out, beyond the {PLATFORM_POSITION:g} m "
                "mobmanip supports"
            )
    team = load_team(args.description)
    if args.export:  # refuse an unwritable page before the motion is computed
        from pathlib import Path

        from ..errors import UsageError

        check_output(args.export)
        if not Path(args.export).resolve().parent.is_dir():
            raise UsageError(f"--export {args.export}: its directory does not exist")
    if args.out:  # refuse an unwritable output before the motion is computed
        out = output_directory(args.out)
        for paths in team_carry_paths(team, out).values():
            for file in paths:
                check_output(file)
    try:
        result = team_carry(
            team,
            path,
            args.objective,
            frame=args.frame,
            step=args.step,
            prepare=args.prepare,
            floor=floor,
            constraints=constraints,
            progress=show_progress(args),
        )
    except CarryFailed as failure:
        return report_partial_carry(failure, args.out, functools.partial(team_carry_partial_outputs, team))
    summary = result.summary()
    require_finite(summary)
    names = ", ".join(f"{m.name} ({m.robot.name})" for m in team.members)
    print(
        f"team {team.name}: {names}; task {result.task}; object path {path.length():.3f} m in "
        f"{path.t[-1] - path.t[0]:g} s, turning {np.degrees(path.sample(path.t[-1:])[1][0]):.1f} deg "
        f"(axes: the {args.frame}'s)"
    )
    print_self_motion(result, "the team's posture")
    for method, label, motion in (
        ("qp", "QP with capacity", result.motion),
        ("pinv", "pseudo-inverse baseline", result.baseline),
    ):
        s = summary[method]
        print(
            f"{label}: min {result.objective.name} {s['min_capacity']:.4g}, mean {s['mean_capacity']:.4g}; "
            f"max hand error {1e3 * s['max_hand_error']:.3f} mm, lateral slip {s['max_lateral_slip']:.2g} m/s, "
            f"grasp strain {1e3 * s['max_grasp_strain']:.3f} mm; efforts up to {100 * s['max_effort_share']:.1f}%, "
            f"rates up to {100 * s['max_velocity_share']:.1f}% of their limits, "
            f"{s['samples_beyond_a_joint_range']} of {len(motion.t)} samples with a joint beyond its range"
        )
    if floor is not None:
        _print_floor(summary, result.robots())
    ratio = summary["min_capacity_ratio"]
    if ratio is not None:
        print(f"min capacity ratio (QP / baseline): {ratio:.3f}")
        print_shared_start(result, summary["mean_capacity_ratio"])
    closest = summary["qp"]["min_platform_distance"]
    if closest is not None:
        print(f"platforms at least {closest:.3f} m apart (centre to centre; the QP has no collision rows)")
    if args.out:
        for written in team_carry_outputs(result, args.out):
            print(f"wrote {written}")
    if args.export:
        page, notes = team_carry_page(result, args.export, args.every)
        for note in notes:
            print(f"note: {note}")
        print(f"wrote {page}")
    print_path_warnings(path, args.step)
    return 0


def _print_floor(summary: dict, robots: tuple[str, ...]) -> None:
    """Each robot's least zero-moment point margin and largest traction use, per motion."""
    for method, label in (("qp", "QP with capacity"), ("pinv", "pseudo-inverse baseline")):
        floor = summary[method].get("floor")
        if floor is None:
            continue
        parts = []
        for name in robots:
            margin, use = floor["min_zmp_margin"][name], floor["max_traction_use"][name]
            where = f"at least {margin:.4f} m inside" if margin >= 0 else f"{-margin:.4f} m outside (it tips)"
            traction = "" if use is None else (f", traction use up to {use:.3f}" if use != "unloaded" else
                                               ", a wheel unloads")  # fmt: skip
            parts.append(f"{name} zero-moment point {where}{traction}")
        print(f"floor, {label}: " + "; ".join(parts))
