"""Hostile input, round 2 (classes 2, 3 and 10): one output path for every command. A run killed
with SIGINT or SIGTERM at any moment leaves no temporary file, no partial output and no new empty
directory; outputs are all or none; special files, inputs behind symlinks and long names are
handled before any work."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hostile_util import ROOT, assert_one_line_error, run_cli, write_robot
from mobmanip.support.files import NAME_MAX, publish_together, temporary_prefix, write_text

SRC = ROOT / "src"
CARRY_PATH = ROOT / "examples" / "carry_line.csv"


def _start(cwd: Path, *argv) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    return subprocess.Popen(
        [sys.executable, "-m", "mobmanip", *map(str, argv)],
        cwd=cwd,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def _kill_all_after(procs: list[subprocess.Popen], delay: float, signum: int) -> list[tuple[int, str]]:
    """Send ``signum`` to every process still running ``delay`` s after the last one's ``main``
    began (counted from there, not from the launch: on a loaded machine Python's own start-up,
    before any line of the command's, can take longer than the shortest delay)."""
    for proc in procs:
        _wait_until_main_runs(proc)
    time.sleep(delay)
    for proc in procs:
        if proc.poll() is None:
            proc.send_signal(signum)
    errors = [proc.communicate(timeout=120)[1] for proc in procs]
    return [(proc.returncode, err) for proc, err in zip(procs, errors)]


def _listing(directory: Path) -> list[str]:
    return sorted(str(p.relative_to(directory)) for p in directory.rglob("*"))


#: How the program ends on each signal: SIGTERM exits with 143; Ctrl-C ends the process by
#: SIGINT itself (the shell reports 130), so that a shell loop running mobmanip stops too.
_EXIT = {signal.SIGINT: -signal.SIGINT, signal.SIGTERM: 128 + signal.SIGTERM}
_LINE = {signal.SIGINT: "mobmanip: interrupted; no output was written",
         signal.SIGTERM: "mobmanip: terminated; no output was written"}  # fmt: skip


def _wait_until_main_runs(proc: subprocess.Popen) -> None:
    """Until the command's ``main`` has begun, seen from outside: its SIGTERM handler shows in the
    process's caught-signal mask. Before that moment only Python's own start-up runs (no line of
    the command's); from it on, the imports of NumPy and Pinocchio are still to come."""
    status = Path(f"/proc/{proc.pid}/status")
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        with contextlib.suppress(OSError):
            for line in status.read_text().splitlines():
                if line.startswith("SigCgt:") and int(line.split()[1], 16) >> (signal.SIGTERM - 1) & 1:
                    return
        time.sleep(0.002)
    raise AssertionError("the command's main never started")


def test_importing_the_command_loads_neither_numpy_nor_pinocchio():
    """What the console script and ``python -m mobmanip`` import before ``main`` runs is the
    standard library only: an interrupt during the heavy imports reaches main's handler."""
    code = "import sys, mobmanip.cli; print(sorted({'numpy', 'pinocchio', 'scipy'} & set(sys.modules)))"
    proc = subprocess.run([sys.executable, "-c", code], env={**os.environ, "PYTHONPATH": str(SRC)},
                          capture_output=True, text=True, check=True)  # fmt: skip
    assert proc.stdout.strip() == "[]", proc.stdout


def _entry_points():
    script = Path(sys.executable).with_name("mobmanip")
    yield pytest.param([sys.executable, "-m", "mobmanip"], id="python-m")
    yield pytest.param(
        [str(script)], id="console-script", marks=pytest.mark.skipif(not script.exists(), reason="not installed")
    )


@pytest.mark.parametrize("entry", list(_entry_points()))
def test_an_interrupt_at_any_moment_is_one_line(tmp_path, entry):
    """Ctrl-C or SIGTERM from the first moment of ``main`` on (through the imports of NumPy,
    SciPy and Pinocchio, loading the robot, computing, writing): no traceback, the one line
    and the program's exit status, and the output either complete or absent."""
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    seen = set()
    cases = [(d, signal.SIGINT) for d in (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.8, 1.1, 1.5)]
    cases += [(d, signal.SIGTERM) for d in (0.0, 0.1, 0.4)]
    for k, (delay, signum) in enumerate(cases):
        work = tmp_path / f"run{k}"
        work.mkdir()
        proc = subprocess.Popen([*entry, "analyze", "planar_dual_arm", "--json", "out.json"], cwd=work, env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
        _wait_until_main_runs(proc)
        time.sleep(delay)
        if proc.poll() is None:
            proc.send_signal(signum)
        out, err = proc.communicate(timeout=120)
        assert "Traceback" not in err, (delay, err)
        if proc.returncode == 0:  # finished before the signal: complete, and the signal ignored
            assert [p.name for p in work.iterdir()] == ["out.json"]
            assert json.loads((work / "out.json").read_text())
            seen.add("finished")
        else:
            assert proc.returncode == _EXIT[signum], (delay, signum, proc.returncode, err)
            assert err.strip().splitlines() == [_LINE[signum]], err
            assert out == "" and list(work.iterdir()) == [], (delay, out)
            seen.add(signum)
    assert signal.SIGINT in seen and signal.SIGTERM in seen, seen


_FINALISER_SCRIPT = """
import signal, sys, time
import mobmanip.cli as cli

class Holder:
    def __del__(self):  # stands for e.g. a matplotlib weak-reference callback
        signal.raise_signal(signal.{signal})  # arrives while the finaliser runs

def run(args):
    Holder()  # dropped at once: the signal is raised inside __del__, where Python swallows it
    for _ in range(100):  # the command goes on computing; the signal must still end it here
        time.sleep(0.05)
    print("finished")
    return 0

cli._run = run
sys.argv = ["mobmanip", "analyze", "planar_dual_arm"]
sys.exit(cli.main())
"""


_SWALLOWED_SCRIPT = """
import signal, sys
import mobmanip.cli as cli

def extension_import():  # as an extension module's init does when its import is interrupted
    try:
        signal.raise_signal(signal.{signal})
        for _ in range(10**6):
            pass
    except KeyboardInterrupt:
        raise ImportError("initialization failed") from None


def optional_import():  # as code that turns a failed import into advice does
    from mobmanip.errors import MobmanipError

    try:
        extension_import()
    except ImportError:
        raise MobmanipError("reading this needs the xacro package: pip install xacro") from None

{where} = lambda *a, **k: {call}()
sys.argv = ["mobmanip", "analyze", "planar_dual_arm"]
sys.exit(cli.main())
"""


@pytest.mark.parametrize(
    ("where", "call"),
    [
        ("cli._check_outputs_first", "extension_import"),
        ("cli.build_parser", "extension_import"),
        ("cli._check_outputs_first", "optional_import"),
    ],
)
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_an_interrupt_a_library_turns_into_its_own_error_is_still_an_interrupt(signum, where, call):
    """CI saw a killed carry end in "internal error (ImportError: initialization failed)": the
    signal arrived while an extension module was being imported, and its init reported an
    ImportError instead (and code that turns a failed import into advice would have printed the
    advice). A signal received during the command makes any error after it the interrupt's one
    line and exit status, in the command's work and before it."""
    script = _SWALLOWED_SCRIPT.replace("{signal}", signal.Signals(signum).name).replace("{where}", where)
    script = script.replace("{call}", call)
    proc = subprocess.run([sys.executable, "-c", script], env={**os.environ, "PYTHONPATH": str(SRC)},
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert "Traceback" not in proc.stderr and "internal error" not in proc.stderr, proc.stderr
    assert proc.stderr.strip().splitlines() == [_LINE[signum]], proc.stderr
    assert proc.returncode == _EXIT[signum], (proc.returncode, proc.stderr)


_AFTER_PUBLISHING_SCRIPT = """
import signal, sys
import mobmanip.cli as cli

cli._log_thread_pools = lambda: signal.raise_signal(signal.{signal})  # right after the files are published
sys.argv = ["mobmanip", "analyze", "planar_dual_arm", "--json", "out.json"]
sys.exit(cli.main())
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_once_the_outputs_are_published_is_ignored(tmp_path, signum):
    """Ctrl-C or SIGTERM after the command has returned and its files are published (the
    interrupt test's 0.5 s landed there once): the run ends as finished, exit 0, the file there
    and "wrote out.json" true. It ended as interrupted, "no output was written", beside the file."""
    script = _AFTER_PUBLISHING_SCRIPT.replace("{signal}", signal.Signals(signum).name)
    proc = subprocess.run([sys.executable, "-c", script], env={**os.environ, "PYTHONPATH": str(SRC)}, cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert proc.returncode == 0, (proc.returncode, proc.stderr)
    assert proc.stderr == "" and proc.stdout.rstrip().endswith("wrote out.json")
    assert json.loads((tmp_path / "out.json").read_text())["robot"] == "planar_dual_arm"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_inside_a_finaliser_still_ends_the_run_in_one_line(signum):
    """Python cannot raise an interrupt that arrives inside a finaliser or a garbage-collector
    callback; it prints "Exception ignored in ..." with a traceback and goes on. The command
    passes the signal on instead: the same one line and exit status as anywhere else."""
    script = _FINALISER_SCRIPT.replace("{signal}", signal.Signals(signum).name)
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", script], env={**os.environ, "PYTHONPATH": str(SRC)},
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert time.monotonic() - start < 4.5  # ended at once, not after the command's work
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr, proc.stderr
    assert proc.stderr.strip().splitlines() == [_LINE[signum]], proc.stderr
    assert proc.stdout == "" and proc.returncode == _EXIT[signum], (proc.returncode, proc.stdout)


@pytest.mark.parametrize(
    ("command", "files"),
    [
        ("carry", {"trajectory.csv", "baseline.csv", "carry.json", "capacity.png"}),
        ("trajectory", {"analysis.csv", "analysis.json", "analysis.png"}),
    ],
)
def test_a_killed_run_leaves_nothing_behind(tmp_path, command, files):
    """Killed at several moments (loading, computing, writing): the new output directory is
    gone, or holds every file; an existing directory keeps its earlier files untouched."""
    trajectory = tmp_path / "motion.csv"
    if command == "trajectory":
        subprocess.run(
            [sys.executable, "-m", "mobmanip", "carry", "planar_dual_arm", "--path", CARRY_PATH, "--prepare", "0",
             "--out", tmp_path / "made"],
            env={**os.environ, "PYTHONPATH": str(SRC)}, check=True, capture_output=True,
        )  # fmt: skip
        (tmp_path / "made" / "trajectory.csv").rename(trajectory)

    def argv(out):
        if command == "carry":
            return ("carry", "planar_dual_arm", "--path", CARRY_PATH, "--prepare", "0", "--out", out)
        return ("trajectory", "planar_dual_arm", trajectory, "--out", out)

    outcomes = set()
    for k, (delay, signum) in enumerate([(0.3, signal.SIGTERM), (1.2, signal.SIGINT), (2.0, signal.SIGTERM),
                                         (3.0, signal.SIGTERM), (4.5, signal.SIGINT)]):  # fmt: skip
        work = tmp_path / f"run{k}"
        work.mkdir()
        existing = work / "kept"
        existing.mkdir()
        (existing / next(iter(sorted(files)))).write_text("earlier result")
        # the run into a new directory and the run into an existing one side by side, killed together
        procs = [_start(work, *argv("new/sub")), _start(work, *argv("kept"))]
        (code_new, err_new), (code_old, err_old) = _kill_all_after(procs, delay, signum)
        for code, err in ((code_new, err_new), (code_old, err_old)):
            # One line, also while NumPy and Pinocchio are being imported (0.3 s after main began).
            assert "Traceback" not in err, err
            assert code in (0, _EXIT[signum]), (code, err)
        listing = _listing(work)
        assert not [name for name in listing if ".tmp" in name or name.endswith(".previous")], listing
        # A signal that arrives while the files are renamed into place is held until all are.
        if (work / "new").exists():
            assert set(_listing(work / "new" / "sub")) == files, listing
            outcomes.add("done")
        else:
            assert code_new != 0  # the directories it made are removed
            outcomes.add("killed")
        kept = set(_listing(existing))
        if kept != files:
            assert code_old != 0
            assert kept == {sorted(files)[0]} and (existing / sorted(files)[0]).read_text() == "earlier result"
    assert "killed" in outcomes, outcomes


def test_a_failed_command_removes_the_directories_it_created(tmp_path, capfd):
    trajectory = tmp_path / "bad.csv"
    trajectory.write_text("t,platform_x\n0,1\n")
    code, _, err = run_cli(capfd, "trajectory", "planar_dual_arm", trajectory, "--out", tmp_path / "a" / "b")
    assert_one_line_error(code, err)
    assert not (tmp_path / "a").exists()
    path = tmp_path / "path.csv"
    path.write_text("t,x,y\n0,0,0\n")  # one row: too short
    code, _, err = run_cli(capfd, "carry", "planar_dual_arm", "--path", path, "--out", tmp_path / "c")
    assert_one_line_error(code, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "path.csv"]


def test_publish_together_removes_created_directories_on_interrupt(tmp_path):
    from mobmanip.support.files import output_directory

    with pytest.raises(KeyboardInterrupt):
        with publish_together():
            out = output_directory(tmp_path / "x" / "y")
            write_text(out / "a.txt", "a")
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("length", [200, 240, 250, 255])
def test_long_output_names_work_up_to_the_file_system_limit(tmp_path, capfd, length):
    name = "a" * (length - len(".json")) + ".json"
    code, _, err = run_cli(capfd, "analyze", "planar_dual_arm", "--json", tmp_path / name)
    assert code == 0, err
    assert [p.name for p in tmp_path.iterdir()] == [name]
    assert len(temporary_prefix(name).encode()) + 8 + len(".tmp.previous") <= NAME_MAX
    multibyte = "é" * 127 + ".j"  # 256 bytes would be too long; 127 two-byte letters and .j fit
    assert len(temporary_prefix(multibyte).encode()) + 8 + len(".tmp.previous") <= NAME_MAX


def test_a_name_over_the_limit_is_one_line(tmp_path, capfd):
    code, _, err = run_cli(capfd, "analyze", "planar_dual_arm", "--json", tmp_path / ("a" * 256))
    assert_one_line_error(code, err, "too long")


def test_place_twice_with_the_same_figure_and_json(tmp_path, capfd):
    """The figure and JSON written by the first run are outputs, not inputs, of the second."""
    spec = write_robot(tmp_path)
    argv = ["place", spec, "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x", "--starts", "1",
            "--figure", tmp_path / "f.png", "--json", tmp_path / "j.json", "--save-q", tmp_path / "q.json"]  # fmt: skip
    for _ in range(2):
        code, _, err = run_cli(capfd, *argv)
        assert code == 0, err


@pytest.mark.parametrize("name", ["out.xyz", "out.png.bak", "out.docx"])
@pytest.mark.parametrize("command", ["place", "team"])
def test_unknown_figure_formats_are_refused_before_work(tmp_path, capfd, command, name):
    if command == "place":
        argv = ["place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x",
                "--figure", tmp_path / name]  # fmt: skip
    else:
        argv = ["team", ROOT / "examples" / "beam_team.toml", "--plot", tmp_path / name]
    code, out, err = run_cli(capfd, *argv)
    assert_one_line_error(code, err, "unknown figure format")
    assert out == "" and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("special", ["/dev/stdout", "/dev/stderr", "/dev/fd/1", "/proc/self/fd/1"])
def test_standard_output_as_a_file_is_refused(tmp_path, special):
    """Decided: ``--json /dev/stdout`` is refused like every device (the results are printed on
    standard output anyway). When standard output is redirected to a file, writing there
    atomically would replace the file under the shell's redirection."""
    redirected = tmp_path / "printed.txt"
    with open(redirected, "w") as stdout:
        proc = subprocess.run(
            [sys.executable, "-m", "mobmanip", "analyze", "planar_dual_arm", "--json", special],
            env={**os.environ, "PYTHONPATH": str(SRC)}, stdout=stdout, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
    assert_one_line_error(proc.returncode, proc.stderr, special)
    assert redirected.read_text() == ""
    proc = subprocess.run(
        [sys.executable, "-m", "mobmanip", "analyze", "planar_dual_arm", "--json", special],
        env={**os.environ, "PYTHONPATH": str(SRC)}, capture_output=True, text=True,
    )  # fmt: skip
    assert_one_line_error(proc.returncode, proc.stderr)


def test_place_map_entries_that_lead_to_inputs_or_devices_are_refused(tmp_path, capfd):
    spec = write_robot(tmp_path)
    urdf = spec.with_suffix(".urdf")
    before = {p: p.read_bytes() for p in (spec, urdf)}
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for name, target in (("map.csv", spec), ("map.npz", urdf), ("map.png", spec), ("map.csv", fifo),
                         ("map.npz", Path(os.devnull))):  # fmt: skip
        directory = tmp_path / f"d_{name}_{target.name}"
        directory.mkdir()
        (directory / name).symlink_to(target)
        code, out, err = run_cli(
            capfd, "place", spec, "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x", "--starts", "1",
            "--map", directory, "--map-cells", "3",
        )  # fmt: skip
        assert_one_line_error(code, err, name)
        assert out == ""
        assert [p.name for p in directory.iterdir()] == [name]
    code, out, err = run_cli(
        capfd, "place", spec, "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x", "--map", fifo
    )
    assert_one_line_error(code, err, "not a directory")
    assert {p: p.read_bytes() for p in before} == before


def test_a_failed_place_map_writes_no_file(tmp_path, capfd):
    """All or none across the whole command: the map, the JSON and the figure together."""
    out = tmp_path / "maps"
    code, _, err = run_cli(
        capfd, "place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x",
        "--starts", "1", "--map", out, "--map-cells", "3", "--json", tmp_path / "j.json",
        "--export", tmp_path / "missing" / "page.html",
    )  # fmt: skip
    assert_one_line_error(code, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_map_whose_bands_run_together_ends_in_one_line(tmp_path, signum):
    """``place --map`` runs its bands as coroutines taking turns (mobmanip.support.lockstep): a
    signal arrives inside whichever band runs; it ends every band at once, the command in its one
    line, with no map written. The signal is sent once ``-v`` has logged that the bands began."""
    log = tmp_path / "stderr.txt"
    with open(log, "w") as stderr:
        proc = subprocess.Popen(
            [sys.executable, "-m", "mobmanip", "-v", "place", "planar_dual_arm", "--object", "1,0.5,0.35",
             "--objective", "kinematic:capacity:+x", "--map", str(tmp_path / "map")],
            cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(SRC)}, stdout=subprocess.DEVNULL, stderr=stderr,
        )  # fmt: skip
    deadline = time.monotonic() + 60
    while "solved together" not in log.read_text() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.01)
    time.sleep(0.05)  # well inside the bands (the 15 x 15 map takes about a second)
    assert proc.poll() is None, "the command ended before its map began"
    sent = time.monotonic()
    proc.send_signal(signum)
    proc.wait(timeout=60)
    err = log.read_text()
    assert time.monotonic() - sent < 5.0
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == _LINE[signum], err
    assert proc.returncode == _EXIT[signum]
    assert not (tmp_path / "map").exists()
