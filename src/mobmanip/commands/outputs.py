"""What the commands write: every table, array file and figure of a result, through the atomic
output path.

The domain layers compute (a sweep, a placement map, a trajectory's analysis, a carried path);
the files they are written to are made here, and their figures are drawn in :mod:`mobmanip.viz`.
Every file goes through :func:`mobmanip.support.files.atomic_output` (figures through
:func:`mobmanip.support.files.save_figure`), so a failure midway never leaves a truncated file,
and inside a command, which runs within :func:`mobmanip.support.files.publish_together`, the
command's files are published all together or not at all. From Python the same functions write
the same files, each one atomically.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..support.files import atomic_output, write_json

if TYPE_CHECKING:
    from ..coordination.carry import TeamCarryResult, TeamCarryRun
    from ..errors import CarryFailed
    from ..motion.carry import CarryResult
    from ..motion.ground import GroundAlong
    from ..motion.retime import Retiming
    from ..motion.traction import FloorScaling, TractionAlong
    from ..motion.trajectory_analysis import TrajectoryAnalysis
    from ..placement.maps import PlacementMap
    from ..placement.site import SiteResult
    from ..robot.model import Robot
    from ..sweep.payload_map import PayloadAlong, PayloadMap
    from ..sweep.results import SweepResult
    from ..team import Team

#: The files ``place --map DIR`` writes in DIR.
PLACEMENT_MAP_FILES = ("map.npz", "map.csv", "map.png")
#: The files ``carry --out DIR`` writes in DIR (and ``preparation.csv`` after a self-motion).
CARRY_FILES = ("trajectory.csv", "baseline.csv", "carry.json", "capacity.png", "preparation.csv")


# ------------------------------------------------------------------------------------------------
# sweeps


def write_sweep_npz(result: SweepResult, path: str | Path) -> Path:
    """Write :meth:`mobmanip.sweep.SweepResult.arrays` to a NumPy ``.npz`` file (compressed).

    Raises:
        OutputError: the directory does not exist or the path cannot be written.
    """
    path = Path(path)
    with atomic_output(path, "wb") as handle:
        np.savez_compressed(handle, **result.arrays())  # type: ignore[arg-type]  # numpy's stub: **kwds as allow_pickle
    return path


def write_sweep_csv(result: SweepResult, path: str | Path) -> Path:
    """Write :meth:`mobmanip.sweep.SweepResult.table` as CSV, one row per grid point (12
    significant digits).

    Raises:
        OutputError: the directory does not exist or the path cannot be written.
    """
    path = Path(path)
    header, table = result.table()
    with atomic_output(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        step = 65536
        for start in range(0, table.shape[0], step):
            writer.writerows([f"{v:.12g}" for v in row] for row in table[start : start + step])
    return path


# ------------------------------------------------------------------------------------------------
# placement maps


def write_placement_map_npz(placement_map: PlacementMap, path: str | Path) -> Path:
    """Arrays ``x``, ``y``, ``values``, ``heading``, ``configurations``, ``hold_turn``, ``target``
    (and ``headings`` for fixed-heading layers), the objective's name under ``objective``."""
    grid = placement_map
    extra = {} if grid.headings is None else {"headings": grid.headings}
    path = Path(path)
    with atomic_output(path, "wb") as handle:
        np.savez_compressed(
            handle,
            x=grid.x,
            y=grid.y,
            values=grid.values,
            heading=grid.heading,
            configurations=grid.configurations,
            hold_turn=np.asarray(grid.hold_turn, dtype=float),  # NaN-filled where no cell holds
            target=grid.target,
            objective=np.array(grid.objective.name),
            **extra,  # type: ignore[arg-type]  # numpy's stub types **kwds as its allow_pickle flag
        )
    return path


def write_placement_map_csv(placement_map: PlacementMap, path: str | Path) -> Path:
    """One row per cell (and layer): x_m, y_m, heading_deg, value; empty value and heading where
    no pose holds the object."""
    grid = placement_map
    layers = [None] if grid.headings is None else list(range(len(grid.headings)))
    path = Path(path)
    with atomic_output(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["x_m", "y_m", "heading_deg", grid.objective.name])
        for layer in layers:
            v = grid.values if layer is None else grid.values[layer]
            h = grid.heading if layer is None else grid.heading[layer]
            for iy, y in enumerate(grid.y):
                for ix, x in enumerate(grid.x):
                    ok = not math.isnan(v[iy, ix])
                    writer.writerow(
                        [f"{x:.6g}", f"{y:.6g}", f"{math.degrees(h[iy, ix]):.4f}" if ok else "",
                         f"{v[iy, ix]:.10g}" if ok else ""]
                    )  # fmt: skip
    return path


