"""When the compiled kernel is compiled: only where it pays, once per pair, announced.

One configuration (``analyze``, and so the ``analyze`` / ``view`` / ``place`` commands) never
waits for a compile: it takes the reference path until this process has compiled the kernel
for that (end effectors, task dimension) pair, and then the kernel, whose ellipsoids equal the
reference's to 1e-10 of their size. Batches and sweeps compile it once per pair, announced on
standard error before any progress bar starts.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import mobmanip
from conftest import ROOT, random_configurations
from mobmanip.batch import analyze_batch, kernel_available, kernel_cached, kernel_ready, warm_kernel
from mobmanip.engine import compiled

needs_kernel = pytest.mark.skipif(not kernel_available(), reason="Numba is not installed")

_ONE_SHOT = textwrap.dedent(
    """
    import json, sys, time
    import numpy as np
    import mobmanip
    from mobmanip.engine import compiled
    robot = mobmanip.load_robot("tiago_dual")
    qs = np.load(sys.argv[1])
    start = time.perf_counter()
    results = [mobmanip.analyze(robot, q, "spatial", object_mass=2.0) for q in qs]
    seconds = time.perf_counter() - start
    kernel = sys.modules.get("mobmanip.engine.kernel")
    print(json.dumps({
        "seconds": seconds,
        "ready": compiled.kernel_ready(2, 6),
        "signatures": 0 if kernel is None else len(kernel.run_chunk.signatures),
        "kinematic": [a.kinematic.semi_axes.tolist() for a in results],
        "dynamic": [a.dynamic.semi_axes.tolist() for a in results],
        "center": [a.dynamic.center.tolist() for a in results],
    }))
    """
)


def test_one_configuration_compiles_nothing(tmp_path, rng):
    """In a fresh process with an empty Numba cache, analyze on TIAGo++ (spatial task) compiles
    no kernel, writes nothing to the cache, answers in well under a second per configuration,
    and gives the reference path's ellipsoids (computed here in this process)."""
    robot = mobmanip.load_robot("tiago_dual")
    qs = np.array(random_configurations(robot, rng, 5))
    np.save(tmp_path / "qs.npy", qs)
    script = tmp_path / "one_shot.py"
    script.write_text(_ONE_SHOT)
    cache = tmp_path / "numba_cache"
    cache.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "qs.npy")], capture_output=True, text=True, check=True, env=env
    )
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["ready"] is False and out["signatures"] == 0
    assert not any(name.startswith("engine") for name in os.listdir(cache))  # no engine kernel cached
    assert "compiling" not in done.stderr
    assert out["seconds"] < 5.0  # five configurations; a compile takes 10 to 20 s on 2 cores
    for i, q in enumerate(qs):
        exact = mobmanip.analyze(robot, q, "spatial", object_mass=2.0, method="exact")
        k_scale = exact.kinematic.semi_axes[0]
        np.testing.assert_allclose(out["kinematic"][i], exact.kinematic.semi_axes, rtol=0, atol=1e-12 * k_scale)
        if not exact.dynamic.empty:
            d_scale = max(exact.dynamic.semi_axes[0], np.linalg.norm(exact.dynamic.center))
            np.testing.assert_allclose(out["dynamic"][i], exact.dynamic.semi_axes, rtol=0, atol=1e-12 * d_scale)
            np.testing.assert_allclose(out["center"][i], exact.dynamic.center, rtol=0, atol=1e-12 * d_scale)


@needs_kernel
def test_after_a_batch_analyze_takes_the_kernel_and_agrees(robot, rng):
    """Once a batch compiled the kernel for the pair, analyze takes it (the engine's a-priori
    bounds are reported) and still equals the reference path to 1e-10 of each ellipsoid's size."""
    qs = np.array(random_configurations(robot, rng, 6))
    analyze_batch(robot, qs[:1], "planar")
    assert kernel_ready(len(robot.arms), 2)
    for q in qs:
        fast = mobmanip.analyze(robot, q, "planar")
        exact = mobmanip.analyze(robot, q, "planar", method="exact")
        scale = exact.kinematic.semi_axes[0]
        np.testing.assert_allclose(fast.kinematic.semi_axes, exact.kinematic.semi_axes, rtol=0, atol=1e-10 * scale)
        d_scale = max(exact.dynamic.semi_axes[0], np.linalg.norm(exact.dynamic.center))
        np.testing.assert_allclose(fast.dynamic.semi_axes, exact.dynamic.semi_axes, rtol=0, atol=1e-10 * d_scale)


@needs_kernel
def test_one_compiled_signature_per_pair(robot, rng):
    """Read-only limits (the robot's own) and writable ones (a sweep's scaled copies) reach the
    kernel as the same Numba type, so each (end effectors, task dimension) pair compiles once."""
    from mobmanip.engine import kernel
    from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep

    qs = np.array(random_configurations(robot, rng, 3))
    analyze_batch(robot, qs, "planar")  # the robot's read-only limit vectors
    grid = SweepGrid(angle_deg=[0.0, 90.0], distance=[0.9, 1.1], wheel_velocity_scale=[0.5, 1.0])
    run_sweep(SweepSpec("planar_dual_arm"), grid, workers=1)  # scaled, writable limit vectors
    pairs = [(sig[0].count, sig[1].count) for sig in kernel.run_chunk.signatures]
    assert len(pairs) == len(set(pairs)), pairs
    assert kernel_cached(len(robot.arms), 2) in (True, None)  # on disk after its compile (or cannot tell)


@needs_kernel
def test_warm_kernel_and_the_announcement():
    """warm_kernel readies the pair of the robot and task; a compile of a pair missing from the
    disk cache is announced once, with an expected duration in seconds, and timed after."""
    panda = mobmanip.load_robot("panda")
    assert warm_kernel(panda, "translational") is True
    assert kernel_ready(1, 3)
    stream = io.StringIO()
    with compiled._first_call(9, 5, stream):  # a pair no test compiles
        assert (9, 5) not in compiled._READY
    assert (9, 5) in compiled._READY
    compiled._READY.discard((9, 5))
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2
    assert "compiling" in lines[0] and "9 end effectors" in lines[0] and "5-D task" in lines[0]
    assert f"up to {compiled.expected_compile_seconds(9):.0f} s" in lines[0]
    assert lines[1].startswith(f"mobmanip: {compiled.kernel_name(9, 5)} compiled in")
