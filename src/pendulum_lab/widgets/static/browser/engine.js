// The live simulator without a kernel: the browser integrates the motion itself.
//
// The simulator's drawing (../simulator.js) plays runs that arrive as messages; in JupyterLab
// the kernel sends them (pendulum_lab.widgets.live.run_messages). Here this module makes the
// same messages from a model's generated equations (./models/, pendulum_lab.codegen.browser)
// and the course's methods (./methods/), and hands them to the drawing through a small object
// that answers as an anywidget model does (get, set, on, off, save_changes, send). It
// integrates in real time: each animation frame takes the steps the time elapsed calls for
// (a little ahead of the motion shown) and sends the states kept, one per chunk, so the
// energy-error trace grows as the motion plays; a frame's steps are capped, and a device
// that cannot keep up falls behind and says so. A page
// mounts it with mount(element, config); config is what pendulum_lab.widgets.browser
// .browser_config writes. Nothing is fetched from another host.

import render from "../simulator.js";
import { ConvergenceError, makeField, METHODS } from "./methods/index.js";

const PLAYBACK_SPACING = 0.01; // widgets.live.PLAYBACK_SPACING
// Integrating ahead of the motion shown by this much simulated time (or two kept states, if
// longer) keeps the drawing from waiting for a state between two frames.
export const LEAD_SECONDS = 0.05;
// At most this many steps, and this much computing, in one frame: a slow device or a tab back
// from the background falls behind (and says so) rather than freezing the page.
export const MAX_STEPS_PER_FRAME = 400;
export const FRAME_BUDGET_MS = 8;
// Frames in a row within the cap before the note on falling behind goes away.
const CAUGHT_UP_FRAMES = 60;
export const DT_CHOICES = [0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1];

// floor(t_end / dt) with the package's slack (driver.simulate.step_count).
export function stepCount(tEnd, dt) {
  return Math.floor((tEnd / dt) * (1 + 1e-12));
}

// The state of one integration: the method's step from (theta0, omega0) with step dt, one step
// at a time. An implicit step that does not converge throws the kernel's sentence.
function integration(module, params, method, theta0, omega0, dt) {
  const entry = METHODS[method];
  if (!entry) throw new Error(`no method named ${method} in the browser (${Object.keys(METHODS)})`);
  const field = makeField(module, params);
  const q = Float64Array.from(theta0);
  const p = new Float64Array(q.length);
  module.momenta(0, q, Float64Array.from(omega0), field.params, p);
  const run = { n: q.length, dt, method, field, q, p, k: 0, memory: {},
    velocity: null, energies: new Float64Array(2) };
  // velocity and energies at the current state; false once the state is not finite
  run.measure = () => {
    const t = run.k * dt;
    [run.velocity] = field.hamilton(t, run.q, run.p);
    module.energies(t, run.q, run.velocity, field.params, run.energies);
    return [...run.q, ...run.p, run.energies[0], run.energies[1]].every(Number.isFinite);
  };
  run.step = () => {
    try {
      [run.q, run.p] = entry.step(field, run.k * dt, run.q, run.p, dt, run.memory);
    } catch (error) {
      if (!(error instanceof ConvergenceError)) throw error;
      const at = run.k + 1;
      throw new ConvergenceError(
        `${method}: the implicit equations did not converge within 100 iterations at step ` +
          `${at} (t = ${Number((at * dt).toPrecision(6))}, dt = ${dt}); use a smaller dt`,
      );
    }
    run.k += 1;
  };
  return run;
}

