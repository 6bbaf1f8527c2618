"""``mobmanip trajectory ROBOT TRAJ.csv``: both measures, demands and the time-scaling margin along a motion."""

from __future__ import annotations

import math
import sys

import numpy as np

from ..support.reading import decimal
from .common import (
    add_constraint_options,
    add_guided_command,
    add_object_mass_option,
    add_out_dir_option,
    add_page_options,
    add_progress_option,
    add_recording_options,
    add_robot_argument,
    add_strict_option,
    add_task_option,
    add_work_option,
    check_trajectory_source,
    read_recorded,
    registered_constraints,
    show_progress,
)

#: Samples a trajectory analysis runs without being asked (each: both ellipsoids, RNEA, scaling).
MAX_SAMPLES = 200_000
#: Wall time of one sample on the paper's robot (s), rounded up (with --polytope: ten times).
SECONDS_PER_SAMPLE = 3e-3

TRAJECTORY_HELP = """\
TRAJ.csv has a header: t (s), platform_x, platform_y (m), platform_yaw (rad), then one column
per moving joint named as in q.json; joints without a column stay at home (wheels without a
column turn as the platform's motion needs). Rates and accelerations are estimated from the
samples; `slip` reports motion the platform cannot make (lateral sliding).

--bag RUN reads a ROS recording instead (ROS 1 .bag, ROS 2 .mcap / .db3 or a ROS 2 bag folder;
no ROS install needed): the joint states (sensor_msgs/JointState) and the odometry
(nav_msgs/Odometry, the pose of the robot's root link) are resampled onto the joint states'
stamps, the odometry interpolated; --start / --end (s from the recording's start) cut it. Gaps,
clock jumps and NaN or infinite values (dropped) are reported as warnings. The joint-state
messages are counted before any is decoded and held to --max-work like a file's rows.

time-scaling margin: the largest factor k by which the whole motion can be sped up with every
wheel and joint within its velocity and effort limits (efforts: RNEA in motion, the object
carried by the hands with the paper's policy). A registered constraint option (e.g. one a
contributor adds) joins it: its rows over the motion run k times faster, named where it decides.

example:
  mobmanip trajectory tiago_dual motion.csv --out results/ --export motion.html
"""


def register(sub) -> None:
    parser = add_guided_command(
        sub,
        "trajectory",
        "measures, demands and time-scaling margin along a whole-body trajectory",
        "Analyse a time-stamped whole-body trajectory: per sample the kinematic and the in-motion "
        "dynamic ellipsoid, the object's velocity and acceleration against them, efforts against limits, and "
        "by how much the motion could be sped up.",
        TRAJECTORY_HELP,
    )
    add_robot_argument(parser)
    parser.add_argument("trajectory", metavar="TRAJ.csv", nargs="?", help="the trajectory (see below), or --bag")
    add_recording_options(parser)
    add_task_option(parser)
    add_object_mass_option(parser)
    parser.add_argument("--decoupled", action="store_true", help="neglect platform-arm dynamic interaction")
    parser.add_argument(
        "--polytope",
        action="store_true",
        help="also the exact kinematic polytope's reach along the object's velocity (slower)",
    )
    parser.add_argument(
        "--ground",
        action="store_true",
        help="also the floor under the motion: the zero-moment point and its margin to the support polygon per "
        "sample, every contact's normal force (compliant sharing) and every driven wheel's traction use "
        "tangential / (mu x normal force) (columns zmp_x, zmp_y, stability_margin, normal_force_C, "
        "traction_use_W; the smallest margin and the largest use printed; a wheel that slips or a support that "
        "unloads warned about)",
    )
    parser.add_argument(
        "--mu",
        type=decimal,
        metavar="MU",
        help="with --ground: friction coefficient of the driven wheels (implies --ground; default: the spec's "
        "[support] mu, else 0.5)",
    )
    add_out_dir_option(parser, "analysis.csv, analysis.json and analysis.png there")
    add_strict_option(parser)
    add_page_options(parser, "the motion with its ellipsoids (in motion) moving along")
    add_constraint_options(parser)
    add_progress_option(parser)
    add_work_option(parser, f"samples (rows of TRAJ.csv, or joint-state messages of --bag; default {MAX_SAMPLES:,})")
    parser.set_defaults(func=run)


