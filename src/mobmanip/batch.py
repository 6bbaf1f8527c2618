"""Analyse many configurations at once: the public face of :mod:`mobmanip.engine`.

:func:`analyze_batch` gives the same ellipsoids as :func:`mobmanip.analysis.analyze` (to 1e-10
of each ellipsoid's size) for every row of an (N, nq) configuration array; the sweep machinery
uses the lower-level :class:`BatchSetup`, :func:`iter_terms` and :func:`ellipsoids_from_terms`.
How the engine works, and where each part lives, is described in :mod:`mobmanip.engine`.

Its names are the engine's (listed once, in ``mobmanip.engine.__all__``) and the fast paths'
tolerance.
"""

from __future__ import annotations

from .engine import *  # noqa: F403 - the engine's public names
from .engine import __all__ as _ENGINE_NAMES
from .support.tolerances import FAST_PATH_TOLERANCE

__all__ = [*_ENGINE_NAMES, "FAST_PATH_TOLERANCE"]
