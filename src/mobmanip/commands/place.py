"""``mobmanip place ROBOT --object X,Y,Z --objective ...``: where the platform should stand."""

from __future__ import annotations

import math

from ..support.reading import decimal
from .common import add_guided_command, add_progress_option, add_robot_argument, add_work_option, show_progress

PLACE_HELP = """\
objective: ELLIPSOID:INDEX[:DIRECTION], ELLIPSOID kinematic or dynamic, INDEX one of
  log_volume    log of the ellipsoid's volume
  log_isotropy  log of the geometric over the arithmetic mean of the squared semi-axes (0: a ball)
  capacity      how far the set reaches along DIRECTION (from the origin: gravity's shift counts)
  minor_axis    the smallest semi-axis (worst-direction capacity about the centre)
DIRECTION is a signed task axis (+x, -z, +yaw) or components (1,1,0). ELLIPSOID:INDEX:linear
(or :angular) takes the index of the set's shadow on the task's linear (angular) rows, one unit,
as `analyze` reports per block: dynamic:minor_axis:linear on a spatial task.

or MEASURE:READING:DIRECTION, MEASURE any other registered measure (kinematic_polytope,
dynamic_polytope, dynamic_polytope_min_norm, force_ellipsoid, force_polytope, or one registered
from Python), READING reach (straight-line reach from rest) or support: no closed-form gradient;
the ellipsoid's capacity along DIRECTION (for a force measure the kinematic ellipsoid's volume)
is optimised first (without the floor or any constraint), then a derivative-free search
(Nelder-Mead, --budget evaluations) maximises the reading from there. With --ground (--mu,
--no-traction, --load, --reserve) the reading is the grounded one; a registered constraint option
is honoured by the reading too.

The hands keep the grasp of the reference posture (the spec's [hold], else home), turned about
the vertical; the object's centre is put at --object. Joint limits hold; --region keeps the
platform origin in a rectangle. --avoid-collision M keeps the shapes that may meet at least M
metres apart (excepted: pairs touching in the reference posture, such as hands meeting at the
object; pairs on two hands that hold the object's orientation, whose distance the hold fixes; and
pairs the robot's collision matrix leaves out, NAME.collision.json beside its spec, written by
`mobmanip collision-matrix`); without it self-collision is not checked.

--object-yaw fixes the object's orientation: the hold turned by YAW degrees about the vertical
from its reference posture's (default: free).

--map OUT_DIR also maps the best value over heading and posture at every platform position of
a grid around the object (--map-extent, --map-cells) and writes OUT_DIR/map.npz, map.csv and
map.png. The map is solved in bands of 3 rows (continuation from neighbouring cells inside a
band), in this process (the bands advance together, their evaluations batched) or, with --dask
ADDRESS (tcp://HOST:PORT, or local:N for a local cluster), as tasks on Dask's distributed
scheduler: the same bands give the same map either way, and a band whose worker is lost is run
again by Dask. With a measure's reading the map is the ellipsoid's, and each cell holds the
reading (with the floor and constraints) at the hold the ellipsoid found best there: a lower
bound of that cell's best reading; its best cells are more seeds of the search.

--figure writes the result from above (PNG or SVG); --view serves it in the meshcat viewer,
--export writes the viewer's scene as a self-contained HTML page.

examples:
  mobmanip place planar_dual_arm --object 1,0.5,0.35 --objective kinematic:capacity:+x
  mobmanip place tiago_dual --object 2,1,0.85 --mass 3 --objective dynamic:log_volume --json out.json
  mobmanip place planar_dual_arm --object 1,0.5,0.35 --objective kinematic:capacity:+x --map maps/
  mobmanip place tiago_dual --object 2,1,0.85 --mass 2 --objective dynamic_polytope:reach:+x --mu 0.5
"""


