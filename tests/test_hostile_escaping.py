"""Hostile input, round 2 (class 5): user-provided strings never drive the terminal or a page.
Robot and team names holding ESC, BEL, C1 controls or bidirectional overrides are printed
escaped, on standard output and in error lines; HTML gets the same text HTML-escaped."""

from __future__ import annotations

import io

import pytest

from hostile_util import ROOT, run_cli, write_robot
from mobmanip.support.text import EscapingStream, escape_html, escape_terminal

TEAM_TEXT = (ROOT / "examples" / "beam_team.toml").read_text()
#: TOML escapes of hostile names: retitle the window, clear the screen, bell, 8-bit CSI, RTL override.
HOSTILE_NAMES = [r"a\u001b]0;pwned\u0007b", r"c\u001b[2Jd", r"e\u0007f", r"g\u009b31mh", r"i\u202ej", r"k\u0000l"]
RAW_CONTROLS = ("\x1b", "\x07", "\x9b", "\u202e", "\x00")


def _assert_clean(text: str) -> None:
    for control in RAW_CONTROLS:
        assert control not in text, repr(text)


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_team_and_robot_names_are_escaped_on_the_terminal(tmp_path, capfd, name):
    team = tmp_path / "team.toml"
    team.write_text(
        TEAM_TEXT.replace('name = "south"', f'name = "{name}"').replace('name = "beam"', f'name = "{name}"')
    )
    code, out, err = run_cli(capfd, "team", team)
    assert code == 0, err
    _assert_clean(out + err)
    assert "\\x" in out or "\\u" in out


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_names_in_error_lines_are_escaped(tmp_path, capfd, name):
    team = tmp_path / "team.toml"
    team.write_text(TEAM_TEXT.replace('robot = "planar_dual_arm"', f'robot = "{name}"'))
    code, out, err = run_cli(capfd, "team", team)
    assert code == 2
    _assert_clean(out + err)
    spec = write_robot(tmp_path, spec_edits=[('name = "planar_dual_arm"', f'name = "{name}"')])
    code, out, err = run_cli(capfd, "analyze", spec)
    _assert_clean(out + err)


def test_escape_functions():
    assert escape_terminal("a\x1b[2Jb\x07c\td\ne\r") == "a\\x1b[2Jb\\x07c\td\ne\r"
    assert escape_terminal("x\u202ey\x9b") == "x\\u202ey\\x9b"
    assert escape_html('<script>"\x1b') == "&lt;script&gt;&quot;\\x1b"
    buffer = io.StringIO()
    stream = EscapingStream(buffer)
    assert stream.write("\x1b]0;t\x07") == len("\x1b]0;t\x07")
    assert buffer.getvalue() == "\\x1b]0;t\\x07"


def test_a_hostile_name_in_an_exported_page_is_inert(tmp_path, capfd):
    page = tmp_path / "page.html"
    team = tmp_path / "team.toml"
    hostile = "</script><script>alert(1)</script>"
    team.write_text(TEAM_TEXT.replace('name = "south"', f'name = "{hostile}"'))
    code, _, err = run_cli(capfd, "team", team, "--export", page)
    assert code == 0, err
    html = page.read_text()
    assert hostile not in html  # names travel inside the scene's encoded commands, never as markup
    assert "<script>alert(1)" not in html


def test_the_documented_promise_names_every_command():
    """The promise paragraph of the command-line reference (docs/cli.md; it was the README's)
    covers every command the CLI registers."""
    from mobmanip.cli import build_parser

    text = (ROOT / "docs" / "cli.md").read_text()
    start = text.index("The promise, for every command")
    paragraph = text[start : text.index("\n\n", start)]
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    for name in commands:
        assert f"`{name}`" in paragraph, name
