"""The spec's ``[support]`` table: passive supports and friction of the driven wheels, read
and checked before any robot is loaded (:mod:`mobmanip.robot.spec` reads it; the support of a
loaded robot, its contact points and polygon, is :mod:`mobmanip.robot.support`'s).

The table (all keys optional)::

    [support]
    mu = 0.5                      # friction coefficient of the driven wheels on the floor
    faces = 8                     # faces of the pyramid inscribed in each wheel's friction cone
    casters = [[0.25, 0.14], ...] # passive supports, [x, y] (on the floor) or [x, y, z] (m, root frame)
    urdf_casters = true           # also take the URDF's caster wheels
    wheels = [[0.2, 0.2], ...]    # driven contacts of a base without wheel joints (omnidirectional:
                                  # a planar joint driven by wheels the file does not model), rows as casters
    rollers = [45.0, -45.0, ...]  # optional, one per row of wheels: the free-rolling direction of its
                                  # rollers (deg from the root frame's +x; mecanum, omni wheels): no force along it

    [support.stiffness]           # relative vertical stiffness per contact (default 1 each)
    caster_0 = 0.4                # e.g. a sprung caster: only the ratios matter
    wheel_left_joint = 1.0        # contacts by name: wheel joints, URDF caster links, caster_<k>

The stiffness decides how a robot on more than three contacts shares its weight when the
sharing is compliant (``Floor(load="compliant")``): under a rigid platform each contact is a
spring, so its normal force is its stiffness times a deflection that is an affine function of
its floor position.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from ..errors import ArgumentError, SpecError

#: Friction coefficient of driven wheels when the spec gives none.
DEFAULT_MU = 0.5
#: The largest friction coefficient accepted: beyond it the friction rows, scaled by mu, leave
#: the linear programs badly scaled (HiGHS stops undecided near 1e9) for no physical meaning.
MAX_MU = 10.0
#: Faces of the pyramid inscribed in each friction cone (conservative by 1 - cos(pi / faces): 7.6 %).
DEFAULT_FACES = 8


@dataclass(frozen=True)
class SupportSpec:
    """The spec's ``[support]`` table (see the module's docstring).

    Attributes:
        casters: passive supports in the root frame, (x, y) or (x, y, z) rows (m).
        mu: friction coefficient of the driven wheels; ``None``: :data:`DEFAULT_MU`.
        faces: faces of the inscribed friction pyramid.
        urdf_casters: also take the URDF's caster wheels.
        stiffness: relative vertical stiffness by contact name (> 0); contacts not named have 1.
        wheels: driven contacts of a base whose wheels are not joints of the file (an
            omnidirectional base), (x, y) or (x, y, z) rows (m); their traction is the base's
            effort.
        rollers: per row of ``wheels``, the free-rolling direction of its rollers (deg from the
            root frame's +x), along which it can push nothing; empty: none (traction in every
            direction within friction).
    """

    casters: tuple[tuple[float, ...], ...] = ()
    mu: float | None = None
    faces: int = DEFAULT_FACES
    urdf_casters: bool = True
    stiffness: Mapping[str, float] = field(default_factory=dict)
    wheels: tuple[tuple[float, ...], ...] = ()
    rollers: tuple[float, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "casters", _points(self.casters, "casters"))
        object.__setattr__(self, "wheels", _points(self.wheels, "wheels"))
        rollers = []
        for k, value in enumerate(self.rollers):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SpecError(f"[support] rollers entry {k} must be an angle in degrees, got {value!r}")
            rollers.append(float(value))
        if rollers and len(rollers) != len(self.wheels):
            raise SpecError(
                f"[support] rollers gives {len(rollers)} angles for {len(self.wheels)} wheels: one per row of wheels"
            )
        object.__setattr__(self, "rollers", tuple(rollers))
        check_mu(self.mu, "[support] mu")
        check_faces(self.faces, "[support] faces")
        if not isinstance(self.urdf_casters, bool):
            raise SpecError(f"[support] urdf_casters must be true or false, got {self.urdf_casters!r}")
        if not isinstance(self.stiffness, Mapping):
            raise SpecError(f"[support] stiffness must be a table of contact = number, got {self.stiffness!r}")
        for name, value in self.stiffness.items():
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not (number and math.isfinite(value) and value > 0):
                raise SpecError(f"[support] stiffness of {name!r} must be a finite number > 0, got {value!r}")
        object.__setattr__(self, "stiffness", {str(k): float(v) for k, v in self.stiffness.items()})


def _points(rows: Iterable[object], key: str) -> tuple[tuple[float, ...], ...]:
    """Rows of [x, y] or [x, y, z] metres, checked."""
    out = []
    row: object
    for k, row in enumerate(rows):
        if not isinstance(row, (list, tuple)) or len(row) not in (2, 3):
            raise SpecError(f"[support] {key} row {k} must be [x, y] or [x, y, z] in metres, got {row!r}")
        values = []
        value: object
        for value in row:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SpecError(f"[support] {key} row {k} must hold finite metres, got {row!r}")
            values.append(float(value))
        out.append(tuple(values))
    return tuple(out)


def support_spec_from_table(table: object, where: str) -> SupportSpec:
    """A :class:`SupportSpec` from the spec's ``[support]`` TOML table."""
    if not isinstance(table, Mapping):
        raise SpecError(f"{where}: [support] must be a table, got {table!r}")
    known = {"casters", "mu", "faces", "urdf_casters", "stiffness", "wheels", "rollers"}
    extra = sorted(set(table) - known)
    if extra:
        raise SpecError(f"{where}: unknown keys in [support]: {extra}; expected some of {sorted(known)}")
    casters = table.get("casters", [])
    if not isinstance(casters, list):
        raise SpecError(f"{where}: [support] casters must be a list of [x, y] rows, got {casters!r}")
    wheels, rollers = table.get("wheels", []), table.get("rollers", [])
    if not isinstance(wheels, list):
        raise SpecError(f"{where}: [support] wheels must be a list of [x, y] rows, got {wheels!r}")
    if not isinstance(rollers, list):
        raise SpecError(f"{where}: [support] rollers must be a list of angles (deg), got {rollers!r}")
    return SupportSpec(
        casters=tuple(casters),
        mu=table.get("mu"),
        faces=table.get("faces", DEFAULT_FACES),
        urdf_casters=table.get("urdf_casters", True),
        stiffness=table.get("stiffness", {}),
        wheels=tuple(wheels),
        rollers=tuple(rollers),
    )


