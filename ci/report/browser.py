"""A report page opened in a real browser: Debian's headless Chromium driven by Playwright (never a downloaded
browser), every request other than ``file:`` or ``data:`` blocked and counted, errors collected, images, sections
and tables measured, and a screenshot taken.

Usage: python -m ci.report.browser PAGE [--screenshot PNG]  (exit 0 when the page passes every check, 1 if not,
4 when Chromium or Playwright is missing)
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from spec.errors import ExitCode, ToolMissing

CHROMIUM_NAMES = ("chromium", "chromium-browser")  # Debian's package, and its name elsewhere
LOAD_TIMEOUT_MS = 60_000


def chromium() -> str | None:
    """The system Chromium's path, or None."""
    return next((found for name in CHROMIUM_NAMES if (found := shutil.which(name))), None)


@dataclass(slots=True)
class PageCheck:
    """What the browser saw."""

    blocked: list[str] = field(default_factory=list)  # requests to anything but file: and data:
    errors: list[str] = field(default_factory=list)  # page errors (uncaught exceptions) and console errors
    images: list[tuple[str, int]] = field(default_factory=list)  # (alt or src, natural width)
    sections: list[tuple[str, float, float]] = field(default_factory=list)  # (id, width, height) in CSS pixels
    tables: list[tuple[str, int]] = field(default_factory=list)  # (caption, body rows)

    def problems(self) -> list[str]:
        """Every check the page fails, one line each; empty when it passes."""
        found = [f"request blocked: {url}" for url in self.blocked]
        found += [f"error: {e}" for e in self.errors]
        found += [f"image not loaded: {name}" for name, width in self.images if width <= 0]
        found += [f"section of no size: {key}" for key, w, h in self.sections if w <= 0 or h <= 0]
        found += [f"empty table: {caption or '(no caption)'}" for caption, rows in self.tables if rows == 0]
        if not self.sections:
            found.append("no section on the page")
        return found


def open_page(page_path: Path, screenshot: Path | None = None, executable: str | None = None) -> PageCheck:
    """Open ``page_path`` in headless Chromium and measure it (``PageCheck``); ToolMissing without Chromium or
    Playwright."""
    executable = executable or chromium()
    if executable is None:
        raise ToolMissing("chromium is not installed (Debian: apt-get install chromium; `OVERTAKE_BROWSER=1 bash "
                          "ci/setup.sh` does it)")
    try:
        from playwright.sync_api import Error, Route, sync_playwright
    except ImportError:
        raise ToolMissing("playwright is not installed (pip install playwright; no browser download is needed)") \
            from None
    check = PageCheck()

    def route(r: Route) -> None:
        if r.request.url.startswith(("file:", "data:")):
            r.continue_()
        else:
            check.blocked.append(r.request.url)
            r.abort()

    def console(message: Any) -> None:
        if message.type == "error":
            check.errors.append(f"console: {message.text}")

    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=executable, args=["--no-sandbox"])
            try:
                page = browser.new_page(viewport={"width": 1200, "height": 900})
                page.route("**/*", route)
                page.on("pageerror", lambda error: check.errors.append(f"page: {error}"))
                page.on("console", console)
                page.goto(page_path.resolve().as_uri(), wait_until="load", timeout=LOAD_TIMEOUT_MS)
                check.images = [(str(a), int(w)) for a, w in page.evaluate(
                    "Array.from(document.images).map(i => [i.alt || i.src.slice(0, 80), i.naturalWidth])")]
                check.sections = [(str(k), float(w), float(h)) for k, w, h in page.evaluate(
                    "Array.from(document.querySelectorAll('section')).map(s => "
                    "[s.id, s.getBoundingClientRect().width, s.getBoundingClientRect().height])")]
                check.tables = [(str(c), int(n)) for c, n in page.evaluate(
                    "Array.from(document.querySelectorAll('table')).map(t => "
                    "[t.caption ? t.caption.textContent : '', t.tBodies.length ? t.tBodies[0].rows.length : 0])")]
                if screenshot is not None:
                    page.screenshot(path=str(screenshot), full_page=False)
            finally:
                browser.close()
    except Error as error:
        raise ToolMissing(f"chromium at {executable} could not open the page: {str(error).splitlines()[0]}") \
            from None
    return check


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("page", type=Path)
    parser.add_argument("--screenshot", type=Path, default=None)
    args = parser.parse_args()
    if not args.page.is_file():
        print(f"browser: {args.page}: no such page", file=sys.stderr)
        sys.exit(ExitCode.BAD_INPUT)
    shot_dir = args.screenshot.parent if args.screenshot is not None else None
    if shot_dir is not None and (not shot_dir.is_dir() or not os.access(shot_dir, os.W_OK)):
        print(f"browser: --screenshot={args.screenshot}: its folder is missing or cannot be written", file=sys.stderr)
        sys.exit(ExitCode.BAD_INPUT)
    try:
        check = open_page(args.page, args.screenshot)
    except ToolMissing as error:
        print(f"browser: {error}", file=sys.stderr)
        sys.exit(ExitCode.TOOL_MISSING)
    problems = check.problems()
    print(f"browser: {args.page}: {len(check.sections)} sections, {len(check.tables)} tables, {len(check.images)} "
          f"images, {len(check.blocked)} requests blocked, {len(check.errors)} errors"
          + (f"; screenshot {args.screenshot}" if args.screenshot else ""))
    for problem in problems:
        print(f"browser: {problem}", file=sys.stderr)
    sys.exit(ExitCode.NO if problems else ExitCode.OK)


if __name__ == "__main__":
    main()
