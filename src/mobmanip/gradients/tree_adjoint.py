"""Configuration derivatives of scalars built from Jacobians, M and g, without dJ/dq or dM/dq.

A gradient of a scalar f of the frame Jacobians J, the mass matrix M and gravity g only needs
the contractions <J_bar, dJ/dq_k>, tr(M_bar dM/dq_k) and g_bar . dg/dq_k for every tangent
direction k, where J_bar, M_bar, g_bar are f's sensitivities (reverse mode). This module
computes those contractions in closed form from world-frame quantities of one Pinocchio pass,
stacked over a chunk of configurations, in O(nv) work per contraction instead of the
O(nv^2) (or, for M, O(nv^3)) of the kinematic Hessians.

Notation, all in the world frame, spatial vectors (linear, angular): xi_i the world Jacobian
column of degree of freedom i, ad(x) y the Lie bracket (w_x x v_y + v_x x w_y, w_x x w_y).
Along tangent direction k (Pinocchio's ``integrate``, which moves joint(k)'s frame by
exp(e S_k) on the right), every column i of joint(k) or of its descendants turns:
dxi_i/dq_k = ad(xi_k) xi_i; other columns do not change. A body's world spatial inertia
turns with it: dI/dq_k = -ad(xi_k)^T I - I ad(xi_k).

- Frame Jacobians (``LOCAL_WORLD_ALIGNED`` at a point p): J_i = X_p xi_i with
  X_p = [[I, -skew(p)], [0, I]], dp/dq_k the linear part of J_k.
- Bilinear forms of M: with V^a_b = sum_(i <= b) xi_i a_i the twist of body b at velocity a and
  H^a_j = sum_(b in subtree(j)) I_b V^a_b the momentum of joint j's subtree,
  d(a^T M b)/dq_k = -(ad(xi_k) V^a_pre)^T H^b_k - (H^a_k)^T ad(xi_k) V^b_pre, where ``pre`` is
  the parent of joint(k). Gravity is the same form with b's twists replaced by the constant
  spatial acceleration A0 = -gravity (g = sum_b J_b^T I_b A0, Pinocchio's RNEA at rest).

The world joint Jacobians, the end effectors' positions and every joint frame's pose come from
one ``computeJointJacobians`` call of the robot's model with massless probe joints
(:class:`mobmanip.engine.probed.ProbedModel`), probes at the end effectors and at every joint;
M and g follow from the bodies' world inertias through their subtrees' composite inertias.
"""

from __future__ import annotations

import contextlib
import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..engine.probed import ProbedModel, frame_positions
from ..engine.stacked_linalg import cross3
from ..errors import ModelError
from ..support.compile_notice import announced_compile, numba_cached, up_to

#: Joint kinds whose configuration moves the joint frame by exp(v S) for a tangent v (what the
#: closed forms here assume); other kinds (spherical, free flyer, mimic) take the Hessian path.
SUPPORTED_JOINTS = ("RX", "RY", "RZ", "RUBX", "RUBY", "RUBZ", "PX", "PY", "PZ", "RevoluteUnaligned",
                    "RevoluteUnboundedUnaligned", "PrismaticUnaligned", "Planar")  # fmt: skip


@dataclass
class TreePass:
    """One chunk's Pinocchio outputs in the robot's degrees of freedom.

    Spatial vectors are world-aligned about the point ``reference`` (the first joint's origin),
    not the world origin; the closed forms hold about any fixed point.

    Attributes:
        xi: joint Jacobian columns about ``reference``, (n, 6, nv).
        M: mass matrices, (n, nv, nv) (with ``dynamics``).
        g: generalized gravity, (n, nv) (with ``dynamics``).
        positions: end-effector positions relative to ``reference``, (n, k, 3).
        frames: end-effector ``LOCAL_WORLD_ALIGNED`` Jacobians (support only), (n, k, 6, nv).
        rotations: joint frames' orientations, (n, nj, 3, 3); origins: their positions relative to
            ``reference``, (n, nj, 3).
        reference: the reference point in the world (m), (n, 3).
        inertia: bodies' spatial inertias about ``reference``, (n, nj, 6, 6); ``None`` until
            :meth:`TreeAdjoint.inertias` fills it.
        frame_rotations: end-effector frames' orientations, (n, k, 3, 3).
    """

    xi: np.ndarray
    M: np.ndarray | None
    g: np.ndarray | None
    positions: np.ndarray
    frames: np.ndarray
    rotations: np.ndarray
    origins: np.ndarray
    reference: np.ndarray
    inertia: np.ndarray | None = None
    frame_rotations: np.ndarray | None = None


