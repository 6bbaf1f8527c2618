"""``mobmanip retime ROBOT TRAJ.csv``: the fastest timing of a whole-body path, from rest to rest,
within the wheels' and joints' limits and, with ``--ground``, on the floor
(:func:`mobmanip.motion.retime.retime`)."""

from __future__ import annotations

from ..support.reading import decimal
from .common import (
    add_guided_command,
    add_motion_floor_options,
    add_object_mass_option,
    add_out_dir_option,
    add_progress_option,
    add_recording_options,
    add_robot_argument,
    add_task_option,
    add_work_option,
    check_trajectory_source,
    motion_floor,
    read_recorded,
    registered_constraints,
    show_progress,
)

RETIME_HELP = """\
TRAJ.csv is a whole-body trajectory as `mobmanip trajectory` reads it (`carry --out` writes
one), or --bag RUN a ROS recording as `mobmanip trajectory --bag` reads it; its configurations
are the path and its time stamps the path parameter s. The fastest
timing s(t) starts and ends at rest and keeps, at every sample, every wheel and joint within its
velocity and effort limits (efforts of the motion with the object held between the hands, the
paper's policy) and, with --ground, the floor of `carry --ground`: the zero-moment point
--zmp-margin inside the support polygon, every support loaded (with --reserve R: at least R of
its equal share), each driven wheel within friction (mu; --no-traction: no traction rows). The
floor covers every platform on wheels (a skid-steer's path must keep its heading). --slope DEG
(--uphill DEG) puts it on a ramp: the path's x, y and z are the ramp's own (z its normal), gravity
leans in the efforts and the floor's rows. Solved exactly
on the samples by reachability analysis (as TOPP-RA): a constant s'' between samples.

--out DIR writes retimed.csv (the path at its fastest timing, an input of `mobmanip trajectory`),
retime.json (duration, what binds where, the profile), retime.png (s' with its limit curve) and
profile.csv.

example:
  mobmanip carry tiago_dual --path examples/carry_turn.csv --object-mass 2 --ground --out carried
  mobmanip retime tiago_dual carried/trajectory.csv --object-mass 2 --ground --reserve 0.3 --out fastest
"""

#: Samples a retiming takes without being asked (each: the dynamics in motion and the floor's rows).
MAX_SAMPLES = 200_000
#: Wall time of one sample on TIAGo++ with the floor (s), rounded up.
SECONDS_PER_SAMPLE = 5e-3


def register(sub) -> None:
    parser = add_guided_command(
        sub,
        "retime",
        "the fastest timing of a whole-body path, within limits and on the floor",
        "The time-optimal timing of a whole-body path from rest to rest: every wheel and joint within "
        "its velocity and effort limits and, with --ground, the robot on its floor (no tip-over, every support "
        "loaded, traction within friction).",
        RETIME_HELP,
    )
    add_robot_argument(parser)
    parser.add_argument(
        "trajectory", metavar="TRAJ.csv", nargs="?", help="the path: a whole-body trajectory (see below), or --bag"
    )
    add_recording_options(parser)
    add_task_option(parser)
    add_object_mass_option(parser)
    parser.add_argument(
        "--stop-within",
        type=decimal,
        metavar="D",
        help="also, at every sample, the highest speed from which the robot still stops within D metres of its "
        "platform's travel along the path, on the same rows (the lowest is printed; retime.json has them all)",
    )
    add_out_dir_option(parser, "retimed.csv, retime.json, retime.png, profile.csv")
    add_motion_floor_options(parser)
    add_progress_option(parser)
    add_work_option(parser, f"samples (default {MAX_SAMPLES:,})")
    parser.set_defaults(func=run)


