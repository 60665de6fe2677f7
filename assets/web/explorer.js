// chaoscope in the browser: flip-time maps computed with WebGPU on the viewer's GPU. The
// physics is chaoscope's own WGSL (flip_time.wgsl, assembled as the engine assembles it);
// manifest.json says how its buffers are laid out (read from that WGSL), gives each
// pendulum's parameters as the engine uploads them, and the colours. This script only drives
// the kernel as src/gpu/flip_time.rs does and draws what it returns. The view lives in the
// address's hash, so a link opens the same view.
"use strict";

const page = { ready: false, error: null, views: 0, lost: 0, last: null, refused: [],
  errors: [] };
window.chaoscope = page;   // for tests and the curious
// Anything the script did not catch, kept where a test can read it.
window.addEventListener("error", (e) => page.errors.push(String(e.message)));
window.addEventListener("unhandledrejection", (e) => page.errors.push(String(e.reason)));

const canvas = document.getElementById("map");
const statusLine = document.getElementById("status");
const deepNote = document.getElementById("deep");
const form = document.getElementById("controls");
const progress = document.getElementById("progress");
const TURN = 2 * Math.PI;

let manifest = null;
let gpu = null;            // { device, layout, module, pipelines: Map }
let generation = 0;        // bumped by every new view: a computation of an older one stops
const view = { pendulum: 0, x: "theta1", y: "theta2", cx: 0, cy: 0, w: TURN, h: TURN,
  t_max: 20, dt: 0.01, colours: "inferno", kind: "flip", setting: 0, verdict: false,
  // The start's angles where no axis sets them (rad; released from rest).
  theta1: 0, theta2: 0 };

// The start's angles the view fixes (those no axis sets), by name.
function fixedAngles(v) {
  return ["theta1", "theta2"].filter((name) => v.x !== name && v.y !== name);
}

function say(text, error) {
  statusLine.textContent = text;
  statusLine.classList.toggle("error", Boolean(error));
}

// ---- The view ----

// The grid of the view on a canvas of width x height pixels: each axis's range (the view's
// width along x and height along y about its centre).
function grid(v, width, height) {
  return { width, height, xVar: v.x, yVar: v.y,
    x: [v.cx - v.w / 2, v.cx + v.w / 2], y: [v.cy - v.h / 2, v.cy + v.h / 2] };
}

// The parameters along the view's axes, by name, sorted: a key of a pendulum's flags.
function parameterAxes(v) {
  return [v.x, v.y].filter((name) => !varOf(name).state).sort().join(",");
}

// Whether the two axes set the same value (src/spec/var.rs `overlaps`): no plane.
function overlapping(v) {
  const a = varOf(v.x).writes, b = varOf(v.y).writes;
  return a.some((w) => b.includes(w));
}

// The values axis `name` may take (src/spec/var.rs `limits`); null: no bound.
function limitsOf(name) {
  const [lo, hi] = varOf(name).limits;
  return [lo === null ? -Infinity : lo, hi === null ? Infinity : hi];
}

// View `v` with its angle axes within the turn the engine accepts (a start beyond pi has
// already flipped): zooming out stops at the whole turn, panning at its edge.
function confine(v) {
  for (const [name, c, size] of [[v.x, "cx", "w"], [v.y, "cy", "h"]]) {
    if (!varOf(name).angle) continue;
    const [lo, hi] = limitsOf(name);
    v[size] = Math.min(v[size], hi - lo);
    v[c] = Math.min(Math.max(v[c], lo + v[size] / 2), hi - v[size] / 2);
  }
  return v;
}

// The first of grid `g`'s axes that leaves the values the engine accepts, in words; null
// if none does.
function outside(g) {
  for (const [name, r] of [[g.xVar, g.x], [g.yVar, g.y]]) {
    const [lo, hi] = limitsOf(name), unit = varOf(name).unit === "1" ? "" : ` ${varOf(name).unit}`;
    if (r[0] < lo || r[1] > hi) {
      return `${name} from ${r[0].toPrecision(5)} to ${r[1].toPrecision(5)}${unit} leaves ` +
        `its range (${lo} to ${hi}${unit}): pan or zoom in.`;
    }
  }
  return null;
}

function varOf(name) { return manifest.vars.find((v) => v.name === name); }

// Whether f32 resolves the view's pixel step along both axes (the rule `zoom` uses).
function resolves(g) {
  const sx = (g.x[1] - g.x[0]) / g.width, sy = (g.y[1] - g.y[0]) / g.height;
  const eps = manifest.constants.f32_epsilon;
  return sx >= finestStep(g.x, varOf(g.xVar).angle, eps) &&
    sy >= finestStep(g.y, varOf(g.yVar).angle, eps);
}

// The command line that computes the same pixels.
function command(v, g) {
  const p = manifest.pendulums[v.pendulum];
  const start = fixedAngles(v).filter((name) => v[name] !== 0)
    .map((name) => ` --${name} ${v[name]}`).join("");
  const values = { width: g.width, height: g.height, x_min: g.x[0], x_max: g.x[1],
    y_min: g.y[0], y_max: g.y[1], t_max: v.t_max, dt: v.dt, start,
    pendulum: p.flags[parameterAxes(v)],
    x: v.x, y: v.y, colours: v.colours, verdict: v.verdict ? " --show-unresolved" : "" };
  return measureOf(v).command.replace(/\{(\w+)\}/g, (_, k) => String(values[k]));
}

// The view of the address's hash, each value held to the rules the controls keep (the
// bounds in manifest.json, the names it lists, own properties only): returns what it refused,
// in words (none: the link's view is the page's).
function readHash() {
  const h = new URLSearchParams(location.hash.slice(1)), refused = [];
  const b = manifest.bounds, n = manifest.pendulums.length;
  const between = ([lo, hi], unit) => [(x) => x >= lo && x <= hi, `from ${lo} to ${hi}${unit}`];
  const numbers = {
    t_max: between(b.t_max, " s"), dt: between(b.dt, " s"),
    cx: [() => true, "a number"], cy: [() => true, "a number"],
    w: [(x) => x > 0, "a width above 0"], h: [(x) => x > 0, "a height above 0"],
    pendulum: [(x) => Number.isInteger(x) && x >= 0 && x < n, `a whole number from 0 to ${n - 1}`],
    theta1: between(limitsOf("theta1"), " rad"), theta2: between(limitsOf("theta2"), " rad"),
  };
  const oneOf = (names) => `one of ${names.join(", ")}`;
  const words = {
    x: [varOf, oneOf(manifest.vars.map((v) => v.name))],
    y: [varOf, oneOf(manifest.vars.map((v) => v.name))],
    kind: [kindOf, oneOf(manifest.kinds.map((k) => k.name))],
    colours: [(c) => Object.hasOwn(manifest.colours, c), oneOf(Object.keys(manifest.colours))],
    verdict: [(s) => s === "0" || s === "1", "0 or 1"],
  };
  for (const [k, raw] of h) {
    const shown = raw.length > 24 ? `${raw.slice(0, 24)}…` : raw;
    if (Object.hasOwn(numbers, k)) {
      const x = raw.trim() === "" ? NaN : Number(raw), [ok, rule] = numbers[k];
      if (Number.isFinite(x) && ok(x)) view[k] = x;
      else refused.push(`${k} = ${shown} (${rule})`);
    } else if (k === "setting") {
      continue;
    } else if (Object.hasOwn(words, k)) {
      const [ok, rule] = words[k];
      if (ok(raw)) view[k] = k === "verdict" ? raw === "1" : raw;
      else refused.push(`${k} = ${shown} (${rule})`);
    } else {
      refused.push(`${k.length > 24 ? `${k.slice(0, 24)}…` : k}: no such setting`);
    }
  }
  // An axis named without its region gets its variable's whole range; a width without a
  // height, a square view.
  for (const k of ["x", "y"]) {
    const [c, size] = k === "x" ? ["cx", "w"] : ["cy", "h"];
    if (h.has(k) && varOf(h.get(k)) && !h.has(c) && !h.has(size)) wholeAxis(k);
  }
  if (h.has("w") && !h.has("h")) view.h = view.w;
  // A setting is one of its kind's (read after the kind, whichever the link gives first).
  if (h.has("setting")) {
    const raw = h.get("setting"), x = raw.trim() === "" ? NaN : Number(raw);
    const n = settingsOf(view.kind).length;
    if (Number.isInteger(x) && x >= 0 && x < n) view.setting = x;
    else refused.push(`setting = ${raw.slice(0, 24)} (a whole number from 0 to ${n - 1} for ${view.kind})`);
  }
  return refused;
}

