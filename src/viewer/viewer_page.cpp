#include "viewer/viewer_page.h"

namespace ferry {

const std::string& viewerPage() {
  static const std::string page = R"PAGE(<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>Ferry viewer</title>
<style>
  body { margin: 0; font: 13px/1.4 system-ui, sans-serif; background: #1b1d21; color: #d8dadf;
         display: flex; height: 100vh; }
  #view { flex: 1; display: flex; align-items: center; justify-content: center; overflow: hidden;
          touch-action: none; cursor: grab; user-select: none; }
  #view:active { cursor: grabbing; }
  #frame { width: 100%; height: 100%; object-fit: contain; }
  #side { width: 300px; padding: 12px 14px; background: #24272d; overflow-y: auto; }
  h1 { font-size: 15px; margin: 0 0 8px; }
  h2 { font-size: 12px; text-transform: uppercase; color: #9aa0aa; margin: 14px 0 6px; }
  label { display: flex; justify-content: space-between; margin: 3px 0; }
  input, select, button { font: inherit; background: #31353c; color: inherit; border: 1px solid #444a53;
                          border-radius: 3px; padding: 2px 5px; }
  input[type=number] { width: 80px; }
  button { cursor: pointer; margin: 6px 6px 0 0; }
  table { border-collapse: collapse; width: 100%; }
  td { padding: 1px 0; } td:last-child { text-align: right; font-variant-numeric: tabular-nums; }
  #error { color: #ff8a80; min-height: 1.4em; }
  .hint { color: #8b919b; font-size: 12px; }
</style>
</head>
<body>
<div id="view"><img id="frame" alt="the accumulated image" draggable="false"></div>
<div id="side">
  <h1>Ferry</h1>
  <div class="hint">Drag: orbit. Shift-drag or right-drag: pan. Wheel or pinch: zoom.
    W A S D, Q E: fly. One finger: orbit, two: zoom. Double-click: focus there.</div>
  <h2>View</h2>
  <label>named view <select id="views"></select></label>
  <h2>Settings</h2>
  <label>width <input id="width" type="number" min="1"></label>
  <label>height <input id="height" type="number" min="1"></label>
  <label>samples per frame <input id="spp" type="number" min="1"></label>
  <label>max depth <input id="depth" type="number" min="0"></label>
  <label>exposure (stops) <input id="exposure" type="number" step="0.25"></label>
  <label id="displayRow" hidden>show <select id="display"></select></label>
  <button id="apply">Apply</button><button id="quit">Quit</button>
  <h2>Depth of field</h2>
  <label>lens radius <input id="lens" type="number" min="0" step="0.01"></label>
  <label>focal distance <input id="focus" type="number" min="0" step="0.1"></label>
  <button id="lensApply">Apply</button><button id="focusCentre">Focus on the orbit centre</button>
  <div id="volume" hidden>
    <h2>Volume</h2>
    <label>opacity <span><input id="opacity" type="range" min="-8" max="8" step="0.25" value="0">
      <span id="opacityValue">1</span></span></label>
    <label>colour map <select id="colormap"></select></label>
  </div>
  <div id="fieldBox" hidden>
    <h2>Data</h2>
    <label>field <select id="field"></select></label>
    <div id="fieldState"></div>
  </div>
  <div id="error"></div>
  <h2>Stats</h2>
  <table id="stats"></table>
</div>
<script>
"use strict";
const $ = (id) => document.getElementById(id);
const img = $("frame");
let frameId = 0, camera = null, settingsShown = false, error = "";

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const len = (a) => Math.sqrt(dot(a, a));
const norm = (a) => mul(a, 1 / len(a));
// Rotates v about the unit axis k by angle t (Rodrigues).
const rotate = (v, k, t) => add(add(mul(v, Math.cos(t)), mul(cross(k, v), Math.sin(t))),
                                mul(k, dot(k, v) * (1 - Math.cos(t))));

function showError(message) { $("error").textContent = message || ""; }

async function post(path, body) {
  const r = await fetch(path, { method: "POST", body: JSON.stringify(body) });
  if (!r.ok) {
    let reason = r.statusText;
    try { reason = (await r.json()).error; } catch (e) {}
    showError(path + ": " + reason);
    return null;
  }
  showError("");
  return path === "/quit" ? {} : r.json();
}

// Camera changes go out at most every 30 ms (a timer, not an animation
// frame: those stop while the tab is hidden or the browser headless).
let cameraDirty = false;
function sendCamera() {
  if (cameraDirty) return;
  cameraDirty = true;
  setTimeout(async () => {
    await post("/camera", camera);
    cameraDirty = false;
  }, 30);
}

function orbit(dx, dy) {
  const up = norm(camera.up);
  let offset = sub(camera.from, camera.at);
  offset = rotate(offset, up, -dx * 0.005);
  const right = norm(cross(up, offset));
  const pitched = rotate(offset, right, -dy * 0.005);
  if (len(cross(norm(pitched), up)) > 0.02) offset = pitched;  // not over the pole
  camera.from = add(camera.at, offset);
  sendCamera();
}

function pan(dx, dy) {
  const forward = sub(camera.at, camera.from);
  const distance = len(forward);
  const right = norm(cross(norm(forward), camera.up));
  const up = norm(cross(right, norm(forward)));
  const scale = distance * Math.tan(camera.fov * Math.PI / 360) * 2 / Math.max(1, img.clientHeight);
  const move = add(mul(right, -dx * scale), mul(up, dy * scale));
  camera.from = add(camera.from, move);
  camera.at = add(camera.at, move);
  sendCamera();
}

function zoom(factor) {
  const offset = sub(camera.from, camera.at);
  camera.from = add(camera.at, mul(offset, Math.min(Math.max(factor, 0.2), 5)));
  sendCamera();
}

function fly(forwardStep, rightStep, upStep) {
  const forward = sub(camera.at, camera.from);
  const step = len(forward) * 0.05;
  const f = norm(forward), r = norm(cross(f, camera.up)), u = norm(camera.up);
  const move = add(add(mul(f, forwardStep * step), mul(r, rightStep * step)), mul(u, upStep * step));
  camera.from = add(camera.from, move);
  camera.at = add(camera.at, move);
  sendCamera();
}

// Mouse and touch on the image.
const view = $("view");
let dragging = null;
view.addEventListener("contextmenu", (e) => e.preventDefault());
view.addEventListener("pointerdown", (e) => {
  if (!camera) return;
  view.setPointerCapture(e.pointerId);
  dragging = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
});
view.addEventListener("pointermove", (e) => {
  if (!dragging || touches.size > 1) return;
  const dx = e.clientX - dragging.x, dy = e.clientY - dragging.y;
  dragging.x = e.clientX; dragging.y = e.clientY;
  if (dragging.pan) pan(dx, dy); else orbit(dx, dy);
});
view.addEventListener("pointerup", () => { dragging = null; });
view.addEventListener("wheel", (e) => {
  e.preventDefault();
  if (camera) zoom(Math.exp(e.deltaY * 0.001));
}, { passive: false });
const touches = new Map();
let pinch = 0;
view.addEventListener("touchstart", (e) => {
  for (const t of e.changedTouches) touches.set(t.identifier, t);
  if (touches.size === 2) {
    const [a, b] = [...touches.values()];
    pinch = Math.hypot(a.clientX - b.clientX, a.clientY - b.clientY);
  }
}, { passive: true });
view.addEventListener("touchmove", (e) => {
  for (const t of e.changedTouches) touches.set(t.identifier, t);
  if (touches.size === 2 && camera) {
    const [a, b] = [...touches.values()];
    const d = Math.hypot(a.clientX - b.clientX, a.clientY - b.clientY);
    if (pinch > 0 && d > 0) zoom(pinch / d);
    pinch = d;
  }
}, { passive: true });
view.addEventListener("touchend", (e) => {
  for (const t of e.changedTouches) touches.delete(t.identifier);
  pinch = 0;
}, { passive: true });
document.addEventListener("keydown", (e) => {
  if (!camera || e.target.tagName === "INPUT") return;
  const keys = { w: [1, 0, 0], s: [-1, 0, 0], a: [0, -1, 0], d: [0, 1, 0], e: [0, 0, 1], q: [0, 0, -1] };
  const k = keys[e.key.toLowerCase()];
  if (k) fly(...k);
});

$("views").addEventListener("change", () => post("/settings", { view: $("views").value }));
$("apply").addEventListener("click", () => post("/settings", {
  width: Number($("width").value), height: Number($("height").value), spp: Number($("spp").value),
  max_depth: Number($("depth").value), exposure: Number($("exposure").value) }));
// The volume's look: the opacity scale on a log2 slider, the colour map by
// name ("" is each volume's own); either restarts the accumulation.
const showOpacity = () => {
  $("opacityValue").textContent = (2 ** Number($("opacity").value)).toPrecision(3);
};
$("opacity").addEventListener("input", showOpacity);
$("opacity").addEventListener("change", () => {
  showOpacity();
  post("/settings", { volume_opacity: 2 ** Number($("opacity").value) });
});
$("colormap").addEventListener("change", () => post("/settings", { color_map: $("colormap").value }));
// Another array of the VTK data: the ranks read the scene again.
$("field").addEventListener("change", () => post("/settings", { field: $("field").value }));
// The colour or one of the AOVs the frames hold (the accumulation goes on).
$("display").addEventListener("change", () => post("/settings", { display: $("display").value }));
// The thin lens travels with the camera (radius 0: a pinhole).
function showLens() {
  $("lens").value = camera.lens_radius; $("focus").value = Number(camera.focal_distance.toPrecision(6));
}
$("lensApply").addEventListener("click", () => {
  if (!camera) return;
  camera.lens_radius = Number($("lens").value);
  camera.focal_distance = Number($("focus").value);
  sendCamera();
});
// Double-click: focus on the surface under the pointer (the ranks find it).
// The point as fractions of the image, which object-fit may letterbox.
view.addEventListener("dblclick", (e) => {
  if (!img.naturalWidth) return;
  const r = img.getBoundingClientRect();
  const scale = Math.min(r.width / img.naturalWidth, r.height / img.naturalHeight);
  const w = img.naturalWidth * scale, h = img.naturalHeight * scale;
  const x = (e.clientX - r.left - (r.width - w) / 2) / w, y = (e.clientY - r.top - (r.height - h) / 2) / h;
  if (x < 0 || x > 1 || y < 0 || y > 1) return;
  // After the camera change still on its way (a drag's last): it carries
  // the old focal distance, and would undo the pick if it came second.
  const focus = () => cameraDirty ? setTimeout(focus, 10) : post("/focus", { x, y });
  focus();
});
$("focusCentre").addEventListener("click", () => {
  if (!camera) return;
  camera.focal_distance = len(sub(camera.at, camera.from));
  showLens();
  sendCamera();
});
$("quit").addEventListener("click", async () => {
  await post("/quit", {});
  showError("the viewer was asked to quit");
});

const mib = (b) => (b / 1048576).toFixed(1) + " MiB";
const count = (n) => n >= 1e6 ? (n / 1e6).toFixed(2) + " M" : n >= 1e3 ? (n / 1e3).toFixed(1) + " K" : String(n);

function showStats(s) {
  const requested = s.requested;
  if (!camera || !cameraDirty) camera = requested.camera;
  // The lens fields follow the camera (a focus pick changes it) unless being edited.
  if (![$("lens"), $("focus")].includes(document.activeElement)) showLens();
  if (!settingsShown) {
    const st = requested.settings;
    $("width").value = st.width; $("height").value = st.height; $("spp").value = st.spp;
    $("depth").value = st.max_depth; $("exposure").value = st.exposure;
    const select = $("views");
    select.replaceChildren(...s.views.map((v) => new Option(v, v)));
    if (s.displays) {
      $("displayRow").hidden = false;
      $("display").replaceChildren(...s.displays.map((d) => new Option(d, d)));
      $("display").value = st.display;
    }
    if (s.color_maps) {
      $("volume").hidden = false;
      $("colormap").replaceChildren(new Option("(the volume's own)", ""),
                                    ...s.color_maps.map((m) => new Option(m, m)));
      $("colormap").value = st.color_map;
      $("opacity").value = Math.log2(st.volume_opacity);
      $("opacityValue").textContent = st.volume_opacity.toPrecision(3);
    }
    settingsShown = true;
  }
  // The arrays with their ranges; the one shown, or the one being read.
  if (s.fields) {
    $("fieldBox").hidden = false;
    const text = (f) => `${f.name} (${f.at}${f.components > 1 ? ", magnitude" : ""}) ` +
                        `[${f.range[0].toPrecision(4)}, ${f.range[1].toPrecision(4)}]`;
    const key = JSON.stringify(s.fields);
    if ($("field").dataset.key !== key) {
      $("field").replaceChildren(...s.fields.map((f) => new Option(text(f), f.name)));
      $("field").dataset.key = key;
    }
    if (document.activeElement !== $("field")) $("field").value = s.loading_field || s.field;
    $("fieldState").textContent = s.loading_field ? `reading '${s.loading_field}'...` : "";
  }
  const f = s.frame || {}, ex = f.exchange || {}, st = f.stage_seconds || {}, tr = f.traces || {};
  const mem = s.memory_per_rank || [];
  const rows = [
    ["frames accumulated", s.frames], ["ranks", s.ranks],
    ["frame time", f.seconds !== undefined ? f.seconds.toFixed(3) + " s" : "-"],
    ["rays traced / frame", count(tr.total || 0)], ["rays forwarded / frame", count(ex.rays_forwarded || 0)],
    ["bytes sent / frame", mib(ex.bytes_sent || 0)],
    ["exchange rounds / messages", (ex.rounds || 0) + " / " + (ex.messages || 0)],
    ["largest rank, resident", mem.length ? mib(Math.max(...mem.map((m) => m.resident_bytes))) : "-"],
    ["largest rank, estimated", mem.length ? mib(Math.max(...mem.map((m) => m.estimated_bytes))) : "-"],
  ];
  for (const k of ["generate", "trace", "exchange", "shade", "wait", "composite"])
    if (st[k] !== undefined) rows.push([k + " (s, all ranks)", st[k].toFixed(3)]);
  $("stats").replaceChildren(...rows.map(([k, v]) => {
    const tr = document.createElement("tr");
    tr.append(Object.assign(document.createElement("td"), { textContent: k }),
              Object.assign(document.createElement("td"), { textContent: v }));
    return tr;
  }));
}

// The frame loop: wait for a frame newer than the one shown, show it, read the stats.
async function loop() {
  for (;;) {
    try {
      const r = await fetch("/frame.png?after=" + frameId, { cache: "no-store" });
      if (r.ok) {
        frameId = Number(r.headers.get("X-Ferry-Frame"));
        const url = URL.createObjectURL(await r.blob());
        await new Promise((done) => { img.onload = img.onerror = done; img.src = url; });
        const old = img.dataset.url;
        img.dataset.url = url;
        if (old) URL.revokeObjectURL(old);
      }
      showStats(await (await fetch("/stats", { cache: "no-store" })).json());
    } catch (e) {
      showError("the viewer is not answering (" + e.message + ")");
      await new Promise((done) => setTimeout(done, 1000));
    }
  }
}
loop();
</script>
</body>
</html>
)PAGE";
  return page;
}

}  // namespace ferry
