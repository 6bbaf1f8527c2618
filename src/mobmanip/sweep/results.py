"""A sweep's results: the index arrays over the grid and their names.

:class:`SweepResult` holds, for every measure swept (:mod:`mobmanip.measures`), its indices over
the grid of :class:`mobmanip.sweep.SweepGrid`; :func:`check_index_name` and :func:`index_names`
define the names users ask for (``kinematic.volume``, ``dynamic.semi_axis_1``, ...).
:func:`mobmanip.viz.sweep_plot.plot_sweep` draws one and :mod:`mobmanip.commands.outputs`
writes a result's files. :mod:`mobmanip.sweep` runs sweeps and re-exports these names.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ArgumentError
from ..measures import Measure, resolve_measures
from ..postures.inverse_kinematics import IKPostureTable
from ..postures.planar import PostureTable
from .spec import AXES

if TYPE_CHECKING:
    from .spec import SweepGrid, SweepSpec

#: Scalar indices recorded by a sweep for every measure: ``capacity`` is the support along the
#: sweep's direction d (max d . p over the set), ``straight_line_reach`` the largest s >= 0 with
#: s d in the set (how far exactly along d from rest); they differ when the set is shifted off
#: the origin (gravity) or when its boundary point farthest along d is not on the ray.
SCALAR_INDICES = ("volume", "isotropy", "capacity", "straight_line_reach")
#: Flags recorded by a sweep for every measure.
FLAGS = ("degenerate", "empty")


@dataclass(frozen=True)
class SweepResult:
    """Indices over a sweep grid.

    ``indices[name]`` has the grid's shape (angle, distance, heading, wheel velocity scale,
    wheel effort scale), with a trailing task axis for per-axis arrays (``*_semi_axes``). Names:
    ``<measure>_{volume,isotropy,capacity,straight_line_reach,degenerate,empty}`` for every
    measure swept (see :data:`SCALAR_INDICES`), and its
    per-axis arrays (``<measure>_semi_axes`` for the ellipsoids), e.g. ``kinematic_volume``.
    Indices of velocities (kinematic) do not depend on the effort scale, nor those of
    accelerations (dynamic) on the velocity scale; both are repeated along that axis.
    Unreachable grid points hold NaN (and False flags).

    Attributes:
        spec: what was swept.
        grid: the grid.
        task: task-space name.
        task_axes: labels of the task coordinates.
        reachable: whether the arms reach each (angle, distance, heading), (A, D, H).
        indices: the arrays described above.
        postures: the arms' postures: a :class:`PostureTable` per distance (planar closed form)
            or a :class:`mobmanip.postures.inverse_kinematics.IKPostureTable` per (angle, distance); see
            :meth:`joint_positions` for both as one array.
    """

    spec: SweepSpec
    grid: SweepGrid
    task: str
    task_axes: tuple[str, ...]
    reachable: np.ndarray
    indices: dict
    postures: PostureTable | IKPostureTable

    def __repr__(self) -> str:
        shape = " x ".join(str(n) for n in self.grid.shape)
        measures = ", ".join(m.name for m in self.measures)
        reach = f"{int(np.count_nonzero(self.reachable))}/{self.reachable.size}"
        return (
            f"SweepResult(robot={str(self.spec.robot)!r}, task={self.task!r}, grid {shape} "
            f"(angle x distance x heading x velocity scale x effort scale), measures {measures}, "
            f"reachable {reach})"
        )

    def joint_positions(self) -> tuple[tuple[str, ...], np.ndarray]:
        """The arm joints' names and positions (rad or m) at every (angle, distance), (A, D, n);
        NaN where unreachable. The platform heading turns the whole robot and does not change them."""
        table = self.postures
        if isinstance(table, IKPostureTable):
            return table.joint_names, table.joints
        a, d = self.grid.shape[:2]
        ia, idist = (i.ravel() for i in np.meshgrid(np.arange(a), np.arange(d), indexing="ij"))
        values, reachable = table.joint_values(np.radians(self.grid.angle_deg[ia]), idist)
        values[~reachable] = np.nan
        return table.joint_names, values.reshape(a, d, -1)

    @property
    def measures(self) -> tuple[Measure, ...]:
        """The definitions of the measures swept, in order."""
        return resolve_measures(self.spec.measures, sweep=True)

    def ignored_constraints(self, name: str) -> tuple[str, ...]:
        """The constraints beyond the joint boxes (``SweepSpec.constraints``) that measure
        ``name`` ignored: those on its quantity's problem when it cannot honour them (an ellipsoid)."""
        measure = next((m for m in self.measures if m.name == name), None)
        if measure is None:
            raise ArgumentError(f"measure {name!r} was not swept ({', '.join(m.name for m in self.measures)})")
        if measure.honours_constraints:
            return ()
        problem = "velocity" if measure.quantity.limits == "velocity" else "acceleration"
        return tuple(c.name for c in self.spec.constraints if c.problem == problem)

    def index(self, name: str) -> np.ndarray:
        """One index by name: ``kinematic.volume``, ``dynamic.semi_axis_1`` (largest), ...

        Raises:
            ArgumentError: an unknown name (the message lists the valid ones).
        """
        kind, what, k = check_index_name(name, len(self.task_axes), self.spec.measures)
        if k is None:
            return self.indices[f"{kind}_{what}"]
        return self.indices[f"{kind}_{what}"][..., k - 1]

    def arrays(self) -> dict[str, np.ndarray]:
        """The grid axes, the indices, the postures and the settings as named arrays: what
        :func:`mobmanip.commands.outputs.write_sweep_npz` writes to a ``.npz`` file.

        Keys: the grid axes (:data:`AXES`), every index array, ``reachable`` (A, D, H),
        ``posture_joint_names`` and ``posture_joints`` (A, D, n) (:meth:`joint_positions`), and
        ``meta_*`` texts (``meta_postures`` is ``planar`` or ``ik``). Planar postures add
        ``posture_right`` / ``posture_left`` ((q2, q3, bearing) per distance); inverse-kinematics
        ones add ``posture_position_error`` and ``posture_rotation_error`` (A, D),
        ``posture_reference`` (the reference configuration) and the hold: ``hold_origin``,
        ``hold_height``, ``hold_offsets``, ``hold_rotations`` (see :class:`mobmanip.postures.inverse_kinematics.Hold`).
        """
        arrays = {name: getattr(self.grid, name) for name in AXES}
        arrays.update(self.indices)
        arrays["reachable"] = self.reachable
        table = self.postures
        names, joints = self.joint_positions()
        arrays["posture_joint_names"] = np.array(names, dtype=str)
        arrays["posture_joints"] = joints
        if isinstance(table, PostureTable):
            arrays["posture_right"] = table.right
            arrays["posture_left"] = table.left
        else:
            arrays["posture_position_error"] = table.position_error
            arrays["posture_rotation_error"] = table.rotation_error
            arrays["posture_reference"] = table.reference
            arrays["hold_origin"] = table.hold.origin
            arrays["hold_height"] = np.array(table.hold.height)
            arrays["hold_offsets"] = table.hold.offsets
            arrays["hold_rotations"] = table.hold.rotations
        meta = {
            "robot": str(self.spec.robot),
            "task": self.task,
            "task_axes": ",".join(self.task_axes),
            "platform": self.spec.platform,
            "decoupled": str(self.spec.decoupled),
            "object_mass": str(self.spec.object_mass),
            "direction": str(self.spec.direction),
            "axes": ",".join(AXES),
            "postures": table.method,
            "constraints": ",".join(c.name for c in self.spec.constraints),
            # each constraint's parameters (a floor's mu, reserve, ramp), JSON: a sweep on a ramp
            # must not read as one on the level floor
            "constraint_models": json.dumps([c.describe() for c in self.spec.constraints]),
        }
        arrays.update({f"meta_{k}": np.array(v) for k, v in meta.items()})
        return arrays

    def table(self) -> tuple[list[str], np.ndarray]:
        """(header, rows): one row per grid point with the axis values, reachability (0 or 1) and
        every index (flags as 0 or 1); what :func:`mobmanip.commands.outputs.write_sweep_csv`
        writes."""
        m = len(self.task_axes)
        grids = np.meshgrid(*(getattr(self.grid, name) for name in AXES), indexing="ij")
        reach = np.broadcast_to(self.reachable[..., None, None], self.grid.shape)
        columns, header = [g.ravel() for g in grids], list(AXES)
        columns.append(reach.ravel().astype(int))
        header.append("reachable")
        for measure in self.measures:
            kind = measure.name
            for name in SCALAR_INDICES:
                columns.append(self.indices[f"{kind}_{name}"].ravel())
                header.append(f"{kind}_{name}")
            for attribute, stem in measure.axis_indices:
                for k in range(m):
                    columns.append(self.indices[f"{kind}_{attribute}"][..., k].ravel())
                    header.append(f"{kind}_{stem}_{k + 1}")
            for flag in FLAGS:
                columns.append(self.indices[f"{kind}_{flag}"].ravel().astype(int))
                header.append(f"{kind}_{flag}")
        return header, np.column_stack(columns)


