"""The paper figures' standard, as checks any figure a command writes must pass (structure, not
pixels): units on every axis and colour bar, no label clipped by the figure's edge, legends
outside the data, no raw tokens (``kinematic:minor_axis``, ``kinematic_polytope``) in labels or
legends, and one unit per axis (a label that names both m/s and rad/s says it is mixed).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager

from matplotlib.axes import Axes
from matplotlib.figure import Figure

UNIT = re.compile(r"\(([^()]|\([^()]*\))+\)$")  # ends with "(unit)", one level of nesting inside


def plain(text: str) -> str:
    """The text outside mathtext ($...$)."""
    return re.sub(r"\$[^$]*\$", "", text)


def is_colorbar(ax: Axes) -> bool:
    return ax.get_label() == "<colorbar>"


def _unit_of(label: str) -> str:
    match = UNIT.search(label)
    assert match is not None, f"no unit in {label!r}"
    return match.group(0)[1:-1]


def check_label(label: str, where: str) -> None:
    """A label with a unit in parentheses at its end, no raw token, one unit (or "mixed")."""
    assert label.strip(), f"{where}: empty label"
    unit = _unit_of(label)
    assert "_" not in plain(label), f"{where}: raw token in {label!r}"
    assert not re.search(r"\w:\w", plain(label)), f"{where}: raw token in {label!r}"
    if "rad" in unit and "m/s" in unit:
        assert unit.startswith("mixed"), f"{where}: two units on one axis in {label!r}"
    assert "m/s (rad/s)" not in label and "(m/s, rad/s)" not in label, f"{where}: {label!r}"


def _alike(ax: Axes, axes: list, which: str) -> list:
    """``ax`` and the panels that show the same ``which`` axis: shared with it, or in the same
    column (x) or row (y) of the figure (the paper's panels label their row's y axis once)."""
    shared = (ax.get_shared_x_axes() if which == "x" else ax.get_shared_y_axes()).get_siblings(ax)
    box = ax.get_position()
    out = [ax, *shared]
    for other in axes:
        o = other.get_position()
        if which == "x" and abs(o.x0 - box.x0) < 1e-3:
            out.append(other)
        if which == "y" and abs(o.y0 - box.y0) < 1e-3:
            out.append(other)
    return out


def legends(fig: Figure) -> list:
    return list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]


def check_paper_ready(fig: Figure, name: str = "figure") -> None:
    """Every check of the module's docstring on one figure (drawn here)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    data_axes = [ax for ax in fig.axes if not is_colorbar(ax)]
    assert data_axes, name
    for k, ax in enumerate(data_axes):
        where = f"{name}, panel {k}"
        if ax.name == "polar":
            check_label(ax.get_xlabel(), where + " (angle and radius)")
        elif ax.has_data() and ax.get_xaxis().get_visible():
            # panels on one axis (shared, or side by side at one scale) carry its label once
            check_label(next((a.get_xlabel() for a in _alike(ax, data_axes, "x") if a.get_xlabel()), ""), where + " x")
            check_label(next((a.get_ylabel() for a in _alike(ax, data_axes, "y") if a.get_ylabel()), ""), where + " y")
    for ax in fig.axes:
        if is_colorbar(ax):
            check_label(ax.get_ylabel() or ax.get_xlabel(), f"{name}: colour bar")
            bar = ax.get_window_extent(renderer)
            for data in data_axes:  # no panel's tick labels or axis labels run under the colour bar
                assert not data.get_tightbbox(renderer).overlaps(bar), f"{name}: a panel runs under the colour bar"
    for legend in legends(fig):
        box = legend.get_window_extent(renderer)
        for ax in data_axes:
            assert not box.overlaps(ax.get_window_extent(renderer)), f"{name}: a legend lies over the data"
        for text in legend.get_texts():
            assert "_" not in plain(text.get_text()), f"{name}: raw token in legend {text.get_text()!r}"
            assert not re.search(r"\w:\w", plain(text.get_text())), f"{name}: raw token {text.get_text()!r}"
    tight, page = fig.get_tightbbox(renderer), fig.bbox_inches  # inches: what is drawn, the page
    slack = 1.0 / fig.dpi
    assert (
        tight.x0 >= page.x0 - slack
        and tight.y0 >= page.y0 - slack
        and tight.x1 <= page.x1 + slack
        and tight.y1 <= page.y1 + slack
    ), f"{name}: drawn {tight.bounds} reaches past the page {page.bounds}: a label is cut off"


def colour_bars(fig: Figure) -> list[Axes]:
    """The figure's colour bars."""
    return [ax for ax in fig.axes if is_colorbar(ax)]


@contextmanager
def paper_ready(fig: Figure, name: str = "figure") -> Iterator[Figure]:
    """``fig`` held to the standard (:func:`check_paper_ready`) before the block's own checks of
    it, and closed after them, whatever happens."""
    import matplotlib.pyplot as plt

    try:
        check_paper_ready(fig, name)
        yield fig
    finally:
        plt.close(fig)
