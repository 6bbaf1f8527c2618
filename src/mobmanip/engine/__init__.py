"""The batch engine: the unified ellipsoids of many configurations, fast, equal to the reference.

:func:`analyze_batch` gives the same ellipsoids as :func:`mobmanip.analysis.analyze` (to 1e-10
of each ellipsoid's size) for every row of a configuration array, several times faster per
configuration than the single path; :func:`evaluate_one` is the same engine on one
configuration, the fast path ``analyze`` takes. The readable reference implementation
(:mod:`mobmanip.terms.dynamics`, :mod:`mobmanip.terms.grasp`, :mod:`mobmanip.sets.ellipsoid`) stays the oracle
every path here is tested against.

Pinocchio is called once per configuration, for one CRBA of the robot's model with massless
probe joints added (:class:`~mobmanip.engine.probed.ProbedModel`), which gives the joint
Jacobians, M, generalized gravity and the end-effector positions at once; everything else runs
per row in a compiled kernel or stacked over a chunk in NumPy, with constant things (S, Q, W
and its pseudo-inverses for grasps that do not move, the object's inertia and gravity, the
limits) computed once per batch in :class:`~mobmanip.engine.setup.BatchSetup`.

Two algorithms compute the ellipsoids:

* the *fast path*, for every row it can certify, uses the closed forms that hold when the
  unified Jacobian J has full row rank (the branch the single path takes too). Kinematic: with
  G_k = J_hat J_hat^T, T = (W^T)^+ and C a basis of null(W), the generator Z J_hat with
  Z = T - Y^T C^T, Y = (C^T G_k C)^-1 C^T G_k T^T, spans the ellipsoid (its Gram is the Schur
  complement that keeps the joint motions a rigid object can follow, stationary in Y). Dynamic:
  J^+ W^T = J^T (J J^T)^-1 W^T by Cholesky with one refinement step, L = Z Lambda_o, semi-axes
  from the eigenvectors of L^T L with Rayleigh quotients ||L v||^2, the centre -L^+ mu_bar with
  one least-squares refinement step. Each row carries an a-priori error bound from the
  condition numbers involved; a row is certified where the bound is at most
  :data:`mobmanip.support.tolerances.FAST_PATH_TOLERANCE` (all thresholds shared by the paths live in
  :mod:`mobmanip.support.tolerances`).
* the *SVD path* mirrors :mod:`mobmanip.sets.ellipsoid` branch by branch with stacked SVDs and
  pseudo-inverses. It takes every row the fast path cannot certify: rank-deficient or
  ill-conditioned Jacobians (degenerate ellipsoids), dynamic ellipsoids at the edge of
  emptiness, and rows whose error bound exceeds the threshold.

The split shows in the results only through :attr:`BatchAnalysis.svd_path`.

The fast path exists twice: compiled row by row with Numba (:mod:`.kernel`, the default) and
stacked over a chunk in NumPy (:mod:`.numpy_path`, ``method="numpy"``). The NumPy version earns
its lines as *the* fast path where Numba is not installed (Numba is an optional dependency,
``pip install mobmanip[fast]``, and often lags new Python releases): there it is 2 to 3 times
faster than the SVD path alone (per configuration, single-threaded: 11 against 22 us for the
paper's robot, 29 against 78 us for TIAGo++ in the spatial task), and it is an independent
implementation of the same certificates that the kernel is tested against. Both routes are tested, the one without Numba
in a process where Numba cannot be imported.

Modules, one concept each:

============================  ===============================================================
:mod:`.results`               :class:`EllipsoidBatch`, :class:`BatchAnalysis`
:mod:`.setup`                 :class:`BatchSetup`: everything constant over a batch, and the
                              one place that reads S
:mod:`.probed`                the probed model, the Pinocchio pass and its workspace
:mod:`.terms`                 a chunk's J_u, P, xi and grasp, stacked in NumPy
:mod:`.numpy_path`            the fast path stacked in NumPy
:mod:`.stacked_linalg`        small linear algebra over stacks of matrices
:mod:`.svd_path`              the SVD path and its backlog over chunks
:mod:`.kernel`                the compiled kernel (Numba)
:mod:`.compiled`              loading and calling the kernel, and when to compile it
:mod:`.pipeline`              :func:`analyze_batch`, :func:`iter_terms`,
                              :func:`ellipsoids_from_terms`
:mod:`.one_row`               :func:`evaluate_one`
============================  ===============================================================
"""

from .compiled import KernelOutcome, kernel_available, kernel_cached, kernel_ready
from .one_row import OneRow, evaluate_one
from .pipeline import (
    DEFAULT_CHUNK,
    KERNEL_CHUNK,
    METHODS,
    analyze_batch,
    check_configurations,
    default_chunk,
    ellipsoids_from_terms,
    iter_terms,
    warm_kernel,
)
from .probed import ProbedModel, Workspace, pinocchio_pass
from .results import BatchAnalysis, EllipsoidBatch
from .setup import BatchSetup
from .svd_path import SvdBacklog
from .terms import ChunkTerms

__all__ = [
    "DEFAULT_CHUNK",
    "KERNEL_CHUNK",
    "METHODS",
    "BatchAnalysis",
    "BatchSetup",
    "ChunkTerms",
    "EllipsoidBatch",
    "KernelOutcome",
    "OneRow",
    "ProbedModel",
    "SvdBacklog",
    "Workspace",
    "analyze_batch",
    "check_configurations",
    "default_chunk",
    "ellipsoids_from_terms",
    "evaluate_one",
    "iter_terms",
    "kernel_available",
    "kernel_cached",
    "kernel_ready",
    "pinocchio_pass",
    "warm_kernel",
]