def placement_map_outputs(placement_map: PlacementMap, out_dir: str | Path) -> list[Path]:
    """:data:`PLACEMENT_MAP_FILES` in ``out_dir`` (which must exist): the arrays, the table and
    the heat map (:func:`mobmanip.viz.placement.plot_placement_map`); returns the paths."""
    from ..viz.placement import plot_placement_map

    out = Path(out_dir)
    npz, table, figure = (out / name for name in PLACEMENT_MAP_FILES)
    return [
        write_placement_map_npz(placement_map, npz),
        write_placement_map_csv(placement_map, table),
        plot_placement_map(placement_map, figure),
    ]


# ------------------------------------------------------------------------------------------------
# trajectories and carried paths


def write_table_csv(path: str | Path, header: list[str], values: ArrayLike) -> Path:
    """A CSV of numbers: the header, then one row per row of ``values`` (each number as Python's
    shortest exact ``repr``)."""
    path = Path(path)
    with atomic_output(path, "w", newline="", encoding="utf-8") as handle:
        handle.write(",".join(header) + "\n")
        for row in np.asarray(values, dtype=float):
            handle.write(",".join(repr(float(v)) for v in row) + "\n")
    return path


def write_trajectory_csv(
    robot: Robot, path: str | Path, t: ArrayLike, qs: ArrayLike, extra: Mapping[str, ArrayLike] | None = None
) -> Path:
    """A trajectory file (:func:`mobmanip.motion.trajectory.trajectory_table`'s columns, readable
    by :func:`mobmanip.motion.trajectory.read_trajectory`) plus ``extra`` columns by name."""
    from ..motion.trajectory import trajectory_table

    header, values = trajectory_table(robot, np.asarray(t, dtype=float), np.asarray(qs, dtype=float))
    for name, column in (extra or {}).items():
        header.append(name)
        values = np.hstack([values, np.asarray(column, dtype=float)[:, None]])
    return write_table_csv(path, header, values)


def trajectory_outputs(
    robot: Robot,
    result: TrajectoryAnalysis,
    out_dir: str | Path,
    prefix: str = "analysis",
    ground: GroundAlong | None = None,
    traction: TractionAlong | None = None,
    floor_scaling: FloorScaling | None = None,
) -> list[str]:
    """``{prefix}.csv`` (:meth:`TrajectoryAnalysis.table`), ``{prefix}.json`` and ``{prefix}.png``
    (:func:`mobmanip.viz.motion_figures.trajectory_figure`) in ``out_dir``; returns the paths.
    With ``ground`` (:func:`mobmanip.motion.ground.ground_along`), the CSV and JSON also hold the
    zero-moment point and the stability margin per sample; with ``traction``
    (:func:`mobmanip.motion.traction.traction_along`), every contact's normal force
    (``normal_force_<contact>``) and every driven wheel's traction use (``traction_use_<wheel>``;
    an unloaded wheel's is ``inf`` in the CSV and ``null`` in the JSON); with ``floor_scaling``
    (:func:`mobmanip.motion.traction.floor_time_scaling`), the JSON's ``floor_time_scaling``."""
    from ..viz.figures import save_and_close
    from ..viz.motion_figures import trajectory_figure

    out = Path(out_dir)
    header, values = result.table()
    document = result.to_dict()
    if ground is not None:
        header = [*header, "zmp_x", "zmp_y", "stability_margin"]
        values = np.hstack([values, ground.zmp, ground.margin[:, None]])
        document["min_stability_margin"] = float(ground.margin.min())
        for name, column in (
            ("zmp_x", ground.zmp[:, 0]),
            ("zmp_y", ground.zmp[:, 1]),
            ("stability_margin", ground.margin),
        ):
            document["columns"][name] = column.tolist()
    if traction is not None:
        columns = [(f"normal_force_{name}", traction.normal[:, c]) for c, name in enumerate(traction.contacts)]
        columns += [(f"traction_use_{name}", traction.use[:, w]) for w, name in enumerate(traction.wheels)]
        header = [*header, *(name for name, _ in columns)]
        values = np.hstack([values, *(column[:, None] for _, column in columns)])
        for name, column in columns:
            document["columns"][name] = [float(v) if math.isfinite(v) else None for v in column]
        i, w = traction.worst()
        worst = float(traction.use[i, w])
        document["traction"] = {
            "mu": traction.mu,
            "load": "compliant",
            "max_traction_use": worst if math.isfinite(worst) else None,
            "worst": {"sample": i, "t": float(result.trajectory.t[i]), "wheel": traction.wheels[w]},
            "slipping_samples": traction.slipping().tolist(),
            "unloaded_samples": traction.unloaded().tolist(),
        }  # fmt: skip
    if floor_scaling is not None:
        document["floor_time_scaling"] = floor_scaling.to_dict()
    paths = [out / f"{prefix}.csv", out / f"{prefix}.json", out / f"{prefix}.png"]
    write_table_csv(paths[0], header, values)
    write_json(paths[1], document)
    save_and_close(trajectory_figure(result), paths[2], dpi=100, bbox_inches="tight")
    return [str(p) for p in paths]


