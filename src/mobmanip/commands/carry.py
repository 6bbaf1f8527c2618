"""``mobmanip carry ROBOT --path PATH.csv``: a whole-body motion that carries the object along a path."""

from __future__ import annotations

import functools

from .common import (
    add_guided_command,
    add_motion_floor_options,
    add_object_mass_option,
    add_out_dir_option,
    add_page_options,
    add_progress_option,
    add_robot_argument,
    add_step_options,
    add_task_option,
    add_work_option,
    motion_floor,
    print_path_warnings,
    print_self_motion,
    print_shared_start,
    registered_constraints,
    report_partial_carry,
    show_progress,
)

CARRY_HELP = """\
PATH.csv has a header t,x,y and optionally z, yaw: the object's path (s, m, rad), relative to
where the start posture holds it (the first row is where it starts). Without yaw the object
turns with the path's direction of travel.

Each step solves a QP over the wheel and joint rates (the platform cannot slide sideways):
the hands follow the object, joint position, velocity and effort limits hold, and the objective's
gradient is climbed: an ellipsoid's in closed form, any other measure's reading (as for `place`:
MEASURE:READING:DIRECTION) by central differences checked at two steps, 4 nv + 1 sets a step
(tens of milliseconds a step on the robots shipped here). The baseline tracks the same path with
the weighted pseudo-inverse. Before the path, the QP motion first moves to a better posture holding the object where it
is (a self-motion: the same QP with the object held still, until the objective stops rising
or for at most --prepare seconds); the path's motion starts there, the baseline starts from
the start posture and is run again from the QP's prepared start, so that the ratio of minima
splits into what the preparation gives and what the motion gives. A ratio whose baseline's set
collapses (a singular posture) is not given. --prepare 0 starts both from the start posture.

--ground (--mu MU, --no-traction, --reserve R, --zmp-margin M) keeps the robot on its floor: at
every step of the QP motion (and of the self-motion) the zero-moment point stays M metres (default
0.02) inside the support polygon, every wheel and caster stays loaded (the contacts share the
load as equally stiff springs) and, unless --no-traction, each driven wheel's traction stays in
its friction pyramid (mu: the spec's [support] mu, else 0.5). These are rows of the QP, exact for
the step's floor wrench with the velocity terms at the previous step's rates; a step they make
infeasible is reported with the floor's row that binds. The baseline ignores the floor. Check a
result with `mobmanip trajectory OUT/trajectory.csv --ground --mu MU`. --slope DEG (--uphill DEG)
puts the floor on a ramp: the path's x, y and z are the ramp's own (z its normal) and gravity
leans in the QP motion's efforts and floor rows (the objective and the baseline are as on a
level floor; `trajectory --ground` checks a level floor only).

A constraint option registered in Python (mobmanip.terms.constraints.options, e.g. a share of
the effort limits) is kept at every step of the QP motion, its rows written over the step's
rates (and --fastest keeps it at every sample); the baseline ignores it.

--out DIR writes trajectory.csv (t, platform_x, platform_y, platform_yaw, one column per joint
as in q.json, then capacity, baseline_capacity, tracking_error), baseline.csv (the baseline's
motion), preparation.csv (the self-motion), carry.json (summary, with what each run started
from) and capacity.png (the capacity profiles). trajectory.csv is a
valid input of `mobmanip trajectory`. --export PAGE.html writes a self-contained page that plays
the QP motion (the self-motion first) with its kinematic and in-motion dynamic ellipsoids; the
camera follows the robot when it drives off (--every K draws every K-th sample).

examples:
  mobmanip carry planar_dual_arm --path examples/carry_turn.csv --out results/
  mobmanip carry tiago_dual --path examples/carry_line.csv --objective dynamic:minor_axis
  mobmanip carry tiago_dual --path examples/carry_turn.csv --export carry.html
"""


