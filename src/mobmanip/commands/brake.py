"""``mobmanip brake ROBOT``: the hardest stop from a straight run, forward and backward, holding the
object level with the arms still, on the floor (no tip-over, the wheels within friction, the
reserve, the ramp): deceleration, distance and time from ``--speed``, the highest speed that stops
within ``--within`` metres, and what stops a harder stop
(:func:`mobmanip.analysis.braking.hardest_stop`).
"""

from __future__ import annotations

import math

from ..support.reading import decimal
from .common import (
    add_floor_options,
    add_json_option,
    add_object_mass_option,
    add_robot_options,
    binding_summary,
    floor_constraints,
    load_robot_and_configuration,
)


def register(sub) -> None:
    parser = sub.add_parser(
        "brake",
        help="the hardest stop from a straight run holding the object, on the floor: distance, time, what stops it",
    )
    add_robot_options(parser)
    add_object_mass_option(parser)
    parser.add_argument("--speed", type=decimal, default=1.0, metavar="M_S", help="the speed braked from (default 1)")
    parser.add_argument(
        "--within", type=decimal, metavar="M", help="also the highest speed from which the robot stops within M metres"
    )
    add_floor_options(parser)
    add_json_option(parser, "the result")
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..analysis.braking import hardest_stop
    from ..errors import ArgumentError
    from ..support.files import require_finite, write_json
    from ..terms.constraints.floor import Floor

    for value, name in ((args.speed, "--speed"), (args.within, "--within")):
        if value is not None and not (math.isfinite(value) and value >= 0.0):
            raise ArgumentError(f"{name} must be a finite number >= 0, got {value!r}")
    robot, q = load_robot_and_configuration(args)
    floor = (floor_constraints(args) or (Floor(),))[0]
    stops = [hardest_stop(robot, q, sense, args.speed, args.object_mass, floor) for sense in (1, -1)]
    mu = floor.resolve(robot)[1]
    where = f"mu {mu:g}" if mu is not None else "traction not limited"
    if floor.reserve:
        where += f", reserve {floor.reserve:g}"
    if floor.slope:
        where += f", a {floor.slope:g} deg ramp rising towards {floor.uphill:g} deg"
    print(f"{robot.name} ({robot.platform.kind}) braking from {args.speed:g} m/s, arms still, object held level, "
          f"on the floor ({where})")  # fmt: skip
    document: dict = {"robot": robot.name, "platform": robot.platform.kind, "floor": floor.describe(), "stops": []}
    for stop in stops:
        sense = "forward " if stop.sense > 0 else "backward"
        if stop.deceleration <= 0.0:
            print(f"  {sense}: it cannot brake at all (no efforts within the limits decelerate it on this floor)")
        else:
            line = (f"  {sense}: {stop.deceleration:.4g} m/s^2, stops in {stop.distance:.4g} m and {stop.time:.4g} s; "
                    f"stops it: {binding_summary(list(stop.binding))}")  # fmt: skip
            if args.within is not None:
                line += f"; stops within {args.within:g} m from up to {stop.speed_for(args.within):.4g} m/s"
            print(line)
        entry = stop.to_dict()
        if args.within is not None:
            entry["within"] = {"distance": args.within, "speed": stop.speed_for(args.within)}
        document["stops"].append(entry)
    if args.json:
        require_finite(document)
        write_json(args.json, document)
        print(f"wrote {args.json}")
    return 0
