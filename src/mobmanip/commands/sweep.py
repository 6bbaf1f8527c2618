"""``mobmanip sweep ROBOT``: ellipsoid indices over a grid of object placements, headings and limits."""

from __future__ import annotations

from ..support.reading import decimal
from ..support.work import MAX_GRID_POINTS
from .common import add_guided_command, add_object_mass_option

GRID_HELP = """\
grid syntax (each axis): START:STOP:COUNT gives COUNT evenly spaced values from START to STOP,
both included (0:360:37 is every 10 deg); V1,V2,... lists values; V is a single value.

The object sits at --angle (deg from the platform heading; 0 in front, 90 to the left) and
horizontal --distance (m) from the arms' reference point. --postures says how the arms hold it:
  planar  two 3-joint planar arms with vertical axes sharing their first joint (planar_dual_arm):
          the reference point is that joint (P_o), both arms take the mirrored posture that
          maximises each arm's own manipulability at that reach (arm 1 bends right), as in the paper.
  ik      any robot: the reference point is the horizontal centroid of the arms' first joints;
          the end effectors hold the object as in the reference posture (--reference, default the
          spec's [hold] posture, else its home configuration): same height, same grasp offsets between the hands, turned
          with the object's direction; inverse kinematics moves only the arm joints, within their
          limits, and keeps the hands' orientation where it can. A point where an end effector
          misses its target by more than 1e-9 m is out of reach. One arm: its end effector is
          the object.
  auto    planar where it applies (and no --reference is given), else ik (the default).
Out-of-reach points get NaN indices; a grid with none in reach is an error. --heading turns the
platform in the world (deg). The wheel scales multiply both wheels' velocity / effort limits
(after --wheel-velocity-limit / --wheel-effort-limit).

indices per measure (--measure; by default the kinematic ellipsoid, m/s and rad/s, and the
dynamic ellipsoid, m/s^2 and rad/s^2), named MEASURE.INDEX: volume, isotropy (min/max reach
from the centre; for an ellipsoid min/max semi-axis), capacity: max d . p over the set for the
unit --direction d (radial: from the reference point towards the object; tangential: 90 deg to
its left; or task coordinates in the world, e.g. 1,0), straight_line_reach: the largest s >= 0
with s d in the set (how far exactly along d from rest; at most the capacity, 0 where the ray
misses the set), and for ellipsoids semi_axis_K (K = 1 is the largest), for polytopes width_K
(along task axis K), e.g. kinematic.volume, dynamic.semi_axis_1, dynamic_polytope.straight_line_reach.
capacity and straight_line_reach are NaN where the set is empty.

outputs, in the folder -o DIR (default sweep; created if missing), as site -o and carry --out:
DIR/sweep.npz (grid axes, index arrays of shape angle x distance x heading x velocity scale x
effort scale [x task axis], the arm joints' positions per angle x distance, settings) and
DIR/sweep.csv (one row per grid point); --plot writes DIR/sweep.png with --index over the two
varying grid axes (polar when they are angle and distance; one panel per value of a third varying
axis, up to 6; further axes at their first value). -o was a file prefix before (OUT.npz, ...): a
name ending in .npz, .csv or .png is refused, and a folder that does not exist yet beside an
earlier run's OUT.npz / OUT.csv / OUT.png gets one line saying where the files go now.

--dask tcp://HOST:8786 runs the chunks on a running Dask scheduler's workers (they load the robot
from its name or spec path, and must import mobmanip); --dask local:N starts a local Dask cluster of
N processes. A worker lost mid-run has its chunks run again elsewhere: the result does not depend
on where (or how many times) a chunk ran. From Python: mobmanip.sweep.run_sweep(spec, grid,
executor=client.get_executor()).

examples:
  mobmanip sweep planar_dual_arm --angle 0:360:37 --distance 0.6:1.4:9 \\
      --wheel-velocity-scale 0.1:1:5 --plot --index kinematic.volume --output fig/sweep   # fig/sweep/sweep.png
  mobmanip sweep panda --angle=-90:90:19 --distance 0.2:0.8:7 --plot -o panda   # "=" before a minus
  mobmanip sweep tiago_dual --angle=-40:40:9 --distance 0.3:0.8:6 -o tiago
"""


