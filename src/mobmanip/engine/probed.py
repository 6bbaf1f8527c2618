"""The Pinocchio pass: one CRBA call per configuration of a model with massless probe joints.

:class:`ProbedModel` adds the probes; :func:`pinocchio_pass` runs CRBA over a chunk of
configurations into a reusable :class:`Workspace`. Everything after this pass (J_u, P, xi, the
grasp and the ellipsoids) is computed from its outputs without calling Pinocchio again.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import ModelError
from .stacked_linalg import cross3

#: Pinocchio's world convention for ``crba`` (CRBA then leaves the world joint Jacobians in
#: ``data.J``), or ``None`` for bindings without conventions (the Jacobians take one more call).
WORLD_CONVENTION = getattr(getattr(pin, "Convention", None), "WORLD", None)


class ProbedModel:
    """The robot's model with massless *probe* joints, so that one CRBA call per configuration
    gives everything the batch needs from Pinocchio.

    CRBA in the world convention leaves the world joint Jacobians in ``data.J`` beside M. Two
    kinds of probes, which carry no mass and sit at q = 0, make the other per-configuration
    calls unnecessary:

    * a prismatic joint along -g at the root, carrying the whole robot: its row of M is
      sum_b m_b dc_b/dq (the robot's momentum along it), so generalized gravity is
      ``g = |g| M[0, v]``;
    * two revolute joints at each end-effector frame, about its x and y axes: a revolute
      joint's world Jacobian column is (p x w, w) for its position p and unit axis w, and
      w x (p x w) = p - w (w . p), so the two columns give the frame's position (see
      :func:`frame_positions`).

    Probes change neither the robot's Jacobians nor its M: its degrees of freedom are columns
    ``vmap`` of the probed model's (the probes go right after their parent's subtree, keeping
    every subtree contiguous as CRBA requires), its configuration entries ``qmap``.
    """

    def __init__(self, model: pin.Model, frame_ids):
        gravity = np.asarray(model.gravity.linear, dtype=float)
        self.gravity = float(np.linalg.norm(gravity))
        axis = -gravity / self.gravity if self.gravity > 0.0 else np.array([0.0, 0.0, 1.0])
        probed = pin.Model()
        probed.name = model.name
        root = probed.addJoint(0, pin.JointModelPrismaticUnaligned(axis), pin.SE3.Identity(), "mobmanip_gravity_probe")
        # each frame's probes follow the last joint of its parent joint's subtree
        after: dict[int, list[int]] = {}
        for a, f in enumerate(frame_ids):
            parent = model.frames[f].parentJoint
            after.setdefault(max(model.subtrees[parent]) if parent > 0 else model.njoints - 1, []).append(a)
        new_id = {0: root}
        probe_ids: list = [None] * len(frame_ids)

        def add_probes(last: int) -> None:
            for a in after.get(last, ()):
                frame = model.frames[frame_ids[a]]
                probe_ids[a] = [
                    probed.addJoint(new_id[frame.parentJoint], joint, frame.placement, f"mobmanip_probe_{a}_{axis}")
                    for axis, joint in (("x", pin.JointModelRX()), ("y", pin.JointModelRY()))
                ]

        add_probes(0)
        for j in range(1, model.njoints):
            parent = new_id[model.parents[j]]
            try:
                new_id[j] = probed.addJoint(parent, model.joints[j], model.jointPlacements[j], model.names[j])
            except Exception as error:  # a joint type Pinocchio's bindings cannot copy
                name, kind = model.names[j], model.joints[j].shortname()
                raise ModelError(f"joint {name!r} ({kind}) cannot be copied for the batch pass: {error}") from None
            probed.appendBodyToJoint(new_id[j], model.inertias[j], pin.SE3.Identity())
            add_probes(j)
        self.vmap = np.zeros(model.nv, dtype=np.uint64)
        self.qmap = np.zeros(model.nq, dtype=np.int64)
        for j in range(1, model.njoints):
            old, new = model.joints[j], probed.joints[new_id[j]]
            self.vmap[old.idx_v : old.idx_v + old.nv] = np.arange(new.idx_v, new.idx_v + new.nv)
            self.qmap[old.idx_q : old.idx_q + old.nq] = np.arange(new.idx_q, new.idx_q + new.nq)
        armature = np.zeros(probed.nv)
        armature[self.vmap.astype(int)] = model.armature
        probed.armature = armature
        self.probe_cols = np.array([[probed.joints[j].idx_v for j in ids] for ids in probe_ids], dtype=np.uint64)
        self.model = probed
        self.data = probed.createData()
        self.nv = model.nv

    def robot_jacobians(self, Jw: np.ndarray) -> np.ndarray:
        """The robot's world joint Jacobians (n, 6, nv) from the probed model's."""
        return Jw[..., self.vmap.astype(int)]

    def robot_mass_matrices(self, M: np.ndarray) -> np.ndarray:
        """The robot's M (n, nv, nv) from the probed model's."""
        v = self.vmap.astype(int)
        return M[:, v[:, None], v]

    def gravity_torques(self, M: np.ndarray) -> np.ndarray:
        """Generalized gravity (n, nv) from the probed model's M."""
        return self.gravity * M[:, 0, self.vmap.astype(int)]

    def frame_positions(self, Jw: np.ndarray) -> np.ndarray:
        """End-effector positions (n, k, 3) from the probe columns of the world Jacobians."""
        return frame_positions(Jw[..., self.probe_cols[:, 0].astype(int)], Jw[..., self.probe_cols[:, 1].astype(int)])


