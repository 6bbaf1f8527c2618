// mobmanip's part of the viewer page (live and exported): a legend with the colours and scales of
// the drawn sets, and a camera that frames the robot, its object and its sets.
//
// The Python side (mobmanip.viz.page) stores what to show as the property "mobmanip_page" of the
// scene node /meshcat/mobmanip; meshcat replays it to every page (and into exported pages). This
// script polls it, rebuilds the legend when it changes and applies each camera request once (by
// its serial number), so that the user's own camera moves are kept until Python asks again.
(function () {
  "use strict";
  const PROPERTY = "mobmanip_page";
  let legendKey = null;
  let cameraSerial = null;

  function pageData() {
    if (typeof viewer === "undefined" || !viewer.scene_tree) return null;
    const root = viewer.scene_tree.children.meshcat;
    const node = root && root.children.mobmanip;
    return node && node.object ? node.object[PROPERTY] || null : null;
  }

  function style() {
    const css = document.createElement("style");
    css.textContent = `
      #mobmanip-legend { position: absolute; left: 8px; bottom: 8px; z-index: 10; max-width: 46vw;
        background: rgba(255, 255, 255, 0.88); color: #111; border-radius: 4px; padding: 6px 9px;
        font: 12px/1.35 system-ui, sans-serif; pointer-events: none; }
      #mobmanip-legend .mm-title { font-weight: 600; margin-bottom: 3px; }
      #mobmanip-legend .mm-row { display: flex; align-items: center; gap: 6px; white-space: nowrap; }
      #mobmanip-legend .mm-key { flex: none; width: 14px; height: 10px; box-sizing: border-box; }
      #mobmanip-legend .mm-ring { border: 2px solid; border-radius: 50%; background: transparent; }
      #mobmanip-legend .mm-dot { width: 10px; border-radius: 50%; border: 1px solid #666; }
      #mobmanip-legend .mm-note { color: #444; white-space: normal; }`;
    document.head.appendChild(css);
  }

  function showLegend(data) {
    let box = document.getElementById("mobmanip-legend");
    if (!box) {
      style();
      box = document.createElement("div");
      box.id = "mobmanip-legend";
      document.body.appendChild(box);
    }
    box.replaceChildren();
    const title = document.createElement("div");
    title.className = "mm-title";
    title.textContent = data.title || "";
    box.appendChild(title);
    for (const row of data.rows || []) {
      const line = document.createElement("div");
      line.className = "mm-row";
      const key = document.createElement("span");
      key.className = "mm-key mm-" + (row.style || "solid");
      if (row.style === "ring") key.style.borderColor = row.color;
      else key.style.background = row.color;
      const text = document.createElement("span");
      text.textContent = row.text;
      line.append(key, text);
      box.appendChild(line);
    }
    for (const note of data.notes || []) {
      const line = document.createElement("div");
      line.className = "mm-row mm-note";
      line.textContent = note;
      box.appendChild(line);
    }
  }

  // meshcat's world (z up) -> the camera's frame (three.js y up).
  const toThree = (p) => [p[0], p[2], -p[1]];

  function fitDistance(camera, target, direction, corners, margin) {
    // Smallest distance along `direction` (unit, target -> camera) at which every corner projects
    // inside `margin` of the view (perspective camera, vertical fov in degrees).
    const tanV = Math.tan((camera.fov * Math.PI) / 360) * margin;
    const tanH = tanV * camera.aspect;
    const f = direction.map((c) => -c);
    let r = [f[1], -f[0], 0];
    const nr = Math.hypot(r[0], r[1]) || 1;
    r = r.map((c) => c / nr);
    const u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]];
    let distance = 0.05;
    for (const p of corners) {
      const d = [p[0] - target[0], p[1] - target[1], p[2] - target[2]];
      const depth = d[0] * f[0] + d[1] * f[1] + d[2] * f[2];
      const x = Math.abs(d[0] * r[0] + d[1] * r[1] + d[2] * r[2]);
      const y = Math.abs(d[0] * u[0] + d[1] * u[1] + d[2] * u[2]);
      distance = Math.max(distance, x / tanH - depth, y / tanV - depth);
    }
    return distance;
  }

  function applyCamera(request) {
    const camera = viewer.camera;
    if (!camera || !viewer.controls) return false;
    let position = request.position;
    const target = request.target;
    if (request.mode === "fit") {
      const d = fitDistance(camera, target, request.direction, request.points, request.margin || 0.95);
      position = target.map((c, i) => c + d * request.direction[i]);
    }
    camera.position.set(...toThree(position));
    viewer.controls.target.set(...toThree(target));
    viewer.controls.update();
    viewer.set_dirty();
    return true;
  }

  function tick() {
    const data = pageData();
    if (!data) return;
    const key = JSON.stringify([data.title, data.rows, data.notes]);
    if (key !== legendKey) {
      showLegend(data);
      legendKey = key;
    }
    const camera = data.camera;
    if (camera && camera.serial !== cameraSerial && applyCamera(camera)) cameraSerial = camera.serial;
  }

  setInterval(tick, 100);
})();
