"""``mobmanip team TEAM.toml``: several robots holding one object (see :mod:`mobmanip.team`).

Prints the team (robots, hands, object), each measure's reach along the task axes with the
robot that limits the team there and every robot's share (:meth:`TeamAnalysis.contributions`),
and the load sharing that holds the object still. ``--json`` writes everything,
``--sweep-heading GRID`` turns the object through heading changes (deg) with the robots reaching
for the moved grasp points (``--dask ADDRESS`` analyses its headings on a Dask cluster, see
:mod:`mobmanip.team.heading_jobs`), ``--plot FILE`` draws the top view (and the sweep), ``--export
SCENE.html`` writes the meshcat scene of all robots, the object and the team's sets.
"""

from __future__ import annotations

import argparse

import numpy as np

from .common import (
    add_dask_option,
    add_floor_options,
    add_json_option,
    add_measure_option,
    add_progress_option,
    add_work_option,
    binding_summary,
    cluster_executor,
    constraints_from_args,
    describe_reaches,
    requested_measures,
    show_progress,
)

TEAM_HELP = """\
--sweep-heading GRID turns the object about its centre through the heading changes of GRID (deg)
while the robots stay where they stand; at each heading the grasping arms' joints are solved
again, starting from the neighbouring heading's solution (from the description's own heading
outwards, so the postures vary continuously). A heading where some hand cannot meet its grasp
point is marked unreachable. With --dask ADDRESS (tcp://HOST:PORT of a running scheduler, or
local:N for a local cluster of N processes) the headings are analysed as tasks on Dask's
distributed scheduler: this process solves the arms' joints heading after heading, the workers
analyse the team at each heading from them; the files equal a run without --dask, and a task
whose worker is lost is run again by Dask. The joints are still solved one heading after the
other, so the cluster pays off for heavy measures (--polytope), hardly for ellipsoids alone.

--ground (or --mu, --no-traction, --load, --reserve) stands every robot on its own wheels and
casters (see `mobmanip analyze --help`): the polytopes honour each robot's floor, with the object
one for all (its weight shared by every robot's hands), and each reach names the robot and the
contact or joint that stops it; a heading sweep keeps the floor at every heading.

examples:
  mobmanip team examples/beam_team.toml
  mobmanip team examples/beam_team.toml --polytope --json beam.json --plot beam.png
  mobmanip team examples/beam_team.toml --polytope --mu 0.5
  mobmanip team examples/beam_team.toml --sweep-heading=-60:60:13 --export beam.html
  mobmanip team examples/beam_team.toml --polytope --sweep-heading=-60:60:61 --json beam.json --dask local:2
"""

#: Robots of a team, and robot-headings of a heading sweep, run without being asked.
MAX_ROBOTS = 64
MAX_ROBOT_HEADINGS = 100_000
#: Wall time of one robot at one heading (reach, terms, sets) on the paper's robot (s), rounded up.
SECONDS_PER_ROBOT_HEADING = 0.05


