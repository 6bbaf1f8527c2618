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


# --- Mutations shared by the fuzzers (tests/test_hostile_fuzz_commands.py) -------------------

#: What a number in an input becomes: non-finite, huge, tiny, negative, text, 400 digits, other
#: notations, a terminal escape, a stray quote.
HOSTILE = ("nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-300", "1e12", "-0.5", "abc", "", "9" * 400,
           "1e-200", "0x10", "1_0", "\x1b[2J", '"')  # fmt: skip
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")
#: What a name becomes: control characters (a terminal escape, a NUL, a newline, a bell).
HOSTILE_NAME_TAILS = ("\x1b[2J", "\x00", "\n", "\x07", "\r", "\u202e")
NAMES = ("name", "model", "link", "joint", "site", "body", "class", "childclass", "robot", "arm", "mesh")
NAME_VALUE = re.compile(r'((?:name|link|joint|site|body|class|childclass|robot|arm)\s*=\s*")([^"]*)(")')
ATTRIBUTE = re.compile(r'\s([\w:]+)="([^"]*)"')
#: An element without children (``<x .../>``) or with only text (``<x ...>text</x>``).
LEAF_ELEMENT = re.compile(r"<([\w:]+)\b[^<>]*?(?:/>|>[^<>]*</\1>)")
XACRO_EXPRESSION = re.compile(r"\$\{[^{}]*\}")
#: What a xacro expression becomes: errors, non-finite and huge values, unknown names.
HOSTILE_EXPRESSIONS = ("${1/0}", "${float('nan')}", "${float('inf')}", "${-1e308*10}", "${undefined_name}",
                       "${'text'}", "${[1, 2]}", "${10**400}", "${", "${}", "${__import__('os')}")  # fmt: skip


def mutate_number(text: str, rng, values=HOSTILE) -> str:
    """One number of ``text`` replaced by a hostile value."""
    matches = list(NUMBER.finditer(text))
    match = matches[rng.integers(len(matches))]
    value = values[rng.integers(len(values))]
    return text[: match.start()] + value + text[match.end() :]


def mutate_lines(text: str, rng, delete: float = 0.4, duplicate: float = 0.8, edit=None) -> str:
    """One line deleted (a draw below ``delete``) or duplicated (below ``duplicate``), else the
    text cut anywhere, or with ``edit`` the line replaced by ``edit(line)``."""
    lines = text.splitlines(keepends=True)
    k = int(rng.integers(len(lines)))
    choice = rng.random()
    if choice < delete:
        del lines[k]
    elif choice < duplicate:
        lines.insert(k, lines[k])
    elif edit is None:
        return text[: int(rng.integers(len(text)))]  # cut
    else:
        lines[k] = edit(lines[k])
    return "".join(lines)


def mutate_name(text: str, rng) -> str:
    """A control character (or a right-to-left override) added to one name of ``text``: a
    ``name = "..."`` of TOML, a ``name="..."`` (or link, joint, site, ...) attribute of XML."""
    matches = list(NAME_VALUE.finditer(text))
    if not matches:
        return mutate_lines(text, rng)
    match = matches[rng.integers(len(matches))]
    tail = HOSTILE_NAME_TAILS[rng.integers(len(HOSTILE_NAME_TAILS))]
    return text[: match.end(2)] + tail + text[match.end(2) :]


def mutate_text(text: str, rng, names: float = 0.0) -> str:
    """A table, a TOML file or an option's text: a number made hostile (60 %), a line deleted
    (15 %) or duplicated (15 %), the text cut (10 %); with ``names`` > 0, that share of the cases
    instead puts a control character into a name (``names=0`` draws what it always drew, so the
    suite's fixed cases stay the same)."""
    if names and rng.random() < names:
        return mutate_name(text, rng)
    choice = rng.random()
    if choice < 0.6:
        return mutate_number(text, rng)
    lines = text.splitlines(keepends=True)
    k = int(rng.integers(len(lines)))
    if choice < 0.75:
        del lines[k]
    elif choice < 0.9:
        lines.insert(k, lines[k])
    else:
        return text[: int(rng.integers(len(text)))]  # cut
    return "".join(lines)


