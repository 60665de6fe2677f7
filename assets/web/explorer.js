// chaoscope in the browser: flip-time maps computed with WebGPU on the viewer's GPU. The
// physics is chaoscope's own WGSL (flip_time.wgsl, assembled as the engine assembles it);
// manifest.json says how its buffers are laid out (read from that WGSL), gives each
// pendulum's parameters as the engine uploads them, and the colours. This script only drives
// the kernel as src/gpu/flip_time.rs does and draws what it returns. The view lives in the
// address's hash, so a link opens the same view.
"use strict";

const page = { ready: false, error: null, views: 0, lost: 0, last: null, dispatches: 0 };
window.chaoscope = page;   // for tests and the curious

const canvas = document.getElementById("map");
const statusLine = document.getElementById("status");
const deepNote = document.getElementById("deep");
const form = document.getElementById("controls");
const progress = document.getElementById("progress");
const TURN = 2 * Math.PI;

let manifest = null;
let gpu = null;            // { device, layout, module, pipelines: Map }
let generation = 0;        // bumped by every new view: a computation of an older one stops
const view = { pendulum: 0, x: "theta1", y: "theta2", cx: 0, cy: 0, w: TURN,
  t_max: 20, dt: 0.01, colours: "inferno" };

function say(text, error) {
  statusLine.textContent = text;
  statusLine.classList.toggle("error", Boolean(error));
}

// ---- The view ----

// The grid of the view on a canvas of width x height pixels: each axis's range.
function grid(v, width, height) {
  const h = v.w * height / width;
  return { width, height, xVar: v.x, yVar: v.y,
    x: [v.cx - v.w / 2, v.cx + v.w / 2], y: [v.cy - h / 2, v.cy + h / 2] };
}

// src/spec/grid.rs `Axis::finest_step`: 16 ulp of the axis's largest value (angles: of pi
// at least, where they flip).
function finestStep(range, angle) {
  const eps = manifest.constants.f32_epsilon;
  const largest = Math.max(Math.abs(range[0]), Math.abs(range[1]), angle ? Math.PI : 0);
  return 16 * eps * Math.pow(2, Math.floor(Math.log2(largest)));
}

function varOf(name) { return manifest.vars.find((v) => v.name === name); }

// Whether f32 resolves the view's pixel step along both axes (the rule `zoom` uses).
function resolves(g) {
  const sx = (g.x[1] - g.x[0]) / g.width, sy = (g.y[1] - g.y[0]) / g.height;
  return sx >= finestStep(g.x, varOf(g.xVar).angle) && sy >= finestStep(g.y, varOf(g.yVar).angle);
}

// The command line that computes the same pixels.
function command(v, g) {
  const p = manifest.pendulums[v.pendulum];
  const values = { width: g.width, height: g.height, x_min: g.x[0], x_max: g.x[1],
    y_min: g.y[0], y_max: g.y[1], t_max: v.t_max, dt: v.dt, pendulum: p.flags,
    x: v.x, y: v.y };
  return manifest.command.replace(/\{(\w+)\}/g, (_, k) => String(values[k]));
}

// src/spec/mod.rs `Stepping::steps`.
function steps(t_max, dt) {
  const n = t_max / dt, rounded = Math.round(n);
  return Math.abs(n - rounded) < 1e-9 * Math.max(n, 1) ? rounded : Math.ceil(n);
}

function readHash() {
  const h = new URLSearchParams(location.hash.slice(1));
  for (const k of ["cx", "cy", "w", "t_max", "dt", "pendulum"]) {
    if (h.has(k) && Number.isFinite(Number(h.get(k)))) view[k] = Number(h.get(k));
  }
  for (const k of ["x", "y"]) if (h.has(k) && varOf(h.get(k))) view[k] = h.get(k);
  if (h.has("colours") && manifest.colours[h.get("colours")]) view.colours = h.get("colours");
  view.pendulum = Math.min(Math.max(0, Math.round(view.pendulum)), manifest.pendulums.length - 1);
}

function writeHash() {
  const q = new URLSearchParams();
  for (const k of ["x", "y", "cx", "cy", "w", "t_max", "dt", "pendulum", "colours"]) {
    q.set(k, String(view[k]));
  }
  history.replaceState(null, "", "#" + q.toString());
}

// ---- WebGPU ----

