"""TIAGo++'s allowed-collision matrix: the matrix path equals the all-pairs path on every pair it
keeps, the pairs it leaves out keep what the rule says, the shipped file is what the generator
writes, the gradients are the distances' derivatives, and bad or stale matrices are refused.

Distances on both paths and in the independent checks are between the same shapes: collision
shapes (visual ones for links without), meshes by their convex hulls."""

from __future__ import annotations

import json
import math
import shutil
import time

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import central_differences, configuration_within_limits
from mobmanip.cli import main
from mobmanip.errors import ModelError
from mobmanip.robot.collision import SelfCollision
from mobmanip.robot.collision_matrix import (
    compute_collision_matrix,
    matrix_path,
    read_collision_matrix,
)
from mobmanip.robot.shape_pairs import robot_geometry

CONFIGURATIONS = 1000


@pytest.fixture(scope="module")
def shipped(tiago):
    return read_collision_matrix(matrix_path(tiago))


def within_limits(robot, count, seed):
    """Configurations drawn here, not by the module: each joint uniform between its limits (a
    full turn without limits), the platform anywhere in a 6 m square."""
    rng = np.random.default_rng(seed)
    return [configuration_within_limits(robot, rng, xy_range=3.0, one_turn=False) for _ in range(count)]


def exact_distances(robot, pairs, configurations):
    """Signed distances of shape-index pairs through Pinocchio's own loop over every pair (no
    broad phase, no clipping), (configurations, pairs)."""
    geometry = robot_geometry(robot, "auto")
    for a, b in pairs:
        geometry.addCollisionPair(pin.CollisionPair(a, b))
    gdata, data = pin.GeometryData(geometry), robot.model.createData()
    for request in gdata.distanceRequests:
        request.gjk_tolerance = request.epa_tolerance = 1e-10
        request.gjk_max_iterations = request.epa_max_iterations = 1000
    out = np.empty((len(configurations), len(pairs)))
    for n, q in enumerate(configurations):
        pin.computeDistances(robot.model, data, geometry, gdata, q)
        out[n] = [result.min_distance for result in gdata.distanceResults]
    return out


def test_matrix_path_equals_all_pairs_on_every_kept_pair(tiago, shipped):
    """On 1,000 random configurations within the joint limits: every pair the matrix keeps has
    the all-pairs path's distance and gradient (to 1e-9), both paths' distances are Pinocchio's
    exact ones where not clipped (and at least the clip where clipped). Both paths' medians are
    printed; their speed is measured side by side by ``scripts/benchmark.py --decisions``, not
    asserted here (a shared machine under load ran the matrix path at 5.6 ms against 2 ms)."""
    every = SelfCollision(tiago, matrix=None)
    kept = SelfCollision(tiago, matrix=shipped)
    assert kept.matrix is shipped and every.matrix is None
    names = {(p.first, p.second): k for k, p in enumerate(every.pairs)}
    disabled = {(shipped.shapes[a], shipped.shapes[b]) for a, b in shipped.never + shipped.always}
    assert [(p.first, p.second) for p in kept.pairs] == [n for n in names if n not in disabled]
    rows = np.array([names[(p.first, p.second)] for p in kept.pairs])
    configurations = within_limits(tiago, CONFIGURATIONS, 11)
    times_every, times_kept, d_kept = [], [], []
    for q in configurations:
        start = time.perf_counter()
        d_all, G_all = every.distances(q)
        times_every.append(time.perf_counter() - start)
        start = time.perf_counter()
        d, G = kept.distances(q)
        times_kept.append(time.perf_counter() - start)
        np.testing.assert_allclose(d, d_all[rows], rtol=0, atol=1e-9)
        np.testing.assert_allclose(G, G_all[rows], rtol=0, atol=1e-9)
        d_kept.append(d)
    print(f"\nall pairs {1e3 * np.median(times_every):.3f} ms ({len(every.pairs)} pairs), "
          f"matrix {1e3 * np.median(times_kept):.3f} ms ({len(kept.pairs)} pairs)")  # fmt: skip
    index = {obj.name: g for g, obj in enumerate(kept.geometry.geometryObjects)}
    pairs = [(index[p.first], index[p.second]) for p in kept.pairs]
    sample = slice(0, 100)  # Pinocchio's loop over all 4,000 pairs is the slow part: 100 of them
    exact = exact_distances(tiago, pairs, configurations[sample])
    d_kept = np.array(d_kept[sample])
    clipped = d_kept >= kept.activation
    np.testing.assert_allclose(d_kept[~clipped], exact[~clipped], rtol=0, atol=1e-9)
    assert np.all(exact[clipped] >= kept.activation - 1e-9)