def register(sub) -> None:
    parser = add_guided_command(
        sub,
        "carry",
        "whole-body motion carrying the object along a path with the most capacity",
        "Synthesise wheel and joint motions that carry the held object along a path while "
        "maximising a measure, and compare with a pseudo-inverse baseline.",
        CARRY_HELP,
    )
    add_robot_argument(parser)
    parser.add_argument("--path", required=True, metavar="PATH.csv", help="the object's path (see below)")
    parser.add_argument(
        "--objective",
        default="kinematic:minor_axis",
        metavar="ELLIPSOID:INDEX[:DIR|:BLOCK]",
        help="what to maximise (as for `place`, e.g. dynamic:minor_axis:linear, or any other measure's reading "
        "MEASURE:READING:DIRECTION such as force_polytope:support:-z; default kinematic:minor_axis)",
    )
    add_task_option(parser)
    parser.add_argument("--start", metavar="Q.json", help="start configuration (default: the spec's hold posture)")
    add_object_mass_option(parser)
    add_step_options(parser)
    add_out_dir_option(parser, "trajectory.csv, baseline.csv, carry.json, capacity.png")
    add_page_options(
        parser, "the QP motion (the self-motion first) with its in-motion ellipsoids, the camera following the robot"
    )
    add_progress_option(parser)
    add_motion_floor_options(parser)
    parser.add_argument(
        "--fastest",
        action="store_true",
        help="also the fastest timing of the QP motion's path, rest to rest, within the limits and on the same floor "
        "(as `mobmanip retime`); with --out it writes fastest.csv, fastest.json, fastest.png, fastest_profile.csv",
    )
    add_work_option(parser, f"QP steps ((path duration + --prepare) / --step; default {MAX_STEPS:,})")
    parser.set_defaults(func=run)


#: QP steps (of the path and of the self-motion before it) a carry runs without being asked.
MAX_STEPS = 200_000
#: Wall time of one step, QP motion and baseline together, on the paper's robot (s), rounded up.
SECONDS_PER_STEP = 2.5e-3
#: The same with a measure's reading as the objective (its gradient by differences, 4 nv + 1 sets
#: a step): 33 ms measured on the paper robot's dynamic polytope (carry_turn.csv), rounded up.
SECONDS_PER_READING_STEP = 0.04
#: Time steps carry accepts (s): at 2e-4 s the QP of the paper robot's example path already fails
#: at its first step (rounding in the rate constraints); 5e-4 s is the smallest step checked to work.
STEP_RANGE = (1e-3, 1.0)


def _check_work(args, path) -> None:
    """Refuse a step outside :data:`STEP_RANGE` and more than the bound of QP steps, before any work."""
    import math

    from ..errors import UsageError
    from ..support.work import WorkEstimate, check_work
    from ..support.work import bound as _bound

    low, high = STEP_RANGE
    if not (math.isfinite(args.step) and low <= args.step <= high):
        raise UsageError(f"--step must be between {low:g} and {high:g} s, got {args.step!r}")
    if not (math.isfinite(args.prepare) and (args.prepare == 0 or args.prepare >= args.step)):
        raise UsageError(f"--prepare must be 0 (none) or at least one step ({args.step:g} s), got {args.prepare!r} s")
    duration = float(path.t[-1] - path.t[0])
    steps = (duration + args.prepare) / args.step
    detail = f"path {duration:g} s + --prepare {args.prepare:g} s, step {args.step:g} s"
    from ..gradients.readings import is_reading_objective

    if args.every is not None and args.export is None:
        raise UsageError("--every thins the frames of --export's page: give --export PAGE.html too")
    if args.every is not None and args.every < 1:
        raise UsageError(f"--every must be a whole number of samples >= 1, got {args.every}")
    if args.export is not None:  # refuse an unwritable page before the motion is computed
        from pathlib import Path

        from ..support.files import check_output

        check_output(args.export)
        if not Path(args.export).resolve().parent.is_dir():
            raise UsageError(f"--export {args.export}: its directory does not exist")
    per_step = SECONDS_PER_READING_STEP if is_reading_objective(args.objective) else SECONDS_PER_STEP
    check_work(WorkEstimate("carry", "QP steps", steps, per_step, detail), _bound(args.max_work, MAX_STEPS))


def print_ratio(label: str, ratio: float | None) -> None:
    print(f"{label}: " + ("not given (its baseline's set has collapsed)" if ratio is None else f"{ratio:.3f}"))


def objective_unit_text(result) -> str:
    """`` m/s`` (a space and the objective's unit, plain text) or nothing for a dimensionless or
    logarithmic one."""
    from ..measures import get_measure

    objective = result.objective
    if objective.index in ("log_volume", "log_isotropy"):
        return ""
    quantity = get_measure(objective.measure_name).quantity
    from ..robot.tasks import get_task

    space = get_task(result.task)
    rows = objective.rows
    if rows is None and objective.direction is not None:
        rows = [i for i, v in enumerate(objective.direction) if v != 0.0]
    rows = range(space.dim) if rows is None else rows
    linear, _, angular = quantity.units.partition(", ")
    kinds = {bool(space.angular[i]) for i in rows}
    if kinds == {False}:
        return f" {linear}"
    if kinds == {True}:
        return f" {angular or linear}"
    return f" ({quantity.units} mixed)"


