"""``mobmanip paper --out DIR``: reproduce the paper's Section 4 (Fig. 3 and Fig. 4)."""

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


def run(args) -> int:
    from ..casestudy import run_case_study
    from ..io import OutputError, write_json
    from ..model import load_robot
    from ..viz.figures import sweep_figure

    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create output directory {out}: {exc.strerror or exc}") from exc
    robot = load_robot(args.robot)
    print(f"[1/4] loaded {robot.name}: {robot.nx} reduced velocities")
    study = run_case_study(robot, progress=lambda message: print(f"[2/4] {message}"))
    print(_table(study))
    write_json(out / "case_study.json", study.to_dict())
    print(f"[3/4] wrote {out / 'case_study.json'}")

    angles = sorted({c.angle_deg for c in study.kinematic})

    def panels(cases, pick, label, style=lambda c: {}):
        result = []
        for angle in angles:
            chosen = [c for c in cases if c.angle_deg == angle]
            analysis = chosen[0].analysis
            result.append(
                (f"object at {angle:g} deg", robot, analysis.q, analysis.held_object.center,
                 [(label(c), pick(c), style(c)) for c in chosen])
            )  # fmt: skip
        return result

    def speed_label(c):
        return "locked platform" if c.platform_speed_max is None else f"platform v_max = {c.platform_speed_max:g} m/s"

    sweep_figure(
        panels(
            study.kinematic,
            lambda c: c.analysis.kinematic,
            speed_label,
            lambda c: {"color": "black", "ls": "--", "lw": 1.2} if c.platform_speed_max is None else {},
        ),
        "Fig. 3: kinematic ellipses, varying platform speed",
        "m/s",
        out / "fig3_kinematic.png",
    )
    for decoupled, name, caption in (
        (True, "fig4_dynamic.png", "Fig. 4: dynamic ellipses, varying wheel torque (decoupled, as in the paper)"),
        (False, "fig4_dynamic_coupled.png", "Dynamic ellipses with platform-arm coupling, varying wheel torque"),
    ):
        cases = [c for c in study.dynamic if c.decoupled == decoupled]
        sweep_figure(
            panels(cases, lambda c: c.analysis.dynamic, lambda c: f"wheel tau_max = {c.wheel_torque_max:g} N m"),
            caption,
            "m/s^2",
            out / name,
        )
    print(f"[4/4] wrote {out / 'fig3_kinematic.png'}, {out / 'fig4_dynamic.png'}, {out / 'fig4_dynamic_coupled.png'}")
    return 0
