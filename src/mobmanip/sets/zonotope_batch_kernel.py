"""3-D capacity zonotopes of many configurations in one compiled pass (the sweeps' hot path).

Row r is the zonotope c_r + G_r [-1, 1]^n in R^3 (an exact dynamic polytope, or a one-hand
kinematic one). For each row, as :class:`mobmanip.sets.polytope.Polytope` does one at a time:
its faces from the compiled face kernel of :mod:`mobmanip.sets.zonotope_kernel` (the very routine
the reference calls), then the volume 8 sum over generator triples of ``|det(g_i, g_j, g_k)|``
(:func:`mobmanip.sets.zonotope.volume`), the inradius (the smallest facet width) and the
circumradius (the farthest vertex from c). A row is declined (status 1; the caller computes it
one at a time) when its generators nearly lose rank (the planar kernel's test) or the face kernel declines it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..support.compile_notice import first_call_notice, numba_cached, up_to
from . import polygon_kernel, zonotope_kernel

try:  # pragma: no cover - exercised when Numba is installed (the default)
    from numba import njit
except ImportError:  # pragma: no cover
    njit = None  # type: ignore[assignment]

_OK, _DECLINED = 0, 1


def _faces(center, G):  # pragma: no cover - replaced by the face kernel's compiled 3-D routine
    raise NotImplementedError


_full_rank = polygon_kernel._clearly_full_rank


def _zonotope_rows(c, G, cap, status, facets, nf, volume, inr, circ):  # pragma: no cover - compiled
    count, _, n = G.shape
    Gr = np.empty((3, n))
    work = np.empty((3, n))
    centre = np.empty(3)
    for r in range(count):
        status[r] = _DECLINED
        nf[r] = 0
        for i in range(3):
            centre[i] = c[r, i]
            for j in range(n):
                Gr[i, j] = G[r, i, j]
        if n < 3:
            continue
        if not _full_rank(Gr, work):  # as the planar kernel: flat rows stay on the reference path
            continue
        result = _faces(centre, Gr)
        if result[0] != 0:
            continue
        V, normals, offsets, widths = result[2], result[4], result[5], result[6]
        if normals.shape[0] > cap:
            continue
        far = 0.0
        for v in range(V.shape[0]):
            d0, d1, d2 = V[v, 0] - centre[0], V[v, 1] - centre[1], V[v, 2] - centre[2]
            far = max(far, math.sqrt(d0 * d0 + d1 * d1 + d2 * d2))
        least = np.inf
        for f in range(normals.shape[0]):
            least = min(least, widths[f])
            for i in range(3):
                facets[r, f, i] = normals[f, i]
            facets[r, f, 3] = offsets[f] + widths[f]
        total = 0.0
        for i in range(n):
            for j in range(i + 1, n):
                x = Gr[1, i] * Gr[2, j] - Gr[2, i] * Gr[1, j]
                y = Gr[2, i] * Gr[0, j] - Gr[0, i] * Gr[2, j]
                z = Gr[0, i] * Gr[1, j] - Gr[1, i] * Gr[0, j]
                for k in range(j + 1, n):
                    total += abs(x * Gr[0, k] + y * Gr[1, k] + z * Gr[2, k])
        volume[r] = 8.0 * total
        inr[r] = max(least, 0.0)
        circ[r] = far
        nf[r] = normals.shape[0]
        status[r] = _OK


_compiled: dict[str, Any] = {}
_CALLED: set[str] = set()
#: The most a compile may take (s; the face kernel's 3-D routine included), printed.
_COMPILE_SECONDS = up_to("3-D sweep")


def _compile():
    """Compile on first use (cached on disk by Numba between runs)."""
    global _faces, _full_rank
    if not zonotope_kernel._compiled:
        zonotope_kernel._compile()
    jit = njit(cache=True, nogil=True)
    _faces, _full_rank = zonotope_kernel._compiled[3], jit(polygon_kernel._clearly_full_rank)
    _compiled["rows"] = jit(_zonotope_rows)


def _kernels() -> list:
    """The compiled functions (compiled first if need be): what the disk cache must hold."""
    if not _compiled:
        _compile()
    return [_compiled["rows"], _faces, _full_rank]


#: Whether the compiled kernel can run: as for the planar kernel, Numba is installed.
available = polygon_kernel.available


def kernel_cached() -> bool | None:
    """Whether Numba's disk cache holds the kernel: ``None`` where it cannot tell or Numba is missing."""
    return None if njit is None else numba_cached(_kernels())


def zonotopes(c: np.ndarray, G: np.ndarray) -> dict:
    """The indices of every 3-D zonotope row, compiled.

    Args:
        c: centres (N, 3).
        G: generators (N, 3, n), finite.

    Returns:
        ``status`` (N,) (0: computed; 1: declined), ``facets`` (N, f, 4) rows (a, b) with unit
        a and the facet a . x <= b, ``facet_count`` (N,), ``volume``, ``inradius`` and
        ``circumradius`` (N,).
    """
    if not _compiled:
        _compile()
    N, _, n = G.shape
    cap = max(2 * n * (n - 1) // 2, 1)  # every pair of generators, both sides
    out = {"status": np.ones(N, dtype=np.int64), **polygon_kernel.facet_outputs(N, cap, 4, "volume")}
    with first_call_notice(_CALLED, "rows", "the 3-D zonotope sweep kernel", _COMPILE_SECONDS, _kernels):
        _compiled["rows"](
            np.ascontiguousarray(c, dtype=float),
            np.ascontiguousarray(G, dtype=float),
            cap,
            *out.values(),
        )
    return out
