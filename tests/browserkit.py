"""Headless Chromium from Debian, driven by Playwright, for the tests of the live page (docs/live.md).

No browser is downloaded: Playwright launches the ``chromium`` the machine
has (``apt-get install chromium``; ``GENOM2BIP_CHROMIUM`` names another
binary).  Without one, the tests that need it skip and say how to install it.
"""
from __future__ import annotations

import os
import shutil

import pytest

#: Far above what a loaded machine takes to lay out a picture or start a stream: a safety net, never the assertion.
SAFETY_MS = 60_000


def chromium_path() -> str | None:
    """The Chromium binary the tests drive: ``GENOM2BIP_CHROMIUM``, else ``chromium`` on PATH."""
    given = os.environ.get("GENOM2BIP_CHROMIUM")
    return given if given else shutil.which("chromium")


def launch(playwright):
    """Debian's Chromium, headless, through ``executable_path``: Playwright's own browsers are never installed."""
    return playwright.chromium.launch(executable_path=chromium_path(), headless=True)


needs_chromium = pytest.mark.skipif(
    chromium_path() is None, reason="no Chromium: `apt-get install chromium` (Debian's headless browser)")


def open_page(browser, url: str):
    """A new page at ``url`` that records the page's script errors in ``page.errors``."""
    page = browser.new_page(viewport={"width": 1500, "height": 1100})
    page.errors = []
    page.on("pageerror", lambda exc: page.errors.append(str(exc)))
    page.goto(url)
    return page
