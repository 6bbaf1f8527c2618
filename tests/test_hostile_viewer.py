"""Hostile and broken input (3): the viewer reads meshes only inside the robot's package roots,
skips missing ones with a note, and its server answers only requests that name it on loopback."""

from __future__ import annotations

import base64
import http.client
import os

import pytest

from hostile_util import assert_one_line_error, run_cli, write_robot
from mobmanip.viz.meshes import resolve_mesh
from mobmanip.viz.server import MeshcatServer
from page_util import page_contents

# The paper robot's base box, replaced by a mesh visual.
BASE_BOX = '<geometry><box size="0.5 0.28 0.18"/></geometry>'


def _stl(marker: str) -> str:
    """An ASCII STL (one tetrahedron) whose name is ``marker``."""
    facets = []
    corners = ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1))
    for a, b, c in ((0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)):
        vertices = "".join(
            f"      vertex {x * 0.1} {y * 0.1} {z * 0.1}\n" for x, y, z in (corners[a], corners[b], corners[c])
        )
        facets.append(f"  facet normal 0 0 1\n    outer loop\n{vertices}    endloop\n  endfacet\n")
    return f"solid {marker}\n{''.join(facets)}endsolid {marker}\n"


def _encodings(data: bytes) -> list[bytes]:
    """``data`` as it appears raw or inside base64 text at any of the three byte alignments
    (the characters that depend on neighbouring bytes are left off)."""
    forms = [data]
    for shift in range(3):
        encoded = base64.b64encode(b"\0" * shift + data)
        forms.append(encoded[(shift * 4 + 2) // 3 + 1 : -4])
    return forms


def _export(tmp_path, capfd, mesh_filename: str):
    spec = write_robot(tmp_path, urdf_edits=[(BASE_BOX, f'<geometry><mesh filename="{mesh_filename}"/></geometry>')])
    page = tmp_path / "scene.html"
    code, out, err = run_cli(capfd, "view", spec, "--export", page, "--no-locked")
    return code, out, err, page


def test_a_mesh_inside_the_package_is_embedded(tmp_path, capfd):
    marker = "INSIDE_MESH_4f1c9e0b2d7a"
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "base.stl").write_text(_stl(marker))
    code, out, err, page = _export(tmp_path, capfd, "meshes/base.stl")
    assert code == 0, err
    html = page_contents(page.read_bytes())  # the compressed store too
    assert any(form in html for form in _encodings(marker.encode()))  # the check below can see a mesh
    assert "not drawn" not in out


@pytest.mark.parametrize("how", ["absolute", "file-uri", "climbing", "package-climbing", "symlink"])
def test_no_byte_of_a_mesh_outside_the_package_reaches_the_page(tmp_path, capfd, how):
    package = tmp_path / "robot"
    package.mkdir()
    secret_dir = tmp_path / "private"
    secret_dir.mkdir()
    marker = "SECRET_OUTSIDE_8c2e61d05b93"
    secret = secret_dir / "secret.stl"
    secret.write_text(_stl(marker))
    link = package / "innocent.stl"
    link.symlink_to(secret)
    filename = {
        "absolute": str(secret),
        "file-uri": f"file://{secret}",
        "climbing": "../private/secret.stl",
        "package-climbing": "package://../private/secret.stl",
        "symlink": "innocent.stl",
    }[how]
    code, out, err, page = _export(package, capfd, filename)
    assert code == 0, err
    html = page_contents(page.read_bytes())  # the compressed store too
    for form in _encodings(marker.encode()) + _encodings(secret.read_bytes()[:64]):
        assert form not in html
    assert "not drawn" in out and "outside the robot's package directories" in out


def test_a_missing_mesh_is_reported_and_the_robot_drawn_without_it(tmp_path, capfd):
    code, out, err, page = _export(tmp_path, capfd, "package://nowhere/meshes/base.stl")
    assert code == 0, err
    assert "'package://nowhere/meshes/base.stl' of link 'base_link' not drawn: no such file" in out
    # and what to do about it (issue 39: the lines did not point at --package-path)
    assert "give the folder that holds package 'nowhere' with --package-path DIR" in out
    assert page.stat().st_size > 0


def test_an_unreadable_mesh_is_one_line_or_skipped(tmp_path, capfd):
    (tmp_path / "broken.stl").write_bytes(b"\x00\x01 not a mesh at all")
    code, out, err, page = _export(tmp_path, capfd, "broken.stl")
    if code == 0:
        assert page.stat().st_size > 0
    else:
        assert_one_line_error(code, err)


def test_resolve_mesh_follows_package_uris_inside_roots_only(tmp_path):
    root = tmp_path / "share"
    (root / "pkg" / "meshes").mkdir(parents=True)
    (root / "pkg" / "meshes" / "a.stl").write_text("solid a\nendsolid a\n")
    path, reason = resolve_mesh("package://pkg/meshes/a.stl", tmp_path, [root])
    assert path == (root / "pkg" / "meshes" / "a.stl").resolve() and reason == ""
    for name in ("package://pkg/../../outside.stl", "/etc/passwd", "file:///etc/hostname", "http://example.com/a.stl"):
        path, reason = resolve_mesh(name, root, [root])
        assert path is None and reason


# ----- the server


def _request(port: int, host: str, origin: str | None = None, websocket: bool = False) -> int:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    headers = {"Host": host}
    if origin is not None:
        headers["Origin"] = origin
    if websocket:
        headers.update(
            {
                "Upgrade": "websocket",
                "Connection": "Upgrade",
                "Sec-WebSocket-Key": base64.b64encode(os.urandom(16)).decode(),
                "Sec-WebSocket-Version": "13",
            }
        )
    try:
        connection.request("GET", "/" if websocket else "/static/", headers=headers)
        return connection.getresponse().status
    finally:
        connection.close()


@pytest.fixture(scope="module")
def server():
    server = MeshcatServer()
    yield server
    server.stop()


def test_the_server_answers_its_own_pages(server):
    own = f"127.0.0.1:{server.port}"
    assert _request(server.port, own) == 200
    assert _request(server.port, f"localhost:{server.port}") == 200
    assert _request(server.port, own, origin=f"http://{own}", websocket=True) == 101


@pytest.mark.parametrize(
    ("host", "origin"),
    [
        ("attacker.example:{port}", None),  # DNS rebinding: the page's name resolves to 127.0.0.1
        ("attacker.example:{port}", "http://attacker.example:{port}"),
        ("127.0.0.1:{port}", "http://attacker.example"),
        ("127.0.0.1:{port}", "http://127.0.0.1:1"),  # another local port
        ("127.0.0.1:1", None),
        ("127.0.0.1.attacker.example:{port}", None),
    ],
)
def test_foreign_host_or_origin_is_refused(server, host, origin):
    host = host.format(port=server.port)
    origin = None if origin is None else origin.format(port=server.port)
    assert _request(server.port, host, origin) == 403
    assert _request(server.port, host, origin, websocket=True) == 403
