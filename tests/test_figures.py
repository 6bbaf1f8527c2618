"""The paper's figures and the sweep plots are fit for a paper: structure, not pixels.

Legends outside the panels, colour-blind-safe set colours distinct from the arms', coinciding
sets drawn once, symbols and units in mathtext, no figure number in the image, a heading arrow,
tight panels at one scale, Fig. 4 and its coupled twin on the same scale and limits, PNG and PDF.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_hex
from matplotlib.patches import FancyArrow

import mobmanip
from mobmanip.casestudy import run_case_study
from mobmanip.viz.figures import ARM_COLORS, OKABE_ITO, PAD, coincide, support
from mobmanip.viz.paper_figures import FIGURES, POLYTOPES, write_figures


@pytest.fixture(scope="module")
def paper(tmp_path_factory):
    out = tmp_path_factory.mktemp("figures")
    robot = mobmanip.load_robot("planar_dual_arm")
    study = run_case_study(
        robot, angles_deg=(0.0, 90.0), platform_speeds=(0.001, 0.5), wheel_torques=(200.0, 10.0), measures=POLYTOPES
    )
    figures: dict = {}
    drawn = write_figures(study, out, keep=figures)
    yield {"out": out, "study": study, "figures": figures, "drawn": drawn, "robot": robot}
    for fig in figures.values():
        plt.close(fig)


def _texts(fig) -> list[str]:
    return [t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text") and callable(a.get_text))]


def test_png_and_pdf_are_written(paper):
    for name in FIGURES:
        png = paper["out"] / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert png.with_suffix(".pdf").read_bytes()[:5] == b"%PDF-"


def test_one_legend_outside_every_panel(paper):
    for name, fig in paper["figures"].items():
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        assert len(fig.legends) == 1, name
        box = fig.legends[0].get_window_extent(renderer)
        for ax in fig.axes:
            assert ax.get_legend() is None
            assert not box.overlaps(ax.get_window_extent(renderer)), name


def test_sets_in_okabe_ito_arms_in_grey_and_labelled(paper):
    palette = {c.lower() for c in OKABE_ITO.values()}
    arms = {c.lower() for c in ARM_COLORS}
    assert not palette & arms
    robot = paper["robot"]
    for name, fig in paper["figures"].items():
        labels = fig.legends[0].get_texts()
        assert [t.get_text() for t in labels][:2] == ["arm 1 (right)", "arm 2 (left)"]
        for ax in fig.axes:
            for line in ax.get_lines():
                label, color = line.get_label(), to_hex(line.get_color()).lower()
                if label.startswith("arm "):
                    assert color in arms
                elif line.get_marker() not in ("+",) and len(line.get_xdata()) > 2:  # a set's outline
                    assert color in palette, (name, label, color)
        assert len(robot.arms) == 2


def test_coinciding_sets_are_drawn_once_with_a_note(paper):
    study = paper["study"]
    for angle in (0.0, 90.0):
        cases = {c.platform_speed_max: c.analysis.kinematic for c in study.kinematic if c.angle_deg == angle}
        # independent of the figure code: the paper's claim, in semi-axes
        np.testing.assert_allclose(cases[0.001].semi_axes, cases[None].semi_axes, rtol=1e-3)
        assert coincide(cases[0.001], cases[None]) and not coincide(cases[0.5], cases[None])
    records = paper["drawn"]["fig3_kinematic.png"]
    slow = [r for r in records if "0.001" in r["label"]]
    assert len(slow) == 2 and all(r["coincides_with"] == "locked platform" for r in slow)
    assert all(r["coincides_with"] is None for r in records if "0.001" not in r["label"])
    fig = paper["figures"]["fig3_kinematic.png"]
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "locked platform" in legend and not any("0.001" in text for text in legend)
    assert any("0.001" in text and "coincides with locked platform" in text for text in _texts(fig))


def test_paper_figures_meet_the_standard_every_command_figure_meets(paper):
    from figure_checks import check_paper_ready

    for name, fig in paper["figures"].items():
        check_paper_ready(fig, name)


def test_support_function_of_an_ellipse_matches_its_boundary(paper):
    e = paper["study"].kinematic[0].analysis.kinematic
    d = np.column_stack([np.cos(np.linspace(0, 6, 40)), np.sin(np.linspace(0, 6, 40))])
    np.testing.assert_allclose(support(e, d), np.max(d @ e.boundary(20000).T, axis=1), rtol=1e-6)


def test_symbols_and_units_in_mathtext_and_no_figure_number(paper):
    for name, fig in paper["figures"].items():
        texts = _texts(fig)
        assert not any("Fig." in t for t in texts), name
        assert not any("tau_max" in t or "m/s^2" in t or " deg" in t for t in texts), name
        assert any("$x$ (m)" == t for t in texts) and any("$y$ (m)" == t for t in texts)
        assert any(t.startswith("object at") and t.endswith("\N{DEGREE SIGN}") for t in texts)
    fig4 = _texts(paper["figures"]["fig4_dynamic.png"])
    assert any("$\\tau_{\\max}$" in t for t in fig4) and any("m/s$^2$" in t for t in fig4)
    assert any("$v_{\\max}$" in t for t in _texts(paper["figures"]["fig3_kinematic.png"]))


def test_heading_arrow_points_along_the_platform(paper):
    study = paper["study"]
    fig = paper["figures"]["fig3_kinematic.png"]
    for ax, angle in zip(fig.axes, (0.0, 90.0)):
        q = next(c.analysis.q for c in study.kinematic if c.angle_deg == angle)
        arrows = [p for p in ax.patches if isinstance(p, FancyArrow)]
        assert len(arrows) == 1
        xy = arrows[0].get_xy()
        tip = xy[np.argmax(np.linalg.norm(xy - q[:2], axis=1))]
        direction = (tip - q[:2]) / np.linalg.norm(tip - q[:2])
        np.testing.assert_allclose(direction, [q[2], q[3]], atol=1e-6)


def test_panels_are_tight_at_one_scale_and_the_fig4_twins_share_it(paper):
    for name, fig in paper["figures"].items():
        spans = np.array([[np.diff(ax.get_xlim())[0], np.diff(ax.get_ylim())[0]] for ax in fig.axes])
        np.testing.assert_allclose(spans, np.broadcast_to(spans[0], spans.shape), rtol=1e-12)  # one scale
        records = paper["drawn"][name]
        widest = np.zeros(2)
        for k, ax in enumerate(fig.axes):
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            points = np.vstack([r["points"] for r in records if r["panel"] == k and len(r["points"])])
            assert np.all((points[:, 0] >= x0) & (points[:, 0] <= x1) & (points[:, 1] >= y0) & (points[:, 1] <= y1))
            widest = np.maximum(widest, points.max(axis=0) - points.min(axis=0))
        assert np.max(widest / spans[0]) >= 0.6  # the sets fill the panels, no half-empty axes
        assert np.max(widest / spans[0]) <= 1.0 / (1.0 + 2.0 * PAD) + 1e-9
    a, b = paper["figures"]["fig4_dynamic.png"], paper["figures"]["fig4_dynamic_coupled.png"]
    for ax_a, ax_b in zip(a.axes, b.axes):
        assert ax_a.get_xlim() == ax_b.get_xlim() and ax_a.get_ylim() == ax_b.get_ylim()
    scales = {r["scale"] for name in ("fig4_dynamic.png", "fig4_dynamic_coupled.png") for r in paper["drawn"][name]}
    assert len(scales) == 1


# --------------------------------------------------------------------------- sweep plots


@pytest.fixture(scope="module")
def wedge():
    from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep

    grid = SweepGrid(angle_deg=np.linspace(-30, 30, 5), distance=np.array([0.8, 1.0, 1.2]))
    return run_sweep(SweepSpec(robot="planar_dual_arm"), grid, workers=1)


def test_polar_sweep_plot_shows_the_swept_wedge_with_units(wedge, tmp_path):
    from mobmanip.viz.sweep_plot import index_unit, plot_sweep, sweep_plot_figure

    fig = sweep_plot_figure(wedge, "kinematic.volume")
    try:
        ax = fig.axes[0]
        assert ax.name == "polar"
        half = 7.5  # half the angle step (deg): the wedge ends where the outer cells do
        assert ax.get_thetamin() == pytest.approx(-30 - half)
        assert ax.get_thetamax() == pytest.approx(30 + half)
        assert ax.get_rorigin() == pytest.approx(0.0)
        assert ax.get_ylim() == pytest.approx((0.7, 1.3))
        colorbar = fig.axes[-1]
        assert colorbar.get_ylabel() == "kinematic ellipsoid volume ((m/s)$^{2}$)"
    finally:
        plt.close(fig)
    path = plot_sweep(wedge, "dynamic.isotropy", tmp_path / "iso.png")
    assert path.read_bytes()[:4] == b"\x89PNG" and path.with_suffix(".pdf").read_bytes()[:5] == b"%PDF-"
    assert index_unit("dynamic.semi_axis_1", "planar") == "m/s$^2$"
    assert index_unit("kinematic.volume", "spatial") == "(m/s)$^{3}$ (rad/s)$^{3}$"
    assert index_unit("kinematic.semi_axis_2", "spatial").startswith("mixed")
    assert index_unit("dynamic.isotropy", "translational") == "1"