function writeHash() {
  const q = new URLSearchParams();
  for (const k of ["kind", "x", "y", "cx", "cy", "w", "h", "t_max", "dt", "pendulum", "colours"]) {
    q.set(k, String(view[k]));
  }
  if (view.setting) q.set("setting", String(view.setting));
  for (const name of fixedAngles(view)) if (view[name] !== 0) q.set(name, String(view[name]));
  if (view.verdict) q.set("verdict", "1");
  history.replaceState(null, "", "#" + q.toString());
}

// ---- WebGPU ----

async function startGpu() {
  if (!navigator.gpu) throw new Error("no-webgpu");
  // After a loss the browser may take a moment to offer an adapter again (its GPU process
  // restarting): a few tries, a second apart.
  let adapter = await navigator.gpu.requestAdapter();
  for (let tries = 0; !adapter && page.lost > 0 && tries < 10; tries++) {
    await new Promise((wake) => setTimeout(wake, 1000));
    adapter = await navigator.gpu.requestAdapter();
  }
  if (!adapter) throw new Error("no-webgpu");
  const device = await adapter.requestDevice({ requiredLimits: {
    maxStorageBufferBindingSize: adapter.limits.maxStorageBufferBindingSize,
    maxBufferSize: adapter.limits.maxBufferSize } });
  const state = { device, kernels: new Map(), pipelines: new Map() };
  device.lost.then((info) => {
    // A lost device (a GPU reset, a driver's timeout, the browser's GPU process gone): the
    // view in progress fails, and is computed again on a new device.
    if (gpu === state) gpu = null;
    page.lost += 1;
    if (info.reason !== "destroyed") {
      say(`The GPU was lost (${info.message || info.reason}); computing again…`, true);
      show();
    }
  });
  return state;
}

// The GPU, started anew when there is none (the first view, or after a loss); callers that
// come while one starts share it.
let starting = null;
async function ready() {
  if (!gpu) {
    starting = starting || startGpu().finally(() => { starting = null; });
    gpu = await starting;
  }
  return gpu;
}

// A kernel's module and layouts, made on first use: its bindings as manifest.json lists them.
async function kernelOf(g, name) {
  if (!g.kernels.has(name)) {
    g.kernels.set(name, (async () => {
      const k = manifest.kernels[name];
      const code = await (await fetch(k.file)).text();
      const layout = g.device.createBindGroupLayout({ entries: k.bindings.map((b) => ({
        binding: b.binding, visibility: GPUShaderStage.COMPUTE, buffer: { type: b.type } })) });
      return { k, layout, module: g.device.createShaderModule({ code }),
        pipelineLayout: g.device.createPipelineLayout({ bindGroupLayouts: [layout] }) };
    })());
  }
  return g.kernels.get(name);
}

