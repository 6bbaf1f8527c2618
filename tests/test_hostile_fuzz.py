"""Hostile and broken input (6): a fuzz-style test. Valid URDFs, specs and configurations of the
paper's robot are mutated (numbers to NaN, inf, negative, huge or tiny; elements deleted or
duplicated) and run through ``mobmanip analyze``. Every run must end in exit code 2 with one
``mobmanip: error:`` line and no traceback, or in a result that the reference path confirms;
no non-finite number is ever printed or written, and no input file changes."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import mobmanip
from hostile_util import (
    NON_FINITE,
    PAPER_SPEC_TEXT,
    PAPER_URDF_TEXT,
    FuzzRun,
    assert_one_line_error,
    mutate_lines,
    run_cli,
)

HOSTILE_NUMBERS = ("nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-300", "1e12", "-0.5", "abc", "")
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")
URDF_ELEMENTS = re.compile(
    r"<(link|joint|inertial|limit|axis|mass|inertia|origin|parent|child|visual|collision)\b[^>]*?(/>|>.*?</\1>)", re.S
)
KINDS = ["urdf", "spec", "q"]
VALID_Q = {"platform": [0.3, -0.2, 0.4], "joints": {"arm_right_2_joint": 0.7, "arm_left_2_joint": -0.7}}


def _mutate_number(text: str, rng) -> str:
    matches = list(NUMBER.finditer(text))
    match = matches[rng.integers(len(matches))]
    value = HOSTILE_NUMBERS[rng.integers(len(HOSTILE_NUMBERS))]
    return text[: match.start()] + value + text[match.end() :]


def _mutate_element(text: str, rng) -> str:
    matches = list(URDF_ELEMENTS.finditer(text))
    match = matches[rng.integers(len(matches))]
    if rng.random() < 0.5:
        return text[: match.start()] + text[match.end() :]  # delete
    return text[: match.end()] + match.group(0) + text[match.end() :]  # duplicate


def _mutate_lines(text: str, rng) -> str:
    """A spec's line deleted, duplicated or uncommented (an override: radius, limits, ...)."""
    return mutate_lines(text, rng, 0.3, 0.6, edit=lambda line: line.lstrip("# "))


def _mutated_q(rng) -> str:
    document = json.loads(json.dumps(VALID_Q))
    choice = rng.random()
    value = HOSTILE_NUMBERS[rng.integers(len(HOSTILE_NUMBERS))]
    number = {"nan": "NaN", "inf": "Infinity", "-inf": "-Infinity", "abc": '"abc"', "": "null"}.get(value, value)
    text = json.dumps(document)
    if choice < 0.6:
        target = list(NUMBER.finditer(text))
        match = target[rng.integers(len(target))]
        return text[: match.start()] + number + text[match.end() :]
    if choice < 0.7:
        return "[" * 100_000 + "]" * 100_000  # nested far too deeply
    if choice < 0.8:
        return text.replace('"platform": [0.3, -0.2, 0.4]', f'"platform": [0.3, {number}]')
    if choice < 0.9:
        return text.replace('"arm_right_2_joint"', '"no_such_joint"')
    return text[: int(rng.integers(len(text)))]  # truncated


def _case(kind: str, seed: int, directory):
    rng = np.random.default_rng(seed)
    urdf, spec, q = PAPER_URDF_TEXT, PAPER_SPEC_TEXT, json.dumps(VALID_Q)
    if kind == "urdf":
        urdf = _mutate_number(urdf, rng) if rng.random() < 0.6 else _mutate_element(urdf, rng)
    elif kind == "spec":
        spec = _mutate_number(spec, rng) if rng.random() < 0.5 else _mutate_lines(spec, rng)
    else:
        q = _mutated_q(rng)
    (directory / "r.urdf").write_text(urdf)
    (directory / "r.toml").write_text(spec.replace("planar_dual_arm.urdf", "r.urdf"))
    (directory / "q.json").write_text(q)
    return directory / "r.toml", directory / "q.json"


def _check_result(spec, q_path, document, out: str) -> None:
    """A result printed and written: finite, and what the reference path computes."""
    assert NON_FINITE.search(out) is None, out
    robot = mobmanip.load_robot(spec)
    q = mobmanip.robot.configurations.read_configuration(robot, q_path)
    exact = mobmanip.analyze(robot, q, method="exact")
    for name, key in (("kinematic", "kinematic_ellipsoid"), ("dynamic", "dynamic_ellipsoid")):
        expected, got = exact.measures[name], document[key]
        scale = max(float(expected.semi_axes[0]), 1e-300)
        assert np.allclose(got["semi_axes"], expected.semi_axes, rtol=0, atol=1e-9 * scale), name


@pytest.mark.parametrize("kind", KINDS)
def test_mutated_inputs_give_one_line_or_a_correct_result(tmp_path, capfd, kind):
    fuzz = FuzzRun(f"analyze-{kind}", default=100)
    for case in fuzz:
        directory = tmp_path / f"{kind}{case}"
        directory.mkdir()
        k = KINDS.index(kind)
        seed = [fuzz.seed, k, case] if fuzz.seed else 1000 * (1 + k) + case  # seed 0: the suite's fixed cases
        spec, q = _case(kind, seed, directory)
        inputs = {p: p.read_bytes() for p in directory.iterdir()}
        out_json = directory / "out.json"
        argv = ("analyze", spec, "--q", q, "--json", out_json)
        code, out, err = run_cli(capfd, *argv)

        with fuzz.case(case, argv, "result" if code == 0 else "error"):
            assert {p: p.read_bytes() for p in inputs} == inputs, "an input changed"
            if code == 0:
                assert err == "", err
                text = out_json.read_text()
                assert NON_FINITE.search(text) is None
                _check_result(spec, q, json.loads(text), out)
            else:
                assert_one_line_error(code, err)
                assert "Traceback" not in err and out == "" or not NON_FINITE.search(out)
                assert not out_json.exists()
    fuzz.finish()
    assert fuzz.outcomes["error"] > 0 and fuzz.outcomes["result"] > 0, fuzz.outcomes  # both outcomes reached