async function startGpu() {
  if (!navigator.gpu) throw new Error("no-webgpu");
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter) throw new Error("no-webgpu");
  const device = await adapter.requestDevice({ requiredLimits: {
    maxStorageBufferBindingSize: adapter.limits.maxStorageBufferBindingSize,
    maxBufferSize: adapter.limits.maxBufferSize } });
  const k = manifest.kernels.flip_time;
  const code = await (await fetch(k.file)).text();
  const module = device.createShaderModule({ code });
  const layout = device.createBindGroupLayout({ entries: k.bindings.map((b) => ({
    binding: b.binding, visibility: GPUShaderStage.COMPUTE, buffer: { type: b.type } })) });
  const state = { device, layout, module, kernel: k, pipelines: new Map(),
    pipelineLayout: device.createPipelineLayout({ bindGroupLayouts: [layout] }) };
  device.lost.then((info) => {
    // A lost device (a GPU reset, a driver's timeout): the next view starts a new one.
    if (gpu === state) gpu = null;
    page.lost += 1;
    if (info.reason !== "destroyed") {
      say(`The GPU was lost (${info.message || info.reason}); computing again…`, true);
      show();
    }
  });
  return state;
}

// flip_init and flip_time for `losses` (the kernel's LOSSES override), early exit on.
async function pipelines(g, losses) {
  if (!g.pipelines.has(losses)) {
    const make = (entry) => g.device.createComputePipelineAsync({
      layout: g.pipelineLayout,
      compute: { module: g.module, entryPoint: entry,
        constants: { LOSSES: losses, EARLY_EXIT: 1 } } });
    g.pipelines.set(losses, Promise.all([make("flip_init"), make("flip_time")]));
  }
  return g.pipelines.get(losses);
}

// The params uniform: the pendulum's words, then the view's fields by name.
function paramsOf(p, fields, size) {
  const bytes = new ArrayBuffer(size);
  new Uint32Array(bytes).set(p.params);
  const f32 = new Float32Array(bytes), u32 = new Uint32Array(bytes);
  const set = (name, value) => {
    const f = fields[name];
    if (!f) throw new Error(`no field ${name} in Params`);
    (f.type === "f32" ? f32 : u32)[f.offset / 4] = value;
  };
  return { bytes, set };
}

