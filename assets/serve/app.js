// chaoscope explorer: the map is Leaflet in CRS.Simple. The region of the plane shown (any
// two axes, the whole turn [-pi, pi]^2 of theta1 and theta2 by default, as tile 0/0/0; or a
// store's map) spans lng 0..units[0], lat -units[1]..0; every tile, point and trajectory is
// computed (or read) by the server from its URL. The page's state lives in the URL's hash.
"use strict";

const TURN = 2 * Math.PI;
const COLOURS = ["#f9a03f", "#4fc3f7", "#aed581", "#f06292", "#ba68c8", "#fff176"];
const KEYS = ["kind", "t_max", "cmap", "m1", "m2", "l1", "l2", "damping", "accurate",
  "unresolved", "lo", "hi", "x", "x_min", "x_max", "y", "y_min", "y_max",
  "theta1", "omega1", "theta2", "omega2"];
// What a store's command fixes.
const PHYSICS = ["t_max", "m1", "m2", "l1", "l2", "damping", "accurate"];
const PLANE = ["x", "x_min", "x_max", "y", "y_min", "y_max", "theta1", "omega1", "theta2",
  "omega2"];
const START = ["theta1", "omega1", "theta2", "omega2"];

const state = {};          // the view's settings, as query keys
const page = { starts: [], info: null, firstView: null, loads: 0, lastLoad: null };
window.chaoscope = page;   // for tests and the curious

const form = document.getElementById("controls");
const statusLine = document.getElementById("status");

// The plane shown: its axes (name, range), the region's size in level-0 units, and the
// axes' units per level-0 unit.
function world() {
  const s = page.info.store;
  const x = s ? s.x : { name: state.x, range: [Number(state.x_min), Number(state.x_max)] };
  const y = s ? s.y : { name: state.y, range: [Number(state.y_min), Number(state.y_max)] };
  // A plane not a store's is tile 0/0/0: 256 level-0 units a side.
  const units = s ? s.units : [256, 256];
  return { x, y, units, kx: (x.range[1] - x.range[0]) / units[0],
    ky: (y.range[1] - y.range[0]) / units[1] };
}
function xOf(lng) { const w = world(); return w.x.range[0] + lng * w.kx; }
function yOf(lat) { const w = world(); return w.y.range[1] + lat * w.ky; }
function lngOf(x) { const w = world(); return (x - w.x.range[0]) / w.kx; }
function latOf(y) { const w = world(); return (y - w.y.range[1]) / w.ky; }
function bounds() { const u = world().units; return [[-u[1], 0], [0, u[0]]]; }
function varInfo(name) { return page.info.vars.find((v) => v.name === name); }

// Whether a query key's value is set by an axis instead (a start component along it, or the
// parameter an axis writes).
function alongAxis(k) {
  const axes = [world().x.name, world().y.name].map(varInfo);
  const sets = k === "damping" ? ["joint1", "joint2"] : [k];
  return axes.some((v) => v.name === k || v.writes.some((w) => sets.includes(w)));
}

// The query string of the view's settings (only those that differ from the server's).
function query(extra) {
  const q = new URLSearchParams();
  for (const k of KEYS) {
    const v = state[k];
    if (v === undefined || v === "" || v === false) continue;
    if ((k === "lo" || k === "hi") && !kindInfo().ranged) continue;
    if (page.info.store && (PHYSICS.includes(k) || PLANE.includes(k))) continue;
    if (alongAxis(k) && !PLANE.slice(0, 6).includes(k)) continue;
    if (START.includes(k) && Number(v) === 0) continue;
    q.set(k, v === true ? "1" : String(v));
  }
  for (const [k, v] of Object.entries(extra || {})) q.set(k, String(v));
  return q.toString();
}

function readHash() {
  const h = new URLSearchParams(location.hash.slice(1));
  for (const k of KEYS) if (h.has(k)) state[k] = h.get(k);
  state.accurate = state.accurate === "1" || state.accurate === true;
  state.unresolved = state.unresolved === "1" || state.unresolved === true;
  // An axis named without its range gets its default one.
  for (const a of ["x", "y"]) if (h.has(a) && !h.has(`${a}_min`)) axisRange(a, state[a]);
  // The centre, along x and y.
  return { z: h.has("z") ? Number(h.get("z")) : null,
    cx: h.has("cx") ? Number(h.get("cx")) : null, cy: h.has("cy") ? Number(h.get("cy")) : null };
}

