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


#: The polytopes the case study computes beside the paper's ellipses (drawn in the extra figures).
POLYTOPES = ("kinematic_polytope", "dynamic_polytope", "dynamic_polytope_min_norm")
#: The figures :func:`write_figures` writes: the paper's, then the ellipses with the polytopes.
FIGURES = (
    "fig3_kinematic.png",
    "fig4_dynamic.png",
    "fig4_dynamic_coupled.png",
    "fig3_kinematic_polytopes.png",
    "fig4_dynamic_polytopes.png",
)


def run(args) -> int:
    from ..casestudy import run_case_study
    from ..io import OutputError, write_json
    from ..model import load_robot

    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create output directory {out}: {exc.strerror or exc}") from exc
    robot = load_robot(args.robot)
    print(f"[1/4] loaded {robot.name}: {robot.nx} reduced velocities")
    study = run_case_study(robot, progress=lambda message: print(f"[2/4] {message}"), measures=POLYTOPES)
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
    """Write the paper's figures and the figures with the polytopes into ``out``.

    Returns:
        What each figure drew, by file name: the records of
        :func:`mobmanip.viz.figures.sweep_figure` (``panel``, ``label``, ``kind``, ``point``,
        ``scale``, ``points``).
    """
    from ..viz.figures import sweep_figure

    robot = study.robot
    angles = sorted({c.angle_deg for c in study.kinematic})
    drawn: dict[str, list] = {name: [] for name in FIGURES}

    def panels(cases, entries):
        result = []
        for angle in angles:
            chosen = [c for c in cases if c.angle_deg == angle]
            analysis = chosen[0].analysis
            sets = [entry for c in chosen for entry in entries(c)]
            result.append((f"object at {angle:g} deg", robot, analysis.q, analysis.held_object.center, sets))
        return result

    def speed_label(c):
        return "locked platform" if c.platform_speed_max is None else f"platform v_max = {c.platform_speed_max:g} m/s"

    def speed_style(c):
        return {"color": "black", "ls": "--", "lw": 1.2} if c.platform_speed_max is None else {}

    sweep_figure(
        panels(study.kinematic, lambda c: [(speed_label(c), c.analysis.kinematic, speed_style(c))]),
        "Fig. 3: kinematic ellipses, varying platform speed",
        "m/s",
        out / FIGURES[0],
        drawn=drawn[FIGURES[0]],
    )
    for decoupled, name, caption in (
        (True, FIGURES[1], "Fig. 4: dynamic ellipses, varying wheel torque (decoupled, as in the paper)"),
        (False, FIGURES[2], "Dynamic ellipses with platform-arm coupling, varying wheel torque"),
    ):
        cases = [c for c in study.dynamic if c.decoupled == decoupled]
        sweep_figure(
            panels(cases, lambda c: [(f"wheel tau_max = {c.wheel_torque_max:g} N m", c.analysis.dynamic)]),
            caption,
            "m/s^2",
            out / name,
            drawn=drawn[name],
        )

    # The same with the exact polytopes: one colour per case, polytope solid, ellipse thin dashed.
    colors = ("#1b9e77", "#d95f02", "#7570b3", "#222222")

    speeds = sorted({c.platform_speed_max for c in study.kinematic if c.platform_speed_max is not None})

    def kinematic_entries(c):
        if c.platform_speed_max is None:  # the locked platform: black dash-dot, over the slowest platform
            look, solid = {"color": colors[3]}, {"lw": 1.3, "ls": "-."}
        else:
            look, solid = {"color": colors[speeds.index(c.platform_speed_max) % 3]}, {"lw": 2.2}
        return [
            (speed_label(c), c.analysis.measure(POLYTOPES[0]), {**look, **solid}),
            ("_ellipse", c.analysis.kinematic, {**look, "lw": 1.0, "ls": "--"}),
        ]

    sweep_figure(
        panels(study.kinematic, kinematic_entries),
        "Fig. 3 with the exact kinematic polytopes",
        "m/s",
        out / FIGURES[3],
        drawn=drawn[FIGURES[3]],
        note="solid: exact polytope (every wheel and joint within its own speed limit); dashed: the ellipse",
        legend_loc="upper left",
    )
    torques = sorted({c.wheel_torque_max for c in study.dynamic}, reverse=True)

    def dynamic_entries(c):
        look = {"color": colors[torques.index(c.wheel_torque_max) % 3]}
        return [
            (f"wheel tau_max = {c.wheel_torque_max:g} N m", c.analysis.measure(POLYTOPES[1]), {**look, "lw": 1.8}),
            ("_policy", c.analysis.measure(POLYTOPES[2]), {**look, "lw": 1.2, "ls": ":"}),
            ("_ellipse", c.analysis.dynamic, {**look, "lw": 1.0, "ls": "--"}),
        ]

    sweep_figure(
        panels([c for c in study.dynamic if c.decoupled], dynamic_entries),
        "Fig. 4 with the exact dynamic polytopes (decoupled)",
        "m/s^2",
        out / FIGURES[4],
        drawn=drawn[FIGURES[4]],
        note="solid: exact polytope (any internal force); dotted: the paper's minimum-norm policy; dashed: the ellipse",
        legend_loc="upper left",
    )
    return drawn
