"""Harness of the website tests: build a site, serve it locally, open every page in Chromium.

Used by ``conftest.py`` (fixtures) and the tests beside it; see ``README.md``.

:func:`crawl` opens each page of a built site from a local HTTP server, once in light and once in
dark mode, and records what a reader's browser met: console errors, requests to other hosts
(blocked, so nothing leaves the machine), failed local requests, the pictures and whether they
loaded, mathematics left untypeset, error output, links and anchors, and the embedded animations
(played, to see them advance). :func:`problems` turns the records into lists of problems by
category; a test asserts that a category is empty, a negative control that it is not.
"""

from __future__ import annotations

import concurrent.futures
import functools
import json
import re
import sys
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

REPO_ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO_ROOT / "test-artifacts" / "site"
SCREENSHOTS = ARTIFACTS / "screenshots"
sys.path[:0] = [str(REPO_ROOT / "tools"), str(REPO_ROOT / "tests" / "browser")]

import build_site  # noqa: E402  (tools/ is not a package)

# One way to start Debian's Chromium and to decide between skipping and failing, shared with the
# JupyterLab tests.
from lab_harness import CHROMIUM_ARGS, chromium_path, in_ci, serve  # noqa: E402, F401 (in_ci: conftest)

VIEWPORT = {"width": 1300, "height": 900}
MAX_SCREENSHOT_HEIGHT = 8000
#: Screenshots after the first mode show the page's top only: enough to see the theme applied
#: (every page's colours are checked from the DOM in each mode); a whole tall page costs about
#: a second of Chromium's time per page.
LATER_MODES_SCREENSHOT_HEIGHT = 2 * 900
MODES = ("light", "dark")
#: Every host name but the local server's address resolves to nothing: a page's request to
#: another host fails at once (and is recorded as a problem), offline or not.
BLOCK_OTHER_HOSTS = "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1"
PLAY_SECONDS = 1.5

CATEGORIES = (
    "error output",
    "images",
    "alt text",
    "math",
    "animations",
    "external requests",
    "failed requests",
    "console errors",
    "internal links",
    "dark mode",
    "code cells",
)


# ---------------------------------------------------------------------------------------------
# Availability policy (as in tests/browser)
# ---------------------------------------------------------------------------------------------
def site_unavailable_reason() -> str | None:
    """Why the site tests cannot run here, or None when they can."""
    for module in ("sphinx", "myst_nb", "sphinx_book_theme", "numpydoc"):
        try:
            __import__(module)
        except ImportError as exc:
            return f'{module} is not importable ({exc}); pip install -e ".[docs]"'
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError as exc:
        return f"Playwright for Python is not importable ({exc}); pip install playwright"
    if chromium_path() is None:
        return "Chromium not found at /usr/bin/chromium nor on PATH; apt-get install -y chromium"
    return build_site.missing_mathjax()


# ---------------------------------------------------------------------------------------------
# Pages of a built site (served locally by lab_harness.serve)
# ---------------------------------------------------------------------------------------------
def list_pages(html_dir: Path) -> list[str]:
    """Every HTML page of a built site, as paths relative to it (sorted)."""
    skip = {"_static", "_sources", "_images", "_modules"}
    return sorted(
        p.relative_to(html_dir).as_posix()
        for p in html_dir.rglob("*.html")
        if not skip & set(p.relative_to(html_dir).parts)
    )


# ---------------------------------------------------------------------------------------------
# What the browser records on one page
# ---------------------------------------------------------------------------------------------
@dataclass
class PageReport:
    page: str
    mode: str
    theme: str = ""
    console_errors: list[str] = field(default_factory=list)
    external_requests: list[str] = field(default_factory=list)
    failed_requests: list[str] = field(default_factory=list)
    images: list[dict] = field(default_factory=list)
    raw_math: list[str] = field(default_factory=list)
    math_errors: int = 0
    typeset: int = 0
    error_outputs: list[str] = field(default_factory=list)
    bare_code: list[str] = field(default_factory=list)
    links: list[str] = field(default_factory=list)
    ids: list[str] = field(default_factory=list)
    animations: list[dict] = field(default_factory=list)
    # Animations the page's HTML embeds (matplotlib players and <video>s), counted in the file;
    # None when the animations were not played (the second mode).
    embedded_animations: int | None = None
    screenshot: str = ""


