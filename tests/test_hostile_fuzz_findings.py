"""What the longer fuzz run (``scripts/fuzz.py``) found, held as plain tests.

- ``1_0`` was read as 10: Python's ``float`` takes underscores between digits (and digits of
  other scripts). A command line or a table that says ``1_0`` holds a typing error; numbers are
  read in decimal notation only, everywhere a number is read from text the user typed.
- An MJCF number attribute of ``1_0`` was read as 10 by mobmanip and as garbage by Pinocchio's
  own MJCF parser (the model built from the same text): they are read in decimal notation too.
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


# --- Round 3 (issue 40): what the fuzzers of team-carry, collision-matrix, site, xacro and MJCF
# found. -------------------------------------------------------------------------------------

SITE_HEAD = 'robot = "planar_dual_arm"\nobjective = "kinematic:capacity:+x"\nstarts = 1\n'


@pytest.mark.parametrize(
    ("positions", "needles"),
    [
        ("[[1.0, " + "9" * 400 + ", 0.35]]", ("positions[0][1] is an integer of 400 digits",)),
        ("[[1.0, 0.5, 0.35], [-" + "9" * 309 + ", 0.5, 0.35]]", ("positions[1][0] is an integer of 309 digits",)),
        ("[[1.0, 0.5, 0.35], [1.5, nan, 0.35]]", ("positions[1][1] = nan must be finite",)),
        ("[[1.0, 0.5, -inf]]", ("positions[0][2] = -inf must be finite",)),
    ],
)
def test_a_site_position_no_float_holds_is_named(tmp_path, capfd, positions, needles):
    """An integer of hundreds of digits among a site's positions was an internal error
    (OverflowError); now one line names the entry, as a non-finite one is named."""
    site = tmp_path / "site.toml"
    site.write_text(SITE_HEAD + f"positions = {positions}\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--no-progress")
    assert_one_line_error(code, err, str(site), *needles)
    assert out == "" and not (tmp_path / "out").exists()


def test_a_site_position_of_a_large_but_finite_integer_is_not_an_overflow(tmp_path):
    """10**300 m is a float: it is refused as beyond the positions a floor holds (+-1e6 m, as a
    platform's), naming the entry, not as too large for a float (a figure could not draw it)."""
    from mobmanip.errors import SpecError
    from mobmanip.placement.site import Site

    site = tmp_path / "site.toml"
    site.write_text(SITE_HEAD + f"positions = [[1.0, {10**300}, 0.35]]\n")
    with pytest.raises(SpecError, match=r"positions\[0\]\[1\] = 1e\+300 m is beyond \+-1e\+06 m"):
        Site.read(site)


MJCF = """<mujoco model="m">
  <worldbody>
    <body name="base"><freejoint/><inertial pos="0 0 0" mass="10" diaginertia="0.1 0.2 0.25"/>
      <body name="arm" pos="0 0 0.3"><joint name="j" axis="0 1 0" range="-1 1"/>
        <geom type="{kind}" size="{size}" mass="1"/><site name="tool" pos="0.3 0 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize(
    ("kind", "size", "needle"),
    [
        ("box", "0.1 0.2", "a box needs 3 size numbers, got size='0.1 0.2'"),
        ("box", "1e309", "a box needs 3 size numbers, got size='1e309'"),
        ("capsule", "0.03", "a capsule needs 2 size numbers"),
        ("ellipsoid", "0.1", "an ellipsoid needs 3 size numbers"),
        ("sphere", "abc", "size is not numeric: 'abc'"),
    ],
)
def test_an_mjcf_geom_with_too_few_or_unreadable_sizes_is_named(tmp_path, capfd, kind, size, needle):
    """A box of one size number was an internal error (IndexError); now one line names the file,
    the body and what the geom's type needs."""
    path = tmp_path / "robot.xml"
    path.write_text(MJCF.format(kind=kind, size=size))
    code, out, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", "tool")
    assert_one_line_error(code, err, f"MJCF {path}", "body 'arm'", needle)
    assert out == ""


def test_an_mjcf_geom_with_its_sizes_is_read(tmp_path):
    from mobmanip.descriptions import read_description

    path = tmp_path / "robot.xml"
    path.write_text(MJCF.format(kind="box", size="0.1 0.2 0.3"))
    (shape,) = [s for link in read_description(path).links.values() for s in link.collisions + link.visuals][:1]
    assert shape.size == pytest.approx((0.2, 0.4, 0.6))


@pytest.mark.parametrize("typo", TYPOS[:2])
@pytest.mark.parametrize(
    ("old", "new"),
    [('pos="0 0 0.3"', 'pos="0 0 {}"'), ('mass="1"', 'mass="{}"'), ('range="-1 1"', 'range="-1 {}"'),
     ('size="0.1 0.2 0.3"', 'size="0.1 0.2 {}"'), ('mass="10"', 'mass="{}"')],
    ids=["body pos", "geom mass", "joint range", "geom size", "inertial mass"],
)  # fmt: skip
def test_numbers_in_an_mjcf_file_are_decimal_only(tmp_path, capfd, typo, old, new):
    """A body at ``pos="1_0 0 0"`` was read as 10 m by mobmanip and as 1.9e227 m by Pinocchio's
    own MJCF parser, which builds the model from the same text: the analysis stopped with an
    internal error (LinAlgError: SVD did not converge; the fuzz run of seed 23, MJCF case 1498).
    A number attribute is read in decimal notation only, as MuJoCo reads it: one line naming the
    file and the value."""
    path = tmp_path / "robot.xml"
    text = MJCF.format(kind="box", size="0.1 0.2 0.3")
    assert text.count(old) == 1
    path.write_text(text.replace(old, new.format(typo)), encoding="utf-8")
    code, out, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", "tool")
    assert_one_line_error(code, err, f"MJCF {path}", typo)
    assert out == ""


@pytest.mark.parametrize(
    ("grid", "needle"),
    [
        (
            "x = [1.0, " + "9" * 400 + ", 2]\ny = 0.5\nz = 0.35",
            "[grid] x must be finite, got 1.0, an integer of 400 digits",
        ),
        ("x = 1.0\ny = -" + "9" * 400 + "\nz = 0.35", "[grid] y must be finite, got an integer of 400 digits"),
        ("x = 1.0\ny = 0.5\nz = [0.1, inf, 2]", "[grid] z must be finite, got 0.1, inf"),
        # the longer run (seed 11): a finite axis far beyond any floor reached the figure as limits
        # it refused, an internal error after the table was computed
        ("x = 1.0\ny = -1e308\nz = 0.35", "[grid] y from -1e+308 to -1e+308 m goes beyond +-1e+06 m"),
    ],
)
def test_a_site_grid_axis_no_float_holds_is_named(tmp_path, capfd, grid, needle):
    """The longer run (seed 7): a grid axis ending at an integer of 400 digits was an internal
    error (OverflowError); now the axis and the value are named."""
    site = tmp_path / "site.toml"
    site.write_text(SITE_HEAD + f"[grid]\n{grid}\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--no-progress")
    assert_one_line_error(code, err, str(site), needle)
    assert out == "" and not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("mass", "shown"), [("inf", "inf"), ("nan", "nan"), ("9" * 400, "an integer of 400 digits"), ("-1", "-1")]
)
def test_a_site_mass_that_is_not_finite_is_refused(tmp_path, capfd, mass, shown):
    """The longer run (seed 7): ``mass = inf`` ran every position, wrote a table whose every row
    gave the same reason and exited 0; a mass that is no finite number is refused on reading."""
    site = tmp_path / "site.toml"
    site.write_text(SITE_HEAD + f"mass = {mass}\npositions = [[1.0, 0.5, 0.35]]\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--no-progress")
    assert_one_line_error(code, err, str(site), f"'mass' must be a finite non-negative number of kg, got {shown}")
    assert out == "" and not (tmp_path / "out").exists()