// Integrate `module` (a generated model) from (theta0, omega0) with `method` over tEnd with
// step dt, all at once (for tests and the benchmark). Every state is kept: angles, momenta,
// velocities, kinetic and potential energy.
export function simulate(module, params, method, theta0, omega0, tEnd, dt) {
  const steps = stepCount(tEnd, dt);
  const run = integration(module, params, method, theta0, omega0, dt);
  const n = run.n;
  const theta = new Float64Array((steps + 1) * n);
  const momenta = new Float64Array((steps + 1) * n);
  const omega = new Float64Array((steps + 1) * n);
  const kinetic = new Float64Array(steps + 1);
  const potential = new Float64Array(steps + 1);
  let kept = steps + 1;
  for (let k = 0; k <= steps; k++) {
    const finite = run.measure();
    theta.set(run.q, k * n);
    momenta.set(run.p, k * n);
    omega.set(run.velocity, k * n);
    [kinetic[k], potential[k]] = run.energies;
    if (!finite) {
      kept = k; // the state became non-finite: the run stops before it
      break;
    }
    if (k === steps) break;
    run.step();
  }
  return {
    n, dt, steps, method, kept, completed: kept === steps + 1, evaluations: run.field.evaluations,
    theta: theta.subarray(0, kept * n), p: momenta.subarray(0, kept * n),
    omega: omega.subarray(0, kept * n), kinetic: kinetic.subarray(0, kept),
    potential: potential.subarray(0, kept),
  };
}