# Waits for MathJax and for every picture (animation frames are set by the page's script).
_SETTLE = """
async () => {
  if (window.MathJax && MathJax.startup && MathJax.startup.promise) {
    await MathJax.startup.promise;
  }
  const pending = [...document.images].filter((img) => !img.complete);
  await Promise.all(pending.map((img) => new Promise((done) => {
    img.addEventListener("load", done); img.addEventListener("error", done);
    setTimeout(done, 5000);
  })));
  return document.documentElement.dataset.theme || "";
}
"""

# Everything read from the DOM once the page has settled.
_INSPECT = """
(darkMode) => {
  const skip = "pre, code, script, style, textarea, mjx-container, .highlight, .MathJax";
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  const rawMath = [];
  for (let node = walker.nextNode(); node; node = walker.nextNode()) {
    if (node.parentElement && node.parentElement.closest(skip)) continue;
    const text = node.textContent;
    for (const mark of ["$$", "\\\\(", "\\\\[", "\\\\begin{"]) {
      const at = text.indexOf(mark);
      if (at >= 0) rawMath.push(text.slice(Math.max(0, at - 30), at + 40).trim());
    }
  }
  const errorSelectors = [
    ".output.traceback", ".output.stderr", ".output.error", ".system-message",
    ".problematic", "div.admonition.error", "mjx-merror",
  ];
  const errors = [];
  for (const el of document.querySelectorAll(errorSelectors.join(","))) {
    errors.push(el.className + ": " + el.textContent.trim().slice(0, 160));
  }
  if (document.body.innerText.includes("Traceback (most recent call last)")) {
    errors.push("the page text contains 'Traceback (most recent call last)'");
  }
  function transparency(img) {
    // Fraction of (sampled) pixels that are not opaque; -1 when it cannot be read.
    try {
      const scale = Math.min(1, 400 / Math.max(1, img.naturalWidth));
      const w = Math.max(1, Math.round(img.naturalWidth * scale));
      const h = Math.max(1, Math.round(img.naturalHeight * scale));
      const canvas = document.createElement("canvas");
      canvas.width = w; canvas.height = h;
      const ctx = canvas.getContext("2d");
      ctx.drawImage(img, 0, 0, w, h);
      const data = ctx.getImageData(0, 0, w, h).data;
      let clear = 0;
      for (let i = 3; i < data.length; i += 4) if (data[i] < 250) clear++;
      return clear / (w * h);
    } catch (e) { return -1; }
  }
  const images = [...document.images].map((img) => ({
    src: img.currentSrc.startsWith("data:") ? "data:..." : img.currentSrc,
    alt: img.getAttribute("alt"),
    width: img.naturalWidth,
    transparent: darkMode && img.naturalWidth > 0 ? transparency(img) : 0,
    background: getComputedStyle(img).backgroundColor,
  }));
  // A notebook cell's code must show as a code block (whitespace kept, highlighted).
  const bareCode = [...document.querySelectorAll(".cell_input")]
    .filter((el) => !el.querySelector("pre"))
    .map((el) => el.textContent.trim().slice(0, 80));
  const ids = [...document.querySelectorAll("[id]")].map((el) => el.id)
    .concat([...document.querySelectorAll("a[name]")].map((el) => el.getAttribute("name")));
  return {
    rawMath, errors, images, ids, bareCode,
    typeset: document.querySelectorAll("mjx-container").length,
    mathErrors: document.querySelectorAll("mjx-merror").length,
    links: [...document.querySelectorAll("a[href]")].map((a) => a.href),
    height: document.documentElement.scrollHeight,
  };
}
"""

