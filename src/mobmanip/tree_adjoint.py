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

The world joint Jacobians, M, g, the end effectors' positions and every joint frame's pose come
from one CRBA call of the robot's model with massless probe joints
(:class:`mobmanip.engine.probed.ProbedModel`), probes at the end effectors and at every joint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .engine.probed import ProbedModel, frame_positions
from .errors import ModelError

#: Joint kinds whose configuration moves the joint frame by exp(v S) for a tangent v (what the
#: closed forms here assume); other kinds (spherical, free flyer, mimic) take the Hessian path.
SUPPORTED_JOINTS = ("RX", "RY", "RZ", "RUBX", "RUBY", "RUBZ", "PX", "PY", "PZ", "RevoluteUnaligned",
                    "RevoluteUnboundedUnaligned", "PrismaticUnaligned", "Planar")  # fmt: skip


@dataclass
class TreePass:
    """One chunk's Pinocchio outputs in the robot's degrees of freedom.

    Attributes:
        xi: world joint Jacobian columns, (n, 6, nv).
        M: mass matrices, (n, nv, nv).
        g: generalized gravity, (n, nv).
        positions: end-effector positions, (n, k, 3).
        frames: end-effector ``LOCAL_WORLD_ALIGNED`` Jacobians (support only), (n, k, 6, nv).
        inertia: joints' body spatial inertias in the world frame at its origin, (n, nj, 6, 6);
            ``None`` until :meth:`TreeAdjoint.inertias` fills it.
    """

    xi: np.ndarray
    M: np.ndarray
    g: np.ndarray
    positions: np.ndarray
    frames: np.ndarray
    rotations: np.ndarray
    origins: np.ndarray
    inertia: np.ndarray | None = None


