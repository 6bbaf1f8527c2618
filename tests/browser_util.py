"""Helpers for the browser tests of the meshcat viewer: headless Chromium through Playwright.

The meshcat page (live or exported) creates a global ``viewer`` (``MeshCat.Viewer``): its
``scene`` is the three.js scene (rotated by -90 deg about x, so that meshcat's z is up), its
``scene_tree`` mirrors the scene paths (``children`` by name; the object set at a path is the
child ``<object>``), ``camera`` is the current camera and ``animator`` plays animations.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import time
from pathlib import Path

import numpy as np

CHROMIUM = "/usr/bin/chromium"
LAUNCH_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
]
VIEWPORT = {"width": 1000, "height": 700}


def missing_browser() -> str | None:
    """Why the browser tests cannot run, or None when they can."""
    if not Path(CHROMIUM).exists():
        return f"{CHROMIUM} is missing (apt-get install chromium)"
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed (pip install playwright)"
    return None


@contextlib.contextmanager
def chromium():
    """A headless Chromium (system binary; Playwright downloads nothing)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_ARGS)
        try:
            yield browser
        finally:
            browser.close()


@contextlib.contextmanager
def opened_page(browser, url: str):
    """A page of ``browser`` (:data:`VIEWPORT`) at ``url``, closed on leaving."""
    page = browser.new_page(viewport=VIEWPORT)
    try:
        page.goto(url)
        yield page
    finally:
        page.close()


# Every scene path that holds an object: [path, three.js type of the object, uuid, visible].
_PATHS_JS = """() => {
  const out = [];
  const walk = (node, path) => {
    for (const [name, child] of Object.entries(node.children)) {
      if (name === "<object>") {
        out.push([path.join("/"), child.object.type, child.object.uuid, node.object.visible]);
      } else {
        walk(child, path.concat([name]));
      }
    }
  };
  walk(viewer.scene_tree, []);
  return out;
}"""

# A summary that changes while the scene is still streaming in or re-rendering.
_STATE_JS = """() => {
  let count = 0;
  viewer.scene.traverse(() => { count += 1; });
  const url = viewer.capture_image();
  let h = 0;
  for (let i = 0; i < url.length; i += 7) { h = (h * 31 + url.charCodeAt(i)) | 0; }
  return [count, viewer.num_messages_received, url.length, h];
}"""

_MATRIX_JS = """(path) => {
  let node = viewer.scene_tree;
  for (const name of path) {
    node = node.children[name];
    if (node === undefined) return null;
  }
  viewer.scene.updateMatrixWorld(true);
  return [viewer.scene.matrixWorld.elements, node.object.matrixWorld.elements];
}"""

_PROJECT_JS = """(points) => {
  viewer.scene.updateMatrixWorld(true);
  viewer.camera.updateMatrixWorld(true);
  const canvas = viewer.renderer.domElement;
  const rect = canvas.getBoundingClientRect();
  return points.map(p => {
    const v = viewer.camera.position.clone();
    v.set(p[0], p[1], p[2]);
    v.applyMatrix4(viewer.scene.matrixWorld);
    v.project(viewer.camera);
    return [rect.left + (v.x + 1) / 2 * rect.width, rect.top + (1 - v.y) / 2 * rect.height];
  });
}"""


def wait_for_scene(page, required: tuple[str, ...] = (), timeout: float = 30.0, stable: float = 1.0) -> float:
    """Wait until the page's scene holds the ``required`` paths and has stopped changing
    (object count, messages received and a hash of the rendered canvas) for ``stable`` s.

    Returns:
        Seconds waited.

    Raises:
        TimeoutError: the scene did not settle within ``timeout`` s.
    """
    start = time.monotonic()
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene !== undefined", timeout=timeout * 1000)
    last, since = None, time.monotonic()
    while time.monotonic() - start < timeout:
        state = page.evaluate(_STATE_JS)
        paths = {p[0] for p in page.evaluate(_PATHS_JS)} if required else set()
        now = time.monotonic()
        if state != last or not set(required) <= paths:
            last, since = state, now
        elif now - since >= stable:
            return now - start
        time.sleep(0.15)
    missing = sorted(set(required) - paths)
    raise TimeoutError(f"the scene did not settle in {timeout} s (missing paths: {missing[:5]})")


def scene_objects(page) -> dict[str, dict]:
    """Every scene path holding an object -> {"type", "uuid", "visible"}."""
    return {p: {"type": t, "uuid": u, "visible": v} for p, t, u, v in page.evaluate(_PATHS_JS)}