// The pipelines of `entries` of kernel `name` with the overrides `constants`.
async function pipelines(g, name, entries, constants) {
  const key = JSON.stringify([name, entries, constants]);
  if (!g.pipelines.has(key)) {
    const kernel = await kernelOf(g, name);
    const make = (entry) => g.device.createComputePipelineAsync({
      layout: kernel.pipelineLayout,
      compute: { module: kernel.module, entryPoint: entry, constants } });
    g.pipelines.set(key, Promise.all(entries.map(make)));
  }
  return g.pipelines.get(key);
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

function kindOf(name) { return manifest.kinds.find((k) => k.name === name); }

// The settings the page offers for a kind's indicator (manifest.json's, its default first).
function settingsOf(name) { return kindOf(name).settings || [kindOf(name)]; }

// What view `v` maps: its kind at its setting (the measure's entries, setting, range rule,
// labels and command line, as src/web.rs `variants` lists them).
function measureOf(v) { return settingsOf(v.kind)[v.setting] || kindOf(v.kind); }

// What every kernel's run shares: the params set for view `v` on grid `g` (as
// src/gpu/layout.rs `with_grid` forms them: in f64, rounded once to f32), the rows to
// integrate (src/spec/grid.rs `point_symmetric`: starts in opposite pairs about the plane's
// centre end alike, so the top half, rounded up, is integrated and the rest mirrored as
// src/field.rs `mirror_below` does), tiles of whole rows that bound memory, buffers.
function setUp(v, g, k) {
  const device = gpu.device, p = manifest.pendulums[v.pendulum];
  const u = paramsOf(p, k.params.fields, k.params.size);
  const x0 = g.x[0], x1 = g.x[1], y0 = g.y[0], y1 = g.y[1];
  // An axis measured in mass in the engine's mass scale.
  const sx = varOf(v.x).mass ? p.mass_scale : 1, sy = varOf(v.y).mass ? p.mass_scale : 1;
  u.set("dt", v.dt);
  u.set("x_mid", 0.5 * (x0 + x1) * sx);
  u.set("x_half_step", 0.5 * ((x1 - x0) / g.width) * sx);
  u.set("y_mid", 0.5 * (y0 + y1) * sy);
  u.set("y_half_step", 0.5 * ((y1 - y0) / g.height) * sy);
  u.set("x_var", varOf(v.x).code);
  u.set("y_var", varOf(v.y).code);
  // The start's fixed part (the axes' components are each pixel's own).
  for (const name of ["omega1", "omega2"]) u.set(name, 0);
  for (const name of ["theta1", "theta2"]) u.set(name, v[name]);
  u.set("width", g.width);
  u.set("height", g.height);
  u.set("t_max", v.t_max);
  // Mirrored only where the fixed start is zero too (src/spec/grid.rs `point_symmetric`).
  const symmetric = 0.5 * (x0 + x1) === 0 && 0.5 * (y0 + y1) === 0 && parameterAxes(v) === "" &&
    fixedAngles(v).every((name) => v[name] === 0);
  const integrated = symmetric ? Math.ceil(g.height / 2) : g.height;
  const rowsPerTile = Math.max(1, Math.min(integrated, Math.floor((1 << 20) / g.width)));
  const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
  const made = [];
  const buffer = (size, use) => {
    const b = device.createBuffer({ size: Math.max(16, size), usage: use || usage });
    made.push(b);
    return b;
  };
  // A parameter along an axis: each pixel forms its own coefficients (PER_PIXEL, set only
  // when on, as src/gpu/pipeline.rs `Variants` does).
  const constants = { LOSSES: p.losses };
  if (parameterAxes(v) !== "") constants.PER_PIXEL = 1;
  return { u, p, integrated, rowsPerTile, capacity: rowsPerTile * g.width, buffer, constants,
    params: buffer(k.params.size, GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST),
    free: () => made.forEach((b) => b.destroy()) };
}

// Records one dispatch of `count` invocations into a new encoder, after writing the params.
function encode(s, pipeline, group, count) {
  const device = gpu.device;
  device.queue.writeBuffer(s.params, 0, s.u.bytes);
  const encoder = device.createCommandEncoder();
  const pass = encoder.beginComputePass();
  pass.setPipeline(pipeline);
  pass.setBindGroup(0, group);
  pass.dispatchWorkgroups(...workgroups(count, manifest.constants));
  pass.end();
  return encoder;
}

// `n` f32s of `buffer`, read back.
async function readF32(s, buffer, n) {
  const read = s.buffer(n * 4, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
  const encoder = gpu.device.createCommandEncoder();
  encoder.copyBufferToBuffer(buffer, 0, read, 0, n * 4);
  gpu.device.queue.submit([encoder.finish()]);
  await read.mapAsync(GPUMapMode.READ);
  const out = new Float32Array(read.getMappedRange(), 0, n).slice();
  read.unmap();
  return out;
}

// The flip times of view `v` on a grid `g` (seconds; Infinity: never flipped within t-max;
// NaN: the integration left the numbers), as the engine's f32 kernel computes them.
async function flipTimes(v, g, onProgress) {
  const c = manifest.constants, kernel = await kernelOf(gpu, "flip_time"), k = kernel.k;
  const s = setUp(v, g, k);
  const [init, advance] = await pipelines(gpu, "flip_time", ["flip_init", "flip_time"],
    Object.assign({ EARLY_EXIT: 1 }, s.constants));
  const states = s.buffer(s.capacity * c.pendulum_bytes), times = s.buffer(s.capacity * 4);
  const lists = [s.buffer(s.capacity * 4), s.buffer(s.capacity * 4)];
  const counter = s.buffer(4);
  const counterRead = s.buffer(4, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
  const byName = { params: s.params, states, times, counter };
  // Bind groups reading list a and writing list b, and the reverse.
  const bind = (from, to) => gpu.device.createBindGroup({ layout: kernel.layout,
    entries: k.bindings.map((b) => ({ binding: b.binding, resource: { buffer:
      b.name === "active_in" ? from : b.name === "active_out" ? to : byName[b.name] } })) });
  const aToB = bind(lists[0], lists[1]), bToA = bind(lists[1], lists[0]);
  // One dispatch; returns how many pixels it left active.
  const dispatch = async (pipeline, group, count) => {
    gpu.device.queue.writeBuffer(counter, 0, new Uint32Array([0]));
    const encoder = encode(s, pipeline, group, count);
    encoder.copyBufferToBuffer(counter, 0, counterRead, 0, 4);
    gpu.device.queue.submit([encoder.finish()]);
    await counterRead.mapAsync(GPUMapMode.READ);
    const n = new Uint32Array(counterRead.getMappedRange())[0];
    counterRead.unmap();
    return n;
  };
  const total = steps(v.t_max, v.dt), tMax = Math.fround(v.t_max);
  const out = new Float32Array(g.width * g.height), mine = generation;
  try {
    for (let row0 = 0; row0 < s.integrated; row0 += s.rowsPerTile) {
      const rows = Math.min(s.rowsPerTile, s.integrated - row0), n = rows * g.width;
      s.u.set("row0", row0); s.u.set("rows", rows); s.u.set("count", n);
      s.u.set("step0", 0); s.u.set("steps", 0);
      let active = await dispatch(init, bToA, n);
      let step0 = 0, forward = true;
      while (step0 < total && active > 0) {
        if (mine !== generation) return null;
        const steps = stepsFor(active, 1, total - step0, manifest.constants);
        s.u.set("step0", step0); s.u.set("steps", steps); s.u.set("count", active);
        active = await dispatch(advance, forward ? aToB : bToA, active);
        forward = !forward;
        step0 += steps;
        onProgress((row0 + rows * step0 / total) / s.integrated);
      }
      const t = await readF32(s, times, n);
      for (let i = 0; i < n; i++) {
        const x = t[i];
        out[row0 * g.width + i] = x === c.nonfinite ? NaN
          : (x === c.never || x > tMax) ? Infinity : x;
      }
    }
  } finally {
    s.free();
  }
  return mirrored(out, s.integrated * g.width);
}

// A divergence-family map of view `v` (FTLE, MEGNO, ...: kind `kind` of manifest.json) on
// grid `g`, as src/gpu/lyapunov.rs and indicators.rs drive it: every pixel every step, the
// steps of a dispatch bounded by their cost; NaN where the run left the numbers.
async function divergence(kind, v, g, onProgress) {
  const c = manifest.constants;
  const kernel = await kernelOf(gpu, kind.kernel), k = kernel.k;
  const s = setUp(v, g, k);
  const [init, advance] = await pipelines(gpu, kind.kernel, kind.entries, s.constants);
  // Binding 1: each pixel's slot (its size read from the WGSL); 2: its value.
  const slotBytes = k.bindings.find((b) => b.binding === 1).stride;
  const slots = s.buffer(s.capacity * slotBytes), values = s.buffer(s.capacity * 4);
  const group = gpu.device.createBindGroup({ layout: kernel.layout,
    entries: k.bindings.map((b) => ({ binding: b.binding,
      resource: { buffer: [s.params, slots, values][b.binding] } })) });
  const total = steps(v.t_max, v.dt), tEnd = total * v.dt;
  // src/spec/map.rs `renorm_steps`.
  s.u.set("interval", Math.max(1, Math.round(kind.renorm / v.dt)));
  s.u.set("total_steps", total);
  s.u.set("setting", kind.setting);
  s.u.set("measure", kind.measure);
  const run = async (pipeline, n) => {
    gpu.device.queue.submit([encode(s, pipeline, group, n).finish()]);
    await gpu.device.queue.onSubmittedWorkDone();
  };
  const out = new Float32Array(g.width * g.height), mine = generation;
  try {
    for (let row0 = 0; row0 < s.integrated; row0 += s.rowsPerTile) {
      const rows = Math.min(s.rowsPerTile, s.integrated - row0), n = rows * g.width;
      s.u.set("row0", row0); s.u.set("rows", rows); s.u.set("count", n);
      await run(init, n);
      for (let step0 = 0; step0 < total;) {
        if (mine !== generation) return null;
        const steps = stepsFor(n, kind.cost, total - step0, manifest.constants);
        s.u.set("step0", step0); s.u.set("steps", steps); s.u.set("count", n);
        await run(advance, n);
        step0 += steps;
        onProgress((row0 + rows * step0 / total) / s.integrated);
      }
      const raw = await readF32(s, values, n);
      for (let i = 0; i < n; i++) {
        const x = raw[i];
        out[row0 * g.width + i] = x < kind.left_below ? NaN
          : kind.never_inf && x === c.never ? Infinity
          : kind.per_time ? Math.fround(x / tEnd) : x;
      }
    }
  } finally {
    s.free();
  }
  return mirrored(out, s.integrated * g.width);
}

// src/quantity.rs `Tolerance::agrees`: within the relative tolerance of the larger or the
// absolute one (in f64, as the engine compares); a time's nevers agree; NaN never does.
function agrees(t, a, b) {
  if (t.time && (a === Infinity || b === Infinity)) return a === b;
  return Math.abs(a - b) <= Math.max(t.relative * Math.max(Math.abs(a), Math.abs(b)), t.absolute);
}

// The verdict on `values`, the map of view `v` on grid `g` (src/plan.rs `planned_map` on a GPU
// without f64, the browser's case): the same map at half the step and at a quarter, 1 where
// each agrees with the next within the kind's vouching tolerance, else 0.
async function verdictOf(values, v, g, onProgress) {
  const t = measureOf(v).vouch;
  const half = await compute(Object.assign({}, v, { dt: v.dt / 2 }), g, (f) => onProgress(f / 3));
  if (half === null) return null;
  const quarter = await compute(Object.assign({}, v, { dt: v.dt / 4 }), g,
    (f) => onProgress((1 + 2 * f) / 3));
  if (quarter === null) return null;
  const mask = new Uint8Array(values.length);
  for (let i = 0; i < values.length; i++) {
    mask[i] = agrees(t, values[i], half[i]) && agrees(t, half[i], quarter[i]) ? 1 : 0;
  }
  return mask;
}

// The map of view `v` on grid `g`, of the view's kind.
async function compute(v, g, onProgress) {
  const beyond = outside(g);
  if (beyond) throw new Error(beyond);
  // The work's bound, whatever asked for it (a view, its verdict's finer steps, a test): the
  // engine's most steps a run.
  const n = steps(v.t_max, v.dt);
  if (!(n >= 1 && n <= manifest.constants.max_steps)) {
    throw new Error(`t-max / dt = ${n.toPrecision(3)} steps: at most ` +
      `${manifest.constants.max_steps} a run.`);
  }
  await ready();
  const kind = measureOf(v);
  return kind.name === "flip" ? flipTimes(v, g, onProgress) : divergence(kind, v, g, onProgress);
}

// ---- Drawing ----

// A colour table from its RRGGBB hex string.
function parseTable(hex) {
  const n = hex.length / 6, rgb = new Uint8Array(n * 3);
  for (let i = 0; i < n * 3; i++) rgb[i] = parseInt(hex.substr(2 * i, 2), 16);
  return rgb;
}

// How values become colours: a position 0..1 along the colour table (NaN for none).
// Flip times: src/render/colormap.rs `flip_colors`, log time from t_lo (brightest) to t-max,
// never black. Divergence maps: `ftle_colors`, linear from 0 to the kind's range: the 99.5th
// percentile of the map, at least the kind's floor (the measure's `default_range`).
function scale(kind, values, v) {
  if (kind.name === "flip") {
    const t0 = manifest.pendulums[v.pendulum].t_lo, lo = Math.log(t0), hi = Math.log(v.t_max);
    return { lo: t0, hi: v.t_max, log: true,
      at: (t) => Number.isFinite(t) ? (Math.log(Math.max(t, t0)) - lo) / (hi - lo) : null };
  }
  // The measure's rule (src/measure/range.rs `RangeRule::apply`), in f32 as the engine's.
  const r = kind.range, finite = values.filter(Number.isFinite).sort((a, b) => a - b);
  let [ql, qh] = [0, 1];
  if (finite.length) {
    const at = (q) => finite[Math.round((finite.length - 1) * q)];
    [ql, qh] = [at(r.quantiles[0]), at(r.quantiles[1])];
    if (r.widen && qh <= ql) [ql, qh] = [Math.fround(ql - 0.5), Math.fround(ql + 0.5)];
  }
  const end = (e, q, keep) => e === "t_max" ? Math.fround(v.t_max) : "fixed" in e ? e.fixed
    : e.bound === null ? q : keep(q, e.bound);
  const lo = end(r.low, ql, Math.min), hi = end(r.high, qh, Math.max);
  // Reversed (src/render/maps.rs `lyapunov_picture`), low values take the bright end.
  return { lo, hi, log: false,
    at: kind.reversed ? (x) => (hi - x) / (hi - lo) : (x) => (x - lo) / (hi - lo) };
}

function colourTable(kind, v) {
  return parseTable(kind.name === "flip" ? manifest.colours[v.colours] : kind.table);
}

function image(values, g, v, sc, mask) {
  const kind = measureOf(v), lut = colourTable(kind, v), n = lut.length / 3;
  const image = new ImageData(g.width, g.height);
  for (let i = 0; i < values.length; i++) {
    const x = values[i];
    let r = 0, gr = 0, b = 0;
    if (mask && !mask[i]) { r = gr = b = 128; } else if (Number.isNaN(x)) { gr = 255; } else {
      const u = sc.at(x);
      if (u !== null) {
        const j = Math.round(Math.min(1, Math.max(0, u)) * (n - 1)) * 3;
        r = lut[j]; gr = lut[j + 1]; b = lut[j + 2];
      }
    }
    // Row 0 is the top (y at its maximum), as in the canvas.
    const o = i * 4;
    image.data[o] = r; image.data[o + 1] = gr; image.data[o + 2] = b; image.data[o + 3] = 255;
  }
  return image;
}

function draw(values, g, v, sc, mask) {
  canvas.getContext("2d").putImageData(image(values, g, v, sc, mask), 0, 0);
  canvas.classList.remove("stale");
  drawAxes(g);
  page.shownCommand = command(v, g);
  document.getElementById("save").hidden = false;
}

// The map shown as a PNG that says how to make it again: the command line's text chunks
// (src/render/maps.rs `provenance`: the version, the command, the path, the adapter).
async function mapPng() {
  const blob = await new Promise((done) => canvas.toBlob(done, "image/png"));
  const png = new Uint8Array(await blob.arrayBuffer());
  const text = [["Software", `chaoscope ${manifest.version}`],
    ["chaoscope:command", page.shownCommand], ["chaoscope:backend", "gpu"],
    ["chaoscope:adapter", `${page.adapter} (WebGPU, in a browser)`]];
  // tEXt is Latin-1: anything else becomes "?".
  const latin1 = (t) => Array.from(t, (ch) => (ch.charCodeAt(0) < 256 ? ch.charCodeAt(0) : 63));
  const chunks = text.map(([key, value]) => {
    const data = [...latin1(key), 0, ...latin1(value)], n = data.length;
    const body = new Uint8Array([116, 69, 88, 116, ...data]);  // "tEXt" and its data
    const crc = crc32(body);
    return new Uint8Array([n >>> 24, (n >>> 16) & 255, (n >>> 8) & 255, n & 255, ...body,
      crc >>> 24, (crc >>> 16) & 255, (crc >>> 8) & 255, crc & 255]);
  });
  // After the signature (8 bytes) and IHDR (25).
  return new Blob([png.subarray(0, 33), ...chunks, png.subarray(33)], { type: "image/png" });
}

// PNG's CRC-32 of `bytes`.
function crc32(bytes) {
  let c = ~0;
  for (const b of bytes) {
    c ^= b;
    for (let k = 0; k < 8; k++) c = (c >>> 1) ^ (0xedb88320 & -(c & 1));
  }
  return ~c >>> 0;
}

// Round values along [lo, hi] to label an axis: about five, at 1, 2 or 5 times a power of
// ten; on an angle axis spanning most of a turn, multiples of pi/4 or pi/2 named so.
function ticks(lo, hi, angle) {
  const span = hi - lo, out = [];
  if (angle && span > 2.5) {
    const quarters = span > 3 ? 2 : 1, step = quarters * Math.PI / 4;
    for (let k = Math.ceil(lo / step - 1e-9); k * step <= hi + 1e-9; k++) {
      const q = k * quarters, sign = q < 0 ? "−" : "";
      const [n, d] = q % 4 === 0 ? [Math.abs(q) / 4, 1] : q % 2 === 0 ? [Math.abs(q) / 2, 2]
        : [Math.abs(q), 4];
      const text = q === 0 ? "0" : `${sign}${n === 1 ? "" : n}π${d === 1 ? "" : "/" + d}`;
      out.push([k * step, text]);
    }
    return out;
  }
  const raw = span / 5, power = Math.pow(10, Math.floor(Math.log10(raw))), f = raw / power;
  const step = (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * power;
  const digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
  for (let k = Math.ceil(lo / step); k * step <= hi; k++) {
    out.push([k * step, (k * step).toFixed(digits).replace(/^-/, "−")]);
  }
  return out;
}

// The map's axes: ticks with their values along the bottom and left edges, and the
// variables' names.
function drawAxes(g) {
  const side = canvas.getBoundingClientRect().width, left = canvas.offsetLeft;
  const place = (id, values, at) => {
    const box = document.getElementById(id);
    box.replaceChildren(...values.map(([value, text]) => {
      const label = document.createElement("span");
      label.textContent = text;
      Object.assign(label.style, at(value));
      return label;
    }));
  };
  const [x0, x1] = g.x, [y0, y1] = g.y;
  place("x-ticks", ticks(x0, x1, varOf(g.xVar).angle),
    (x) => ({ left: `${left + (x - x0) / (x1 - x0) * side}px`, top: `${side}px` }));
  place("y-ticks", ticks(y0, y1, varOf(g.yVar).angle),
    (y) => ({ left: `${left}px`, top: `${(y1 - y) / (y1 - y0) * side}px` }));
  const name = (v) => `${varOf(v).symbol}${varOf(v).unit === "1" ? "" : ` (${varOf(v).unit})`}`;
  Object.assign(document.getElementById("x-name"), { textContent: name(g.xVar) }).style.cssText =
    `left: ${left + side / 2}px; top: ${side + 20}px`;
  // Beside the map, turned; on a narrow screen, inside its top left corner.
  Object.assign(document.getElementById("y-name"), { textContent: name(g.yVar) }).style.cssText =
    NARROW.matches ? `left: ${left + 40}px; top: 4px` : `left: 9px; top: ${side / 2}px`;
}

function drawBar(sc) {
  const kind = measureOf(view);
  const bar = document.getElementById("bar-colours"), ctx = bar.getContext("2d");
  const lut = colourTable(kind, view), n = lut.length / 3;
  for (let x = 0; x < bar.width; x++) {
    const j = Math.round(x / (bar.width - 1) * (n - 1)) * 3;
    ctx.fillStyle = `rgb(${lut[j]},${lut[j + 1]},${lut[j + 2]})`;
    ctx.fillRect(x, 0, 1, bar.height);
  }
  const ticks = document.getElementById("bar-ticks");
  ticks.replaceChildren();
  document.getElementById("bar-label").textContent =
    kind.name === "flip" ? "flip time (s)" : kind.bar_label;
  document.getElementById("about").textContent = kind.about;
  if (!sc) return;
  const marks = sc.log ? [0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500]
    : [0, 0.25, 0.5, 0.75, 1].map((f) => Number((sc.lo + f * (sc.hi - sc.lo)).toPrecision(2)));
  for (const t of marks) {
    if (t < sc.lo || t > sc.hi) continue;
    const el = document.createElement("span");
    el.style.left = `${100 * Math.min(1, sc.at(t))}%`;
    el.textContent = String(t);
    ticks.append(el);
  }
}

// ---- Computing the view ----

// Views at least 4 x this many pixels wide are drawn coarse first.
const PREVIEW_MIN = 64;

// A coarse map of the view, stretched over the canvas (its pixels as blocks).
function preview(values, g, v) {
  const small = document.createElement("canvas");
  [small.width, small.height] = [g.width, g.height];
  small.getContext("2d").putImageData(image(values, g, v, scale(measureOf(v), values, v)), 0, 0);
  const ctx = canvas.getContext("2d");
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(small, 0, 0, canvas.width, canvas.height);
  canvas.classList.remove("stale");
}

// The start last clicked ({x, y} on axes xVar, yVar), kept across views: marked on the map,
// its words those of the map shown.
let clicked = null;

function pixelWords(kind, value) {
  return kind.name === "flip"
    ? (Number.isFinite(value) ? `flips at ${value.toFixed(3)} s` : Number.isNaN(value)
      ? "left the numbers" : `never flips within ${view.t_max} s`)
    : `${kind.label} ${Number.isFinite(value) ? value.toPrecision(4)
      : Number.isNaN(value) ? "NaN (left the numbers)" : value}`;
}

function markClicked() {
  const marker = document.getElementById("marker"), text = document.getElementById("pixel-text");
  marker.hidden = true;
  if (!clicked || !page.shown) return;
  const at = `${clicked.xVar} = ${clicked.x.toPrecision(6)}, ${clicked.yVar} = ` +
    clicked.y.toPrecision(6);
  if (clicked.xVar !== view.x || clicked.yVar !== view.y) {
    text.textContent = `${at}: not on this plane (${view.x}, ${view.y}).`;
    return;
  }
  const g = grid(view, canvas.width, canvas.height);
  const fx = (clicked.x - g.x[0]) / (g.x[1] - g.x[0]), fy = (g.y[1] - clicked.y) / (g.y[1] - g.y[0]);
  if (!(fx >= 0 && fx < 1 && fy >= 0 && fy < 1)) {
    text.textContent = `${at}: outside this view.`;
    return;
  }
  const side = canvas.getBoundingClientRect().width;
  marker.style.left = `${canvas.offsetLeft + fx * side}px`;
  marker.style.top = `${fy * side}px`;
  marker.hidden = false;
  const value = page.shown[Math.floor(fy * g.height) * g.width + Math.floor(fx * g.width)];
  text.textContent = `${at}: ${pixelWords(measureOf(view), value)}`;
  page.clickedText = text.textContent;
}

let pending = null;
async function show() {
  confine(view);
  const g = grid(view, canvas.width, canvas.height);
  writeHash();
  drawBar(null);
  form.elements.colours.closest("label").hidden = view.kind !== "flip";
  const settings = settingsOf(view.kind);
  form.elements.setting.replaceChildren(...settings.map((m, i) => new Option(m.options, String(i))));
  form.elements.setting.value = String(view.setting);
  form.elements.setting.closest("label").hidden = settings.length < 2;
  for (const name of ["theta1", "theta2"]) {
    form.elements[name].value = view[name];
    form.elements[name].closest("label").hidden = !fixedAngles(view).includes(name);
  }
  document.getElementById("command").textContent = command(view, g);
  const span = (name, r) => `${name} from ${r[0].toPrecision(5)} to ${r[1].toPrecision(5)} ` +
    `${varOf(name).unit}`;
  document.getElementById("extent").textContent =
    `${span(view.x, g.x)} (left to right); ${span(view.y, g.y)} (bottom to top).`;
  const mine = ++generation;
  if (overlapping(view)) {
    say(`${view.x} and ${view.y} set the same value: pick two axes that do not.`, true);
    return;
  }
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
  canvas.classList.add("stale");
  say("computing on the GPU…");
  try {
    // A quarter of the resolution first (a sixteenth of the work): the new view in a moment,
    // then sharpened.
    if (g.width >= 4 * PREVIEW_MIN) {
      const coarse = Object.assign({}, g, { width: Math.ceil(g.width / 4),
        height: Math.ceil(g.height / 4) });
      const rough = await compute(view, coarse, () => {});
      if (rough === null || mine !== generation) return;
      preview(rough, coarse, view);
      page.previewSeconds = (performance.now() - started) / 1000;
    }
    const values = await compute(view, g, (f) => {
      progress.firstElementChild.style.width = `${(100 * f).toFixed(1)}%`;
      say(`computing on the GPU… ${(100 * f).toFixed(0)} %`);
    });
    if (values === null || mine !== generation) return;
    let mask = null;
    if (view.verdict && view.dt <= manifest.constants.verdict_dt_max * (1 + 1e-9)) {
      say("the verdict: the same map at half and a quarter of the step…");
      mask = await verdictOf(values, view, g, (f) => {
        progress.firstElementChild.style.width = `${(100 * f).toFixed(1)}%`;
      });
      if (mask === null || mine !== generation) return;
    }
    const kind = measureOf(view), sc = scale(kind, values, view);
    draw(values, g, view, sc, mask);
    drawBar(sc);
    page.shown = values;
    markClicked();
    const seconds = (performance.now() - started) / 1000;
    const finite = values.filter(Number.isFinite).length / values.length;
    page.views += 1;
    page.last = { seconds, finite, width: g.width, height: g.height, kind: kind.name };
    let judged = "";
    if (mask) {
      const resolved = mask.reduce((a, m) => a + m, 0) / mask.length;
      page.last.resolved = resolved;
      judged = ` ${(100 * resolved).toFixed(1)} % resolved (grey: not): the same map at half ` +
        `and a quarter of the step gives ${kind.vouch.words}, in f32.`;
    } else if (view.verdict) {
      judged = ` No verdict above dt = ${manifest.constants.verdict_dt_max} s: the runs at ` +
        "smaller steps are not trusted to settle a pixel there.";
    }
    say(`${g.width} x ${g.height} pendulums over ${view.t_max} s in ${seconds.toFixed(2)} s ` +
      `on ${page.adapter}` + (kind.name === "flip"
        ? `; ${(100 * finite).toFixed(1)} % flipped.` : `: ${kind.label}.`) + judged);
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
  const pad = getComputedStyle(document.getElementById("frame"));
  // Room for the axes' labels (#frame's padding) and a margin.
  const across = parseFloat(pad.paddingLeft) + parseFloat(pad.paddingRight) + 16;
  const below = parseFloat(pad.paddingTop) + parseFloat(pad.paddingBottom) + 16;
  // Beside the panel the map fills the view's height; above it (a narrow screen, style.css)
  // the width, at most most of the screen's height.
  const tall = NARROW.matches ? 0.8 * window.innerHeight : box.clientHeight - below;
  const side = Math.max(64, Math.floor(Math.min(box.clientWidth - across, tall)));
  const pixels = Math.min(1024, Math.round(side * (window.devicePixelRatio || 1)));
  canvas.style.width = canvas.style.height = `${side}px`;
  if (canvas.width !== pixels) {
    canvas.width = canvas.height = pixels;
    return true;
  }
  return false;
}

// A narrow screen (a phone): the map above the panel (style.css).
const NARROW = matchMedia("(max-width: 760px)");

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
    view.w *= k; view.h *= k;
    later();
  }, { passive: false });
  let drag = null;
  // Two fingers pinch: the view scales about their midpoint as their distance changes.
  const touches = new Map();
  let pinch = null;
  const spread = () => {
    const [a, b] = [...touches.values()];
    return { d: Math.hypot(a.x - b.x, a.y - b.y), x: (a.x + b.x) / 2, y: (a.y + b.y) / 2 };
  };
  canvas.addEventListener("pointerdown", (e) => {
    touches.set(e.pointerId, { x: e.clientX, y: e.clientY });
    canvas.setPointerCapture(e.pointerId);
    if (touches.size === 2) {
      drag = null;
      const s0 = spread();
      pinch = { d: s0.d, at: pointAt({ clientX: s0.x, clientY: s0.y }), cx: view.cx,
        cy: view.cy, w: view.w, h: view.h };
      return;
    }
    drag = { x: e.clientX, y: e.clientY, cx: view.cx, cy: view.cy, moved: false };
  });
  canvas.addEventListener("pointercancel", (e) => { touches.delete(e.pointerId); });
  canvas.addEventListener("pointermove", (e) => {
    if (touches.has(e.pointerId)) touches.set(e.pointerId, { x: e.clientX, y: e.clientY });
    if (pinch && touches.size === 2) {
      const k = pinch.d / Math.max(1, spread().d);
      canvas.style.transform = `scale(${1 / k})`;
      view.cx = pinch.at.x + (pinch.cx - pinch.at.x) * k;
      view.cy = pinch.at.y + (pinch.cy - pinch.at.y) * k;
      view.w = pinch.w * k; view.h = pinch.h * k;
      return;
    }
    if (!drag) return;
    const box = canvas.getBoundingClientRect(), dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) > 3) drag.moved = true;
    canvas.style.transform = `translate(${dx}px, ${dy}px)`;
    view.cx = drag.cx - dx / box.width * view.w;
    view.cy = drag.cy + dy / box.height * view.h;
  });
  canvas.addEventListener("pointerup", (e) => {
    touches.delete(e.pointerId);
    if (pinch) {
      // The view waits for both fingers to lift.
      if (touches.size === 0) { pinch = null; canvas.style.transform = ""; later(); }
      return;
    }
    canvas.style.transform = "";
    if (drag && drag.moved) later(); else if (drag) describe(e);
    drag = null;
  });
  form.addEventListener("change", () => {
    const f = new FormData(form);
    view.pendulum = Number(f.get("pendulum"));
    let axes = false;
    for (const a of ["x", "y"]) {
      if (view[a] !== f.get(a)) { view[a] = f.get(a); wholeAxis(a); axes = true; }
    }
    const t = Number(f.get("t_max")), dt = Number(f.get("dt"));
    const b = manifest.bounds;
    if (t >= b.t_max[0] && t <= b.t_max[1]) view.t_max = t;
    if (dt >= b.dt[0] && dt <= b.dt[1]) view.dt = dt;
    for (const name of ["theta1", "theta2"]) {
      const a = Number(f.get(name)), [lo, hi] = limitsOf(name);
      if (!axes && f.get(name) !== null && a >= lo && a <= hi) view[name] = a;
    }
    // Axes newly set to two parameters from a start at rest would map pendulums hanging
    // still: they start where the guide's parameter plane does, both arms at 2 rad.
    const params = [view.x, view.y].every((name) => !varOf(name).state);
    if (axes && params && view.theta1 === 0 && view.theta2 === 0) {
      view.theta1 = 2; view.theta2 = 2;
    }
    view.colours = f.get("colours");
    // Another kind starts at its default setting.
    view.setting = view.kind === f.get("kind") ? Number(f.get("setting") || 0) : 0;
    view.kind = f.get("kind");
    view.verdict = f.get("verdict") === "on";
    later();
  });
  window.addEventListener("resize", () => { if (fit()) later(); });
  canvas.addEventListener("dblclick", (e) => {
    const at = pointAt(e);
    view.cx = at.x; view.cy = at.y; view.w /= 2; view.h /= 2;
    later();
  });
  document.getElementById("save").addEventListener("click", async () => {
    if (!page.shownCommand) return;
    const link = document.createElement("a");
    link.href = URL.createObjectURL(await mapPng());
    link.download = `chaoscope-${view.kind}.png`;
    link.click();
    setTimeout(() => URL.revokeObjectURL(link.href), 10000);
  });
  document.getElementById("copy").addEventListener("click", async () => {
    page.copied = location.href;
    try {
      await navigator.clipboard.writeText(location.href);
      say("Link copied: it opens this view, computed on the viewer's GPU.");
    } catch (e) {
      // A page not served over https (nor from this machine) may not reach the clipboard.
      say(`Copy this link: ${location.href}`);
    }
  });
  document.getElementById("reset").addEventListener("click", () => {
    wholeAxis("x"); wholeAxis("y");
    later();
  });
}