def test_left_out_pairs_keep_the_rule(tiago, shipped):
    """Checked with Pinocchio's exact distances, not the matrix's code: on 1,000 of the
    generator's own samples every pair left out as ``never`` is at least the rule's distance
    apart (its body pair never came closer), every ``always`` pair overlaps; and on 1,000 fresh
    configurations (drawn here) no ``never`` pair comes within half the rule's distance (0.05 m,
    2.5 times the default margin). The rule is a sampling claim: these are what these samples
    show, no bound over every configuration."""
    from mobmanip.robot.collision_matrix import sample_configurations

    own = list(sample_configurations(tiago, shipped.samples, shipped.seed)[:CONFIGURATIONS])
    fresh = within_limits(tiago, CONFIGURATIONS, 2026)
    never, always = list(shipped.never), list(shipped.always)
    assert never, "TIAGo++'s matrix leaves pairs out"
    assert exact_distances(tiago, never, own).min() >= shipped.never_closer_than
    assert exact_distances(tiago, never, fresh).min() >= shipped.never_closer_than / 2
    if always:
        assert np.all(exact_distances(tiago, always, own) < 0.0)
    geometry = robot_geometry(tiago, "auto")
    joints = [obj.parentJoint for obj in geometry.geometryObjects]
    model = tiago.model
    for a, b in shipped.adjacent:
        assert model.parents[joints[a]] == joints[b] or model.parents[joints[b]] == joints[a]


def test_shipped_matrix_is_what_the_generator_writes(tiago, shipped, tmp_path, capsys):
    """Regenerating TIAGo++'s matrix by the command gives the shipped file byte for byte."""
    out = tmp_path / "tiago_dual.collision.json"
    assert main(["collision-matrix", "tiago_dual", "--samples", str(shipped.samples), "--out", str(out)]) == 0
    assert out.read_text() == matrix_path(tiago).read_text()
    assert read_collision_matrix(out) == shipped
    assert compute_collision_matrix(tiago, samples=50).text() != out.read_text()  # the samples matter


def test_gradients_equal_central_differences_on_tiago(tiago, shipped):
    """On 3 configurations within the limits, each kept pair's gradient equals central
    differences of its distance through pin.integrate (pairs away from the clip)."""
    checker = SelfCollision(tiago, matrix=shipped)
    model, step = tiago.model, 1e-5
    for q in within_limits(tiago, 3, 5):
        d, G = checker.distances(q)
        fd = central_differences(lambda q: checker.distances(q)[0], model, q, step)
        smooth = np.abs(d - checker.activation) > 1e-3
        assert smooth.sum() >= 10
        np.testing.assert_allclose(G[smooth], fd[smooth], atol=1e-5)


def test_a_margin_at_the_rules_distance_keeps_the_never_pairs(tiago, shipped):
    """The ``never`` pairs are left out only for margins below the rule's distance."""
    small = SelfCollision(tiago, margin=0.02, matrix=shipped)
    large = SelfCollision(tiago, margin=shipped.never_closer_than, matrix=shipped)
    every = SelfCollision(tiago, margin=shipped.never_closer_than, matrix=None)
    assert [p.first + p.second for p in large.pairs] == [p.first + p.second for p in every.pairs]
    assert len(small.pairs) < len(SelfCollision(tiago, margin=0.02, matrix=None).pairs)
    assert math.isinf(large.left_out_clearance(tiago.hold_configuration()))  # nothing left out
    assert small.left_out_clearance(tiago.hold_configuration()) >= shipped.never_closer_than


@pytest.fixture
def tiago_copy(tmp_path):
    """TIAGo++'s spec and matrix copied to a scratch directory (the spec names its URDF by package)."""
    from mobmanip.descriptions.resources import builtin_robots_dir

    for name in ("tiago_dual.toml", "tiago_dual.collision.json"):
        shutil.copy(builtin_robots_dir() / name, tmp_path / name)
    return tmp_path


def test_a_stale_matrix_is_refused_in_one_line(tiago_copy, capsys):
    path = tiago_copy / "tiago_dual.collision.json"
    data = json.loads(path.read_text())
    data["fingerprint"] = "0" * 16
    path.write_text(json.dumps(data))
    robot = mobmanip.load_robot(str(tiago_copy / "tiago_dual.toml"))
    with pytest.raises(ModelError, match="regenerate it with `mobmanip collision-matrix tiago_dual`"):
        SelfCollision(robot)
    argv = ["place", str(tiago_copy / "tiago_dual.toml"), "--object", "1.5,0.5,0.85", "--objective",
            "kinematic:log_volume", "--avoid-collision", "0.02"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mobmanip: error: collision matrix") and err.count("\n") == 1


def test_a_file_that_is_not_a_matrix_is_refused(tiago_copy, capsys):
    (tiago_copy / "tiago_dual.collision.json").write_text('{"format": "something else"}')
    robot = mobmanip.load_robot(str(tiago_copy / "tiago_dual.toml"))
    with pytest.raises(ModelError, match="is not a matrix file"):
        SelfCollision(robot)


def test_bad_generator_options_exit_2(capsys):
    for argv in (["--samples", "0"], ["--never-closer-than", "nan"], ["--never-closer-than", "1.5"]):
        assert main(["collision-matrix", "planar_dual_arm", *argv]) == 2
        err = capsys.readouterr().err
        assert err.startswith("mobmanip: error: ") and err.count("\n") == 1
