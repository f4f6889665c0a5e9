"""Headless Chromium driven over the DevTools pipe, for the report browser tests.

Chromium reads commands on fd 3 and writes replies on fd 4 (``--remote-debugging-pipe``,
NUL-separated JSON), so no extra Python package is needed. Where Chromium is missing,
:func:`chromium` installs it with apt-get when run as root, else it skips the test with the
reason. Imported by ``test_report_browser.py`` and ``test_report_study.py``.
"""

from __future__ import annotations

import base64
import json
import os
import select
import shutil
import subprocess
import time
from pathlib import Path

import pytest

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--remote-debugging-pipe",
]

# Evaluated in the page: every <img> decoded, non-empty, laid out and not hidden.
CHECK_FIGURES = """
(() => Array.from(document.images).map((img) => {
  const r = img.getBoundingClientRect();
  const s = getComputedStyle(img);
  return {alt: img.alt, complete: img.complete, naturalWidth: img.naturalWidth,
          naturalHeight: img.naturalHeight, width: r.width, height: r.height,
          visible: s.display !== 'none' && s.visibility !== 'hidden' && Number(s.opacity) > 0};
}))()
"""


def chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    if hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("apt-get"):
        for cmd in (
            ["apt-get", "install", "-y", "-qq", "chromium"],
            ["apt-get", "update", "-qq"],
            ["apt-get", "install", "-y", "-qq", "chromium"],
        ):
            subprocess.run(cmd, capture_output=True, timeout=900, check=False)
            if shutil.which("chromium"):
                return shutil.which("chromium")  # type: ignore[return-value]
    pytest.skip(
        "Chromium is not installed and cannot be installed here "
        "(install the Debian package 'chromium' as root to run this test)"
    )


def _to_fds_3_and_4(read_end: int, write_end: int) -> None:
    """In the child: put the command pipe on fd 3 and the reply pipe on fd 4."""
    a, b = os.dup(read_end), os.dup(write_end)  # out of the way if either is 3 or 4
    os.dup2(a, 3)
    os.dup2(b, 4)


class _DevTools:
    """A minimal DevTools-protocol client over Chromium's debugging pipe."""

    def __init__(self, binary: str, profile: Path) -> None:
        cmd_r, self._cmd_w = os.pipe()  # we write commands; Chromium reads fd 3
        self._out_r, out_w = os.pipe()  # Chromium writes fd 4; we read
        self.proc = subprocess.Popen(
            [binary, *FLAGS, f"--user-data-dir={profile}", "about:blank"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(3, 4),
            preexec_fn=lambda: _to_fds_3_and_4(cmd_r, out_w),
        )
        os.close(cmd_r)
        os.close(out_w)
        self._next = 0
        self._buf = b""
        self.events: list[dict] = []

    def _read_message(self, deadline: float) -> dict:
        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._out_r], [], [], left)[0]:
                raise TimeoutError("no reply from Chromium")
            chunk = os.read(self._out_r, 1 << 20)
            if not chunk:
                raise RuntimeError("Chromium closed the debugging pipe")
            self._buf += chunk
        raw, self._buf = self._buf.split(b"\0", 1)
        return json.loads(raw)

    def send(
        self,
        method: str,
        params: dict | None = None,
        *,
        session: str | None = None,
        timeout: float = 30.0,
    ) -> dict:
        self._next += 1
        msg = {"id": self._next, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._cmd_w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self.events.append(reply)

    def wait_event(self, method: str, timeout: float = 30.0) -> dict:
        for ev in self.events:
            if ev.get("method") == method:
                return ev
        deadline = time.monotonic() + timeout
        while True:
            ev = self._read_message(deadline)
            self.events.append(ev)
            if ev.get("method") == method:
                return ev

    def close(self) -> None:
        try:
            self.send("Browser.close", timeout=10)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self._cmd_w)
        os.close(self._out_r)


LAYOUT = """
(() => ({
  pageOverflowX: document.documentElement.scrollWidth - document.documentElement.clientWidth,
  tables: Array.from(document.querySelectorAll("table.data")).map((t) => {
    const box = t.closest(".table-scroll");
    return {scrolls: box !== null && ["auto", "scroll"].includes(getComputedStyle(box).overflowX),
            overflows: box !== null && box.scrollWidth > box.clientWidth + 1,
            hintShown: box !== null && box.previousElementSibling !== null
              && box.previousElementSibling.classList.contains("table-hint")
              && !box.previousElementSibling.hidden};
  }),
  headings: Array.from(document.querySelectorAll("section.card h2")).map((h) => h.textContent),
}))()
"""
"""Evaluated in the page with ``probe=LAYOUT``: horizontal overflow of the page, whether every
table sits in a scrolling box (and is announced when it overflows it), the section headings."""


def inspect_page(binary: str, page: Path, screenshot: Path, profile: Path,
                 probe: str | None = None):
    """Load ``page``; return (figure checks, console errors) and save a full-page screenshot;
    with ``probe`` (a JavaScript expression) also its value: (figures, errors, value)."""
    browser = _DevTools(binary, profile)
    try:
        target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"
        ]
        for domain in ("Page", "Runtime", "Log"):
            browser.send(f"{domain}.enable", session=session)
        browser.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1400, "height": 900, "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        browser.events.clear()
        browser.send("Page.navigate", {"url": page.as_uri()}, session=session)
        browser.wait_event("Page.loadEventFired", timeout=60)
        figures = browser.send(
            "Runtime.evaluate",
            {"expression": CHECK_FIGURES, "returnByValue": True},
            session=session,
        )["result"]["value"]
        probed = None if probe is None else browser.send(
            "Runtime.evaluate", {"expression": probe, "returnByValue": True}, session=session,
        )["result"].get("value")
        height = browser.send(
            "Runtime.evaluate",
            {"expression": "document.documentElement.scrollHeight", "returnByValue": True},
            session=session,
        )["result"]["value"]
        shot = browser.send(
            "Page.captureScreenshot",
            {
                "format": "png",
                "captureBeyondViewport": True,
                "clip": {"x": 0, "y": 0, "width": 1400, "height": height, "scale": 1},
            },
            session=session,
            timeout=60,
        )
        screenshot.write_bytes(base64.b64decode(shot["data"]))
        errors = [
            ev["params"]
            for ev in browser.events
            if (ev.get("method") == "Runtime.exceptionThrown")
            or (
                ev.get("method") == "Runtime.consoleAPICalled"
                and ev["params"].get("type") in ("error", "assert")
            )
            or (
                ev.get("method") == "Log.entryAdded"
                and ev["params"]["entry"].get("level") == "error"
            )
        ]
    finally:
        browser.close()
    if probe is not None:
        return figures, errors, probed
    return figures, errors


def figure_ok(fig: dict) -> bool:
    return (
        fig["complete"]
        and fig["naturalWidth"] > 100
        and fig["naturalHeight"] > 100
        and fig["visible"]
        and fig["width"] > 300
        and fig["height"] > 100
    )
