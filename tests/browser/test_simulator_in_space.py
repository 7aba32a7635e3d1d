"""The live simulator of a system in space, in Chromium: the spherical pendulum, run by the
kernel-free engine (the website's) in a page as ``simulator_html`` writes it.

Checked: it draws and plays (the bob moves between frames; paused, it does not); turning the
view changes the picture but not the run (pressing the view already shown changes nothing);
a drag in the top view sets the start's horizontal (x, y) to the pointer's, within one pixel
(a drag beyond the rod's reach stops at 95 % of it), while the same drag in a turned view only
turns the view and says how to set the start. The kernel's side of the same simulator is
tested without a browser in ``tests/widgets/test_live_in_space.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from browser_engine import engine_page

import pendulum_lab as pl

pytestmark = pytest.mark.browser

#: The pivot's place across the canvas [CSS px] (simulator.js: the chain panel's centre; in
#: the top view it is the centre, else it moves up and down with the tilt: ``data-pivot``).
PIVOT = 170
#: JavaScript: how many pixels of the chain panel differ from white, and a digest of them.
INK = """
() => {
  const canvas = document.querySelector('.plab-live-canvas');
  const c = canvas.getContext('2d');
  const side = Math.round(340 * canvas.width / 900);
  const data = c.getImageData(0, 0, side, side).data;
  let ink = 0, digest = 0;
  for (let i = 0; i < data.length; i += 4) {
    const dark = 765 - data[i] - data[i + 1] - data[i + 2];
    if (dark > 30) ink += 1;
    digest = (digest * 31 + dark * (i + 1)) % 1000000007;
  }
  return [ink, digest];
}
"""


@pytest.fixture(scope="module")
def space(tmp_path_factory):
    """A page with the spherical pendulum's kernel-free simulator: 2 s of an ellipse."""
    from pendulum_lab.widgets.browser import browser_config, simulator_html

    config = browser_config(pl.spherical_pendulum(), [0.4, 0.0], [0.0, 1.5], t_end=2.0,
                            dt=0.01, method="glrk4")
    html = ('<!doctype html><html><head><link rel="stylesheet" href="/live.css"></head><body>'
            + simulator_html(config, "/browser/engine.js") + "</body></html>")
    with engine_page(tmp=tmp_path_factory.mktemp("chromium")) as (p, base, _):
        p.route(f"{base}/space.html",
                lambda route: route.fulfill(body=html, content_type="text/html"))
        p.goto(f"{base}/space.html")
        p.wait_for_function("() => document.querySelector('.plab-live')?.dataset.run === '1'")
        yield p


def data(p) -> dict:
    return p.evaluate("() => ({...document.querySelector('.plab-live').dataset})")


def points(p) -> list[float]:
    return [float(v) for v in data(p)["points"].split()]


def pause_at_start(p):
    p.evaluate("() => document.querySelector('.plab-live').focus()")
    if data(p)["playing"] == "1":
        p.keyboard.press("Space")
    p.keyboard.press("Home")
    p.wait_for_function("() => document.querySelector('.plab-live').dataset.time === '0.0000'")
    p.wait_for_timeout(60)  # a frame drawn there


def test_a_system_in_space_is_drawn_and_its_bob_moves_while_playing(space):
    p = space
    ink, _ = p.evaluate(INK)
    assert ink > 500  # the floor circle, the rod, the bob, the trail, the labels
    assert len(points(p)) == 3 and p.locator(".plab-view").count() == 3
    assert p.locator(".plab-views").is_visible()
    first = points(p)
    p.wait_for_timeout(250)
    assert np.hypot(*np.subtract(points(p), first)[:2]) > 0.01
    # negative control: paused, the bob stays where it is
    pause_at_start(p)
    still = points(p)
    p.wait_for_timeout(250)
    assert points(p) == still
    assert still == pytest.approx([0.4, 0.0, -np.sqrt(1 - 0.16)], abs=1e-5)
    assert p.errors == []


