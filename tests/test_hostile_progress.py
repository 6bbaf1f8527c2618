"""Progress bars for long runs: every command that can run long (carry, team-carry, trajectory,
place with --map, team --sweep-heading (also with --dask), sweep, site) draws one on standard
error when that is a terminal (a pseudo-terminal here), and none when standard error is piped;
standard output (results, JSON printed) never holds one, and ``--no-progress`` turns it off on a
terminal too."""

from __future__ import annotations

import fcntl
import os
import pty
import re
import struct
import subprocess
import sys
import termios
import threading
from pathlib import Path

import pytest

from shared_texts import grid_site

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SITE = grid_site(starts=1, x_count=2)
MOTION = (
    "t,platform_x,platform_y,platform_yaw,arm_right_2_joint\n"
    "0,0,0,0,0.5\n0.1,0.01,0,0,0.51\n0.2,0.02,0,0.01,0.52\n0.3,0.03,0,0.02,0.53\n"
)

#: command -> (argv after ``mobmanip``, the bar's description as the user reads it)
COMMANDS = {
    "carry": (["carry", "planar_dual_arm", "--path", EXAMPLES / "carry_line.csv", "--prepare", "0", "--out", "out"],
              "carry qp"),
    "trajectory": (["trajectory", "planar_dual_arm", "../motion.csv"], "trajectory planar_dual_arm"),
    "place": (["place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x",
               "--starts", "1", "--map", "maps", "--map-cells", "5"], "map"),
    "team": (["team", EXAMPLES / "beam_team.toml", "--sweep-heading=-10:10:3"], "team headings"),
    "team-carry": (["team-carry", EXAMPLES / "beam_team.toml", "--path", "../short.csv", "--prepare", "0"],
                   "team-carry qp"),
    "team-dask": (["team", EXAMPLES / "beam_team.toml", "--sweep-heading=-10:10:3", "--dask", "local:1"],
                  "team headings"),
    "sweep": (["sweep", "planar_dual_arm", "--angle", "0,90", "--distance", "1.0", "--workers", "1", "-o", "s"],
              "sweep planar_dual_arm"),
    "site": (["site", "../site.toml", "-o", "site"], "site planar_dual_arm"),
}  # fmt: skip


def _bar(description: str) -> re.Pattern:
    """tqdm's bar as drawn: ``DESC:  40%|####      | 2/5 [...]``."""
    return re.compile(re.escape(description) + r": +\d+%\|.*\| *\d+/\d+")


def _run(argv, cwd: Path, terminal: bool) -> tuple[int, str, str]:
    """The CLI in a subprocess; standard error on a pseudo-terminal when ``terminal``, else piped.
    Returns (exit code, stdout, stderr as read)."""
    command = [sys.executable, "-m", "mobmanip", *map(str, argv)]
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "COLUMNS": "120"}
    if not terminal:
        proc = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
        return proc.returncode, proc.stdout, proc.stderr
    master, slave = pty.openpty()
    # a terminal of 24 rows and 120 columns (a new pseudo-terminal has 0 x 0, where tqdm draws nothing)
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    proc = subprocess.Popen(command, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=slave)  # fmt: skip
    os.close(slave)
    chunks: list[bytes] = []

    def drain():
        while True:
            try:
                data = os.read(master, 65536)
            except OSError:  # EIO: the child closed the terminal
                return
            if not data:
                return
            chunks.append(data)

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    out, _ = proc.communicate(timeout=600)
    reader.join(timeout=30)
    os.close(master)
    return proc.returncode, out.decode(), b"".join(chunks).decode(errors="replace")


#: The first 2 s of examples/carry_line.csv: a team-carry of 100 steps per motion.
SHORT_PATH = "".join((EXAMPLES / "carry_line.csv").read_text().splitlines(keepends=True)[:22])


@pytest.fixture
def work(tmp_path):
    (tmp_path / "site.toml").write_text(SITE)
    (tmp_path / "motion.csv").write_text(MOTION)
    (tmp_path / "short.csv").write_text(SHORT_PATH)
    return tmp_path


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_bar_on_a_terminal_none_in_piped_output(work, command):
    argv, description = COMMANDS[command]
    bar = _bar(description)

    (work / "tty").mkdir()
    code, out, err = _run(argv, work / "tty", terminal=True)
    assert code == 0, err
    assert bar.search(err), f"no {description!r} bar on the terminal: {err!r}"
    assert "\r" not in out and not bar.search(out)

    (work / "pipe").mkdir()
    code, out, err = _run(argv, work / "pipe", terminal=False)
    assert code == 0, err
    assert not bar.search(err) and "\r" not in err, f"a bar in piped standard error: {err!r}"
    assert "\r" not in out and not bar.search(out)


@pytest.mark.parametrize("command", ["carry", "site", "team-carry"])
def test_no_progress_turns_the_bar_off_on_a_terminal(work, command):
    argv, description = COMMANDS[command]
    (work / "quiet").mkdir()
    code, _, err = _run([*argv, "--no-progress"], work / "quiet", terminal=True)
    assert code == 0, err
    assert not _bar(description).search(err), err
