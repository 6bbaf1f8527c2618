"""What the longer fuzz run (``scripts/fuzz.py``) found, held as plain tests.

- ``1_0`` was read as 10: Python's ``float`` takes underscores between digits (and digits of
  other scripts). A command line or a table that says ``1_0`` holds a typing error; numbers are
  read in decimal notation only, everywhere a number is read from text the user typed.
- ``place --map`` with a ``--map-extent`` wholly out of the arms' reach from the object ran the
  whole placement, printed its results and warnings, and only then failed on the map: more than
  one line for bad input, and the work thrown away. Such an extent is now refused first.
"""

from __future__ import annotations

import time

import pytest

from hostile_util import assert_one_line_error, run_cli

TYPOS = ["1_0", "\u0661", "1\u00a05"]  # underscore, ARABIC-INDIC DIGIT ONE, a no-break space inside


@pytest.mark.parametrize("typo", TYPOS)
def test_numbers_on_the_command_line_are_decimal_only(capfd, typo):
    for argv in (
        ["carry", "planar_dual_arm", "--path", "examples/carry_line.csv", "--step", typo],
        ["place", "planar_dual_arm", "--object", f"1,{typo},0.35", "--objective", "kinematic:capacity:+x"],
        ["sweep", "planar_dual_arm", "--angle", f"0,{typo}", "--no-progress"],
        ["sweep", "planar_dual_arm", "--angle", f"0:{typo}:3", "--no-progress"],
    ):
        code, out, err = run_cli(capfd, *argv)
        assert out == ""
        assert_one_line_error(code, err, repr(typo)[1:-1] if typo.isascii() else "")


@pytest.mark.parametrize("typo", TYPOS)
def test_numbers_in_a_table_are_decimal_only(tmp_path, capfd, typo):
    path = tmp_path / "p.csv"
    path.write_text(f"t,x,y\n0,0,0\n1,{typo},0\n2,0.2,0\n", encoding="utf-8")
    code, out, err = run_cli(capfd, "carry", "planar_dual_arm", "--path", path)
    assert out == ""
    assert_one_line_error(code, err, "p.csv line 3", "'x'", "not a number")


def test_decimal_numbers_still_read(tmp_path, capfd):
    """What decimal notation allows stays allowed: signs, a leading or trailing point, exponents."""
    from mobmanip.support.reading import decimal

    for text, value in (("1", 1.0), ("-2.5", -2.5), ("+.5", 0.5), ("3.", 3.0), ("1e-3", 1e-3), (" 2E+2 ", 200.0)):
        assert decimal(text) == value
    for text in ("1_0", "0x10", "", "1e", ".", "--1", "\u0661"):
        with pytest.raises(ValueError):
            decimal(text)


def test_a_map_extent_out_of_reach_is_refused_before_any_work(tmp_path, capfd):
    """The fuzz case itself (the object 10 m away from a 1 m square of platform positions): one
    line naming the extent, before the placement runs (nothing printed on standard output)."""
    maps = tmp_path / "maps"
    start = time.monotonic()
    code, out, err = run_cli(
        capfd, "place", "planar_dual_arm", "--object", "1,10,0.35", "--objective", "kinematic:capacity:+x",
        "--starts", "1", "--json", tmp_path / "j.json", "--map", maps, "--map-cells", "2", "--map-extent", "0,1,0,1",
    )  # fmt: skip
    assert_one_line_error(code, err, "--map-extent 0,1,0,1", "9.000 m away")
    assert out == "" and list(tmp_path.iterdir()) == []
    assert time.monotonic() - start < 5


def test_a_map_extent_around_the_object_is_not_refused(tmp_path, capfd):
    code, out, err = run_cli(
        capfd, "place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x",
        "--starts", "1", "--map", tmp_path / "maps", "--map-cells", "3", "--map-extent", "0,1,0,1", "--no-progress",
    )  # fmt: skip
    assert code == 0, err
    assert "platform positions hold the object" in out
