"""Every figure a command writes meets the paper figures' standard (:mod:`figure_checks`): units
on every axis and colour bar, no label cut off, legends outside the data, no raw tokens, one
unit per axis; and what each figure is about: the polar sweep ticks on its grid, a vertical
objective seen from the side, a collapsed set said so, arms named after their robot, a
planar task's trajectory in m/s.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from conftest import paper_case
from figure_checks import colour_bars, paper_ready
from mobmanip.gradients.evaluator import Objective

ROOT = Path(__file__).resolve().parents[1]

#: Every function the commands call to make a figure, and the test below that checks it.
COVERED = {
    "write_figures": "test_figures.py (the paper's figures, and test_paper_figures_meet_the_standard)",
    "plot_sweep": "test_sweep_polar_plot_ticks_on_its_grid",
    "placement_figure": "test_placement_figure_*",
    "plot_placement_map": "test_placement_map_figure",
    "carry_figure": "test_carry_figure",
    "trajectory_figure": "test_trajectory_figure_of_a_planar_task",
    "team_figure": "test_team_figure",
    "plot_site": "test_site_figure",
    "team_carry_figure": "test_team_carry.py (test_team_carry_figures_meet_the_paper_figures_standard)",
    "retime_figure": "test_retime_figure",
    "payload_map_figure": "test_payload_map_figure",
}


def test_every_figure_a_command_writes_is_covered():
    """The commands' imports from mobmanip.viz that write or build a figure, read from the source."""
    found = set()
    for path in (ROOT / "src" / "mobmanip" / "commands").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("viz"):
                for alias in node.names:
                    if "figure" in alias.name or alias.name.startswith("plot"):
                        found.add(alias.name)
    assert found, "no figure found: the parse is wrong"
    assert found <= set(COVERED), sorted(found - set(COVERED))


@pytest.fixture(scope="module")
def planar():
    return paper_case(30.0)


def _placement(robot, q, objective: Objective, value: float, start_q=None, start_value=None):
    from mobmanip.analysis.single import analyze
    from mobmanip.placement.optimize import Placement

    target = analyze(robot, q).held_object.center
    return Placement(q=q, objective=objective, value=value, start_value=start_value, target=target, hold_turn=0.0,
                     residual=0.0, evaluations=1, constraint_evaluations=1, start_q=start_q)  # fmt: skip


