// The status line of an instrument (anywidget front-end module).
//
// One sentence about the latest run, as an ARIA live region, and a "Copy as code" button.
// A busy sentence (kind "busy") replaces the previous one only after `busy_delay` seconds,
// followed by the seconds elapsed (outside the live region, so that a screen reader
// announces the sentence once). The kernel (pendulum_lab.widgets.status) fades the
// figure meanwhile through a CSS class on the instrument's box. No imports, nothing from
// the network.

function element(tag, className, attributes = {}) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  return node;
}

function render({ model, el }) {
  const root = element("div", "plab-statusline");
  const text = element("span", "plab-status-text", { role: "status", "aria-live": "polite" });
  const elapsed = element("span", "plab-elapsed", { "aria-hidden": "true" });
  const copy = element("button", "plab-button plab-copy", {
    type: "button",
    title: "copy the pendulum_lab code that computes this picture",
  });
  copy.textContent = "Copy as code";
  const note = element("span", "plab-copy-note", { role: "status", "aria-live": "polite" });
  const manual = element("textarea", "plab-copy-manual", {
    readonly: "",
    rows: "6",
    "aria-label": "the code of this picture, to copy by hand",
  });
  manual.hidden = true;
  root.append(text, elapsed, copy, note, manual);
  el.appendChild(root);

  let busyTimer = 0;
  let tickTimer = 0;
  let busySince = 0; // when the current stretch of work began (0: no work under way)

  function show(sentence, kind) {
    text.textContent = sentence;
    root.dataset.kind = kind;
  }
  function stopBusy() {
    clearTimeout(busyTimer);
    clearInterval(tickTimer);
    busyTimer = tickTimer = 0;
    elapsed.textContent = "";
  }
  function update() {
    const kind = model.get("kind");
    const sentence = model.get("text");
    const shownBusy = root.dataset.kind === "busy";
    stopBusy();
    if (kind !== "busy") {
      busySince = 0;
      show(sentence, kind);
      return;
    }
    if (!busySince) busySince = performance.now();
    const showBusy = () => {
      show(sentence, "busy");
      const tick = () => {
        elapsed.textContent = ` ${((performance.now() - busySince) / 1000).toFixed(1)} s`;
      };
      tick();
      tickTimer = setInterval(tick, 100);
    };
    // The delay keeps a short piece of work from flickering; once a busy sentence is shown,
    // the next one (compiling, then computing) replaces it at once, with the seconds counted
    // from the start of the work.
    const wait = 1000 * model.get("busy_delay") - (performance.now() - busySince);
    if (shownBusy || wait <= 0) showBusy();
    else busyTimer = setTimeout(showBusy, wait);
  }

  function showCode() {
    const code = model.get("code");
    copy.hidden = !code;
    if (!manual.hidden) manual.value = code;
    root.dataset.code = code ? "1" : "0";
  }
  copy.addEventListener("click", async () => {
    const code = model.get("code");
    try {
      await navigator.clipboard.writeText(code);
      manual.hidden = true;
      note.textContent = "copied: paste it into a code cell";
      root.dataset.copied = String(Number(root.dataset.copied || 0) + 1);
    } catch (error) {
      // No clipboard here (an insecure page, or permission refused): show the code to copy.
      manual.hidden = false;
      manual.value = code;
      manual.focus();
      manual.select();
      note.textContent = "select and copy the code below (Ctrl+C)";
      root.dataset.copied = "manual";
    }
  });

  const listeners = {
    "change:text": update,
    "change:kind": update,
    "change:code": showCode,
  };
  for (const [name, listener] of Object.entries(listeners)) model.on(name, listener);
  update();
  showCode();
  return () => {
    stopBusy();
    for (const [name, listener] of Object.entries(listeners)) model.off(name, listener);
  };
}

export default { render };
