"""``mobmanip paper --out DIR``: reproduce the paper's Section 4 (Fig. 3 and Fig. 4).

Beside the paper's figures it writes the same with the exact capacity polytopes drawn over the
ellipses (``fig3_kinematic_polytopes.png``, ``fig4_dynamic_polytopes.png``); the case study's
JSON lists each case's polytopes of the same quantity beside its ellipse.
"""

from __future__ import annotations

from pathlib import Path


def register(sub) -> None:
    parser = sub.add_parser("paper", help="reproduce the paper's case study (Fig. 3 and Fig. 4)")
    parser.add_argument(
        "--robot", default="planar_dual_arm", help="a two-arm differential drive (default: %(default)s)"
    )
    parser.add_argument("--out", default="out", metavar="DIR", help="output directory (default: %(default)s)")
    parser.set_defaults(func=run)


def _table(study) -> str:
    lines = ["kinematic ellipses (m/s)", f"{'angle':>6} {'platform v_max':>15} {'major':>9} {'minor':>9}"]
    for c in study.kinematic:
        speed = "locked" if c.platform_speed_max is None else f"{c.platform_speed_max:g} m/s"
        major, minor = c.analysis.kinematic.semi_axes
        lines.append(f"{c.angle_deg:6g} {speed:>15} {major:9.4f} {minor:9.4f}")
    lines += [
        "dynamic ellipses (m/s^2)",
        f"{'angle':>6} {'wheel tau_max':>14} {'dynamics':>10} {'major':>9} {'minor':>9}",
    ]
    for c in study.dynamic:
        major, minor = c.analysis.dynamic.semi_axes
        kind = "decoupled" if c.decoupled else "coupled"
        lines.append(f"{c.angle_deg:6g} {c.wheel_torque_max:10g} N m {kind:>10} {major:9.4f} {minor:9.4f}")
    return "\n".join(lines)


from ..viz.paper_figures import FIGURES, POLYTOPES  # noqa: E402  (names only; no plotting imports)


def run(args) -> int:
    from ..casestudy import run_case_study
    from ..robot.model import load_robot
    from ..support.files import output_directory, write_json

    out = output_directory(args.out)
    robot = load_robot(args.robot)
    loaded = [f"[1/4] loaded {robot.name}: {robot.nx} reduced velocities"]

    def note(message: str) -> None:  # the first note comes once the robot is found to fit the study
        while loaded:
            print(loaded.pop())
        print(f"[2/4] {message}")

    study = run_case_study(robot, progress=note, measures=POLYTOPES)
    print(_table(study))
    print(_polytope_table(study))
    write_json(out / "case_study.json", study.to_dict())
    print(f"[3/4] wrote {out / 'case_study.json'}")
    write_figures(study, out)
    print(f"[4/4] wrote {', '.join(str(out / name) for name in FIGURES)}")
    return 0


def _polytope_table(study) -> str:
    """Each polytope's area over its ellipse's, per case: what the ellipses leave out."""
    lines = [
        "area of the exact polytopes over the ellipse's (kinematic; dynamic decoupled: exact, minimum-norm policy)",
        f"{'angle':>6} {'case':>22} {'kinematic':>10} {'exact':>8} {'policy':>8}",
    ]
    for c in study.kinematic:
        speed = "locked" if c.platform_speed_max is None else f"v_max {c.platform_speed_max:g} m/s"
        a = c.analysis
        lines.append(f"{c.angle_deg:6g} {speed:>22} {a.measure(POLYTOPES[0]).volume / a.kinematic.volume:10.3f}")
    for c in study.dynamic:
        if not c.decoupled:
            continue
        a = c.analysis
        ratios = [a.measure(name).volume / a.dynamic.volume for name in POLYTOPES[1:]]
        case = f"tau_max {c.wheel_torque_max:g} N m"
        lines.append(f"{c.angle_deg:6g} {case:>22} {'':>10} {ratios[0]:8.3f} {ratios[1]:8.3f}")
    return "\n".join(lines)


def write_figures(study, out: Path) -> dict[str, list]:
    """Write the figures into ``out`` (see :func:`mobmanip.viz.paper_figures.write_figures`)."""
    from ..viz.paper_figures import write_figures as write

    return write(study, out)
