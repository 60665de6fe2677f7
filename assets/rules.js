// The engine's rules the explorer pages apply to each view themselves, in one file shared by
// the served page (/assets/rules.js) and the static one (rules.js). Each is the rule of the
// Rust function it names, over the constants the pages are handed (manifest.json's
// `constants`, the served page's /api/info): the pages hold no copy of a rule elsewhere, and
// tests/web.rs holds the pages' maps, steps and verdicts to the engine's.
"use strict";

// f64::MIN_POSITIVE: the smallest largest value an axis is measured against.
const MIN_POSITIVE = 2.2250738585072014e-308;

// src/spec/grid.rs `Axis::finest_step`: the finest pixel step a precision of machine epsilon
// `epsilon` resolves along an axis over `range`, 16 ulp of the axis's largest value (angles:
// of pi at least, where they flip).
function finestStep(range, angle, epsilon) {
  const largest = Math.max(Math.abs(range[0]), Math.abs(range[1]), angle ? Math.PI : MIN_POSITIVE);
  return 16 * epsilon * Math.pow(2, Math.floor(Math.log2(largest)));
}

// src/spec/mod.rs `Stepping::steps`: t_max / dt steps, rounded where within rounding of a
// whole number, else up.
function steps(t_max, dt) {
  const n = t_max / dt, rounded = Math.round(n);
  return Math.abs(n - rounded) < 1e-9 * Math.max(n, 1) ? rounded : Math.ceil(n);
}

// src/gpu/pipeline.rs `workgroups`: workgroup counts (x, y) covering `n` invocations of
// `c.workgroup_size`, at most `c.max_workgroups` along x.
function workgroups(n, c) {
  const groups = Math.max(1, Math.ceil(n / c.workgroup_size));
  const x = Math.min(groups, c.max_workgroups);
  return [x, Math.ceil(groups / x)];
}

// src/gpu/tiled.rs `time_loop`: the steps of the next dispatch of `active` pixels, each step
// costing `cost` plain steps, `left` steps to go: at most c.steps_per_dispatch pendulum-steps
// (a driver's watchdog; the browser stays responsive between dispatches), at least
// c.min_steps, at most c.steps_per_invocation (lavapipe's loop limit) a pixel.
function stepsFor(active, cost, left, c) {
  const bounded = Math.max(Math.floor(c.steps_per_dispatch / cost / active),
    Math.floor(c.min_steps / cost));
  return Math.min(bounded, Math.max(1, Math.floor(c.steps_per_invocation / cost)), left);
}

// src/field.rs `mirror_below`: rows from `start` on filled by point reflection.
function mirrored(out, start) {
  for (let i = start; i < out.length; i++) out[i] = out[out.length - 1 - i];
  return out;
}