def mutate_xml(text: str, rng) -> str:
    """A robot file (URDF, xacro, MJCF): a number in an attribute, an attribute deleted, doubled
    or emptied, an element deleted or duplicated, a name with a control character, a line deleted,
    duplicated or cut; for xacro also an expression ``${...}`` made hostile, a property's value
    or a macro's parameter list mutated."""
    choice = rng.random()
    if "xacro" in text and choice < 0.25:
        return _mutate_xacro(text, rng)
    if choice < 0.5:
        return mutate_number(text, rng)
    if choice < 0.65:
        matches = list(ATTRIBUTE.finditer(text))
        match = matches[rng.integers(len(matches))]
        which = rng.random()
        if which < 0.4:
            return text[: match.start()] + text[match.end() :]  # deleted
        if which < 0.6:
            return text[: match.end()] + match.group(0) + text[match.end() :]  # doubled (not XML)
        value = ("", " ", "1 2", "nan nan nan", "1e309")[rng.integers(5)]
        if match.group(1) in NAMES:  # a name is text: "nan" there is a name, printed as given
            value = value.replace("nan", "x")
        return text[: match.start(2)] + value + text[match.end(2) :]
    if choice < 0.8:
        matches = list(LEAF_ELEMENT.finditer(text))
        match = matches[rng.integers(len(matches))]
        if rng.random() < 0.5:
            return text[: match.start()] + text[match.end() :]
        return text[: match.end()] + match.group(0) + text[match.end() :]
    if choice < 0.88:
        return mutate_name(text, rng)
    return mutate_lines(text, rng)


def _mutate_xacro(text: str, rng) -> str:
    choice = rng.random()
    if choice < 0.5:
        matches = list(XACRO_EXPRESSION.finditer(text))
        match = matches[rng.integers(len(matches))]
        value = HOSTILE_EXPRESSIONS[rng.integers(len(HOSTILE_EXPRESSIONS))]
        return text[: match.start()] + value + text[match.end() :]
    if choice < 0.75:
        properties = list(re.finditer(r'(<xacro:property name="\w+" value=")([^"]*)(")', text))
        match = properties[rng.integers(len(properties))]
        value = (*HOSTILE, *HOSTILE_EXPRESSIONS)[rng.integers(len(HOSTILE) + len(HOSTILE_EXPRESSIONS))]
        return text[: match.start(2)] + value + text[match.end(2) :]
    macros = list(re.finditer(r'(<xacro:macro name="\w+" params=")([^"]*)(")', text))
    match = macros[rng.integers(len(macros))]
    params = match.group(2).split()
    if params and rng.random() < 0.5:
        del params[int(rng.integers(len(params)))]  # a parameter the macro's calls pass goes missing
    else:
        params.append("extra")  # one the calls do not pass
    return text[: match.start(2)] + " ".join(params) + text[match.end(2) :]


def hostile_option(rng, default: str) -> str:
    """An option's value: its valid default half the time, else a hostile value."""
    return default if rng.random() < 0.5 else HOSTILE[rng.integers(len(HOSTILE))]


def check_fuzz_case(fuzz: FuzzRun, case: int, argv, code, out: str, err: str, inputs: dict, outputs, partial=None):
    """The promise of every fuzz case, noted in ``fuzz``: no input changed, no raw escape on the
    terminal; exit 0 with only finite numbers printed and written (in the ``outputs``' JSON and
    CSV files), or exit 2 with one ``mobmanip: error:`` line and nothing written, unless
    ``partial(outputs)`` says the failed run kept, flagged, the part that succeeded."""
    with fuzz.case(case, argv, "result" if code == 0 else "error"):
        assert {p: p.read_bytes() for p in inputs} == inputs, "an input changed"
        assert "\x1b" not in out + err, "a raw escape reached the terminal"
        if code == 0:
            assert NON_FINITE.search(out) is None, out
            for path in outputs:
                files = [path] if path.is_file() else list(path.rglob("*.json")) + list(path.rglob("*.csv"))
                for file in files:
                    assert NON_FINITE.search(file.read_text()) is None, file
        else:
            assert_one_line_error(code, err)
            if partial is not None and partial(outputs):
                assert "partial" in out and NON_FINITE.search(out) is None, out
            else:
                assert not any(p.exists() for p in outputs), f"exit {code} ({err.strip()}) wrote {outputs}"