def check_mu(mu: object, what: str = "mu") -> None:
    """A friction coefficient: a finite number from 0 to :data:`MAX_MU` (or ``None``)."""
    if mu is None:
        return
    # (compared, not math.isfinite: a TOML integer of 400 digits overflows a float)
    if isinstance(mu, bool) or not isinstance(mu, (int, float)) or not -math.inf < mu < math.inf or mu < 0:
        raise SpecError(f"{what} must be a finite friction coefficient >= 0, got {mu!r}")
    if mu > MAX_MU:
        raise SpecError(
            f"{what} {mu!r} is above {MAX_MU:g}, more than any floor gives (a tyre on dry concrete: about 1); "
            "for traction without a limit, give no friction coefficient (--no-traction)"
        )


def check_reserve(reserve: object, what: str = "the floor's reserve") -> None:
    """A floor's safety reserve: a fraction in [0, 1) (the one check of every reserve: the
    floor at rest's, the floor of motion's and ``--reserve``'s)."""
    if isinstance(reserve, bool) or not isinstance(reserve, (int, float)) or not 0.0 <= reserve < 1.0:
        raise ArgumentError(f"{what} must be a fraction in [0, 1), got {reserve!r}")


def check_faces(faces: object, what: str = "faces") -> None:
    """Faces of a friction pyramid: an integer from 3 to 64."""
    if isinstance(faces, bool) or not isinstance(faces, int) or not 3 <= faces <= 64:
        raise SpecError(f"{what} must be an integer from 3 to 64, got {faces!r}")
