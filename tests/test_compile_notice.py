"""Every Numba compile announces itself on standard error, with up to how long it may take,
before it runs: the polytope/zonotope face kernel (``analyze --polytope``) and the gradient tree
kernel (``place --objective dynamic:...`` with enough starts to use it), as the batch engine's kernel already did
(tests/test_compile_policy.py). Checked in fresh processes with an empty cache
(``NUMBA_CACHE_DIR``): the cold run announces each compile and reports its time, the warm run
(the cache filled) prints nothing, and ``mobmanip warmup`` finds those kernels cached. On a
terminal a line counts the seconds while a compile runs. The announced bounds are at least the
slowest compiles measured (issue 39: "about 2 s" took 18.9 s on a busy machine); ``warmup`` names
every kernel, compiles those missing and reports the others cached.
"""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
import time

import pytest

from conftest import ROOT
from mobmanip.support.compile_notice import announced_compile, numba_cached

ANALYZE = ["analyze", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "spatial", "--polytope"]
#: Ten starts: a placement of fewer runs the gradients' NumPy forms (COMPILED_FROM_ROUNDS).
PLACE = ["place", "tiago_dual", "--object", "2,1,0.9", "--mass", "3", "--objective", "dynamic:capacity:+z",
         "--starts", "10"]  # fmt: skip
ANNOUNCE = re.compile(r"^mobmanip: compiling (.+), once \(up to (\d+) s on a busy 2-core machine")
DONE = re.compile(r"^mobmanip: (.+) compiled in ([\d.]+) s$")