def test_a_work_count_no_float_holds_is_refused_by_its_length(tmp_path, capfd):
    """The longer run (seed 7): ``collision-matrix --samples`` with 400 digits was an internal
    error (OverflowError) while the work bound described it; now the bound refuses it by its
    length."""
    code, out, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--samples", "9" * 400,
                             "--out", tmp_path / "m.json")  # fmt: skip
    assert_one_line_error(code, err, "a number of 400 digits of", "--max-work")
    assert out == "" and list(tmp_path.iterdir()) == []


def test_an_inertia_warning_against_a_geometry_of_absurd_size_prints_no_infinity(tmp_path, capfd):
    """The longer run (seed 7): a xacro wheel 1e308 m long gave the warning "trace inf kg m^2, inf
    times more", in the terminal and in the JSON; it now says the trace is beyond any float."""
    from hostile_util import NON_FINITE
    from test_hostile_fuzz_commands import XACRO_TEXT

    robot = tmp_path / "robot.urdf.xacro"
    robot.write_text(XACRO_TEXT.replace('length="0.04"', 'length="1e308"'))
    out_json = tmp_path / "a.json"
    code, out, err = run_cli(capfd, "analyze", "--urdf", robot, "--ee", "tool", "--json", out_json)
    assert code == 0, err
    assert "has a trace beyond any float" in err
    assert NON_FINITE.search(out + err + out_json.read_text()) is None


@pytest.mark.parametrize("command", ["carry", "team-carry"])
def test_a_preparation_longer_than_any_float_counts_is_refused_by_the_work_bound(tmp_path, capfd, command):
    """The longer run (seed 11): ``--prepare 1e308`` makes a step count of infinity, which the
    work bound's description turned into an internal error (OverflowError)."""
    target = ["planar_dual_arm"] if command == "carry" else ["examples/beam_team.toml"]
    code, out, err = run_cli(capfd, command, *target, "--path", "examples/carry_line.csv", "--prepare", "1e308",
                             "--out", tmp_path / "out")  # fmt: skip
    assert_one_line_error(code, err, "more than any float counts of", "--max-work")
    assert out == "" and list(tmp_path.iterdir()) == []


def test_a_friction_coefficient_no_float_holds_is_named(tmp_path, capfd):
    """The longer run (seed 11): a site's ``[grounded] mu`` of 400 digits was an internal error
    (OverflowError in math.isfinite); it is now above the largest friction coefficient."""
    site = tmp_path / "site.toml"
    site.write_text(SITE_HEAD + "positions = [[1.0, 0.5, 0.35]]\n[grounded]\nmu = " + "9" * 400 + "\n")
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--no-progress")
    assert_one_line_error(code, err, "[grounded] mu 9999", "is above 10")
    assert out == "" and not (tmp_path / "out").exists()


def test_a_map_extent_narrower_than_a_millimetre_is_refused(tmp_path, capfd):
    """The longer run (seed 11): ``--map-extent 0,1e-200,0,1`` reached the map's figure as an axis
    it could not draw, an internal error after the map was computed."""
    code, out, err = run_cli(capfd, "place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective",
                             "kinematic:capacity:+x", "--map", tmp_path / "m",
                             "--map-extent", "0,1e-200,0,1")  # fmt: skip
    assert_one_line_error(code, err, "--map-extent", "at least 0.001 m", "0,1e-200,0,1")
    assert out == "" and not (tmp_path / "m").exists()
