"""Helpers for the hostile-input tests: mutated copies of the paper robot and the CLI in-process."""

from __future__ import annotations

import math
import re
from pathlib import Path

from mobmanip.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAPER_URDF_TEXT = (ROOT / "robots" / "planar_dual_arm.urdf").read_text()
PAPER_SPEC_TEXT = (ROOT / "robots" / "planar_dual_arm.toml").read_text()

#: A number printed as a result that is not finite ("nan", "inf", "-inf", "Infinity").
NON_FINITE = re.compile(r"(?<![A-Za-z_])(nan|-?inf|-?infinity)(?![A-Za-z_])", re.IGNORECASE)


def write_robot(directory: Path, urdf_edits=(), spec_edits=(), name: str = "robot") -> Path:
    """Copies of the paper robot's URDF and spec with ``(old, new)`` text replacements (each
    ``old`` must occur; only its first occurrence is replaced). Returns the spec's path."""
    urdf, spec = PAPER_URDF_TEXT, PAPER_SPEC_TEXT.replace("planar_dual_arm.urdf", f"{name}.urdf")
    for old, new in urdf_edits:
        assert old in urdf, old
        urdf = urdf.replace(old, new, 1)
    for old, new in spec_edits:
        assert old in spec, old
        spec = spec.replace(old, new, 1)
    (directory / f"{name}.urdf").write_text(urdf)
    path = directory / f"{name}.toml"
    path.write_text(spec)
    return path


def run_cli(capfd, *argv) -> tuple[int, str, str]:
    """``mobmanip ARGV`` in this process; (exit code, stdout, stderr) at the file-descriptor
    level, so what native code prints is seen too."""
    capfd.readouterr()
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capfd.readouterr()
    return code, out, err


def assert_one_line_error(code, err: str, *needles: str) -> str:
    """Exit code 2 and exactly one line ``mobmanip: error: ...`` (no traceback, no warning),
    containing every needle; returns the line."""
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("mobmanip: error: "), err
    assert "internal error" not in lines[0], err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


def assert_finite_output(out: str) -> None:
    """No NaN or infinity printed."""
    assert NON_FINITE.search(out) is None, out


def finite(value: float) -> bool:
    return math.isfinite(value)