def check_index_name(name: str, m: int, measures: Iterable[str] | None = None) -> tuple[str, str, int | None]:
    """Split an index name into (measure, index or per-axis array, axis number or None):
    ``"kinematic.volume"`` gives ``("kinematic", "volume", None)``, ``"dynamic.semi_axis_2"``
    gives ``("dynamic", "semi_axes", 2)``.

    Args:
        name: ``<measure>.<index>``.
        m: task dimension.
        measures: the measures swept (names; ``None``: the default ones).

    Raises:
        ArgumentError: an unknown name (the message lists the valid ones for an m-dimensional task).
    """
    kind, _, what = str(name).replace("-", "_").partition(".")
    for measure in resolve_measures(measures, sweep=True):
        if kind != measure.name:
            continue
        if what in SCALAR_INDICES:
            return kind, what, None
        for attribute, stem in measure.axis_indices:
            number = what[len(stem) + 1 :] if what.startswith(f"{stem}_") else ""
            if number.isdigit() and 1 <= int(number) <= m:
                return kind, attribute, int(number)
    raise ArgumentError(f"unknown index {name!r}; expected one of {', '.join(index_names(m, measures))}")


def index_names(m: int, measures: Iterable[str] | None = None) -> list[str]:
    """Names accepted by :meth:`SweepResult.index` for an m-dimensional task and the measures
    swept (names; ``None``: the default ones)."""
    out = []
    for measure in resolve_measures(measures, sweep=True):
        out += [f"{measure.name}.{name}" for name in SCALAR_INDICES]
        for _, stem in measure.axis_indices:
            out += [f"{measure.name}.{stem}_{k}" for k in range(1, m + 1)]
    return out
