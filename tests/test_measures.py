"""Measures as a family: the registry, the JSON it produces, and two toy measures registered here.

The toy measures prove that a new measure reaches analyze's JSON, the command line, the sweeps
and the viewer through its definition alone:

- ``doubled``: the kinematic ellipsoid of the robot with doubled speed limits, which is exactly
  twice the kinematic ellipsoid (J_hat = J_u Y^-1 doubles); sweepable and drawn as an ellipsoid.
- ``kinematic_box``: the box that bounds the kinematic ellipsoid along the task axes, a
  :class:`TaskSet` of a kind the viewer has no drawing for and without a batch form.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pytest

import mobmanip
from conftest import random_configurations
from mobmanip import EllipsoidBatch, Measure, MeasureTerms, TaskSet, register_measure, unregister_measure
from mobmanip.batch import BatchSetup, ellipsoids_from_terms, iter_terms
from mobmanip.casestudy import configuration_at
from mobmanip.cli import main
from mobmanip.commands.outputs import write_sweep_csv, write_sweep_npz
from mobmanip.errors import MeasureError, MobmanipError, UnknownMeasureError
from mobmanip.measures import (
    MEASURES,
    VELOCITY,
    BatchRequest,
    default_measures,
    evaluate_batch,
    get_measure,
    measure_names,
    resolve_measures,
)
from mobmanip.sets.ellipsoid import dynamic_ellipsoid, kinematic_ellipsoid
from mobmanip.sets.taskset import check_membership_points, membership
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
from mobmanip.sweep.runner import index_names
from mobmanip.terms.dynamics import end_effector_positions, reduced_dynamics, unified_jacobian
from mobmanip.terms.grasp import HeldObject

# The keys of `mobmanip analyze --json` before measures became a family: they must all stay.
DOCUMENT_KEYS = [
    "robot",
    "platform",
    "task",
    "task_axes",
    "decoupled",
    "q",
    "reduced_velocity_names",
    "arms",
    "object",
    "unified_jacobian",
    "reduced_inertia",
    "reduced_inertia_decoupled",
    "input_matrix",
    "bias",
    "velocity_limits",
    "effort_limits",
    "grasp_matrix",
    "warnings",
    "kinematic_ellipsoid",
    "dynamic_ellipsoid",
]
ELLIPSOID_KEYS = ["center", "semi_axes", "axes", "matrix", "volume", "isotropy", "degenerate", "empty"]


# --------------------------------------------------------------------------- the toy measures


def _doubled(terms: MeasureTerms) -> TaskSet:
    return kinematic_ellipsoid(terms.J_u, terms.W, 2.0 * terms.velocity_limits)


def _doubled_batch(request: BatchRequest) -> dict:
    (limits,) = request.limits.values()
    out = EllipsoidBatch.allocate(len(request.terms), request.setup.m)
    ellipsoids_from_terms(request.setup, request.terms, velocity_limits=2.0 * limits, kinematic=out)
    return {"doubled": out}


#: Measure's fields in order: name, JSON key, quantity, label, set kind, colour, locked colour,
#: compute; then by keyword the batch form and the per-axis sweep indices.
DOUBLED = Measure("doubled", "doubled_ellipsoid", VELOCITY, "doubled kinematic ellipsoid", "ellipsoid", 0x3366FF,
                  0x99BBFF, _doubled, batch=_doubled_batch, axis_indices=(("semi_axes", "semi_axis"),))  # fmt: skip


@dataclass(frozen=True)
class Box(TaskSet):
    """The box {c + r * z : |z_i| <= 1} (a toy set kind)."""

    center: np.ndarray
    half_widths: np.ndarray
    empty: bool = False

    kind = "box"

    @property
    def dim(self) -> int:
        return len(self.half_widths)

    @property
    def degenerate(self) -> bool:
        return bool(np.any(self.half_widths == 0.0))

    @property
    def volume(self) -> float:
        return float(np.prod(2.0 * self.half_widths))

    @property
    def isotropy(self) -> float:
        return float(np.min(self.half_widths) / np.linalg.norm(self.half_widths))

    def support(self, direction) -> float:
        d = np.asarray(direction, dtype=float)
        return float(d @ self.center + self.half_widths @ np.abs(d))

    def radius_along(self, direction) -> float:
        d = np.asarray(direction, dtype=float)
        return float(self.half_widths @ np.abs(d / np.linalg.norm(d)))

    def contains(self, points, tol: float = 1e-9) -> bool | np.ndarray:
        P, single = check_membership_points(points, self.dim)  # one point (m,) or points (n, m)
        return membership(np.all(np.abs(P - self.center) <= self.half_widths + tol, axis=1), single)

    def project(self, dims: Sequence[int] = (0, 1)) -> Box:
        return Box(self.center[list(dims)], self.half_widths[list(dims)])

    def slice(self, dims: Sequence[int] = (0, 1)) -> Box:
        return self.project(dims)

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "center": self.center.tolist(),
            "half_widths": self.half_widths.tolist(),
            "empty": self.empty,
            "degenerate": self.degenerate,
        }


def _bounding_box(terms: MeasureTerms) -> TaskSet:
    E = kinematic_ellipsoid(terms.J_u, terms.W, terms.velocity_limits)
    return Box(E.center, np.sqrt(np.diag(E.generator @ E.generator.T)))


BOX = Measure("kinematic_box", "kinematic_bounding_box", VELOCITY, "kinematic bounding box", "box", 0x777777, 0xBBBBBB,
              _bounding_box)  # fmt: skip


@pytest.fixture
def toys():
    """Both toy measures registered for one test, then removed."""
    register_measure(DOUBLED)
    register_measure(BOX)
    yield
    unregister_measure(DOUBLED.name)
    unregister_measure(BOX.name)


def _same_ellipsoid_document(got: dict, expected, rel: float = 1e-9) -> None:
    """The JSON of an ellipsoid against an independently computed one (axes up to sign)."""
    size = max(float(expected.semi_axes[0]), 1e-300)
    assert got["kind"] == "ellipsoid"
    assert list(got)[1:] == ELLIPSOID_KEYS
    np.testing.assert_allclose(got["semi_axes"], expected.semi_axes, rtol=0, atol=rel * size)
    np.testing.assert_allclose(got["center"], expected.center, rtol=0, atol=rel * max(size, 1.0))
    for k in range(expected.dim):
        if expected.semi_axes[k] > 1e-6 * size:  # a direction is defined only for a distinct semi-axis
            assert abs(np.dot(got["axes"][k], expected.axes[k])) == pytest.approx(1.0, abs=1e-7)
    G = expected.generator
    np.testing.assert_allclose(
        np.array(got["matrix"]) @ (G @ G.T) @ np.array(got["matrix"]), got["matrix"], rtol=0, atol=1e-7
    )
    assert got["volume"] == pytest.approx(expected.volume, rel=1e-8)
    assert got["isotropy"] == pytest.approx(expected.isotropy, rel=1e-8, abs=1e-12)
    assert (got["degenerate"], got["empty"]) == (expected.degenerate, expected.empty)


# --------------------------------------------------------------------------- the registry


def test_default_registry_holds_the_papers_two_ellipsoids():
    assert measure_names()[:2] == ("kinematic", "dynamic")
    assert default_measures() == ("kinematic", "dynamic")
    assert [get_measure(n).json_key for n in default_measures()] == ["kinematic_ellipsoid", "dynamic_ellipsoid"]
    kin, dyn = get_measure("kinematic"), get_measure("dynamic")
    assert (kin.quantity.limits, dyn.quantity.limits) == ("velocity", "effort")
    assert (kin.quantity.unit, dyn.quantity.unit) == ("m/s", "m/s^2")
    assert not kin.quantity.inertial and dyn.quantity.inertial
    assert mobmanip.get_measure is get_measure and mobmanip.TaskSet is TaskSet


def test_registered_definitions_are_consistent(robot, rng):
    """Names, keys, paths and colours are unique; each compute returns its declared set kind;
    each batch form gives, row by row, the sets its reference computation gives."""
    measures = list(MEASURES.values())
    assert [m.name for m in measures] == list(MEASURES)
    for field in ("json_key", "scene_path", "locked_scene_path"):
        values = [getattr(m, field) for m in measures]
        assert len(set(values)) == len(values), field
    colors = [c for m in measures for c in (m.color, m.locked_color)]
    assert len(set(colors)) == len(colors)
    qs = np.array(random_configurations(robot, rng, 6))
    setup = BatchSetup(robot, "planar", 2.0)
    for m in measures:
        for q in qs[:2]:
            assert m.compute(MeasureTerms.of(mobmanip.analyze(robot, q, "planar", method="exact"))).kind == m.set_kind
        if not m.sweepable:
            continue
        limits = robot.velocity_limits if m.quantity.limits == "velocity" else robot.effort_limits
        (start, terms), *_ = iter_terms(setup, qs)
        batch = evaluate_batch(BatchRequest(setup, terms, {m.name: limits}, False))[m.name]
        d = np.array([0.6, -0.8])
        for row, q in enumerate(qs):
            exact = m.compute(MeasureTerms.of(mobmanip.analyze(robot, q, "planar", method="exact")))
            size = max(exact.radius_along(d), exact.radius_along([0.8, 0.6]), 1e-12)
            assert batch.volume[row] == pytest.approx(exact.volume, rel=1e-8)
            assert batch.isotropy[row] == pytest.approx(exact.isotropy, rel=1e-8, abs=1e-12)
            assert batch.support(d)[row] == pytest.approx(exact.support(d), abs=1e-9 * size)
            assert (batch.empty[row], batch.degenerate[row]) == (exact.empty, exact.degenerate)


def test_unknown_measure_names_the_registered_ones(robot):
    for call in (
        lambda: get_measure("kinematic_polytope_x"),
        lambda: mobmanip.analyze(robot, robot.neutral(), measures=("kinematic", "nope")),
        lambda: resolve_measures(["dynamic", "nope"]),
    ):
        with pytest.raises(UnknownMeasureError) as info:
            call()
        assert isinstance(info.value, MobmanipError)
        assert all(name in str(info.value) for name in measure_names())
    with pytest.raises(MeasureError, match="no measure asked for"):
        mobmanip.analyze(robot, robot.neutral(), measures=())


def test_registration_refuses_clashes(toys):
    with pytest.raises(MeasureError, match="already registered"):
        register_measure(DOUBLED)
    clash = Measure("other", "kinematic_ellipsoid", VELOCITY, "x", "ellipsoid", 0x010203, 0x040506, _doubled)
    with pytest.raises(MeasureError, match="taken by 'kinematic'"):
        register_measure(clash)
    with pytest.raises(MeasureError, match="letters, digits and underscores"):
        Measure("has.dot", "k", VELOCITY, "x", "ellipsoid", 0, 0, _doubled)
    with pytest.raises(MeasureError, match="0xRRGGBB"):
        Measure("colour", "k", VELOCITY, "x", "ellipsoid", 0x1000000, 0, _doubled)
    with pytest.raises(UnknownMeasureError):
        unregister_measure("never_registered")
    assert "other" not in measure_names()


# --------------------------------------------------------------------------- analyze and its JSON


@pytest.mark.parametrize(
    ("name", "task", "mass", "decoupled"),
    [
        ("planar_dual_arm", "planar", None, False),
        ("planar_dual_arm", "planar", None, True),
        ("tiago_dual", "spatial", 2.0, False),
    ],
)
def test_json_keeps_every_ellipsoid_value(name, task, mass, decoupled, rng):
    """analyze's JSON against the reference ellipsoids computed from independently built terms."""
    robot = mobmanip.load_robot(name)
    q = robot.neutral()
    for joint in (j for arm in robot.arms for j in arm.joint_names):
        index = robot.model.joints[robot.model.getJointId(joint)].idx_q
        q[index] = rng.uniform(-1.0, 1.0)
    result = mobmanip.analyze(robot, q, task, object_mass=mass, decoupled=decoupled)
    document = json.loads(json.dumps(result.to_dict()))
    expected = list(DOCUMENT_KEYS)
    if task == "spatial":  # linear and angular rows: the unit-consistent indices per block come too
        expected.insert(expected.index("warnings") + 1, "block_indices")
    assert list(document) == expected
    obj = HeldObject.between(end_effector_positions(robot, q), robot.spec.object_mass if mass is None else mass)
    J_u, W = unified_jacobian(robot, q, task), obj.grasp_matrix(task)
    dyn = reduced_dynamics(robot, q, decoupled=decoupled)
    kin = kinematic_ellipsoid(J_u, W, robot.velocity_limits)
    acc = dynamic_ellipsoid(
        J_u, W, dyn.P, dyn.Q, dyn.xi, obj.inertia_matrix(task), obj.gravity_vector(task), robot.effort_limits
    )
    _same_ellipsoid_document(document["kinematic_ellipsoid"], kin)
    _same_ellipsoid_document(document["dynamic_ellipsoid"], acc)
    assert result.kinematic is result.measures["kinematic"] and result.dynamic is result.measures["dynamic"]


