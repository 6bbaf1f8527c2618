"""Helpers of the MJCF tests: a robot file read by mobmanip and by MuJoCo's own compiler, side by side."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from mobmanip.descriptions import read_description


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
