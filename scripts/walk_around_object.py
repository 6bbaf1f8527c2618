"""The paper's robot walks once around an object while its ellipsoids change (meshcat viewer).

The object stays at the world origin (where meshcat's camera looks). The platform circles it at
the arms' optimal reach; its heading swings so that the object's direction from the heading
goes back and forth between 0 and 90 deg (twice per lap), and both arms re-aim at the object
in their mirrored optimal posture (:func:`mobmanip.casestudy.configuration_at`). The kinematic
(green) and dynamic (magenta) ellipsoids, and the locked-platform pair (yellow and red rings),
change with that direction and turn with the robot.

    python scripts/walk_around_object.py                 # animation (play controls), Ctrl-C to stop
    python scripts/walk_around_object.py --live          # in-place updates (EllipsoidViewer.update)
    python scripts/walk_around_object.py --export walk.html   # a self-contained page, then exit

No browser opens unless --open; open the printed URL.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.viz.scene import EllipsoidViewer, Frame, ScaleFactors, analyze_pair


def walk_frames(robot, count: int = 120) -> list[Frame]:
    """One lap around an object at the origin, ``count`` frames."""
    posture = optimal_posture(robot)
    frames = []
    for s in np.arange(count) / count:
        bearing = 2 * math.pi * s  # where the robot stands, seen from the object
        alpha = 45.0 + 45.0 * math.sin(4 * math.pi * s)  # object direction from the heading (deg)
        heading = bearing + math.pi - math.radians(alpha)  # so that the robot faces the object at alpha
        q = configuration_at(robot, posture, alpha, heading=heading)
        q[:2] -= analyze_pair(robot, q, locked=False)[0].held_object.center[:2]  # move the object to the origin
        analysis, locked = analyze_pair(robot, q)
        frames.append(
            Frame(q, analysis, locked, label=f"bearing {math.degrees(bearing):5.1f} deg, alpha {alpha:4.1f} deg")
        )
    return frames


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=120, help="frames per lap (default 120)")
    parser.add_argument("--fps", type=float, default=20.0, help="frames per second (default 20)")
    parser.add_argument("--live", action="store_true", help="update the scene in place instead of an animation")
    parser.add_argument("--export", metavar="WALK.html", help="write the animation as a self-contained page and exit")
    parser.add_argument("--port", type=int, help="HTTP port (default: the first free one from 7000)")
    parser.add_argument("--open", action="store_true", help="open the viewer in the default web browser")
    args = parser.parse_args(argv)
    if args.frames < 2 or args.fps <= 0:
        parser.error("--frames must be at least 2 and --fps positive")

    robot = mobmanip.load_robot("planar_dual_arm")
    frames = walk_frames(robot, args.frames)
    scales = ScaleFactors.fit([a for f in frames for a in (f.analysis, f.locked)])
    with EllipsoidViewer(robot, port=args.port, open_browser=args.open, scales=scales) as viewer:
        print(f"scale: {scales.describe()}")
        if args.export or not args.live:
            viewer.animate(frames, step=1.0 / args.fps, repetitions=1000)
        if args.export:
            print(f"wrote {viewer.export_html(args.export)}")
            return 0
        print(f"meshcat viewer: {viewer.url}  (Ctrl-C to stop)", flush=True)
        try:
            while True:
                if not args.live:
                    time.sleep(0.2)
                    continue
                for frame in frames:
                    started = time.monotonic()
                    viewer.update(frame.q, frame.analysis, frame.locked)
                    time.sleep(max(0.0, 1.0 / args.fps - (time.monotonic() - started)))
        except KeyboardInterrupt:
            print("stopped")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