def _texts(fig) -> list[str]:
    return [t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text") and callable(a.get_text))]


def test_placement_figure_from_above_has_units_and_a_legend_below(planar):
    from mobmanip.analysis.single import analyze
    from mobmanip.viz.placement import placement_top_figure

    robot, q = planar
    objective = Objective.parse("kinematic:minor_axis", "planar")
    value = float(analyze(robot, q).kinematic.semi_axes[-1])
    with paper_ready(
        placement_top_figure(robot, _placement(robot, q, objective, value, q, value)), "place --figure"
    ) as fig:
        titles = [ax.get_title() for ax in fig.axes]
        assert titles == [f"best start: {value:.4g} (m/s)", f"optimum: {value:.4g} (m/s)"]
        assert [ax.get_xlabel() for ax in fig.axes] == ["$x$ (m)"] * 2
        assert not any("collapsed" in t for t in _texts(fig))


def test_placement_figure_shows_a_vertical_objective_from_the_side():
    from mobmanip.analysis.single import analyze
    from mobmanip.viz.placement import placement_top_figure

    robot = mobmanip.load_robot("tiago_dual")
    q = robot.hold_configuration()
    objective = Objective.parse("dynamic:capacity:+z", "translational")
    analysis = analyze(robot, q, "translational")
    value = analysis.dynamic.support(np.array([0.0, 0.0, 1.0]))
    with paper_ready(
        placement_top_figure(robot, _placement(robot, q, objective, value), "translational"), "place --figure (+z)"
    ) as fig:
        (ax,) = fig.axes
        assert ax.get_ylabel() == "$z$ (m)" and "from the platform towards the object" in ax.get_xlabel()
        assert ax.get_title() == f"optimum: {value:.4g} (m/s$^2$)"
        # the object (+) is drawn at its height, the set's shadow around it, reaching up by
        # its support along +z times the scale
        plus = next(line for line in ax.get_lines() if line.get_marker() == "+")
        assert plus.get_ydata()[0] == pytest.approx(analysis.held_object.center[2])
        shadow = next(line for line in ax.get_lines() if "ellipsoid" in line.get_label())
        scale = 0.6 / analysis.dynamic.semi_axes[0]
        top = analysis.held_object.center[2] + scale * value
        assert np.max(shadow.get_ydata()) == pytest.approx(top, rel=1e-3)


def test_placement_figure_says_when_the_optimum_set_has_collapsed(planar):
    from mobmanip.analysis.single import analyze
    from mobmanip.viz.placement import placement_top_figure

    robot, _ = planar
    fixed = robot.with_platform("fixed")
    q = fixed.configuration((0.0, 0.0, 0.0), {})  # every arm stretched straight ahead: singular
    kinematic = analyze(fixed, q).kinematic
    # independently: the hands cannot move along the stretched arms (the x axis)
    assert kinematic.support(np.array([1.0, 0.0])) < 1e-9 * kinematic.semi_axes[0]
    objective = Objective.parse("kinematic:minor_axis", "planar")
    with paper_ready(
        placement_top_figure(fixed, _placement(fixed, q, objective, float(kinematic.semi_axes[-1]))),
        "place --figure (collapsed)",
    ) as fig:
        assert any("collapsed" in t for t in _texts(fig))


def test_placement_map_figure(planar):
    from mobmanip.placement.maps import PlacementMap
    from mobmanip.viz.placement import placement_map_figure

    robot, q = planar
    x, y = np.linspace(-1.0, 1.0, 5), np.linspace(-1.0, 0.5, 4)
    values = np.add.outer(y, x) + 3.0
    values[0, 0] = np.nan
    configurations = np.broadcast_to(q, values.shape + q.shape).copy()
    objective = Objective.parse("kinematic:minor_axis", "planar")
    grid = PlacementMap(objective, np.array([1.0, 0.5, 0.35]), x, y, None, values, np.zeros_like(values),
                        configurations, 1, 0.0, task="planar")  # fmt: skip
    with paper_ready(placement_map_figure(grid), "map.png") as fig:
        (bar,) = colour_bars(fig)
        assert bar.get_ylabel() == "kinematic minor semi-axis (m/s)"


def _run(method: str, t, capacity):
    from mobmanip.motion.carry import CarryRun

    n = len(t)
    return CarryRun(method, t, np.zeros((n, 3)), np.zeros((n - 1, 2)), capacity, np.zeros(n), np.zeros(n))


@pytest.mark.parametrize(
    "text, task, unit",
    [
        ("kinematic:minor_axis", "translational", "(m/s)"),
        ("dynamic:capacity:+yaw", "planar_rigid", "(rad/s$^2$)"),
        ("kinematic:minor_axis", "spatial", "(mixed: m/s, rad/s)"),
    ],
)
def test_carry_figure(text, task, unit):
    from mobmanip.motion.carry import CarryResult
    from mobmanip.viz.motion_figures import carry_figure

    t = np.linspace(0.0, 2.0, 11)
    result = CarryResult(
        Objective.parse(text, task), task, _run("qp", t, 1 + t), _run("pinv", t, 1 + 0.5 * t), _run("qp", t - 2.0, t)
    )
    with paper_ready(carry_figure(result, "tiago_pro"), "capacity.png") as fig:
        (ax,) = fig.axes
        assert ax.get_ylabel().endswith(unit) and ":" not in ax.get_ylabel().split("(")[0]
        assert ax.get_title().startswith("tiago_pro: ")


def test_retime_figure():
    """The fastest timing's figure: s' against the limit curve with the binding kinds marked under
    it, and the new time against the input's, each axis with its unit."""
    from mobmanip.motion.retime import retime
    from mobmanip.motion.trajectory import trajectory_from_samples
    from mobmanip.viz.motion_figures import retime_figure

    robot = mobmanip.load_robot("panda")
    home = robot.hold_configuration()
    s = np.linspace(0.0, 1.0, 41)
    qs = np.tile(home, (len(s), 1))
    joint = robot.model.joints[robot.model.getJointId("panda_joint1")].idx_q
    qs[:, joint] += 1.5 * s**2 * (3.0 - 2.0 * s)
    result = retime(robot, trajectory_from_samples(robot, s, qs), object_mass=0.0)
    with paper_ready(retime_figure(result), "retime.png") as fig:
        top, bottom = fig.axes
        assert top.get_ylabel().endswith("(1)") and bottom.get_ylabel() == "time (s)"
        assert bottom.get_xlabel().endswith("(s)")
        legend = [t.get_text() for t in top.get_legend().get_texts()]
        assert "fastest timing" in legend and any(text.startswith("binds: ") for text in legend)
        assert fig._suptitle.get_text().startswith("panda, spatial task, joint limits only: 1 s -> ")


def test_payload_map_figure():
    """The payload map: a polar heat map with its colour bar in kg, the heaviest cell marked, the
    acceleration asked for with its unit in the title."""
    from mobmanip.sweep.payload_map import payload_map
    from mobmanip.sweep.spec import SweepGrid
    from mobmanip.viz.payload_figure import payload_map_figure

    robot = mobmanip.load_robot("planar_dual_arm")
    grid = SweepGrid(np.linspace(-60.0, 60.0, 4), np.linspace(0.3, 0.9, 3))
    with paper_ready(
        payload_map_figure(payload_map(robot, grid, "planar", acceleration=(1.0, 0.0))), "payload_map.png"
    ) as fig:
        (bar,) = colour_bars(fig)
        assert bar.get_ylabel() == "heaviest object (kg)"
        assert "given the acceleration (1, 0) m/s$^2$" in fig._suptitle.get_text()


def test_trajectory_figure_of_a_planar_task(planar):
    from mobmanip.motion.trajectory import trajectory_from_samples
    from mobmanip.motion.trajectory_analysis import analyze_trajectory
    from mobmanip.viz.motion_figures import trajectory_figure

    robot, q0 = planar
    t = np.linspace(0.0, 3.0, 25)
    base = robot.configuration_dict(q0)["joints"]
    arms = [name for arm in robot.arms for name in arm.joint_names]
    qs = []
    for ti in t:
        joints = {name: base[name] + 0.1 * math.sin(0.7 * ti + k) for k, name in enumerate(arms)}
        qs.append(robot.configuration((0.2 * ti, 0.0, 0.0), joints))
    result = analyze_trajectory(robot, trajectory_from_samples(robot, t, np.array(qs), known_joints=arms))
    assert result.task == "planar"
    with paper_ready(trajectory_figure(result), "analysis.png") as fig:
        assert [ax.get_ylabel() for ax in fig.axes] == [
            "velocity (m/s)",
            "acceleration (m/s$^2$)",
            "use of the limit (1)",
        ]


def test_team_figure():
    import tomllib

    from mobmanip.team.analysis import analyze_team
    from mobmanip.team.members import load_team
    from mobmanip.team.sweep import sweep_heading
    from mobmanip.viz.team_figure import team_figure_of

    path = ROOT / "examples" / "beam_team.toml"
    team = load_team(path)
    measures = ("kinematic", "dynamic", "kinematic_polytope")
    analysis = analyze_team(team, measures=measures)
    data = tomllib.loads(path.read_text())
    sweep = sweep_heading(data, np.linspace(-30.0, 30.0, 3), base_dir=path.parent, measures=measures)
    with paper_ready(team_figure_of(analysis, sweep), "team --plot") as fig:
        top, linear, angular = fig.axes
        labels = [line.get_label() for line in top.get_lines() if not line.get_label().startswith("_")]
        for member in team.members:  # each arm named after its robot, once
            arms = [label for label in labels if label.startswith(f"{member.name}: arm ")]
            assert len(arms) == len(member.robot.arms) == len(set(arms))
        assert linear.get_ylabel().endswith("(m/s)") and angular.get_ylabel().endswith("(rad/s)")


def test_site_figure():
    from mobmanip.placement.site import COLUMNS, Site, SiteResult
    from mobmanip.viz.site_figure import site_figure

    positions = np.array([[1.0, 0.0, 0.35], [1.5, 0.5, 0.35], [2.0, 1.0, 0.35]])
    site = Site("planar_dual_arm", "kinematic:capacity:+x", positions)
    table = np.full((3, len(COLUMNS)), np.nan)
    table[:, :3] = positions
    table[:2, COLUMNS.index("value")] = (1.0, 2.0)
    for name, values in (("platform_x", (0.0, 0.5)), ("platform_y", (0.0, 0.0)), ("heading_deg", (0.0, 30.0))):
        table[:2, COLUMNS.index(name)] = values
    result = SiteResult(site, table, COLUMNS, ("", "", "out of reach"), 0.0, "planar")
    with paper_ready(site_figure(result), "site.png") as fig:
        (bar,) = colour_bars(fig)
        assert bar.get_ylabel() == "kinematic capacity along +x (m/s)"
    # positions that tie up to rounding (a symmetric robot's): one colour, and the colour bar reads
    # as the value, not as an offset plus 1e-9 of noise
    table[:2, COLUMNS.index("value")] = (7.498511612918628, 7.498511612918628 + 3e-9)
    with paper_ready(site_figure(SiteResult(site, table, COLUMNS, ("", "", "out of reach"), 0.0, "planar"))) as fig:
        fig.canvas.draw()
        (bar,) = colour_bars(fig)
        low, high = bar.get_ylim()
        assert high - low >= 0.01 * 7.4985 and low < 7.4985 < high
        labels = [t.get_text() for t in bar.get_yticklabels()] + [bar.yaxis.get_offset_text().get_text()]
        assert not any("e-" in text for text in labels), labels


def test_sweep_polar_plot_ticks_on_its_grid():
    from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
    from mobmanip.viz.sweep_plot import sweep_plot_figure

    angles = np.arange(-30.0, 30.0 + 1e-9, 10.0)
    grid = SweepGrid(angle_deg=angles, distance=np.array([0.9, 1.1]))
    result = run_sweep(SweepSpec(robot="planar_dual_arm"), grid, workers=1)
    with paper_ready(sweep_plot_figure(result, "kinematic.semi_axis_2"), "sweep --plot") as fig:
        ax = fig.axes[0]
        ticks = np.degrees(ax.get_xticks())
        np.testing.assert_allclose(np.sort(ticks), angles, atol=1e-9)