def test_analyze_computes_the_measures_asked_for(robot, posture):
    q = configuration_at(robot, posture, 45.0)
    both = mobmanip.analyze(robot, q)
    only = mobmanip.analyze(robot, q, measures=["dynamic"])
    assert list(only.measures) == ["dynamic"]
    assert list(only.to_dict())[-1] == "dynamic_ellipsoid" and "kinematic_ellipsoid" not in only.to_dict()
    np.testing.assert_array_equal(only.dynamic.semi_axes, both.dynamic.semi_axes)
    with pytest.raises(MeasureError, match="'kinematic' was not computed"):
        _ = only.kinematic
    reordered = mobmanip.analyze(robot, q, measures=("dynamic", "kinematic", "dynamic"))
    assert list(reordered.measures) == ["kinematic", "dynamic"]  # the registry's order, once each
    with pytest.raises(TypeError):
        reordered.measures["kinematic"] = None  # read-only


def test_a_registered_measure_reaches_analyze_and_its_json(robot, posture, toys):
    q = configuration_at(robot, posture, 90.0)
    plain = mobmanip.analyze(robot, q)
    assert list(plain.measures) == ["kinematic", "dynamic"]  # not default: not computed unasked
    result = mobmanip.analyze(robot, q, measures=("kinematic", "dynamic", "doubled", "kinematic_box"))
    assert list(result.measures) == ["kinematic", "dynamic", "doubled", "kinematic_box"]
    document = json.loads(json.dumps(result.to_dict()))
    assert list(document) == DOCUMENT_KEYS + ["doubled_ellipsoid", "kinematic_bounding_box"]
    kin = result.kinematic
    np.testing.assert_allclose(document["doubled_ellipsoid"]["semi_axes"], 2.0 * kin.semi_axes, rtol=1e-12)
    assert document["doubled_ellipsoid"]["volume"] == pytest.approx(4.0 * kin.volume, rel=1e-12)
    # The bounding box reaches as far as the ellipsoid along each task axis.
    widths = document["kinematic_bounding_box"]["half_widths"]
    np.testing.assert_allclose(widths, [kin.support(e) for e in np.eye(2)], rtol=1e-12)