class TreeAdjoint:
    """The contractions of one robot, constant structure computed once.

    Args:
        model: the robot's Pinocchio model.
        frame_ids: the end-effector frames, in arm order.

    Raises:
        ModelError: a joint kind outside :data:`SUPPORTED_JOINTS`, or a joint without its
            ``JOINT`` frame (the caller then uses the kinematic Hessians).
    """

    def __init__(self, model: pin.Model, frame_ids):
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
        self.pre = np.array(
            [model.parents[int(j) + 1] for j in self.dof_joint]
        )  # 0 = universe, else joint index (1-based)
        self.supports = np.zeros((self.k, model.nv))
        for a, f in enumerate(frame_ids):
            parent = model.frames[f].parentJoint
            self.supports[a] = self.anc[:, parent - 1] if parent > 0 else 0.0
        inertias = [model.inertias[j] for j in range(1, model.njoints)]
        self.mass = np.array([float(inr.mass) for inr in inertias])
        self.lever = np.array([np.asarray(inr.lever, dtype=float) for inr in inertias])
        self.rot_inertia = np.array([np.asarray(inr.inertia, dtype=float) for inr in inertias])
        self.vmap = self.probed.vmap.astype(int)
        self._buffers: dict[int, tuple] = {}

    # ----- the Pinocchio pass -----

    def run(self, qs: np.ndarray) -> TreePass:
        """One CRBA call per configuration of qs, (n, nq), and the quantities read from it."""
        n = qs.shape[0]
        probed = self.probed
        model, data = probed.model, probed.data
        if n not in self._buffers:
            self._buffers[n] = (np.zeros((n, model.nq)), np.empty((n, model.nv, model.nv)), np.empty((n, 6, model.nv)))
        qp, Ma, Ja = self._buffers[n]
        qp[:, probed.qmap] = qs
        crba, J, world = pin.crba, data.J, pin.Convention.WORLD
        for q, M, Jw in zip(qp, Ma, Ja):
            M[...] = crba(model, data, q, world)
            Jw[...] = J
        v = self.vmap
        xi = Ja[:, :, v]
        Mr = Ma[:, v[:, None], v]
        Mr = np.triu(Mr) + np.swapaxes(np.triu(Mr, 1), 1, 2)  # CRBA fills the upper triangle
        g = probed.gravity * Ma[:, 0, v]
        cols = probed.probe_cols.astype(int)
        x_cols, y_cols = Ja[:, :, cols[:, 0]], Ja[:, :, cols[:, 1]]
        points = frame_positions(x_cols, y_cols)  # (n, k + nj, 3)
        ex, ey = np.swapaxes(x_cols[:, 3:], 1, 2), np.swapaxes(y_cols[:, 3:], 1, 2)  # (n, k + nj, 3)
        rotations = np.stack([ex, ey, np.cross(ex, ey)], axis=-1)[:, self.k :]  # (n, nj, 3, 3) columns
        positions = points[:, : self.k]
        frames = np.empty((n, self.k, 6, self.nv))
        w = xi[:, 3:]
        for a in range(self.k):
            p = positions[:, a, :, None]
            frames[:, a, :3] = xi[:, :3] + np.cross(w, p, axisa=1, axisb=1, axisc=1)
            frames[:, a, 3:] = w
            frames[:, a] *= self.supports[a]
        return TreePass(xi, Mr, g, positions, frames, rotations, points[:, self.k :])

    def inertias(self, t: TreePass) -> np.ndarray:
        """The joints' body spatial inertias in the world frame at its origin, (n, nj, 6, 6)."""
        if t.inertia is None:
            R, o = t.rotations, t.origins
            c = o + np.einsum("njab,jb->nja", R, self.lever)  # centres of mass
            Ic = R @ self.rot_inertia @ np.swapaxes(R, -1, -2)
            m = self.mass[None, :, None, None]
            S = _skew(c)
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
        v, w = xi[:, :3], xi[:, 3:]  # (n, 3, nv)
        out = np.zeros((xi.shape[0], self.nv))
        for a in range(self.k):
            Jb = J_bar[:, a] * self.supports[a]
            bl, ba = Jb[:, :3], Jb[:, 3:]
            p = t.positions[:, a, :, None]
            ba = ba + np.cross(p, bl, axisa=1, axisb=1, axisc=1)  # beta = X_p^T J_bar
            gamma = np.concatenate(
                [np.cross(w, bl, axis=1), np.cross(v, bl, axis=1) + np.cross(w, ba, axis=1)], axis=1
            )  # (n, 6, nv)
            out += np.einsum("nxk,nxk->nk", xi, gamma @ self.suffix) * self.supports[a]
            rho = -np.cross(w, bl, axis=1).sum(axis=2)  # (n, 3)
            if p_bar is not None:
                rho = rho + p_bar[:, a]
            out += np.einsum("nx,nxk->nk", rho, t.frames[:, a, :3])
        return out

    def bilinear_term(self, t: TreePass, a: np.ndarray, b: np.ndarray, g_bar: np.ndarray | None = None) -> np.ndarray:
        """sum_r d(a_r^T M b_r)/dq_k + d(g_bar . g)/dq_k, (n, nv).

        Args:
            t: the chunk's pass.
            a, b: the pairs, (n, R, nv).
            g_bar: sensitivity of generalized gravity, (n, nv), or ``None``.
        """
        n = a.shape[0]
        I = self.inertias(t)
        xi = t.xi
        offset = np.zeros((a.shape[1], 6))
        if g_bar is not None:  # gravity: the pair (g_bar, 0) with b's twists the constant A0
            a = np.concatenate([a, g_bar[:, None]], axis=1)
            b = np.concatenate([b, np.zeros_like(g_bar)[:, None]], axis=1)
            offset = np.vstack([offset, self.gravity_acceleration])
        Va = (xi[:, None] * a[:, :, None, :]) @ self.anc  # (n, R, 6, nj)
        Vb = (xi[:, None] * b[:, :, None, :]) @ self.anc + offset[None, :, :, None]
        Ha = np.einsum("njxy,nryj->nrxj", I, Va) @ self.desc
        Hb = np.einsum("njxy,nryj->nrxj", I, Vb) @ self.desc
        zero = np.zeros(Va.shape[:3] + (1,))
        Va_pre = np.concatenate([zero, Va], axis=3)[..., self.pre]  # (n, R, 6, nv)
        Vb_pre = np.concatenate([zero + offset[None, :, :, None], Vb], axis=3)[..., self.pre]
        Ha_k, Hb_k = Ha[..., self.dof_joint], Hb[..., self.dof_joint]
        gam = _gamma(Va_pre, Hb_k) + _gamma(Vb_pre, Ha_k)  # (n, R, 6, nv)
        return -np.einsum("nxk,nxk->nk", xi, gam.sum(axis=1)) if n else np.zeros((0, self.nv))


def _gamma(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """gamma with x . ad(z) y = z . gamma(y, x) for every z: (w_y x x_l, v_y x x_l + w_y x x_a),
    spatial vectors on axis -2."""
    vy, wy, xl, xa = y[..., :3, :], y[..., 3:, :], x[..., :3, :], x[..., 3:, :]
    return np.concatenate([np.cross(wy, xl, axis=-2), np.cross(vy, xl, axis=-2) + np.cross(wy, xa, axis=-2)], axis=-2)


def _skew(r: np.ndarray) -> np.ndarray:
    out = np.zeros(r.shape + (3,))
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    out[..., 0, 1], out[..., 0, 2] = -z, y
    out[..., 1, 0], out[..., 1, 2] = z, -x
    out[..., 2, 0], out[..., 2, 1] = -y, x
    return out