def carry_partial_outputs(robot: Robot, failure: CarryFailed, out_dir: str | Path) -> list[str]:
    """After a failed carry: the part of the motion that succeeded as trajectory.csv (a valid
    input of ``mobmanip trajectory``), the self-motion before it as preparation.csv (when there
    is one) and carry.json flagged ``"partial": true`` with the diagnosis; returns the paths."""
    out = Path(out_dir)
    run = failure.partial
    paths = [out / CARRY_FILES[0], out / CARRY_FILES[2]]
    write_trajectory_csv(
        robot, paths[0], run.t, run.q, {"capacity": run.capacity, "tracking_error": run.tracking_error}
    )
    write_json(paths[1], {"robot": robot.name, **_partial_summary(failure)})
    prep = failure.preparation
    if prep is not None:
        paths.append(out / CARRY_FILES[4])
        write_trajectory_csv(
            robot, paths[-1], prep.t, prep.q, {"capacity": prep.capacity, "tracking_error": prep.tracking_error}
        )
    return [str(p) for p in paths]


def carry_outputs(robot: Robot, result: CarryResult, out_dir: str | Path) -> list[str]:
    """trajectory.csv, baseline.csv, carry.json and capacity.png in ``out_dir``, and
    preparation.csv (the self-motion before the path, when there is one); returns the paths.

    trajectory.csv is the QP motion (a valid input of ``mobmanip trajectory``) with its capacity,
    the baseline's and its tracking error; capacity.png is
    :func:`mobmanip.viz.motion_figures.carry_figure`.
    """
    from ..viz.figures import save_and_close
    from ..viz.motion_figures import carry_figure

    out = Path(out_dir)
    motion, base = result.motion, result.baseline
    paths = [out / name for name in CARRY_FILES[:4]]
    write_trajectory_csv(
        robot,
        paths[0],
        motion.t,
        motion.q,
        {"capacity": motion.capacity, "baseline_capacity": base.capacity, "tracking_error": motion.tracking_error},
    )
    write_trajectory_csv(
        robot, paths[1], base.t, base.q, {"capacity": base.capacity, "tracking_error": base.tracking_error}
    )
    write_json(paths[2], {"robot": robot.name, **result.summary()})
    prep = result.preparation
    if prep is not None:
        paths.append(out / CARRY_FILES[4])
        write_trajectory_csv(
            robot, paths[-1], prep.t, prep.q, {"capacity": prep.capacity, "tracking_error": prep.tracking_error}
        )
    save_and_close(carry_figure(result, robot.name), paths[3], dpi=100, bbox_inches="tight")
    return [str(p) for p in paths]


#: The files ``retime --out DIR`` writes in DIR ...
RETIME_FILES = ("retimed.csv", "retime.json", "retime.png", "profile.csv")
#: ... and those ``carry --fastest --out DIR`` adds, in the same roles.
CARRY_FASTEST_FILES = ("fastest.csv", "fastest.json", "fastest.png", "fastest_profile.csv")