function writeHash() {
  const c = map.getCenter();
  const h = new URLSearchParams(query());
  h.set("z", map.getZoom());
  h.set("cx", xOf(c.lng).toPrecision(17));
  h.set("cy", yOf(c.lat).toPrecision(17));
  history.replaceState(null, "", "#" + h.toString());
}

function fillForm() {
  for (const k of KEYS) {
    const el = form.elements[k];
    if (!el) continue;
    if (el.type === "checkbox") el.checked = !!state[k]; else el.value = state[k] ?? "";
    const fixed = page.info.store && (PHYSICS.includes(k) || PLANE.includes(k));
    // A value an axis varies is not the form's: its input is off, and says so.
    const along = !PLANE.slice(0, 6).includes(k) && alongAxis(k);
    el.disabled = fixed || along;
    if (along) { el.value = ""; el.placeholder = "along an axis"; } else el.placeholder = "";
  }
  for (const a of ["x", "y"]) {
    const v = varInfo(world()[a].name);
    document.getElementById(`${a}-unit`).textContent = v.unit === "1" ? "" : `(${v.unit})`;
  }
  document.getElementById("ftle-range").hidden = !kindInfo().ranged;
  document.getElementById("range-unit").textContent = kindInfo().unit ? `(${kindInfo().unit})` : "";
  // A map without accurate settings (the flip kind is located with RK4 only).
  if (!kindInfo().accurate) state.accurate = false;
  form.elements.accurate.checked = !!state.accurate;
  form.elements.accurate.disabled = !kindInfo().accurate;
}

// How many steps of the finest an axis' pixels are at zoom z in a precision of machine
// epsilon `epsilon` (below 1: its pixels are no longer distinct; rules.js `finestStep`).
function resolves(axis, step, epsilon) {
  return step / finestStep(axis.range, varInfo(axis.name).angle, epsilon);
}

// The pixel's steps along x and y at zoom z, and what precision they need.
function precisionAt(z) {
  const w = world();
  const steps = [Math.abs(w.kx) / 2 ** z, Math.abs(w.ky) / 2 ** z];
  const below = (epsilon) => Math.min(resolves(w.x, steps[0], epsilon),
    resolves(w.y, steps[1], epsilon)) < 1;
  const info = page.info;
  if (info.store && z <= info.store.native) return [steps, `read from ${info.store.name}`];
  if (below(info.f64_epsilon)) return [steps, "beyond f64: no pixel is resolved"];
  const where = info.place === "the CPU" ? "CPU" : "GPU";
  if (state.accurate) return [steps, `f64 DP54 on the ${info.has_f64 ? where : "CPU"}`];
  if (below(info.f32_epsilon)) return [steps, `f64 on the ${info.has_f64 ? where : "CPU"}`];
  return [steps, `f32 on the ${where}`];
}

// A pixel's size in words: "1.23e-2 rad", or one step per axis when they differ.
function pixelWords(steps) {
  const w = world();
  const [ux, uy] = [varInfo(w.x.name).unit, varInfo(w.y.name).unit];
  const f = (v, u) => `${v.toExponential(2)}${u === "1" ? "" : " " + u}`;
  if (ux === uy && Math.abs(steps[0] - steps[1]) <= 1e-12 * steps[0]) return f(steps[0], ux);
  return `${f(steps[0], ux)} × ${f(steps[1], uy)}`;
}

// The zoom of the tiles in view: the view's zoom may be fractional (the first view fills the
// window), and Leaflet draws the nearest whole zoom's tiles scaled.
function tileZoom() {
  return Math.min(page.info.max_zoom, Math.max(0, Math.round(map.getZoom())));
}

function showStatus(extra, isError) {
  const z = tileZoom();
  const [steps, precision] = precisionAt(z);
  statusLine.className = isError ? "error" : "";
  statusLine.textContent = `zoom ${z} · pixel ${pixelWords(steps)} · ${precision}` +
    ` · tiles by ${page.info.place}` + (extra ? ` · ${extra}` : "");
}