def register(sub) -> None:
    from .common import add_dask_option, add_floor_options, add_posture_option

    parser = add_guided_command(
        sub,
        "place",
        "optimal platform pose and arm posture holding an object at a point",
        "Find the platform pose and arm posture that hold the object at a world point and "
        "maximise a measure (gradient-based, several starts).",
        PLACE_HELP,
    )
    add_robot_argument(parser)
    parser.add_argument("--object", required=True, metavar="X,Y,Z", help="object centre in the world (m)")
    parser.add_argument("--objective", required=True, metavar="ELLIPSOID:INDEX[:DIR]", help="what to maximise")
    parser.add_argument("--mass", type=decimal, metavar="KG", help="object mass (default: the spec's)")
    parser.add_argument("--task", help="task space (default: the spec's default_task)")
    parser.add_argument("--region", metavar="XMIN,XMAX,YMIN,YMAX", help="rectangle for the platform origin (m)")
    parser.add_argument("--starts", type=int, default=8, help="number of starts (default 8)")
    parser.add_argument("--decoupled", action="store_true", help="neglect platform-arm dynamic interaction")
    add_posture_option(parser, "the posture whose grasp the hands keep", "hold, else home")
    parser.add_argument("--json", metavar="OUT.json", help="write the result and its analysis as JSON")
    parser.add_argument("--save-q", metavar="Q.json", help="write the configuration for `analyze --q`")
    parser.add_argument(
        "--avoid-collision",
        type=decimal,
        metavar="M",
        help="keep shapes that may meet (URDF collision shapes, else visual ones) at least M metres apart",
    )
    parser.add_argument("--object-yaw", type=decimal, metavar="DEG", help="fixed object orientation (default: free)")
    parser.add_argument("--figure", metavar="OUT.png", help="write the start and the optimum from above (PNG or SVG)")
    parser.add_argument("--view", action="store_true", help="show the optimum in the meshcat viewer (Ctrl-C stops)")
    parser.add_argument("--export", metavar="PAGE.html", help="write the optimum's viewer scene as an HTML page")
    parser.add_argument(
        "--map",
        metavar="OUT_DIR",
        help="also map the best value over platform positions (a measure's reading: "
        "its value at each cell's best hold for the reading's ellipsoid)",
    )
    parser.add_argument(
        "--map-extent", metavar="XMIN,XMAX,YMIN,YMAX", help="the map's platform positions (default: the arms' reach)"
    )
    parser.add_argument("--map-cells", type=int, default=15, metavar="N", help="map cells per axis (default 15)")
    add_progress_option(parser, "--map")
    add_floor_options(parser)
    parser.add_argument(
        "--budget",
        type=int,
        metavar="N",
        help=f"with a measure's reading: evaluations of the derivative-free search (default {DEFAULT_BUDGET}; "
        "refused with an ellipsoid objective, which gradient ascent maximises)",
    )
    add_dask_option(parser)
    add_work_option(
        parser,
        f"starts, map cells and search evaluations (defaults {MAX_STARTS:,} starts, {MAX_MAP_CELLS:,} cells, "
        f"{MAX_EVALUATIONS:,} evaluations)",
    )
    parser.set_defaults(func=run)


#: Default evaluations of a measure reading's derivative-free search (--budget).
DEFAULT_BUDGET = 300
#: Evaluations of that search place runs without being asked, and the wall time of one (s).
MAX_EVALUATIONS = 20_000
SECONDS_PER_EVALUATION = 0.02  # TIAGo++ on the floor, 300 in 4.4 s (the paper robot: 2.5 s)
#: Starts and map cells (--map-cells squared) place runs without being asked.
MAX_STARTS = 1_000
MAX_MAP_CELLS = 10_000
#: Wall time of one start and of one map cell on the paper's robot (s), rounded up.
SECONDS_PER_START = 0.25
SECONDS_PER_CELL = 0.03


def _check_work(args) -> None:
    from ..errors import UsageError
    from ..support.work import WorkEstimate, check_work
    from ..support.work import bound as _bound

    if args.starts < 1:
        raise UsageError(f"--starts must be at least 1, got {args.starts}")
    check_work(WorkEstimate("place", "starts", args.starts, SECONDS_PER_START), _bound(args.max_work, MAX_STARTS))
    if args.budget is not None and not _polytope_objective(args):
        raise UsageError(
            f"--budget {args.budget} sets the derivative-free search of a measure's reading (e.g. "
            f"dynamic_polytope:reach:+x); the objective {args.objective!r} is not one (an ellipsoid objective is "
            "maximised by gradient ascent from --starts starts)"
        )
    if args.budget is None:
        args.budget = DEFAULT_BUDGET
    if args.budget < 1:
        raise UsageError(f"--budget must be at least 1 evaluation, got {args.budget}")
    if _polytope_objective(args):
        check_work(WorkEstimate("place", "search evaluations", args.budget, SECONDS_PER_EVALUATION),
                   _bound(args.max_work, MAX_EVALUATIONS))  # fmt: skip
    if args.map:
        cells = args.map_cells**2
        detail = f"--map-cells {args.map_cells} per axis"
        check_work(WorkEstimate("place --map", "map cells", cells, SECONDS_PER_CELL, detail),
                   _bound(args.max_work, MAX_MAP_CELLS))  # fmt: skip


