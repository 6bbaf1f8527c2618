"""BLAS and OpenMP thread pools: one thread each inside a ``mobmanip`` command, unless the user
sized them in the environment (mobmanip.support.threads).

The pools are read with threadpoolctl's ``threadpool_info()`` from inside a command's run: a
child Python process runs ``mobmanip.cli.main`` with the analyze command's ``run`` wrapped by a
spy that records the pools (and the environment a worker process would inherit) before the
command does its work. A process of its own, so that the pools of the test process are never
touched and the libraries load as they do for the console script.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mobmanip.errors import ArgumentError
from mobmanip.support.threads import VARIABLES, LimitedExecutor, limit_threads, user_governed

#: Every variable that sizes a pool, as the module reads them.
ALL_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "MKL_NUM_THREADS",
                 "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")  # fmt: skip

#: Runs ``mobmanip -vv analyze planar_dual_arm`` through cli.main and prints, as JSON, the pools
#: seen inside the command, after it, and before it (only when NumPy is loaded first: argv[1]),
#: and the variables named after it as the command's worker processes would inherit them.
SPY = r"""
import json, os, sys
numpy_first = sys.argv[1] == "numpy-first"
if numpy_first:
    import numpy
    from threadpoolctl import threadpool_info
import mobmanip.cli as cli

VARIABLES = sys.argv[2:]
seen = {}

def pools():
    from threadpoolctl import threadpool_info
    return [(info["user_api"], info["filepath"], info["num_threads"]) for info in threadpool_info()]

build_parser = cli.build_parser

def spying_build_parser(*args, **kwargs):
    from mobmanip.commands import analyze
    run = analyze.run

    def spy(args):
        seen["inside"] = pools()
        seen["environment"] = {name: os.environ.get(name) for name in VARIABLES}
        return run(args)

    analyze.run = spy
    return build_parser(*args, **kwargs)

cli.build_parser = spying_build_parser
if numpy_first:
    seen["before"] = pools()