// A run integrated as it plays: advance(steps) takes that many steps and keeps every state the
// drawing plays (one per PLAYBACK_SPACING, as widgets.live.run_messages keeps them); messages
// (from, to) are the kernel's run messages of the kept states [from, to), one state per chunk,
// their scales (energy range, largest energy error, reach) as far as the run has come.
export function liveRun(module, params, config, method, theta0, omega0, dt) {
  const run = integration(module, params, method, theta0, omega0, dt);
  const n = run.n;
  const steps = stepCount(config.t_end, dt);
  const stride = Math.max(1, Math.floor((PLAYBACK_SPACING / dt) * (1 + 1e-9)));
  const planned = Math.ceil((steps + 1) / stride);
  const count = config.figure.masses.length;
  const points = config.figure.kind === "points";
  const width = module.DIMENSIONS || 2; // (x, y), or (x, y, z) for points in space
  const kept = {
    angles: new Float32Array(planned * n), energies: new Float32Array(planned * 3),
    error: new Float32Array(planned), points: new Float32Array(points ? planned * count * width : 0),
  };
  const place = new Float64Array(width * module.POINTS);
  const live = { id: 0, method, dt, steps, stride, states: 0, planned, done: false, completed: true,
    energy0: NaN, low: 0, high: 0, errorMax: 0, figure: { ...config.figure }, integration: run };
  live.time = () => run.k * dt;
  // the lead holds at least two kept states, whatever the step
  live.lead = Math.max(LEAD_SECONDS, 2 * stride * dt);
  function measure() {
    const finite = run.measure();
    const total = run.energies[0] + run.energies[1];
    if (run.k === 0) live.energy0 = total;
    // E - E(0) in float64 before the cast, as the kernel does
    if (Number.isFinite(total)) live.errorMax = Math.max(live.errorMax, Math.abs(total - live.energy0));
    if (!finite) {
      live.done = true; // the state became non-finite: the run stops before it
      live.completed = false;
      return;
    }
    if (run.k % stride === 0) {
      const s = live.states++;
      kept.angles.set(run.q, s * n);
      kept.energies.set([run.energies[0], run.energies[1], total], s * 3);
      kept.error[s] = total - live.energy0;
      for (const e of [run.energies[0], run.energies[1], total]) {
        [live.low, live.high] = [Math.min(live.low, e), Math.max(live.high, e)];
      }
      if (points) {
        module.positions(run.k * dt, run.q, params, place);
        kept.points.set(place, s * count * width);
        const reach = Math.max(live.figure.reach, ...place.map(Math.abs).filter(Number.isFinite));
        if (reach > live.figure.reach) live.figure = { ...live.figure, reach };
      }
    }
    if (run.k === steps) live.done = true;
  }
  measure();
  // Take up to `count` steps (fewer at the run's end); returns the steps taken.
  live.advance = (wanted) => {
    let taken = 0;
    while (taken < wanted && !live.done) {
      run.step();
      taken += 1;
      measure();
    }
    return taken;
  };
  live.messages = (from, to) => {
    const meta = {
      type: "run", run: live.id, chunks: planned, chunk_states: 1,
      states: live.done ? live.states : planned, links: n, lengths: config.lengths,
      figure: live.figure, spacing: stride * dt, dt, stride,
      steps: live.done ? run.k - (live.completed ? 0 : 1) : steps, method,
      energy0: live.energy0, energy_range: [live.low, live.high], error_max: live.errorMax,
      completed: live.completed, conserved: config.conserved, forces: config.forces,
      changed_by: config.changed_by,
    };
    const messages = [];
    for (let s = from; s < to; s++) {
      const part = (array, width) => new DataView(array.slice(s * width, (s + 1) * width).buffer);
      const buffers = [part(kept.angles, n), part(kept.energies, 3), part(kept.error, 1)];
      if (points) buffers.push(part(kept.points, count * width));
      messages.push([{ ...meta, chunk: s, first: s, count: 1 }, buffers]);
    }
    return messages;
  };
  return live;
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
  // the cap and the budget of a frame (a test sets them to count steps, not time)
  const maxSteps = config.max_steps_per_frame || MAX_STEPS_PER_FRAME;
  const budgetMs = config.frame_budget_ms || FRAME_BUDGET_MS;
  const clock = { shown: 0, last: null, computeMs: 0, behindFrames: 0, caughtUp: 0, running: true };
  let previous = null; // the run before the current one, while the current one may still fail
  function describeRun(live) {
    const words = `${live.steps} steps of ${live.method} (Δt = ${live.dt} s) computed in the browser`;
    if (!live.done) return `${words} as the motion plays.`;
    return `${words} as the motion played (${clock.computeMs.toFixed(0)} ms of computing in all)` +
      `${live.completed ? "" : "; the state became non-finite and the run stops there"}.`;
  }
  // Hand the drawing the states kept since the last delivery.
  function deliver(live, from = live.delivered) {
    for (const [content, buffers] of live.messages(from, live.states)) model.deliver(content, buffers);
    live.delivered = live.states;
    el.dataset.states = String(live.states);
    el.dataset.steps = String(live.integration.k);
  }
  function show(live) {
    state.id += 1;
    live.id = state.id;
    state.run = live;
    clock.shown = 0;
    clock.last = null;
    model.set("time", 0);
    deliver(live, 0);
    el.dataset.run = String(state.id);
  }
  // Integrate the current run up to the time shown plus the lead, within the frame's cap.
  function integrate(live, untilTime, started) {
    const wanted = Math.max(0, Math.floor((untilTime / live.dt) * (1 + 1e-9)) - live.integration.k);
    let taken = 0;
    while (taken < Math.min(wanted, maxSteps) && !live.done) {
      taken += live.advance(1);
      if (performance.now() - started > budgetMs) break;
    }
    return [wanted, taken];
  }
  // A new run from the current start; the lead is integrated at once, so that a step that
  // does not converge at the start leaves the previous run going on.
  function compute() {
    const started = performance.now();
    try {
      const refusal = config.refused[state.method];
      if (refusal) throw new Error(refusal);
      const live = liveRun(module, params, config, state.method, state.theta, state.omega, state.dt);
      live.advance(Math.ceil((live.lead / state.dt) * (1 - 1e-9)));
      previous = state.run ? { run: state.run, method: state.method0, dt: state.dt0,
        theta: state.theta0, omega: state.omega0 } : null;
      [state.method0, state.dt0, state.theta0, state.omega0] = [state.method, state.dt, state.theta, state.omega];
      clock.computeMs = performance.now() - started;
      show(live);
      say(describeRun(live));
      return true;
    } catch (error) {
      const what = error instanceof ConvergenceError ? "The solver did not converge" : "Cannot run this combination";
      say(`${what}: ${error.message}. The previous motion goes on.`, "error");
      return false;
    }
  }
  // A step of the current run failed later in its course: the previous run goes on, from its
  // start, and goes on integrating where it had stopped.
  function fallBack(error) {
    say(`The solver did not converge: ${error.message}. The previous motion goes on.`, "error");
    if (!previous) {
      // nothing to go back to: the run ends at its last step and plays again from its start
      // (as a new run, so that the drawing takes its length)
      state.run.done = true;
      show(state.run);
      return;
    }
    [state.method, state.dt, state.theta, state.omega] = [previous.method, previous.dt, previous.theta, previous.omega];
    [state.method0, state.dt0, state.theta0, state.omega0] = [state.method, state.dt, state.theta, state.omega];
    methodBox.value = state.method;
    dtBox.value = String(state.dt);
    const live = previous.run;
    previous = null;
    show(live);
  }
  // One animation frame: the time shown moves on by the time elapsed (at the drawing's speed),
  // and the run is integrated that far ahead.
  function frame(elapsedMs) {
    const live = state.run;
    if (!live || !model.get("playing")) return 0;
    const started = performance.now();
    clock.shown += (elapsedMs / 1000) * model.get("speed");
    if (live.done) return 0;
    let wanted = 0;
    let taken = 0;
    try {
      [wanted, taken] = integrate(live, clock.shown + live.lead, started);
    } catch (error) {
      if (!(error instanceof ConvergenceError)) throw error;
      fallBack(error);
      return 0;
    }
    clock.computeMs += performance.now() - started;
    if (taken < wanted && !live.done) {
      // behind: the motion waits for the states, the backlog is dropped
      clock.shown = live.time() - live.lead;
      clock.behindFrames += 1;
      clock.caughtUp = 0;
      el.dataset.behind = String(clock.behindFrames);
      if (status.dataset.kind !== "behind" && status.dataset.kind !== "error") {
        status.textContent = `Falling behind: this device computed ${taken} of the ${wanted} steps ` +
          `of ${live.method} (Δt = ${live.dt} s) this frame called for, so the motion plays ` +
          "slower than real time.";
        status.dataset.kind = "behind";
      }
    } else if (status.dataset.kind === "behind" && ++clock.caughtUp >= CAUGHT_UP_FRAMES) {
      say(describeRun(live));
    }
    if (live.states > live.delivered) deliver(live);
    if (live.done) {
      previous = null; // the run is whole: nothing can fail any more
      if (status.dataset.kind !== "error") say(describeRun(live));
    }
    return taken;
  }
  function tick(stamp) {
    if (!clock.running) return;
    requestAnimationFrame(tick);
    frame(clock.last === null ? 0 : stamp - clock.last);
    clock.last = stamp;
  }
  model.on("change:playing", () => {
    clock.last = null; // a pause is not elapsed time
  });
  model.onsend = (content) => {
    if (content.type === "release") {
      let ok = false;
      try {
        const theta = releasedAngles(module, params, config, content.theta, content.bob,
          content.x === null ? NaN : content.x, content.y === null ? NaN : content.y);
        const before = [state.theta, state.omega];
        [state.theta, state.omega] = [theta, new Float64Array(theta.length)];
        ok = compute();
        if (!ok) [state.theta, state.omega] = before;
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
    const before = state.method;
    state.method = methodBox.value;
    if (!compute()) {
      state.method = before;
      methodBox.value = before;
    }
  });
  dtBox.addEventListener("change", () => {
    const before = state.dt;
    state.dt = Number(dtBox.value);
    if (!compute()) {
      state.dt = before;
      dtBox.value = String(before);
    }
  });
  render.render({ model, el: canvasHolder });
  compute();
  requestAnimationFrame(tick); // after the drawing's own loop: its frame sees this frame's states
  // frame(ms) advances by hand; stop() ends the loop (tests drive the frames themselves)
  return { model, state, compute, module, frame, stop: () => (clock.running = false) };
}