def retime_outputs(
    robot: Robot, result: Retiming, out_dir: str | Path, names: tuple[str, ...] = RETIME_FILES
) -> list[str]:
    """In ``out_dir``, under ``names``: the path at its fastest timing (readable by ``mobmanip
    trajectory``), :meth:`mobmanip.motion.retime.Retiming.to_dict` as JSON, the figure
    (:func:`mobmanip.viz.motion_figures.retime_figure`) and the profile (s, t, s', s'', the limit
    curve and the controllable bound per grid point) as CSV; returns the paths."""
    from ..viz.figures import save_and_close
    from ..viz.motion_figures import retime_figure

    out = Path(out_dir)
    paths = [out / name for name in names]
    write_trajectory_csv(robot, paths[0], result.t, result.trajectory.q)
    write_json(paths[1], result.to_dict())
    save_and_close(retime_figure(result), paths[2], dpi=100, bbox_inches="tight")
    header, values = result.table()
    write_table_csv(paths[3], header, values)
    return [str(p) for p in paths]


def write_rows_csv(path: str | Path, header: list[str], rows: list[list]) -> Path:
    """A CSV of rows already written as text (numbers by ``repr``, empty where there is none)."""
    with atomic_output(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)
    return Path(path)


def write_payload_along(result: PayloadAlong, out_dir: str | Path) -> list[str]:
    """payload_along.csv (one row per sample) and payload_along.json
    (:meth:`mobmanip.sweep.payload_map.PayloadAlong.to_dict`) in ``out_dir``; returns the paths."""
    out = Path(out_dir)
    paths = [out / "payload_along.csv", out / "payload_along.json"]
    write_rows_csv(paths[0], *result.table())
    write_json(paths[1], result.to_dict())
    return [str(p) for p in paths]


def write_payload_map(result: PayloadMap, out_dir: str | Path) -> list[str]:
    """payload_map.csv (one row per object position), payload_map.json
    (:meth:`mobmanip.sweep.payload_map.PayloadMap.to_dict`) and payload_map.png
    (:func:`mobmanip.viz.payload_figure.payload_map_figure`) in ``out_dir``; returns the paths."""
    from ..viz.figures import save_and_close
    from ..viz.payload_figure import payload_map_figure

    out = Path(out_dir)
    paths = [out / "payload_map.csv", out / "payload_map.json", out / "payload_map.png"]
    write_rows_csv(paths[0], *result.table())
    write_json(paths[1], result.to_dict())
    save_and_close(payload_map_figure(result), paths[2], dpi=100, bbox_inches="tight")
    return [str(p) for p in paths]


# ------------------------------------------------------------------------------------------------
# teams carrying an object

#: The files ``team-carry --out DIR`` writes in DIR besides one trajectory per robot.
TEAM_CARRY_FILES = ("team_carry.json", "capacity.png", "paths.png")


def team_file_stem(team: Team, index: int) -> str:
    """The robot's name in the team when it is a safe file name (letters, digits, ``_``, ``-``, ``.``,
    not starting with a dot, at most 64 characters), else ``robot<index + 1>``."""
    import re

    name = team.members[index].name
    if re.fullmatch(r"[A-Za-z0-9_-][A-Za-z0-9_.-]{0,63}", name):
        return name
    return f"robot{index + 1}"


def team_carry_paths(team: Team, out_dir: str | Path) -> dict[str, list[Path]]:
    """Every file ``team-carry --out DIR`` may write, by kind: ``trajectory``, ``baseline`` and
    ``preparation`` (one per robot, ``<kind>_<robot>.csv``) and ``summary`` (the JSON and figure)."""
    out = Path(out_dir)
    stems = [team_file_stem(team, k) for k in range(len(team.members))]
    paths = {kind: [out / f"{kind}_{stem}.csv" for stem in stems] for kind in ("trajectory", "baseline", "preparation")}
    paths["summary"] = [out / name for name in TEAM_CARRY_FILES]
    return paths


def _team_run_files(team: Team, run: TeamCarryRun, paths: list[Path], extra: Mapping[str, ArrayLike]) -> list[str]:
    for member, q, path in zip(team.members, run.q, paths):
        write_trajectory_csv(member.robot, path, run.t, q, extra)
    return [str(p) for p in paths]


