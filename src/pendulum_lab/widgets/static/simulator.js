// The live pendulum simulator, drawn in the browser (anywidget front-end module).
//
// The kernel sends each run as float32 buffers in chunks (pendulum_lab.widgets.live.
// run_messages); this module plays the run with requestAnimationFrame at the display's
// frame rate, interpolating linearly between the saved states, and draws the model with
// a trail, energy bars, the energy-error trace and the readouts. The model is points
// joined by rods and springs (header.figure): a chain's points come from its angles and
// lengths, a system's points are sent beside its coordinates. Dragging a bob moves the
// chain (a system's point follows the pointer alone); on release the kernel is asked for
// the motion from there. A point the coordinates do not place (a shaken pivot) is not
// dragged: its sentence, from the kernel, goes to the status line. A system in space
// (figure.dimensions = 3, points sent as x, y, z with z up) is drawn in a projection the
// student turns: a drag on anything but a bob in the top view turns it about the vertical
// (left-right) and tilts it (up-down); "reset view", "top" and "side" pick one. Only seen from
// straight above is a point's place on the screen a place in space (its horizontal x, y: the
// height follows from the coordinates), so only there does dragging a bob set the start. A text
// description of the state shown (time, energies, energy error) is kept in an ARIA live
// region, updated when the state shown changes other than by playing (a step, a scrub,
// pause, a new run) and when playing starts or ends, so that a screen reader announces it.
// No imports, nothing from the network: the file travels inside the Python package.

const WIDTH = 900;
const HEIGHT = 340;
const CHAIN = 340; // the chain's square panel, at the left
const READOUT_CHARS = 38; // characters of the readout's monospace lines that fit the canvas
const COLOURS = {
  kinetic: "#1f77b4",
  potential: "#ff7f0e",
  total: "#000000",
  trail: "#9467bd",
  bob: "#d62728",
  rod: "#404040",
  grid: "#d0d0d0",
  text: "#222222",
  faint: "#9a9a9a",
};
// A system in space: the view it opens with (turned 30 degrees, seen from 25 degrees above the
// horizontal), radians per pixel of a turning drag, and how far from the pivot (a fraction of
// the dragged point's distance from it) a drag in the top view may place a point: where
// coordinates such as the spherical pendulum's (x, y) fail, at the pivot's level, stays out.
const VIEW_START = { turn: -Math.PI / 6, tilt: (25 * Math.PI) / 180 };
const TURN_PER_PIXEL = 0.01;
const DRAG_REACH = 0.95;
const TOP = Math.PI / 2;
const PLANE_HINT = "drag a bob · Space play/pause · ←/→ step · ↑/↓ speed";
const SPACE_HINT = "drag the picture to turn it · to set where the bob starts: “top”, then " +
  "drag the bob · Space play/pause · ←/→ step";
const KEY_HELP =
  "Space or K: play or pause. Left and right arrows: one step back or forward. " +
  "Up and down arrows: faster or slower. Home, End: start, end. " +
  "Drag a bob to start the motion from there.";

function element(tag, className, attributes = {}) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  return node;
}

// One run as it arrives: preallocated arrays filled chunk by chunk.
function newRun(header) {
  const { states, links, figure } = header;
  const sentPoints = figure.kind === "points" ? figure.masses.length : 0;
  const width = figure.dimensions || 2; // x, y (and z for points in space)
  return {
    id: header.run,
    meta: header,
    angles: new Float32Array(states * links),
    points: new Float32Array(states * sentPoints * width), // a system's x, y (, z) of each point
    energies: new Float32Array(states * 3),
    error: new Float32Array(states),
    lastBob: new Float32Array(states * 3), // x, y, z of the last bob, for the trail (z = 0 in a plane)
    got: new Set(),
    available: 0, // states received without a gap from the first
  };
}

// What a run integrated as it plays (browser/engine.js) knows better with each chunk: its
// length if it stops early, and the scales (energy range, largest error, reach) so far.
const GROWING = ["states", "steps", "completed", "energy_range", "error_max", "figure"];

function addChunk(run, header, buffers) {
  if (run.got.has(header.chunk)) return;
  for (const key of GROWING) if (key in header) run.meta[key] = header[key];
  const n = header.links;
  const floats = (view) => new Float32Array(view.buffer, view.byteOffset, view.byteLength / 4);
  run.angles.set(floats(buffers[0]), header.first * n);
  run.energies.set(floats(buffers[1]), header.first * 3);
  run.error.set(floats(buffers[2]), header.first);
  const figure = header.figure;
  if (figure.kind === "points") {
    const count = figure.masses.length;
    const width = figure.dimensions || 2;
    run.points.set(floats(buffers[3]), header.first * count * width);
    for (let i = header.first; i < header.first + header.count; i++) {
      for (let c = 0; c < width; c++) {
        run.lastBob[3 * i + c] = run.points[(i * count + figure.trailed) * width + c];
      }
    }
  }
  const lengths = figure.kind === "chain" ? header.lengths : [];
  for (let i = header.first; figure.kind === "chain" && i < header.first + header.count; i++) {
    let x = 0;
    let y = 0;
    for (let j = 0; j < n; j++) {
      const a = run.angles[i * n + j];
      x += lengths[j] * Math.sin(a);
      y -= lengths[j] * Math.cos(a);
    }
    run.lastBob[3 * i] = x;
    run.lastBob[3 * i + 1] = y;
  }
  run.got.add(header.chunk);
  // Playable: the states up to the first chunk still missing.
  const size = run.meta.chunk_states;
  while (run.available < run.meta.states && run.got.has(run.available / size)) {
    run.available = Math.min(run.meta.states, run.available + size);
  }
}

