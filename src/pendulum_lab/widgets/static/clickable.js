// A picture where a click launches an orbit (anywidget front-end module).
//
// The kernel sends the picture (a PNG), where its axes are (`frame`) and the orbits
// launched so far (`orbits`: float32 (x, y) pairs, a colour, a label). This module
// draws the orbits over the picture and sends each click, in data coordinates, to the
// kernel (pendulum_lab.widgets.clickable). Keyboard: arrows move a cross-hair, Enter
// launches there, U undoes. No imports, nothing from the network.

function element(tag, className, attributes = {}) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  return node;
}

function render({ model, el }) {
  const root = element("div", "plab-click", {
    tabindex: "0",
    role: "group",
    "aria-label":
      "Clickable plot: click a point to launch the orbit through it. " +
      "Keyboard: arrow keys move a cross-hair, Enter launches there, U removes the last orbit.",
    "data-lm-suppress-shortcuts": "true",
  });
  const figure = element("div", "plab-click-figure");
  const image = element("img", "", { alt: "", draggable: "false" });
  const canvas = element("canvas", "plab-click-canvas", { role: "img", "aria-label": "orbits" });
  const readout = element("div", "plab-readout");
  const status = element("div", "plab-status", { role: "status", "aria-live": "polite" });
  figure.append(image, canvas);
  root.append(figure, readout, status);
  el.appendChild(root);
  const context = canvas.getContext("2d");

  let imageUrl = null;
  let pending = false;
  let cursor = null; // keyboard cross-hair, data coordinates
  let hover = null;

  const frame = () => model.get("frame") || {};
  function size() {
    const [w, h] = frame().size || [600, 440];
    return [w, h];
  }
  // Data coordinates <-> CSS pixels of the picture, through the axes' box.
  function toPixels(x, y) {
    const f = frame();
    const [w, h] = size();
    const [left, top, right, bottom] = f.box;
    const px = (left + ((x - f.xlim[0]) / (f.xlim[1] - f.xlim[0])) * (right - left)) * w;
    const py = (bottom - ((y - f.ylim[0]) / (f.ylim[1] - f.ylim[0])) * (bottom - top)) * h;
    return [px, py];
  }
  function toData(px, py) {
    const f = frame();
    const [w, h] = size();
    const [left, top, right, bottom] = f.box;
    const u = (px / w - left) / (right - left);
    const v = (bottom - py / h) / (bottom - top);
    return {
      x: f.xlim[0] + u * (f.xlim[1] - f.xlim[0]),
      y: f.ylim[0] + v * (f.ylim[1] - f.ylim[0]),
      inside: u >= 0 && u <= 1 && v >= 0 && v <= 1,
    };
  }
  function pointerPixels(event) {
    const rect = canvas.getBoundingClientRect();
    const [w, h] = size();
    return [((event.clientX - rect.left) * w) / rect.width, ((event.clientY - rect.top) * h) / rect.height];
  }

  function showBackground() {
    const data = model.get("background");
    if (imageUrl) URL.revokeObjectURL(imageUrl);
    imageUrl = null;
    if (data && data.byteLength) {
      imageUrl = URL.createObjectURL(new Blob([data], { type: "image/png" }));
      image.src = imageUrl;
    }
    const [w, h] = size();
    image.style.width = `${w}px`;
    image.style.height = `${h}px`;
    const scale = window.devicePixelRatio || 1;
    canvas.width = Math.round(w * scale);
    canvas.height = Math.round(h * scale);
    canvas.style.width = `${w}px`;
    canvas.style.height = `${h}px`;
    const f = frame();
    root.dataset.frame = JSON.stringify({ box: f.box, xlim: f.xlim, ylim: f.ylim, size: [w, h] });
    const [xName, yName] = f.labels || ["x", "y"];
    image.alt = f.title ? `${f.title}: ${yName} against ${xName}` : "";
    draw();
  }

  function draw() {
    const f = frame();
    if (!f.box) return;
    const [w, h] = size();
    const scale = canvas.width / w;
    const c = context;
    c.setTransform(scale, 0, 0, scale, 0, 0);
    c.clearRect(0, 0, w, h);
    const [left, top, right, bottom] = f.box;
    c.save();
    c.beginPath();
    c.rect(left * w, top * h, (right - left) * w, (bottom - top) * h);
    c.clip();
    const span = Math.abs(f.xlim[1] - f.xlim[0]);
    let points = 0;
    const orbits = model.get("orbits") || [];
    for (const orbit of orbits) {
      const view = orbit.xy;
      const xy = new Float32Array(view.buffer, view.byteOffset, view.byteLength / 4);
      const count = xy.length / 2;
      points += count;
      c.fillStyle = orbit.colour;
      c.strokeStyle = orbit.colour;
      if (f.style === "line") {
        c.lineWidth = 1.6;
        c.beginPath();
        for (let i = 0; i < count; i++) {
          const [px, py] = toPixels(xy[2 * i], xy[2 * i + 1]);
          // A wrapped angle jumps from pi to -pi: break the line there.
          const jump = i > 0 && Math.abs(xy[2 * i] - xy[2 * i - 2]) > span / 2;
          if (i === 0 || jump) c.moveTo(px, py);
          else c.lineTo(px, py);
        }
        c.stroke();
      } else {
        for (let i = 0; i < count; i++) {
          const [px, py] = toPixels(xy[2 * i], xy[2 * i + 1]);
          c.fillRect(px - 1.25, py - 1.25, 2.5, 2.5);
        }
      }
      if (count > 0) {
        const [sx, sy] = toPixels(xy[0], xy[1]);
        c.beginPath();
        c.arc(sx, sy, 4.5, 0, 2 * Math.PI);
        c.fill();
        c.strokeStyle = "#000000";
        c.lineWidth = 1;
        c.stroke();
      }
    }
    const mark = cursor || hover;
    if (mark) {
      const [px, py] = toPixels(mark.x, mark.y);
      c.strokeStyle = cursor ? "#1a73e8" : "rgba(0,0,0,0.35)";
      c.lineWidth = 1;
      c.beginPath();
      c.moveTo(px - 8, py);
      c.lineTo(px + 8, py);
      c.moveTo(px, py - 8);
      c.lineTo(px, py + 8);
      c.stroke();
    }
    c.restore();
    root.dataset.orbits = String(orbits.length);
    root.dataset.points = String(points);
    root.dataset.pending = pending ? "1" : "0";
  }

  function describe(point) {
    const [xName, yName] = frame().labels || ["x", "y"];
    return `${xName} = ${point.x.toFixed(3)}, ${yName} = ${point.y.toFixed(3)}`;
  }
  function showMessage() {
    status.textContent = model.get("message") || "";
    status.dataset.kind = model.get("message_kind") || "info";
  }
  function launch(point) {
    if (pending) return;
    pending = true;
    root.dataset.pending = "1";
    status.textContent = `launching the orbit through ${describe(point)}…`;
    status.dataset.kind = "info";
    model.send({ type: "click", x: point.x, y: point.y });
  }

  canvas.addEventListener("pointerdown", (event) => {
    if (event.button > 0) return;
    root.focus({ preventScroll: true });
    const point = toData(...pointerPixels(event));
    if (!point.inside) return;
    event.preventDefault();
    cursor = null;
    launch(point);
  });
  canvas.addEventListener("pointermove", (event) => {
    const point = toData(...pointerPixels(event));
    hover = point.inside ? point : null;
    readout.textContent = hover ? describe(hover) : "";
    draw();
  });
  canvas.addEventListener("pointerleave", () => {
    hover = null;
    readout.textContent = "";
    draw();
  });
  root.addEventListener("keydown", (event) => {
    const f = frame();
    if (!f.box) return;
    const dx = (f.xlim[1] - f.xlim[0]) / 50;
    const dy = (f.ylim[1] - f.ylim[0]) / 50;
    if (!cursor) cursor = { x: (f.xlim[0] + f.xlim[1]) / 2, y: (f.ylim[0] + f.ylim[1]) / 2 };
    const moves = { ArrowLeft: [-dx, 0], ArrowRight: [dx, 0], ArrowUp: [0, dy], ArrowDown: [0, -dy] };
    if (moves[event.key]) {
      const [mx, my] = moves[event.key];
      cursor = {
        x: Math.min(Math.max(cursor.x + mx, f.xlim[0]), f.xlim[1]),
        y: Math.min(Math.max(cursor.y + my, f.ylim[0]), f.ylim[1]),
      };
      readout.textContent = describe(cursor);
    } else if (event.key === "Enter" || event.key === " ") {
      launch(cursor);
    } else if (event.key === "u" || event.key === "U") {
      model.send({ type: "undo" });
    } else {
      return;
    }
    event.preventDefault();
    event.stopPropagation();
    draw();
  });

  function onMessage(content) {
    if (content && content.type === "launched") {
      pending = false;
      showMessage();
      draw();
    }
  }
  const listeners = {
    "msg:custom": onMessage,
    "change:background": showBackground,
    "change:frame": showBackground,
    "change:orbits": draw,
    "change:message": showMessage,
    "change:message_kind": showMessage,
  };
  for (const [name, listener] of Object.entries(listeners)) model.on(name, listener);
  showBackground();
  showMessage();

  return () => {
    if (imageUrl) URL.revokeObjectURL(imageUrl);
    for (const [name, listener] of Object.entries(listeners)) model.off(name, listener);
  };
}

export default { render };
