"""Open a generated report in headless Chromium: no console errors, every figure visible.

Chromium is driven through the DevTools protocol over a pipe (``--remote-debugging-pipe``: the
browser reads commands on fd 3 and writes replies on fd 4, NUL-separated JSON), so no extra
Python package is needed. Where Chromium is missing the test installs it with apt-get when run
as root, else it is skipped with the reason. The screenshot is kept in pytest's tmp dir (its
path is printed; run with ``-s`` to see it).
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

from test_report import example_report

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


def _chromium() -> str:
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


def _inspect(binary: str, page: Path, screenshot: Path, profile: Path) -> tuple[list, list]:
    """Load ``page``; return (figure checks, console errors) and save a full-page screenshot."""
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
    return figures, errors


def _figure_ok(fig: dict) -> bool:
    return (
        fig["complete"]
        and fig["naturalWidth"] > 100
        and fig["naturalHeight"] > 100
        and fig["visible"]
        and fig["width"] > 300
        and fig["height"] > 100
    )


@pytest.fixture(scope="module")
def report_index(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example report, written once for both browser tests."""
    return example_report().write(tmp_path_factory.mktemp("browser") / "report")


def test_report_opens_in_headless_chromium(tmp_path: Path, report_index: Path):
    binary = _chromium()
    index = report_index
    screenshot = tmp_path / "report.png"
    figures, errors = _inspect(binary, index, screenshot, tmp_path / "profile")
    print(f"\nreport screenshot: {screenshot}")
    assert errors == [], f"console errors: {errors}"
    assert len(figures) == 5
    for fig in figures:
        assert _figure_ok(fig), fig
    assert screenshot.stat().st_size > 20_000


def test_the_browser_check_catches_errors_and_hidden_or_broken_figures(
    tmp_path: Path, report_index: Path
):
    # A negative control: the same inspection must see a script error, a missing image and a
    # hidden one, so a passing report check means something.
    binary = _chromium()
    html = report_index.read_text(encoding="utf-8")
    first = html.index('<img src="data:image/png;base64,')
    html = html[:first] + '<img src="missing.png" alt="broken">' + html[first:]
    html = html.replace("<figure>", '<figure style="display:none">', 1)
    html = html.replace(
        "</body>", "<script>console.error('boom'); undefinedCall();</script></body>"
    )
    bad = tmp_path / "bad.html"
    bad.write_text(html, encoding="utf-8")
    figures, errors = _inspect(binary, bad, tmp_path / "bad.png", tmp_path / "profile")
    texts = json.dumps(errors)
    assert "boom" in texts and "undefinedCall" in texts
    assert "missing.png" in texts  # the failed load is reported as a console error
    assert len(figures) == 6
    assert sum(not _figure_ok(f) for f in figures) == 2  # the broken and the hidden one