# Plays each embedded animation: matplotlib's JavaScript player (.animation) and <video>. First
# every animation is left alone for the same time (the paused control: nothing may move unless
# played), then each is played in turn and must show a new frame.
_PLAY = """
async (seconds) => {
  const sleep = (ms) => new Promise((done) => setTimeout(done, ms));
  const players = [...document.querySelectorAll("div.animation")];
  const videos = [...document.querySelectorAll("video")];
  function shown(player) {
    const slider = player.querySelector("input[type=range]");
    const img = player.querySelector("img");
    return {
      frame: slider ? slider.value : null,
      picture: img ? img.src : null,
      width: img ? img.naturalWidth : 0,
    };
  }
  if (players.length + videos.length === 0) return [];
  const start = players.map(shown);
  const startTimes = videos.map((video) => video.currentTime);
  await sleep(seconds * 1000);
  const idle = players.map(shown);
  const results = [];
  for (const [k, player] of players.entries()) {
    const slider = player.querySelector("input[type=range]");
    const play = player.querySelector("button[title=Play]");
    const before = shown(player);
    if (play) play.click();
    await sleep(seconds * 1000);
    const after = shown(player);
    const pause = player.querySelector("button[title=Pause]");
    if (pause) pause.click();
    results.push({
      kind: "player", frames: slider ? Number(slider.max) + 1 : 0, play_button: Boolean(play),
      moved_unplayed: start[k].frame !== idle[k].frame || start[k].picture !== idle[k].picture,
      advanced: before.frame !== after.frame,
      changed: before.picture !== after.picture && after.width > 0,
    });
  }
  for (const [k, video] of videos.entries()) {
    const unplayed = video.currentTime !== startTimes[k];
    video.muted = true;
    const before = video.currentTime;
    try { await video.play(); } catch (e) {}
    await sleep(seconds * 1000);
    const t = video.currentTime;
    video.pause();
    results.push({
      kind: "video", frames: 0, play_button: true, moved_unplayed: unplayed,
      advanced: t > before, changed: t > before,
    });
  }
  return results;
}
"""

# What counts as an embedded animation in a page's HTML: matplotlib's player is created by
# ``new Animation(`` once per animation (the class is defined beside it), a video by its tag.
_EMBEDDED_ANIMATION = re.compile(r"new Animation\(|<video\b", re.IGNORECASE)


def embedded_animations(html_file: Path) -> int:
    """The number of animations the HTML of a page embeds (players and videos)."""
    return len(_EMBEDDED_ANIMATION.findall(html_file.read_text(encoding="utf-8", errors="replace")))


def api_pages_checked_in_one_mode(html_dir) -> dict[str, str]:
    """The API reference pages but the first, each with the one mode it is checked in (light
    and dark in turn): text from one template, without pictures, so the first stands for all
    on screenshots and each is checked once (they are half of the site's pages, and the two
    modes' crawls run side by side, so they share them out)."""
    reference = sorted(p for p in list_pages(html_dir) if p.startswith("reference/"))
    return {page: MODES[number % len(MODES)] for number, page in enumerate(reference[1:])}


def _screenshot_name(page: str) -> str:
    return page.removesuffix(".html").replace("/", "__") + ".png"


def crawl(
    html_dir: Path,
    pages: list[str] | None = None,
    modes: tuple[str, ...] = MODES,
    screenshots: Path | None = None,
    play_animations: bool = True,
    one_mode: dict[str, str] | None = None,
) -> list[PageReport]:
    """Open every page (or ``pages``) of the site in ``html_dir`` in Chromium, in each mode.

    The pages of ``one_mode`` (page -> mode) are opened in that mode only, without a
    screenshot.

    Requests to any host other than the local server are recorded and blocked. Animations are
    played in the first mode only. Screenshots (whole page, at most 8000 px tall, in the
    later modes the top two screens) go to
    ``screenshots/MODE/PAGE.png`` when a folder is given. The modes run side by side, each in
    a thread with its own Playwright and Chromium (Playwright's rule: one instance per thread);
    the time goes into Chromium's rendering and screenshots, one core per browser.
    """
    pages = list_pages(html_dir) if pages is None else pages
    one_mode = one_mode or {}
    jobs = [
        (html_dir, [p for p in pages if one_mode.get(p, mode) == mode], mode, screenshots,
         play_animations and mode == modes[0], tuple(one_mode),
         MAX_SCREENSHOT_HEIGHT if mode == modes[0] else LATER_MODES_SCREENSHOT_HEIGHT)
        for mode in modes
    ]
    if len(jobs) == 1:
        return _crawl_mode(*jobs[0])
    with concurrent.futures.ThreadPoolExecutor(len(jobs)) as pool:
        results = list(pool.map(_crawl_mode, *zip(*jobs)))
    return [report for result in results for report in result]


