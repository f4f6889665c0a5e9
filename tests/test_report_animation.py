"""The animated runner of the predictive report: frames of every runner model, and the page
played in headless Chromium (the animation advances, the slider moves it, nothing is clipped).
The screenshot is kept: its path is printed (``-s``), and copied into $BLADELAB_ARTIFACTS when
that variable names a folder."""

from __future__ import annotations

import base64
import math
import os
import re
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

from bladelab.blade import load_blade
from bladelab.report import Report
from bladelab.report.animation import animation_html, runner_frames
from bladelab.runner import build_runner, simulate_runner


@pytest.mark.parametrize("kind", ["able", "amputee", "multilink"])
def test_frames_of_every_runner_model(kind):
    if kind == "multilink":
        model = build_runner("amputee", blade_model=load_blade("xtreme-cat5").build())
    else:
        model = build_runner(kind)
    res = simulate_runner(model, duration=0.1, excitations=0.05, dt=1e-4,
                          fall_height=-math.inf, record_every=5)
    frames = runner_frames(res, fps=100)
    assert len(frames.time) == 11 and frames.time[-1] == pytest.approx(0.1)
    n = frames.points.shape[1]
    assert all(0 <= a < n and 0 <= b < n for a, b, _ in frames.edges)
    # point 0 is the pelvis (its centre of mass), standing still on the ground
    np.testing.assert_allclose(frames.points[0, 0], [res.qpos[0, 0], res.qpos[0, 1]], atol=1e-9)
    styles = {s for _, _, s in frames.edges}
    assert {"l", "r", "trunk"} <= styles
    assert ("blade" in styles) == (kind != "able")
    # standing, settling onto the ground: the legs' forces are those of the contacts
    grf = res.leg_grf()
    for leg, name in enumerate(frames.legs):
        fz = np.interp(frames.time, res.time, grf[grf.leg == name].Fz.to_numpy())
        np.testing.assert_allclose(frames.grf[:, leg, 2], fz, rtol=1e-9, atol=1e-9)
    assert frames.grf[-1, :, 2].sum() > 0.2 * model.body_weight
    html = animation_html(res, label="a </script> label").html
    assert html.count("</script>") == 2  # the label cannot close the data block early
    # nothing loaded from elsewhere: no src/href, no fetch, no stylesheet link
    assert re.search(r"\b(src|href)\s*=|fetch\(|XMLHttpRequest|<link", html) is None


def _evaluate(browser, session, expression):
    reply = browser.send("Runtime.evaluate", {"expression": expression, "returnByValue": True},
                         session=session)
    return reply["result"].get("value")


def _open(binary, page: Path, profile: Path):
    from browser import _DevTools

    browser = _DevTools(binary, profile)
    target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})[
        "sessionId"]
    for domain in ("Page", "Runtime", "Log"):
        browser.send(f"{domain}.enable", session=session)
    browser.send("Emulation.setDeviceMetricsOverride",
                 {"width": 1400, "height": 900, "deviceScaleFactor": 1, "mobile": False},
                 session=session)
    browser.events.clear()
    browser.send("Page.navigate", {"url": page.as_uri()}, session=session)
    browser.wait_event("Page.loadEventFired", timeout=60)
    return browser, session


def _keep(screenshot: Path) -> None:
    print(f"\nscreenshot: {screenshot}")
    folder = os.environ.get("BLADELAB_ARTIFACTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        shutil.copy(screenshot, Path(folder) / screenshot.name)


FRAME = "document.querySelector('.runner-animation').getAttribute('data-frame')"
CLIPPED = ("Array.from(document.querySelectorAll('.table-scroll'))"
           ".filter(t => t.scrollWidth > t.clientWidth + 1).length")


def test_the_runner_is_animated_in_headless_chromium(tmp_path, shipped_amputee_report):
    from browser import CHECK_FIGURES, chromium, figure_ok

    binary = chromium()
    rep = shipped_amputee_report  # the shipped amputee Cat6 solution, 3 s (conftest.py)
    browser, session = _open(binary, Path(rep.index), tmp_path / "profile")
    try:
        assert _evaluate(browser, session, FRAME) == "0"
        n_lines = _evaluate(browser, session,
                            "document.querySelectorAll('.runner-animation svg line').length")
        assert n_lines > 12
        _evaluate(browser, session, "document.querySelector('button.anim-play').click()")
        time.sleep(1.5)
        advanced = int(_evaluate(browser, session, FRAME))
        assert advanced > 3  # 1.5 s at 0.25× and 50 frames per simulated second: ~18
        assert _evaluate(browser, session, "document.querySelector('.anim-slider').value") \
            == str(advanced) or int(_evaluate(browser, session, FRAME)) > advanced
        _evaluate(browser, session, "document.querySelector('button.anim-play').click()")
        paused = _evaluate(browser, session, FRAME)
        time.sleep(0.5)
        assert _evaluate(browser, session, FRAME) == paused
        _evaluate(browser, session, "const s = document.querySelector('.anim-slider');"
                                    "s.value = 40; s.dispatchEvent(new Event('input'));")
        assert _evaluate(browser, session, FRAME) == "40"
        assert "t = 0.800 s" in _evaluate(browser, session,
                                          "document.querySelector('.anim-time').textContent")
        figures = _evaluate(browser, session, CHECK_FIGURES)
        assert len(figures) == 12 and all(figure_ok(f) for f in figures)
        assert _evaluate(browser, session, CLIPPED) == 0
        height = _evaluate(browser, session, "document.documentElement.scrollHeight")
        shot = browser.send("Page.captureScreenshot", {
            "format": "png", "captureBeyondViewport": True,
            "clip": {"x": 0, "y": 0, "width": 1400, "height": height, "scale": 1}},
            session=session, timeout=60)
        errors = [e for e in browser.events if e.get("method") == "Runtime.exceptionThrown"
                  or (e.get("method") == "Log.entryAdded"
                      and e["params"]["entry"].get("level") == "error")]
    finally:
        browser.close()
    screenshot = tmp_path / "predictive-report-animation.png"
    screenshot.write_bytes(base64.b64decode(shot["data"]))
    _keep(screenshot)
    assert errors == []
    assert screenshot.stat().st_size > 50_000


def test_two_animations_in_one_page_play_independently(tmp_path):
    from browser import chromium

    binary = chromium()
    model = build_runner("able")
    res = simulate_runner(model, duration=0.2, excitations=0.05, fall_height=-math.inf)
    report = Report("two runners")
    report.add_section("A", html=[animation_html(res, label="first")])
    report.add_section("B", html=[animation_html(res, label="second")])
    index = report.write(tmp_path / "r")
    browser, session = _open(binary, index, tmp_path / "profile")
    try:
        _evaluate(browser, session,
                  "document.querySelectorAll('button.anim-play')[1].click()")
        deadline = time.monotonic() + 15.0  # a loaded machine may render late: poll
        while True:
            time.sleep(0.5)
            frames = _evaluate(browser, session, "Array.from(document.querySelectorAll("
                                                 "'.runner-animation')).map(r => r.dataset.frame)")
            if int(frames[1]) > 0 or time.monotonic() > deadline:
                break
    finally:
        browser.close()
    assert frames[0] == "0" and int(frames[1]) > 0