def _polytope_objective(args) -> bool:
    from ..gradients.readings import is_reading_objective

    return is_reading_objective(args.objective)


def _parse_point(text: str):
    from ..errors import UsageError

    try:
        values = [decimal(v) for v in text.split(",")]
    except ValueError:
        raise UsageError(f"--object must be X,Y,Z in metres, got {text!r}") from None
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise UsageError(f"--object must be three finite numbers X,Y,Z in metres, got {text!r}")
    return values


def run(args) -> int:
    from .common import cluster_executor

    if args.dask is not None:
        from ..errors import UsageError

        if not args.map:
            raise UsageError("--dask runs a placement map on a cluster: give --map OUT_DIR too")
    with cluster_executor(args) as executor:  # connected (or refused) before any work
        return _run(args, executor)


def _run(args, executor) -> int:
    from ..analysis.single import analyze
    from ..placement.optimize import place, placement_document
    from ..robot.model import load_robot
    from ..robot.spec import find_spec
    from ..support.files import write_json
    from .common import floor_constraints, print_warnings, refuse_constraint_options

    _check_work(args)
    robot = load_robot(find_spec(args.robot))
    target = _parse_point(args.object)
    if _polytope_objective(args):
        return _run_polytope(args, robot, target, executor)
    refuse_constraint_options(args)  # an ellipsoid objective honours no constraint beyond the joint boxes
    if floor_constraints(args):
        from ..errors import UsageError

        raise UsageError(
            f"--ground needs a measure's reading (e.g. dynamic_polytope:reach:+x): the ellipsoid of "
            f"{args.objective!r} ignores the floor"
        )
    reference, region, extent, yaw = _request(args, robot, target)
    collision = None
    if args.avoid_collision is not None:
        from ..robot.collision import SelfCollision

        collision = SelfCollision(robot, margin=args.avoid_collision)
    # With --map the map comes first: its best cells are more starts of the placement, which is
    # then at least as good as any cell of its own map.
    grid = _compute_map(args, robot, target, extent, yaw, collision, reference, executor) if args.map else None
    result = place(
        robot,
        target,
        args.objective,
        args.task,
        object_mass=args.mass,
        decoupled=args.decoupled,
        region=region,
        starts=args.starts,
        reference=reference,
        hold_turn=yaw,
        collision=collision,
        seeds=() if grid is None else grid.best_cells(MAP_SEEDS),
    )
    x, y, heading = result.platform
    print(f"robot {robot.name}: object at ({target[0]:g}, {target[1]:g}, {target[2]:g}) m, {result.objective.name}")
    print(f"platform: x {x:.4f} m, y {y:.4f} m, heading {math.degrees(heading):.2f} deg")
    joints = robot.configuration_dict(result.q)["joints"]
    print("joints: " + ", ".join(f"{name} {value:.4f}" for name, value in joints.items()))
    print(f"{result.objective.name} = {result.value:.6g}")
    _warn_if_collapsed(robot, result, args)
    if result.start_value is not None:
        where = "reference hold placed at the object" + (", or one of the map's best cells" if grid else "")
        print(f"best start ({where}): {result.start_value:.6g}")
    print(
        f"{result.evaluations} measure evaluations, {len(result.runs)} starts, hold error {result.residual:.1e}, "
        f"{result.seconds:.2f} s"
    )
    from ..placement.optimize import AGREEMENT_RTOL

    ends = result.agreement()
    short = result.value - AGREEMENT_RTOL * abs(result.value)
    lower = [v for _, v in result.runs if v is not None and v < short]
    print(
        f"starts: {ends['best']} of {len(result.runs)} reached the best value"
        + (
            f", {ends['lower']} stopped lower (the highest of them at {max(lower):.7g}, the best {result.value:.7g})"
            if lower
            else ""
        )
        + (f", {ends['failed']} found no hold" if ends["failed"] else "")
    )
    if collision is not None:
        print(f"self-collision: {len(collision.pairs)} shape pairs kept >= {collision.margin:g} m apart; "
              f"clearance {collision.clearance(result.q):.4f} m")  # fmt: skip
        if collision.matrix is not None:
            left_out = collision.left_out_clearance(result.q)
            print(f"collision matrix: {collision.left_out.first.size} pairs left out, their clearance "
                  f"{left_out:.4f} m{'' if left_out >= collision.margin else ' (BELOW the margin)'}")  # fmt: skip
    if args.save_q:
        write_json(args.save_q, robot.configuration_dict(result.q))
        print(f"wrote {args.save_q}")
    if args.json:
        analysis = analyze(  # as `mobmanip analyze` computes it: the reference path
            robot, result.q, args.task, object_mass=args.mass, decoupled=args.decoupled, method="exact"
        )
        write_json(args.json, placement_document(robot, result, analysis))
        print_warnings(analysis)
        print(f"wrote {args.json}")
    if args.figure:
        from ..viz.placement import placement_figure

        path = placement_figure(robot, result, args.figure, args.task, object_mass=args.mass, decoupled=args.decoupled)
        print(f"wrote {path}")
    if grid is not None:
        _write_map(args, grid, result)
    if args.view or args.export:
        _show(args, robot, result)
    return 0


