"""Replay a robot's grounded capacity in MuJoCo: what `analyze --ground` promises, against a
physics engine that mobmanip does not contain.

Run from a checkout (the MuJoCo model builder lives with the tests, ``tests/mujoco_referee.py``;
``mujoco`` is a test dependency: ``pip install -e '.[test]'``)::

    python scripts/check_physics.py planar_dual_arm --object-mass 2
    python scripts/check_physics.py tiago_dual --posture hold --object-mass 2 --task spatial --mu 0.5
    python scripts/check_physics.py my_robot.toml --q q.json --load any

For each task axis, both senses, it takes the grounded straight-line maximum of the exact dynamic
polytope, the efforts that reach ``--fraction`` of it (default 97 %) with the least reduced
acceleration among those with half the most slack, and applies them from rest to a MuJoCo model
built from the same URDF (meshes stripped, spheres at the wheel and caster contacts, equally stiff
supports, the object welded or pinned to the hands). It prints, per axis: the predicted reach, the
largest error of MuJoCo's object acceleration at t = 0 (% of the predicted acceleration's norm),
the largest difference of a contact's normal force (% of the weight), and over ``--duration``
(default 20 ms) how far a support rose (mm) and how fast a driven wheel slid (mm/s). A support that
rises by more than 0.1 mm or a wheel that slides faster than 1 mm/s fails the axis.

Compare like with like: for a robot that is not planar, use the spatial task. MuJoCo's weld holds
the object level, so the analysis replayed here holds it level too (``Floor(level=True)``, as
``--level`` asks). A planar task then leaves the hands free to turn about the vertical, which an object welded or
pinned to the hands in MuJoCo does not (TIAGo++ in its hold: 32 % apart sideways at t = 0, against
0.00 % with the spatial task).

The capacity is instantaneous: held constant, efforts move the robot away from the state they were
computed for (docs, "Capacity that holds on the floor"); ``--held`` replays instead, per axis, the
reach that mobmanip's own replay holds for ``--duration`` (``analyze --hold``), and ``--longest``
the efforts that hold ``--fraction`` of each maximum longest (``analyze --hold``'s
``instant_efforts``), printing mobmanip's predicted hold time beside MuJoCo's (its last sample
before a support rises or a wheel slides; the axis passes when MuJoCo holds at least 90 % of the
prediction). Exit code 0 when every axis holds (or, with ``--longest``, holds as predicted), 1 when
one does not, 2 for bad input.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RISE, SLIP = 1e-4, 1e-3  # m, m/s: a support lifted, a wheel sliding


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2), as the mobmanip command's."""

    def error(self, message):  # noqa: D401 - argparse API
        self.exit(2, f"check_physics.py: error: {message}\n")