def test_command_line_summary_and_json_loop_over_measures(tmp_path, capsys, toys):
    out = tmp_path / "a.json"
    argv = ["analyze", "planar_dual_arm", "--measure", "kinematic", "--measure", "kinematic_box"]
    assert main([*argv, "--measure", "doubled", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    document = json.loads(out.read_text())
    assert "dynamic_ellipsoid" not in document and "dynamic ellipsoid" not in text
    kin = document["kinematic_ellipsoid"]
    assert f"kinematic ellipsoid semi-axes (m/s): {kin['semi_axes'][0]:.4f}" in text
    doubled = document["doubled_ellipsoid"]["semi_axes"]
    assert f"doubled kinematic ellipsoid semi-axes (m/s): {doubled[0]:.4f}, {doubled[1]:.4f}" in text
    widths = document["kinematic_bounding_box"]["half_widths"]
    reach = "; ".join(f"-{w:.4f} .. +{w:.4f}" for w in widths)
    assert f"kinematic bounding box reach along the task axes (m/s): {reach}" in text
    assert main(["analyze", "planar_dual_arm", "--measure", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mobmanip: error: unknown measure 'nope'") and "kinematic_box" in err


def test_case_study_json_lists_a_measure_beside_its_figures_ellipsoid(robot, toys):
    from mobmanip.casestudy import run_case_study

    study = run_case_study(
        robot, angles_deg=(90.0,), platform_speeds=(1.0,), wheel_torques=(50.0,), measures=["doubled"]
    )
    document = json.loads(json.dumps(study.to_dict()))
    for case, entry in zip(study.kinematic, document["kinematic"]):  # velocity: beside Fig. 3's ellipses
        assert list(entry)[-1] == "doubled_ellipsoid"
        np.testing.assert_allclose(entry["doubled_ellipsoid"]["semi_axes"], 2.0 * np.array(entry["semi_axes"]))
        np.testing.assert_array_equal(entry["semi_axes"], case.analysis.kinematic.semi_axes)
    assert all("doubled_ellipsoid" not in entry for entry in document["dynamic"])  # not an acceleration set
    plain = run_case_study(robot, angles_deg=(90.0,), platform_speeds=(1.0,), wheel_torques=(50.0,)).to_dict()
    assert [list(entry) for entry in plain["kinematic"]] == [list(entry)[:-1] for entry in document["kinematic"]]


# --------------------------------------------------------------------------- sweeps


GRID = SweepGrid(angle_deg=[0.0, 60.0, 120.0], distance=[0.9, 1.1, 9.0], wheel_velocity_scale=[0.5, 1.0])


def test_a_registered_measure_is_swept_beside_the_ellipsoids(tmp_path, toys):
    result = run_sweep(SweepSpec("planar_dual_arm", measures=("doubled", "kinematic")), GRID, workers=1)
    assert [m.name for m in result.measures] == ["kinematic", "doubled"]
    assert "dynamic_volume" not in result.indices
    reachable = result.reachable[:, :, :, None, None] & np.ones(GRID.shape, dtype=bool)
    assert reachable.any() and not reachable.all()
    kin, doubled = result.index("kinematic.semi_axis_1"), result.index("doubled.semi_axis_1")
    np.testing.assert_allclose(doubled[reachable], 2.0 * kin[reachable], rtol=1e-10)
    np.testing.assert_allclose(
        result.index("doubled.volume")[reachable], 4.0 * result.index("kinematic.volume")[reachable], rtol=1e-10
    )
    np.testing.assert_allclose(
        result.index("doubled.capacity")[reachable], 2.0 * result.index("kinematic.capacity")[reachable], rtol=1e-10
    )
    assert np.isnan(doubled[~reachable]).all()
    # velocity quantity: it changes along the velocity scale, not along the effort scale
    assert not np.allclose(doubled[..., 0, 0][reachable[..., 0, 0]], doubled[..., 1, 0][reachable[..., 1, 0]])
    assert "doubled.semi_axis_2" in index_names(2, ("kinematic", "doubled"))
    path = write_sweep_csv(result, tmp_path / "s.csv")
    with open(path) as f:
        header = next(csv.reader(f))
    assert header[6:] == [
        f"{kind}_{name}"
        for kind in ("kinematic", "doubled")
        for name in (
            *("volume", "isotropy", "capacity", "straight_line_reach"),
            *("semi_axis_1", "semi_axis_2", "degenerate", "empty"),
        )
    ]
    data = np.load(write_sweep_npz(result, tmp_path / "s.npz"))
    np.testing.assert_array_equal(data["doubled_semi_axes"], result.indices["doubled_semi_axes"])


def test_a_measure_without_batch_form_is_refused_by_name(capsys, toys):
    with pytest.raises(MeasureError, match="'kinematic_box' has no batch form"):
        run_sweep(SweepSpec("planar_dual_arm", measures=("kinematic", "kinematic_box")), GRID, workers=1)
    assert main(["sweep", "planar_dual_arm", "--measure", "kinematic_box", "--no-progress"]) == 2
    assert "'kinematic_box' has no batch form" in capsys.readouterr().err


def test_sweep_command_takes_measures(tmp_path, capsys, toys):
    out = tmp_path / "s"
    argv = ["sweep", "planar_dual_arm", "--angle", "0,90", "--distance", "1.0", "--workers", "1", "--no-progress"]
    assert main([*argv, "--measure", "doubled", "--plot", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "doubled volume: min" in text and "kinematic volume" not in text
    data = np.load(out / "sweep.npz")
    assert {k for k in data if k.endswith("_volume")} == {"doubled_volume"}
    assert (out / "sweep.png").exists()


# --------------------------------------------------------------------------- the viewer


def test_a_registered_measure_appears_in_the_viewer(robot, posture, toys):
    from mobmanip.viz.scene import EllipsoidViewer, analyze_pair, planar_thickness, scene_path

    q = configuration_at(robot, posture, 90.0)
    measures = ("kinematic", "dynamic", "doubled", "kinematic_box")
    analysis, locked = analyze_pair(robot, q, measures=measures)
    with EllipsoidViewer(robot) as viewer:
        assert (False, "doubled") not in viewer.scene_paths()  # loaded when first shown
        viewer.show(q, analysis, locked)
        paths = viewer.scene_paths()
        assert paths[False, "doubled"] == scene_path("doubled") == "mobmanip/ellipsoids/doubled"
        assert paths[True, "doubled"] == "mobmanip/locked/doubled"
        assert not any(name == "kinematic_box" for _, name in paths)
        assert viewer.undrawn == {"kinematic_box": "box"}  # no drawing for its kind yet
        # One scale per quantity: the doubled set shares the kinematic one, fitted to the largest.
        scales = viewer.scales
        assert scales["doubled"] == scales.kinematic
        largest = 2.0 * max(analysis.kinematic.semi_axes[0], locked.kinematic.semi_axes[0])
        assert largest * scales.kinematic == pytest.approx(0.5, rel=1e-12)
        for is_locked, source in ((False, analysis), (True, locked)):
            T = viewer.placement(source, (is_locked, "doubled"))
            K = viewer.placement(source, (is_locked, "kinematic"))
            # the same principal directions (up to sign), twice as long
            np.testing.assert_allclose(T[:3, :2] @ T[:3, :2].T, 4.0 * K[:3, :2] @ K[:3, :2].T, rtol=0, atol=1e-12)
            np.testing.assert_allclose(np.abs(T[:3, 2]), [0, 0, planar_thickness("doubled", is_locked)], atol=1e-15)
            np.testing.assert_allclose(T[:3, 3], source.held_object.center, atol=1e-12)
    thickness = [planar_thickness(name, lk) for name in measure_names() for lk in (False, True)]
    assert len(set(thickness)) == len(thickness)  # no two flat discs z-fight


def test_a_registered_measure_is_drawn_in_the_browser(robot, posture, toys):
    from browser_util import VIEWPORT, chromium, missing_browser, wait_for_scene, world_matrix
    from mobmanip.viz.scene import EllipsoidViewer, analyze_pair

    reason = missing_browser()
    if reason is not None:
        pytest.skip(f"browser tests need Chromium and Playwright: {reason}")
    q = configuration_at(robot, posture, 30.0)
    analysis, locked = analyze_pair(robot, q, measures=("kinematic", "doubled"))
    with EllipsoidViewer(robot) as viewer, chromium() as browser:
        viewer.show(q, analysis, locked)
        page = browser.new_page(viewport=VIEWPORT)
        page.goto(viewer.url)
        shapes = [f"meshcat/mobmanip/{p}/shape" for p in ("ellipsoids/doubled", "locked/doubled")]
        wait_for_scene(page, tuple(shapes))
        for path, source, key in zip(shapes, (analysis, locked), ((False, "doubled"), (True, "doubled"))):
            np.testing.assert_allclose(world_matrix(page, path), viewer.placement(source, key), atol=1e-5)
        tree = "viewer.scene_tree.children.meshcat.children.mobmanip.children"
        visible = page.evaluate(f"() => {tree}.ellipsoids.children.dynamic.object.visible")
        assert visible is False  # this analysis has no dynamic ellipsoid: hidden


# --------------------------------------------------------------------------- the ellipsoid as a TaskSet


def _random_ellipsoid(rng, m: int, rank: int | None = None):
    G = rng.normal(size=(m, rank or m)) * rng.uniform(0.3, 2.0, size=rank or m)
    c = rng.normal(size=m)
    return mobmanip.Ellipsoid.from_generator(c, G), c, G


def _unit(rng, n: int, m: int) -> np.ndarray:
    u = rng.normal(size=(n, m))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


@pytest.mark.parametrize("m", [2, 3, 6])
def test_support_against_dense_boundary_samples(m, rng):
    """support(d) bounds every boundary point c + G u and is reached at c + G G^T d / |G^T d|."""
    E, c, G = _random_ellipsoid(rng, m)
    assert isinstance(E, TaskSet) and E.kind == "ellipsoid" and E.dim == m
    boundary = c + _unit(rng, 200_000, m) @ G.T
    A = np.linalg.inv(G @ G.T)
    for d in _unit(rng, 30, m) * rng.uniform(0.2, 5.0, size=(30, 1)):
        h = E.support(d)
        sampled = boundary @ d
        assert sampled.max() <= h + 1e-12 * abs(h)
        top = c + G @ (G.T @ d) / np.linalg.norm(G.T @ d)
        assert top @ d == pytest.approx(h, rel=1e-12)
        assert (top - c) @ A @ (top - c) == pytest.approx(1.0, rel=1e-10)
        if m == 2:  # dense in 2-D: the samples come within (spacing)^2 of the support
            assert sampled.max() >= h - 1e-6 * np.linalg.norm(d) * E.semi_axes[0]
        unit = d / np.linalg.norm(d)
        assert E.radius_along(d) == pytest.approx(E.support(unit) - unit @ c, rel=1e-12)


@pytest.mark.parametrize("m", [2, 3, 6])
def test_contains_agrees_with_the_quadratic_form(m, rng):
    E, c, G = _random_ellipsoid(rng, m)
    A = np.linalg.inv(G @ G.T)
    points = c + _unit(rng, 4000, m) @ G.T * rng.uniform(0.0, 1.5, size=(4000, 1)) ** (1 / m)
    value = np.einsum("ni,ij,nj->n", points - c, A, points - c)
    clear = np.abs(value - 1.0) > 1e-6
    np.testing.assert_array_equal(E.contains(points)[clear], (value <= 1.0)[clear])
    assert 0.2 < np.mean(value[clear] <= 1.0) < 0.9
    assert E.contains(c) is True


@pytest.mark.parametrize("dims", [(0,), (0, 2), (3, 1, 4)])
def test_projection_and_slice_are_consistent(dims, rng):
    """The shadow's support is the full support along the embedded direction; the slice lies in
    the full set and in the shadow, and its boundary lies on the full set's boundary."""
    E, c, G = _random_ellipsoid(rng, 6)
    shadow, cut = E.project(dims), E.slice(dims)
    k = len(dims)
    assert shadow.dim == cut.dim == k
    embed = np.zeros((6, k))
    embed[list(dims), range(k)] = 1.0
    A = np.linalg.inv(G @ G.T)
    for d in _unit(rng, 40, k):
        assert shadow.support(d) == pytest.approx(E.support(embed @ d), rel=1e-10)
        assert cut.support(d) <= shadow.support(d) * (1 + 1e-12) + 1e-12
        # the point of the cut furthest along d: on the boundary of the full ellipsoid
        Gc = cut.generator
        far = cut.center + Gc @ (Gc.T @ d) / np.linalg.norm(Gc.T @ d)
        assert far @ d == pytest.approx(cut.support(d), rel=1e-12)
        full = c.copy()
        full[list(dims)] = far
        assert (full - c) @ A @ (full - c) == pytest.approx(1.0, rel=1e-9)
        assert E.contains(full, tol=1e-9) and not E.contains(c + 1.001 * (full - c))


def test_empty_ellipsoid_answers_zero_and_never_nan(rng):
    E = mobmanip.Ellipsoid.from_generator(rng.normal(size=3), np.zeros((3, 1)), empty=True)
    d = rng.normal(size=3)
    assert (E.support(d), E.radius_along(d), E.volume, E.isotropy) == (0.0, 0.0, 0.0, 0.0)
    assert E.indices() == {"volume": 0.0, "isotropy": 0.0}
    assert not E.contains(np.vstack([E.center, rng.normal(size=(5, 3))])).any()
    for part in (E.project((0, 2)), E.slice((1, 2))):
        assert part.empty and part.support(d[:2]) == 0.0 and part.volume == 0.0
    document = E.to_dict()
    assert document["kind"] == "ellipsoid" and document["empty"] is True
    assert all(np.all(np.isfinite(v)) for key, v in document.items() if key != "kind")


def test_bad_queries_raise_a_set_query_error(rng):
    from mobmanip.errors import SetQueryError

    E, _, _ = _random_ellipsoid(rng, 3)
    for call in (
        lambda: E.support(np.zeros(3)),
        lambda: E.support([1.0, math.nan, 0.0]),
        lambda: E.radius_along([1.0, 0.0]),
        lambda: E.contains(np.zeros((4, 2))),
        lambda: E.contains([[0.0, math.inf, 0.0]]),
        lambda: E.project((0, 3)),
        lambda: E.slice((1, 1)),
        lambda: E.project(()),
        lambda: E.slice((True, 0)),
        lambda: E.boundary(),
    ):
        with pytest.raises(SetQueryError) as info:
            call()
        assert isinstance(info.value, MobmanipError) and isinstance(info.value, ValueError)
