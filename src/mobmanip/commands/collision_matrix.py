"""``mobmanip collision-matrix ROBOT``: compute a robot's allowed-collision matrix once (sampled
configurations, :mod:`mobmanip.robot.collision_matrix`) and store it beside its spec, where
``place --avoid-collision`` finds it."""

from __future__ import annotations

import time

from ..support.reading import decimal

#: Configurations sampled without being asked (--max-work raises it): ten times the default.
MAX_SAMPLES = 100_000
#: Wall time of one sampled configuration on the paper's robot (s), rounded up (TIAGo++: 3.5e-3 s).
SECONDS_PER_SAMPLE = 2e-4


def register(sub) -> None:
    from ..robot.collision_matrix import DEFAULT_NEVER_CLOSER_THAN, DEFAULT_SAMPLES, DEFAULT_SEED
    from .common import add_robot_argument, add_work_option

    parser = sub.add_parser(
        "collision-matrix",
        help="compute the shape pairs self-collision checks leave out, and store them with the spec",
        description="Sample the robot's configurations within its joint limits and write the pairs that are "
        "always in contact or never near (an allowed-collision matrix, as MoveIt's setup assistant makes) "
        "as NAME.collision.json beside the spec.",
    )
    add_robot_argument(parser)
    parser.add_argument(
        "--samples", type=int, default=DEFAULT_SAMPLES, help=f"configurations sampled (default {DEFAULT_SAMPLES})"
    )
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED, help=f"random seed (default {DEFAULT_SEED})")
    parser.add_argument(
        "--never-closer-than",
        type=decimal,
        default=DEFAULT_NEVER_CLOSER_THAN,
        metavar="M",
        help=f"pairs never closer than M metres in the samples are left out for margins below M "
        f"(default {DEFAULT_NEVER_CLOSER_THAN})",
    )
    parser.add_argument(
        "--source",
        choices=["auto", "collision", "visual"],
        default="auto",
        help="shapes: collision, visual, or collision and visual ones for links without (default auto)",
    )
    parser.add_argument("--out", metavar="FILE.json", help="write here (default: NAME.collision.json beside the spec)")
    add_work_option(parser, f"sampled configurations (default {MAX_SAMPLES:,})")
    parser.set_defaults(func=run)


def _check_work(args, robot) -> None:
    """Refuse a sample count above the bound (--max-work) or above what fits in memory, before
    any sample is drawn (the estimate is announced only for work that will run)."""
    from ..robot.collision_matrix import check_samples
    from ..support.work import WorkEstimate, bound, check_work

    work = WorkEstimate("collision-matrix", "sampled configurations", args.samples, SECONDS_PER_SAMPLE,
                        f"--samples {args.samples}")  # fmt: skip
    limit = bound(args.max_work, MAX_SAMPLES)
    if args.samples > limit:
        check_work(work, limit)  # refuses, naming the bound and --max-work
    check_samples(robot, args.samples, "--samples")
    check_work(work, limit)


def run(args) -> int:
    from ..errors import UsageError
    from ..robot.collision_matrix import compute_collision_matrix, matrix_path
    from ..robot.model import load_robot
    from ..robot.spec import find_spec
    from ..support.files import check_output, write_text

    if args.samples < 1:
        raise UsageError(f"--samples must be at least 1, got {args.samples}")
    if args.seed < 0:
        raise UsageError(f"--seed must be a whole number of at least 0, got {args.seed}")
    if not 0.0 < args.never_closer_than < 1.0:  # refused before the work is announced
        raise UsageError(f"--never-closer-than must be between 0 and 1 m, got {args.never_closer_than!r}")
    robot = load_robot(find_spec(args.robot))
    _check_work(args, robot)
    out = args.out if args.out else matrix_path(robot)
    if out is None:
        raise UsageError(f"robot {robot.name!r} has no spec file to store the matrix beside; give --out")
    check_output(out)
    start = time.perf_counter()
    matrix = compute_collision_matrix(
        robot, samples=args.samples, seed=args.seed, never_closer_than=args.never_closer_than, source=args.source
    )
    write_text(out, matrix.text())
    kept = matrix.checked - len(matrix.always) - len(matrix.never)
    print(
        f"robot {robot.name}: {matrix.checked} shape pairs may meet; over {matrix.samples} sampled configurations "
        f"{len(matrix.always)} always touch, {len(matrix.never)} never came within {matrix.never_closer_than:g} m; "
        f"{kept} kept ({time.perf_counter() - start:.1f} s)"
    )
    print(f"wrote {out}")
    return 0
