"""Hostile input, round 2 (fuzz): the decision commands under mutated inputs, as
``test_hostile_fuzz.py`` does for ``analyze``. Valid inputs of ``carry`` (an object path),
``trajectory`` (a motion), ``place`` (its options, with a map) and ``team`` (a team file) are
mutated (numbers to NaN, inf, huge, tiny, negative, text or 400 digits; lines deleted, duplicated
or cut; control characters in names). Every run ends in exit code 2 with one ``mobmanip:
error:`` line, or in exit 0 with only finite numbers printed and written; no input file ever
changes and a failed run writes nothing.

``MOBMANIP_FUZZ_CASES`` sets the mutations per command (default 60, about 10 s each); a longer
run, with other seeds and a time budget, is ``python scripts/fuzz.py`` (see
:class:`hostile_util.FuzzRun`)."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from hostile_util import NON_FINITE, ROOT, FuzzRun, assert_one_line_error, run_cli

COMMANDS = ["carry", "trajectory", "place", "team"]
HOSTILE = ("nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-300", "1e12", "-0.5", "abc", "", "9" * 400,
           "1e-200", "0x10", "1_0", "\x1b[2J", '"')  # fmt: skip
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")
TEAM_TEXT = (ROOT / "examples" / "beam_team.toml").read_text()
PATH_TEXT = "t,x,y\n0,0,0\n0.1,0.001,0\n0.2,0.004,0.001\n0.3,0.009,0.002\n"
MOTION_TEXT = (
    "t,platform_x,platform_y,platform_yaw,arm_right_2_joint\n"
    "0,0,0,0,0.5\n0.1,0.01,0,0,0.51\n0.2,0.02,0,0.01,0.52\n0.3,0.03,0,0.02,0.53\n"
)


def _mutate_text(text: str, rng, toml: bool = False) -> str:
    choice = rng.random()
    if choice < 0.6:
        matches = list(NUMBER.finditer(text))
        match = matches[rng.integers(len(matches))]
        value = HOSTILE[rng.integers(len(HOSTILE))]
        if toml and value in ("nan", "inf", "-inf"):
            value = {"nan": "nan", "inf": "inf", "-inf": "-inf"}[value]
        return text[: match.start()] + value + text[match.end() :]
    lines = text.splitlines(keepends=True)
    k = int(rng.integers(len(lines)))
    if choice < 0.75:
        del lines[k]
    elif choice < 0.9:
        lines.insert(k, lines[k])
    else:
        return text[: int(rng.integers(len(text)))]  # cut
    return "".join(lines)


def _hostile_option(rng, default: str) -> str:
    return default if rng.random() < 0.5 else HOSTILE[rng.integers(len(HOSTILE))]


def _case(command: str, rng, directory):
    """(argv, input files, output files) of one mutated run."""
    if command == "carry":
        path = directory / "p.csv"
        path.write_text(_mutate_text(PATH_TEXT, rng))
        out = directory / "out"
        argv = ["carry", "planar_dual_arm", "--path", path, "--prepare", _hostile_option(rng, "0"),
                "--step", _hostile_option(rng, "0.05"), "--out", out]  # fmt: skip
        return argv, [path], [out]
    if command == "trajectory":
        path = directory / "m.csv"
        path.write_text(_mutate_text(MOTION_TEXT, rng))
        out = directory / "out"
        return ["trajectory", "planar_dual_arm", path, "--out", out], [path], [out]
    if command == "place":
        values = ["1", "0.5", "0.35"]
        values[int(rng.integers(3))] = _hostile_option(rng, "0.5")
        out = directory / "j.json"
        maps = directory / "maps"
        argv = ["place", "planar_dual_arm", "--object", ",".join(values), "--objective", "kinematic:capacity:+x",
                "--starts", "1", "--json", out, "--map", maps, "--map-cells", "2",
                "--map-extent", f"0,{_hostile_option(rng, '1')},0,1"]  # fmt: skip
        if rng.random() < 0.3:
            argv += ["--object-yaw", _hostile_option(rng, "10")]
        return argv, [], [out, maps]
    team = directory / "team.toml"
    team.write_text(_mutate_text(TEAM_TEXT, rng, toml=True))
    out = directory / "t.json"
    return ["team", team, "--json", out], [team], [out]


def _partial_carry(command: str, outputs) -> bool:
    """Whether a failed run is a carry that wrote the part that succeeded: its ``carry.json``
    says ``"partial": true`` and every number it wrote is finite (a failed carry keeps the part
    that succeeded: docs/howto/floor.md, team.md)."""
    summary = outputs[0] / "carry.json"
    if command != "carry" or not summary.is_file():
        return False
    for file in [*outputs[0].glob("*.json"), *outputs[0].glob("*.csv")]:
        assert NON_FINITE.search(file.read_text()) is None, file
    return json.loads(summary.read_text()).get("partial") is True


@pytest.mark.parametrize("command", COMMANDS)
def test_mutated_inputs_give_one_line_or_a_finite_result(tmp_path, capfd, command):
    fuzz = FuzzRun(command, default=60)
    for case in fuzz:
        rng = np.random.default_rng([fuzz.seed, COMMANDS.index(command), case])
        directory = tmp_path / f"c{case}"
        directory.mkdir()
        argv, inputs, outputs = _case(command, rng, directory)
        before = {p: p.read_bytes() for p in inputs}
        code, out, err = run_cli(capfd, *argv)

        with fuzz.case(case, argv, "result" if code == 0 else "error"):
            assert {p: p.read_bytes() for p in inputs} == before, "an input changed"
            assert "\x1b" not in out + err, "a raw escape reached the terminal"
            if code == 0:
                assert NON_FINITE.search(out) is None, out
                for path in outputs:
                    files = [path] if path.is_file() else list(path.rglob("*.json")) + list(path.rglob("*.csv"))
                    for file in files:
                        assert NON_FINITE.search(file.read_text()) is None, file
            else:
                assert_one_line_error(code, err)
                if _partial_carry(command, outputs):  # carry keeps what succeeded, flagged partial
                    assert "partial" in out and NON_FINITE.search(out) is None, out
                else:
                    assert not any(p.exists() for p in outputs), f"exit {code} ({err.strip()}) wrote {outputs}"
    fuzz.finish()
    assert fuzz.outcomes["error"] > 0 and fuzz.outcomes["result"] > 0, fuzz.outcomes
