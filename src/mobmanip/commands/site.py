"""``mobmanip site SITE.toml``: the best placement for every object position of a site."""

from __future__ import annotations

from .common import add_guided_command

SITE_HELP = """\
SITE.toml names the robot, the objective (as mobmanip place) and the object positions, a list
or a grid:

  robot = "planar_dual_arm"            # built-in name or spec path (relative to SITE.toml)
  objective = "kinematic:capacity:+x"
  mass = 1.0                           # optional (kg); also task = "...", starts = 8
                                       # a measure's reading (dynamic_polytope:reach:+x) as objective
                                       # honours the constraint options; budget = 300 its search
  positions = [[1.0, 0.5, 0.35], [1.5, 0.5, 0.35]]
  # or instead of positions: [grid] with x, y, z each a value or [start, stop, count]
  [grounded]                           # optional: capacity on the floor at each optimum
  mu = 0.5                             # the driven wheels' friction coefficient, or "spec"
  direction = "+x"                     # straight-line reach (m/s^2) of the dynamic polytope

Each position is solved as `mobmanip place` solves it (same starts: the result does not depend on
where it runs). OUT_DIR/site.csv has one row per position (object x, y, z, value, platform x, y,
heading, hold turn, grounded reach, evaluations, the configuration q by name (q.platform_x,
q.platform_y, q.platform_cos_yaw, q.platform_sin_yaw, then q.JOINT for each joint) and, where a
position has no placement or no grounded reach (the robot cannot stand on its floor there), the
reason); OUT_DIR/site.png shows the positions coloured by value,
each with its platform position and heading. A site of more than 10,000 positions is refused
before any is made unless --max-work N allows it (at most 1,000,000). --dask ADDRESS (tcp://HOST:PORT, or local:N for a
local cluster) runs the positions on Dask's distributed scheduler; a progress bar counts the
positions finished across the cluster; a lost worker's positions are run again by Dask.

examples:
  mobmanip site shelf.toml -o shelf/
  mobmanip site warehouse.toml -o warehouse/ --dask local:2
  mobmanip site warehouse.toml -o warehouse/ --dask tcp://scheduler:8786
"""


#: Object positions site runs without being asked (--max-work raises it up to the site's own
#: ceiling, :data:`mobmanip.placement.site.MAX_POSITIONS`).
MAX_SITE_POSITIONS = 10_000
#: Wall time of one position on the paper's robot (s), rounded up (the example's 16 in 2.5 s).
SECONDS_PER_POSITION = 0.25


def register(sub) -> None:
    from .common import add_constraint_options, add_dask_option, add_progress_option, add_work_option

    parser = add_guided_command(
        sub,
        "site",
        "best placement and its value for every object position of a site (list or grid; Dask)",
        "Place the robot for every object position of a site and write one table and a map.",
        SITE_HELP,
    )
    parser.add_argument("site", metavar="SITE.toml", help="the site file (see below)")
    parser.add_argument("--output", "-o", default="site", metavar="OUT_DIR", help="output directory (default: site)")
    parser.add_argument("--positions-per-task", type=int, default=1, metavar="N", help="positions per task (default 1)")
    add_progress_option(parser)
    add_dask_option(parser)
    add_work_option(parser, f"object positions (default {MAX_SITE_POSITIONS:,})")
    add_constraint_options(parser)
    parser.set_defaults(func=run)


def _position_check(args):
    """The work bound on a site's positions, checked before any position is made."""
    from ..support.work import WorkEstimate, bound, check_work

    limit = bound(args.max_work, MAX_SITE_POSITIONS)

    def check(count: int, detail: str) -> None:
        check_work(WorkEstimate("site", "object positions", count, SECONDS_PER_POSITION, detail), limit)

    return check


def run(args) -> int:
    import dataclasses
    from pathlib import Path

    import numpy as np

    from ..errors import UsageError
    from ..placement.site import Site, check_site, run_site
    from ..support.files import check_output, output_directory
    from .common import cluster_executor, registered_constraints, show_progress
    from .outputs import SITE_FILES, site_outputs

    site = Site.read(args.site, _position_check(args))
    constraints, _ = registered_constraints(args)
    site = dataclasses.replace(site, constraints=constraints)
    if args.positions_per_task < 1:
        raise UsageError(f"--positions-per-task must be at least 1, got {args.positions_per_task}")
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--output {args.output}: not a directory")
    for name in SITE_FILES:
        check_output(out / name)
    if args.dask is not None:
        from ..support.cluster import check_address

        check_address(args.dask)
    check_site(site)  # a bad robot, objective or direction says so before the header
    kept = "".join(f", keeping {c.name}" for c in constraints)
    print(f"site {args.site}: {len(site.positions)} object positions, robot {Path(site.robot).name}, "
          f"{site.objective}{kept}")  # fmt: skip
    with cluster_executor(args) as executor:  # connected (or refused) before any work
        result = run_site(site, executor, args.positions_per_task, progress=show_progress(args))
    values = result.values
    placed = int(np.isfinite(values).sum())
    line = f"{placed} of {len(values)} positions placed in {result.seconds:.2f} s"
    if placed:
        k = int(np.nanargmax(values))
        line += f"; best {values[k]:.6g} for the object at ({', '.join(f'{v:g}' for v in site.positions[k])}) m"
    print(line)
    written = site_outputs(result, output_directory(args.output, "--output"))
    print(f"wrote {', '.join(str(path) for path in written)}")
    return 0
