// The live simulator without a kernel: the browser integrates the motion itself.
//
// The simulator's drawing (../simulator.js) plays runs that arrive as messages; in JupyterLab
// the kernel sends them (pendulum_lab.widgets.live.run_messages). Here this module makes the
// same messages from a model's generated equations (./models/, pendulum_lab.codegen.browser)
// and the course's methods (./methods/), and hands them to the drawing through a small object
// that answers as an anywidget model does (get, set, on, off, save_changes, send). A page
// mounts it with mount(element, config); config is what pendulum_lab.widgets.browser
// .browser_config writes. Nothing is fetched from another host.

import render from "../simulator.js";
import { ConvergenceError, makeField, METHODS } from "./methods/index.js";

const PLAYBACK_SPACING = 0.01; // widgets.live.PLAYBACK_SPACING
const CHUNK_STATES = 4096; // widgets.live.CHUNK_STATES
export const DT_CHOICES = [0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1];

// floor(t_end / dt) with the package's slack (driver.simulate.step_count).
export function stepCount(tEnd, dt) {
  return Math.floor((tEnd / dt) * (1 + 1e-12));
}

// Integrate `module` (a generated model) from (theta0, omega0) with `method` over tEnd with
// step dt. Every state is kept: angles, momenta, velocities, kinetic and potential energy.
// An implicit step that does not converge throws the kernel's sentence.
export function simulate(module, params, method, theta0, omega0, tEnd, dt) {
  const entry = METHODS[method];
  if (!entry) throw new Error(`no method named ${method} in the browser (${Object.keys(METHODS)})`);
  const n = module.COORDINATES;
  const steps = stepCount(tEnd, dt);
  const field = makeField(module, params);
  const theta = new Float64Array((steps + 1) * n);
  const momenta = new Float64Array((steps + 1) * n);
  const omega = new Float64Array((steps + 1) * n);
  const kinetic = new Float64Array(steps + 1);
  const potential = new Float64Array(steps + 1);
  let q = Float64Array.from(theta0);
  let p = new Float64Array(n);
  module.momenta(0, q, Float64Array.from(omega0), field.params, p);
  const memory = {};
  const energies = new Float64Array(2);
  let kept = steps + 1;
  for (let k = 0; k <= steps; k++) {
    const t = k * dt;
    const [velocity] = field.hamilton(t, q, p);
    module.energies(t, q, velocity, field.params, energies);
    theta.set(q, k * n);
    momenta.set(p, k * n);
    omega.set(velocity, k * n);
    kinetic[k] = energies[0];
    potential[k] = energies[1];
    if (![...q, ...p, energies[0], energies[1]].every(Number.isFinite)) {
      kept = k; // the state became non-finite: the run stops before it
      break;
    }
    if (k === steps) break;
    try {
      [q, p] = entry.step(field, t, q, p, dt, memory);
    } catch (error) {
      if (!(error instanceof ConvergenceError)) throw error;
      const at = k + 1;
      throw new ConvergenceError(
        `${method}: the implicit equations did not converge within 100 iterations at step ` +
          `${at} (t = ${Number((at * dt).toPrecision(6))}, dt = ${dt}); use a smaller dt`,
      );
    }
  }
  return {
    n, dt, steps, method, kept, completed: kept === steps + 1, evaluations: field.evaluations,
    theta: theta.subarray(0, kept * n), p: momenta.subarray(0, kept * n),
    omega: omega.subarray(0, kept * n), kinetic: kinetic.subarray(0, kept),
    potential: potential.subarray(0, kept),
  };
}