class TreeAdjoint:
    """The contractions of one robot, constant structure computed once.

    Args:
        model: the robot's Pinocchio model.
        frame_ids: the end-effector frames, in arm order.
        compiled: use the compiled row loops (:mod:`mobmanip.gradients.tree_kernel`); default where Numba
            is available. ``False`` runs the stacked NumPy forms (the reference).

    Raises:
        ModelError: a joint kind outside :data:`SUPPORTED_JOINTS`, or a joint without its
            ``JOINT`` frame (the caller then uses the kinematic Hessians).
    """

    def __init__(self, model: pin.Model, frame_ids, compiled: bool | None = None):
        nj = model.njoints - 1
        joint_frames = []
        for j in range(1, model.njoints):
            kind = model.joints[j].shortname().removeprefix("JointModel")
            if kind not in SUPPORTED_JOINTS:
                raise ModelError(f"joint {model.names[j]!r} ({kind}) has no closed-form derivative here")
            found = [
                f for f in range(model.nframes)
                if model.frames[f].parentJoint == j and model.frames[f].type == pin.FrameType.JOINT
                and model.frames[f].placement.isIdentity()
            ]  # fmt: skip
            if not found:
                raise ModelError(f"joint {model.names[j]!r} has no JOINT frame")
            joint_frames.append(found[0])
        self.model = model
        self.nv = model.nv
        self.k = len(frame_ids)
        self.probed = ProbedModel(model, list(frame_ids) + joint_frames)
        self.gravity_acceleration = -np.asarray(model.gravity.vector, dtype=float)  # A0, (6,)
        # structure: joint of each dof (0-based over robot joints), ancestry
        self.dof_joint = np.empty(model.nv, dtype=int)
        for j in range(1, model.njoints):
            jm = model.joints[j]
            self.dof_joint[jm.idx_v : jm.idx_v + jm.nv] = j - 1
        desc = np.zeros((nj, nj))  # desc[b, j]: body b in subtree of joint j
        for j in range(1, model.njoints):
            for b in model.subtrees[j]:
                desc[b - 1, j - 1] = 1.0
        self.desc = desc
        self.anc = desc[:, self.dof_joint].T.copy()  # anc[i, b]: dof i's joint is an ancestor of (or is) b
        self.suffix = desc[self.dof_joint][:, self.dof_joint].copy()  # suffix[i, k]: dof i in subtree of joint(k)
        self.joint_parent = np.array([model.parents[j] for j in range(1, model.njoints)])  # 0 = universe
        self.upper = self.anc[:, self.dof_joint] > 0  # upper[i, k]: joint(i) is an ancestor of (or) joint(k)
        self.supports = np.zeros((self.k, model.nv))
        for a, f in enumerate(frame_ids):
            parent = model.frames[f].parentJoint
            self.supports[a] = self.anc[:, parent - 1] if parent > 0 else 0.0
        inertias = [model.inertias[j] for j in range(1, model.njoints)]
        self.mass = np.array([float(inr.mass) for inr in inertias])
        self.lever = np.array([np.asarray(inr.lever, dtype=float) for inr in inertias])
        self.rot_inertia = np.array([np.asarray(inr.inertia, dtype=float) for inr in inertias])
        self.vmap = self.probed.vmap.astype(np.int64)
        self.kernel = _kernel() if compiled is None or compiled else None
        if compiled and self.kernel is None:
            raise ModelError("the compiled tree loops need Numba")
        self.parent0 = np.array([model.parents[j] - 1 for j in range(1, model.njoints)], dtype=np.int64)
        self.dof_start = np.array([model.joints[j].idx_v for j in range(1, model.njoints)], dtype=np.int64)
        self.dof_count = np.array([model.joints[j].nv for j in range(1, model.njoints)], dtype=np.int64)
        self.armature = np.asarray(model.armature, dtype=float)
        self._buffers: tuple[np.ndarray, np.ndarray] | None = None  # the largest chunk's so far
        self._x_cols = self.probed.probe_cols[:, 0].astype(np.int64)  # probe columns, as indices
        self._y_cols = self.probed.probe_cols[:, 1].astype(np.int64)

    # ----- the Pinocchio pass -----

    def _joint_jacobians(self, qs: np.ndarray) -> np.ndarray:
        """The probed model's world joint Jacobians at qs (n, nq), (n, 6, nv_p): one
        ``computeJointJacobians`` call per configuration, into a buffer reused across calls."""
        n = qs.shape[0]
        probed = self.probed
        model, data = probed.model, probed.data
        if self._buffers is None or self._buffers[0].shape[0] < n:
            self._buffers = (np.zeros((n, model.nq)), np.empty((n, 6, model.nv)))
        qp, Ja = self._buffers[0][:n], self._buffers[1][:n]
        qp[:, probed.qmap] = qs
        jacobians = pin.computeJointJacobians
        for q, Jw in zip(qp, Ja):
            Jw[...] = jacobians(model, data, q)
        return Ja

    def run(self, qs: np.ndarray, dynamics: bool = True) -> TreePass:
        """The quantities at qs, (n, nq), from one ``computeJointJacobians`` call per configuration
        of the probed model; M and g only with ``dynamics``."""
        n = qs.shape[0]
        Ja = self._joint_jacobians(qs)
        xi = Ja[:, :, self.vmap]
        x_cols, y_cols = Ja[:, :, self._x_cols], Ja[:, :, self._y_cols]
        points = frame_positions(x_cols, y_cols)  # (n, k + nj, 3)
        ex, ey = np.swapaxes(x_cols[:, 3:], 1, 2), np.swapaxes(y_cols[:, 3:], 1, 2)  # (n, k + nj, 3)
        all_rotations = np.stack([ex, ey, cross3(ex, ey)], axis=-1)  # (n, k + nj, 3, 3) columns
        rotations = all_rotations[:, self.k :]
        # spatial vectors about the first joint's origin (world-aligned): M's terms m |c|^2 then
        # stay of the robot's size wherever it stands, which keeps round-off off the values
        reference = points[:, self.k].copy()
        points -= reference[:, None, :]
        w = xi[:, 3:]
        xi[:, :3] += _cross(w, reference[:, :, None])
        positions = points[:, : self.k]
        # every frame at once, (n, k, 6, nv): (v + w x p, w) on the columns that move it
        frames = np.empty((n, self.k, 6, self.nv))
        frames[:, :, :3] = xi[:, None, :3] + _cross_frames(w, positions)
        frames[:, :, 3:] = w[:, None]
        frames *= self.supports[:, None, :]
        t = TreePass(xi, None, None, positions, frames, rotations, points[:, self.k :], reference)
        t.frame_rotations = all_rotations[:, : self.k]
        if dynamics:
            self._mass_and_gravity(t)
        return t

    def run_kinematic(self, qs: np.ndarray) -> TreePass:
        """:meth:`run` without dynamics, through the compiled row loop
        (:func:`mobmanip.gradients.tree_kernel.tree_frames`; needs :attr:`kernel`). The same
        quantities to round-off (tests/test_gradient_kernel.py)."""
        assert self.kernel is not None
        n = qs.shape[0]
        Ja = self._joint_jacobians(qs)
        nf, k, nv = len(self._x_cols), self.k, self.nv
        xi, points = np.empty((n, 6, nv)), np.empty((n, nf, 3))
        rotations, reference, frames = np.empty((n, nf, 3, 3)), np.empty((n, 3)), np.empty((n, k, 6, nv))
        self.kernel.tree_frames(Ja, self.vmap, self._x_cols, self._y_cols, k, self.supports, xi, points, rotations,
                                reference, frames)  # fmt: skip
        t = TreePass(xi, None, None, points[:, :k], frames, rotations[:, k:], points[:, k:], reference)
        t.frame_rotations = rotations[:, :k]
        return t

    def _mass_and_gravity(self, t: TreePass) -> None:
        """M and g from the bodies' world inertias: with Ic_j the composite inertia of joint j's
        subtree, M_ik = xi_i^T Ic_joint(k) xi_k for joint(i) an ancestor of (or) joint(k), and
        g_k = xi_k^T Ic_joint(k) A0 (CRBA and RNEA at rest in the world frame)."""
        I = self.inertias(t)
        n, nj = I.shape[:2]
        if self.kernel is not None:
            t.M, t.g = np.empty((n, self.nv, self.nv)), np.empty((n, self.nv))
            with _first_call("mass_and_gravity"):
                self.kernel.mass_and_gravity(
                    t.xi,
                    I,
                    self.parent0,
                    self.dof_start,
                    self.dof_count,
                    self.gravity_acceleration,
                    self.armature,
                    t.M,
                    t.g,
                )
            return
        # every product here is one matrix per configuration, as a stack: one product over the
        # stacked rows lets BLAS sum a row in an order that depends on the chunk's size, and a
        # batched placement would then differ from its starts run alone (tests/test_lockstep.py)
        Ic = I.reshape(n, nj, 36).transpose(0, 2, 1) @ self.desc  # (n, 36, nj)
        Ic = Ic[..., self.dof_joint].reshape(n, 6, 6, self.nv)  # (n, 6, 6, nv): Ic of each dof's joint
        F = np.einsum("nxyk,nyk->nxk", Ic, t.xi)  # (n, 6, nv)
        X = np.swapaxes(t.xi, 1, 2) @ F  # X[i, k] = xi_i . Ic_joint(k) xi_k
        M = np.where(self.upper, X, np.swapaxes(X, 1, 2) * self.upper.T)
        M[:, np.arange(self.nv), np.arange(self.nv)] += self.model.armature
        t.M = M
        t.g = np.einsum("nxyk,y,nxk->nk", Ic, self.gravity_acceleration, t.xi)

    def inertias(self, t: TreePass) -> np.ndarray:
        """The bodies' spatial inertias about ``t.reference`` (world-aligned), (n, nj, 6, 6)."""
        if t.inertia is None and self.kernel is not None:
            t.inertia = np.empty(t.rotations.shape[:2] + (6, 6))
            with _first_call("world_inertias"):
                self.kernel.world_inertias(t.rotations, t.origins, self.mass, self.lever, self.rot_inertia, t.inertia)
        if t.inertia is None:
            R, o = t.rotations, t.origins
            c = o + np.einsum("njab,jb->nja", R, self.lever)  # centres of mass
            Ic = R @ self.rot_inertia @ np.swapaxes(R, -1, -2)
            m = self.mass[None, :, None, None]
            S = skew(c)
            out = np.empty(R.shape[:2] + (6, 6))
            out[..., :3, :3] = m * np.eye(3)
            out[..., :3, 3:] = -m * S
            out[..., 3:, :3] = m * S
            out[..., 3:, 3:] = Ic - m * (S @ S)
            t.inertia = out
        return t.inertia

    # ----- contractions -----

    def frame_term(self, t: TreePass, J_bar: np.ndarray, p_bar: np.ndarray | None = None) -> np.ndarray:
        """sum over frames of <J_bar, dJ/dq_k> + p_bar . dp/dq_k, (n, nv).

        Args:
            t: the chunk's pass.
            J_bar: sensitivities of the frames' ``LOCAL_WORLD_ALIGNED`` Jacobians, (n, k, 6, nv).
            p_bar: sensitivities of the frames' positions, (n, k, 3), or ``None``.
        """
        xi = t.xi
        n, k, nv = xi.shape[0], self.k, self.nv
        v, w = xi[:, None, :3], xi[:, None, 3:]  # (n, 1, 3, nv): every frame at once below
        Jb = J_bar * self.supports[:, None, :]  # (n, k, 6, nv)
        bl = Jb[:, :, :3]
        ba = Jb[:, :, 3:] + _cross_frames_left(t.positions, bl)  # beta = X_p^T J_bar
        w_bl = _cross_frames_both(w, bl)
        gamma = np.empty((n, k, 6, nv))
        gamma[:, :, :3] = w_bl
        gamma[:, :, 3:] = _cross_frames_both(v, bl) + _cross_frames_both(w, ba)
        G = (gamma.reshape(n, k * 6, nv) @ self.suffix).reshape(n, k, 6, nv)
        rho = -w_bl.sum(axis=3)  # (n, k, 3)
        if p_bar is not None:
            rho = rho + p_bar
        turn = np.einsum("nxj,naxj->naj", xi, G) * self.supports  # (n, k, nv)
        move = np.einsum("nax,naxj->naj", rho, t.frames[:, :, :3])
        out = np.zeros((n, nv))
        for a in range(k):  # the frames' terms summed in frame order
            out += turn[:, a]
            out += move[:, a]
        return out

    def bilinear_term(self, t: TreePass, a: np.ndarray, b: np.ndarray, g_bar: np.ndarray | None = None) -> np.ndarray:
        """sum_r d(a_r^T M b_r)/dq_k + d(g_bar . g)/dq_k, (n, nv).

        Args:
            t: the chunk's pass.
            a, b: the pairs, (n, R, nv).
            g_bar: sensitivity of generalized gravity, (n, nv), or ``None``.
        """
        n, R = a.shape[:2]
        if n == 0:
            return np.zeros((0, self.nv))
        I = self.inertias(t)
        xi = t.xi
        nv, nj = self.nv, self.desc.shape[0]
        offset = np.zeros((6, 2 * R))
        if g_bar is not None:  # gravity: the pair (g_bar, 0) with b's twists the constant A0
            a = np.concatenate([a, g_bar[:, None]], axis=1)
            b = np.concatenate([b, np.zeros_like(g_bar)[:, None]], axis=1)
            R += 1
            offset = np.zeros((6, 2 * R))
            offset[:, -1] = self.gravity_acceleration
        coef = np.concatenate([a, b], axis=1)  # (n, 2R, nv): a's then b's
        if self.kernel is not None:
            out = np.empty((n, nv))
            with _first_call("bilinear_rows"):
                self.kernel.bilinear_rows(xi, coef, offset, I, self.parent0, self.dof_start, self.dof_count, R, out)
            return out
        # twists of every joint's body (n, 6, 2R, nj): V_j = offset + sum_(i <= j) xi_i c_i
        V = ((xi[:, :, None, :] * coef[:, None, :, :]).reshape(n, -1, nv) @ self.anc).reshape(n, 6, 2 * R, nj)
        V += offset[None, :, :, None]
        h = I @ V.transpose(0, 3, 1, 2)  # (n, nj, 6, 2R) momenta of the bodies
        H = (h.transpose(0, 2, 3, 1).reshape(n, -1, nj) @ self.desc).reshape(n, 6, 2 * R, nj)  # of the subtrees
        pre = np.concatenate([np.broadcast_to(offset[None, :, :, None], (n, 6, 2 * R, 1)), V], axis=3)
        pre = pre[..., self.joint_parent]  # twists of each joint's parent, (n, 6, 2R, nj)
        swap = np.r_[R : 2 * R, 0:R]  # pair each a with its b: gamma(V^a_pre, H^b) + gamma(V^b_pre, H^a)
        gam = _gamma_sum(pre, H[:, :, swap])[..., self.dof_joint]  # (n, 6, nv)
        return -np.einsum("nxk,nxk->nk", xi, gam)


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u x v for 3-vectors on axis 1 (any trailing axes)."""
    c0 = u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1]
    out = np.empty(c0.shape[:1] + (3,) + c0.shape[1:])
    out[:, 0] = c0
    out[:, 1] = u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2]
    out[:, 2] = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    return out


def _cross_frames(w: np.ndarray, p: np.ndarray) -> np.ndarray:
    """w x p_a for every frame a: w (n, 3, nv), p (n, k, 3) -> (n, k, 3, nv), each frame's the
    products and differences of ``_cross(w, p[:, a, :, None])`` (equal bit for bit)."""
    w0, w1, w2 = w[:, None, 0], w[:, None, 1], w[:, None, 2]  # (n, 1, nv)
    p0, p1, p2 = p[:, :, 0, None], p[:, :, 1, None], p[:, :, 2, None]  # (n, k, 1)
    out = np.empty(p.shape[:2] + (3,) + w.shape[2:])
    out[:, :, 0] = w1 * p2 - w2 * p1
    out[:, :, 1] = w2 * p0 - w0 * p2
    out[:, :, 2] = w0 * p1 - w1 * p0
    return out


def _cross_frames_left(p: np.ndarray, b: np.ndarray) -> np.ndarray:
    """p_a x b_a for every frame a: p (n, k, 3), b (n, k, 3, nv) -> (n, k, 3, nv), each frame's
    as ``_cross(p[:, a, :, None], b[:, a])`` (equal bit for bit)."""
    p0, p1, p2 = p[:, :, 0, None], p[:, :, 1, None], p[:, :, 2, None]  # (n, k, 1)
    b0, b1, b2 = b[:, :, 0], b[:, :, 1], b[:, :, 2]
    out = np.empty(b.shape)
    out[:, :, 0] = p1 * b2 - p2 * b1
    out[:, :, 1] = p2 * b0 - p0 * b2
    out[:, :, 2] = p0 * b1 - p1 * b0
    return out


def _cross_frames_both(u: np.ndarray, b: np.ndarray) -> np.ndarray:
    """u x b over axis 2 of (n, k or 1, 3, nv) stacks (broadcast over frames), as ``_cross``."""
    u0, u1, u2 = u[:, :, 0], u[:, :, 1], u[:, :, 2]
    b0, b1, b2 = b[:, :, 0], b[:, :, 1], b[:, :, 2]
    out = np.empty(np.broadcast_shapes(u.shape, b.shape))
    out[:, :, 0] = u1 * b2 - u2 * b1
    out[:, :, 1] = u2 * b0 - u0 * b2
    out[:, :, 2] = u0 * b1 - u1 * b0
    return out


#: The most a compile of each compiled loop may take (s), printed when a first call compiles it.
_COMPILE_SECONDS = {
    name: up_to(name) for name in ("world_inertias", "mass_and_gravity", "bilinear_rows", "kinematic chain")
}
#: Loops compiled together, under one name: the kinematic measures' chain.
_GROUPS = {"kinematic chain": ("tree_frames", "kinematic_shape", "kinematic_shape_adjoint", "frame_term")}
#: The loops already called in this process (no compile, no announcement).
_CALLED: set[str] = set()


def _first_call(name: str):
    """A context for a call of the tree kernel's loop ``name``: the first in a process announces
    a compile on standard error when Numba's disk cache does not hold the loop."""
    if name in _CALLED:
        return contextlib.nullcontext()
    _CALLED.add(name)
    kernel = _kernel()
    loops = [getattr(kernel, loop) for loop in _GROUPS.get(name, (name,))]
    what = f"the gradient tree kernel's {name} loops" if name in _GROUPS else f"the gradient tree kernel's {name} loop"
    return announced_compile(what, _COMPILE_SECONDS[name], loops)


