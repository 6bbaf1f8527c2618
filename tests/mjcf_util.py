"""Helpers of the MJCF tests: their small robot files (``tests/data/mjcf``), a robot file read by
mobmanip and by MuJoCo's own compiler, side by side."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from mobmanip.descriptions import read_description

#: The small MJCF robots the tests write, one a file (each file's comment says what it holds).
MJCF_DATA = Path(__file__).resolve().parent / "data" / "mjcf"


def mjcf_text(name: str) -> str:
    """The text of the test robot ``tests/data/mjcf/<name>.xml``."""
    return (MJCF_DATA / f"{name}.xml").read_text()


def read_beside_mujoco(path):
    """The MJCF at ``path`` read by mobmanip (its description, and the Pinocchio model on a planar
    base) and compiled by MuJoCo: (description, model, MuJoCo's model)."""
    import mujoco

    description = read_description(path)
    model = description.build_model(pin.JointModelPlanar())
    return description, model, mujoco.MjModel.from_xml_path(str(path))


def compiled_inertia(theirs, body: str) -> tuple[float, np.ndarray, np.ndarray]:
    """A body's mass, centre of mass and inertia tensor about it, in the body's frame, as MuJoCo
    compiled them (its principal moments turned back by ``iquat``)."""
    b = theirs.body(body)
    w, x, y, z = b.iquat
    R = pin.Quaternion(w, x, y, z).normalized().matrix()
    return float(b.mass[0]), b.ipos, R @ np.diag(b.inertia) @ R.T


def mujoco_terms(theirs, qpos, qvel, frames):
    """MuJoCo's own mass matrix (``mj_fullM``), bias (``qfrc_bias``: Coriolis, centrifugal and
    gravity) and, per frame, its Jacobian ``[jacp; jacr]`` (``mj_jacSite`` for a site, else
    ``mj_jacBody`` at the body's origin) and position, at ``qpos``, ``qvel``."""
    import mujoco

    data = mujoco.MjData(theirs)
    data.qpos[:] = qpos
    data.qvel[:] = qvel
    mujoco.mj_forward(theirs, data)
    M = np.zeros((theirs.nv, theirs.nv))
    mujoco.mj_fullM(theirs, data, M)
    jacobians, positions = [], []
    for frame in frames:
        jacp, jacr = np.zeros((3, theirs.nv)), np.zeros((3, theirs.nv))
        if mujoco.mj_name2id(theirs, mujoco.mjtObj.mjOBJ_SITE, frame) >= 0:
            site = theirs.site(frame).id
            mujoco.mj_jacSite(theirs, data, jacp, jacr, site)
            positions.append(data.site_xpos[site].copy())
        else:
            body = theirs.body(frame).id
            mujoco.mj_jacBody(theirs, data, jacp, jacr, body)
            positions.append(data.xpos[body].copy())
        jacobians.append(np.vstack([jacp, jacr]))
    return M, data.qfrc_bias.copy(), jacobians, positions


def platform_map(theta: float, rows: tuple[int, int, int], nv_theirs: int, nv_ours: int) -> np.ndarray:
    """T (nv_theirs, nv_ours) with MuJoCo's velocity = T mobmanip's for the platform's three
    velocities (mobmanip: v_x, v_y in the platform's frame, then omega; MuJoCo: x', y' along the
    world's axes at ``rows[:2]``, the yaw rate at ``rows[2]``); the caller fills the joints' ones."""
    c, s = np.cos(theta), np.sin(theta)
    T = np.zeros((nv_theirs, nv_ours))
    T[rows[0], :2] = (c, -s)
    T[rows[1], :2] = (s, c)
    T[rows[2], 2] = 1.0
    return T


def platform_map_rate(theta: float, v: np.ndarray, rows: tuple[int, int, int], nv_theirs: int) -> np.ndarray:
    """dT/dt v for :func:`platform_map` (the platform's velocity turning with it), (nv_theirs,):
    MuJoCo's acceleration is T v' + dT/dt v, so mobmanip's bias is T^T (bias + M dT/dt v)."""
    c, s = np.cos(theta), np.sin(theta)
    vx, vy, omega = v[:3]
    out = np.zeros(nv_theirs)
    out[rows[0]] = omega * (-s * vx - c * vy)
    out[rows[1]] = omega * (c * vx - s * vy)
    return out
