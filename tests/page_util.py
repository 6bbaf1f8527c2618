"""Reading an exported viewer page as a browser would, without the browser.

An exported page keeps meshcat's scene commands in one gzip store (``mobmanip.viz.compact_page``
describes the layout): parts at offsets, each distinct mesh file once, a binary STL as its distinct
vertices and triangle corners. :func:`page_commands` rebuilds the commands from the page alone
(the rebuild written here, apart from the package's page script), so that tests can look at what
the viewer receives."""

from __future__ import annotations

import base64
import gzip
import json
import re

import numpy as np

STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def _element(html: str, element_id: str) -> str | None:
    match = re.search(rf'<script type="[^"]+" id="{element_id}">(.*?)</script>', html, re.S)
    return None if match is None else match.group(1)


def _stl(blob: bytes, mesh: dict) -> bytes:
    header = blob[mesh["header"] : mesh["header"] + 80]
    (at, n), (tat, m) = mesh["vertices"], mesh["triangles"]
    vertices = np.frombuffer(blob, "<f4", 3 * n, at).reshape(n, 3)
    corners = vertices[np.frombuffer(blob, "<u4", 3 * m, tat).reshape(m, 3)]
    c = corners.astype(np.float64)
    normal = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    records = np.zeros(m, STL_RECORD)
    records["normal"], records["corners"] = normal, corners
    return header + m.to_bytes(4, "little") + records.tobytes()


def page_commands(html: str) -> list[bytes] | None:
    """The scene commands (msgpack bytes) an exported page hands to the viewer, in order; ``None``
    for a page without the store."""
    data, table = _element(html, "mobmanip-scene-data"), _element(html, "mobmanip-scene-table")
    if data is None or table is None:
        return None
    blob = gzip.decompress(base64.b64decode(data.strip()))
    layout = json.loads(table)
    meshes = [blob[m["raw"][0] : sum(m["raw"])] if "raw" in m else _stl(blob, m) for m in layout["meshes"]]
    return [
        b"".join(meshes[s] if isinstance(s, int) else blob[s[0] : s[0] + s[1]] for s in segments)
        for segments in layout["commands"]
    ]


def meshcat_commands(html: str) -> list[bytes]:
    """The commands of meshcat's own static page (base64 data URIs), in order."""
    return [base64.b64decode(b) for b in re.findall(r'fetch\("data:application/octet-binary;base64,([^"]*)"', html)]


def page_contents(html: str | bytes) -> bytes:
    """Every byte the page gives the viewer: its text and the commands it rebuilds."""
    text = html.decode("utf-8") if isinstance(html, bytes) else html
    return text.encode("utf-8") + b"".join(page_commands(text) or [])
