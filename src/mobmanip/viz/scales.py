"""Scale factors of the viewer: metres of scene per unit of each drawn quantity."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from ..analysis.single import Analysis
from ..errors import MobmanipError
from ..measures import Quantity, get_measure, measure_names, resolve_measures
from .server import ViewerError
from .shapes import DRAWINGS

DEFAULT_SIZE = 0.5  # m: the largest drawn extent of each quantity's sets


@dataclass(frozen=True)
class ScaleFactors:
    """How long 1 unit of each quantity is drawn (metres of scene per m/s, per m/s^2, ...).

    Index it by a quantity, its name (``"velocity"``), its label (``"kinematic"``) or the name of
    a measure of it (``scales["kinematic"]``); labels also work as attributes
    (``scales.kinematic``, ``scales.dynamic``).

    Attributes:
        values: metres of scene per unit, by quantity.
    """

    values: Mapping[Quantity, float]

    def _quantity(self, key) -> Quantity:
        if isinstance(key, Quantity):
            return key
        for quantity in self.values:
            if key in (quantity.name, quantity.label):
                return quantity
        return get_measure(key).quantity

    def __getitem__(self, key) -> float:
        quantity = self._quantity(key)
        try:
            return self.values[quantity]
        except KeyError:
            raise ViewerError(f"no scale for {quantity.name} ({key!r}); scales: {self.describe()}") from None

    def __getattr__(self, name: str) -> float:
        if name.startswith("_") or name == "values":
            raise AttributeError(name)
        try:
            return self[name]
        except MobmanipError:
            raise AttributeError(name) from None

    @classmethod
    def fit(
        cls, analyses: Sequence[Analysis | None], size: float = DEFAULT_SIZE, measures: Iterable[str] | None = None
    ) -> ScaleFactors:
        """Scales that draw the largest extent (``|centre|`` + largest semi-axis for an ellipsoid) of
        each quantity's drawable sets, over all given analyses, ``size`` metres long (1 when
        everything is zero or empty). Quantities: those of ``measures`` (default: the default
        measures) and of every measure the analyses hold, in the registry's order."""
        present = {name for a in analyses if a is not None for name in a.measures}
        present.update(m.name for m in resolve_measures(measures))
        values: dict[Quantity, float] = {}
        for name in measure_names():
            quantity = get_measure(name).quantity
            if name not in present or quantity in values:
                continue
            extent = max(
                (
                    DRAWINGS[s.kind].extent(s, a.task)
                    for a in analyses
                    if a is not None
                    for key, s in a.measures.items()
                    if get_measure(key).quantity == quantity and s.kind in DRAWINGS
                ),
                default=0.0,
            )
            values[quantity] = size / extent if extent > 0.0 else 1.0
        return cls(values)

    def including(self, other: ScaleFactors) -> ScaleFactors:
        """These scales, and those of ``other`` for the quantities these do not have."""
        return ScaleFactors({**other.values, **self.values})

    def describe(self) -> str:
        """E.g. ``kinematic: 1 m/s = 0.0974 m; dynamic: 1 m/s^2 = 0.0190 m``."""
        return "; ".join(f"{q.label}: 1 {q.unit} = {v:.4g} m" for q, v in self.values.items())