// The kind of map shown, as the server's table describes it (/api/info's kinds).
function kindInfo() {
  return page.info.kinds.find((k) => k.name === state.kind) || {};
}

function legend() {
  document.getElementById("legend").textContent = (kindInfo().legend || "") +
    (state.unresolved && state.kind !== "resolved" ? " Grey: not resolved." : "");
  drawBar();
}

// The colour bar, from the server's colour tables (the tiles' own).
async function drawBar() {
  const bar = document.getElementById("bar");
  bar.hidden = state.kind === "resolved";
  if (bar.hidden) return;
  const r = await fetch("/api/legend?" + query());
  if (!r.ok) return;
  const { label, colors, ticks } = await r.json();
  const c = document.getElementById("bar-colours");
  const g = c.getContext("2d");
  colors.forEach(([red, green, blue], i) => {
    g.fillStyle = `rgb(${red},${green},${blue})`;
    const x0 = Math.floor((i * c.width) / colors.length);
    g.fillRect(x0, 0, Math.ceil(c.width / colors.length) + 1, c.height);
  });
  const holder = document.getElementById("bar-ticks");
  holder.textContent = "";
  for (const [f, text] of ticks) {
    const span = document.createElement("span");
    span.style.left = `${(f * 100).toFixed(2)}%`;
    span.textContent = text;
    holder.appendChild(span);
  }
  document.getElementById("bar-label").textContent = label;
}

let map, layer;

async function start() {
  page.info = await (await fetch("/api/info")).json();
  const d = page.info.defaults;
  Object.assign(state, { kind: "flip", t_max: d.t_max, cmap: "", m1: d.m1, m2: d.m2,
    l1: d.l1, l2: d.l2, damping: d.damping, accurate: false, unresolved: false,
    lo: "", hi: "", x: "theta1", y: "theta2", theta1: 0, omega1: 0, theta2: 0, omega2: 0 });
  for (const a of ["x", "y"]) {
    const menu = form.elements[a];
    for (const v of page.info.vars) {
      menu.add(new Option(`${v.symbol}${v.unit === "1" ? "" : ` (${v.unit})`}`, v.name));
    }
    axisRange(a, state[a]);
  }
  // The menu of maps is the server's table: a new quantity appears here by itself.
  for (const k of page.info.kinds) form.elements.kind.add(new Option(k.label, k.name));
  if (page.info.store) {
    const s = page.info.store;
    state.kind = s.kind;
    for (const o of [...form.elements.kind.options]) {
      if (o.value !== s.kind && o.value !== "resolved") o.remove();
    }
    Object.assign(state, { x: s.x.name, y: s.y.name, ...s.start, x_min: s.x.range[0],
      x_max: s.x.range[1], y_min: s.y.range[0], y_max: s.y.range[1] });
    document.getElementById("hint").textContent =
      `Showing the store ${s.name} (${s.width} x ${s.height}), made by: ${s.command}. ` +
      "Zoomed past its pixels, tiles are computed with its settings.";
  }
  const cmap = form.elements.cmap;
  cmap.add(new Option("default", ""));
  for (const c of page.info.colormaps) cmap.add(new Option(c, c));
  const view = readHash();
  fillForm();

  map = L.map("map", { crs: L.CRS.Simple, minZoom: 0, maxZoom: page.info.max_zoom,
    // Quarter steps, so the first view fills most of any window (whole steps left a
    // 1400 x 900 window two-thirds empty); the buttons and the wheel still step by one.
    zoomSnap: 0.25, zoomDelta: 1, wheelPxPerZoomLevel: 120, attributionControl: false,
    maxBounds: L.latLngBounds(bounds()).pad(0.5) });
  page.map = map;
  if (view.z === null) map.fitBounds(bounds());
  else map.setView([latOf(view.cy ?? 0), lngOf(view.cx ?? 0)], view.z);
  await setLayer();
  map.on("moveend", () => { writeHash(); showStatus(); });
  map.on("click", (e) => pick(e.latlng, e.originalEvent.shiftKey));
  form.addEventListener("change", onChange);
  document.getElementById("save-button").addEventListener("click", saveView);
  document.getElementById("zoom-button").addEventListener("click", () =>
    zoomFilm().catch((err) => { page.zoomCommand = null; showZoom(String(err)); }));
  legend();
}