// The messages of widgets.live.run_messages for a run of the browser.
export function runMessages(run, module, params, config, id, chunkStates = CHUNK_STATES) {
  const n = run.n;
  const stride = Math.max(1, Math.floor((PLAYBACK_SPACING / run.dt) * (1 + 1e-9)));
  const states = Math.ceil(run.kept / stride);
  const figure = { ...config.figure };
  const count = figure.masses.length;
  const width = module.DIMENSIONS || 2; // (x, y), or (x, y, z) for points in space
  const angles = new Float32Array(states * n);
  const energies = new Float32Array(states * 3);
  const error = new Float32Array(states);
  const points = new Float32Array(figure.kind === "points" ? states * count * width : 0);
  const energy0 = run.kinetic[0] + run.potential[0];
  let low = 0;
  let high = 0;
  let errorMax = 0;
  let reach = 0;
  const place = new Float64Array(width * module.POINTS);
  for (let k = 0; k < run.kept; k++) {
    const total = run.kinetic[k] + run.potential[k];
    // E - E(0) in float64 before the cast, as the kernel does
    if (Number.isFinite(total)) errorMax = Math.max(errorMax, Math.abs(total - energy0));
    if (k % stride) continue;
    const s = k / stride;
    for (let j = 0; j < n; j++) angles[s * n + j] = run.theta[k * n + j];
    energies.set([run.kinetic[k], run.potential[k], total], s * 3);
    error[s] = total - energy0;
    for (const e of [run.kinetic[k], run.potential[k], total]) {
      if (Number.isFinite(e)) [low, high] = [Math.min(low, e), Math.max(high, e)];
    }
    if (figure.kind === "points") {
      module.positions(k * run.dt, run.theta.subarray(k * n, (k + 1) * n), params, place);
      points.set(place, s * count * width);
      for (const c of place) if (Number.isFinite(c)) reach = Math.max(reach, Math.abs(c));
    }
  }
  if (figure.kind === "points") figure.reach = reach > 0 ? reach : 1;
  const chunks = Math.ceil(states / chunkStates);
  const meta = {
    type: "run", run: id, chunks, chunk_states: chunkStates, states, links: n,
    lengths: config.lengths, figure, spacing: stride * run.dt, dt: run.dt, stride,
    steps: run.kept - 1, method: run.method, energy0, energy_range: [low, high],
    error_max: errorMax, completed: run.completed, conserved: config.conserved,
    forces: config.forces, changed_by: config.changed_by,
  };
  const messages = [];
  for (let chunk = 0, first = 0; first < states; chunk++, first += chunkStates) {
    const last = Math.min(states, first + chunkStates);
    const part = (array, width) => new DataView(array.slice(first * width, last * width).buffer);
    const buffers = [part(angles, n), part(energies, 3), part(error, 1)];
    if (figure.kind === "points") buffers.push(part(points, count * width));
    messages.push([{ ...meta, chunk, first, count: last - first }, buffers]);
  }
  return messages;
}

// The coordinates after point `bob` is released at (x, y) (widgets.live.released_angles): a
// chain's bob turns about the joint before it; a system's coordinates are moved from `theta`
// by Gauss-Newton steps until the point is there.
export function releasedAngles(module, params, config, theta, bob, x, y) {
  if (![x, y].every(Number.isFinite)) throw new Error("the release point is not a finite number");
  const angles = Float64Array.from(theta);
  const width = module.DIMENSIONS || 2; // a point in space is placed by its (x, y)
  const place = new Float64Array(width * module.POINTS);
  if (config.figure.kind === "chain") {
    module.positions(0, angles, params, place);
    const [jx, jy] = bob > 0 ? [place[2 * bob - 2], place[2 * bob - 1]] : [0, 0];
    if (x === jx && y === jy) throw new Error("the release point is the joint itself: no direction");
    angles[bob] = Math.atan2(x - jx, -(y - jy));
  } else {
    const refusal = config.figure.movable[bob];
    if (refusal) throw new Error(refusal);
    for (let sweep = 0; sweep < 50; sweep++) {
      module.positions(0, angles, params, place);
      const residual = [place[width * bob] - x, place[width * bob + 1] - y];
      if (Math.hypot(...residual) < 1e-12) break;
      // the 2 x n Jacobian by central differences, then the least-squares step
      const jacobian = [];
      for (let j = 0; j < angles.length; j++) {
        const d = 1e-7 * Math.max(1, Math.abs(angles[j]));
        const moved = [1, -1].map((sign) => {
          const shifted = Float64Array.from(angles);
          shifted[j] += sign * d;
          const out = new Float64Array(place.length);
          module.positions(0, shifted, params, out);
          return [out[width * bob], out[width * bob + 1]];
        });
        jacobian.push([(moved[0][0] - moved[1][0]) / (2 * d), (moved[0][1] - moved[1][1]) / (2 * d)]);
      }
      // minimum-norm step: J^T (J J^T)^-1 r
      let [sxx, sxy, syy] = [0, 0, 0];
      for (const [jx, jy] of jacobian) [sxx, sxy, syy] = [sxx + jx * jx, sxy + jx * jy, syy + jy * jy];
      const det = sxx * syy - sxy * sxy;
      if (!(Math.abs(det) > 1e-300)) break;
      const u = (syy * residual[0] - sxy * residual[1]) / det;
      const v = (sxx * residual[1] - sxy * residual[0]) / det;
      jacobian.forEach(([jx, jy], j) => {
        angles[j] -= jx * u + jy * v;
      });
    }
  }
  return angles.map((a, j) => (config.angle_coordinates[j] ? Math.atan2(Math.sin(a), Math.cos(a)) : a));
}

// A stand-in for an anywidget model: the drawing's state, and the messages between the
// drawing and the engine.
function localModel(initial) {
  const state = { ...initial };
  const listeners = {};
  const model = {
    get: (name) => state[name],
    set: (name, value) => {
      state[name] = value;
      for (const listener of listeners[`change:${name}`] || []) listener();
    },
    save_changes: () => {},
    on: (name, listener) => (listeners[name] = [...(listeners[name] || []), listener]),
    off: (name, listener) => (listeners[name] = (listeners[name] || []).filter((l) => l !== listener)),
    send: (content) => model.onsend && model.onsend(content),
    deliver: (content, buffers) => {
      for (const listener of listeners["msg:custom"] || []) listener(content, buffers);
    },
  };
  return model;
}