seen["code"] = cli.main(["-vv", "analyze", "planar_dual_arm"])
seen["after"] = pools()
seen["environment_after"] = {name: os.environ.get(name) for name in VARIABLES}
print(json.dumps(seen))
"""

#: The pools a plain process gets from the same environment, NumPy and SciPy's linear algebra loaded.
PLAIN = r"""
import json
import numpy, scipy.linalg
from threadpoolctl import threadpool_info
print(json.dumps([(i["user_api"], i["filepath"], i["num_threads"]) for i in threadpool_info()]))
"""


def _environment(**user) -> dict[str, str]:
    environ = {k: v for k, v in os.environ.items() if k not in ALL_VARIABLES}
    environ.update(user)
    return environ


def _run(script: str | Path, environ: dict[str, str], *args: str, cwd=None) -> tuple[object, str]:
    """Run ``script`` (source, or a file) in a child Python; its last line read as JSON, and its stderr."""
    source = [str(script)] if isinstance(script, Path) else ["-c", script]
    child = subprocess.run([sys.executable, *source, *args], env=environ, capture_output=True, text=True,
                           cwd=cwd, timeout=300)  # fmt: skip
    assert child.returncode == 0, child.stderr
    return json.loads(child.stdout.strip().splitlines()[-1]), child.stderr


def _threads(pools, api: str) -> set[int]:
    return {threads for kind, _, threads in pools if kind == api}


def _blas_default(environ) -> int:
    """What the BLAS of a plain process gets from ``environ`` (OpenBLAS caps it at the cores)."""
    pools, _ = _run(PLAIN, environ)
    (threads,) = _threads(pools, "blas")
    return threads


# ------------------------------------------------------------------------------------------------
# which pools are the user's


@pytest.mark.parametrize(
    ("environ", "expected"),
    [
        ({}, set()),
        ({"PATH": "/usr/bin", "NUMBA_NUM_THREADS": "2"}, set()),
        ({"OPENBLAS_NUM_THREADS": "2"}, {"blas"}),
        ({"GOTO_NUM_THREADS": "2"}, {"blas"}),
        ({"MKL_NUM_THREADS": "4"}, {"blas"}),
        ({"BLIS_NUM_THREADS": "1"}, {"blas"}),
        ({"VECLIB_MAXIMUM_THREADS": "3"}, {"blas"}),
        ({"OMP_NUM_THREADS": "2"}, {"blas", "openmp"}),  # every BLAS falls back on OpenMP's variable
        ({"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "2"}, {"blas", "openmp"}),
    ],
)
def test_user_governed_names_the_pools_the_environment_sizes(environ, expected):
    assert user_governed(environ) == frozenset(expected)


# ------------------------------------------------------------------------------------------------
# the environment inside and after a block


@pytest.fixture
def clean_environment(monkeypatch):
    for name in ALL_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    return monkeypatch


def test_a_block_sets_every_variable_and_removes_it_after(clean_environment):
    with limit_threads() as kinds:
        assert kinds == {"blas", "openmp"}
        assert {name: os.environ.get(name) for name in ALL_VARIABLES} == {
            "OMP_NUM_THREADS": "1",
            "OPENBLAS_NUM_THREADS": "1",
            "GOTO_NUM_THREADS": None,  # OpenBLAS reads its own name first
            "MKL_NUM_THREADS": "1",
            "BLIS_NUM_THREADS": "1",
            "VECLIB_MAXIMUM_THREADS": "1",
        }
        assert user_governed() == frozenset()  # what the block set is not the user's
    assert not any(name in os.environ for name in ALL_VARIABLES)


def test_a_users_blas_variable_is_kept_and_only_openmp_is_limited(clean_environment):
    clean_environment.setenv("OPENBLAS_NUM_THREADS", "3")
    with limit_threads() as kinds:
        assert kinds == {"openmp"}
        assert os.environ["OPENBLAS_NUM_THREADS"] == "3"
        assert os.environ["OMP_NUM_THREADS"] == "1"
        assert not any(name in os.environ for name in VARIABLES["blas"] if name != "OPENBLAS_NUM_THREADS")
    assert os.environ["OPENBLAS_NUM_THREADS"] == "3"
    assert "OMP_NUM_THREADS" not in os.environ


def test_a_users_openmp_variable_leaves_every_pool_alone(clean_environment):
    clean_environment.setenv("OMP_NUM_THREADS", "2")
    with limit_threads() as kinds:
        assert kinds == frozenset()
        assert {name: os.environ.get(name) for name in ALL_VARIABLES if os.environ.get(name)} == {
            "OMP_NUM_THREADS": "2"
        }
    assert os.environ["OMP_NUM_THREADS"] == "2"


def test_nested_blocks_restore_the_outer_limit(clean_environment):
    with limit_threads():
        with limit_threads(2) as inner:
            assert inner == {"blas", "openmp"}  # the outer block's settings are not the user's
            assert os.environ["OPENBLAS_NUM_THREADS"] == os.environ["OMP_NUM_THREADS"] == "2"
        assert os.environ["OPENBLAS_NUM_THREADS"] == os.environ["OMP_NUM_THREADS"] == "1"
    assert not any(name in os.environ for name in ALL_VARIABLES)


def test_a_value_the_block_sets_itself_stays_and_becomes_the_users(clean_environment):
    with limit_threads():
        os.environ["OPENBLAS_NUM_THREADS"] = "4"
    assert os.environ["OPENBLAS_NUM_THREADS"] == "4"
    assert "OMP_NUM_THREADS" not in os.environ
    assert user_governed() == {"blas"}


@pytest.mark.parametrize("limit", [0, -1, 1.5, True, "1"])
def test_a_limit_must_be_a_positive_integer(limit):
    with pytest.raises(ArgumentError, match="positive integer"), limit_threads(limit):
        pass


# ------------------------------------------------------------------------------------------------
# inside a command's run


def test_a_command_runs_with_one_thread_per_pool(tmp_path):
    """The console script's case: nothing loaded before the command starts, no variable set."""
    seen, stderr = _run(SPY, _environment(), "fresh", *ALL_VARIABLES, cwd=tmp_path)
    assert seen["code"] == 0
    inside = seen["inside"]
    assert _threads(inside, "blas") == {1}, inside  # NumPy's OpenBLAS (and SciPy's, if loaded)
    assert _threads(inside, "openmp") <= {1}
    # worker processes the command starts inherit one thread per pool
    assert seen["environment"] == {name: (None if name == "GOTO_NUM_THREADS" else "1") for name in ALL_VARIABLES}
    # -vv names every pool and its threads once the command is done
    (line,) = [line for line in stderr.splitlines() if "thread pools" in line]
    assert "(blas) 1" in line and "(blas) 2" not in line
    # called from Python, main leaves the environment as it found it
    assert seen["environment_after"] == dict.fromkeys(ALL_VARIABLES)