def register(sub) -> None:
    from .common import add_dask_option, add_floor_options, add_measure_option, add_posture_option, add_progress_option

    parser = add_guided_command(
        sub,
        "sweep",
        "indices over object direction, distance, heading and limit scales (parallel)",
        "Sweep the unified ellipsoids' indices over a grid, on local cores.",
        GRID_HELP,
    )
    parser.add_argument("robot", help="built-in robot name (e.g. planar_dual_arm) or path of a robot spec (.toml)")
    grid = parser.add_argument_group("grid")
    grid.add_argument(
        "--angle", default="0:360:37", metavar="GRID", help="object direction, deg (default: %(default)s)"
    )
    grid.add_argument(
        "--distance", default="0.6:1.4:9", metavar="GRID", help="object distance, m (default: %(default)s)"
    )
    grid.add_argument("--heading", default="0", metavar="GRID", help="platform heading, deg (default: %(default)s)")
    grid.add_argument("--wheel-velocity-scale", default="1", metavar="GRID", help="factor on the wheels' qdot_max")
    grid.add_argument("--wheel-effort-scale", default="1", metavar="GRID", help="factor on the wheels' tau_max")
    analysis = parser.add_argument_group("analysis")
    analysis.add_argument("--task", help="task space (default: the spec's default_task)")
    analysis.add_argument(
        "--wheel-velocity-limit", type=decimal, metavar="RAD_S", help="both wheels' qdot_max before scaling"
    )
    analysis.add_argument(
        "--wheel-effort-limit", type=decimal, metavar="NM", help="both wheels' tau_max before scaling"
    )
    analysis.add_argument("--decoupled", action="store_true", help="neglect platform-arm dynamic interaction")
    analysis.add_argument("--platform", choices=["own", "fixed"], default="own", help="'fixed' locks the platform")
    add_object_mass_option(analysis)
    analysis.add_argument(
        "--direction", default="radial", metavar="D", help="capacity direction: radial, tangential or X,Y[,...]"
    )
    add_measure_option(analysis)
    add_floor_options(analysis)
    postures = parser.add_argument_group("arm postures")
    postures.add_argument(
        "--postures", choices=["auto", "planar", "ik"], default="auto", help="how the arms hold the object (see below)"
    )
    postures.add_argument(
        "--reference",
        metavar="Q.json",
        help='reference posture for ik, {"joints": {NAME: value}} (platform ignored; default: [hold] of the spec)',
    )
    add_posture_option(postures, "reference posture for ik by name, instead of --reference", "hold, else home")
    run = parser.add_argument_group("execution and output")
    run.add_argument("--workers", type=int, metavar="N", help="worker processes (default: the usable cores)")
    add_dask_option(run)
    run.add_argument("--chunk-size", type=int, default=4096, metavar="N", help="configurations per task")
    run.add_argument(
        "--output",
        "-o",
        default="sweep",
        metavar="OUT_DIR",
        help="output directory for sweep.npz, sweep.csv and sweep.png (default: %(default)s)",
    )
    run.add_argument("--no-csv", action="store_true", help="write only OUT_DIR/sweep.npz")
    run.add_argument("--plot", action="store_true", help="also write OUT_DIR/sweep.png")
    run.add_argument("--index", help="index to plot (default: the first measure's volume, kinematic.volume)")
    add_progress_option(run)
    run.add_argument(
        "--max-points",
        type=int,
        default=MAX_GRID_POINTS,
        metavar="N",
        help="refuse grids of more points than this (default: %(default)s; the estimate is printed first)",
    )
    parser.set_defaults(func=run_command)


def _direction(text: str):
    from ..errors import UsageError

    if text in ("radial", "tangential"):
        return text
    try:
        return tuple(decimal(v) for v in text.split(","))
    except ValueError:
        raise UsageError(f"--direction must be radial, tangential or numbers like 1,0; got {text!r}") from None