function control(tag, attributes, label) {
  const wrapper = document.createElement("label");
  wrapper.className = "plab-engine-control";
  wrapper.append(label + " ");
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  wrapper.append(node);
  return [wrapper, node];
}

// Mount a kernel-free simulator in `el`; `config` as widgets.browser.browser_config writes it.
// Returns {model, simulate(), run} for scripts and tests; the run shown is `state.run`.
export async function mount(el, config) {
  // a shipped model's module is a file; any other model's text came in the config
  const module = await import(config.source
    ? URL.createObjectURL(new Blob([config.source], { type: "text/javascript" }))
    : new URL(config.module, config.base || import.meta.url).href);
  const params = Float64Array.from(config.params);
  const state = { theta: Float64Array.from(config.theta0), omega: Float64Array.from(config.omega0),
    method: config.method, dt: config.dt, id: 0, run: null };
  const bar = document.createElement("div");
  bar.className = "plab-engine-bar";
  const [methodLabel, methodBox] = control("select", { "aria-label": "method" }, "method");
  for (const name of config.methods) {
    const option = document.createElement("option");
    option.value = name;
    option.textContent = name;
    methodBox.append(option);
  }
  const [dtLabel, dtBox] = control("select", { "aria-label": "time step" }, "Δt (s)");
  for (const dt of [...new Set([...DT_CHOICES, config.dt])].sort((a, b) => a - b)) {
    const option = document.createElement("option");
    option.value = String(dt);
    option.textContent = String(dt);
    dtBox.append(option);
  }
  const status = document.createElement("div");
  status.className = "plab-engine-status";
  status.setAttribute("role", "status");
  bar.append(methodLabel, dtLabel, status);
  const canvasHolder = document.createElement("div");
  el.replaceChildren(bar, canvasHolder);
  el.dataset.engine = "browser";

  const model = localModel({
    playing: true, speed: 1, speeds: config.speeds, trail: config.trail, loop: true, time: 0,
    run: 0, message: "", message_kind: "info", engine: "browser",
  });
  function say(text, kind = "info") {
    status.textContent = text;
    status.dataset.kind = kind;
    model.set("message", kind === "info" ? "" : text);
    model.set("message_kind", kind);
  }
  // One run from the current start; on failure the previous run goes on, with the reason.
  function compute() {
    const started = performance.now();
    try {
      const refusal = config.refused[state.method];
      if (refusal) throw new Error(refusal);
      const run = simulate(module, params, state.method, state.theta, state.omega, config.t_end, state.dt);
      state.id += 1;
      state.run = run;
      model.set("time", 0);
      for (const [content, buffers] of runMessages(run, module, params, config, state.id)) {
        model.deliver(content, buffers);
      }
      const ms = performance.now() - started;
      el.dataset.computeMs = ms.toFixed(2);
      el.dataset.run = String(state.id);
      say(`${run.steps} steps of ${state.method} (Δt = ${state.dt} s) computed in the browser in ` +
        `${ms.toFixed(0)} ms${run.completed ? "" : "; the state became non-finite and the run stops there"}.`);
      return true;
    } catch (error) {
      const what = error instanceof ConvergenceError ? "The solver did not converge" : "Cannot run this combination";
      say(`${what}: ${error.message}. The previous motion goes on.`, "error");
      return false;
    }
  }
  model.onsend = (content) => {
    if (content.type === "release") {
      let ok = false;
      try {
        const theta = releasedAngles(module, params, config, content.theta, content.bob,
          content.x === null ? NaN : content.x, content.y === null ? NaN : content.y);
        const previous = [state.theta, state.omega];
        [state.theta, state.omega] = [theta, new Float64Array(theta.length)];
        ok = compute();
        if (!ok) [state.theta, state.omega] = previous;
      } catch (error) {
        say(`Cannot start from that drag: ${error.message}. The previous motion goes on.`, "error");
      }
      model.set("playing", true);
      model.deliver({ type: "released", ok, message: status.textContent }, []);
    }
  };
  methodBox.value = state.method;
  dtBox.value = String(state.dt);
  methodBox.addEventListener("change", () => {
    const previous = state.method;
    state.method = methodBox.value;
    if (!compute()) {
      state.method = previous;
      methodBox.value = previous;
    }
  });
  dtBox.addEventListener("change", () => {
    const previous = state.dt;
    state.dt = Number(dtBox.value);
    if (!compute()) {
      state.dt = previous;
      dtBox.value = String(previous);
    }
  });
  render.render({ model, el: canvasHolder });
  compute();
  return { model, state, compute, module };
}