// The flip times of view `v` on a grid `g` (seconds; Infinity: never flipped within t-max;
// NaN: the integration left the numbers), as the engine's f32 kernel computes them.
async function flipTimes(v, g, onProgress) {
  if (!gpu) gpu = await startGpu();
  const mine = gpu, device = mine.device, k = mine.kernel, c = manifest.constants;
  const p = manifest.pendulums[v.pendulum];
  const [init, advance] = await pipelines(mine, p.losses);
  const pixels = g.width * g.height;
  // src/spec/grid.rs `point_symmetric`: starts in opposite pairs about the plane's centre
  // flip at the same time, so the top half (rounded up) is integrated and mirrored.
  const symmetric = 0.5 * (g.x[0] + g.x[1]) === 0 && 0.5 * (g.y[0] + g.y[1]) === 0;
  const integrated = symmetric ? Math.ceil(g.height / 2) : g.height;
  // Tiles of whole rows: memory bounded by the tile, not the view.
  const rowsPerTile = Math.max(1, Math.min(integrated, Math.floor((1 << 20) / g.width)));
  const capacity = rowsPerTile * g.width;
  const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
  const buffer = (size, u) => device.createBuffer({ size: Math.max(16, size), usage: u || usage });
  const params = buffer(k.params.size, GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST);
  const states = buffer(capacity * c.pendulum_bytes);
  const times = buffer(capacity * 4);
  const lists = [buffer(capacity * 4), buffer(capacity * 4)];
  const counter = buffer(4);
  const counterRead = buffer(4, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
  const timesRead = buffer(capacity * 4, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
  const byName = { params, states, times, counter };
  // Bind groups reading list a and writing list b, and the reverse.
  const bind = (from, to) => device.createBindGroup({ layout: mine.layout,
    entries: k.bindings.map((b) => ({ binding: b.binding, resource: { buffer:
      b.name === "active_in" ? from : b.name === "active_out" ? to : byName[b.name] } })) });
  const aToB = bind(lists[0], lists[1]), bToA = bind(lists[1], lists[0]);
  const out = new Float32Array(pixels);
  const total = steps(v.t_max, v.dt);
  const tMax = Math.fround(v.t_max);
  const u = paramsOf(p, k.params.fields, k.params.size);
  const x0 = g.x[0], x1 = g.x[1], y0 = g.y[0], y1 = g.y[1];
  // As src/gpu/layout.rs `with_grid` forms them, in f64, rounded once to f32.
  const fixed = { theta1: 0, omega1: 0, theta2: 0, omega2: 0 };
  u.set("dt", v.dt);
  u.set("x_mid", 0.5 * (x0 + x1));
  u.set("x_half_step", 0.5 * ((x1 - x0) / g.width));
  u.set("y_mid", 0.5 * (y0 + y1));
  u.set("y_half_step", 0.5 * ((y1 - y0) / g.height));
  u.set("x_var", varOf(v.x).code);
  u.set("y_var", varOf(v.y).code);
  for (const [name, value] of Object.entries(fixed)) u.set(name, value);
  u.set("width", g.width);
  u.set("height", g.height);
  u.set("t_max", v.t_max);
  const workgroups = (n) => {
    const groups = Math.max(1, Math.ceil(n / c.workgroup_size));
    const x = Math.min(groups, 65535);
    return [x, Math.ceil(groups / x)];
  };
  // One dispatch of `count` invocations; returns how many pixels it left active.
  const dispatch = async (pipeline, group, count) => {
    device.queue.writeBuffer(params, 0, u.bytes);
    device.queue.writeBuffer(counter, 0, new Uint32Array([0]));
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, group);
    pass.dispatchWorkgroups(...workgroups(count));
    pass.end();
    encoder.copyBufferToBuffer(counter, 0, counterRead, 0, 4);
    device.queue.submit([encoder.finish()]);
    await counterRead.mapAsync(GPUMapMode.READ);
    const n = new Uint32Array(counterRead.getMappedRange())[0];
    counterRead.unmap();
    return n;
  };
  const mineNow = generation;
  try {
    for (let row0 = 0; row0 < integrated; row0 += rowsPerTile) {
      const rows = Math.min(rowsPerTile, integrated - row0), n = rows * g.width;
      u.set("row0", row0); u.set("rows", rows); u.set("count", n);
      u.set("step0", 0); u.set("steps", 0);
      let active = await dispatch(init, bToA, n);
      let step0 = 0, forward = true;
      // src/gpu/tiled.rs `time_loop`: each dispatch holds at most steps_per_dispatch
      // pendulum-steps (a driver's watchdog; the browser stays responsive between them).
      while (step0 < total && active > 0) {
        if (mineNow !== generation) return null;
        const bounded = Math.max(Math.floor(c.steps_per_dispatch / active), c.min_steps);
        const s = Math.min(bounded, c.steps_per_invocation, total - step0);
        u.set("step0", step0); u.set("steps", s); u.set("count", active);
        active = await dispatch(advance, forward ? aToB : bToA, active);
        forward = !forward;
        step0 += s;
        page.dispatches += 1;
        onProgress((row0 + rows * step0 / total) / integrated);
      }
      const encoder = device.createCommandEncoder();
      encoder.copyBufferToBuffer(times, 0, timesRead, 0, n * 4);
      device.queue.submit([encoder.finish()]);
      await timesRead.mapAsync(GPUMapMode.READ);
      const t = new Float32Array(timesRead.getMappedRange(), 0, n);
      for (let i = 0; i < n; i++) {
        const x = t[i];
        out[row0 * g.width + i] = x === c.nonfinite ? NaN
          : (x === c.never || x > tMax) ? Infinity : x;
      }
      timesRead.unmap();
    }
    // src/field.rs `mirror_below`: pixel (col, row) is pixel (width-1-col, height-1-row).
    for (let i = integrated * g.width; i < pixels; i++) out[i] = out[pixels - 1 - i];
  } finally {
    for (const b of [params, states, times, ...lists, counter, counterRead, timesRead]) b.destroy();
  }
  return out;
}

// ---- Drawing ----

function table(name) {
  const hex = manifest.colours[name], n = hex.length / 6, rgb = new Uint8Array(n * 3);
  for (let i = 0; i < n * 3; i++) rgb[i] = parseInt(hex.substr(2 * i, 2), 16);
  return rgb;
}

// src/render/colormap.rs `flip_colors`: log time from t_lo (brightest) to t-max; never
// black, NaN green.
function draw(times, g, v) {
  const p = manifest.pendulums[v.pendulum], lut = table(v.colours), n = lut.length / 3;
  const lo = Math.log(p.t_lo), hi = Math.log(v.t_max);
  const image = new ImageData(g.width, g.height);
  for (let i = 0; i < times.length; i++) {
    const t = times[i];
    let r = 0, gr = 0, b = 0;
    if (Number.isNaN(t)) { gr = 255; } else if (Number.isFinite(t)) {
      const u = Math.min(1, Math.max(0, (Math.log(Math.max(t, p.t_lo)) - lo) / (hi - lo)));
      const j = Math.round(u * (n - 1)) * 3;
      r = lut[j]; gr = lut[j + 1]; b = lut[j + 2];
    }
    // Row 0 is the top (y at its maximum), as in the canvas.
    const o = i * 4;
    image.data[o] = r; image.data[o + 1] = gr; image.data[o + 2] = b; image.data[o + 3] = 255;
  }
  canvas.getContext("2d").putImageData(image, 0, 0);
}

function drawBar() {
  const bar = document.getElementById("bar-colours"), ctx = bar.getContext("2d");
  const lut = table(view.colours), n = lut.length / 3;
  for (let x = 0; x < bar.width; x++) {
    const j = Math.round(x / (bar.width - 1) * (n - 1)) * 3;
    ctx.fillStyle = `rgb(${lut[j]},${lut[j + 1]},${lut[j + 2]})`;
    ctx.fillRect(x, 0, 1, bar.height);
  }
  const p = manifest.pendulums[view.pendulum], lo = Math.log(p.t_lo), hi = Math.log(view.t_max);
  const ticks = document.getElementById("bar-ticks");
  ticks.replaceChildren();
  for (const t of [0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500]) {
    if (t < p.t_lo || t > view.t_max) continue;
    const s = document.createElement("span");
    s.style.left = `${100 * (Math.log(t) - lo) / (hi - lo)}%`;
    s.textContent = String(t);
    ticks.append(s);
  }
}

// ---- Computing the view ----

let pending = null;
async function show() {
  const g = grid(view, canvas.width, canvas.height);
  writeHash();
  drawBar();
  document.getElementById("command").textContent = command(view, g);
  const mine = ++generation;
  if (!resolves(g)) {
    deepNote.hidden = false;
    deepNote.textContent = "This view is deeper than f32 resolves (neighbouring pixels would " +
      "start from the same numbers): the browser has no f64. The command below computes it " +
      "in f64 on your machine.";
    say("Not computed here: zoom out, or run the command.");
    return;
  }
  deepNote.hidden = true;
  const started = performance.now();
  progress.hidden = false;
  say("computing on the GPU…");
  try {
    const times = await flipTimes(view, g, (f) => {
      progress.firstElementChild.style.width = `${(100 * f).toFixed(1)}%`;
      say(`computing on the GPU… ${(100 * f).toFixed(0)} %`);
    });
    if (times === null || mine !== generation) return;
    draw(times, g, view);
    const seconds = (performance.now() - started) / 1000;
    const flipped = times.filter(Number.isFinite).length / times.length;
    page.views += 1;
    page.last = { seconds, flipped, width: g.width, height: g.height };
    say(`${g.width} x ${g.height} pendulums over ${view.t_max} s in ${seconds.toFixed(2)} s ` +
      `on ${page.adapter}; ${(100 * flipped).toFixed(1)} % flipped.`);
  } catch (e) {
    if (mine === generation) say(`Could not compute: ${e.message}`, true);
  } finally {
    if (mine === generation) progress.hidden = true;
  }
}

// The canvas: a square filling the space beside the panel, one pixel a device pixel (at
// most 1024 a side: the work grows with the pixels).
function fit() {
  const box = document.getElementById("view");
  const side = Math.max(64, Math.min(box.clientWidth, box.clientHeight) - 16);
  const pixels = Math.min(1024, Math.round(side * (window.devicePixelRatio || 1)));
  canvas.style.width = canvas.style.height = `${side}px`;
  if (canvas.width !== pixels) {
    canvas.width = canvas.height = pixels;
    return true;
  }
  return false;
}

function later() {
  clearTimeout(pending);
  pending = setTimeout(show, 120);
}

// The plane's point under a canvas position (CSS pixels).
function pointAt(event) {
  const box = canvas.getBoundingClientRect();
  const fx = (event.clientX - box.left) / box.width, fy = (event.clientY - box.top) / box.height;
  const g = grid(view, canvas.width, canvas.height);
  return { x: g.x[0] + fx * (g.x[1] - g.x[0]), y: g.y[1] - fy * (g.y[1] - g.y[0]), fx, fy };
}

function wire() {
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const at = pointAt(e), k = Math.pow(1.0015, e.deltaY);
    view.cx = at.x + (view.cx - at.x) * k;
    view.cy = at.y + (view.cy - at.y) * k;
    view.w *= k;
    later();
  }, { passive: false });
  let drag = null;
  canvas.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, cx: view.cx, cy: view.cy, moved: false };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const box = canvas.getBoundingClientRect(), dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) > 3) drag.moved = true;
    canvas.style.transform = `translate(${dx}px, ${dy}px)`;
    view.cx = drag.cx - dx / box.width * view.w;
    view.cy = drag.cy + dy / box.height * view.w * canvas.height / canvas.width;
  });
  canvas.addEventListener("pointerup", (e) => {
    canvas.style.transform = "";
    if (drag && drag.moved) later(); else if (drag) describe(e);
    drag = null;
  });
  form.addEventListener("change", () => {
    const f = new FormData(form);
    view.pendulum = Number(f.get("pendulum"));
    view.x = f.get("x"); view.y = f.get("y");
    const t = Number(f.get("t_max")), dt = Number(f.get("dt"));
    if (t >= 0.1 && t <= 1000) view.t_max = t;
    if (dt >= 1e-4 && dt <= 0.1) view.dt = dt;
    view.colours = f.get("colours");
    later();
  });
  window.addEventListener("resize", () => { if (fit()) later(); });
  canvas.addEventListener("dblclick", (e) => {
    const at = pointAt(e);
    view.cx = at.x; view.cy = at.y; view.w /= 2;
    later();
  });
  document.getElementById("reset").addEventListener("click", () => {
    Object.assign(view, { cx: 0, cy: 0, w: TURN });
    later();
  });
}