def _run_polytope(args, robot, target, executor) -> int:
    """``place`` with a measure's reading (:func:`mobmanip.placement.grounded.place_polytope`);
    with ``--map``, the map of the reading at each cell's surrogate hold
    (:func:`mobmanip.placement.grounded.reading_map`) first, its best cells more seeds."""
    from ..analysis.single import analyze
    from ..errors import UsageError
    from ..gradients.readings import ReadingObjective
    from ..placement.grounded import place_polytope, reading_map, surrogate
    from ..robot.tasks import get_task
    from ..support.files import write_json
    from .common import constraints_from_args, print_warnings

    for option, given in (("--figure", args.figure), ("--avoid-collision", args.avoid_collision is not None)):
        if given:
            raise UsageError(f"{option} is not available with a measure's reading ({args.objective})")
    task = get_task(args.task or robot.spec.default_task)
    objective = ReadingObjective.parse(args.objective, task)
    constraints = constraints_from_args(args)
    reference, region, extent, yaw = _request(args, robot, target)
    grid = None
    if args.map:
        grid = _compute_map(args, robot, target, extent, yaw, None, reference, executor, surrogate(objective))
        grid = reading_map(grid, robot, objective, constraints=constraints, object_mass=args.mass,
                           decoupled=args.decoupled)  # fmt: skip
    result = place_polytope(robot, target, objective, task.name, constraints=constraints, object_mass=args.mass,
                            decoupled=args.decoupled, region=region, reference=reference, starts=args.starts,
                            hold_turn=yaw, budget=args.budget,
                            seeds=() if grid is None else grid.best_cells(MAP_SEEDS))  # fmt: skip
    x, y, heading = result.platform
    where = "on the floor" if constraints else "ideal"
    print(f"robot {robot.name}: object at ({target[0]:g}, {target[1]:g}, {target[2]:g}) m, {objective.name} ({where})")
    print(f"platform: x {x:.4f} m, y {y:.4f} m, heading {math.degrees(heading):.2f} deg")
    joints = robot.configuration_dict(result.q)["joints"]
    print("joints: " + ", ".join(f"{name} {value:.4f}" for name, value in joints.items()))
    print(f"{objective.name} = {result.value:.6g}")
    print(
        f"at the optimum of {surrogate(objective)} ({result.ungrounded.value:.6g}, without the floor or constraints): "
        f"{objective.name} = {result.ungrounded_value:.6g}"
    )
    print(
        f"{result.evaluations} search evaluations (budget {result.budget}), {len(result.ungrounded.runs)} starts, "
        f"hold error {result.residual:.1e}, {result.seconds:.2f} s"
    )
    if args.save_q:
        write_json(args.save_q, robot.configuration_dict(result.q))
        print(f"wrote {args.save_q}")
    if args.json:
        analysis = analyze(robot, result.q, task.name, object_mass=args.mass, decoupled=args.decoupled,
                           constraints=constraints, measures=(objective.measure,))  # fmt: skip
        document = {
            "robot": robot.name,
            "object": [float(v) for v in target],
            "objective": objective.name,
            "constraints": [c.describe() for c in constraints],
            "value": result.value,
            "ungrounded": {
                "objective": surrogate(objective),
                "value": result.ungrounded.value,
                "q": robot.configuration_dict(result.ungrounded.q),
                "objective_value": result.ungrounded_value,
            },
            "hold_turn": result.hold_turn,
            "hold_error": result.residual,
            "evaluations": result.evaluations,
            "budget": result.budget,
            "seconds": result.seconds,
            "q": robot.configuration_dict(result.q),
            "analysis": analysis.to_dict(),
        }
        write_json(args.json, document)
        print_warnings(analysis)
        print(f"wrote {args.json}")
    if grid is not None:
        print(f"map: each cell's {objective.name} at the hold that maximises {surrogate(objective)} there")
        _write_map(args, grid, result)
    if args.view or args.export:
        _show(args, robot, result)
    return 0


