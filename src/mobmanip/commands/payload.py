"""``mobmanip payload ROBOT``: the heaviest object the robot can hold still (``--static``: with the
robot static too) or give ``--accel`` at one posture, on the ideal model or on the floor, and what
stops it
(:func:`mobmanip.analysis.payload.payload`: one linear program with the mass as a variable).
"""

from __future__ import annotations

import numpy as np

from .common import (
    add_dask_option,
    add_floor_options,
    add_json_option,
    add_robot_options,
    binding_summary,
    constraints_from_args,
    limits_summary,
    load_robot_and_configuration,
)

#: The problem the payload's linear program solves: a constraint's rows join it when they are of
#: this problem (and affine in the object's mass, as the floor's are).
ACCELERATION = ("acceleration",)


def register(sub) -> None:
    parser = sub.add_parser(
        "payload", help="the heaviest object the robot can hold still, or give an acceleration, and what stops it"
    )
    add_robot_options(parser)
    parser.add_argument(
        "--accel",
        metavar="A1,A2,...",
        help="the object's acceleration in the task's coordinates (m/s^2, rad/s^2), one number per task axis "
        "(default: held still)",
    )
    parser.add_argument(
        "--static",
        action="store_true",
        help="the robot static too: every wheel and joint at zero acceleration (statics, what can be held for a "
        "while); by default only the object is still and the joints may accelerate, an instant's capacity",
    )
    add_floor_options(parser)
    add_json_option(parser, "the result")
    mapping = parser.add_argument_group("a map over object positions (instead of one posture)")
    mapping.add_argument(
        "--map",
        action="store_true",
        help="the payload at every object position of a polar grid around the robot, the arms holding each as "
        "`mobmanip sweep` finds them (not with --q or --posture)",
    )
    mapping.add_argument(
        "--angle", default="-90:90:13", metavar="GRID", help="the object's direction from the heading, deg "
        "(START:STOP:COUNT, V1,V2,... or V; default %(default)s)"
    )  # fmt: skip
    mapping.add_argument("--distance", default="0.3:0.9:13", metavar="GRID",
                         help="its distance from the arms' reference point, m (default %(default)s)")  # fmt: skip
    mapping.add_argument("--postures", choices=["auto", "planar", "ik"], default="auto",
                         help="how the arms hold each position, as `mobmanip sweep` (default %(default)s)")  # fmt: skip
    add_dask_option(mapping)
    mapping.add_argument(
        "--out", metavar="DIR", help="with --map: write payload_map.csv, payload_map.json, payload_map.png; "
        "with --trajectory: payload_along.csv, payload_along.json"
    )  # fmt: skip
    parser.add_argument(
        "--trajectory",
        metavar="TRAJ.csv",
        help="the payload at every sample's posture of a whole-body trajectory (as `mobmanip trajectory` reads it; "
        "not with --q, --posture or --map): what could be held had the robot stopped there",
    )
    parser.set_defaults(func=run)


def parse_acceleration(text: str | None) -> tuple[float, ...] | None:
    """--accel's numbers (their count is checked against the task by the function).

    Raises:
        ArgumentError: an entry that is not a number.
    """
    from ..errors import ArgumentError
    from ..support.reading import decimal

    if text is None:
        return None
    values = []
    for entry in text.split(","):
        try:
            values.append(decimal(entry.strip()))
        except (ValueError, ArgumentError):
            raise ArgumentError(f"--accel must be numbers separated by commas, got {text!r}") from None
    return tuple(values)


def run(args) -> int:
    from ..analysis.payload import payload
    from ..support.files import require_finite, write_json

    if args.map and args.trajectory:
        from ..errors import UsageError

        raise UsageError("give --map (object positions) or --trajectory (a path's samples), not both")
    if args.dask is not None and not args.map:
        from ..errors import UsageError

        raise UsageError("--dask runs a payload map on a cluster: give --map too")
    if args.map:
        return run_map(args)
    if args.trajectory:
        return run_along(args)
    if args.out:
        from ..errors import UsageError

        raise UsageError("--out writes a payload map's files: give --map (one posture's result: --json)")
    robot, q = load_robot_and_configuration(args)
    acceleration = parse_acceleration(args.accel)
    constraints = constraints_from_args(args, ACCELERATION)
    found = payload(robot, q, args.task, acceleration=acceleration, constraints=constraints, static=args.static)
    document = found.to_dict()
    static = _static_payload(robot, q, args, found, constraints)
    if static is not None:
        document["static_mass"] = static
    require_finite(document)  # never a NaN or an infinity printed as a result
    print(f"robot {robot.name} ({robot.platform.kind}), task {found.task} ({', '.join(document['task_axes'])})")
    print(found.summary())
    if found.status == "bounded":
        if found.limits:  # ranked by the program's multipliers: the first is what to change
            print(f"what stops it (kg gained per 1 % more): {limits_summary(list(found.limits))}")
        else:
            print(f"what stops it: {binding_summary(list(found.reading))}")
        print("  the program's binding rows:")
        for label in found.binding:
            print(f"    {label}")
        if static is not None:
            xdot = np.abs(found.variables["xdot"])
            print(
                f"  for an instant only: the object stays still while the joints accelerate (up to {xdot.max():.4g} "
                f"rad/s^2 or m/s^2, {found.reduced_names[int(xdot.argmax())]}); with the robot static too "
                f"(--static), what can be held for a while: {static:.6g} kg"
            )
        if found.floor is not None:
            contacts = ", ".join(f"{name} {_force(c['normal'])}" for name, c in found.floor["contacts"].items())
            print(f"  normal forces (N): {contacts}")
            if found.floor["zmp"] is not None:
                zmp = ", ".join(f"{v:.4f}" for v in found.floor["zmp"])
                print(f"  zero-moment point ({zmp}) m, {found.floor['margin']:.4f} m inside the support polygon")
    if args.json:
        write_json(args.json, document)
        print(f"wrote {args.json}")
    return 0


