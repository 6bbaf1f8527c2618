"""Masses that live in meshes: a body with no ``<inertial>`` whose mesh geoms MuJoCo integrates
(density 1000 kg/m^3 unless set, or a geom's ``mass``). mobmanip integrates the same meshes
(trimesh, exactly) and gives Pinocchio the result; MuJoCo's own compiler is the reference.

MuJoCo keeps mesh vertices in single precision: its masses, centres and inertias of meshes are
float32 computations, so they agree to 1e-6 relative, not to 1e-12 as its primitives do.
"""

from __future__ import annotations

import numpy as np
import pytest

from mjcf_util import compiled_inertia, mjcf_text, read_beside_mujoco
from mobmanip.descriptions import read_description

trimesh = pytest.importorskip("trimesh")
mujoco = pytest.importorskip("mujoco")

#: Three bodies with no <inertial> whose geoms carry the mass: meshes (one scaled, one given a
#: density, one a mass), a box with a mass; the mesh files are written beside it.
ROBOT = mjcf_text("meshed")


def _write(tmp_path, text=ROBOT):
    block = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    block.apply_translation((0.05, 0.02, 0.01))  # off the mesh file's own origin
    block.export(tmp_path / "block.obj")
    corner = trimesh.path.polygons.Polygon([(0, 0), (0.4, 0), (0.4, 0.1), (0.1, 0.1), (0.1, 0.3), (0, 0.3)])
    trimesh.creation.extrude_polygon(corner, 0.2).export(tmp_path / "ell.obj")  # not convex
    path = tmp_path / "meshed.xml"
    path.write_text(text)
    return path


def test_mesh_bodies_weigh_what_mujoco_compiles(tmp_path):
    """Three bodies with no <inertial>: a scaled, turned, offset box mesh at MuJoCo's default
    density; a non-convex mesh at density 700 (inertia="exact") beside a box geom with a mass; a
    mesh given a mass. Each body's mass, centre of mass and inertia in Pinocchio's model and in the
    description equal MuJoCo's compiled ones to 1e-6 (the base alone, 1 kg and a unit tensor in
    Pinocchio before: 7.2 kg, the scaled block at 1000 kg/m^3)."""
    path = _write(tmp_path)
    description, model, theirs = read_beside_mujoco(path)
    for joint, body in (("shoulder", "upper"), ("elbow", "lower")):
        their_mass, com, expected = compiled_inertia(theirs, body)
        inertial = description.links[body].inertial
        Rl = inertial.origin.rotation
        for mass, lever, tensor in (
            (inertial.mass, np.asarray(inertial.origin.xyz), Rl @ inertial.inertia_matrix @ Rl.T),
            (model.inertias[model.getJointId(joint)].mass, model.inertias[model.getJointId(joint)].lever,
             model.inertias[model.getJointId(joint)].inertia),
        ):  # fmt: skip
            assert mass == pytest.approx(their_mass, rel=1e-6)
            np.testing.assert_allclose(lever, com, atol=1e-6)
            np.testing.assert_allclose(tensor, expected, atol=1e-6 * np.abs(expected).max())
    base = theirs.body("base")
    assert description.links["base"].inertial.mass == pytest.approx(float(base.mass[0]), rel=1e-6)
    assert float(base.mass[0]) == pytest.approx(1000 * 0.3 * 0.3 * 0.08, rel=1e-6)  # 7.2 kg: scaled 1 x 1.5 x 0.8


def test_a_non_convex_mesh_at_mujocos_default_is_noted_and_a_missing_one_named(tmp_path):
    """MuJoCo's default integration of a mesh (legacy) over-counts a non-convex one: mobmanip keeps
    the exact volume and its notes say so, naming the mesh and the body; a mesh file that is not
    there is named with its body, not passed off as 1 kg."""
    path = _write(tmp_path, ROBOT.replace('mesh="ell" density', 'mesh="ell_legacy" density'))
    notes = " ".join(read_description(path).notes)
    assert "mesh 'ell_legacy' of body 'upper' is not convex" in notes and 'inertia="exact"' in notes
    (tmp_path / "block.obj").unlink()
    notes = " ".join(read_description(path).notes)
    assert "whose files are missing or not closed: 'base', 'lower'" in notes


def test_a_shell_mesh_and_a_class_scaled_mesh_weigh_what_mujoco_compiles(tmp_path):
    """A mesh with ``inertia="shell"`` (its mass on the surface: Stretch's stickers) and a mesh
    whose scale comes from its class's default (Robotiq's millimetres, in TidyBot), each alone in a
    body: mass, centre and inertia equal MuJoCo's compiled ones."""
    text = ROBOT.replace(
        '<mesh name="ell_legacy" file="ell.obj"/>',
        '<mesh name="ell_legacy" file="ell.obj"/><mesh name="skin" file="block.obj" inertia="shell"/>'
        '<mesh name="small" class="mm" file="block.obj"/>',
    ).replace("<compiler", '<default><default class="mm"><mesh scale="0.5 0.25 2"/></default></default><compiler')
    text = text.replace(
        '<site name="tool" pos="0.25 0 0"/>',
        '<site name="tool" pos="0.25 0 0"/><body name="sticker" pos="0.1 0 0"><geom type="mesh" mesh="skin" '
        'mass="0.3" pos="0.01 0.02 0"/><body name="tiny"><geom type="mesh" mesh="small"/></body></body>',
    )
    description, _, theirs = read_beside_mujoco(_write(tmp_path, text))
    for body in ("sticker", "tiny"):
        their_mass, com, expected = compiled_inertia(theirs, body)
        inertial = description.links[body].inertial
        R = inertial.origin.rotation
        assert inertial.mass == pytest.approx(their_mass, rel=1e-6)
        np.testing.assert_allclose(inertial.origin.xyz, com, atol=1e-7)
        np.testing.assert_allclose(R @ inertial.inertia_matrix @ R.T, expected, atol=1e-6 * np.abs(expected).max())