async function setLayer() {
  if (kindInfo().ranged && (state.lo === "" || state.hi === "")) {
    const r = await fetch("/api/range?" + query());
    if (r.ok) {
      const { lo, hi } = await r.json();
      state.lo = Number(lo.toPrecision(3));
      state.hi = Number(hi.toPrecision(3));
      fillForm();
    }
  }
  if (layer) map.removeLayer(layer);
  page.loads = 0;
  // When the tiles in view started loading (the layer's, then each zoom's or pan's).
  let began = performance.now();
  layer = L.tileLayer("/tile/{z}/{x}/{y}.png?" + query(), {
    tileSize: 256, noWrap: true, bounds: bounds(),
    minZoom: 0, maxZoom: page.info.max_zoom, keepBuffer: 1, updateWhenZooming: false,
  });
  page.layer = layer;
  layer.on("load", () => {
    page.loads += 1;
    page.lastLoad = performance.now();
    if (page.firstView === null) page.firstView = page.lastLoad;
    document.body.dataset.tiles = "loaded";
    showStatus(`drawn in ${((page.lastLoad - began) / 1000).toFixed(2)} s`);
  });
  layer.on("loading", () => {
    began = performance.now();
    document.body.dataset.tiles = "loading";
    showStatus("computing…");
  });
  layer.on("tileerror", async (e) => {
    const r = await fetch(e.tile.src).catch(() => null);
    if (r && !r.ok && r.status !== 503) showStatus(await r.text(), true);
  });
  layer.addTo(map);
  writeHash();
  showStatus("computing…");
}

// An axis' range: its default for what it varies (the server's table).
function axisRange(a, name) {
  const r = varInfo(name).range;
  state[`${a}_min`] = r[0];
  state[`${a}_max`] = r[1];
}

function onChange(e) {
  const el = e.target;
  if (!(el.name in state)) return;
  const before = state[el.name];
  state[el.name] = el.type === "checkbox" ? el.checked : el.value;
  const plane = PLANE.includes(el.name);
  if (el.name === "x" || el.name === "y") {
    // Both axes on one thing: they trade places.
    const other = el.name === "x" ? "y" : "x";
    if (state[other] === state[el.name]) {
      state[other] = before;
      axisRange(other, before);
    }
    axisRange(el.name, state[el.name]);
  }
  if (el.name !== "lo" && el.name !== "hi" && kindInfo().ranged && (plane ||
    ["kind", "t_max", "m1", "m2", "l1", "l2", "damping"].includes(el.name))) {
    state.lo = ""; state.hi = "";   // a new physics, a new colour range
  }
  fillForm();
  if (plane) {
    // Another plane: the old view and clicks mean nothing on it.
    page.starts = [];
    for (const m of page.markers || []) m.remove();
    document.getElementById("pendulum").hidden = true;
    map.fitBounds(bounds());
  }
  setLayer().then(legend);
  if (page.starts.length) refreshStarts();
}

// The centre of the pixel under `latlng` at the current zoom, along x and y, and its size.
function pixelAt(latlng) {
  const w = world();
  const scale = 2 ** tileZoom();
  const col = Math.floor(latlng.lng * scale);
  const row = Math.floor(-latlng.lat * scale);
  return { x: w.x.range[0] + (col + 0.5) * w.kx / scale,
    y: w.y.range[1] - (row + 0.5) * w.ky / scale,
    dx: Math.abs(w.kx) / scale, dy: Math.abs(w.ky) / scale };
}

async function pick(latlng, add) {
  const u = world().units;
  if (latlng.lng < 0 || latlng.lng > u[0] || latlng.lat > 0 || latlng.lat < -u[1]) return;
  const p = pixelAt(latlng);
  if (!add) page.starts = [];
  if (page.starts.length >= COLOURS.length) page.starts.shift();
  page.starts.push(p);
  await refreshStarts();
}

