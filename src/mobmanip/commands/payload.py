"""``mobmanip payload ROBOT``: the heaviest object the robot can hold still (``--static``: with the
robot static too) or give ``--accel`` at one posture, on the ideal model or on the floor, and what
stops it
(:func:`mobmanip.analysis.payload.payload`: one linear program with the mass as a variable).
"""

from __future__ import annotations

from .common import (
    add_floor_options,
    add_robot_options,
    binding_summary,
    floor_constraints,
    load_robot_and_configuration,
)


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
    parser.add_argument("--json", metavar="OUT.json", help="write the result as JSON")
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

    robot, q = load_robot_and_configuration(args)
    acceleration = parse_acceleration(args.accel)
    constraints = floor_constraints(args)
    found = payload(robot, q, args.task, acceleration=acceleration, constraints=constraints, static=args.static)
    document = found.to_dict()
    require_finite(document)  # never a NaN or an infinity printed as a result
    print(f"robot {robot.name} ({robot.platform.kind}), task {found.task} ({', '.join(document['task_axes'])})")
    print(found.summary())
    if found.status == "bounded":
        print(f"what stops it: {binding_summary(list(found.reading))}")
        print("  the program's binding rows:")
        for label in found.binding:
            print(f"    {label}")
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


def _force(value: float) -> str:
    """A force for the summary, N (no "-0" for a contact unloaded to rounding)."""
    text = f"{value:.4g}"
    return "0" if float(text) == 0.0 else text
