"""Every Numba compile announces itself on standard error, with its expected duration, before it
runs: the polytope/zonotope face kernel (``analyze --polytope``) and the gradient tree kernel
(``place --objective dynamic:...``), as the batch engine's kernel already did
(tests/test_compile_policy.py). Checked in fresh processes with an empty cache
(``NUMBA_CACHE_DIR``): the cold run announces each compile and reports its time, the warm run
(the cache filled) prints nothing.
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
PLACE = ["place", "tiago_dual", "--object", "2,1,0.9", "--mass", "3", "--objective", "dynamic:capacity:+z"]
ANNOUNCE = re.compile(r"^mobmanip: compiling (.+), once \(about (\d+) s on 2 cores")
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
            assert ANNOUNCE.match(first) and "about 7 s" in first
            assert DONE.match(second)