// Axis `a` ("x" or "y") over its variable's default range.
function wholeAxis(a) {
  const r = varOf(view[a]).range, [c, size] = a === "x" ? ["cx", "w"] : ["cy", "h"];
  view[c] = 0.5 * (r[0] + r[1]); view[size] = r[1] - r[0];
}

// A clicked pixel: its start, its value in the map shown, and its pendulum swinging, the
// motion computed by the engine's trajectory kernel (one run, every state kept at about 60 a
// second) on the GPU, as src/gpu/trajectory.rs drives it.
async function describe(e) {
  const at = pointAt(e);
  const g = grid(view, canvas.width, canvas.height);
  const col = Math.min(g.width - 1, Math.floor(at.fx * g.width));
  const row = Math.min(g.height - 1, Math.floor(at.fy * g.height));
  // The pixel's centre, as the kernels place it (src/spec/grid.rs `Axis::at`).
  const x = 0.5 * (g.x[0] + g.x[1]) + (2 * col + 1 - g.width) * 0.5 * ((g.x[1] - g.x[0]) / g.width);
  const y = 0.5 * (g.y[0] + g.y[1]) - (2 * row + 1 - g.height) * 0.5 * ((g.y[1] - g.y[0]) / g.height);
  const start = { theta1: view.theta1, omega1: 0, theta2: view.theta2, omega2: 0 };
  for (const [name, value] of [[view.x, x], [view.y, y]]) if (varOf(name).state) start[name] = value;
  clicked = { x, y, xVar: view.x, yVar: view.y };
  document.getElementById("pixel").hidden = false;
  markClicked();
  // The swing in sight without scrolling: beside the map, or below it on a narrow screen.
  document.getElementById("pixel").scrollIntoView({ block: "nearest" });
  document.getElementById("swing").hidden = false;
  document.getElementById("swing-command").textContent = swingCommand(view, start, { x, y });
  try {
    animate(await trajectory(start, view, { x, y }), view);
  } catch (err) {
    say(`Could not swing the pendulum: ${err.message}`, true);
  }
}