def run_command(args) -> int:

    from ..errors import UsageError
    from ..measures import resolve_measures
    from ..robot.spec import find_spec
    from ..robot.tasks import TASKS
    from ..support.files import output_directory
    from ..sweep.budget import check_grid
    from ..sweep.runner import SweepGrid, SweepSpec, check_index_name, default_workers, run_sweep
    from ..viz.sweep_plot import plot_sweep
    from .common import cluster_executor, constraints_from_args, requested_measures, robot_for_workers, show_progress
    from .outputs import write_sweep_csv, write_sweep_npz

    _check_outputs(args)  # before anything is loaded, compiled or computed
    grid = SweepGrid.parse(args.angle, args.distance, args.heading, args.wheel_velocity_scale, args.wheel_effort_scale)
    if args.task is not None and args.task not in TASKS:
        raise UsageError(f"unknown task {args.task!r}; expected one of {', '.join(TASKS)}")
    measures = tuple(m.name for m in resolve_measures(requested_measures(args), sweep=True))  # before the sweep runs
    index = args.index or f"{measures[0]}.volume"
    if args.plot:  # check the index name before the sweep runs
        check_index_name(index, len(TASKS[args.task or find_spec(args.robot).default_task].rows), measures)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be at least 1, got {args.workers}")
    if args.chunk_size < 1:
        raise UsageError(f"--chunk-size must be at least 1, got {args.chunk_size}")
    reference = None
    if args.reference is not None and args.posture is not None:
        raise UsageError(f"give either --reference ({args.reference}) or --posture ({args.posture}), not both")
    if args.reference is not None or args.posture is not None:
        from ..postures.named import named_configuration
        from ..robot.configurations import read_configuration
        from ..robot.model import load_robot

        robot = load_robot(args.robot)
        if args.reference is not None:
            q_ref = read_configuration(robot, args.reference)
        else:
            q_ref = named_configuration(robot, args.posture)
        reference = robot.configuration_dict(q_ref)["joints"]
    if args.dask is not None and args.workers is not None:
        raise UsageError("give either --workers (local processes) or --dask (a Dask cluster), not both")
    if args.dask is not None:
        from ..support.cluster import check_address

        check_address(args.dask)
    spec = SweepSpec(
        robot=robot_for_workers(args.robot) if args.dask is not None else args.robot,
        task=args.task,
        platform=args.platform,
        object_mass=args.object_mass,
        decoupled=args.decoupled,
        wheel_velocity_limit=args.wheel_velocity_limit,
        wheel_effort_limit=args.wheel_effort_limit,
        direction=_direction(args.direction),
        postures=args.postures,
        reference=reference,
        measures=measures,
        constraints=constraints_from_args(args),
    )
    _check_floor(args, spec)  # before the estimate is printed and the kernels compiled
    out = output_directory(args.output, "-o")  # removed again if the sweep fails
    if args.max_points < 1:
        raise UsageError(f"--max-points must be at least 1, got {args.max_points}")
    cost = check_grid(grid.shape, args.max_points, args.workers or default_workers())
    a, d, h, v, e = grid.shape
    print(f"estimate: {cost.describe()}")
    print(
        f"sweep {args.robot}: {a} angles x {d} distances x {h} headings = {grid.n_configurations} configurations, "
        f"x {v} velocity x {e} effort scales"
    )
    with cluster_executor(args) as executor:  # connected (or refused) before the sweep's work
        result = run_sweep(
            spec,
            grid,
            executor=executor,
            workers=args.workers,
            chunk_size=args.chunk_size,
            progress=show_progress(args),
            max_points=args.max_points,
        )
    table = result.postures
    if table.method == "ik":
        hold = table.hold  # type: ignore[union-attr]
        print(
            f"postures by inverse kinematics in {table.seconds:.2f} s: "  # type: ignore[union-attr]
            f"object at height {hold.height:.3f} m, "
            f"distances from ({hold.origin[0]:.3f}, {hold.origin[1]:.3f}) m; "
            f"{int(table.reachable.sum())} of {table.reachable.size} (angle, distance) points in reach"
        )
    unreachable = int((~result.reachable).sum())
    if unreachable:
        print(f"{unreachable} of {result.reachable.size} configurations are out of the arms' reach (NaN indices)")
    task = TASKS[str(result.spec.task)]
    mixed = bool(task.linear_rows) and bool(task.angular_rows)
    for measure in result.measures:
        kind = measure.name
        values = result.index(f"{kind}.volume")
        if result.reachable.any():
            label = f"{kind} volume"
            if mixed:  # m^k rad^(m-k): only comparable within this task and quantity
                label += f" ({task.dim}-D, mixing {measure.quantity.units}: compare only within this sweep)"
            ignored = result.ignored_constraints(kind)
            if ignored:
                label += f" [ignores {', '.join(ignored)}]"
            print(f"{label}: min {_nanfmt(values, 'min')}, max {_nanfmt(values, 'max')}")
    written = [write_sweep_npz(result, out / "sweep.npz")]
    if not args.no_csv:
        written.append(write_sweep_csv(result, out / "sweep.csv"))
    if args.plot:
        written.append(plot_sweep(result, index, out / "sweep.png"))
    for path in written:
        print(f"wrote {path}")
    return 0