def _sample_bound(args):
    """The bound on the samples analysed (--max-work, else :data:`MAX_SAMPLES`)."""
    from ..support.work import WorkBound, bound

    each = SECONDS_PER_SAMPLE * (10 if args.polytope else 1)
    return WorkBound("trajectory", "samples", each, bound(args.max_work, MAX_SAMPLES))


def _check_work(args) -> None:
    """Count the samples (lines) before the file is parsed, and refuse more than the bound; a
    recording's joint-state messages are counted by
    :func:`~mobmanip.commands.common.read_recorded` before any is decoded."""
    from pathlib import Path

    from ..errors import UsageError
    from ..support.reading import read_user_bytes

    work = _sample_bound(args)
    if work.limit < 1:
        raise UsageError(f"--max-work must be at least 1, got {work.limit}")
    if args.trajectory is None:
        return
    lines = read_user_bytes(args.trajectory, "trajectory").count(b"\n")
    work.check(max(lines - 1, 0), f"rows of {Path(args.trajectory).name}")


def _report_floor_scaling(robot, trajectory, ground, args, scaling):
    """The time-scaling margin the floor allows, printed beside the limits' own with the one that
    holds both; returned (:class:`mobmanip.motion.traction.FloorScaling`)."""
    from ..motion.traction import floor_time_scaling

    floor = floor_time_scaling(robot, trajectory, ground, args.mu, object_mass=args.object_mass)
    if floor.k_max is None:
        print("time-scaling margin on the floor: unbounded (the floor's forces do not change with the speed)")
        return floor
    print(
        f"time-scaling margin on the floor {floor.k_max:.6g} (decided by {floor.limit} at sample {floor.sample}: "
        "the zero-moment point inside the support polygon, every support loaded, every wheel within friction)"
    )
    if scaling.feasible and scaling.k_max is not None:
        both = min(floor.k_max, scaling.k_max)
        which = "the floor" if floor.k_max <= scaling.k_max else f"the {scaling.limit} limit"
        print(f"time-scaling margin, limits and floor together {both:.6g} (decided by {which})")
    return floor


def _report_traction(traction, trajectory) -> None:
    """The largest traction use printed; a wheel that slips and a support that unloads warned about."""
    i, k = traction.worst()
    use = traction.use[i, k]
    print(
        f"largest traction use {use:.4f} ({traction.wheels[k]} at sample {i}, t = {trajectory.t[i]:g} s; "
        f"mu = {traction.mu:g}, compliant load sharing)"
    )
    worst = f"; the worst {traction.wheels[k]} at sample {i} (t = {trajectory.t[i]:g} s)"
    # (what happens, at which samples, who: names and the amount per sample, the one picked, its unit)
    for what, found, names, amounts, pick, unit, tail in (
        ("a driven wheel slips (traction use above 1)", traction.slipping(), traction.wheels, traction.use,
         np.argmax, "use {:.4g}", worst),
        ("a support unloads (normal force 0 or less with the contacts equally stiff)", traction.unloaded(),
         traction.contacts, traction.normal, np.argmin, "{:.4g} N", ""),
    ):  # fmt: skip
        if found.size:
            j = int(found[0])
            c = int(pick(amounts[j]))
            print(
                f"warning: {what} at {found.size} of {len(trajectory)} samples: first {names[c]} at sample {j} "
                f"(t = {trajectory.t[j]:g} s, {unit.format(amounts[j, c])}){tail}",
                file=sys.stderr,
            )


