"""What a command line imports: only what its command needs (a command's start-up is mostly
imports). Read in a fresh interpreter's ``sys.modules`` after each command has run."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Packages no command below uses: the viewer, the mesh and simulation libraries, the cluster.
#: ``mobmanip.viz.figures`` imports pyplot and draws the robots; the map's figure needs neither.
NEVER = ("meshcat", "trimesh", "mujoco", "dask", "distributed", "matplotlib.pyplot", "mobmanip.viz.figures")
#: Every command module but the one named.
OTHER_COMMANDS = ("analyze", "sweep", "view", "init_spec", "trajectory", "team", "carry", "site", "paper")

_SCRIPT = """
import contextlib, io, json, sys
from mobmanip.cli import main
watched = json.loads(sys.argv[1])
seen = []
for argv in json.loads(sys.argv[2]):
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main(argv)
    seen.append([code, [name for name in watched if name in sys.modules]])
print(json.dumps(seen))
"""


def _imported(tmp_path, *commands: list[str]) -> list[tuple[int, set[str]]]:
    """For each command, run in turn in one fresh interpreter: its exit code and the watched
    modules imported so far."""
    watched = [*NEVER, "matplotlib", "numba", *(f"mobmanip.commands.{name}" for name in OTHER_COMMANDS)]
    proc = subprocess.run(
        [sys.executable, "-c", _SCRIPT, json.dumps(watched), json.dumps(commands)],
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    return [(code, set(names)) for code, names in json.loads(proc.stdout)]


def test_a_command_imports_neither_other_commands_nor_what_it_does_not_draw_with(tmp_path):
    """``place`` without --figure draws nothing: no matplotlib at all; with --map it writes the
    map's PNG through matplotlib's Agg canvas, without pyplot or the robot-drawing figures. No
    other command's module is imported, nor the viewer, meshes, MuJoCo or Dask. A placement of
    a few starts runs the gradients' NumPy forms and never loads Numba; the map's thousands of
    evaluations run the compiled loops."""
    (placed, after_place), (mapped, after_map) = _imported(
        tmp_path,
        ["place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x"],
        [
            "place",
            "planar_dual_arm",
            "--object",
            "1,0.5,0.35",
            "--objective",
            "kinematic:capacity:+x",
            "--map",
            str(tmp_path / "map"),
            "--map-cells",
            "5",
        ],  # fmt: skip
    )
    assert placed == 0 and mapped == 0
    assert after_place == set(), after_place
    assert after_map == {"matplotlib", "numba"}, after_map
    assert (tmp_path / "map" / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_every_command_is_registered_under_its_module_name():
    """The parser built for a command line names its command alone, found by the command's
    module name: every command's ``register`` adds the name :data:`mobmanip.commands.NAMES` has."""
    from mobmanip.cli import build_parser
    from mobmanip.commands import NAMES

    def commands(parser) -> list[str]:
        (subparsers,) = (action for action in parser._actions if action.dest == "command")
        return list(subparsers.choices)

    assert commands(build_parser()) == list(NAMES)
    for name in NAMES:
        assert commands(build_parser(name)) == [name]


def test_the_command_is_read_past_the_verbosity_options_only():
    """``-v``/``-vv``/``--verbose`` may come before the command; any other option first (``--help``,
    ``--version``) leaves the command unnamed, and the parser then registers every command."""
    from mobmanip.cli import command_named

    assert command_named(["place", "tiago_dual", "-v"]) == "place"
    assert command_named(["-vv", "--verbose", "-v", "team-carry", "--help"]) == "team-carry"
    assert command_named(["--help", "place"]) is None
    assert command_named(["--version"]) is None
    assert command_named(["-", "place"]) is None
    assert command_named([]) is None