def _check_floor(args, spec) -> None:
    """Refuse the floor's options for a robot whose platform does not move on the floor (or one
    --platform fixed locks)."""
    from ..robot.spec import find_spec
    from ..terms.constraints.floor import Floor, check_floor_platform

    if any(isinstance(constraint, Floor) for constraint in spec.constraints):
        robot = find_spec(args.robot)
        check_floor_platform(robot.name, "fixed" if args.platform == "fixed" else robot.platform)


#: The files a sweep writes into its -o folder; -o was once a prefix of names ending so.
OUTPUT_SUFFIXES = (".npz", ".csv", ".png")


def _check_outputs(args) -> None:
    """Refuse, before any work, an -o that cannot be the sweep's folder or whose files could not
    be written; say in one line where the files go when -o looks like the file prefix it once was.

    The transition rule: -o names a folder (as ``site -o`` and ``carry --out`` do) holding sweep.npz,
    sweep.csv and sweep.png. A name ending in one of those suffixes was meant as a file: refused,
    naming the folder to give instead. A folder that does not exist yet, beside files an earlier
    run wrote with -o as a prefix (OUT.npz, OUT.csv or OUT.png), is created, with one line saying
    that the new files go inside it and the old ones stay.

    Raises:
        OutputError: naming the path and what to give instead.
    """
    from pathlib import Path

    from ..support.files import OutputError, check_output
    from ..support.notices import notice

    text = str(args.output)
    out = Path(text)
    if out.suffix.lower() in OUTPUT_SUFFIXES:
        raise OutputError(
            f"-o {text}: -o names the folder the sweep writes sweep.npz, sweep.csv and sweep.png into (it was a "
            f"file prefix before); give -o {out.with_suffix('')}"
        )
    if out.exists() and not out.is_dir():
        raise OutputError(f"-o {text}: a file of that name exists; -o names a folder (sweep.npz, sweep.csv go into it)")
    suffixes = [".npz"] + ([] if args.no_csv else [".csv"]) + ([".png"] if args.plot else [])
    for suffix in suffixes:
        check_output(out / f"sweep{suffix}")
    old = [out.with_name(out.name + suffix) for suffix in OUTPUT_SUFFIXES]
    if not out.exists() and any(path.is_file() for path in old):
        first = next(path for path in old if path.is_file())
        notice(
            f"-o {text} is a folder now (it was a file prefix): the results go to {out / 'sweep.npz'} and beside "
            f"it, not to {first}, which stays as it is"
        )


def _nanfmt(values, how: str) -> str:
    import numpy as np

    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return "n/a"
    return f"{(finite.min() if how == 'min' else finite.max()):.4g}"
