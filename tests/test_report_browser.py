"""Open a generated report in headless Chromium: no console errors, every figure visible.

Chromium is driven through the DevTools protocol over a pipe (``--remote-debugging-pipe``: the
browser reads commands on fd 3 and writes replies on fd 4, NUL-separated JSON), so no extra
Python package is needed. Where Chromium is missing the test installs it with apt-get when run
as root, else it is skipped with the reason. The screenshot is kept in pytest's tmp dir (its
path is printed; run with ``-s`` to see it).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from browser import chromium, figure_ok, inspect_page
from test_report import example_report


@pytest.fixture(scope="module")
def report_index(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example report, written once for both browser tests."""
    return example_report().write(tmp_path_factory.mktemp("browser") / "report")


def test_report_opens_in_headlesschromium(tmp_path: Path, report_index: Path):
    binary = chromium()
    index = report_index
    screenshot = tmp_path / "report.png"
    figures, errors = inspect_page(binary, index, screenshot, tmp_path / "profile")
    print(f"\nreport screenshot: {screenshot}")
    assert errors == [], f"console errors: {errors}"
    assert len(figures) == 5
    for fig in figures:
        assert figure_ok(fig), fig
    assert screenshot.stat().st_size > 20_000


def test_the_browser_check_catches_errors_and_hidden_or_broken_figures(
    tmp_path: Path, report_index: Path
):
    # A negative control: the same inspection must see a script error, a missing image and a
    # hidden one, so a passing report check means something.
    binary = chromium()
    html = report_index.read_text(encoding="utf-8")
    first = html.index('<img src="data:image/png;base64,')
    html = html[:first] + '<img src="missing.png" alt="broken">' + html[first:]
    html = html.replace("<figure>", '<figure style="display:none">', 1)
    html = html.replace(
        "</body>", "<script>console.error('boom'); undefinedCall();</script></body>"
    )
    bad = tmp_path / "bad.html"
    bad.write_text(html, encoding="utf-8")
    figures, errors = inspect_page(binary, bad, tmp_path / "bad.png", tmp_path / "profile")
    texts = json.dumps(errors)
    assert "boom" in texts and "undefinedCall" in texts
    assert "missing.png" in texts  # the failed load is reported as a console error
    assert len(figures) == 6
    assert sum(not figure_ok(f) for f in figures) == 2  # the broken and the hidden one
