"""``mobmanip referee``: the grounded maxima replayed in MuJoCo, from the installed package.

With a safety reserve of 0.3 every axis of three robots holds: Stretch (one arm, home, 0.5 kg,
translational), TIAGo++ (two arms, hold, 2 kg, spatial) and the paper robot (two planar arms at
its case-study posture, 2 kg, planar). The command's reaches are those of ``analyze`` on the floor
with the object held level and the same object, and the numbers it reports are held here to
stated bounds: MuJoCo's acceleration at t = 0 within 0.5 % of the predicted one's norm (measured:
at most 0.15 %, Stretch +-x), every normal force within 0.1 % of the weight (measured: at most
0.04 %), no support rising more than 0.1 mm and no wheel sliding faster than 1 mm/s over 20 ms.
Without a reserve TIAGo++ -x is named as the one axis that does not hold, with a wheel sliding
faster than 0.1 m/s (its arms swing the object: tests/test_floor_physics.py), and still agrees
with MuJoCo at t = 0. Bad input is one line and exit code 2, and so is a missing MuJoCo.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from contextlib import redirect_stderr, redirect_stdout
from io import StringIO

import numpy as np
import pytest

pytest.importorskip("mujoco")
import mobmanip  # noqa: E402
from mobmanip.casestudy import configuration_at, optimal_posture  # noqa: E402
from mobmanip.cli import main  # noqa: E402
from mobmanip.postures.named import named_configuration  # noqa: E402
from mobmanip.referee import POINT_OBJECT_RADIUS, object_for_referee  # noqa: E402
from mobmanip.terms.constraints.floor import Floor  # noqa: E402

#: The acceleration error at t = 0 the cases stay within (share of the predicted norm).
ACCELERATION_BOUND = 5e-3
#: Normal force error bound (share of the weight).
NORMAL_BOUND = 1e-3


def _run(tmp_path, capsys, *args):
    """The command in this process: (exit code, standard output, the JSON it wrote or None)."""
    out = tmp_path / "referee.json"
    try:
        code = main(["referee", *args, "--json", str(out)])
    except SystemExit as exc:  # argparse's own errors end the process as the command's do
        code = exc.code
    text = capsys.readouterr()
    return code, text.out, text.err, (json.loads(out.read_text()) if out.exists() else None)


CASES = {
    "stretch": (["stretch", "--object-mass", "0.5"], "home", "translational", 0.5),
    "tiago_dual": (
        ["tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "spatial"],
        "hold",
        "spatial",
        2.0,
    ),
    "planar_dual_arm": (["planar_dual_arm", "--object-mass", "2"], None, "planar", 2.0),
}


@pytest.fixture(scope="module")
def paper_q(tmp_path_factory):
    """The paper robot's case-study posture (object at 0 deg) as a --q file."""
    robot = mobmanip.load_robot("planar_dual_arm")
    path = tmp_path_factory.mktemp("paper") / "q.json"
    path.write_text(json.dumps(robot.configuration_dict(configuration_at(robot, optimal_posture(robot), 0.0))))
    return str(path)


@pytest.fixture(scope="module")
def reserved(tmp_path_factory, paper_q):
    """Each case with --reserve 0.3: (exit code, stdout, stderr, JSON) by robot."""
    out = {}
    for name, (args, _, _, _) in CASES.items():
        args = args + (["--q", paper_q] if name == "planar_dual_arm" else []) + ["--reserve", "0.3"]
        path = tmp_path_factory.mktemp(name) / "referee.json"
        stdout, stderr = StringIO(), StringIO()  # capsys is per test; the module's runs are shared
        with redirect_stdout(stdout), redirect_stderr(stderr):
            code = main(["referee", *args, "--json", str(path)])
        out[name] = (code, stdout.getvalue(), stderr.getvalue(), json.loads(path.read_text()))
    return out


def _configuration(robot, name, posture):
    if name == "planar_dual_arm":
        return configuration_at(robot, optimal_posture(robot), 0.0)
    return named_configuration(robot, posture)