// A clicked pixel: its start and its flip time, from the map shown.
function describe(e) {
  const at = pointAt(e);
  const box = document.getElementById("pixel");
  box.hidden = false;
  document.getElementById("pixel-text").textContent =
    `${view.x} = ${at.x.toPrecision(6)}, ${view.y} = ${at.y.toPrecision(6)}`;
}

function fillForm() {
  const options = (name, items) => {
    const s = form.elements[name];
    s.replaceChildren(...items.map(([value, text]) => new Option(text, value)));
  };
  options("pendulum", manifest.pendulums.map((p, i) => [String(i), p.name]));
  options("x", manifest.vars.map((v) => [v.name, v.name]));
  options("y", manifest.vars.map((v) => [v.name, v.name]));
  options("colours", Object.keys(manifest.colours).map((c) => [c, c]));
  form.elements.pendulum.value = String(view.pendulum);
  form.elements.x.value = view.x; form.elements.y.value = view.y;
  form.elements.t_max.value = view.t_max; form.elements.dt.value = view.dt;
  form.elements.colours.value = view.colours;
}

// For tests: the command line of a view on a width x height grid.
page.command = (v, width, height) => {
  const w = Object.assign({}, view, v);
  return command(w, grid(w, width, height));
};

// For tests: whether f32 resolves a view's pixel step on a width x height grid.
page.resolves = (v, width, height) => resolves(grid(Object.assign({}, view, v), width, height));

