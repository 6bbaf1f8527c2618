"""Writing files: nothing is lost when a write fails halfway, and failures are MobmanipErrors."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mobmanip.support.files import OutputError, atomic_output, save_figure  # noqa: E402


def test_failure_midway_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "result.npz"
    target.write_bytes(b"previous good content")
    with pytest.raises(RuntimeError):
        with atomic_output(target, "wb") as handle:
            handle.write(b"half of the new")
            raise RuntimeError("interrupted")
    assert target.read_bytes() == b"previous good content"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.npz"]


def test_complete_write_replaces_the_file(tmp_path):
    target = tmp_path / "table.csv"
    target.write_text("old")
    with atomic_output(target, "w", newline="") as handle:
        handle.write("a,b\n1,2\n")
    assert target.read_text() == "a,b\n1,2\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_missing_directory_is_an_output_error_naming_the_path(tmp_path):
    target = tmp_path / "missing" / "x.npz"
    with pytest.raises(OutputError, match="missing/x.npz"):
        with atomic_output(target, "wb") as handle:
            np.save(handle, np.zeros(3))


def test_figures_are_saved_in_the_suffix_format(tmp_path):
    fig = plt.figure()
    try:
        png = save_figure(fig, tmp_path / "a.png")
        svg = save_figure(fig, tmp_path / "a.svg")
    finally:
        plt.close(fig)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in svg.read_bytes()[:400]