def register(sub) -> None:
    parser = sub.add_parser(
        "team",
        help="analyse several robots holding one object (a team description)",
        description="Analyse several robots holding one object: each measure's reach, the robot that "
        "limits the team, load sharing; optionally over object headings.",
        epilog=TEAM_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("description", metavar="TEAM.toml", help="the team description (robots, grasps, object)")
    add_measure_option(parser)
    add_floor_options(parser)
    parser.add_argument(
        "--payload",
        action="store_true",
        help="also the heaviest object the team can hold still where it stands (the object's shape per kilogram "
        "as given; with --ground, every robot on its own floor) and what stops it",
    )
    add_json_option(parser, "the full result")
    parser.add_argument("--plot", metavar="FILE", help="write a figure (top view; with a sweep, its curves too)")
    parser.add_argument(
        "--export", metavar="SCENE.html", help="write the 3-D scene (robots, object, sets) as a self-contained page"
    )
    parser.add_argument(
        "--sweep-heading",
        metavar="GRID",
        help="object heading changes, deg: START:STOP:COUNT or V1,V2,... (robots reach for the moved grasps)",
    )
    add_progress_option(parser, "--sweep-heading")
    add_work_option(
        parser, f"robots and robot-headings (robots x sweep headings; defaults {MAX_ROBOTS}, {MAX_ROBOT_HEADINGS:,})"
    )
    add_dask_option(parser)
    parser.set_defaults(func=run)


def _read_checked(args, offsets):
    """The team file's TOML, after checking its robots and the sweep's robot-headings against the bounds."""
    from ..errors import TeamError
    from ..support.reading import read_user_toml
    from ..support.work import WorkEstimate, check_work
    from ..support.work import bound as _bound
    from ..team.members import MAX_TEAM_BYTES

    data = read_user_toml(args.description, "team", limit=MAX_TEAM_BYTES, error=TeamError)
    robots = data.get("robots")
    count = len(robots) if isinstance(robots, list) else 0
    check_work(WorkEstimate("team", "robots", count, SECONDS_PER_ROBOT_HEADING), _bound(args.max_work, MAX_ROBOTS))
    if offsets is not None:
        work = WorkEstimate("team --sweep-heading", "robot-headings", count * len(offsets), SECONDS_PER_ROBOT_HEADING,
                            f"{count} robots x {len(offsets)} headings")  # fmt: skip
        check_work(work, _bound(args.max_work, MAX_ROBOT_HEADINGS))
    return data


def run(args) -> int:
    from ..errors import UsageError
    from ..support.files import check_output
    from ..sweep.runner import parse_grid

    if args.dask is not None and not args.sweep_heading:
        raise UsageError("--dask runs a heading sweep on a cluster: give --sweep-heading GRID too")
    constraints = constraints_from_args(args)
    if args.plot:
        check_output(args.plot)
    offsets = parse_grid(args.sweep_heading, "--sweep-heading") if args.sweep_heading else None
    data = _read_checked(args, offsets)
    with cluster_executor(args) as executor:  # connected (or refused) before any work
        return _run(args, offsets, data, executor, constraints)


def _run(args, offsets, data, executor, constraints=()) -> int:
    from pathlib import Path

    from ..measures import get_measure
    from ..robot.tasks import get_task
    from ..support.files import require_finite, write_json
    from ..team.analysis import analyze_team, ray_radius
    from ..team.members import load_team

    team = load_team(args.description)
    measures = requested_measures(args)
    analysis = analyze_team(team, measures, constraints=constraints)
    document = analysis.to_dict()
    task = get_task(team.task)
    print(f"team {team.name}: {len(team.members)} robots, {len(team.hands)} hands, task {task.name}")
    for member in team.members:
        pose = member.robot.configuration_dict(member.q)["platform"]
        print(
            f"  {member.name}: {member.robot.name} ({member.robot.platform.kind}) at ({pose[0]:.3f}, {pose[1]:.3f}) m, "
            f"yaw {np.degrees(pose[2]):.1f} deg; hands {', '.join(member.arm_names)}"
        )
    obj = team.held_object
    c = obj.center
    heading = np.degrees(team.object_yaw)
    print(f"object: {obj.mass:g} kg at ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m, heading {heading:.1f} deg")
    names = [m.name for m in team.members]
    for name, task_set in analysis.measures.items():
        measure = get_measure(name)
        model = getattr(task_set, "model", None) or {}
        floors = [v["floor"] for v in model.values() if isinstance(v, dict) and "floor" in v]
        grounded = bool(floors)
        label = measure.label
        if constraints and not measure.honours_constraints and measure.quantity.limits == "effort":
            label += " [ignores floor: an ellipsoid cannot honour it]"
        if task_set.empty:
            why = "on the floor as modelled: some robot cannot stand still" if grounded else "the limits cannot hold"
            print(f"{label}: EMPTY ({why} the load still)" if not grounded else f"{label}: EMPTY ({why})")
            continue
        print(f"{label} ({measure.quantity.units}): reach from its centre along each task axis, both ways")
        if np.any(task_set.center != 0.0):
            held = bool(task_set.contains(np.zeros(task.dim)))
            print(
                f"  centre {np.array2string(task_set.center, precision=4)}; "
                + ("the object at rest is inside" if held else "the object cannot be held still (rest is outside)")
            )
        table = document["limiting_robot"][name]
        for j, label in enumerate(task.labels):
            cells = []
            for sign in ("+", "-"):
                e = np.zeros(task.dim)
                e[j] = 1.0 if sign == "+" else -1.0
                shares = table[f"{sign}{label}"]
                best = round(max(shares.values()), 2)  # ties as printed
                top = "+".join(n for n in names if round(shares[n], 2) >= best) if best > 0 else "-"
                if top == "-" and grounded and ray_radius(task_set, e) > 0.0:
                    top = "the floor"  # no robot's limits move it (see what stops it below)
                parts = ", ".join(f"{n} {shares[n]:.2f}" for n in names)
                cells.append(f"{sign}{ray_radius(task_set, e):.4f} limited by {top} ({parts})")
            print(f"  {label}: " + "; ".join(cells))
        reaches = document[measure.json_key].get("reaches")
        if reaches and grounded:
            mu = "no traction limit" if floors[0].get("mu") is None else f"mu {floors[0]['mu']:g}"
            print(f"  on the floor ({mu}), every robot on its own contacts:")
            print(describe_reaches(reaches, measure.quantity.units_for(team.task), None))
    sharing = analysis.load_sharing()
    state = "OVERLOAD: no internal forces hold it within the limits" if sharing.empty else "within the limits"
    print(f"load sharing at rest: worst normalised torque {sharing.worst:.4f} ({state})")
    for name, worst in zip(names, sharing.worst_by_robot):
        print(f"  {name}: worst normalised torque {worst:.4f}")
    if sharing.limiting:
        print(f"  most loaded joint: {sharing.limiting}")
    if args.payload:
        from ..team.payload import team_payload

        found = team_payload(team, constraints=constraints)
        print(found.summary())
        if found.status == "bounded":
            print(f"  what stops it: {binding_summary(list(found.reading))}")
        document["payload"] = found.to_dict()
    sweep = None
    if offsets is not None:
        from ..team.heading_jobs import HeadingJob, run_heading_sweep

        path = Path(args.description)
        names = None if measures is None else tuple(measures)
        job = HeadingJob(data, tuple(float(v) for v in offsets), str(path.resolve().parent), names, str(path),
                         constraints=tuple(constraints))  # fmt: skip
        sweep = run_heading_sweep(job, executor, progress=show_progress(args))
        reachable = int(sweep.reachable.sum())
        print(f"heading sweep: {reachable} of {len(offsets)} headings reachable")
        for point in sweep.points:
            if not point.reachable:
                print(f"  {point.offset_deg:+7.1f} deg: unreachable")
                continue
            first = sweep.measures[0]
            reach = ", ".join(
                f"{a} {r:.3f} ({who or '-'})"
                for a, r, who in zip(task.labels, point.reach[first], point.limiting[first])
            )
            print(f"  {point.offset_deg:+7.1f} deg: {first} {reach}; worst torque {point.worst_torque:.3f}")
        document["heading_sweep"] = sweep.to_dict()
    require_finite(document)
    if args.json:
        write_json(args.json, document)
        print(f"wrote {args.json}")
    if args.plot:
        from ..viz.team_figure import team_figure

        team_figure(analysis, args.plot, sweep)
        print(f"wrote {args.plot}")
    if args.export:
        from ..viz.team_scene import TeamViewer

        with TeamViewer(analysis) as viewer:
            viewer.export_html(args.export)
            for note in viewer.mesh_notes:
                print(f"note: {note}")
        print(f"wrote {args.export}")
    return 0