def exported_scene(path, timeout: float = 90.0) -> tuple[set[str], str]:
    """An exported page opened in Chromium (800 x 600): the scene's object paths and the page's
    text (its legend and notes, the folded notes opened as a click would), once the scene has
    settled."""
    with chromium() as browser:
        view = browser.new_page(viewport={"width": 800, "height": 600})
        view.goto(Path(path).as_uri())
        wait_for_scene(view, timeout=timeout)
        view.evaluate("() => document.querySelectorAll('#mobmanip-legend details').forEach(d => { d.open = true; })")
        return set(scene_objects(view)), view.inner_text("body")


def world_matrix(page, path: str, node: bool = False) -> np.ndarray | None:
    """The 4x4 world transform (meshcat's z-up world) of the object at a scene path, or with
    ``node`` of the path's own group (the object's matrix adds e.g. a cylinder's y-to-z turn)."""
    result = page.evaluate(_MATRIX_JS, path.split("/") + ([] if node else ["<object>"]))
    if result is None:
        return None
    scene, obj = (np.array(m, dtype=float).reshape(4, 4).T for m in result)  # three.js is column-major
    return np.linalg.solve(scene, obj)


_GEOMETRY_BOX_JS = """(path) => {
  let node = viewer.scene_tree;
  for (const name of path) {
    node = node.children[name];
    if (node === undefined) return null;
  }
  const geometry = node.object.geometry;
  geometry.computeBoundingBox();
  return [geometry.boundingBox.min.toArray(), geometry.boundingBox.max.toArray()];
}"""

_LEGEND_SHARE_JS = """() => {
  const box = document.getElementById("mobmanip-legend");
  if (!box) return null;
  const r = box.getBoundingClientRect();
  return r.width * r.height / (window.innerWidth * window.innerHeight);
}"""


def geometry_corners(page, path: str) -> np.ndarray | None:
    """The 8 corners (8, 3), meshcat's z-up world, of the bounding box of the geometry drawn at
    a scene path, as three.js computes it from the geometry's own vertices, placed by the
    object's world transform."""
    box = page.evaluate(_GEOMETRY_BOX_JS, path.split("/") + ["<object>"])
    if box is None:
        return None
    lo, hi = (np.array(v, dtype=float) for v in box)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    T = world_matrix(page, path)
    return corners @ T[:3, :3].T + T[:3, 3]


def legend_share(page) -> float | None:
    """The share of the view (the window's area) the legend's box covers, or None without one."""
    return page.evaluate(_LEGEND_SHARE_JS)


def project(page, points) -> np.ndarray:
    """Page pixel coordinates (x right, y down) of world points, (n, 2)."""
    return np.array(page.evaluate(_PROJECT_JS, [[float(c) for c in p] for p in points]))


def screenshot(page) -> np.ndarray:
    """The page as an RGB array (height, width, 3), uint8."""
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB"))


def image_digest(image: np.ndarray) -> str:
    return hashlib.sha1(image.tobytes()).hexdigest()


# Colour classes by hue (deg) and saturation / value of the rendered pixels.
COLOR_CLASSES = {
    "green": lambda h, s, v: (h >= 90) & (h <= 170) & (s >= 0.3) & (v >= 0.2),
    "magenta": lambda h, s, v: (h >= 270) & (h <= 330) & (s >= 0.3) & (v >= 0.2),
    "yellow": lambda h, s, v: (h >= 40) & (h <= 72) & (s >= 0.4) & (v >= 0.4),
    "red": lambda h, s, v: ((h >= 345) | (h <= 12)) & (s >= 0.5) & (v >= 0.3),
    "orange": lambda h, s, v: (h > 12) & (h <= 38) & (s >= 0.4) & (v >= 0.3),
    "grey": lambda h, s, v: (s <= 0.15) & (v >= 0.25) & (v <= 0.9),
}


def classify(pixels: np.ndarray, name: str) -> np.ndarray:
    """Which RGB pixels (..., 3) uint8 fall in the colour class ``name``."""
    from matplotlib.colors import rgb_to_hsv

    hsv = rgb_to_hsv(pixels.astype(float) / 255.0)
    return COLOR_CLASSES[name](hsv[..., 0] * 360.0, hsv[..., 1], hsv[..., 2])


def patch(image: np.ndarray, xy, radius: int = 1) -> np.ndarray:
    """The pixels (k, 3) in a (2 radius + 1)^2 square around a pixel position."""
    x, y = int(round(xy[0])), int(round(xy[1]))
    h, w = image.shape[:2]
    block = image[max(y - radius, 0) : min(y + radius + 1, h), max(x - radius, 0) : min(x + radius + 1, w)]
    return block.reshape(-1, 3)