// For tests: the flip times of a view, as base64 of little-endian f32s.
// `page.computeSeconds` says how long the computation took (without the transfer).
page.flipTimes = async (v, width, height) => {
  const w = Object.assign({}, view, v), started = performance.now();
  const times = await flipTimes(w, grid(w, width, height), () => {});
  page.computeSeconds = (performance.now() - started) / 1000;
  let s = "";
  const bytes = new Uint8Array(times.buffer);
  for (let i = 0; i < bytes.length; i += 0x8000) {
    s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(s);
};

async function main() {
  manifest = await (await fetch("manifest.json")).json();
  readHash();
  fillForm();
  fit();
  wire();
  try {
    gpu = await startGpu();
    const info = gpu.device.adapterInfo || {};
    page.adapter = [info.vendor, info.architecture, info.description].filter(Boolean)
      .join(" ") || "this GPU";
  } catch (e) {
    page.error = e.message;
    say(e.message === "no-webgpu"
      ? "This browser offers no WebGPU, so the maps cannot be computed here. Chrome, Edge " +
        "and Safari 26 have it; Firefox on Windows too. Or install chaoscope and run " +
        "`chaoscope serve` (the explorer computing on your machine), or the command below."
      : `WebGPU did not start: ${e.message}`, true);
    document.getElementById("command").textContent =
      command(view, grid(view, canvas.width, canvas.height));
    return;
  }
  page.ready = true;
  show();
}

main();