def _crawl_mode(html_dir, pages, mode, screenshots, play, unshot=(),
                shot_height=MAX_SCREENSHOT_HEIGHT) -> list[PageReport]:
    from playwright.sync_api import sync_playwright

    reports = []
    with serve(html_dir) as base, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium_path(),
                                    args=[*CHROMIUM_ARGS, BLOCK_OTHER_HOSTS])
        try:
            context = browser.new_context(viewport=VIEWPORT, color_scheme=mode)
            # The theme keeps the reader's choice in localStorage; set it as a reader would.
            context.add_init_script(
                f"localStorage.setItem('mode', '{mode}'); localStorage.setItem('theme', '{mode}');"
            )
            for page_path in pages:
                shots = None if page_path in unshot else screenshots
                report = _visit(context, base, page_path, mode, shots, play, shot_height)
                if play:
                    report.embedded_animations = embedded_animations(html_dir / page_path)
                reports.append(report)
            context.close()
        finally:
            browser.close()
    return reports


def _visit(context, base: str, page_path: str, mode: str, screenshots, play: bool,
           shot_height: int = MAX_SCREENSHOT_HEIGHT) -> PageReport:
    report = PageReport(page_path, mode)
    local = urlsplit(base).netloc
    page = context.new_page()

    def request(r):
        parts = urlsplit(r.url)
        if parts.scheme in ("http", "https", "ws", "wss") and parts.netloc != local:
            report.external_requests.append(r.url)

    def response(resp):
        if resp.status >= 400 and urlsplit(resp.url).netloc == local:
            report.failed_requests.append(f"{resp.status} {resp.url.removeprefix(base)}")

    def console(message):
        if message.type == "error":
            report.console_errors.append(message.text[:300])

    # Recorded here, blocked by Chromium's resolver (BLOCK_OTHER_HOSTS): a route would hold
    # up every request of the site's own on its way through Playwright.
    page.on("request", request)
    page.on("response", response)
    page.on("console", console)
    page.on("pageerror", lambda exc: report.console_errors.append(f"uncaught: {exc}"[:300]))
    try:
        page.goto(f"{base}/{page_path}", wait_until="load")
        report.theme = page.evaluate(_SETTLE)
        found = page.evaluate(_INSPECT, mode == "dark")
        report.raw_math = found["rawMath"]
        report.error_outputs = found["errors"]
        report.bare_code = found["bareCode"]
        report.images = found["images"]
        report.ids = found["ids"]
        report.links = found["links"]
        report.typeset = found["typeset"]
        report.math_errors = found["mathErrors"]
        if play:
            report.animations = page.evaluate(_PLAY, PLAY_SECONDS)
        if screenshots is not None:
            path = Path(screenshots) / mode / _screenshot_name(page_path)
            path.parent.mkdir(parents=True, exist_ok=True)
            height = min(found["height"], shot_height)
            clip = {"x": 0, "y": 0, "width": VIEWPORT["width"], "height": height}
            page.screenshot(path=str(path), full_page=True, clip=clip)
            report.screenshot = str(path)
    finally:
        page.close()
    return report


