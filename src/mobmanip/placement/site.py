"""Sites: the best placement for every object position of a list or grid, on one machine or a cluster.

A site file (TOML) names the robot, the objective and the object positions::

    robot = "planar_dual_arm"            # built-in name or spec path (relative to the site file)
    objective = "kinematic:capacity:+x"  # as mobmanip place
    mass = 1.0                           # optional, kg (default: the spec's)
    task = "planar"                      # optional (default: the spec's)
    starts = 8                           # optional, starts per position (default 8)
    positions = [[1.0, 0.5, 0.35], [1.5, 0.5, 0.35]]   # a list of X,Y,Z (m) ...

    [grid]                               # ... or a grid: [start, stop, count] per axis, or a value
    x = [0.0, 3.0, 4]
    y = [0.0, 1.0, 2]
    z = 0.35

    [grounded]                           # optional: the capacity on the floor at each optimum
    mu = 0.5                             # friction coefficient, or "spec"
    direction = "+x"                     # signed task axis of the straight-line reach
    level = false                        # hold the object level on the floor (as --level)

Each position is :func:`mobmanip.placement.place`'s problem on its own (the same starts, so
the result does not depend on the order, the worker or a retry). An objective that reads a
measure (``MEASURE:READING:DIRECTION``, e.g. ``dynamic_polytope:reach:+x``) is placed by
:func:`mobmanip.placement.grounded.place_polytope` instead (``budget`` evaluations of its
search, default 300), with the site's ``constraints`` (a user's, e.g. from a registered
command-line option): the value is the reading with them. An ellipsoid's objective cannot honour
a constraint and is refused with one. With ``[grounded]`` the
optimum is analysed with :class:`mobmanip.terms.constraints.floor.Floor` and the
``dynamic_polytope`` measure (and the site's constraints), and the straight-line reach (m/s^2)
along ``direction`` is recorded;
where that set is empty (the robot cannot stand still with every support loaded, e.g. arms
stretched far out) the value is left out and the row's reason says which supports would unload.
Positions run in tasks of ``positions_per_task`` through any :class:`concurrent.futures.Executor`
(a Dask client's for a cluster) or in this process.
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import sys
import time
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, MobmanipError, SpecError, TaskError
from ..gradients.readings import is_reading_objective
from ..robot.model import Robot, robot_in_process
from ..robot.support_spec import check_mu
from ..robot.tasks import TaskSpace, get_task
from ..support.ranges import PLATFORM_POSITION
from .grounded import DEFAULT_BUDGET, place_polytope
from .optimize import DEFAULT_STARTS, place

#: Most object positions one site may hold, whatever the work bound (a list or a grid).
MAX_POSITIONS = 1_000_000
#: The largest ``budget`` of a reading objective's search per position.
MAX_BUDGET = 100_000

#: A check of a site's number of positions before they are made: ``(count, how it follows from
#: the file)``; raises to refuse.
CountCheck = Callable[[int, str], None]

#: Per-position result columns (besides the joints).
COLUMNS = ("x", "y", "z", "value", "platform_x", "platform_y", "heading_deg", "hold_turn_deg", "grounded_reach",
           "evaluations")  # fmt: skip


@dataclass(frozen=True)
class Site:
    """A site: the robot, the objective and the object positions.

    Attributes:
        robot: built-in robot name or spec path (absolute).
        objective: the objective's text (see :func:`mobmanip.placement.place`).
        positions: object centres (m, world), (n, 3).
        mass, task, starts: as :func:`place`'s ``object_mass``, ``task``, ``starts``.
        mu: the floor's friction coefficient (a number or ``"spec"``) for the grounded capacity;
            None: not computed.
        direction: signed task axis of the grounded straight-line reach (e.g. ``"+x"``).
        grid_shape: (Nx, Ny, Nz) when the positions are a grid (x fastest), else None.
        level: the grounded capacity holds the object level (``Floor(level=True)``).
        budget: evaluations of a reading objective's search (:func:`place_polytope`'s).
        constraints: constraints every set honours (a reading objective's and the grounded
            reach's); not read from the file: a user's come from Python or a command-line option.
    """

    robot: str
    objective: str
    positions: np.ndarray = field(compare=False)
    mass: float | None = None
    task: str | None = None
    starts: int = DEFAULT_STARTS
    mu: float | str | None = None
    direction: str = "+x"
    grid_shape: tuple[int, int, int] | None = None
    level: bool = False
    budget: int = DEFAULT_BUDGET
    constraints: tuple = field(default=(), compare=False)

    @classmethod
    def read(cls, path: str | Path, check_count: CountCheck | None = None) -> Site:
        """Read and check a site file.

        Args:
            path: the site file.
            check_count: called with the number of positions and how it follows from the file
                (``"[grid] x 4 x y 2 x z 1"``) before any position is made; it raises to refuse
                (the ``site`` command's work bound, ``--max-work``).

        Raises:
            SpecError: unreadable, malformed, or with no positions or more than :data:`MAX_POSITIONS`.
        """
        from ..support.reading import read_user_text

        path = Path(path)
        text = read_user_text(path, "site file", error=SpecError)  # a regular file of bounded size
        try:
            document = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise SpecError(f"site file {path}: {exc}") from None
        return cls.from_document(document, path.parent, str(path), check_count)

    @classmethod
    def from_document(
        cls, document: Mapping, base: Path = Path("."), where: str = "site", check_count: CountCheck | None = None
    ) -> Site:
        """A site from its TOML document (paths relative to ``base``; ``check_count`` as :meth:`read`)."""
        known = {"robot", "objective", "mass", "task", "starts", "budget", "positions", "grid", "grounded"}
        unknown = sorted(set(document) - known)
        if unknown:
            raise SpecError(f"{where}: unknown key(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
        robot, objective = document.get("robot"), document.get("objective")
        if not isinstance(robot, str) or not robot:
            raise SpecError(f"{where}: 'robot' must name a built-in robot or a spec file")
        if not isinstance(objective, str) or not objective:
            raise SpecError(f"{where}: 'objective' must be text like \"kinematic:capacity:+x\"")
        spec_path = base / robot
        if robot.endswith(".toml") and spec_path.is_file():
            robot = str(spec_path.resolve())
        mass = document.get("mass")
        number = isinstance(mass, (int, float)) and not isinstance(mass, bool)
        if mass is not None and (not number or not 0 <= mass < math.inf or not math.isfinite(_float(mass))):
            raise SpecError(f"{where}: 'mass' must be a finite non-negative number of kg, got {_shown(mass)}")
        starts = document.get("starts", DEFAULT_STARTS)
        if isinstance(starts, bool) or not isinstance(starts, int) or not 1 <= starts <= 64:
            raise SpecError(f"{where}: 'starts' must be an integer from 1 to 64, got {starts!r}")
        budget = document.get("budget", DEFAULT_BUDGET)
        if isinstance(budget, bool) or not isinstance(budget, int) or not 1 <= budget <= MAX_BUDGET:
            raise SpecError(f"{where}: 'budget' must be an integer from 1 to {MAX_BUDGET:,}, got {budget!r}")
        task = document.get("task")
        if task is not None and not isinstance(task, str):
            raise SpecError(f"{where}: 'task' must be a task space's name, got {task!r}")
        positions, shape = _positions(document, where, check_count)
        grounded = document.get("grounded")
        mu, direction, level = None, "+x", False
        if grounded is not None:
            if not isinstance(grounded, Mapping) or set(grounded) - {"mu", "direction", "level"}:
                raise SpecError(f"{where}: [grounded] takes mu, direction and level")
            level = grounded.get("level", False)
            if not isinstance(level, bool):
                raise SpecError(f"{where}: [grounded] level must be true or false, got {level!r}")
            mu = grounded.get("mu", "spec")
            if mu != "spec" and (isinstance(mu, bool) or not isinstance(mu, (int, float)) or not mu > 0):
                raise SpecError(f'{where}: [grounded] mu must be a positive number or "spec", got {mu!r}')
            if mu != "spec":
                check_mu(mu, f"{where}: [grounded] mu")
            direction = grounded.get("direction", "+x")
            if not isinstance(direction, str) or direction[:1] not in "+-" or len(direction) < 2:
                raise SpecError(f'{where}: [grounded] direction must be a signed task axis like "+x"')
        return cls(robot, objective, positions, None if mass is None else float(mass), task, starts, mu, direction,
                   shape, level, budget)  # fmt: skip


def _axis(value, name: str, where: str) -> tuple[float, float, int]:
    """``(start, stop, count)`` of one grid axis, checked; nothing is allocated here."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        start = stop = _float(value)
        count = 1
    elif isinstance(value, list) and len(value) == 3 and all(isinstance(v, (int, float)) for v in value):
        start, stop, count = value
        if isinstance(count, bool) or not isinstance(count, int) or count < 1 or (count == 1 and start != stop):
            raise SpecError(f"{where}: [grid] {name} = [start, stop, count] needs a whole count >= 1")
        start, stop = _float(start), _float(stop)
    else:
        raise SpecError(f"{where}: [grid] {name} must be a number or [start, stop, count]")
    if not (math.isfinite(start) and math.isfinite(stop)):
        shown = ", ".join(_shown(v) for v in (value if isinstance(value, list) else [value])[:2])
        raise SpecError(f"{where}: [grid] {name} must be finite, got {shown}")
    if max(abs(start), abs(stop)) > PLATFORM_POSITION:  # a figure cannot even draw such an axis
        raise SpecError(f"{where}: [grid] {name} from {start:g} to {stop:g} m goes beyond +-{PLATFORM_POSITION:g} m")
    return start, stop, count


def _check_count(count: int, detail: str, check_count: CountCheck | None) -> None:
    """Refuse ``count`` positions above :data:`MAX_POSITIONS` or above what ``check_count`` allows,
    before any of them is made."""
    if count > MAX_POSITIONS:  # never made, whatever the work bound
        raise SpecError(f"{detail} gives {count:,} object positions, more than the {MAX_POSITIONS:,} any site may hold")
    if check_count is not None:
        check_count(count, detail)


def _float(value: int | float) -> float:
    """``float(value)``, or infinity for an integer no float holds (hundreds of digits)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf


def _shown(value) -> str:
    """A value for a message: an integer of hundreds of digits by its length."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > sys.float_info.max:
        return f"an integer of {len(str(abs(value)))} digits"
    return repr(value)


def _unrepresentable(raw) -> str:
    """Where ``raw`` (the positions as read) holds an integer too large for a float, and its size."""
    for i, row in enumerate(raw):
        for j, value in enumerate(row if isinstance(row, list) else [row]):
            if isinstance(value, int) and not isinstance(value, bool) and abs(value) > sys.float_info.max:
                return f"positions[{i}][{j}] is an integer of {len(str(abs(value)))} digits, too large for metres"
    return "'positions' holds a number too large for metres"


def _positions(
    document: Mapping, where: str, check_count: CountCheck | None = None
) -> tuple[np.ndarray, tuple[int, int, int] | None]:
    has_list, has_grid = "positions" in document, "grid" in document
    if has_list == has_grid:
        which = "both" if has_list else "neither"
        raise SpecError(f"{where}: give either 'positions' (a list of [x, y, z]) or a [grid], not {which}")
    if has_list:
        raw = document["positions"]
        if isinstance(raw, list):
            _check_count(len(raw), f"'positions' in {where}", check_count)
        try:
            positions = np.array(raw, dtype=float)
        except OverflowError:  # an integer of hundreds of digits: no float holds it
            raise SpecError(f"{where}: {_unrepresentable(raw)}") from None
        except (TypeError, ValueError):
            positions = np.zeros((0, 0))
        if positions.ndim != 2 or positions.shape[1] != 3 or positions.shape[0] == 0:
            raise SpecError(f"{where}: 'positions' must be a non-empty list of [x, y, z] in metres")
        if not np.all(np.isfinite(positions)):
            i, j = np.argwhere(~np.isfinite(positions))[0]
            raise SpecError(f"{where}: positions[{i}][{j}] = {positions[i, j]} must be finite")
        if np.any(np.abs(positions) > PLATFORM_POSITION):
            i, j = np.argwhere(np.abs(positions) > PLATFORM_POSITION)[0]
            raise SpecError(f"{where}: positions[{i}][{j}] = {positions[i, j]:g} m is beyond +-{PLATFORM_POSITION:g} m")
        shape = None
    else:
        grid = document["grid"]
        if not isinstance(grid, Mapping) or set(grid) != {"x", "y", "z"}:
            raise SpecError(f"{where}: [grid] needs exactly x, y and z")
        axes = {k: _axis(grid[k], k, where) for k in "xyz"}
        counts = [axes[k][2] for k in "xyz"]
        detail = f"[grid] in {where}: x {counts[0]:,} by y {counts[1]:,} by z {counts[2]:,}"
        _check_count(math.prod(counts), detail, check_count)  # before any position is made
        with np.errstate(all="ignore"):  # an overflowing step is refused below, not warned about
            xs, ys, zs = (np.linspace(*axes[k]) for k in "xyz")
        for name, values in zip("xyz", (xs, ys, zs)):
            if not np.all(np.isfinite(values)):  # e.g. [-1e308, 1e308, 3]: the step overflows
                raise SpecError(f"{where}: [grid] {name} must be finite")
        Z, Y, X = np.meshgrid(zs, ys, xs, indexing="ij")
        positions = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
        shape = (xs.size, ys.size, zs.size)
    return positions, shape


@dataclass(frozen=True)
class SiteResult:
    """The site's per-position results (rows in the site's order; NaN where nothing holds the object).

    Attributes:
        site: the site.
        table: :data:`COLUMNS` then one column per configuration entry (``q.`` and its name, e.g.
            ``q.platform_cos_yaw``), (n, len(columns)).
        columns: the column names.
        reasons: per position, why it has no placement ("" where it has one).
        seconds: wall time of the run (s).
        task: the task space the objective was measured in (the site's, else the robot's default).
    """

    site: Site
    table: np.ndarray
    columns: tuple[str, ...]
    reasons: tuple[str, ...]
    seconds: float
    task: str | None = None

    @property
    def values(self) -> np.ndarray:
        return self.table[:, self.columns.index("value")]


def _grounded_reach(robot: Robot, q: np.ndarray, site: Site) -> float:
    from ..analysis.plausibility import floor_warnings
    from ..analysis.single import analyze
    from ..terms.constraints.floor import Floor

    task = get_task(site.task or robot.spec.default_task)
    e = _grounded_direction(site, task)
    constraints = (Floor(mu=site.mu, level=site.level), *site.constraints)
    analysis = analyze(robot, q, task.name, object_mass=site.mass, constraints=constraints,
                       measures=("dynamic_polytope",))  # fmt: skip
    polytope = analysis.measure("dynamic_polytope")
    reach = getattr(polytope, "straight_line_reach", None)
    if reach is None:
        raise ArgumentError("the dynamic polytope of this robot has no straight-line reach")
    if polytope.empty:  # not even rest: no reach to report, and the reason why
        raise TaskError(" ".join(floor_warnings(analysis)) or "the set on the floor is empty")
    return float(reach(e))


def _grounded_direction(site: Site, task) -> np.ndarray:
    """The unit task direction of ``[grounded] direction``.

    Raises:
        ArgumentError: not one of the task's axes.
    """
    label = site.direction[1:]
    if label not in task.labels:
        axes = ", ".join(f"{sign}{name}" for name in task.labels for sign in "+-")
        raise ArgumentError(f"[grounded] direction {site.direction!r}: the {task.name} task's axes are {axes}")
    e = np.zeros(task.dim)
    e[task.labels.index(label)] = 1.0 if site.direction[0] == "+" else -1.0
    return e


def solve_positions(site: Site, start: int, stop: int) -> tuple[int, np.ndarray, list[str]]:
    """Rows [start, stop) of the site (a worker task): (start, rows, reasons)."""
    robot = robot_in_process(site.robot)
    nq = robot.model.nq
    rows = np.full((stop - start, len(COLUMNS) + nq), np.nan)
    reasons = []
    for k, position in enumerate(site.positions[start:stop]):
        rows[k, :3] = position
        try:
            if is_reading_objective(site.objective):
                result = place_polytope(robot, position, site.objective, site.task, constraints=site.constraints,
                                        object_mass=site.mass, starts=site.starts, budget=site.budget)  # fmt: skip
            else:
                result = place(robot, position, site.objective, site.task, object_mass=site.mass, starts=site.starts)
        except MobmanipError as exc:
            reasons.append(" ".join(str(exc).split()))
            continue
        x, y, heading = result.platform
        grounded = math.nan
        if site.mu is not None:
            try:
                grounded = _grounded_reach(robot, result.q, site)
            except MobmanipError as exc:
                reasons.append(f"grounded capacity: {' '.join(str(exc).split())}")
            else:
                reasons.append("")
        else:
            reasons.append("")
        values = (result.value, x, y, math.degrees(heading), math.degrees(result.hold_turn), grounded,
                  result.evaluations)  # fmt: skip
        rows[k, 3 : len(COLUMNS)] = values
        rows[k, len(COLUMNS) :] = result.q
    return start, rows, reasons


def check_site(site: Site) -> tuple[Robot, TaskSpace]:
    """The site's robot and task, once its robot, objective, task, constraints and grounded
    direction are checked (what :func:`run_site` checks before any work; a command calls it
    before it prints).

    Raises:
        MobmanipError: the robot cannot be loaded, the objective or the task is malformed, an
            ellipsoid's objective with constraints, a grounded direction not of the task.
    """
    from ..gradients.evaluator import Objective
    from ..gradients.readings import ReadingObjective

    robot = robot_in_process(site.robot)  # a bad robot fails here, once; the tasks here reuse it
    task = get_task(site.task or robot.spec.default_task)
    if is_reading_objective(site.objective):
        ReadingObjective.parse(site.objective, task)
    else:
        Objective.parse(site.objective, task)
        if site.constraints:
            names = ", ".join(getattr(c, "name", type(c).__name__) for c in site.constraints)
            raise ArgumentError(
                f"the site's objective {site.objective!r} is an ellipsoid's, which cannot honour the constraints "
                f"({names}): give a measure's reading (e.g. dynamic_polytope:reach:+x)"
            )
    if site.mu is not None:
        _grounded_direction(site, task)
    return robot, task


def run_site(
    site: Site, executor: cf.Executor | None = None, positions_per_task: int = 1, progress: bool = False
) -> SiteResult:
    """Every position's placement, in this process or on ``executor``; the same result either way.

    Raises:
        ArgumentError: ``positions_per_task`` below 1.
        MobmanipError: as :func:`check_site` (checked here first, once, not in every task).
    """
    if isinstance(positions_per_task, bool) or not isinstance(positions_per_task, int) or positions_per_task < 1:
        raise ArgumentError(f"positions per task must be a positive integer, got {positions_per_task!r}")
    started = time.perf_counter()
    robot, task = check_site(site)
    n = len(site.positions)
    # the configuration's columns, named (not q_0..) and apart from the placement's own platform_x, platform_y
    names = tuple(f"q.{name}" for name in robot.coordinate_names)
    table = np.full((n, len(COLUMNS) + len(names)), np.nan)
    reasons = [""] * n
    bounds = [(s, min(s + positions_per_task, n)) for s in range(0, n, positions_per_task)]

    from tqdm import tqdm

    bar = tqdm(total=n, unit="position", disable=not progress, desc=f"site {robot.name}", leave=False)

    def store(start: int, rows: np.ndarray, why: list[str]) -> None:
        table[start : start + len(rows)] = rows
        reasons[start : start + len(rows)] = why
        bar.update(len(rows))

    try:
        if executor is None:
            for s, e in bounds:
                store(*solve_positions(site, s, e))
        else:
            futures = [executor.submit(solve_positions, site, s, e) for s, e in bounds]
            for future in cf.as_completed(futures):
                store(*future.result())
    finally:
        bar.close()
    return SiteResult(site, table, COLUMNS + names, tuple(reasons), time.perf_counter() - started, task.name)