def _run(args, cache, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.Popen(
        [sys.executable, "-m", "mobmanip", *args], cwd=tmp_path, env=env, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


def _timed_lines(process):
    """stderr lines with the time each arrived (s since the call)."""
    start, lines = time.perf_counter(), []
    assert process.stderr is not None
    for line in process.stderr:
        lines.append((time.perf_counter() - start, line.rstrip("\n")))
    assert process.wait() == 0
    return lines


@pytest.mark.parametrize("args, kernels", [(ANALYZE, ["face kernel for 3-D sets"]),
                                           (PLACE, ["world_inertias", "mass_and_gravity", "bilinear_rows"])],
                         ids=["polytope", "tree"])  # fmt: skip
def test_cold_compiles_are_announced_and_warm_runs_are_silent(args, kernels, tmp_path):
    cache = tmp_path / "numba_cache"
    cache.mkdir()
    cold = _timed_lines(_run(args, cache, tmp_path))
    announced = [(t, m.group(1), int(m.group(2))) for t, line in cold if (m := ANNOUNCE.match(line))]
    finished = [(t, m.group(1), float(m.group(2))) for t, line in cold if (m := DONE.match(line))]
    for name in kernels:
        starts = [a for a in announced if name in a[1]]
        ends = [f for f in finished if name in f[1]]
        assert len(starts) == 1 and len(ends) == 1, (name, cold)
        (t0, what, expected), (t1, what_done, took) = starts[0], ends[0]
        assert what == what_done and expected >= 1
        assert t0 <= t1 and took <= t1 - t0 + 0.5  # announced before the compile, not after
    assert os.listdir(cache)  # the compiles were kept on disk
    warm = _timed_lines(_run(args, cache, tmp_path))
    assert not any(ANNOUNCE.match(line) or DONE.match(line) for _, line in warm), warm
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_CACHE_DIR": str(cache)}
    listed = subprocess.run(
        [sys.executable, "-m", "mobmanip", "warmup", "--list", "--only", kernels[0]], cwd=tmp_path, env=env,
        capture_output=True, text=True, check=True,
    ).stdout.splitlines()  # fmt: skip
    assert len(listed) == 1 and f"{kernels[0]}" in listed[0] and ": cached (a compile takes up to" in listed[0]


class _FakeCacheFile:
    def __init__(self, index):
        self.index = index

    def _load_index(self):
        if isinstance(self.index, Exception):
            raise self.index
        return self.index


class _FakeDispatcher:
    def __init__(self, index):
        self._cache = type("C", (), {"_cache_file": _FakeCacheFile(index)})()


def test_the_notice_follows_the_cache():
    """Cached: silent; missing or unreadable: announced with the expected time, then the time taken."""
    assert numba_cached([_FakeDispatcher({"sig": "file"})]) is True
    assert numba_cached([_FakeDispatcher({"sig": "file"}), _FakeDispatcher({})]) is False
    assert numba_cached([_FakeDispatcher(KeyError("layout"))]) is None
    for index, printed in (({"sig": "file"}, False), ({}, True), (KeyError("layout"), True)):
        stream = io.StringIO()
        with announced_compile("the test kernel", 7.0, [_FakeDispatcher(index)], stream=stream):
            pass
        text = stream.getvalue()
        assert bool(text) == printed
        if printed:
            first, second = text.splitlines()
            assert ANNOUNCE.match(first) and "up to 7 s" in first
            assert DONE.match(second)


def test_the_announced_bounds_hold_every_measured_compile():
    """Each kernel's announced bound is at least its slowest compile measured on a busy machine;
    the batch kernel's by its end effectors, as printed."""
    from mobmanip.engine.compiled import expected_compile_seconds
    from mobmanip.support.compile_notice import MEASURED, UP_TO

    assert set(MEASURED) == set(UP_TO)
    for kernel, seconds in MEASURED.items():
        assert seconds and UP_TO[kernel] >= max(seconds), kernel
    assert expected_compile_seconds(1) == UP_TO["batch, 1 end effector"]
    assert expected_compile_seconds(2) == UP_TO["batch, 2 end effectors"]


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_compile_counts_its_seconds_on_a_terminal():
    """On a terminal the notice redraws a line with the seconds so far, and clears it at the end;
    in a file (not a terminal) it writes only its two lines."""
    from mobmanip.support.compile_notice import compiling

    for stream, counts in ((_Terminal(), True), (io.StringIO(), False)):
        with compiling("the test kernel", 9.0, stream=stream, tick=0.05):
            time.sleep(0.3)
        text = stream.getvalue()
        lines = [line for line in text.split("\n") if line]
        assert ANNOUNCE.match(lines[0]) and DONE.match(lines[-1].split("\r\033[K")[-1])
        ticks = re.findall(r"\r  compiling: (\d+) s of up to 9 s ", text)
        assert (len(ticks) >= 2) == counts and ("\033[K" in text) == counts


def test_warmup_compiles_what_is_missing_and_names_each_kernel(monkeypatch, capsys):
    """``warmup`` names every kernel with its state; compiles the missing ones (each named with the
    time it took) and reports the cached ones; a second run finds them all cached."""
    from mobmanip.cli import main
    from mobmanip.commands import warmup

    cache: dict[str, bool] = {"alpha kernel": False, "beta kernel": True, "gamma kernel": False}
    compiled = []

    def fake(name):
        return warmup.Kernel(
            name, 5.0, lambda: cache[name], lambda: (compiled.append(name), cache.update({name: True}))
        )

    monkeypatch.setattr(warmup, "kernels", lambda: [fake(name) for name in cache])
    assert main(["warmup", "--list"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "alpha kernel: not cached (a compile takes up to 5 s)",
        "beta kernel: cached (a compile takes up to 5 s)",
        "gamma kernel: not cached (a compile takes up to 5 s)",
    ]
    assert main(["warmup"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert compiled == ["alpha kernel", "gamma kernel"]
    assert re.fullmatch(r"alpha kernel: compiled in [\d.]+ s \(up to 5 s\)", out[0])
    assert out[1] == "beta kernel: cached"
    assert out[3].startswith("3 kernels: 2 compiled in ") and out[3].endswith(", 1 already cached")
    assert main(["warmup", "--only", "gamma"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "gamma kernel: cached",
        "1 kernels: 0 compiled in 0.0 s, 1 already cached",
    ]
    assert main(["warmup", "--only", "delta"]) == 2
    assert "--only 'delta' names no kernel" in capsys.readouterr().err


def test_warmup_lists_every_compiled_kernel(capsys):
    """The real list: both face kernels, both sweep kernels, the tree kernel's loops and the batch
    kernel of each built-in robot's default task, each with its state and bound."""
    from mobmanip.cli import main
    from mobmanip.gradients.tree_adjoint import LOOPS

    assert main(["warmup", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for name in ("face kernel for 2-D sets", "face kernel for 3-D sets", "planar polytope sweep", "3-D zonotope sweep",
                 *LOOPS, "1 end effector and a 3-D task", "1 end effector and a 6-D task",
                 "2 end effectors and a 2-D task", "2 end effectors and a 6-D task"):  # fmt: skip
        assert sum(name in line for line in lines) == 1, (name, lines)
    assert all(re.search(r": (cached|not cached|cannot tell) \(a compile takes up to \d+ s\)$", line) for line in lines)
