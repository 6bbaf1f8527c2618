"""``mobmanip view ROBOT``: the robot, its held object and its ellipsoids in the meshcat viewer.

Starts a meshcat server on 127.0.0.1 (the first free port from 7000, or ``--port``), prints its
URL and the scale factors, and serves until Ctrl-C (or ``--duration``); no browser opens unless
``--open``. ``--export SCENE.html`` writes a self-contained page of the scene instead of
serving. ``--sweep`` sends an animation (play controls in the viewer's panel, under
"Animations"). See :mod:`mobmanip.viz.scene` for what is drawn.
"""

from __future__ import annotations

import contextlib
import math
import signal
import sys
import time

from ..support.reading import decimal
from .common import add_configuration_command, configuration_from_command, print_warnings


def register(sub) -> None:
    from ..viz.sweeps import SWEEPS

    parser = add_configuration_command(sub, "view", "show the robot and its ellipsoids in the meshcat web viewer")
    parser.add_argument(
        "--sweep",
        choices=SWEEPS,
        help="animate: object-angle (0..90 deg; other robots turn the platform heading), "
        "fig3 (wheel speed) or fig4 (wheel torque) of the paper's robot",
    )
    parser.add_argument("--export", metavar="SCENE.html", help="write a self-contained HTML page and exit")
    parser.add_argument("--port", type=int, help="HTTP port of the viewer (default: the first free one from 7000)")
    parser.add_argument("--open", action="store_true", help="open the viewer in the default web browser")
    parser.add_argument("--no-locked", action="store_true", help="leave out the locked-platform ellipsoids")
    parser.add_argument(
        "--size", type=decimal, default=0.5, metavar="M", help="drawn length of the largest semi-axis (default 0.5 m)"
    )
    parser.add_argument("--duration", type=decimal, metavar="S", help="stop serving after S seconds (default: Ctrl-C)")
    parser.set_defaults(func=run)


def _check(args) -> None:
    from ..errors import UsageError

    if not (math.isfinite(args.size) and args.size > 0):
        raise UsageError(f"--size must be a positive number of metres, got {args.size!r}")
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration >= 0):
        raise UsageError(f"--duration must be a non-negative number of seconds, got {args.duration!r}")
    if args.sweep in ("fig3", "fig4") and (args.q or args.posture):
        raise UsageError(f"--sweep {args.sweep} places the paper's robot itself; leave out --q and --posture")
    if args.sweep == "fig3" and args.wheel_velocity_limit is not None:
        raise UsageError("--sweep fig3 sets the wheel speed limit itself; leave out --wheel-velocity-limit")
    if args.sweep == "fig4" and args.wheel_effort_limit is not None:
        raise UsageError("--sweep fig4 sets the wheel torque limit itself; leave out --wheel-effort-limit")


@contextlib.contextmanager
def _stop_on_sigterm():
    """SIGTERM ends the wait like Ctrl-C does, so the server is stopped either way."""

    def handler(signum, frame):
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _describe_empty(name: str, analysis) -> list[str]:
    from ..measures import get_measure

    if analysis is None:
        return []
    return [
        f"{name} {get_measure(key).label} is EMPTY (the torque limits cannot hold the load still): not drawn"
        for key, task_set in analysis.measures.items()
        if task_set.empty
    ]


def _serving(duration: float | None) -> str:
    """How long the server will run, as the line with the viewer's URL says it."""
    if duration is None:
        return "Ctrl-C to stop"
    return f"serving for {duration:g} s, then stopping; Ctrl-C stops it sooner"


def run(args) -> int:
    from ..viz.scene import EllipsoidViewer, analyze_pair
    from ..viz.server import ViewerError
    from ..viz.sweeps import sweep_frames

    _check(args)
    robot, q, options = configuration_from_command(args)
    frames = None
    if args.sweep:
        given = args.q or args.posture
        frames = sweep_frames(args.sweep, robot, q if given else None, args.task, locked=not args.no_locked, **options)
        first = frames[0]
    else:
        analysis, locked = analyze_pair(robot, q, args.task, locked=not args.no_locked, **options)

    with _stop_on_sigterm(), EllipsoidViewer(robot, port=args.port, size=args.size) as viewer:
        if frames is not None:
            schedule = viewer.animate(frames)
            print(f"robot {robot.name}, task {first.analysis.task}, sweep {args.sweep}: {len(frames)} frames")
            for start, end, label in schedule:
                print(f"  {start:5.1f} .. {end:5.1f} s  {label}")
            notes = [note for i, f in enumerate(frames) for note in _describe_empty(f"frame {i}", f.analysis)]
        else:
            viewer.show(q, analysis, locked)
            print(f"robot {robot.name} ({robot.platform.kind}), task {analysis.task}")
            c = analysis.held_object.center
            print(f"task point (object): ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m")
            notes = _describe_empty("the", analysis) + _describe_empty("the locked-platform", locked)
            print_warnings(analysis)
        print(f"scale: {viewer.scales.describe()}")  # type: ignore[union-attr]  # fitted by show/animate
        for (is_locked, name), factor in viewer.magnified.items():
            if factor != 1.0:  # too small to see at its quantity's scale (the page's legend says so too)
                print(f"{'locked-platform ' if is_locked else ''}{name}: drawn {factor:g} times larger")
        for note in viewer.mesh_notes + notes:
            print(note)
        if args.export:
            path = viewer.export_html(args.export)
            print(f"wrote {path}")
            return 0
        if args.open:
            viewer.open()
        print(f"meshcat viewer: {viewer.url}  ({_serving(args.duration)})", flush=True)
        deadline = None if args.duration is None else time.monotonic() + args.duration
        try:
            while deadline is None or time.monotonic() < deadline:
                time.sleep(0.1 if deadline is None else max(min(0.1, deadline - time.monotonic()), 0.0))
                if not viewer.server_running:
                    raise ViewerError("the meshcat server exited")
        except KeyboardInterrupt:
            pass
    print("stopped the meshcat server", file=sys.stderr)
    return 0