def _parser() -> argparse.ArgumentParser:
    from mobmanip.commands.common import add_floor_options, add_robot_options

    parser = _Parser(prog="check_physics.py", description=__doc__.split("\n\n")[0])
    add_robot_options(parser)
    add_floor_options(parser)
    parser.add_argument("--object-mass", type=float, metavar="KG", help="mass of the held object (default: spec)")
    parser.add_argument("--fraction", type=float, default=0.97, help="share of each maximum replayed (default 0.97)")
    parser.add_argument("--duration", type=float, default=0.02, help="how long the efforts are held (s, default 0.02)")
    parser.add_argument(
        "--grasp",
        choices=("weld", "point"),
        help="how MuJoCo holds the object: welded to the hands, or pinned at its centre (default: pinned "
        "for planar and translational tasks, else welded)",
    )
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument(
        "--held",
        action="store_true",
        help="replay, per axis, the reach mobmanip predicts to hold for --duration (analyze --hold) instead of "
        "--fraction of the instantaneous maximum",
    )
    mode.add_argument(
        "--longest",
        action="store_true",
        help="replay, per axis, the efforts that hold --fraction of the maximum longest (analyze --hold's "
        "instant_efforts) and compare how long they hold in MuJoCo with mobmanip's prediction",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    sys.path.insert(0, str(ROOT / "tests"))
    try:
        import mujoco  # noqa: F401

        from mujoco_referee import build
    except ImportError as exc:
        print(f"check_physics.py: error: needs mujoco and a checkout's tests/ ({exc})", file=sys.stderr)
        return 2
    import mobmanip
    from mobmanip.commands.common import floor_constraints, load_robot_and_configuration
    from mobmanip.errors import MobmanipError
    from mobmanip.motion.hold import held_reach
    from mobmanip.robot.support import robot_support
    from mobmanip.robot.tasks import get_task
    from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor, ground_reaction

    args = _parser().parse_args(argv)
    try:
        if not (0.0 < args.fraction <= 1.0 and 0.0 < args.duration <= 1.0):
            raise MobmanipError(
                f"--fraction must be in (0, 1] and --duration in (0, 1] s, got {args.fraction}, {args.duration}"
            )
        robot, q = load_robot_and_configuration(args)
        task = args.task or robot.spec.default_task
        # the object welded to the hands in MuJoCo is held level: so is the analysis replayed
        floor = (dataclasses.replace((floor_constraints(args) or (Floor(),))[0], level=True),)
        if (args.held or args.longest) and floor[0].slope:
            raise MobmanipError("--held and --longest replay mobmanip's own model on a level floor: leave out --slope")
        analysis = mobmanip.analyze(
            robot, q, task, object_mass=args.object_mass, measures=("dynamic_polytope",), constraints=floor
        )
        grounded = analysis.measures["dynamic_polytope"]
        if grounded.empty:
            raise MobmanipError("the grounded set is empty: " + "; ".join(analysis.warnings))
        support = robot_support(robot)
        casters = {c.name: c.point for c in support.contacts if not c.driven}
        mu = floor[0].resolve(robot)[1] or 0.0
        referee = build(robot, q, support_points=casters, object=analysis.held_object, mu=mu, grasp=args.grasp,
                        gravity=floor[0].gravity())  # fmt: skip
    except (MobmanipError, ValueError) as exc:
        print(f"check_physics.py: error: {exc}", file=sys.stderr)
        return 2

    info = grounded.model["floor"]
    pose = info["pose"]
    R = np.array([[np.cos(pose[2]), -np.sin(pose[2])], [np.sin(pose[2]), np.cos(pose[2])]])
    what = "the reach mobmanip predicts to last" if args.held else f"{args.fraction:.0%} of each grounded maximum"
    if args.longest:
        what += ", with the efforts that hold it longest,"
    print(f"{robot.name}, task {task}, load sharing {info['load']}, mu {info['mu']}: "
          f"{what} held {1e3 * args.duration:g} ms in MuJoCo")  # fmt: skip
    columns = f"{'axis':>6} {'reach':>9} {'acc err %':>10} {'normal err %W':>14} {'rise mm':>8} {'slip mm/s':>10}"
    print(columns + (f" {'predicted ms':>12} {'MuJoCo ms':>9}" if args.longest else "") + "  verdict")
    names = get_task(task).labels
    failed = 0
    for k in range(grounded.dim):
        for sign in (1.0, -1.0):
            e = np.zeros(grounded.dim)
            e[k] = sign
            reach = grounded.straight_line_reach(e)
            label = f"{'+' if sign > 0 else '-'}{names[k]}"
            if reach <= 0.0:
                print(f"{label:>6} {reach:9.3f}  (no motion along this axis from rest)")
                continue
            if args.held:
                found = held_reach(robot, q, grounded, e, task, object_mass=args.object_mass, floor=floor[0],
                                   duration=args.duration, fraction=args.fraction)  # fmt: skip
                if found.witness is None or found.reach <= 0.0:
                    print(f"{label:>6} {0.0:9.3f}  (mobmanip predicts no reach along this axis holds)")
                    continue
                reach, w = found.reach, found.witness
                target = reach * e
            elif args.longest:
                found = held_reach(robot, q, grounded, e, task, object_mass=args.object_mass, floor=floor[0],
                                   duration=args.duration, fraction=args.fraction)  # fmt: skip
                target, w = args.fraction * reach * e, found.instant_witness
                predicted_hold = found.instant_hold.held
            else:
                target = args.fraction * reach * e
                w = grounded.witness_at(target, least="xdot")
            acc, contacts = referee.forward(w.variables["tau"])
            got = acc[: grounded.dim] if task == "planar" else acc
            acc_err = 100.0 * np.abs(got - target).max() / np.linalg.norm(target)
            predicted = ground_reaction(info, w.variables[CONTACT_FORCES])["contacts"]
            worst = 0.0
            for c in info["contacts"]:
                s = min(referee.supports, key=lambda s: np.linalg.norm(R @ s.point[:2] + pose[:2] - c["point"][:2]))
                worst = max(worst, abs(contacts[s.name].normal - predicted[c["name"]]["normal"]))
            run = referee.rollout(w.variables["tau"], duration=args.duration)
            rise = max(-run.penetration.min(), 0.0)
            driven = [i for i, s in enumerate(run.supports) if s.driven]
            slip = max((run.slip_speed[:, i].max() for i in driven), default=0.0)
            ok = rise <= RISE and slip <= SLIP
            row = (f"{label:>6} {reach:9.3f} {acc_err:10.2f} {100.0 * worst / referee.weight:14.3f} "
                   f"{1e3 * rise:8.3f} {1e3 * slip:10.2f}")  # fmt: skip
            if args.longest:
                # MuJoCo's hold: up to the sample before a support first rises or a wheel first slides
                bad = (-run.penetration.min(axis=1) > RISE) | (run.slip_speed[:, driven].max(axis=1) > SLIP)
                gave = np.flatnonzero(bad)
                measured = args.duration if len(gave) == 0 else float(run.time[max(gave[0] - 1, 0)])
                ok = measured >= 0.9 * predicted_hold
                row += f" {1e3 * predicted_hold:12.2f} {1e3 * measured:9.2f}  {'as predicted' if ok else 'SHORTER'}"
            else:
                row += f"  {'holds' if ok else 'FAILS'}"
            failed += not ok
            print(row)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