function format(value, digits = 3) {
  if (!Number.isFinite(value)) return String(value);
  return value.toFixed(digits);
}

function render({ model, el }) {
  const root = element("div", "plab-live", {
    tabindex: "0",
    role: "group",
    "aria-label": "Pendulum simulator. " + KEY_HELP,
    "data-lm-suppress-shortcuts": "true",
  });
  const canvas = element("canvas", "plab-live-canvas", {
    role: "img",
    "aria-label": "The pendulum, its energies and its energy error",
  });
  const bar = element("div", "plab-live-bar");
  const back = element("button", "plab-button", { type: "button", title: "one step back (Left)" });
  back.textContent = "◀|";
  const play = element("button", "plab-button plab-play", { type: "button", title: "play/pause (Space)" });
  const forward = element("button", "plab-button", { type: "button", title: "one step forward (Right)" });
  forward.textContent = "|▶";
  const speedBox = element("select", "plab-speed", { title: "playback speed (Up/Down)", "aria-label": "playback speed" });
  const scrub = element("input", "plab-scrub", {
    type: "range",
    min: "0",
    max: "0",
    step: "1",
    value: "0",
    "aria-label": "time",
  });
  const clock = element("span", "plab-clock");
  // The views of a system in space (hidden in a plane).
  const views = element("span", "plab-views", { role: "group", "aria-label": "view" });
  const viewButtons = {};
  for (const [name, title] of [
    ["reset view", "the view it opened with"],
    ["top", "from straight above: drag the bob to set where it starts"],
    ["side", "from the side: x across, z up"],
  ]) {
    viewButtons[name] = element("button", "plab-button plab-view", { type: "button", title });
    viewButtons[name].textContent = name;
    views.append(viewButtons[name]);
  }
  views.hidden = true;
  const help = element("span", "plab-help");
  const status = element("div", "plab-status", { role: "status", "aria-live": "polite" });
  const description = element("div", "plab-sr-only plab-description", {
    "aria-live": "polite",
    "aria-atomic": "true",
  });
  bar.append(back, play, forward, speedBox, scrub, clock, views);
  root.append(canvas, bar, help, status, description);
  el.appendChild(root);

  const context = canvas.getContext("2d");
  let scale = 1; // device pixels per CSS pixel
  function fitCanvas() {
    scale = window.devicePixelRatio || 1;
    canvas.width = Math.round(WIDTH * scale);
    canvas.height = Math.round(HEIGHT * scale);
    canvas.style.width = `${WIDTH}px`;
    canvas.style.height = "auto"; // keeps the aspect ratio where max-width narrows it
  }
  fitCanvas();

  // ---- state -----------------------------------------------------------------------------
  let run = null; // the run shown
  let incoming = null; // a newer run still arriving (shown once its first chunk is in)
  let t = model.get("time") || 0;
  let playing = model.get("playing");
  let speed = model.get("speed");
  let lastStamp = null;
  let frames = 0;
  let dirty = true;
  let dragging = null; // {bob, angles, pointerId}
  let view = { ...VIEW_START }; // a system in space: turn about the vertical, tilt above the horizontal
  let turning = null; // a drag turning the view: {pointerId, px, py, turn, tilt}
  let pending = false; // a release sent, no answer yet
  let frameId = 0;
  let drawSeconds = 0; // time spent drawing, for data-draw-ms (the cost of one frame)
  let describeDue = true; // the description waits for the next frame drawn

  function setStatus(text, kind) {
    status.textContent = text || "";
    status.dataset.kind = kind || "info";
  }
  function showModelMessage() {
    setStatus(model.get("message"), model.get("message_kind"));
  }
  showModelMessage();

  function fillSpeeds() {
    speedBox.replaceChildren();
    for (const s of model.get("speeds")) {
      const option = element("option", "", { value: String(s) });
      option.textContent = `${s}×`;
      speedBox.appendChild(option);
    }
    speedBox.value = String(speed);
  }
  fillSpeeds();
  showViews();

  function duration() {
    if (!run) return 0;
    return (Math.max(run.available, 1) - 1) * run.meta.spacing;
  }
  function fullDuration() {
    return run ? (run.meta.states - 1) * run.meta.spacing : 0;
  }

  function setPlaying(value, save = true) {
    if (value && run && run.available === run.meta.states && t >= duration()) t = 0;
    if (value !== playing) describeDue = true;
    playing = value;
    play.textContent = playing ? "❚❚ pause" : "▶ play";
    play.setAttribute("aria-pressed", playing ? "true" : "false");
    root.dataset.playing = playing ? "1" : "0";
    lastStamp = null;
    if (save && model.get("playing") !== playing) {
      model.set("playing", playing);
      if (!playing) model.set("time", t);
      model.save_changes();
    }
    dirty = true;
  }
  setPlaying(playing, false);

  function seek(time, save = true) {
    t = Math.min(Math.max(time, 0), duration());
    dirty = true;
    describeDue = true;
    if (save) {
      model.set("time", t);
      model.save_changes();
    }
  }

  function stepBy(direction) {
    if (!run) return;
    setPlaying(false);
    const index = Math.round(t / run.meta.spacing) + direction;
    seek(index * run.meta.spacing);
  }

  function changeSpeed(direction) {
    const speeds = model.get("speeds");
    const k = speeds.indexOf(speed);
    const next = speeds[Math.min(Math.max(k + direction, 0), speeds.length - 1)];
    if (next !== speed) {
      speed = next;
      speedBox.value = String(speed);
      model.set("speed", speed);
      model.save_changes();
      dirty = true;
      describeDue = true;
    }
  }

  // ---- interpolation ---------------------------------------------------------------------
  function anglesAt(time) {
    const n = run.meta.links;
    const last = Math.max(run.available - 1, 0);
    const s = Math.min(time / run.meta.spacing, last);
    const i = Math.min(Math.floor(s), last);
    const f = i < last ? s - i : 0;
    const out = new Float64Array(n);
    for (let j = 0; j < n; j++) {
      const a = run.angles[i * n + j];
      const b = i < last ? run.angles[(i + 1) * n + j] : a;
      out[j] = a + f * (b - a);
    }
    return out;
  }
  // A system's points at `time`: [xs, ys, zs], interpolated like the coordinates (zs zero
  // in a plane).
  function pointsAt(time) {
    const count = run.meta.figure.masses.length;
    const width = run.meta.figure.dimensions || 2;
    const xs = new Float64Array(count);
    const ys = new Float64Array(count);
    const zs = new Float64Array(count);
    for (let j = 0; j < count; j++) {
      xs[j] = seriesAt(run.points, width * count, width * j, time);
      ys[j] = seriesAt(run.points, width * count, width * j + 1, time);
      if (width === 3) zs[j] = seriesAt(run.points, width * count, width * j + 2, time);
    }
    return [xs, ys, zs];
  }
  function seriesAt(array, width, column, time) {
    const last = Math.max(run.available - 1, 0);
    const s = Math.min(time / run.meta.spacing, last);
    const i = Math.min(Math.floor(s), last);
    const f = i < last ? s - i : 0;
    const a = array[i * width + column];
    const b = i < last ? array[(i + 1) * width + column] : a;
    return a + f * (b - a);
  }

  // ---- geometry of the chain panel -------------------------------------------------------
  function chainScale() {
    const reach = run ? run.meta.figure.reach : 2;
    return (CHAIN / 2 - 14) / (1.05 * reach);
  }
  const pivot = { x: CHAIN / 2, y: CHAIN / 2 };
  // In space the pivot moves up or down with the tilt, so that the floor circle (radius and
  // depth reach) and the pivot's level, seen from view.tilt, sit centred in the panel.
  function placePivot() {
    pivot.y = CHAIN / 2;
    if (!inSpace()) return;
    const reach = run.meta.figure.reach;
    const [sin, cos] = [Math.sin(view.tilt), Math.cos(view.tilt)];
    const [low, high] = [-reach * (sin + cos), Math.max(0, reach * (sin - cos))];
    pivot.y = CHAIN / 2 + chainScale() * ((low + high) / 2);
  }
  function toCanvas(x, y, s) {
    return [pivot.x + x * s, pivot.y - y * s];
  }
  function inSpace() {
    return Boolean(run) && run.meta.figure.dimensions === 3;
  }
  function topView() {
    return inSpace() && view.tilt === TOP;
  }
  // The picture's (across, up) [m] of the point (x, y, z): turned by view.turn about the
  // vertical z, then seen from view.tilt above the horizontal (0: from the side, x across and z
  // up; pi/2: from above, x across and y up). In a plane, (x, y) as it is.
  function project(x, y, z) {
    if (!inSpace()) return [x, y];
    const [c, s] = [Math.cos(view.turn), Math.sin(view.turn)];
    const deep = -x * s + y * c;
    return [x * c + y * s, deep * Math.sin(view.tilt) + z * Math.cos(view.tilt)];
  }
  // A point of the top view's picture, (across, up) [m], as the horizontal (x, y) it shows.
  function unproject(across, up) {
    const [c, s] = [Math.cos(view.turn), Math.sin(view.turn)];
    return [across * c - up * s, across * s + up * c];
  }
  function screen(x, y, z, s) {
    return toCanvas(...project(x, y, z), s);
  }
  // The points of the configuration shown, [xs, ys, zs] (the pivot not among them; zs zero
  // in a plane).
  function positions(angles) {
    if (run.meta.figure.kind === "points") {
      return dragging ? [dragging.xs, dragging.ys, dragging.zs] : pointsAt(t);
    }
    const lengths = run.meta.lengths;
    const xs = [];
    const ys = [];
    let x = 0;
    let y = 0;
    for (let j = 0; j < angles.length; j++) {
      x += lengths[j] * Math.sin(angles[j]);
      y -= lengths[j] * Math.cos(angles[j]);
      xs.push(x);
      ys.push(y);
    }
    return [xs, ys, new Float64Array(xs.length)];
  }
  function bobRadius(j) {
    const masses = run.meta.figure.masses;
    return masses[j] > 0 ? 4 + 8 * Math.sqrt(masses[j] / Math.max(...masses)) : 4;
  }

  // ---- drawing ---------------------------------------------------------------------------
  function draw() {
    const c = context;
    c.setTransform(scale, 0, 0, scale, 0, 0);
    c.clearRect(0, 0, WIDTH, HEIGHT);
    c.fillStyle = "#ffffff";
    c.fillRect(0, 0, WIDTH, HEIGHT);
    if (!run || run.available === 0) {
      c.fillStyle = COLOURS.faint;
      c.font = "14px sans-serif";
      // in a page without a kernel the browser computes the run (browser/engine.js)
      c.fillText(model.get("engine") === "browser" ? "computing…" : "waiting for the kernel…", 20, 30);
      return;
    }
    const angles = dragging ? dragging.angles : anglesAt(t);
    drawChain(c, angles);
    drawBars(c);
    drawError(c);
    drawReadout(c);
    root.dataset.time = t.toFixed(4);
    root.dataset.theta = Array.from(angles, (a) => a.toFixed(5)).join(",");
    const [xs, ys, zs] = positions(angles);
    const space = inSpace();
    root.dataset.points = Array.from(xs, (x, j) =>
      `${x.toFixed(5)} ${ys[j].toFixed(5)}${space ? ` ${zs[j].toFixed(5)}` : ""}`).join(",");
    if (space) root.dataset.view = `${view.turn.toFixed(5)},${view.tilt.toFixed(5)}`;
  }

  function drawChain(c, angles) {
    const s = chainScale();
    placePivot();
    root.dataset.scale = s.toFixed(6);
    root.dataset.pivot = `${pivot.x.toFixed(3)},${pivot.y.toFixed(3)}`;
    c.strokeStyle = COLOURS.grid;
    c.lineWidth = 1;
    c.strokeRect(0.5, 0.5, CHAIN - 1, CHAIN - 1);
    if (inSpace()) drawReference(c, s);
    // Trail of the last bob over the past `trail` seconds, fading out.
    const trail = model.get("trail");
    if (!dragging && trail > 0) {
      const spacing = run.meta.spacing;
      const last = Math.min(Math.floor(t / spacing), run.available - 1);
      const first = Math.max(0, Math.ceil((t - trail) / spacing));
      const [xs, ys, zs] = positions(angles);
      const segments = 8;
      const per = Math.max(1, Math.ceil((last - first + 1) / segments));
      c.lineWidth = 1.5;
      for (let k = first; k <= last; k += per) {
        const end = Math.min(k + per, last);
        c.beginPath();
        c.globalAlpha = 0.15 + 0.6 * ((k - first) / Math.max(last - first, 1));
        c.strokeStyle = COLOURS.trail;
        const bob = run.lastBob;
        c.moveTo(...screen(bob[3 * k], bob[3 * k + 1], bob[3 * k + 2], s));
        for (let i = k + 1; i <= end; i++) c.lineTo(...screen(bob[3 * i], bob[3 * i + 1], bob[3 * i + 2], s));
        const j = run.meta.figure.trailed;
        if (end === last) c.lineTo(...screen(xs[j], ys[j], zs[j], s));
        c.stroke();
      }
      c.globalAlpha = 1;
    }
    const [xs, ys, zs] = positions(angles);
    const figure = run.meta.figure;
    const at = (k) => (k < 0 ? toCanvas(0, 0, s) : screen(xs[k], ys[k], zs[k], s));
    c.strokeStyle = COLOURS.rod;
    c.lineWidth = 3;
    for (const [i, j] of figure.rods) {
      c.beginPath();
      c.moveTo(...at(i));
      c.lineTo(...at(j));
      c.stroke();
    }
    c.lineWidth = 1.5;
    for (const [i, j] of figure.springs) drawSpring(c, at(i), at(j));
    c.fillStyle = "#000000";
    if (figure.uses_origin) c.fillRect(pivot.x - 4, pivot.y - 4, 8, 8);
    for (let j = 0; j < xs.length; j++) {
      const [px, py] = at(j);
      if (figure.masses[j] === 0) {
        c.fillStyle = "#000000"; // a massless point: a shaken pivot
        c.fillRect(px - 4, py - 4, 8, 8);
        continue;
      }
      c.beginPath();
      c.arc(px, py, bobRadius(j), 0, 2 * Math.PI);
      c.fillStyle = dragging && dragging.bob === j ? "#ff9896" : COLOURS.bob;
      c.fill();
      c.strokeStyle = "#000000";
      c.lineWidth = 1;
      c.stroke();
    }
    if (dragging || pending) {
      c.fillStyle = COLOURS.text;
      c.font = "12px sans-serif";
      c.fillText(pending ? "computing the new motion…" : "release to start from here", 10, CHAIN - 10);
    }
  }

  // A system in space: a faint floor circle (radius reach, at the depth of reach below the
  // pivot) with its x and y axes, the plumb line from the pivot and each bob's shadow on the
  // floor, so that a turn of the view shows; the view's name in the corner.
  function drawReference(c, s) {
    const reach = run.meta.figure.reach;
    const floor = -reach;
    c.save();
    c.strokeStyle = COLOURS.grid;
    c.lineWidth = 1;
    c.beginPath();
    for (let k = 0; k <= 64; k++) {
      const a = (2 * Math.PI * k) / 64;
      const [px, py] = screen(reach * Math.cos(a), reach * Math.sin(a), floor, s);
      if (k === 0) c.moveTo(px, py);
      else c.lineTo(px, py);
    }
    c.stroke();
    c.fillStyle = COLOURS.faint;
    c.font = "12px sans-serif";
    for (const [label, ax, ay] of [["x", 1, 0], ["y", 0, 1]]) {
      c.beginPath();
      c.moveTo(...screen(0, 0, floor, s));
      const end = screen(ax * reach, ay * reach, floor, s);
      c.lineTo(...end);
      c.stroke();
      c.fillText(label, end[0] + 3, end[1] - 3);
    }
    c.setLineDash([3, 4]);
    c.beginPath();
    c.moveTo(...screen(0, 0, 0, s));
    c.lineTo(...screen(0, 0, floor, s));
    c.stroke();
    c.setLineDash([]);
    const [xs, ys] = positions(dragging ? dragging.angles : anglesAt(t));
    for (let j = 0; j < xs.length; j++) {
      if (run.meta.figure.masses[j] === 0) continue;
      const [px, py] = screen(xs[j], ys[j], floor, s);
      c.beginPath();
      c.arc(px, py, 3, 0, 2 * Math.PI);
      c.fill();
    }
    const name = topView() ? "from above: drag the bob"
      : view.tilt === 0 && view.turn === 0 ? "from the side: x, z"
        : `turned ${Math.round((view.turn * 180) / Math.PI)}°, ` +
          `${Math.round((view.tilt * 180) / Math.PI)}° above`;
    c.fillText(name, 8, 16);
    c.restore();
  }

  // A zigzag between two canvas points, of constant width however far it is stretched.
  function drawSpring(c, [x0, y0], [x1, y1]) {
    const length = Math.hypot(x1 - x0, y1 - y0);
    if (length === 0) return;
    const [ux, uy] = [(x1 - x0) / length, (y1 - y0) / length];
    const turns = 9;
    const width = 6;
    c.beginPath();
    c.moveTo(x0, y0);
    for (let k = 0; k <= 2 * turns; k++) {
      const along = length * (0.1 + (0.8 * k) / (2 * turns));
      const side = k === 0 || k === 2 * turns ? 0 : k % 2 ? width : -width;
      c.lineTo(x0 + along * ux - side * uy, y0 + along * uy + side * ux);
    }
    c.lineTo(x1, y1);
    c.stroke();
  }

  function drawBars(c) {
    const left = CHAIN + 30;
    const top = 40;
    const bottom = HEIGHT - 40;
    const [low, high] = run.meta.energy_range;
    const span = Math.max(high - low, 1e-12);
    const yOf = (e) => bottom - ((Math.min(Math.max(e, low), high) - low) / span) * (bottom - top);
    const names = [
      ["T", "kinetic", 0],
      ["V", "potential", 1],
      ["E", "total", 2],
    ];
    c.font = "12px sans-serif";
    c.fillStyle = COLOURS.text;
    c.fillText("energy (J)", left, 20);
    c.strokeStyle = COLOURS.faint;
    c.lineWidth = 1;
    c.beginPath();
    c.moveTo(left - 6, yOf(0));
    c.lineTo(left + 170, yOf(0));
    c.stroke();
    names.forEach(([label, key, column], k) => {
      const value = seriesAt(run.energies, 3, column, t);
      const x = left + k * 56;
      const y0 = yOf(0);
      const y1 = yOf(value);
      c.fillStyle = COLOURS[key];
      c.fillRect(x, Math.min(y0, y1), 36, Math.max(Math.abs(y1 - y0), 1));
      c.fillStyle = COLOURS.text;
      c.fillText(label, x + 13, bottom + 16);
      c.fillText(format(value, 2), x, bottom + 30);
    });
    // Dotted line at E(0): the total-energy bar should stay on it.
    c.setLineDash([3, 3]);
    c.strokeStyle = COLOURS.total;
    c.beginPath();
    c.moveTo(left + 106, yOf(run.meta.energy0));
    c.lineTo(left + 150, yOf(run.meta.energy0));
    c.stroke();
    c.setLineDash([]);
    c.fillText("E(0)", left + 152, yOf(run.meta.energy0) + 4);
  }

  // What the readout shows, in sentences (the live region's text).
  function energyWords(meta) {
    return meta.conserved
      ? "energy error E − E(0)"
      : `energy change E − E(0) (energy is not conserved: ${meta.forces})`;
  }
  function describe() {
    if (!run || run.available === 0) return "Waiting for the kernel.";
    const meta = run.meta;
    const [kinetic, potential, total] = [0, 1, 2].map((k) => seriesAt(run.energies, 3, k, t));
    const error = seriesAt(run.error, 1, 0, t);
    const state = playing ? `Playing at ${speed}× speed from` : "Paused at";
    return (
      `${state} t = ${format(t, 2)} s of ${format(fullDuration(), 1)} s (${meta.method}, ` +
      `Δt = ${meta.dt} s). Kinetic energy T = ${format(kinetic, 3)} J, potential energy ` +
      `V = ${format(potential, 3)} J, total E = ${format(total, 3)} J; ` +
      `${energyWords(meta)} = ${error.toExponential(2)} J.`
    );
  }

  function drawError(c) {
    const left = CHAIN + 240;
    const right = WIDTH - 16;
    const top = 150;
    const bottom = HEIGHT - 36;
    const total = Math.max(fullDuration(), 1e-9);
    const bound = Math.max(run.meta.error_max, 1e-300);
    const xOf = (time) => left + (time / total) * (right - left);
    const yOf = (e) => (top + bottom) / 2 - (e / bound) * ((bottom - top) / 2);
    c.strokeStyle = COLOURS.grid;
    c.lineWidth = 1;
    c.strokeRect(left, top, right - left, bottom - top);
    c.beginPath();
    c.moveTo(left, yOf(0));
    c.lineTo(right, yOf(0));
    c.stroke();
    c.fillStyle = COLOURS.text;
    c.font = "12px sans-serif";
    c.fillText(run.meta.conserved ? "energy error E − E(0) (J)" : "energy change E − E(0) (J)",
      left, top - 8);
    c.fillStyle = COLOURS.faint;
    c.fillText(`+${bound.toExponential(1)}`, right - 58, top - 8);
    c.fillText(`0 … ${total.toFixed(1)} s`, right - 70, bottom + 16);
    const spacing = run.meta.spacing;
    const now = Math.min(Math.floor(t / spacing), run.available - 1);
    const step = Math.max(1, Math.floor(run.available / (right - left)));
    for (const [upto, colour, width] of [
      [run.available - 1, COLOURS.faint, 1],
      [now, COLOURS.total, 1.5],
    ]) {
      c.strokeStyle = colour;
      c.lineWidth = width;
      c.beginPath();
      for (let i = 0; i <= upto; i += step) {
        const x = xOf(i * spacing);
        const y = yOf(run.error[i]);
        if (i === 0) c.moveTo(x, y);
        else c.lineTo(x, y);
      }
      c.stroke();
    }
    c.strokeStyle = COLOURS.bob;
    c.beginPath();
    c.moveTo(xOf(t), top);
    c.lineTo(xOf(t), bottom);
    c.stroke();
  }

  function drawReadout(c) {
    const meta = run.meta;
    const step = Math.min(Math.round(t / meta.dt), meta.steps);
    const lines = [
      `t = ${format(t, 2)} s of ${format(fullDuration(), 1)} s`,
      `${meta.method}, Δt = ${meta.dt} s, ${speed}× speed`,
      `step ${step} of ${meta.steps}`,
      `E − E(0) = ${seriesAt(run.error, 1, 0, t).toExponential(2)} J`,
    ];
    if (!meta.conserved) {
      // What changes the energy, in the kernel's words, wrapped to the readout's width.
      lines[3] += ", not conserved";
      let line = "by";
      for (const word of String(meta.changed_by || "its forces").split(" ")) {
        if (line.length + 1 + word.length > READOUT_CHARS) {
          lines.push(line);
          line = word;
        } else {
          line = `${line} ${word}`;
        }
      }
      lines.push(line);
    }
    if (!meta.completed) lines.push("the run stopped: the state became non-finite");
    c.fillStyle = COLOURS.text;
    c.font = "13px monospace";
    lines.forEach((line, k) => c.fillText(line, CHAIN + 240, 24 + 20 * k));
  }

  // ---- the animation loop ----------------------------------------------------------------
  function tick(stamp) {
    frameId = requestAnimationFrame(tick);
    if (playing && run && !dragging && !pending) {
      if (lastStamp !== null) {
        t += ((stamp - lastStamp) / 1000) * speed;
        const end = duration();
        const complete = run.available === run.meta.states;
        if (t >= end) {
          if (complete && model.get("loop") && end > 0) t = t % end;
          else if (complete) {
            t = end;
            setPlaying(false);
          } else t = end; // wait for the next chunk
        }
      }
      lastStamp = stamp;
      dirty = true;
    }
    if (dirty) {
      const started = performance.now();
      draw();
      drawSeconds += (performance.now() - started) / 1000;
      dirty = false;
      frames += 1;
      root.dataset.frames = String(frames);
      root.dataset.drawMs = ((1000 * drawSeconds) / frames).toFixed(3);
      root.dataset.clock = stamp.toFixed(3);
      if (run) {
        scrub.value = String(Math.round(t / run.meta.spacing));
        clock.textContent = `${format(t, 2)} s`;
      }
      if (describeDue) {
        description.textContent = describe();
        describeDue = false;
      }
    }
  }
  frameId = requestAnimationFrame(tick);

  // ---- messages from the kernel ----------------------------------------------------------
  function onMessage(content, buffers) {
    if (!content || typeof content !== "object") return;
    if (content.type === "run") {
      if (run && content.run < run.id) return;
      if (run && content.run === run.id) {
        addChunk(run, content, buffers);
      } else {
        if (!incoming || incoming.id !== content.run) incoming = newRun(content);
        addChunk(incoming, content, buffers);
        if (incoming.available > 0) {
          run = incoming;
          incoming = null;
          dragging = null;
          t = 0;
          lastStamp = null;
          describeDue = true;
          scrub.max = String(run.meta.states - 1);
          showViews();
        }
      }
      root.dataset.run = String(run ? run.id : -1);
      root.dataset.states = String(run ? run.available : 0);
      root.dataset.chunks = String(run ? run.got.size : 0);
      dirty = true;
    } else if (content.type === "released") {
      pending = false;
      dragging = null;
      if (!content.ok) setStatus(content.message, "error");
      lastStamp = null;
      dirty = true;
    }
  }
  const onPlaying = () => setPlaying(model.get("playing"), false);
  const onSpeed = () => {
    speed = model.get("speed");
    speedBox.value = String(speed);
    dirty = true;
  };
  const onTime = () => {
    const time = model.get("time");
    if (Math.abs(time - t) > 1e-9 && !playing) seek(time, false);
  };
  const onDirty = () => {
    dirty = true;
  };
  const listeners = {
    "msg:custom": onMessage,
    "change:playing": onPlaying,
    "change:speed": onSpeed,
    "change:speeds": fillSpeeds,
    "change:time": onTime,
    "change:trail": onDirty,
    "change:message": showModelMessage,
    "change:message_kind": showModelMessage,
  };
  for (const [name, listener] of Object.entries(listeners)) model.on(name, listener);

  // ---- controls --------------------------------------------------------------------------
  function showViews() {
    views.hidden = !inSpace();
    help.textContent = inSpace() ? SPACE_HINT : PLANE_HINT;
  }
  function setView(turn, tilt) {
    view = { turn, tilt: Math.min(Math.max(tilt, 0), TOP) };
    dirty = true;
  }
  viewButtons["reset view"].addEventListener("click", () => setView(VIEW_START.turn, VIEW_START.tilt));
  viewButtons.top.addEventListener("click", () => setView(0, TOP));
  viewButtons.side.addEventListener("click", () => setView(0, 0));
  play.addEventListener("click", () => setPlaying(!playing));
  back.addEventListener("click", () => stepBy(-1));
  forward.addEventListener("click", () => stepBy(1));
  speedBox.addEventListener("change", () => {
    speed = Number(speedBox.value);
    model.set("speed", speed);
    model.save_changes();
    dirty = true;
  });
  scrub.addEventListener("input", () => {
    if (!run) return;
    setPlaying(false);
    seek(Number(scrub.value) * run.meta.spacing);
  });

  root.addEventListener("keydown", (event) => {
    const tag = event.target.tagName;
    const native = tag === "INPUT" || tag === "SELECT" || (tag === "BUTTON" && (event.key === " " || event.key === "Enter"));
    if (native) {
      event.stopPropagation(); // the control handles it; JupyterLab must not
      return;
    }
    const actions = {
      " ": () => setPlaying(!playing),
      k: () => setPlaying(!playing),
      K: () => setPlaying(!playing),
      ArrowRight: () => stepBy(1),
      ".": () => stepBy(1),
      ArrowLeft: () => stepBy(-1),
      ",": () => stepBy(-1),
      ArrowUp: () => changeSpeed(1),
      "+": () => changeSpeed(1),
      "=": () => changeSpeed(1),
      ArrowDown: () => changeSpeed(-1),
      "-": () => changeSpeed(-1),
      Home: () => {
        setPlaying(false);
        seek(0);
      },
      End: () => {
        setPlaying(false);
        seek(duration());
      },
    };
    const action = actions[event.key];
    if (!action) return;
    event.preventDefault();
    event.stopPropagation();
    action();
  });

  // ---- dragging a bob --------------------------------------------------------------------
  // The pointer in metres: the picture's (across, up), in the top view the horizontal (x, y).
  function pointerMetres(event) {
    const rect = canvas.getBoundingClientRect();
    const px = ((event.clientX - rect.left) * WIDTH) / rect.width;
    const py = ((event.clientY - rect.top) * HEIGHT) / rect.height;
    const s = chainScale();
    placePivot();
    const [across, up] = [(px - pivot.x) / s, -(py - pivot.y) / s];
    return [...(inSpace() ? unproject(across, up) : [across, up]), px, py];
  }
  canvas.addEventListener("pointerdown", (event) => {
    if (!run || event.button > 0) return;
    const [, , px, py] = pointerMetres(event);
    const angles = anglesAt(t);
    const [xs, ys, zs] = positions(angles);
    const s = chainScale();
    let best = -1;
    let bestDistance = Infinity;
    for (let j = 0; j < xs.length; j++) {
      const [bx, by] = screen(xs[j], ys[j], zs[j], s);
      const d = Math.hypot(px - bx, py - by);
      if (d <= bobRadius(j) + 10 && d < bestDistance) {
        best = j;
        bestDistance = d;
      }
    }
    root.focus({ preventScroll: true });
    if (inSpace() && (best < 0 || !topView() || pending) && px < CHAIN) {
      // anything but a bob seen from above turns the view
      if (best >= 0 && !topView()) {
        setStatus("Seen at an angle, a place on the screen is no place in space: press “top” " +
          "and drag the bob there to set where it starts (its height follows from the rod).");
      }
      event.preventDefault();
      canvas.setPointerCapture(event.pointerId);
      turning = { pointerId: event.pointerId, px, py, turn: view.turn, tilt: view.tilt };
      return;
    }
    if (best < 0 || pending) return;
    const refusal = run.meta.figure.movable[best];
    if (refusal) {
      setStatus(refusal, "error"); // a point the coordinates do not place: say why, no drag
      root.dataset.refused = String(best);
      return;
    }
    event.preventDefault();
    canvas.setPointerCapture(event.pointerId);
    dragging = { bob: best, angles, xs: Array.from(xs), ys: Array.from(ys), zs: Array.from(zs),
      pointerId: event.pointerId,
      // a point in space stays within its reach horizontally (DRAG_REACH)
      reach: DRAG_REACH * Math.hypot(xs[best], ys[best], zs[best]) };
    root.dataset.dragging = String(best);
    dirty = true;
  });
  // Where a drag in the top view puts a point in space: within its reach, horizontally.
  function withinReach(x, y) {
    const r = Math.hypot(x, y);
    return inSpace() && r > dragging.reach ? [(x * dragging.reach) / r, (y * dragging.reach) / r] : [x, y];
  }
  canvas.addEventListener("pointermove", (event) => {
    if (turning && event.pointerId === turning.pointerId) {
      const [, , px, py] = pointerMetres(event);
      setView(turning.turn - (px - turning.px) * TURN_PER_PIXEL,
        turning.tilt + (py - turning.py) * TURN_PER_PIXEL);
      return;
    }
    if (!dragging || event.pointerId !== dragging.pointerId) return;
    const [x, y] = withinReach(...pointerMetres(event));
    const k = dragging.bob;
    if (run.meta.figure.kind === "points") {
      // Only the kernel knows a system's coordinates: the point follows the pointer alone.
      dragging.xs[k] = x;
      dragging.ys[k] = y;
      dirty = true;
      return;
    }
    const [xs, ys] = positions(dragging.angles);
    const [jx, jy] = k > 0 ? [xs[k - 1], ys[k - 1]] : [0, 0];
    const angle = Math.atan2(x - jx, -(y - jy));
    if (Number.isFinite(angle)) dragging.angles[k] = angle;
    dirty = true;
  });
  canvas.addEventListener("pointerup", (event) => {
    if (turning && event.pointerId === turning.pointerId) {
      turning = null;
      return;
    }
    if (!dragging || event.pointerId !== dragging.pointerId) return;
    const [x, y] = withinReach(...pointerMetres(event));
    pending = true;
    delete root.dataset.dragging;
    root.dataset.release = `${x},${y}`;
    model.send({ type: "release", bob: dragging.bob, x, y, theta: Array.from(dragging.angles) });
    dirty = true;
  });
  canvas.addEventListener("pointercancel", () => {
    turning = null;
    dragging = null;
    delete root.dataset.dragging;
    dirty = true;
  });

  model.send({ type: "ready" });
  return () => {
    cancelAnimationFrame(frameId);
    for (const [name, listener] of Object.entries(listeners)) model.off(name, listener);
  };
}

export default { render };