@pytest.mark.parametrize("name", list(CASES))
def test_with_a_reserve_every_axis_holds_and_mujoco_agrees(reserved, name):
    code, stdout, stderr, document = reserved[name]
    _, posture, task, mass = CASES[name]
    assert code == 0, stdout + stderr
    axes = document["axes"]
    assert len(axes) == 2 * {"translational": 3, "spatial": 6, "planar": 2}[task]
    assert document["task"] == task and document["passed"] and document["floor"]["level"] is True
    assert document["floor"]["load"] == "compliant" and document["floor"]["reserve"] == 0.3
    # the reaches replayed are analyze's on the floor, the object held level, the same object
    robot = mobmanip.load_robot(name)
    q = _configuration(robot, name, posture)
    held = object_for_referee(mobmanip.analyze(robot, q, task, object_mass=mass, measures=("kinematic",)).held_object)
    grounded = mobmanip.analyze(
        robot, q, task, held_object=held, measures=("dynamic_polytope",),
        constraints=(Floor(level=True, reserve=0.3),),
    ).measures["dynamic_polytope"]  # fmt: skip
    for axis in axes:
        e = np.asarray(axis["direction"])
        assert axis["reach"] == pytest.approx(grounded.straight_line_reach(e), rel=1e-9), (name, axis["axis"])
        assert axis["replayed"] and axis["passed"], (name, axis)
        assert axis["acceleration_error"] <= ACCELERATION_BOUND, (name, axis["axis"], axis["acceleration_error"])
        got, want = np.asarray(axis["acceleration"]), np.asarray(axis["target"])
        assert np.abs(got - want).max() <= ACCELERATION_BOUND * np.linalg.norm(want)
        assert np.allclose(want, axis["reach"] * e)  # the maximum itself (--fraction 1)
        normals = axis["normal_forces"]
        assert set(normals) == {c["name"] for c in grounded.model["floor"]["contacts"]}
        worst = max(abs(n["predicted"] - n["mujoco"]) for n in normals.values())
        assert worst == pytest.approx(axis["normal_error"]) and worst <= NORMAL_BOUND * document["weight"]
        assert sum(n["mujoco"] for n in normals.values()) == pytest.approx(
            sum(n["predicted"] for n in normals.values()), rel=2e-3
        )
        assert axis["rise"] <= 1e-4 and axis["slide"] <= 1e-3
    assert stdout.count("holds") == len(axes)


def test_a_one_hand_object_has_the_same_small_inertia_on_both_sides(reserved):
    """Stretch's object (one hand: a point mass in mobmanip) is a 5 cm solid sphere for MuJoCo and
    for the analysis replayed; a two-hand object is left as mobmanip makes it."""
    inertia = np.asarray(reserved["stretch"][3]["object"]["inertia"])
    assert np.allclose(inertia, 0.4 * 0.5 * POINT_OBJECT_RADIUS**2 * np.eye(3), rtol=1e-12, atol=0)
    robot = mobmanip.load_robot("tiago_dual")
    held = mobmanip.analyze(robot, named_configuration(robot, "hold"), "spatial", object_mass=2.0,
                            measures=("kinematic",)).held_object  # fmt: skip
    assert object_for_referee(held) is held
    assert np.allclose(reserved["tiago_dual"][3]["object"]["inertia"], held.inertia, rtol=0, atol=0)


def test_without_a_reserve_tiago_minus_x_is_named_as_not_holding(tmp_path, capsys):
    """The known case (tests/test_floor_physics.py): the maximum along -x swings the object with
    the arms, and within 20 ms a wheel slides faster than 0.1 m/s; at t = 0 MuJoCo still agrees,
    and every other axis holds."""
    code, stdout, _, document = _run(tmp_path, capsys, *CASES["tiago_dual"][0])
    assert code == 1
    failed = [a for a in document["axes"] if not a["passed"]]
    assert [a["axis"] for a in failed] == ["-x"]
    assert failed[0]["slide"] > 0.1 and failed[0]["agrees"] and not failed[0]["holds"]
    assert failed[0]["acceleration_error"] <= ACCELERATION_BOUND
    row = next(line for line in stdout.splitlines() if line.split()[0] == "-x")
    assert row.endswith("a wheel SLID")
    with pytest.raises(SystemExit):  # the exit status 1 is what --help says it is
        main(["referee", "--help"])
    assert "1 when one does not" in " ".join(capsys.readouterr().out.split())


