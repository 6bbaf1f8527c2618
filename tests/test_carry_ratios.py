"""carry's ratios say what they compare: a baseline whose set collapses (a singular posture) gets
no ratio, and with a self-motion the baseline is also run from the QP's prepared start, so that
the gain splits into what the preparation gives and what the motion gives.

The collapse is checked on the batch engine's ellipsoids (another path than carry's reference
analysis), the prepared baseline's start against the QP's, and the split against its product.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from mobmanip.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _carry(tmp_path, capsys, *extra):
    out = tmp_path / "out"
    argv = ["carry", "tiago_pro", "--path", str(EXAMPLES / "carry_line.csv"), "--out", str(out), *extra]
    assert main(argv) == 0
    text = capsys.readouterr().out
    return text, json.loads((out / "carry.json").read_text()), out


def _read_q(robot, csv_path: Path) -> np.ndarray:
    import csv

    with csv_path.open() as handle:
        rows = list(csv.DictReader(handle))
    joints = [n for n in rows[0] if n not in ("t", "platform_x", "platform_y", "platform_yaw")]
    joints = [n for n in joints if n in robot.configuration_dict(robot.neutral())["joints"]]
    return np.array([
        robot.configuration((float(r["platform_x"]), float(r["platform_y"]), float(r["platform_yaw"])),
                            {n: float(r[n]) for n in joints})
        for r in rows
    ])  # fmt: skip


def test_a_baseline_through_a_singular_posture_gets_no_ratio(capsys):
    from mobmanip.commands.carry import print_ratio
    from mobmanip.motion.carry import carry, read_path

    robot = mobmanip.load_robot("tiago_pro")  # from home: a singular posture
    result = carry(robot, read_path(EXAMPLES / "carry_line.csv"), start=robot.neutral())
    summary = result.summary()
    assert summary["min_capacity_ratio"] is None
    assert summary["ratio_parts"]["preparation"] is None
    assert "pinv" in summary["collapsed"] and "qp" not in summary["collapsed"]
    # independently: the batch engine's kinematic ellipsoids along the baseline
    batch = mobmanip.analyze_batch(robot, result.baseline.q, task="spatial", method="svd").kinematic
    ratio = batch.semi_axes[:, -1] / batch.semi_axes[:, 0]
    lowest = int(np.argmin(batch.semi_axes[:, -1]))
    assert ratio[lowest] < 1e-3  # collapsed: minor semi-axis below 1e-3 of the major
    # carry's value is the smallest eigenvalue of C = G G^T (squared semi-axes): near a singular
    # posture it is known to about eps * (largest / smallest semi-axis)^2, relative
    rel = 10 * np.finfo(float).eps / ratio[lowest] ** 2
    assert summary["pinv"]["min_capacity"] == pytest.approx(batch.semi_axes[lowest, -1], rel=rel)
    entry = summary["collapsed"]["pinv"]
    assert entry["smallest_semi_axis"] == pytest.approx(batch.semi_axes[lowest, -1], rel=rel)
    assert entry["largest_semi_axis"] == pytest.approx(batch.semi_axes[lowest, 0], rel=1e-6)
    print_ratio("min capacity ratio, QP / baseline from the start posture", summary["min_capacity_ratio"])
    assert capsys.readouterr().out.strip().endswith("not given (its baseline's set has collapsed)")


def test_the_ratio_splits_into_preparation_and_motion(tmp_path, capsys):
    text, summary, out = _carry(tmp_path, capsys, "--objective", "kinematic:minor_axis:linear")
    assert summary["objective"] == "kinematic:minor_axis:linear" and summary["collapsed"] == {}
    whole, parts = summary["min_capacity_ratio"], summary["ratio_parts"]
    qp, pinv, prepared = (summary[k]["min_capacity"] for k in ("qp", "pinv", "pinv_prepared"))
    assert whole == pytest.approx(qp / pinv, rel=1e-12)
    assert parts["preparation"] == pytest.approx(prepared / pinv, rel=1e-12)
    assert parts["motion"] == pytest.approx(qp / prepared, rel=1e-12)
    assert parts["preparation"] * parts["motion"] == pytest.approx(whole, rel=1e-12)
    assert summary["pinv_prepared"]["start"] == summary["qp"]["start"]
    # the prepared baseline starts where the QP motion starts: the self-motion's last configuration
    robot = mobmanip.load_robot("tiago_pro")
    start = _read_q(robot, out / "trajectory.csv")[0]
    end_of_preparation = _read_q(robot, out / "preparation.csv")[-1]
    np.testing.assert_allclose(start, end_of_preparation, atol=1e-9)
    # the linear block's minor semi-axis, by the reference analysis' shadow at the QP's start
    shadow = mobmanip.analyze(robot, start, "spatial").kinematic.project((0, 1, 2))
    assert summary["qp"]["start"]["capacity"] == pytest.approx(shadow.semi_axes[-1], rel=1e-6)
    line = text.split("QP with capacity")[1].splitlines()[0]
    assert " m/s, mean" in line and "rad/s" not in line  # the linear block: one unit
    assert "and the motion gives (QP / baseline from the prepared start)" in text


@pytest.mark.parametrize("name", ["tiago", "stretch"])
def test_without_a_self_motion_the_shared_start_is_said(tmp_path, capsys, name):
    """Without a self-motion both runs set out from one posture. TIAGo's capacity, from its home
    configuration (the arm stretched out to the side), is least there
    (both minima equal the kinematic minor axis at the start, from the batch engine's ellipsoid):
    the minima's ratio is 1 and says nothing of the motion, so the command says so and gives the
    means' ratio (here about 2.2), checked against the per-step capacities it wrote. Stretch's
    capacity stays put to 1e-9 (a joint's speed limit bounds it): no such note."""
    import csv

    from mobmanip.motion.carry import default_start

    robot = mobmanip.load_robot(name)
    path, out = tmp_path / "ahead.csv", tmp_path / "out"
    t = np.linspace(0.0, 2.0, 11)
    ahead = 0.2 * (3.0 * (t / 2.0) ** 2 - 2.0 * (t / 2.0) ** 3)  # from rest to rest
    path.write_text("t,x,y\n" + "".join(f"{a:.3f},{b:.9f},0\n" for a, b in zip(t, ahead)))
    start = robot.neutral() if name == "tiago" else default_start(robot)  # TIAGo: its arm stretched out
    (tmp_path / "start.json").write_text(json.dumps(robot.configuration_dict(start)))
    argv = ["carry", name, "--path", str(path), "--prepare", "0", "--start", str(tmp_path / "start.json")]
    assert main([*argv, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    summary = json.loads((out / "carry.json").read_text())
    with (out / "trajectory.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    qp, pinv = (np.array([float(r[column]) for r in rows]) for column in ("capacity", "baseline_capacity"))
    note = "both runs are least at the start posture they share"
    if name == "tiago":
        at_start = mobmanip.analyze_batch(robot, start[None, :], task="spatial").kinematic
        for run in ("qp", "pinv"):
            assert summary[run]["min_capacity"] == pytest.approx(at_start.semi_axes[0, -1], rel=1e-9)
        assert summary["min_capacity_ratio"] == pytest.approx(1.0, rel=1e-12)
        means = qp.mean() / pinv.mean()
        assert summary["mean_capacity_ratio"] == pytest.approx(means, rel=1e-12) and means > 2.0
        assert f"{note}, so the ratio says nothing of the motion: the means' ratio is {means:.3f}" in text
    else:
        assert np.ptp(qp) < 1e-9 and np.ptp(pinv) < 1e-9
        assert note not in text