def test_turning_the_view_changes_the_picture_and_not_the_run(space):
    p = space
    pause_at_start(p)
    run, shown = data(p)["run"], points(p)
    before = p.evaluate(INK)
    p.get_by_role("button", name="side").click()
    p.wait_for_timeout(60)
    side = p.evaluate(INK)
    assert side[1] != before[1]
    assert [float(v) for v in data(p)["view"].split(",")] == [0.0, 0.0]
    # a drag on empty canvas turns it about the vertical and tilts it
    box = p.locator(".plab-live-canvas").bounding_box()
    p.mouse.move(box["x"] + 40, box["y"] + 300)
    p.mouse.down()
    p.mouse.move(box["x"] + 90, box["y"] + 320, steps=3)
    p.mouse.up()
    p.wait_for_timeout(60)
    turn, tilt = (float(v) for v in data(p)["view"].split(","))
    assert turn == pytest.approx(-0.5, abs=0.02) and tilt == pytest.approx(0.2, abs=0.02)
    assert p.evaluate(INK)[1] not in (before[1], side[1])
    # the run and the state shown did not change
    assert data(p)["run"] == run and points(p) == shown and data(p)["time"] == "0.0000"
    # negative control: the view already shown, pressed again, leaves the same pixels
    p.get_by_role("button", name="side").click()
    p.wait_for_timeout(60)
    again = p.evaluate(INK)
    p.get_by_role("button", name="side").click()
    p.wait_for_timeout(60)
    assert p.evaluate(INK) == again == side
    assert p.errors == []


def drag(p, start, end):
    box = p.locator(".plab-live-canvas").bounding_box()
    p.mouse.move(box["x"] + start[0], box["y"] + start[1])
    p.mouse.down()
    p.mouse.move(box["x"] + end[0], box["y"] + end[1], steps=4)
    p.mouse.up()


def test_a_drag_in_the_top_view_sets_the_start_and_elsewhere_turns_the_view(space):
    p = space
    pause_at_start(p)
    # negative control first: in a turned view, the same gesture on the bob only turns it
    p.get_by_role("button", name="reset view").click()
    p.wait_for_timeout(60)
    run, view = data(p)["run"], data(p)["view"]
    bob = p.evaluate("""() => { const d = document.querySelector('.plab-live').dataset;
        return d.points; }""")
    s = float(data(p)["scale"])
    x, y, z = (float(v) for v in bob.split())
    turn, tilt = (float(v) for v in view.split(","))
    across = x * np.cos(turn) + y * np.sin(turn)
    up = (-x * np.sin(turn) + y * np.cos(turn)) * np.sin(tilt) + z * np.cos(tilt)
    pivot_y = float(data(p)["pivot"].split(",")[1])
    assert pivot_y < PIVOT  # seen from 25 degrees above, the pivot is drawn above the centre
    drag(p, (PIVOT + s * across, pivot_y - s * up), (PIVOT + 0.3 * s, PIVOT + 0.2 * s))
    p.wait_for_timeout(100)
    assert data(p)["run"] == run and data(p)["view"] != view
    assert "press “top”" in p.locator(".plab-status").text_content()
    # from above: the bob goes where it is dragged, (x, y) = (0.3, -0.2) m
    p.get_by_role("button", name="top").click()
    p.wait_for_timeout(60)
    assert data(p)["pivot"] == f"{PIVOT:.3f},{PIVOT:.3f}"
    drag(p, (PIVOT + s * x, PIVOT - s * y), (PIVOT + 0.3 * s, PIVOT + 0.2 * s))
    p.wait_for_function(f"() => document.querySelector('.plab-live').dataset.run !== '{run}'")
    pause_at_start(p)
    pixel = 1 / s  # metres per CSS pixel
    assert points(p) == pytest.approx([0.3, -0.2, -np.sqrt(1 - 0.13)], abs=pixel)
    # beyond the rod's reach it stops at 95 % of it, in the pointer's direction
    run = data(p)["run"]
    drag(p, (PIVOT + 0.3 * s, PIVOT + 0.2 * s), (PIVOT + 1.5 * s, PIVOT))
    p.wait_for_function(f"() => document.querySelector('.plab-live').dataset.run !== '{run}'")
    pause_at_start(p)
    assert points(p)[:2] == pytest.approx([0.95, 0.0], abs=pixel)
    assert p.errors == []
