"""Hostile input whose refusal used to be unclear: ``collision-matrix --samples`` beyond its
bound or beyond memory says so (not "out of memory"), and ``place --budget`` with an objective
that has no derivative-free search is refused instead of silently ignored."""

from __future__ import annotations

import time

import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.commands.collision_matrix import MAX_SAMPLES
from mobmanip.errors import ArgumentError
from mobmanip.robot import collision_matrix
from mobmanip.robot.collision_matrix import MAX_SAMPLE_BYTES, check_samples


@pytest.fixture
def no_sampling(monkeypatch):
    """Fails the test if a configuration is ever sampled."""

    def refuse(*args, **kwargs):
        raise AssertionError("sampled")

    monkeypatch.setattr(collision_matrix, "sample_configurations", refuse)


@pytest.mark.parametrize(
    ("samples", "shown"),
    [(1_000_000_000_000, "1,000,000,000,000"), (2**63 - 1, "9.22e+18"), (MAX_SAMPLES + 1, f"{MAX_SAMPLES + 1:,}")],
)
def test_collision_matrix_samples_beyond_the_bound_name_the_option_and_the_bound(capfd, tmp_path, no_sampling,
                                                                                 samples, shown):  # fmt: skip
    started = time.perf_counter()
    code, out, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--samples", samples,
                             "--out", tmp_path / "m.json")  # fmt: skip
    line = assert_one_line_error(code, err, f"{shown} sampled configurations", f"--samples {samples}",
                                 f"more than the {MAX_SAMPLES:,} sampled configurations", "--max-work N")  # fmt: skip
    assert "memory" not in line and out == "" and not (tmp_path / "m.json").exists()
    assert time.perf_counter() - started < 5


def test_collision_matrix_samples_raised_past_memory_name_the_limit(capfd, tmp_path, no_sampling):
    """--max-work lets more run, but not more configurations than fit in memory: the count and
    the most that fit (planar_dual_arm: 14 numbers a configuration), no estimate printed first."""
    most = MAX_SAMPLE_BYTES // (8 * 14)
    samples = most + 1
    code, out, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--samples", samples, "--max-work",
                             10**15, "--out", tmp_path / "m.json")  # fmt: skip
    assert_one_line_error(code, err, f"--samples: {samples:,} configurations of planar_dual_arm (14 numbers each)",
                          f"more than the {most:,} that fit in {MAX_SAMPLE_BYTES >> 20} MiB")  # fmt: skip


@pytest.mark.parametrize("samples", ["0", "-3"])
def test_collision_matrix_needs_a_sample(capfd, tmp_path, samples):
    code, out, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--samples", samples)
    assert_one_line_error(code, err, f"--samples must be at least 1, got {samples}")


def test_collision_matrix_library_refuses_before_allocating():
    robot = mobmanip.load_robot("planar_dual_arm")
    with pytest.raises(ArgumentError, match=r"1,000,000,000,000 configurations of planar_dual_arm"):
        collision_matrix.compute_collision_matrix(robot, samples=10**12)
    with pytest.raises(ArgumentError, match="must be a positive integer, got True"):
        check_samples(robot, True)
    check_samples(robot, MAX_SAMPLE_BYTES // (8 * robot.model.nq))  # the most that fit pass


def test_collision_matrix_within_the_bound_runs(capfd, tmp_path):
    code, out, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--samples", "20",
                             "--out", tmp_path / "m.json")  # fmt: skip
    assert code == 0, err
    assert "over 20 sampled configurations" in out and (tmp_path / "m.json").is_file()


PLACE = ["place", "planar_dual_arm", "--object", "1,0.5,0.35"]


@pytest.mark.parametrize("objective", ["kinematic:capacity:+x", "dynamic:capacity:+x", "dynamic:capacity:-y"])
@pytest.mark.parametrize("budget", ["50", "300", "0"])
def test_budget_with_an_ellipsoid_objective_is_refused(capfd, objective, budget):
    code, out, err = run_cli(capfd, *PLACE, "--objective", objective, "--budget", budget)
    assert_one_line_error(code, err, f"--budget {budget}", repr(objective), "a measure's reading", "not one")
    assert out == ""


def test_without_budget_an_ellipsoid_objective_runs_as_before(capfd):
    code, out, err = run_cli(capfd, *PLACE, "--objective", "kinematic:capacity:+x", "--starts", "2")
    assert code == 0, err
    assert "budget" not in out + err


def test_budget_still_bounds_a_polytope_search(capfd):
    code, out, err = run_cli(capfd, *PLACE, "--objective", "dynamic_polytope:reach:+x", "--budget", "0")
    assert_one_line_error(code, err, "--budget must be at least 1 evaluation, got 0")
    code, out, err = run_cli(capfd, *PLACE, "--objective", "dynamic_polytope:reach:+x", "--budget", "30000")
    assert_one_line_error(code, err, "30,000 search evaluations", "--max-work")


def test_collision_matrix_refuses_a_negative_seed(capfd, tmp_path, no_sampling):
    code, out, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--seed", "-1", "--out", tmp_path / "m.json")
    assert_one_line_error(code, err, "--seed must be a whole number of at least 0, got -1")
    robot = mobmanip.load_robot("planar_dual_arm")
    with pytest.raises(ArgumentError, match="seed must be a whole number of at least 0, got -7"):
        collision_matrix.compute_collision_matrix(robot, samples=3, seed=-7)