# ---------------------------------------------------------------------------------------------
# From records to problems
# ---------------------------------------------------------------------------------------------
class _Ids(HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if value and (name == "id" or (tag == "a" and name == "name")):
                self.ids.add(value)


@functools.cache
def _ids_in_file(path: Path) -> frozenset[str]:
    parser = _Ids()
    parser.feed(path.read_text(encoding="utf-8", errors="replace"))
    return frozenset(parser.ids)


def _luminance(css_colour: str) -> tuple[float, float]:
    """(relative luminance, alpha) of a computed CSS colour such as ``rgba(255, 255, 255, 1)``."""
    numbers = [float(x) for x in re.findall(r"[\d.]+", css_colour)]
    if len(numbers) < 3:
        return 0.0, 0.0
    r, g, b = (x / 255 for x in numbers[:3])
    alpha = numbers[3] if len(numbers) > 3 else 1.0
    return 0.2126 * r + 0.7152 * g + 0.0722 * b, alpha


def problems(reports: list[PageReport], html_dir: Path) -> dict[str, list[str]]:
    """Problems found, by category (each an empty list when all is well)."""
    found: dict[str, list[str]] = {category: [] for category in CATEGORIES}
    ids_by_page = {(r.page): set(r.ids) for r in reports}

    def add(category: str, report: PageReport, text: str):
        found[category].append(f"{report.page} [{report.mode}]: {text}")

    for r in reports:
        for text in r.error_outputs:
            add("error output", r, text)
        for image in r.images:
            if image["width"] <= 0:
                add("images", r, f"picture did not load: {image['src']}")
            if not (image["alt"] or "").strip():
                add("alt text", r, f"picture without alt text: {image['src']}")
            if r.mode == "dark" and image["transparent"] != 0:
                luminance, alpha = _luminance(image["background"])
                if image["transparent"] < 0 or alpha < 1 or luminance < 0.7:
                    add(
                        "dark mode", r,
                        f"picture with transparent parts and no light backing "
                        f"({image['background']}): {image['src']}",
                    )  # fmt: skip
        for text in r.bare_code:
            add("code cells", r, f"a code cell shown as plain text, not as code: {text!r}")
        for text in r.raw_math:
            add("math", r, f"untypeset mathematics: {text!r}")
        if r.math_errors:
            add("math", r, f"{r.math_errors} MathJax error(s)")
        for animation in r.animations:
            if animation["moved_unplayed"]:
                add("animations", r, f"animation changed before it was played: {animation}")
            if not (animation["advanced"] and animation["changed"]):
                add("animations", r, f"animation did not advance when played: {animation}")
        if r.embedded_animations is not None and r.embedded_animations != len(r.animations):
            add(
                "animations", r,
                f"{r.embedded_animations} animation(s) embedded in the HTML, "
                f"{len(r.animations)} found and played in the browser",
            )  # fmt: skip
        for url in r.external_requests:
            add("external requests", r, f"request outside the site: {url}")
        for text in r.failed_requests:
            add("failed requests", r, text)
        for text in r.console_errors:
            add("console errors", r, text)
        if r.mode == "dark" and r.theme != "dark":
            add("dark mode", r, f"the page did not switch to dark mode (theme {r.theme!r})")
        if r.mode == "light":
            for text in _broken_links(r, html_dir, ids_by_page):
                add("internal links", r, text)
    return found


def _broken_links(report: PageReport, html_dir: Path, ids_by_page: dict) -> list[str]:
    """Links of one page into the site that lead to no file, or to no such anchor."""
    broken = []
    for href in dict.fromkeys(report.links):
        parts = urlsplit(href)
        if parts.scheme not in ("http", "https") or parts.hostname != "127.0.0.1":
            continue  # links to other sites are not requests; javascript:, mailto: neither
        target = unquote(parts.path).lstrip("/")
        path = html_dir / target
        if target == "" or path.is_dir():
            path = path / "index.html"
            target = path.relative_to(html_dir).as_posix()
        if not path.is_file():
            broken.append(f"link to a missing file: /{target}")
            continue
        fragment = unquote(parts.fragment)
        if fragment and path.suffix == ".html":
            ids = ids_by_page.get(target) or _ids_in_file(path)
            if fragment not in ids:
                broken.append(f"link to a missing anchor: /{target}#{fragment}")
    return broken


def summary(reports: list[PageReport]) -> dict:
    """Counts for the record: pages, pictures, animations, dark-mode pages."""
    light = [r for r in reports if r.mode == MODES[0]]
    return {
        "pages": len(light),
        "images": sum(len(r.images) for r in light),
        "animations": sum(len(r.animations) for r in light),
        "animations_embedded": sum(r.embedded_animations or 0 for r in light),
        "pages_with_animations": sorted(r.page for r in light if r.animations),
        "typeset_formulas": sum(r.typeset for r in light),
        "dark_pages": sorted(r.page for r in reports if r.mode == "dark"),
        "screenshots": sorted(r.screenshot for r in reports if r.screenshot),
    }


def write_json(path: Path, data) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