def _request(args, robot, target):
    """(reference configuration, region, map extent, object yaw) of the request, each checked
    (the outputs too) before any work."""
    from ..placement.optimize import Region
    from ..postures.named import named_configuration

    reference = None if args.posture is None else named_configuration(robot, args.posture)
    region = None if args.region is None else Region.parse(args.region)
    extent = _check_map_options(args)
    if args.map and extent is not None and not robot.platform_locked:
        _check_extent_reaches(args, robot, target, extent, reference)
    _check_outputs(args)
    yaw = None if args.object_yaw is None else _check_yaw(args.object_yaw)
    return reference, region, extent, yaw


def _check_outputs(args) -> None:
    """Refuse unwritable output paths before any work."""
    from pathlib import Path

    from ..errors import UsageError
    from ..support.files import check_output

    for option, path in (("--json", args.json), ("--save-q", args.save_q), ("--figure", args.figure),
                         ("--export", args.export)):  # fmt: skip
        if path:
            check_output(path)
            if not Path(path).resolve().parent.is_dir():
                raise UsageError(f"{option} {path}: its directory does not exist")
    if args.map and Path(args.map).exists() and not Path(args.map).is_dir():
        raise UsageError(f"--map {args.map}: not a directory")
    if args.map:
        from .outputs import PLACEMENT_MAP_FILES

        for name in PLACEMENT_MAP_FILES:
            check_output(Path(args.map) / name)


def _check_yaw(degrees: float) -> float:
    from ..errors import UsageError

    if not math.isfinite(degrees):
        raise UsageError(f"--object-yaw must be a finite angle in degrees, got {degrees!r}")
    return math.radians(degrees)


def _check_map_options(args):
    """The map's extent (or None for the default) after checking --map-extent and --map-cells."""
    from ..errors import UsageError
    from ..placement.maps import MAX_CELLS_PER_AXIS
    from ..support.ranges import PLATFORM_POSITION

    if not 2 <= args.map_cells <= MAX_CELLS_PER_AXIS:
        raise UsageError(f"--map-cells must be between 2 and {MAX_CELLS_PER_AXIS}, got {args.map_cells}")
    if args.map_extent is None:
        return None
    try:
        values = [decimal(v) for v in args.map_extent.split(",")]
    except ValueError:
        values = []
    if (
        len(values) != 4
        or not all(math.isfinite(v) and abs(v) <= PLATFORM_POSITION for v in values)
        or values[1] - values[0] < MIN_MAP_WIDTH
        or values[3] - values[2] < MIN_MAP_WIDTH
    ):
        raise UsageError(f"--map-extent must be XMIN,XMAX,YMIN,YMAX in metres with XMAX - XMIN and YMAX - YMIN "
                         f"at least {MIN_MAP_WIDTH:g} m, each within +-{PLATFORM_POSITION:g} m, "
                         f"got {args.map_extent!r}")  # fmt: skip
    return values


#: The narrowest side of a map (m): a figure draws no narrower axis, and a map of it says nothing.
MIN_MAP_WIDTH = 1e-3