def frame_positions(x_cols: np.ndarray, y_cols: np.ndarray) -> np.ndarray:
    """Positions p (n, k, 3) from the world Jacobian columns (n, 6, k) of revolute joints at p
    about two orthogonal unit axes w_x, w_y: a = w_x x v_x = p - w_x (w_x . p) lacks only p's
    component along w_x, which b = w_y x v_y keeps: p = a + w_x (w_x . b)."""
    vx, wx = np.swapaxes(x_cols[:, :3], 1, 2), np.swapaxes(x_cols[:, 3:], 1, 2)
    vy, wy = np.swapaxes(y_cols[:, :3], 1, 2), np.swapaxes(y_cols[:, 3:], 1, 2)
    a = cross3(wx, vx)
    b = cross3(wy, vy)
    return a + wx * np.sum(wx * b, axis=-1, keepdims=True)


class Workspace:
    """Reusable buffers for the Pinocchio pass of up to ``n`` configurations.

    Attributes:
        q: the probed model's configurations, (n, nq_p); the probes' entries stay 0.
        Ma: the probed model's mass matrices, (n, nv_p, nv_p).
        Ja: the probed model's world joint Jacobians, (n, 6, nv_p).
        pos: end-effector positions, (n, k, 3), filled by whoever reads the probe columns.
    """

    def __init__(self, probed: ProbedModel, n: int):
        model = probed.model
        self.n = n
        self.q = np.zeros((n, model.nq))
        self.Ma = np.zeros((n, model.nv, model.nv))
        self.Ja = np.zeros((n, 6, model.nv))
        self.pos = np.zeros((n, probed.probe_cols.shape[0], 3))
        self.q_rows, self.M_rows, self.J_rows = list(self.q), list(self.Ma), list(self.Ja)


def pinocchio_pass(probed: ProbedModel, qs: np.ndarray, ws: Workspace, *, convention=WORLD_CONVENTION) -> None:
    """Fill the workspace's first ``len(qs)`` rows from Pinocchio: one CRBA call per configuration
    of the probed model, in the world convention, which also leaves the world joint Jacobians in
    ``data.J``.

    Args:
        probed: the probed model.
        qs: the robot's configurations, (n, nq), n <= ``ws.n``.
        ws: the workspace to fill (``Ma`` and ``Ja``).
        convention: Pinocchio's world convention, or ``None`` to compute the joint Jacobians by
            their own call (what bindings without conventions need).
    """
    n = qs.shape[0]
    model, data = probed.model, probed.data
    ws.q[:n, probed.qmap] = qs
    rows = zip(ws.q_rows[:n], ws.M_rows[:n], ws.J_rows[:n])  # views made once: cheaper than indexing
    crba = pin.crba
    if convention is None:  # an older Pinocchio: one more call
        jacobians = pin.computeJointJacobians
        for q, M, Jw in rows:
            M[...] = crba(model, data, q)
            Jw[...] = jacobians(model, data, q)
        return
    J = data.J  # a view of Pinocchio's buffer, refreshed by every crba call below
    for q, M, Jw in rows:
        M[...] = crba(model, data, q, convention)
        Jw[...] = J