#: The share of the instant's payload the static one must fall short by to be said (below it the two
#: print alike).
STATIC_SHORTFALL = 1e-3


def _static_payload(robot, q, args, found, constraints) -> float | None:
    """The payload with the robot static too, where holding the object still takes less than the
    instant's payload (whose joints may accelerate while the object does not); else ``None``."""
    from ..analysis.payload import payload

    if args.static or found.status != "bounded" or not found.held_still:
        return None
    static = payload(robot, q, args.task, constraints=constraints, static=True)
    if static.mass is None or found.mass is None or static.mass >= found.mass * (1.0 - STATIC_SHORTFALL):
        return None
    return float(static.mass)


def _force(value: float) -> str:
    """A force for the summary, N (no "-0" for a contact unloaded to rounding)."""
    text = f"{value:.4g}"
    return "0" if float(text) == 0.0 else text


def run_map(args) -> int:
    """``--map``: the payload over a polar grid of object positions."""
    from ..sweep.payload_map import CELL_STATUSES, payload_map
    from ..sweep.spec import SweepGrid, parse_grid
    from .common import cluster_executor, robot_for_workers, robot_spec_from_args
    from .outputs import write_payload_map

    _refuse_one_posture(args, "--map", "holds the object at every grid position in the posture the sweep finds")
    from ..robot.model import load_robot

    robot = load_robot(robot_spec_from_args(args))
    grid = SweepGrid(parse_grid(args.angle, "--angle"), parse_grid(args.distance, "--distance", positive=True))
    _check_outputs(args.out, ("payload_map.csv", "payload_map.json", "payload_map.png"))
    source = None
    if args.dask is not None:
        if args.robot is None:
            from ..errors import UsageError

            raise UsageError("--dask: the workers load the robot by its name or spec path; give ROBOT, not --urdf")
        source = robot_for_workers(args.robot)
    with cluster_executor(args) as executor:  # connected (or refused) before any work
        found = payload_map(robot, grid, args.task, acceleration=parse_acceleration(args.accel),
                            constraints=constraints_from_args(args, ACCELERATION), static=args.static,
                            postures=args.postures, executor=executor, robot_source=source)  # fmt: skip
    counts = {status: int((found.status == status).sum()) for status in CELL_STATUSES}
    print(f"robot {robot.name}, task {found.task}: {found.status.size} object positions "
          f"({', '.join(f'{n} {s}' for s, n in counts.items() if n)})")  # fmt: skip
    best = found.best()
    if best is None:
        print("no position has a bounded payload")
    else:
        bounded = found.mass[found.status == "bounded"]
        print(f"heaviest object: {found.mass[best]:.6g} kg at {found.angle_deg[best[0]]:g} deg, "
              f"{found.distance[best[1]]:g} m; the lightest of the positions: {bounded.min():.6g} kg")  # fmt: skip
    return _stops_and_outputs(found, best, write_payload_map, args.out)


def run_along(args) -> int:
    """``--trajectory``: the payload at every sample of a motion."""
    from ..motion.trajectory import read_trajectory
    from ..robot.model import load_robot
    from ..support.files import note_input
    from ..sweep.payload_map import payload_along
    from .common import robot_spec_from_args
    from .outputs import write_payload_along

    _refuse_one_posture(args, "--trajectory", "holds the object at every sample's posture")
    note_input(args.trajectory)
    robot = load_robot(robot_spec_from_args(args))
    motion = read_trajectory(robot, args.trajectory)
    _check_outputs(args.out, ("payload_along.csv", "payload_along.json"))
    found = payload_along(robot, motion, args.task, acceleration=parse_acceleration(args.accel),
                          constraints=constraints_from_args(args, ACCELERATION), static=args.static)  # fmt: skip
    print(f"robot {robot.name}, task {found.task}: {len(found.t)} samples")
    k = found.lightest()
    if k is None:
        print("no sample has a bounded payload")
    else:
        print(f"lightest payload along the path: {found.mass[k]:.6g} kg at sample {k} (t = {found.t[k]:g} s); "
              f"the heaviest sample's {np.nanmax(found.mass):.6g} kg")  # fmt: skip
    return _stops_and_outputs(found, k, write_payload_along, args.out)


def _check_outputs(out: str | None, names: tuple[str, ...]) -> None:
    """Refuse an unwritable output file in ``--out`` before any payload is computed."""
    from ..support.files import check_output, output_directory

    if out:
        directory = output_directory(out)
        for name in names:
            check_output(directory / name)


def _stops_and_outputs(found, at, write, out: str | None) -> int:
    """What stops the payload at the index ``at`` of a map or a path (where one is bounded), then
    the files ``write`` puts in ``out``."""
    if at is not None:
        print(f"what stops it there: {binding_summary(found.limit[at].split('; '))}")
    if out:
        for written in write(found, out):
            print(f"wrote {written}")
    return 0


def _refuse_one_posture(args, option: str, why: str) -> None:
    """A map or a path has its own postures and writes its JSON beside its other files: --q,
    --posture and --json are refused with ``option``, saying ``why``."""
    from ..errors import UsageError

    if args.q or args.posture:
        raise UsageError(f"{option} {why}: --q and --posture do not apply")
    if args.json:
        raise UsageError(f"{option} writes its JSON with its other files: give --out DIR")
