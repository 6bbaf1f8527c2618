"""The paper's Fig. 3 and Fig. 4 from a case study (``mobmanip paper``), and the same with the
exact capacity polytopes, as figures to put into a LaTeX document as they are.

No "Fig. N" in the images (the document's caption numbers them); mathtext symbols and units;
each figure written as PNG and PDF (:data:`mobmanip.viz.figures.FORMATS`). Fig. 4 and its coupled
twin share their scale and axis limits, so that they compare at a glance.
"""

from __future__ import annotations

from pathlib import Path

#: The figures :func:`write_figures` writes (PNG; a PDF beside each): the paper's, then the
#: ellipses with the polytopes.
FIGURES = (
    "fig3_kinematic.png",
    "fig4_dynamic.png",
    "fig4_dynamic_coupled.png",
    "fig3_kinematic_polytopes.png",
    "fig4_dynamic_polytopes.png",
)
#: The polytopes the case study computes beside the paper's ellipses (drawn in the extra figures).
POLYTOPES = ("kinematic_polytope", "dynamic_polytope", "dynamic_polytope_min_norm")
VELOCITY_UNIT = "m/s"
ACCELERATION_UNIT = "m/s$^2$"
LOCKED_STYLE = {"color": "black", "ls": (0, (4, 2)), "lw": 1.3}


def speed_label(speed: float | None) -> str:
    """``locked platform`` or ``$v_{\\max}$ = 0.5 m/s`` (the platform's maximum rim speed)."""
    return "locked platform" if speed is None else f"platform $v_{{\\max}}$ = {speed:g} m/s"


def torque_label(torque: float) -> str:
    """``wheel $\\tau_{\\max}$ = 200 N m``."""
    return f"wheel $\\tau_{{\\max}}$ = {torque:g} N m"


def angle_caption(angle_deg: float) -> str:
    """``object at 45°``."""
    return f"object at {angle_deg:g}\N{DEGREE SIGN}"


def write_figures(study, out: Path, keep: dict | None = None) -> dict[str, list]:
    """Write the paper's figures and the figures with the polytopes into ``out``.

    Args:
        study: a :class:`mobmanip.casestudy.CaseStudy`.
        out: the output directory.
        keep: if given, each matplotlib figure, left open, by file name (the caller closes them).

    Returns:
        What each figure drew, by file name: the records of
        :func:`mobmanip.viz.figures.sweep_figure` (``panel``, ``label``, ``kind``, ``point``,
        ``scale``, ``points``, ``coincides_with``).
    """
    from .figures import SET_COLORS, panel_bounds, panel_limits, scale_of, sweep_figure

    out = Path(out)
    robot = study.robot
    angles = sorted({c.angle_deg for c in study.kinematic})
    drawn: dict[str, list] = {name: [] for name in FIGURES}
    speeds = sorted({c.platform_speed_max for c in study.kinematic if c.platform_speed_max is not None})
    torques = sorted({c.wheel_torque_max for c in study.dynamic}, reverse=True)

    def panels(cases, entries):
        result = []
        for angle in angles:
            chosen = [c for c in cases if c.angle_deg == angle]
            analysis = chosen[0].analysis
            sets = [entry for c in chosen for entry in entries(c)]
            result.append((angle_caption(angle), robot, analysis.q, analysis.held_object.center, sets))
        return result

    def speed_look(c):
        if c.platform_speed_max is None:
            return dict(LOCKED_STYLE)
        return {"color": SET_COLORS[speeds.index(c.platform_speed_max) % len(SET_COLORS)]}

    def torque_look(c):
        return {"color": SET_COLORS[torques.index(c.wheel_torque_max) % len(SET_COLORS)]}

    sweep_figure(
        panels(study.kinematic, lambda c: [(speed_label(c.platform_speed_max), c.analysis.kinematic, speed_look(c))]),
        "",
        VELOCITY_UNIT,
        out / FIGURES[0],
        drawn=drawn[FIGURES[0]],
        keep=_keeper(keep, FIGURES[0]),
    )
    twins = {}
    for decoupled in (True, False):
        cases = [c for c in study.dynamic if c.decoupled == decoupled]
        twins[decoupled] = panels(
            cases, lambda c: [(torque_label(c.wheel_torque_max), c.analysis.dynamic, torque_look(c))]
        )
    scale = min(scale_of(twins[True]), scale_of(twins[False]))  # the larger sets of the two fit
    limits = panel_limits(panel_bounds(twins[True], scale), panel_bounds(twins[False], scale))
    for decoupled, name, note in (
        (True, FIGURES[1], "decoupled dynamics (the paper's Section 4.3)"),
        (False, FIGURES[2], "with the platform-arm dynamic coupling"),
    ):
        sweep_figure(
            twins[decoupled],
            "",
            ACCELERATION_UNIT,
            out / name,
            scale=scale,
            limits=limits,
            drawn=drawn[name],
            keep=_keeper(keep, name),
            note=note,
        )

    # The same with the exact polytopes: one colour per case, polytope solid, ellipse thin dashed.
    def kinematic_entries(c):
        look = speed_look(c)
        solid = {"lw": 1.3, "ls": "-."} if c.platform_speed_max is None else {"lw": 1.8}
        return [
            (speed_label(c.platform_speed_max), c.analysis.measure(POLYTOPES[0]), {**look, **solid}),
            ("_ellipse", c.analysis.kinematic, {**look, "lw": 0.8, "ls": "--"}),
        ]

    sweep_figure(
        panels(study.kinematic, kinematic_entries),
        "",
        VELOCITY_UNIT,
        out / FIGURES[3],
        drawn=drawn[FIGURES[3]],
        keep=_keeper(keep, FIGURES[3]),
        note="solid: exact polytope (every wheel and joint within its own speed limit); dashed: the ellipse",
    )

    def dynamic_entries(c):
        look = torque_look(c)
        return [
            (torque_label(c.wheel_torque_max), c.analysis.measure(POLYTOPES[1]), {**look, "lw": 1.6}),
            ("_policy", c.analysis.measure(POLYTOPES[2]), {**look, "lw": 1.0, "ls": ":"}),
            ("_ellipse", c.analysis.dynamic, {**look, "lw": 0.8, "ls": "--"}),
        ]

    sweep_figure(
        panels([c for c in study.dynamic if c.decoupled], dynamic_entries),
        "",
        ACCELERATION_UNIT,
        out / FIGURES[4],
        drawn=drawn[FIGURES[4]],
        keep=_keeper(keep, FIGURES[4]),
        note="decoupled; solid: exact polytope (any internal force); dotted: the paper's minimum-norm policy; "
        "dashed: the ellipse",
    )
    return drawn


class _Keeper(list):
    """A list that files the figure appended to it under a name in a dict."""

    def __init__(self, into: dict, name: str):
        super().__init__()
        self._into, self._name = into, name

    def append(self, figure) -> None:
        self._into[self._name] = figure


def _keeper(keep: dict | None, name: str):
    return None if keep is None else _Keeper(keep, name)
