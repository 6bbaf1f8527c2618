"""Exported viewer pages that keep each mesh file once, compressed.

meshcat's static page (its ``get_scene``) embeds every scene command as a base64 data URI that
the page fetches and hands to the viewer. A mesh file drawn by several objects (TIAGo++'s two
arms, a wheel used four times) is then embedded once per object, and every mesh is the base64 of
its raw bytes (a binary STL: 50 bytes a triangle; Collada: XML text): 11 to 37 MB for the
built-in robots. :func:`compact` rewrites such a page:

- each command is split around the mesh files it carries (the ``data`` of a ``_meshfile``
  geometry or of a ``_meshfile_object``): the literal bytes before, between and after them;
- each distinct mesh file is stored once. A binary STL is stored *indexed* (its distinct float32
  vertices, bit for bit, and three uint32 corners a triangle) when the page can rebuild it: no
  colour attributes, and every stored face normal along the normal its triangle's corners give
  (:data:`NORMAL_COS`); the page then writes the binary STL again, each normal from its corners.
  Every other mesh is stored as it is;
- all of it is one gzip stream, base64 text in a ``<script type="application/octet-stream">``
  element, with a JSON table of the parts; the page decompresses it with the browser's
  ``DecompressionStream`` and hands the rebuilt commands to the viewer one after another, in the
  order meshcat recorded them.

The viewer receives the same commands as before, so the scene (paths, transforms, animation,
mobmanip's legend and camera) is unchanged.
"""

from __future__ import annotations

import base64
import gzip
import json
import re
from dataclasses import dataclass, field

import numpy as np

#: meshcat 0.3's embedded command (``zmqserver.create_command``).
COMMAND = re.compile(
    r'fetch\("data:application/octet-binary;base64,(?P<data>[A-Za-z0-9+/=]*)"\)\s*'
    r"\.then\(res => res\.arrayBuffer\(\)\)\s*"
    r"\.then\(buffer => viewer\.handle_command_bytearray\(new Uint8Array\(buffer\)\)\);"
)
#: A mesh file smaller than this (bytes) stays inside its command.
MIN_MESH_BYTES = 1024
#: A binary STL is stored indexed only if each non-degenerate face's stored normal is within
#: acos(NORMAL_COS) (about 2.6 deg) of the normal its corners give (as the page recomputes it).
NORMAL_COS = 0.999
DATA_ID = "mobmanip-scene-data"
TABLE_ID = "mobmanip-scene-table"
STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


@dataclass
class _Blob:
    """The decompressed store: parts at 4-byte aligned offsets (typed arrays view them in place)."""

    chunks: list[bytes] = field(default_factory=list)
    size: int = 0

    def add(self, data: bytes) -> list[int]:
        at = self.size
        pad = -len(data) % 4
        self.chunks.append(data + b"\0" * pad)
        self.size += len(data) + pad
        return [at, len(data)]


def _mesh_payloads(command: dict) -> list[bytes]:
    """The mesh files a decoded ``set_object`` command carries, as their bytes (msgpack order)."""
    if command.get("type") != "set_object":
        return []
    obj = command.get("object") or {}
    found = []
    for geometry in obj.get("geometries") or []:
        if isinstance(geometry, dict) and geometry.get("type") == "_meshfile":
            found.append(geometry.get("data"))
    inner = obj.get("object") or {}
    if isinstance(inner, dict) and inner.get("type") == "_meshfile_object":
        found.append(inner.get("data"))
    out = []
    for data in found:
        raw = getattr(data, "data", data)  # an ext (typed array) carries its bytes in .data
        raw = raw.encode("utf-8") if isinstance(raw, str) else raw
        if isinstance(raw, bytes) and len(raw) >= MIN_MESH_BYTES:
            out.append(raw)
    return out


def indexed_stl(raw: bytes) -> tuple[bytes, np.ndarray, np.ndarray] | None:
    """A binary STL as (80-byte header, distinct vertices (n, 3) float32, corners (m, 3) uint32),
    or ``None`` when rebuilding it from these would change what three.js draws: not a binary STL
    of the stated size, colour attributes (``COLOR=`` or non-zero attribute words), or a stored
    normal that is not along its triangle's (see :data:`NORMAL_COS`)."""
    if len(raw) < 84 or raw[:5].lower() == b"solid" and b"facet" in raw[:1024]:
        return None
    count = int.from_bytes(raw[80:84], "little")
    if count == 0 or len(raw) != 84 + 50 * count or b"COLOR=" in raw[:80]:
        return None
    records = np.frombuffer(raw, dtype=STL_RECORD, count=count, offset=84)
    if np.any(records["attribute"]):
        return None
    corners = records["corners"].astype(np.float64)
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(cross, axis=1)
    stored = records["normal"].astype(np.float64)
    stored_length = np.linalg.norm(stored, axis=1)
    faces = length > 0
    if not np.all(np.isfinite(corners)) or np.any(faces & (stored_length == 0)):
        return None
    cos = np.einsum("ij,ij->i", cross[faces], stored[faces]) / (length[faces] * stored_length[faces])
    if np.any(cos < NORMAL_COS):
        return None
    points = np.ascontiguousarray(records["corners"].reshape(-1, 3))
    keys = points.view(np.dtype((np.void, 12))).ravel()  # bit for bit (-0.0 is not 0.0)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return raw[:80], points[first], inverse.reshape(-1, 3).astype("<u4")