def team_carry_outputs(result: TeamCarryResult, out_dir: str | Path) -> list[str]:
    """One trajectory per robot (``trajectory_<robot>.csv``, each a valid input of ``mobmanip
    trajectory``, with the team's capacity, the baseline's and the object's tracking error), the
    baseline's (``baseline_<robot>.csv``), the self-motion's (``preparation_<robot>.csv``, when
    there is one), ``team_carry.json`` (:meth:`TeamCarryResult.summary` and which file is whose),
    ``capacity.png`` (:func:`mobmanip.viz.motion_figures.carry_figure`) and ``paths.png`` (the top
    view, :func:`mobmanip.viz.motion_figures.team_carry_figure`); returns the paths."""
    from ..viz.figures import save_and_close
    from ..viz.motion_figures import carry_figure, team_carry_figure

    team = result.team
    paths = team_carry_paths(team, out_dir)
    motion, base, prep = result.motion, result.baseline, result.preparation
    written = _team_run_files(
        team, motion, paths["trajectory"],
        {"capacity": motion.capacity, "baseline_capacity": base.capacity, "tracking_error": motion.tracking_error},
    )  # fmt: skip
    written += _team_run_files(
        team, base, paths["baseline"], {"capacity": base.capacity, "tracking_error": base.tracking_error}
    )
    if prep is not None:
        written += _team_run_files(
            team, prep, paths["preparation"], {"capacity": prep.capacity, "tracking_error": prep.tracking_error}
        )
    summary, figure, top = paths["summary"]
    files = {kind: {m.name: p.name for m, p in zip(team.members, paths[kind])} for kind in ("trajectory", "baseline")}
    if prep is not None:
        files["preparation"] = {m.name: p.name for m, p in zip(team.members, paths["preparation"])}
    write_json(summary, {**result.summary(), "files": files})
    save_and_close(carry_figure(result, f"team {team.name}"), figure, dpi=100)
    save_and_close(team_carry_figure(result), top, dpi=100)
    return written + [str(summary), str(figure), str(top)]


def team_carry_page(result: TeamCarryResult, path: str | Path, every: int | None = None) -> tuple[Path, list[str]]:
    """The page ``team-carry --export PAGE.html`` writes: the team's QP motion played in the viewer
    (:func:`mobmanip.viz.team_motion_page.export_team_motion_page`); returns its path and one note
    per mesh left out."""
    from ..viz.team_motion_page import export_team_motion_page

    return export_team_motion_page(result, path, every=every)


def team_carry_partial_outputs(team: Team, failure: CarryFailed, out_dir: str | Path) -> list[str]:
    """After a failed team carry: the part of the motion that succeeded, one trajectory per robot,
    the self-motion before it (when there is one) and ``team_carry.json`` flagged ``"partial":
    true`` with the diagnosis; returns the paths."""
    paths = team_carry_paths(team, out_dir)
    run = failure.partial
    kind = "preparation" if run.method == "self-motion" else "trajectory"
    written = _team_run_files(team, run, paths[kind], {"capacity": run.capacity, "tracking_error": run.tracking_error})
    prep = failure.preparation
    if prep is not None and kind != "preparation":
        written += _team_run_files(
            team, prep, paths["preparation"], {"capacity": prep.capacity, "tracking_error": prep.tracking_error}
        )
    write_json(paths["summary"][0], {"team": team.name, **_partial_summary(failure)})
    return written + [str(paths["summary"][0])]


# ------------------------------------------------------------------------------------------------
# sites

#: The files ``mobmanip site`` writes in its output directory.
SITE_FILES = ("site.csv", "site.png")


def write_site_csv(result: SiteResult, path: str | Path) -> Path:
    """One row per object position, in the site's order: the result's columns (numbers as
    Python's shortest exact ``repr``, empty where there is no placement) and ``reason``, why a
    position has no placement or no grounded capacity."""
    path = Path(path)
    with atomic_output(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow([*result.columns, "reason"])
        for row, reason in zip(result.table, result.reasons):
            writer.writerow([*("" if not math.isfinite(v) else repr(float(v)) for v in row), reason])
    return path


def site_outputs(result: SiteResult, out_dir: str | Path) -> list[Path]:
    """:data:`SITE_FILES` in ``out_dir`` (which must exist): the table and the map figure."""
    from ..viz.site_figure import plot_site

    out = Path(out_dir)
    table, figure = (out / name for name in SITE_FILES)
    return [write_site_csv(result, table), plot_site(result, figure)]


def _partial_summary(failure) -> dict:
    """What a failed carry (one robot's or a team's) kept: flagged partial, how far it got, the
    diagnosis, and the part's capacity and tracking."""
    run = failure.partial
    return {
        "partial": True,
        "method": run.method,
        "completed_until": float(run.t[-1]),
        "failure": failure.diagnosis.to_dict(),
        "min_capacity": float(run.capacity.min()),
        "max_tracking_error": float(run.tracking_error.max()),
    }