def run(args) -> int:
    from dataclasses import replace

    from ..motion.retime import path_rows, retime, stops_along
    from ..motion.trajectory import read_trajectory
    from ..robot.model import load_robot
    from ..robot.spec import find_spec
    from ..support.files import check_output, note_input, output_directory
    from ..support.reading import read_user_bytes
    from ..support.work import WorkBound, bound
    from .outputs import RETIME_FILES, retime_outputs

    check_trajectory_source(args)
    note_input(args.trajectory or args.bag)
    work = WorkBound("retime", "samples", SECONDS_PER_SAMPLE, bound(args.max_work, MAX_SAMPLES))
    if args.trajectory is not None:  # counted before the file is parsed
        work.check(max(read_user_bytes(args.trajectory, "trajectory").count(b"\n") - 1, 0), "rows of the trajectory")
    robot = load_robot(find_spec(args.robot))
    constraints, floor_args = registered_constraints(args)
    floor = motion_floor(floor_args, "retime")
    if args.bag is not None:  # the path as recorded: its messages counted before any is decoded
        trajectory = read_recorded(robot, args, work)
    else:
        trajectory = read_trajectory(robot, args.trajectory)
    if args.out:  # refuse an unwritable output before the timing is computed
        out = output_directory(args.out)
        for name in RETIME_FILES:
            check_output(out / name)
    rows = path_rows(robot, trajectory, args.task, object_mass=args.object_mass, floor=floor,
                     progress=show_progress(args), constraints=constraints)  # fmt: skip
    result = retime(robot, trajectory, args.task, object_mass=args.object_mass, floor=floor, rows=rows,
                    constraints=constraints)  # fmt: skip
    stops = None
    if args.stop_within is not None:
        stops = stops_along(robot, trajectory, args.stop_within, rows=rows)
        result = replace(result, stops=stops)
    before = float(result.s[-1] - result.s[0])
    floor_text = "joint limits only" if floor is None else _floor_text(floor, robot)
    print(f"robot {robot.name}, task {result.task}, {len(result.s)} samples; {floor_text}")
    print(f"fastest timing from rest to rest: {result.duration:.4g} s (the input takes {before:.4g} s)")
    print(f"what limits it: {binding_shares(result)}")
    for note in result.notes:
        print(f"note: {note}")
    if stops is not None and stops.slowest() < 0:
        print(f"to stop within {stops.within:g} m of travel: no sample has that much of the path ahead of it")
    elif stops is not None and stops.base_speed[stops.slowest()] == 0.0:
        k = stops.slowest()
        print(
            f"to stop within {stops.within:g} m of travel: not possible from any speed at sample {k} "
            f"(s = {stops.s[k]:.4g} s, {stops.distance[k]:.3g} m along): its rows leave no stop there"
        )
    elif stops is not None:
        k = stops.slowest()
        print(
            f"to stop within {stops.within:g} m of travel: at most {stops.base_speed[k]:.4g} m/s at sample {k} "
            f"(s = {stops.s[k]:.4g} s, {stops.distance[k]:.3g} m along), the lowest along the path"
        )
    if args.out:
        for written in retime_outputs(robot, result, args.out):
            print(f"wrote {written}")
    return 0


def _floor_text(floor, robot) -> str:
    mu = floor.resolve(robot)[1]
    traction = "no traction limit" if mu is None else f"traction mu {mu:g}"
    ramp = f", a ramp of {floor.slope:g} deg rising towards {floor.uphill:g} deg" if floor.slope else ""
    return (f"on the floor (zero-moment point {floor.zmp_margin:g} m inside, {traction}, reserve {floor.reserve:g}"
            f"{ramp})")  # fmt: skip


def binding_shares(result) -> str:
    """The binding rows by the share of the path's samples where each binds, largest first."""
    from collections import Counter

    counts = Counter(result.binding).most_common()
    n = len(result.binding)
    parts = [f"{label} ({100.0 * k / n:.0f} % of the samples)" for label, k in counts[:4]]
    if len(counts) > 4:
        parts.append(f"{len(counts) - 4} more")
    return "; ".join(parts)