def test_a_users_variable_wins_inside_a_command(tmp_path):
    environ = _environment(OPENBLAS_NUM_THREADS="2")
    expected = _blas_default(environ)  # 2 on a machine of 2 cores or more
    seen, _ = _run(SPY, environ, "fresh", *ALL_VARIABLES, cwd=tmp_path)
    assert _threads(seen["inside"], "blas") == {expected}
    assert _threads(seen["inside"], "openmp") <= {1}  # not the user's: limited
    assert seen["environment"]["OPENBLAS_NUM_THREADS"] == "2"
    assert seen["environment"]["OMP_NUM_THREADS"] == "1"

    environ = _environment(OMP_NUM_THREADS="2")
    expected = _blas_default(environ)
    seen, _ = _run(SPY, environ, "fresh", *ALL_VARIABLES, cwd=tmp_path)
    assert _threads(seen["inside"], "blas") == {expected}
    assert _threads(seen["inside"], "openmp") <= {expected}
    assert {k: v for k, v in seen["environment"].items() if v is not None} == {"OMP_NUM_THREADS": "2"}


def test_libraries_loaded_before_main_are_limited_and_restored(tmp_path):
    """A Python user's case: NumPy loaded before ``main`` is called; its BLAS gets its threads back
    afterwards, and a library first loaded inside the command keeps the one thread it started with."""
    environ = _environment()
    default = _blas_default(environ)
    seen, _ = _run(SPY, environ, "numpy-first", *ALL_VARIABLES, cwd=tmp_path)
    before = {path: threads for kind, path, threads in seen["before"] if kind == "blas"}
    after = {path: threads for kind, path, threads in seen["after"] if kind == "blas"}
    assert before and set(before.values()) == {default}
    assert _threads(seen["inside"], "blas") == {1}
    assert {path: after[path] for path in before} == before
    assert {path: threads for path, threads in after.items() if path not in before} == dict.fromkeys(
        set(after) - set(before), 1
    )


# ------------------------------------------------------------------------------------------------
# workers this process did not start: LimitedExecutor

#: One spawned worker with NumPy loaded and the environment of this script's process; prints, as
#: JSON, the worker's BLAS threads for a plain task, for a task through LimitedExecutor, and for a
#: plain task after it (the worker keeps its limit), and LimitedExecutor.map's results.
WORKER = r"""
import concurrent.futures as cf, importlib, json, multiprocessing
from threadpoolctl import threadpool_info
from mobmanip.support.threads import LimitedExecutor

def blas(info):
    return sorted({i["num_threads"] for i in info if i["user_api"] == "blas"})

if __name__ == "__main__":
    context = multiprocessing.get_context("spawn")
    with cf.ProcessPoolExecutor(1, mp_context=context, initializer=importlib.import_module,
                                initargs=("numpy",)) as pool:
        plain = blas(pool.submit(threadpool_info).result())
        limited = LimitedExecutor(pool)
        inside = blas(limited.submit(threadpool_info).result())
        after = blas(pool.submit(threadpool_info).result())
        mapped = list(limited.map(pow, [2, 3], [3, 2]))
    print(json.dumps({"plain": plain, "inside": inside, "after": after, "mapped": mapped}))
"""


def test_a_limited_executor_limits_the_workers_it_did_not_start(tmp_path):
    script = tmp_path / "worker.py"  # spawn imports the parent's __main__: a file, not -c
    script.write_text(WORKER)
    seen, _ = _run(script, _environment())  # the worker inherits no limit from its parent
    default = _blas_default(_environment())
    assert seen == {"plain": [default], "inside": [1], "after": [1], "mapped": [8, 9]}

    environ = _environment(OPENBLAS_NUM_THREADS="2")  # the worker's user sized its BLAS: it stays
    seen, _ = _run(script, environ)
    expected = _blas_default(environ)
    assert seen == {"plain": [expected], "inside": [expected], "after": [expected], "mapped": [8, 9]}


def test_a_limited_executor_refuses_a_bad_limit():
    import concurrent.futures as cf

    with cf.ThreadPoolExecutor(1) as pool, pytest.raises(ArgumentError, match="positive integer"):
        LimitedExecutor(pool, 0)
