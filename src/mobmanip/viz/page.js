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
  // The legend never covers more than LEGEND_WIDTH % x LEGEND_HEIGHT % of the view (it scrolls
  // beyond); its notes fold under one line when, shown, the legend would cover more than
  // NOTES_SHARE of the view (a click shows them).
  const LEGEND_WIDTH = 38;
  const LEGEND_HEIGHT = 50;
  const NOTES_SHARE = 0.12;
  let legendKey = null;
  let cameraSerial = null;
  let notesToggled = false; // the user opened or closed the notes: leave them so

  function pageData() {
    if (typeof viewer === "undefined" || !viewer.scene_tree) return null;
    const root = viewer.scene_tree.children.meshcat;
    const node = root && root.children.mobmanip;
    return node && node.object ? node.object[PROPERTY] || null : null;
  }

  function style() {
    if (document.getElementById("mobmanip-style")) return;
    const css = document.createElement("style");
    css.id = "mobmanip-style";
    css.textContent = `
      #mobmanip-legend { position: absolute; left: 8px; bottom: 8px; z-index: 10;
        max-width: ${LEGEND_WIDTH}vw; max-height: ${LEGEND_HEIGHT}vh; overflow-y: auto;
        box-sizing: border-box; background: rgba(255, 255, 255, 0.88); color: #111;
        border-radius: 4px; padding: 4px 7px; font: 11px/1.3 system-ui, sans-serif; }
      #mobmanip-legend .mm-title { font-weight: 600; margin-bottom: 2px; }
      #mobmanip-legend .mm-row { display: flex; align-items: center; gap: 5px; }
      #mobmanip-legend .mm-key { flex: none; width: 12px; height: 9px; box-sizing: border-box; }
      #mobmanip-legend .mm-ring { border: 2px solid; border-radius: 50%; background: transparent; }
      #mobmanip-legend .mm-dot { width: 9px; border-radius: 50%; border: 1px solid #666; }
      #mobmanip-legend .mm-note { color: #444; white-space: normal; }
      #mobmanip-legend summary { color: #444; cursor: pointer; }
      .mobmanip-banner { position: absolute; left: 50%; transform: translateX(-50%); z-index: 10;
        max-width: 70vw; box-sizing: border-box; background: rgba(255, 255, 255, 0.88); color: #111;
        border-radius: 4px; padding: 3px 8px; font: 12px/1.3 system-ui, sans-serif; text-align: center; }
      #mobmanip-caption { top: 8px; }
      #mobmanip-progress { top: 34px; color: #444; }`;
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
    const notes = data.notes || [];
    if (notes.length) {
      const fold = document.createElement("details");
      const summary = document.createElement("summary");
      summary.textContent = notes.length === 1 ? "1 note" : `${notes.length} notes`;
      summary.addEventListener("click", () => { notesToggled = true; });
      fold.appendChild(summary);
      for (const note of notes) {
        const line = document.createElement("div");
        line.className = "mm-row mm-note";
        line.textContent = note;
        fold.appendChild(line);
      }
      box.appendChild(fold);
    }
    fitLegend();
  }

  function fitLegend() {
    // Show the notes when the legend stays small with them, else fold them.
    const box = document.getElementById("mobmanip-legend");
    const fold = box && box.querySelector("details");
    if (!fold || notesToggled) return;
    fold.open = true;
    const r = box.getBoundingClientRect();
    fold.open = r.width * r.height <= NOTES_SHARE * window.innerWidth * window.innerHeight;
  }
  window.addEventListener("resize", fitLegend);

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

  // A camera that follows an animation: request.targets[k] (world) at request.times[k] (s of
  // the animation), each frame's points request.frames[k] within `margin` of the view around its
  // own target; between keyframes the target moves linearly, as meshcat moves the robot.
  let follow = null;

  function animationTime() {
    const animator = viewer.animator;
    return animator && animator.actions.length ? animator.actions[0].time : 0;
  }

  function followTarget(t) {
    const times = follow.times;
    const targets = follow.targets;
    if (t <= times[0]) return targets[0];
    const last = times.length - 1;
    if (t >= times[last]) return targets[last];
    let k = 0;
    while (times[k + 1] < t) k += 1;
    const s = (t - times[k]) / (times[k + 1] - times[k] || 1);
    return targets[k].map((c, i) => c + s * (targets[k + 1][i] - c));
  }

  function followStep() {
    updateFollow();
    requestAnimationFrame(followStep);
  }

  function updateFollow() {
    // Move the camera and its orbit target together by the target's motion: the user's own
    // orbit, zoom and pan are kept, only carried along.
    if (follow && viewer.controls) {
      const target = toThree(followTarget(animationTime()));
      const shift = target.map((c, i) => c - follow.last[i]);
      if (shift.some((c) => c !== 0)) {
        viewer.camera.position.set(...shift.map((c, i) => c + viewer.camera.position.getComponent(i)));
        viewer.controls.target.set(...shift.map((c, i) => c + viewer.controls.target.getComponent(i)));
        viewer.controls.update();
        viewer.set_dirty();
        follow.last = target;
      }
    }
  }
  // For a test or a script that seeks the animation: bring the camera to the time now, at once.
  window.mobmanipFollow = updateFollow;
  // ... and the page's caption and progress.
  window.mobmanipTick = () => tick();

  function applyCamera(request) {
    const camera = viewer.camera;
    if (!camera || !viewer.controls) return false;
    let position = request.position;
    let target = request.target;
    follow = null;
    if (request.mode === "fit") {
      const d = fitDistance(camera, target, request.direction, request.points, request.margin || 0.95);
      position = target.map((c, i) => c + d * request.direction[i]);
    } else if (request.mode === "follow") {
      let d = 0;
      request.frames.forEach((points, k) => {
        d = Math.max(d, fitDistance(camera, request.targets[k], request.direction, points, request.margin));
      });
      follow = { times: request.times, targets: request.targets };
      target = followTarget(animationTime());
      position = target.map((c, i) => c + d * request.direction[i]);
      follow.last = toThree(target);
    }
    camera.position.set(...toThree(position));
    viewer.controls.target.set(...toThree(target));
    viewer.controls.update();
    viewer.set_dirty();
    return true;
  }

  // A banner at the top of the view (the animation's caption, the scene's progress), or none.
  function banner(id, text) {
    let box = document.getElementById(id);
    if (!text) {
      if (box) box.remove();
      return;
    }
    if (!box) {
      style();
      box = document.createElement("div");
      box.id = id;
      box.className = "mobmanip-banner";
      document.body.appendChild(box);
    }
    if (box.textContent !== text) box.textContent = text;
  }

  // The caption of the animation's frame at its current time: captions.texts[k] from
  // captions.times[k] (s) until the next one.
  function showCaption(captions) {
    if (!captions || !captions.times || !captions.times.length) {
      banner("mobmanip-caption", "");
      return;
    }
    const t = animationTime();
    let k = 0;
    while (k + 1 < captions.times.length && captions.times[k + 1] <= t + 1e-9) k += 1;
    banner("mobmanip-caption", captions.texts[k]);
  }

  // Whether the scene node at `path` (under /meshcat) holds an object somewhere below it.
  function holdsObject(node) {
    if (!node) return false;
    return Object.entries(node.children).some(([name, child]) => name === "<object>" || holdsObject(child));
  }

  function arrived(path) {
    let node = viewer.scene_tree.children.meshcat;
    for (const name of path.split("/")) node = node && node.children[name];
    return holdsObject(node);
  }

  // Until every part the page expects has arrived (the live page receives the scene over a
  // socket: the robot's meshes can take tens of seconds), say how many have.
  function showProgress(expect) {
    if (!expect || !expect.length) {
      banner("mobmanip-progress", "");
      return;
    }
    const got = expect.filter(arrived).length;
    const text = got < expect.length ? `receiving the scene: ${got} of ${expect.length} parts...` : "";
    banner("mobmanip-progress", text);
  }

  function tick() {
    const data = pageData();
    if (!data) return;
    showCaption(data.captions);
    showProgress(data.expect);
    const key = JSON.stringify([data.title, data.rows, data.notes]);
    if (key !== legendKey) {
      showLegend(data);
      legendKey = key;
    }
    const camera = data.camera;
    if (camera && camera.serial !== cameraSerial && applyCamera(camera)) cameraSerial = camera.serial;
  }

  setInterval(tick, 100);
  requestAnimationFrame(followStep);
})();
