"""``mobmanip referee ROBOT``: replay the grounded maxima in MuJoCo (``pip install 'mobmanip[referee]'``).

For each task axis, both senses, the efforts of the grounded straight-line maximum (``analyze
--ground``'s reach, or ``--fraction`` of it) are applied from rest to MuJoCo's model of the robot
standing on the floor with the object held (:mod:`mobmanip.referee`). Per axis: the predicted
reach; MuJoCo's acceleration at t = 0 against the predicted one (largest error on the task's
rows, % of its norm); each contact's normal force predicted and MuJoCo's (the largest difference,
% of the weight); over ``--duration`` how far a support rose and how fast a driven wheel slid.
Exit status 0 when every axis agrees and holds, 1 when one does not, 2 for bad input.

MuJoCo's weld keeps the object level, so the analysis replayed holds it level too
(``Floor(level=True)``, as ``--level``). ``--held`` replays instead the reach that mobmanip's own
replay holds for ``--duration`` (``analyze --hold``), ``--longest`` the efforts that hold
``--fraction`` of each maximum longest, with mobmanip's predicted hold time beside MuJoCo's (the
axis passes when MuJoCo holds at least 90 % of it).
"""

from __future__ import annotations

import math

from ..support.reading import decimal
from .common import add_floor_options, add_json_option, add_object_mass_option, add_robot_options

#: MuJoCo's friction coefficient of the driven wheels when the floor does not limit traction.
UNLIMITED_FRICTION = 10.0
#: --longest: MuJoCo holds the efforts at least this share of mobmanip's predicted time.
HOLD_SHARE = 0.9


def register(sub) -> None:
    parser = sub.add_parser(
        "referee",
        help="replay the grounded maxima in MuJoCo (needs mobmanip[referee])",
        description="Replay each grounded straight-line maximum in MuJoCo and judge it. Exit status: 0 when every "
        "replayed axis agrees and holds, 1 when one does not, 2 for bad input.",
    )
    add_robot_options(parser)
    add_object_mass_option(parser)
    add_floor_options(parser)
    parser.add_argument(
        "--fraction", type=decimal, default=1.0, help="share of each maximum replayed, in (0, 1] (default 1)"
    )
    parser.add_argument(
        "--duration", type=decimal, default=0.02, help="how long the efforts are held, in (0, 1] s (default 0.02)"
    )
    parser.add_argument(
        "--grasp",
        choices=("weld", "point", "level"),
        help="how MuJoCo holds the object: welded to the hands; each hand pinned at the object's centre; or held "
        "level, the hands free to turn about the vertical and the object never turning about it (default: level "
        "for a task without rotations, else welded)",
    )
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument(
        "--held",
        action="store_true",
        help="replay, per axis, the reach mobmanip's own replay holds for --duration (analyze --hold)",
    )
    mode.add_argument(
        "--longest",
        action="store_true",
        help="replay, per axis, the efforts that hold --fraction of the maximum longest, and compare how long "
        "they hold in MuJoCo with mobmanip's prediction",
    )
    add_json_option(parser, "every axis's numbers")
    parser.set_defaults(func=run)


def _import_referee():
    """:mod:`mobmanip.referee`, or the one-line reason it cannot be used."""
    from ..errors import MobmanipError

    try:
        from .. import referee
    except ImportError as exc:
        if exc.name is not None and exc.name.split(".")[0] != "mujoco":
            raise
        raise MobmanipError("the referee needs MuJoCo: pip install 'mobmanip[referee]'") from None
    return referee


