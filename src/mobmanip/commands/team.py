"""``mobmanip team TEAM.toml``: several robots holding one object (see :mod:`mobmanip.team`).

Prints the team (robots, hands, object), each measure's reach along the task axes with the
robot that limits the team there and every robot's share (:meth:`TeamAnalysis.contributions`),
and the load sharing that holds the object still. ``--json`` writes everything,
``--sweep-heading GRID`` turns the object through heading changes (deg) with the robots reaching
for the moved grasp points, ``--plot FILE`` draws the top view (and the sweep), ``--export
SCENE.html`` writes the meshcat scene of all robots, the object and the team's sets.
"""

from __future__ import annotations

import numpy as np

from .common import add_measure_option, requested_measures


def register(sub) -> None:
    parser = sub.add_parser("team", help="analyse several robots holding one object (a team description)")
    parser.add_argument("description", metavar="TEAM.toml", help="the team description (robots, grasps, object)")
    add_measure_option(parser)
    parser.add_argument("--json", metavar="OUT.json", help="write the full result as JSON")
    parser.add_argument("--plot", metavar="FILE", help="write a figure (top view; with a sweep, its curves too)")
    parser.add_argument(
        "--export", metavar="SCENE.html", help="write the 3-D scene (robots, object, sets) as a self-contained page"
    )
    parser.add_argument(
        "--sweep-heading",
        metavar="GRID",
        help="object heading changes, deg: START:STOP:COUNT or V1,V2,... (robots reach for the moved grasps)",
    )
    parser.set_defaults(func=run)


def run(args) -> int:
    import tomllib
    from pathlib import Path

    from ..measures import get_measure
    from ..robot.tasks import get_task
    from ..support.files import check_output, require_finite, write_json
    from ..sweep.runner import parse_grid
    from ..team.analysis import analyze_team, ray_radius
    from ..team.members import load_team

    if args.plot:
        check_output(args.plot)
    offsets = parse_grid(args.sweep_heading, "--sweep-heading") if args.sweep_heading else None
    team = load_team(args.description)
    measures = requested_measures(args)
    analysis = analyze_team(team, measures)
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
        if task_set.empty:
            print(f"{measure.label}: EMPTY (the limits cannot hold the load still)")
            continue
        print(f"{measure.label} ({measure.quantity.units}): reach from its centre along each task axis, both ways")
        if np.any(task_set.center != 0.0):
            held = bool(task_set.contains(np.zeros(task.dim))[0])
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
                parts = ", ".join(f"{n} {shares[n]:.2f}" for n in names)
                cells.append(f"{sign}{ray_radius(task_set, e):.4f} limited by {top} ({parts})")
            print(f"  {label}: " + "; ".join(cells))
    sharing = analysis.load_sharing()
    state = "OVERLOAD: no internal forces hold it within the limits" if sharing.empty else "within the limits"
    print(f"load sharing at rest: worst normalised torque {sharing.worst:.4f} ({state})")
    for name, worst in zip(names, sharing.worst_by_robot):
        print(f"  {name}: worst normalised torque {worst:.4f}")
    if sharing.limiting:
        print(f"  most loaded joint: {sharing.limiting}")
    sweep = None
    if offsets is not None:
        from ..team.sweep import sweep_heading

        path = Path(args.description)
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        sweep = sweep_heading(data, offsets, base_dir=path.resolve().parent, measures=measures, where=str(path))
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
