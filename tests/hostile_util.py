"""Helpers for the hostile-input tests: mutated copies of the paper robot and the CLI in-process."""

from __future__ import annotations

import contextlib
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


class FuzzRun:
    """The cases of one fuzz test, run to the end: every case that breaks the promise is noted
    (not only the first), and the test fails at the end listing them.

    The environment sets the run: ``MOBMANIP_FUZZ_CASES`` (cases, default ``default``),
    ``MOBMANIP_FUZZ_SEED`` (0: the fixed cases of the test suite), ``MOBMANIP_FUZZ_SECONDS``
    (stop starting cases after this long) and ``MOBMANIP_FUZZ_REPORT`` (a file to which one JSON
    line per test is appended: name, cases run, outcomes, problems). ``scripts/fuzz.py`` sets them.
    """

    def __init__(self, name: str, default: int):
        import os
        import time

        self.name = name
        self.cases = int(os.environ.get("MOBMANIP_FUZZ_CASES", str(default)))
        self.seed = int(os.environ.get("MOBMANIP_FUZZ_SEED", "0"))
        seconds = os.environ.get("MOBMANIP_FUZZ_SECONDS")
        self._deadline = time.monotonic() + float(seconds) if seconds else math.inf
        self.run = 0
        self.outcomes = {"error": 0, "result": 0}
        self.problems: list[str] = []

    def __iter__(self):
        import time

        for case in range(self.cases):
            if time.monotonic() > self._deadline:
                return
            self.run += 1
            yield case

    @contextlib.contextmanager
    def case(self, case: int, argv, outcome: str):
        """The assertions about one case: an AssertionError inside is noted as a problem, and the
        run goes on; otherwise the case counts as ``outcome`` (``"error"`` or ``"result"``)."""
        try:
            yield
        except AssertionError as exc:
            self.problems.append(f"case {case}: {[str(a) for a in argv]}: {' '.join(str(exc).split())[:600]}")
        else:
            self.outcomes[outcome] += 1

    def finish(self) -> None:
        """Append the report line (when asked) and fail listing the problems, if any."""
        import json
        import os

        report = os.environ.get("MOBMANIP_FUZZ_REPORT")
        if report:
            line = {"test": self.name, "seed": self.seed, "cases": self.run, **self.outcomes, "problems": self.problems}
            with open(report, "a") as handle:
                handle.write(json.dumps(line) + "\n")
        assert not self.problems, f"{len(self.problems)} of {self.run} cases:\n" + "\n".join(self.problems[:20])