def run(args) -> int:
    referee_package = _import_referee()
    import dataclasses

    from ..analysis.single import analyze
    from ..errors import ArgumentError, MobmanipError
    from ..robot.tasks import get_task
    from ..support.files import require_finite, write_json
    from ..terms.constraints.floor import Floor
    from .common import floor_constraints, load_robot_and_configuration, print_warnings

    for value, name in ((args.fraction, "--fraction"), (args.duration, "--duration")):
        if not (math.isfinite(value) and 0.0 < value <= 1.0):
            raise ArgumentError(f"{name} must be in (0, 1]{' s' if name == '--duration' else ''}, got {value!r}")
    robot, q = load_robot_and_configuration(args)
    referee_package.check_representable(robot)
    task = args.task or robot.spec.default_task
    # MuJoCo's weld holds the object level: so does the analysis replayed
    floor = dataclasses.replace((floor_constraints(args) or (Floor(),))[0], level=True)
    if (args.held or args.longest) and floor.slope:
        raise ArgumentError("--held and --longest replay mobmanip's own model on a level floor: leave out --slope")
    default = analyze(robot, q, task, object_mass=args.object_mass, measures=("kinematic",)).held_object
    held_object = referee_package.object_for_referee(default)
    if (args.held or args.longest) and held_object is not default:
        raise ArgumentError(
            "--held and --longest replay mobmanip's own model, where a one-hand object is a point mass, which "
            "MuJoCo cannot hold: replay the maxima without them"
        )
    analysis = analyze(robot, q, task, held_object=held_object, measures=("dynamic_polytope",), constraints=(floor,))
    grounded = analysis.measures["dynamic_polytope"]
    if grounded.empty:
        raise MobmanipError("nothing to replay: the grounded set is empty (" + "; ".join(analysis.warnings) + ")")
    info = getattr(grounded, "model", {})["floor"]
    mu = UNLIMITED_FRICTION if info["mu"] is None else float(info["mu"])
    grasp = args.grasp or ("weld" if get_task(task).angular_rows else "level")
    try:
        referee = referee_package.build(
            robot, q, contacts=referee_package.contacts_of_floor(info), object=held_object, grasp=grasp, mu=mu,
            gravity=info.get("gravity"),
        )  # fmt: skip
    except ValueError as exc:  # the robot's file disagrees with its model (MuJoCo's own complaints too)
        raise MobmanipError(f"MuJoCo's model of {robot.name} cannot be built: {exc}") from None

    if args.held or args.longest:
        axes = _replay_held(referee_package, referee, robot, q, grounded, task, args, floor, held_object.mass)
    else:
        axes = referee_package.replay_maxima(referee, grounded, task, fraction=args.fraction, duration=args.duration)
    document = _document(robot, task, info, referee, axes, args, held_object)
    require_finite(document)
    _print(robot, task, info, axes, args, referee_package)
    print_warnings(analysis)
    if args.json:
        write_json(args.json, document)
        print(f"wrote {args.json}")
    failed = [a.axis for a in axes if not _passed(a, args)]
    return 1 if failed else 0


def _replay_held(referee_package, referee, robot, q, grounded, task, args, floor, mass):
    """--held / --longest: per axis the efforts mobmanip's own replay finds (analyze --hold)."""
    from ..motion.hold import held_reach

    out = []
    for axis, e in referee_package.axis_directions(task):
        reach = float(grounded.straight_line_reach(e))
        found = None
        if reach > 0.0:
            found = held_reach(robot, q, grounded, e, task, object_mass=mass,
                               floor=floor, duration=args.duration, fraction=args.fraction)  # fmt: skip
        if found is None or (args.held and (found.witness is None or found.reach <= 0.0)):
            out.append(referee_package.AxisReplay(axis, e, 0.0 if found is not None else reach, None))
            continue
        if args.held:
            reach, target, witness = found.reach, found.reach * e, found.witness
        else:
            target, witness = args.fraction * reach * e, found.instant_witness
        replay = referee_package.replay_axis(referee, grounded, task, axis, e, reach, target, witness,
                                             duration=args.duration)  # fmt: skip
        if args.longest:
            replay.extra["predicted_hold"] = float(found.instant_hold.held)
            replay.extra["mujoco_hold"] = _mujoco_hold(referee, witness, args.duration, referee_package)
        out.append(replay)
    return out


def _mujoco_hold(referee, witness, duration, referee_package) -> float:
    """How long MuJoCo holds the efforts: its last sample before a support first rises or a
    driven wheel first slides (``duration`` if neither happens)."""
    import numpy as np

    run = referee.rollout(witness.variables["tau"], duration=duration)
    driven = [k for k, s in enumerate(run.supports) if s.driven]
    bad = -run.penetration.min(axis=1) > referee_package.RISE
    if driven:
        bad |= run.slip_speed[:, driven].max(axis=1) > referee_package.SLIDE
    gave = np.flatnonzero(bad)
    return duration if len(gave) == 0 else float(run.time[max(gave[0] - 1, 0)])


def _passed(axis, args) -> bool:
    if args.longest and axis.replayed:
        return axis.agrees and axis.extra["mujoco_hold"] >= HOLD_SHARE * axis.extra["predicted_hold"]
    return axis.passed