def run(args) -> int:
    from ..errors import UsageError
    from ..motion.trajectory import read_trajectory
    from ..motion.trajectory_analysis import analyze_trajectory
    from ..robot.model import load_robot
    from ..robot.spec import find_spec
    from ..support.files import check_output, note_input, output_directory
    from .outputs import trajectory_outputs

    constraints, _ = registered_constraints(args)
    check_trajectory_source(args)
    if args.mu is not None:
        if not (math.isfinite(args.mu) and args.mu > 0.0):
            raise UsageError(f"--mu must be a positive friction coefficient, got {args.mu!r}")
        args.ground = True
    note_input(args.trajectory or args.bag)
    _check_work(args)
    if args.out:  # refuse an unwritable output before the analysis runs
        out = output_directory(args.out)
        for suffix in (".csv", ".json", ".png"):
            check_output(out / f"analysis{suffix}")
    robot = load_robot(find_spec(args.robot), strict=True if args.strict else None)
    if args.ground:  # before the analysis is printed
        from ..terms.constraints.floor import check_floor_platform

        check_floor_platform(robot.name, robot.platform.kind)
    if args.bag is not None:
        trajectory = read_recorded(robot, args, _sample_bound(args))
    else:
        trajectory = read_trajectory(robot, args.trajectory)
    result = analyze_trajectory(
        robot,
        trajectory,
        args.task,
        object_mass=args.object_mass,
        decoupled=args.decoupled,
        polytope=args.polytope,
        progress=show_progress(args),
        constraints=constraints,
    )
    s = result.scaling
    duration = trajectory.t[-1] - trajectory.t[0]
    print(f"robot {robot.name}, task {result.task}: {len(trajectory)} samples over {duration:g} s")
    print(f"largest velocity use {result.velocity_use.max():.4f}, largest effort use {result.effort_use.max():.4f}")
    print(f"largest platform slip {trajectory.slip.max():.2e}")
    print(
        f"smallest velocity capacity along v_o {result.velocity_capacity.min():.4g}, "
        f"acceleration capacity along a_o {result.acceleration_capacity.min():.4g}"
    )
    if result.impulsive.size:
        times = ", ".join(f"{trajectory.t[i]:.6g}" for i in result.impulsive[:8])
        more = f" and {result.impulsive.size - 8} more" if result.impulsive.size > 8 else ""
        print(
            f"warning: the object's acceleration is impulsive at {result.impulsive.size} of {len(trajectory)} samples "
            f"(t = {times}{more} s): it jumps between samples (e.g. a path interpolated linearly), so the efforts "
            "and the time-scaling margin there come from those jumps",
            file=sys.stderr,
        )
    if result.velocity_polytope_capacity is not None:
        print(f"smallest kinematic polytope reach along v_o {result.velocity_polytope_capacity.min():.4g}")
    if not s.feasible:
        print("time-scaling margin: none (gravity alone breaks an effort limit)")
    elif s.k_max is None:
        print("time-scaling margin: unbounded (the motion stands still)")
    else:
        print(f"time-scaling margin {s.k_max:.6g} (decided by the {s.limit} limit at sample {s.sample})")
        if s.k_min > 0.0:
            print(f"slowest feasible speed-up {s.k_min:.6g}")
    ground = traction = floor_scaling = None
    if args.ground:
        from ..motion.ground import ground_along
        from ..motion.traction import traction_along

        ground = ground_along(robot, trajectory, result.object_acceleration, result.task, object_mass=args.object_mass)
        k = ground.worst()
        tipping = " (outside the support: the robot tips)" if ground.margin[k] < 0 else ""
        print(
            f"smallest stability margin {ground.margin[k]:.4f} m{tipping} at sample {k} (t = {trajectory.t[k]:g} s), "
            f"zero-moment point ({ground.zmp[k, 0]:.3f}, {ground.zmp[k, 1]:.3f}) m"
        )
        from ..errors import SpecError

        try:
            traction = traction_along(ground, trajectory, args.mu)
        except SpecError as exc:  # e.g. more than two driven wheels: the margin stands, the traction is left out
            print(f"traction per wheel: not computed ({exc})")
        else:
            _report_traction(traction, trajectory)
            floor_scaling = _report_floor_scaling(robot, trajectory, ground, args, s)
    if args.out:
        for path in trajectory_outputs(robot, result, args.out, ground=ground, traction=traction,
                                       floor_scaling=floor_scaling):  # fmt: skip
            print(f"wrote {path}")
    if args.export:
        from ..viz.trajectory_page import export_trajectory_page

        page = export_trajectory_page(
            robot, trajectory, args.export, result.task, every=args.every, object_mass=args.object_mass,
            decoupled=args.decoupled,
        )  # fmt: skip
        print(f"wrote {page}")
    return 0