async function load(p) {
  const where = { px: p.x, py: p.y };
  const [point, csv] = await Promise.all([
    fetch("/api/point?" + query({ ...where, pixel: p.dx, pixel_y: p.dy, kind: "flip" })),
    fetch("/api/trajectory?" + query({ ...where, kind: "flip" })),
  ]);
  if (!point.ok) throw new Error(await point.text());
  if (!csv.ok) throw new Error(await csv.text());
  const text = await csv.text();
  const lines = text.trim().split("\n");
  const rows = lines.slice(2).map((l) => l.split(",").map(Number));
  return { ...p, point: await point.json(), command: lines[0].replace(/^# /, ""), rows };
}

async function refreshStarts() {
  const section = document.getElementById("pendulum");
  section.hidden = false;
  document.body.dataset.pendulum = "loading";
  try {
    page.loaded = await Promise.all(page.starts.map(load));
  } catch (err) {
    showStatus(String(err.message || err), true);
    return;
  }
  const list = document.getElementById("starts");
  list.textContent = "";
  // Each start marked on the map in its colour.
  for (const m of page.markers || []) m.remove();
  page.markers = page.loaded.map((s, i) => L.circleMarker(
    [latOf(s.point.y), lngOf(s.point.x)],
    { radius: 6, color: COLOURS[i], weight: 2, fill: false, interactive: false }).addTo(map));
  page.loaded.forEach((s, i) => {
    const li = document.createElement("li");
    li.style.setProperty("--c", COLOURS[i]);
    const t = s.point.flip_time;
    const flip = typeof t === "number" ? `flips at ${t.toFixed(3)} s` :
      t === "never" ? `no flip within ${s.point.t_max} s` : "NaN (blew up)";
    const [vx, vy] = [varInfo(world().x.name), varInfo(world().y.name)];
    li.textContent = `${vx.symbol} ${s.point.x.toPrecision(7)}, ${vy.symbol} ${s.point.y.toPrecision(7)}: ${flip}` +
      ` (${s.point.precision}, ${s.point.resolved ? "resolved" : "NOT resolved"})`;
    list.appendChild(li);
  });
  document.getElementById("command").textContent = page.loaded[page.loaded.length - 1].command;
  drawPlot();
  document.body.dataset.pendulum = "shown";
  if (!page.animating) { page.animating = true; page.t0 = performance.now(); requestAnimationFrame(swing); }
  else page.t0 = performance.now();
}

// The pendulums at time t (s), looping over the trajectory.
function swing(now) {
  const c = document.getElementById("swing");
  const g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const starts = page.loaded || [];
  if (starts.length) {
    // Each pendulum's arms as its pixel has them (an axis may vary them).
    const l = Math.max(...starts.map((s) => s.point.params.l1 + s.point.params.l2));
    const scale = (c.width / 2 - 12) / l;
    const [cx, cy] = [c.width / 2, c.height / 2];
    const rows = starts[0].rows;
    const span = rows[rows.length - 1][0] + 1;
    const t = ((now - page.t0) / 1000) % span;
    starts.forEach((s, i) => {
      let k = s.rows.findIndex((r) => r[0] >= t);
      if (k < 0) k = s.rows.length - 1;
      const r = s.rows[k];
      // The lower bob's trail over the last second, fading.
      const from = Math.max(0, k - 50);
      g.lineWidth = 1;
      for (let j = from + 1; j <= k; j++) {
        g.globalAlpha = (j - from) / (k - from + 1) * 0.6;
        g.strokeStyle = COLOURS[i];
        g.beginPath();
        g.moveTo(cx + s.rows[j - 1][7] * scale, cy - s.rows[j - 1][8] * scale);
        g.lineTo(cx + s.rows[j][7] * scale, cy - s.rows[j][8] * scale);
        g.stroke();
      }
      g.globalAlpha = 1;
      const [x1, y1, x2, y2] = [cx + r[5] * scale, cy - r[6] * scale, cx + r[7] * scale, cy - r[8] * scale];
      g.strokeStyle = COLOURS[i]; g.fillStyle = COLOURS[i]; g.lineWidth = 2;
      g.beginPath(); g.moveTo(cx, cy); g.lineTo(x1, y1); g.lineTo(x2, y2); g.stroke();
      for (const [x, y] of [[x1, y1], [x2, y2]]) { g.beginPath(); g.arc(x, y, 6, 0, TURN); g.fill(); }
    });
    g.fillStyle = "#888"; g.beginPath(); g.arc(cx, cy, 3, 0, TURN); g.fill();
    g.fillStyle = "#aaa"; g.font = "12px system-ui";
    g.fillText(`t = ${t.toFixed(2)} s`, 8, 16);
  }
  requestAnimationFrame(swing);
}

function drawPlot() {
  const c = document.getElementById("plot");
  const g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const starts = page.loaded;
  const tMax = Math.max(...starts.map((s) => s.rows[s.rows.length - 1][0]));
  let lo = -Math.PI, hi = Math.PI;
  for (const s of starts) for (const r of s.rows) { lo = Math.min(lo, r[1], r[3]); hi = Math.max(hi, r[1], r[3]); }
  const X = (t) => 4 + (t / tMax) * (c.width - 8);
  const Y = (v) => c.height - 4 - ((v - lo) / (hi - lo)) * (c.height - 8);
  g.strokeStyle = "#333"; g.setLineDash([]);
  for (const v of [-Math.PI, Math.PI]) { g.beginPath(); g.moveTo(0, Y(v)); g.lineTo(c.width, Y(v)); g.stroke(); }
  starts.forEach((s, i) => {
    for (const [col, dash] of [[1, [4, 3]], [3, []]]) {
      g.strokeStyle = COLOURS[i]; g.setLineDash(dash); g.lineWidth = 1.2;
      g.beginPath();
      s.rows.forEach((r, k) => (k ? g.lineTo(X(r[0]), Y(r[col])) : g.moveTo(X(r[0]), Y(r[col]))));
      g.stroke();
    }
    const t = s.point.flip_time;
    if (typeof t === "number") {
      g.fillStyle = COLOURS[i]; g.beginPath(); g.arc(X(t), 6, 3, 0, TURN); g.fill();
    }
  });
  g.setLineDash([]);
}

function saveView() {
  const b = map.getBounds();
  const clamp = (v, a, z) => Math.min(z, Math.max(a, v));
  const u = world().units;
  const [west, east] = [clamp(b.getWest(), 0, u[0]), clamp(b.getEast(), 0, u[0])];
  const [south, north] = [clamp(b.getSouth(), -u[1], 0), clamp(b.getNorth(), -u[1], 0)];
  const width = Number(document.querySelector("#save select[name=width]").value);
  // Square pixels on the screen stay square in the file.
  const height = Math.max(16, Math.round(width * (north - south) / (east - west)));
  const annotate = document.querySelector("#save input[name=annotate]").checked;
  const url = "/api/save?" + query({ x_min: xOf(west), x_max: xOf(east), y_min: yOf(south),
    y_max: yOf(north), width, height: Math.min(height, 4096), annotate: annotate ? 1 : 0 });
  const link = document.createElement("a");
  link.href = url;
  link.download = `chaoscope-${state.kind}.png`;
  document.getElementById("save-status").textContent = "computing… (the download starts when done)";
  link.click();
}

// "Zoom film to here": the command of a film from the whole plane to the view on the screen
// (its centre, its width along x; the film's frames square, as the plane is on the screen).
async function zoomFilm() {
  const b = map.getBounds();
  const c = map.getCenter();
  const { x, y } = world();
  const [xw, yw] = [x.range[1] - x.range[0], y.range[1] - y.range[0]];
  // The end view is square on the screen, as the plane is, and inside the plane: as wide
  // as the screen's view at most the plane, its centre moved in where the view would reach out.
  const w = Math.min(xOf(b.getEast()) - xOf(b.getWest()), xw);
  const h = w * yw / xw;
  const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
  const cx = clamp(xOf(c.lng), x.range[0] + w / 2, x.range[1] - w / 2);
  const cy = clamp(yOf(c.lat), y.range[0] + h / 2, y.range[1] - h / 2);
  showZoom("planning…");
  const r = await fetch("/api/zoom?" + query({ cx, cy, w, width: 1080, height: 1080 }));
  if (!r.ok) throw new Error(await r.text());
  page.zoomCommand = (await r.json()).command;
  showZoom(page.zoomCommand);
}
function showZoom(text) {
  const el = document.getElementById("zoom-command");
  el.hidden = false;
  el.textContent = text;
}

start().catch((err) => { statusLine.className = "error"; statusLine.textContent = String(err); });