def _print(robot, task, info, axes, args, referee_package) -> None:
    if args.held:
        what = "the reach mobmanip predicts to last"
    else:
        what = f"{args.fraction:.0%} of each grounded maximum"
        what += ", with the efforts that hold it longest," if args.longest else ""
    mu = "not limited" if info["mu"] is None else f"{info['mu']:g}"
    print(f"{robot.name} ({robot.platform.kind}), task {task}, load sharing {info['load']}, mu {mu}: "
          f"{what} held {1e3 * args.duration:g} ms in MuJoCo")  # fmt: skip
    columns = f"{'axis':>6} {'reach':>9} {'acc err %':>10} {'normal err %W':>14} {'rise mm':>8} {'slide mm/s':>10}"
    print(columns + (f" {'predicted ms':>12} {'MuJoCo ms':>9}" if args.longest else "") + "  verdict")
    for a in axes:
        if not a.replayed:
            print(f"{a.axis:>6} {a.reach:9.3f}  (no motion along this axis from rest: nothing to replay)")
            continue
        normal = f"{100.0 * a.normal_error / a.weight:.3f}" + ("" if a.judge_normals else "*")
        row = (f"{a.axis:>6} {a.reach:9.3f} {100.0 * a.acceleration_error:10.4f} {normal:>14} {1e3 * a.rise:8.3f} "
               f"{1e3 * a.slide:10.2f}")  # fmt: skip
        if args.longest:
            row += f" {1e3 * a.extra['predicted_hold']:12.2f} {1e3 * a.extra['mujoco_hold']:9.2f}"
        print(row + "  " + _verdict(a, args))
    tolerance = (
        f"an axis passes when at t = 0 MuJoCo's acceleration is within "
        f"{100 * referee_package.ACCELERATION_TOLERANCE:g} % of its norm and every normal force within "
        f"{100 * referee_package.NORMAL_TOLERANCE:g} % of the weight of mobmanip's, and during the replay no "
        f"support rises more than {1e3 * referee_package.RISE:g} mm and no driven wheel slides faster than "
        f"{1e3 * referee_package.SLIDE:g} mm/s"
    )
    print(tolerance)
    for a in axes:
        if a.replayed and a.first_failure is not None and not _passed(a, args):
            print(f"{a.axis}: {_mechanism(a)}")
    if any(a.replayed and not a.judge_normals for a in axes):
        print("* not judged: with load sharing 'any' the predicted normal forces are one balancing share among many")


def _verdict(axis, args) -> str:
    if args.longest:
        held = axis.extra["mujoco_hold"] >= HOLD_SHARE * axis.extra["predicted_hold"]
        return ("as predicted" if held else "SHORTER") + ("" if axis.agrees else ", DISAGREES at t = 0")
    if axis.passed:
        return "holds"
    reasons = []
    if not axis.agrees:
        reasons.append("DISAGREES at t = 0")
    if axis.rise > 1e-4:
        reasons.append("a support ROSE")
    if axis.slide > 1e-3:
        reasons.append("a wheel SLID")
    return ", ".join(reasons)


def _mechanism(axis) -> str:
    """What made an axis fail during its replay, in one line."""
    f = axis.first_failure
    what = "a wheel" if "traction_use" in f else "a support"
    line = f"{what}, {f['support']}, {f['event']} first, at {1e3 * f['time']:.1f} ms; its normal force went from "
    line += f"{f['normal'][0]:.4g} to {f['normal'][1]:.4g} N"
    if "traction_use" in f:
        line += f" and its traction use from {f['traction_use'][0]:.2f} to {f['traction_use'][1]:.2f} of its friction"
    if axis.agrees and f["event"] != "slides":
        line += ": MuJoCo agreed at t = 0, so the maximum of that instant drifted off as the robot moved"
    elif axis.agrees:  # a slide below the friction limit, with the support loaded
        line += " (below its friction limit: MuJoCo's contact gave way, not the floor model's limits)"
    return line


def _document(robot, task, info, referee, axes, args, held_object) -> dict:
    replay = "held" if args.held else "longest" if args.longest else "fraction"
    return {
        "robot": robot.name,
        "platform": robot.platform.kind,
        "task": task,
        "floor": {k: info[k] for k in ("mu", "load", "reserve", "faces", "pose", "level") if k in info}
        | ({"slope": info["slope"], "uphill": info["uphill"]} if "slope" in info else {}),
        "object": {"mass": held_object.mass, "inertia": held_object.inertia.tolist()},
        "replay": replay,
        "fraction": args.fraction,
        "duration": args.duration,
        "weight": referee.weight,
        "inertia_repairs": sorted(referee.repairs),
        "axes": [a.to_dict() for a in axes],
        "passed": all(_passed(a, args) for a in axes),
    }
