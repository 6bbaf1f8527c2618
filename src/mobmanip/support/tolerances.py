"""The tolerances that tie the reference, NumPy and compiled paths together, in one place.

The reference path (:mod:`mobmanip.sets.ellipsoid`), the stacked NumPy fast path, the stacked SVD
path and the compiled kernel of :mod:`mobmanip.engine` must take the same branches and accept
the same rows, so every threshold they share lives here and each of them reads it from here.
All values are dimensionless ratios.

The compiled kernel receives them as an argument of each call (see
:func:`kernel_tolerances`) rather than as module globals: Numba freezes globals into its
on-disk cache, which a change here would not invalidate.
"""

from __future__ import annotations

import numpy as np

#: Machine epsilon of float64 (not a choice; here so that every error bound uses one name).
EPS = float(np.finfo(float).eps)

#: Rank tolerance: singular values at or below this fraction of the largest count as zero
#: (null spaces, pseudo-inverses, the rank of J_u, zero semi-axes). Used by the reference path
#: and its stacked mirror, the SVD path.
RANK_RTOL = 1e-10

#: The reference path takes its full-rank closed forms (J of full row rank, L of full column
#: rank) while the smallest singular value exceeds this fraction of the largest; below it, the
#: general (null-space) branch. The SVD path mirrors this branch for branch.
FAST_RTOL = 1e-8

#: Largest condition number (of J_hat, of L, of the kinematic generator) the fast paths accept:
#: 1e-2 / FAST_RTOL, i.e. the reference path's full-rank branch with a margin of 100, so that a
#: certified row is one where the reference path takes the same branch.
CONDITION_LIMIT = 1e-2 / FAST_RTOL

#: Largest condition number of a Gram matrix (J J^T, C^T G_k C, G G^T) the fast paths accept:
#: Gram matrices square the condition number.
GRAM_CONDITION_LIMIT = CONDITION_LIMIT**2

#: Largest estimated fast-path error, relative to the ellipsoid's size, before a row is sent to
#: the SVD path (the *certificate threshold*). The estimate is a first-order worst-case bound
#: from the condition numbers involved (pessimistic by 10^2 .. 10^4). Over 20,000 random
#: configurations per case (TIAGo++ and the paper's robot, several tasks, moving and locked
#: platform, light and heavy objects), the rows accepted at this setting differed from the SVD
#: path by at most 1e-11 of the ellipsoid's size, with identical flags; ``analyze`` promises
#: 1e-9 and ``analyze_batch`` 1e-10 against the reference path.
FAST_PATH_TOLERANCE = 1e-9

#: Anisotropy (largest over smallest semi-axis) up to which the compiled kernel first solves
#: J^+ W^T without a refinement step: its error bound 8 eps kappa(J J^T) anisotropy then passes
#: :data:`FAST_PATH_TOLERANCE` for kappa(J J^T) up to :data:`PLAIN_SOLVE_CONDITION_LIMIT`.
#: Rows the certificate then refuses are computed again, refined. Changes speed, not results.
PLAIN_SOLVE_ANISOTROPY = 100.0

#: kappa(J J^T) up to which the kernel tries the unrefined J^+ W^T first (see above).
PLAIN_SOLVE_CONDITION_LIMIT = FAST_PATH_TOLERANCE / (8.0 * EPS * PLAIN_SOLVE_ANISOTROPY)


def kernel_tolerances() -> tuple[float, float, float, float]:
    """The thresholds the compiled kernel needs, read now from this module.

    Returns:
        (FAST_PATH_TOLERANCE, CONDITION_LIMIT, GRAM_CONDITION_LIMIT, PLAIN_SOLVE_CONDITION_LIMIT).
    """
    return (
        float(FAST_PATH_TOLERANCE),
        float(CONDITION_LIMIT),
        float(GRAM_CONDITION_LIMIT),
        float(FAST_PATH_TOLERANCE / (8.0 * EPS * PLAIN_SOLVE_ANISOTROPY)),
    )