def compact(html: str) -> str:
    """meshcat's static page with its commands stored as :mod:`this module <mobmanip.viz.compact_page>`
    describes; the page unchanged if it holds none in meshcat's form."""
    import umsgpack

    matches = list(COMMAND.finditer(html))
    if not matches:
        return html
    blob, index = _Blob(), {}
    meshes: list[dict] = []
    commands = []
    for match in matches:
        data = base64.b64decode(match.group("data"))
        segments: list = []
        at = 0
        for raw in _mesh_payloads(umsgpack.unpackb(data)):
            start = data.find(raw, at)
            if start < 0:  # pragma: no cover - msgpack keeps bytes and strings as they are
                continue
            if start > at:
                segments.append(blob.add(data[at:start]))
            if raw not in index:
                index[raw] = len(meshes)
                stl = indexed_stl(raw)
                if stl is None:
                    meshes.append({"raw": blob.add(raw)})
                else:
                    header, vertices, triangles = stl
                    meshes.append(
                        {
                            "header": blob.add(header)[0],
                            "vertices": [blob.add(vertices.astype("<f4").tobytes())[0], len(vertices)],
                            "triangles": [blob.add(triangles.tobytes())[0], len(triangles)],
                        }
                    )
            segments.append(index[raw])
            at = start + len(raw)
        if at < len(data):
            segments.append(blob.add(data[at:]))
        commands.append(segments)
    packed = base64.b64encode(gzip.compress(b"".join(blob.chunks), compresslevel=6, mtime=0)).decode("ascii")
    table = json.dumps({"meshes": meshes, "commands": commands}, separators=(",", ":"))
    first, last = matches[0], matches[-1]
    loader = _LOADER.replace("__DATA__", DATA_ID).replace("__TABLE__", TABLE_ID)
    body = html[: first.start()] + loader + html[last.end() :]
    stores = (
        f'<script type="application/octet-stream" id="{DATA_ID}">{packed}</script>\n'
        f'<script type="application/json" id="{TABLE_ID}">{table}</script>\n'
    )
    at = body.find("<script")
    return body[:at] + stores + body[at:] if at >= 0 else stores + body


#: Rebuilds the commands (see the module's description); runs where meshcat's commands were.
_LOADER = """
(async function () {
  "use strict";
  function stl(buffer, mesh) {
    const v = new Float32Array(buffer, mesh.vertices[0], 3 * mesh.vertices[1]);
    const t = new Uint32Array(buffer, mesh.triangles[0], 3 * mesh.triangles[1]);
    const count = mesh.triangles[1];
    const out = new Uint8Array(84 + 50 * count);
    out.set(new Uint8Array(buffer, mesh.header, 80), 0);
    const view = new DataView(out.buffer);
    view.setUint32(80, count, true);
    for (let i = 0; i < count; i++) {
      const a = 3 * t[3 * i], b = 3 * t[3 * i + 1], c = 3 * t[3 * i + 2];
      const ux = v[b] - v[a], uy = v[b + 1] - v[a + 1], uz = v[b + 2] - v[a + 2];
      const wx = v[c] - v[a], wy = v[c + 1] - v[a + 1], wz = v[c + 2] - v[a + 2];
      let nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
      const n = Math.hypot(nx, ny, nz);
      if (n > 0) { nx /= n; ny /= n; nz /= n; }
      let o = 84 + 50 * i;
      for (const x of [nx, ny, nz, v[a], v[a + 1], v[a + 2], v[b], v[b + 1], v[b + 2], v[c], v[c + 1], v[c + 2]]) {
        view.setFloat32(o, x, true);
        o += 4;
      }
    }
    return out;
  }
  try {
    const text = document.getElementById("__DATA__").textContent.trim();
    const table = JSON.parse(document.getElementById("__TABLE__").textContent);
    const packed = await (await fetch("data:application/octet-stream;base64," + text)).blob();
    const buffer = await new Response(packed.stream().pipeThrough(new DecompressionStream("gzip"))).arrayBuffer();
    const meshes = table.meshes.map((m) => (m.raw ? new Uint8Array(buffer, m.raw[0], m.raw[1]) : stl(buffer, m)));
    for (const segments of table.commands) {
      const parts = segments.map((s) => (typeof s === "number" ? meshes[s] : new Uint8Array(buffer, s[0], s[1])));
      const bytes = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
      let at = 0;
      for (const part of parts) {
        bytes.set(part, at);
        at += part.length;
      }
      viewer.handle_command_bytearray(bytes);
    }
  } catch (error) {
    const note = document.createElement("div");
    note.style.cssText = "position:absolute;top:8px;left:8px;z-index:20;" +
      "background:#fee;padding:6px;font:13px sans-serif";
    note.textContent =
      "This page needs a browser with DecompressionStream (Chrome 80, Firefox 113, Safari 16.4 or later): " + error;
    document.body.appendChild(note);
  }
})();
"""