def loops_cached(name: str) -> bool | None:
    """Whether Numba's disk cache holds the tree kernel's loop (or group of loops) ``name`` (a key
    of its compile times): ``None`` where it cannot tell or Numba is missing."""
    kernel = _kernel()
    if kernel is None:
        return None
    return numba_cached([getattr(kernel, loop) for loop in _GROUPS.get(name, (name,))])


#: The loops (or groups of loops) of the tree kernel, each compiled on its first call.
LOOPS = tuple(_COMPILE_SECONDS)


@functools.cache
def _kernel():
    """The compiled row loops' module, or ``None`` where Numba is missing or unusable."""
    try:
        from . import tree_kernel
    except ImportError:
        return None
    return tree_kernel


def _gamma_sum(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """sum_r gamma(y_r, x_r) for spatial vectors on axis 1 and pairs r on axis 2, through the
    pairs' summed outer products O = sum_r y_r x_r^T (u x v = the axial vector of u v^T - v u^T)."""
    O = np.einsum("nbrj,ncrj->nbcj", y, x)

    def axial(B):  # sum_r u_r x v_r from B = sum_r u_r v_r^T
        return np.stack([B[:, 1, 2] - B[:, 2, 1], B[:, 2, 0] - B[:, 0, 2], B[:, 0, 1] - B[:, 1, 0]], axis=1)

    return np.concatenate([axial(O[:, 3:, :3]), axial(O[:, :3, :3]) + axial(O[:, 3:, 3:])], axis=1)


def skew(r: np.ndarray) -> np.ndarray:
    out = np.zeros(r.shape + (3,))
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    out[..., 0, 1], out[..., 0, 2] = -z, y
    out[..., 1, 0], out[..., 1, 2] = z, -x
    out[..., 2, 0], out[..., 2, 1] = -y, x
    return out