// The command line of the run from `start` at the plane's point `at` ({x, y}): a parameter
// axis sets the pixel's pendulum, as `trajectory --at NAME=VALUE` does.
function swingCommand(v, start, at) {
  const p = manifest.pendulums[v.pendulum];
  const set = [[v.x, at.x], [v.y, at.y]].filter(([name]) => !varOf(name).state);
  const values = { theta1: start.theta1, omega1: start.omega1, theta2: start.theta2,
    omega2: start.omega2, t_max: v.t_max, dt: v.dt,
    pendulum: p.flags[parameterAxes(v)] + set.map(([name, x]) => ` --at ${name}=${x}`).join("") };
  return manifest.swing_command.replace(/\{(\w+)\}/g, (_, k) => String(values[k]));
}

// The states of one run from `start` over the view's t-max, every `stride`-th step.
// On a parameter plane, `at` ({x, y}: the axes' values) makes the run the plane's pixel
// there: a grid of that one pixel, whose coefficients the kernel forms as the map's do.
async function trajectory(start, v, at) {
  await ready();
  const c = manifest.constants, kernel = await kernelOf(gpu, "trajectory"), k = kernel.k;
  const p = manifest.pendulums[v.pendulum];
  const plane = parameterAxes(v) !== "";
  const constants = plane ? { LOSSES: p.losses, PLANE_RUN: 1 } : { LOSSES: p.losses };
  const [pipeline] = await pipelines(gpu, "trajectory", ["trajectory"], constants);
  const stride = Math.max(1, Math.round(1 / 60 / v.dt));
  const total = Math.max(stride, Math.floor(steps(v.t_max, v.dt) / stride) * stride);
  const kept = total / stride + 1;
  const device = gpu.device, made = [];
  const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
  const buffer = (size, use) => {
    const b = device.createBuffer({ size: Math.max(16, size), usage: use || usage });
    made.push(b);
    return b;
  };
  try {
    const u = paramsOf(p, k.params.fields, k.params.size);
    u.set("dt", v.dt); u.set("interval", stride); u.set("count", 1); u.set("total_steps", total);
    if (plane) {
      const scaled = (name, value) => value * (varOf(name).mass ? p.mass_scale : 1);
      u.set("x_mid", scaled(v.x, at.x)); u.set("y_mid", scaled(v.y, at.y));
      u.set("x_half_step", 0); u.set("y_half_step", 0);
      u.set("x_var", varOf(v.x).code); u.set("y_var", varOf(v.y).code);
      u.set("width", 1); u.set("height", 1);
    }
    const params = buffer(k.params.size, GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST);
    const y = [start.theta1, start.omega1, start.theta2, start.omega2];
    const states = buffer(kept * 16), damping = buffer(16), carried = buffer(32);
    device.queue.writeBuffer(states, 0, new Float32Array(y));
    device.queue.writeBuffer(carried, 0, new Float32Array([...y, Math.cos(y[0]),
      Math.sin(y[0]), Math.cos(y[2]), Math.sin(y[2])]));
    const byBinding = [params, states, damping, carried];
    const group = device.createBindGroup({ layout: kernel.layout,
      entries: k.bindings.map((b) => ({ binding: b.binding,
        resource: { buffer: byBinding[b.binding] } })) });
    for (let step0 = 0; step0 < total; step0 += c.steps_per_invocation) {
      u.set("step0", step0); u.set("steps", Math.min(c.steps_per_invocation, total - step0));
      device.queue.writeBuffer(params, 0, u.bytes);
      const encoder = device.createCommandEncoder();
      const pass = encoder.beginComputePass();
      pass.setPipeline(pipeline); pass.setBindGroup(0, group); pass.dispatchWorkgroups(1);
      pass.end();
      device.queue.submit([encoder.finish()]);
    }
    const read = buffer(kept * 16, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
    const encoder = device.createCommandEncoder();
    encoder.copyBufferToBuffer(states, 0, read, 0, kept * 16);
    device.queue.submit([encoder.finish()]);
    await read.mapAsync(GPUMapMode.READ);
    const out = new Float32Array(read.getMappedRange()).slice();
    read.unmap();
    return { states: out, seconds: stride * v.dt, arms: arms(p, v, at) };
  } finally {
    made.forEach((b) => b.destroy());
  }
}

// The arms' lengths of the run (m): the pendulum's, or a length axis's value at the pixel
// (src/spec/var.rs `Var::set`: l2/l1 multiplies the upper arm, set first).
function arms(p, v, at) {
  const set = { l1: p.l1, l2: p.l2 };
  const along = at ? [[v.x, at.x], [v.y, at.y]] : [];
  for (const [name, value] of along.filter(([n]) => n === "l1" || n === "l2")) set[name] = value;
  for (const [name, value] of along.filter(([n]) => n === "l2/l1")) set.l2 = value * set.l1;
  return [set.l1, set.l2];
}

// The pendulum swinging in real time, again and again; the lower bob leaves a trail.
let swinging = null;
function animate(run, v) {
  const swing = document.getElementById("swing"), ctx = swing.getContext("2d");
  const [l1, l2] = run.arms, scale = 0.45 * swing.width / (l1 + l2);
  const o = { x: swing.width / 2, y: swing.height / 2 }, n = run.states.length / 4;
  const at = (k) => {
    const s = run.states.subarray(4 * k, 4 * k + 4);
    const b1 = { x: o.x + scale * l1 * Math.sin(s[0]), y: o.y + scale * l1 * Math.cos(s[0]) };
    return [b1, { x: b1.x + scale * l2 * Math.sin(s[2]), y: b1.y + scale * l2 * Math.cos(s[2]) }];
  };
  cancelAnimationFrame(swinging);
  const t0 = performance.now();
  const frame = (now) => {
    const k = Math.floor((now - t0) / 1000 / run.seconds) % n;
    ctx.fillStyle = "#0b0b0e"; ctx.fillRect(0, 0, swing.width, swing.height);
    ctx.strokeStyle = "rgba(249,160,63,0.35)"; ctx.beginPath();
    for (let j = Math.max(0, k - 90); j <= k; j++) {
      const [, b2] = at(j);
      if (j === Math.max(0, k - 90)) ctx.moveTo(b2.x, b2.y); else ctx.lineTo(b2.x, b2.y);
    }
    ctx.stroke();
    const [b1, b2] = at(k);
    ctx.strokeStyle = "#ddd"; ctx.lineWidth = 2; ctx.beginPath();
    ctx.moveTo(o.x, o.y); ctx.lineTo(b1.x, b1.y); ctx.lineTo(b2.x, b2.y); ctx.stroke();
    ctx.lineWidth = 1; ctx.fillStyle = "#f9a03f";
    for (const b of [b1, b2]) { ctx.beginPath(); ctx.arc(b.x, b.y, 6, 0, 2 * Math.PI); ctx.fill(); }
    document.getElementById("swing-time").textContent = `t = ${(k * run.seconds).toFixed(2)} s`;
    swinging = requestAnimationFrame(frame);
  };
  swinging = requestAnimationFrame(frame);
  page.swung = { states: n, seconds: run.seconds };
}

function fillForm() {
  const options = (name, items) => {
    const s = form.elements[name];
    s.replaceChildren(...items.map(([value, text]) => new Option(text, value)));
  };
  options("pendulum", manifest.pendulums.map((p, i) => [String(i), p.name]));
  const axes = manifest.vars.map((v) => [v.name, `${v.name} (${v.unit})`]);
  options("x", axes);
  options("y", axes);
  options("colours", Object.keys(manifest.colours).map((c) => [c, c]));
  options("kind", manifest.kinds.map((k) => [k.name, k.label]));
  form.elements.kind.value = view.kind;
  form.elements.verdict.checked = view.verdict;
  form.elements.pendulum.value = String(view.pendulum);
  form.elements.x.value = view.x; form.elements.y.value = view.y;
  for (const k of ["t_max", "dt"]) {
    [form.elements[k].min, form.elements[k].max] = manifest.bounds[k].map(String);
    form.elements[k].value = view[k];
  }
  form.elements.colours.value = view.colours;
}

// The page's view with `v`'s settings (a width without a height: a square view).
function viewOf(v) {
  return confine(Object.assign({}, view, "w" in v && !("h" in v) ? { h: v.w } : {}, v));
}

// For tests: the run a click on a pixel with start `start` swings (its kept states, and the
// seconds between them).
page.swing = async (start, v, at) => {
  const from = Object.assign({ theta1: 0, omega1: 0, theta2: 0, omega2: 0 }, start);
  const w = viewOf(v), run = await trajectory(from, w, at);
  if (at) return { states: Array.from(run.states), seconds: run.seconds, arms: run.arms,
    command: swingCommand(w, from, at) };
  return { states: Array.from(run.states), seconds: run.seconds };
};

// For tests: the command line of a view on a width x height grid.
page.command = (v, width, height) => {
  const w = viewOf(v);
  return command(w, grid(w, width, height));
};

// For tests: the verdict on a view's map (1 resolved, 0 not), as base64 of bytes.
page.verdict = async (v, width, height) => {
  const w = viewOf(v), g = grid(w, width, height);
  return base64(await verdictOf(await compute(w, g, () => {}), w, g, () => {}));
};

// Bytes as base64 (in slices: a spread of millions of arguments overflows the stack).
function base64(bytes) {
  let s = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(s);
}

// For tests: the PNG "Save PNG" downloads, as base64.
page.png = async () => base64(new Uint8Array(await (await mapPng()).arrayBuffer()));

// For tests: whether f32 resolves a view's pixel step on a width x height grid.
page.resolves = (v, width, height) => resolves(grid(viewOf(v), width, height));

// For tests: the flip times of a view, as base64 of little-endian f32s.
// For tests: the map of a view (its kind's values, as the command line's --data holds them),
// as base64 of little-endian f32s; `page.computeSeconds` says how long the computation took
// (without the transfer).
page.values = async (v, width, height) => {
  const w = viewOf(v), started = performance.now();
  const times = await compute(w, grid(w, width, height), () => {});
  page.computeSeconds = (performance.now() - started) / 1000;
  // Its colours' range as the page draws them (the kind's rule).
  const sc = scale(measureOf(w), times, w);
  page.valuesRange = [sc.lo, sc.hi];
  return base64(new Uint8Array(times.buffer));
};

// The view in the address of `chaoscope serve`'s own explorer: its region as the plane's
// range (the explorer fits it to the window), the map and t-max; the server's physics.
function serverView() {
  const g = grid(view, canvas.width, canvas.height), q = new URLSearchParams();
  q.set("kind", view.kind); q.set("t_max", String(view.t_max));
  q.set("x", view.x); q.set("x_min", String(g.x[0])); q.set("x_max", String(g.x[1]));
  q.set("y", view.y); q.set("y_min", String(g.y[0])); q.set("y_max", String(g.y[1]));
  return new URL(`../#${q}`, location.href).href;
}

async function main() {
  try {
    manifest = await (await fetch("manifest.json")).json();
  } catch (e) {
    // Opened from disk (file://), the browser lets the page read none of its files.
    say(location.protocol === "file:"
      ? "This page must be served, not opened from disk: in its folder run " +
        "`python3 -m http.server`, then open http://127.0.0.1:8000/ (or put the folder on " +
        "any web host)."
      : `The page's settings (manifest.json) could not be read: ${e.message}`, true);
    page.error = "no-manifest";
    return;
  }
  page.refused = readHash();
  fillForm();
  fit();
  wire();
  try {
    await ready();
    const info = gpu.device.adapterInfo || {};
    page.adapter = [info.vendor, info.architecture, info.description].filter(Boolean)
      .join(" ") || "this GPU";
  } catch (e) {
    page.error = e.message;
    // Served by `chaoscope serve` (under /web/): its own explorer computes on the server.
    const server = await fetch("../api/info").then((r) => r.ok, () => false);
    if (server) {
      say("This browser offers no WebGPU: the server's explorer computes the view instead…");
      page.fallback = serverView();
      location.replace(page.fallback);
      return;
    }
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
  if (page.refused.length) {
    // A link outside the controls' rules: said, and nothing computed until a control moves.
    say(`This link's view was not computed: ${page.refused.join("; ")}. Change a control ` +
      "or press Whole plane to compute a view.", true);
    document.getElementById("command").textContent =
      command(view, grid(view, canvas.width, canvas.height));
    return;
  }
  show();
}

main();