def test_a_fraction_replays_that_share_of_each_maximum(tmp_path, capsys, reserved):
    code, _, _, document = _run(tmp_path, capsys, *CASES["stretch"][0], "--reserve", "0.3", "--fraction", "0.5")
    assert code == 0
    for half, full in zip(document["axes"], reserved["stretch"][3]["axes"]):
        assert half["reach"] == full["reach"]
        assert np.allclose(half["target"], 0.5 * np.asarray(full["target"]), rtol=1e-12)
        assert half["acceleration_error"] <= ACCELERATION_BOUND


@pytest.mark.parametrize(
    "args, words",
    [
        (["stretch", "--fraction", "2"], "--fraction must be in (0, 1]"),
        (["stretch", "--duration", "0"], "--duration must be in (0, 1] s"),
        (["nope"], "nope"),
        (["stretch", "--object-mass", "0"], "positive --object-mass"),
        (["planar_dual_arm_omni", "--held"], "a replay on the floor covers differential-drive platforms"),
        (["panda"], "panda"),
        (["stretch", "--held", "--longest"], "not allowed with"),
        (["stretch", "--held"], "point mass"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, args, words):
    code, stdout, stderr, document = _run(tmp_path, capsys, *args)
    assert code == 2 and document is None, stdout + stderr
    assert stderr.count("\n") == 1 and stderr.startswith("mobmanip: error: ") and words in stderr, stderr


def test_without_mujoco_the_command_says_how_to_install_it():
    """MuJoCo made unimportable in a fresh process: one line naming the extra, exit code 2."""
    script = textwrap.dedent(
        """
        import sys
        sys.modules["mujoco"] = None  # import mujoco now fails, as where it is not installed
        from mobmanip.cli import main
        sys.exit(main(["referee", "stretch"]))
        """
    )
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr == "mobmanip: error: the referee needs MuJoCo: pip install 'mobmanip[referee]'\n"


def test_a_skid_steer_side_drives_its_wheels_geared_together():
    """TIAGo Pro's right side's torque is shared by its two wheels (B: half each, in each joint's
    own sense), which MuJoCo gears together: from rest they accelerate at one rate."""
    from mobmanip.referee import build

    robot = mobmanip.load_robot("tiago_pro")
    referee = build(robot, named_configuration(robot, "home"))
    tau = np.zeros(robot.nx)
    tau[list(robot.reduced_velocity_names).index("right_side")] = 4.0
    force, model = referee.generalized_force(tau), referee.model
    right = robot.platform.side_wheels("right_side")
    left = robot.platform.side_wheels("left_side")
    dofs = {name: int(model.joint(name).dofadr[0]) for name in right + left}
    S = robot.S
    for name in right:
        v = robot.model.joints[robot.model.getJointId(name)].idx_v
        assert force[dofs[name]] == pytest.approx(4.0 * S[v, 0] / len(right), rel=1e-12)
    assert all(force[dofs[name]] == 0.0 for name in left)
    referee.forward(tau)
    rates = [referee.data.qacc[dofs[name]] for name in right]
    assert abs(rates[0]) > 1.0 and rates[1] == pytest.approx(rates[0], rel=1e-9)


def test_a_skid_steer_on_the_floor_agrees_with_mujoco_and_names_what_gives_way(tmp_path, capsys):
    """TIAGo Pro (skid-steer) with its arms bent, spatial, reserve 0.3: on the floor its base does
    not start a turn (a turn from rest would slide its wheels), and the wheels of an axle share the
    sideways force as equal tyres do; MuJoCo agrees at t = 0 on every axis (acceleration within
    0.5 %, normal forces within 0.1 % of the weight; before, 0 of 12 axes agreed and accelerations
    were over 100 % apart), and each axis that gives way within 20 ms is named with the wheel
    that slid first, when, and its load and traction use then (the arms' own motion moves the
    load: measured 6 of 12 axes hold)."""
    joints = {f"arm_{side}_{k}_joint": v for side in ("right", "left")
              for k, v in enumerate((0.3, 0.5, -0.4, 1.2, 0.2, 0.5, 0.1), start=1)}  # fmt: skip
    q = tmp_path / "q.json"
    q.write_text(json.dumps({"platform": [0.0, 0.0, 0.0], "joints": joints}))
    code, out, _, document = _run(tmp_path, capsys, "tiago_pro", "--q", str(q), "--task", "spatial", "--reserve", "0.3")
    axes = [a for a in document["axes"] if a["replayed"]]
    assert len(axes) == 12
    for a in axes:
        assert a["acceleration_error"] <= ACCELERATION_BOUND, a["axis"]
        assert a["normal_error_of_weight"] <= NORMAL_BOUND, a["axis"]
    failed = [a for a in axes if not a["passed"]]
    assert code == (1 if failed else 0) and 1 <= len(failed) < 12
    for a in failed:
        f = a["first_failure"]
        assert f["event"] in ("slides", "rises", "unloads", "reaches its friction limit") and 0.0 < f["time"] <= 0.02
        assert f["support"] in {c for c in a["normal_forces"]}
        assert f"{a['axis']}: a {'wheel' if 'traction_use' in f else 'support'}, {f['support']}, {f['event']}" in out
        if f["event"] == "reaches its friction limit":  # what moved it there: its load, since t = 0
            assert f["traction_use"][1] >= 0.999 > f["traction_use"][0]
    for a in axes:
        if a["passed"]:
            assert a["first_failure"] is None


def test_a_mecanum_base_is_replayed_on_hubs_that_carry_the_floors_traction(tmp_path, capsys):
    """The paper's arms on four mecanum wheels, 2 kg, reserve 0.3, 90 % of each maximum: each wheel
    a hub on two slides (free along its rollers, its traction from the floor's solution along the
    other): MuJoCo agrees at t = 0 (acceleration within 0.5 %, normal forces within 0.1 % of the
    weight; measured 0.09 % and 0.01 %), no hub slides and no support rises over 20 ms. The base's
    efforts (x, y, yaw) are exactly the sum of the hubs' traction in mobmanip's solution, so MuJoCo's
    base feels what mobmanip's does."""
    code, out, _, document = _run(
        tmp_path, capsys, "planar_dual_arm_omni", "--object-mass", "2", "--reserve", "0.3", "--fraction", "0.9"
    )
    axes = [a for a in document["axes"] if a["replayed"]]
    assert code == 0 and len(axes) == 4, out
    for a in axes:
        assert a["acceleration_error"] <= ACCELERATION_BOUND and a["normal_error_of_weight"] <= NORMAL_BOUND, a
        assert a["passed"] and a["first_failure"] is None, a


def test_a_hub_pushes_the_base_with_the_traction_it_is_given_and_nothing_along_its_rollers():
    """At rest, with the floor's traction of one wheel given along its drive direction and along its
    rollers, the MuJoCo force on the hub's driven slide is minus the drive component (the floor
    holds the hub, the base feels the traction), and the rollers' component reaches no joint."""
    from mobmanip.referee import build, contacts_of_floor

    robot = mobmanip.load_robot("planar_dual_arm_omni")
    q = named_configuration(robot, "home")
    q[:4] = (0.2, -0.1, np.cos(0.7), np.sin(0.7))  # turned: the drive direction in the world turns too
    info = (
        mobmanip.analyze(
            robot, q, "planar", object_mass=2.0, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
        )
        .measures["dynamic_polytope"]
        .model["floor"]
    )
    referee = build(robot, q, contacts=contacts_of_floor(info), mu=0.5)
    name, dof, axis = referee.drives[0]
    free = next(c["free"] for c in info["contacts"] if c["name"] == name)
    c, s = np.cos(0.7), np.sin(0.7)
    drive_world = np.array([c * axis[0] - s * axis[1], s * axis[0] + c * axis[1]])
    free_world = np.array([c * free[0] - s * free[1], s * free[0] + c * free[1]])
    assert abs(drive_world @ free_world) <= 1e-12
    traction = {other: np.zeros(2) for other, _, _ in referee.drives} | {name: 3.0 * drive_world + 5.0 * free_world}
    force = referee.generalized_force(np.zeros(robot.nx), traction)
    assert force[dof] == pytest.approx(-3.0, abs=1e-12)
    assert np.count_nonzero(force) == 1


def test_an_mjcf_robot_is_refereed_from_its_own_file(tmp_path, capsys):
    """Menagerie's TIAGo++ (MJCF, skid-steer: four plain wheels), its limits taken from PAL's URDF:
    MuJoCo reads the file with its own parser (not mobmanip's reading of it), the joints mobmanip
    locks folded into their bodies, and agrees with the floor at t = 0 on every axis of the
    translational task (acceleration within 1 % of the predicted norm, measured 0.46 %: the
    reaches are small, 2.5-5.5 m/s^2, against a fixed 0.01 m/s^2 of soft-contact give; normal forces
    within 0.1 % of the weight, measured 0.01 %)."""
    from mobmanip.robot.detect import spec_from_urdf
    from test_mjcf import HANDS, TIAGO_MJCF, TIAGO_URDF

    urdf_robot = mobmanip.load_robot(spec_from_urdf(TIAGO_URDF, HANDS, platform="fixed"))
    limits = []
    for name, v, e in zip(urdf_robot.reduced_velocity_names, urdf_robot.velocity_limits, urdf_robot.effort_limits):
        limits += ["--velocity-limit", f"{name}={v}", "--effort-limit", f"{name}={e}"]
    spec = tmp_path / "tiago_mjcf.toml"
    argv = ["init-spec", str(TIAGO_MJCF), "--ee", HANDS[0], "--ee", HANDS[1], *limits,
            "--wheel-velocity-limit", "10", "--wheel-effort-limit", "6", "--out", str(spec)]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    joints = {f"arm_{side}_{k}_joint": v for side in ("right", "left") for k, v in ((1, 0.3), (2, 0.3), (4, 1.2))}
    q = tmp_path / "q.json"
    q.write_text(json.dumps({"platform": [0.0, 0.0, 0.0], "joints": joints}))
    code, out, _, document = _run(
        tmp_path, capsys, str(spec), "--q", str(q), "--object-mass", "1", "--task", "translational", "--reserve", "0.3"
    )
    axes = [a for a in document["axes"] if a["replayed"]]
    assert len(axes) == 6 and code in (0, 1), out
    for a in axes:
        assert a["acceleration_error"] <= 1e-2 and a["normal_error_of_weight"] <= NORMAL_BOUND, a
        assert a["passed"] or a["first_failure"] is not None
    assert sum(a["passed"] for a in axes) >= 4


def test_a_maximum_at_the_programs_round_off_is_not_replayed(monkeypatch):
    """TIAGo Pro at home (its arms hanging, a singular posture): the linear programs gave +z a
    reach of 2.7e-6 m/s^2 and -y one of -1e-12 beside -x's 10.4, so the command replayed them and
    printed acceleration errors of 4.5e6 %. A reach below 1e-6 of the longest (HiGHS holds its
    equations to about 1e-7 of the set's scale) is listed as 0, not replayed; one above it is."""
    import mobmanip.referee.check as check

    reaches = {"+x": 5.632, "-x": 10.423, "+y": 3e-5, "-y": -1e-12, "+z": 2.7e-6, "-z": 0.0}

    class Grounded:
        def straight_line_reach(self, e):
            return reaches[next(label for label, d in check.axis_directions("translational") if np.array_equal(d, e))]

        def witness_at(self, target, least):
            return target

    replayed = []
    monkeypatch.setattr(check, "replay_axis", lambda referee, grounded, task, axis, *rest, **kw: replayed.append(axis))
    out = check.replay_maxima(None, Grounded(), "translational")
    assert replayed == ["+x", "-x", "+y"]
    listed = {a.axis: a.reach for a in out if isinstance(a, check.AxisReplay)}
    assert listed == {"-y": 0.0, "+z": 0.0, "-z": 0.0}
    assert all(a.target is None for a in out if isinstance(a, check.AxisReplay))
