"""Hostile input, round 2 (class 1): the package boundary holds for every file a mesh references.
A Collada mesh inside the package whose texture (``<library_images><image><init_from>``) lies
outside it is left out of the drawing, and no byte of that texture reaches any exported page:
``view``, ``place``, ``trajectory`` and ``team --export``."""

from __future__ import annotations

import base64

import pytest

from hostile_util import ROOT, run_cli, write_robot
from mobmanip.viz.meshes import mesh_references
from page_util import page_contents

BASE_BOX = '<geometry><box size="0.5 0.28 0.18"/></geometry>'
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _collada(texture: str, namespace: bool = True) -> str:
    ns = ' xmlns="http://www.collada.org/2005/11/COLLADASchema"' if namespace else ""
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA{ns} version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_images><image id="tex" name="tex"><init_from>{texture}</init_from></image></library_images>
  <library_geometries>
    <geometry id="m" name="m"><mesh>
      <source id="m-pos"><float_array id="m-pos-a" count="9">0 0 0 0.1 0 0 0 0.1 0</float_array>
        <technique_common><accessor source="#m-pos-a" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="m-vtx"><input semantic="POSITION" source="#m-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#m-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#m"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""


def _encodings(data: bytes) -> list[bytes]:
    forms = [data]
    for shift in range(3):
        encoded = base64.b64encode(b"\0" * shift + data)
        forms.append(encoded[(shift * 4 + 2) // 3 + 1 : -4])
    return forms


def _package(tmp_path, how: str):
    """A robot package whose base is a Collada mesh naming a texture; returns (spec, secret bytes)."""
    package = tmp_path / "robot"
    package.mkdir()
    private = tmp_path / "private"
    private.mkdir()
    secret = PNG_MAGIC + b"SECRET_TEXTURE_5d1e0c7a93b4" * 8
    (private / "secret.png").write_bytes(secret)
    (package / "inside.png").write_bytes(PNG_MAGIC + b"INSIDE_TEXTURE")
    (package / "link.png").symlink_to(private / "secret.png")
    texture = {
        "absolute": str(private / "secret.png"),
        "climbing": "../private/secret.png",
        "symlink": "link.png",
        "file-uri": f"file://{private / 'secret.png'}",
        "inside": "inside.png",
    }[how]
    (package / "base.dae").write_text(_collada(texture))
    spec = write_robot(package, urdf_edits=[(BASE_BOX, '<geometry><mesh filename="base.dae"/></geometry>')])
    return spec, secret


def _exports(tmp_path, spec):
    """Every command that exports a page, with its argv."""
    team = tmp_path / "team.toml"
    team.write_text((ROOT / "examples" / "beam_team.toml").read_text().replace("planar_dual_arm", str(spec)))
    motion = tmp_path / "m.csv"
    motion.write_text("t,platform_x,platform_y,platform_yaw\n0,0,0,0\n0.1,0.01,0,0\n0.2,0.02,0,0\n")
    return {
        "view": ("view", spec, "--no-locked"),
        "place": ("place", spec, "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x", "--starts", "1"),
        "trajectory": ("trajectory", spec, motion),
        "team": ("team", team),
    }


@pytest.mark.parametrize("how", ["absolute", "climbing", "symlink", "file-uri"])
@pytest.mark.parametrize("command", ["view", "place", "trajectory", "team"])
def test_no_byte_of_a_texture_outside_the_package_reaches_any_page(tmp_path, capfd, how, command):
    spec, secret = _package(tmp_path, how)
    page = tmp_path / "page.html"
    code, out, err = run_cli(capfd, *_exports(tmp_path, spec)[command], "--export", page)
    assert code == 0, err
    html = page_contents(page.read_bytes())  # the compressed store too
    for form in _encodings(secret[8:40]):
        assert form not in html, how
    if command in ("view", "team"):  # the commands that print the viewer's notes
        assert "texture" in out and "not drawn" in out


def test_a_texture_inside_the_package_keeps_the_mesh(tmp_path, capfd):
    spec, _ = _package(tmp_path, "inside")
    page = tmp_path / "page.html"
    code, out, err = run_cli(capfd, "view", spec, "--no-locked", "--export", page)
    assert code == 0, err
    assert "not drawn" not in out


def test_mesh_references_reads_every_texture(tmp_path):
    for namespace in (True, False):
        dae = tmp_path / f"m{namespace}.dae"
        dae.write_text(_collada("a/b.png", namespace))
        assert mesh_references(dae) == (["a/b.png"], "")
    empty = tmp_path / "e.dae"
    empty.write_text(_collada(""))
    assert mesh_references(empty)[0] is None
    broken = tmp_path / "b.dae"
    broken.write_text("<COLLADA><library_images>")
    assert mesh_references(broken)[0] is None
    stl = tmp_path / "x.stl"
    stl.write_text("solid x\nendsolid x\n")
    assert mesh_references(stl) == ([], "")