def run(args) -> int:
    from ..errors import CarryFailed
    from ..motion.carry import carry, read_path
    from ..robot.configurations import read_configuration
    from ..robot.model import load_robot
    from ..robot.spec import find_spec
    from ..support.files import check_output, note_input, output_directory
    from .outputs import CARRY_FASTEST_FILES, CARRY_FILES, carry_outputs, carry_partial_outputs

    note_input(args.path)
    robot = load_robot(find_spec(args.robot))
    path = read_path(args.path)
    _check_work(args, path)
    start = read_configuration(robot, args.start) if args.start else None
    constraints, floor_args = registered_constraints(args)
    floor = motion_floor(floor_args, "carry")
    if floor is not None:  # before the kernels are compiled
        from ..terms.constraints.floor import check_floor_platform

        check_floor_platform(robot.name, robot.platform.kind)
    if args.out:  # refuse an unwritable output before the motion is computed
        out = output_directory(args.out)
        for name in CARRY_FILES + (CARRY_FASTEST_FILES if args.fastest else ()):
            check_output(out / name)
    try:
        result = carry(
            robot,
            path,
            args.objective,
            args.task,
            start=start,
            object_mass=args.object_mass,
            step=args.step,
            prepare=args.prepare,
            progress=show_progress(args),
            floor=floor,
            constraints=constraints,
        )
    except CarryFailed as failure:
        return report_partial_carry(failure, args.out, functools.partial(carry_partial_outputs, robot))
    summary = result.summary()
    print(f"robot {robot.name}, task {result.task}: {path.length():.3f} m in {path.t[-1] - path.t[0]:g} s")
    print_self_motion(result, "the start posture")
    labels = {
        "qp": "QP with capacity",
        "pinv": "pseudo-inverse baseline from the start posture",
        "pinv_prepared": "pseudo-inverse baseline from the QP's prepared start",
    }
    unit = objective_unit_text(result)
    for key, label in labels.items():
        if key not in summary:
            continue
        s = summary[key]
        print(
            f"{label}: min {result.objective.name} {s['min_capacity']:.4g}{unit}, mean {s['mean_capacity']:.4g}, "
            f"max tracking error {1e3 * s['max_tracking_error']:.3f} mm"
        )
    for key, value in summary["collapsed"].items():
        print(
            f"{labels[key]}: its set has collapsed at its minimum (a singular posture: smallest semi-axis "
            f"{value['smallest_semi_axis']:.2g} of {value['largest_semi_axis']:.3g}); no ratio to it is given"
        )
    print_ratio("min capacity ratio, QP / baseline from the start posture", summary["min_capacity_ratio"])
    print_shared_start(result, summary["mean_capacity_ratio"])
    parts = summary.get("ratio_parts")
    if parts is not None:
        print_ratio("  of which the preparation gives (baseline from the prepared start / from the start posture)",
                     parts["preparation"])  # fmt: skip
        print_ratio("  and the motion gives (QP / baseline from the prepared start)", parts["motion"])
    fastest = _fastest(robot, result, args, floor, constraints) if args.fastest else None
    if args.out:
        for written in carry_outputs(robot, result, args.out):
            print(f"wrote {written}")
        if fastest is not None:
            from .outputs import retime_outputs

            for written in retime_outputs(robot, fastest, args.out, CARRY_FASTEST_FILES):
                print(f"wrote {written}")
    if args.export:
        from ..viz.trajectory_page import export_carry_page

        page = export_carry_page(robot, result, args.export, every=args.every, object_mass=args.object_mass)
        print(f"wrote {page}")
    print_path_warnings(path, args.step)
    return 0


def _fastest(robot, result, args, floor, constraints=()):
    """The QP motion's path at its fastest timing (:func:`mobmanip.motion.retime.retime`), printed."""
    from ..motion.retime import retime
    from ..motion.trajectory import trajectory_from_samples
    from .retime import binding_shares

    motion = result.motion
    path = trajectory_from_samples(robot, motion.t, motion.q)
    fastest = retime(robot, path, result.task, object_mass=args.object_mass, floor=floor, constraints=constraints)
    where = "on the same floor" if floor is not None else "within the limits (no floor: --ground keeps it)"
    print(
        f"fastest timing of the QP motion's path, rest to rest, {where}: {fastest.duration:.4g} s "
        f"(the QP motion takes {float(motion.t[-1] - motion.t[0]):.4g} s); limited by {binding_shares(fastest)}"
    )
    for note in fastest.notes:
        print(f"note: {note}")
    return fastest