def _check_extent_reaches(args, robot, target, extent, reference) -> None:
    """Refuse, before any work, a --map-extent that lies wholly beyond the arms' reach bound from
    the object: the map would find no cell that holds it (the map skips exactly those cells)."""
    from ..errors import UsageError
    from ..placement.maps import reach_bound

    x0, x1, y0, y1 = extent
    dx = max(x0 - target[0], 0.0, target[0] - x1)
    dy = max(y0 - target[1], 0.0, target[1] - y1)
    reach = reach_bound(robot, robot.hold_configuration() if reference is None else reference)
    if math.hypot(dx, dy) > reach:
        raise UsageError(
            f"--map-extent {args.map_extent}: no platform position in it holds the object at "
            f"({target[0]:g}, {target[1]:g}) m, {math.hypot(dx, dy):.3f} m away; the arms reach at most {reach:.3f} m"
        )


#: The map's best cells that seed ``place --map`` (each one more start).
MAP_SEEDS = 3


def _compute_map(args, robot, target, extent, yaw, collision, reference, executor, objective=None):
    """The placement map --map asks for (:func:`mobmanip.placement.map_jobs.run_map`), of
    ``objective`` (default --objective)."""
    import numpy as np

    from ..placement.map_jobs import MapJob, run_map
    from ..placement.maps import default_extent
    from .common import robot_for_workers

    x0, x1, y0, y1 = extent if extent is not None else default_extent(robot, target)
    xs, ys = np.linspace(x0, x1, args.map_cells), np.linspace(y0, y1, args.map_cells)
    job = MapJob(
        robot=robot_for_workers(args.robot),
        target=(float(target[0]), float(target[1]), float(target[2])),
        objective=objective or args.objective,
        x=tuple(float(v) for v in xs),
        y=tuple(float(v) for v in ys),
        task=args.task,
        object_mass=args.mass,
        decoupled=args.decoupled,
        reference=None if reference is None else tuple(float(v) for v in reference),
        hold_turn=yaw,
        avoid_collision=None if collision is None else collision.margin,
    )
    return run_map(job, executor, progress=show_progress(args))


def _write_map(args, grid, result) -> None:
    import numpy as np

    from ..robot.model import platform_pose
    from ..support.files import output_directory
    from .outputs import placement_map_outputs

    written = placement_map_outputs(grid, output_directory(args.map, "--map"))
    value, q, _ = grid.best()
    reachable = int(np.sum(~np.isnan(grid.values)))
    print(
        f"map: {reachable} of {grid.values.size} platform positions hold the object; best {value:.6g} at "
        f"x {q[0]:.4f} m, y {q[1]:.4f} m, heading {math.degrees(platform_pose(q)[2]):.2f} deg "
        f"(place, started also from the map's {MAP_SEEDS} best cells: {result.value:.6g}); "
        f"{grid.evaluations} evaluations, {grid.seconds:.2f} s"
    )
    print(f"wrote {', '.join(str(path) for path in written)}")


def _warn_if_collapsed(robot, result, args) -> None:
    """One line on standard error when the optimum's set has collapsed (a singular posture): its
    value then says little about the directions the objective does not look along."""
    import sys

    from ..analysis.single import analyze
    from ..measures import get_measure
    from ..support.notices import notice
    from ..viz.placement import collapsed_note

    analysis = analyze(robot, result.q, args.task, object_mass=args.mass, decoupled=args.decoupled)
    name = result.objective.ellipsoid
    note = collapsed_note(analysis.measure(name), get_measure(name).quantity.units_for(analysis.task))  # type: ignore[arg-type]
    if note is not None:
        notice(f"at the optimum, {note}", stream=sys.stderr)


def _show(args, robot, result) -> None:
    import time

    from ..viz.scene import EllipsoidViewer, analyze_pair

    analysis, locked = analyze_pair(robot, result.q, args.task, object_mass=args.mass, decoupled=args.decoupled)
    with EllipsoidViewer(robot) as viewer:
        viewer.show(result.q, analysis, locked)
        if args.export:
            print(f"wrote {viewer.export_html(args.export)}")
        if args.view:
            print(f"meshcat viewer: {viewer.url}  (Ctrl-C to stop)", flush=True)
            try:
                while viewer.server_running:
                    time.sleep(0.1)
            except KeyboardInterrupt:
                pass
