"""Headless Chromium for the browser tests and the screenshot tools (test tooling, not package).

Debian's ``chromium`` binary driven by Playwright (``executable_path``); never
``playwright install``. :func:`launch_chromium` starts one browser in a running Playwright;
:func:`chromium` is the whole lifetime (Playwright and browser) for a tool.
"""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Iterator, Sequence
from typing import Any

from hexapod_kin.exceptions import OptionalDependencyError

#: Command-line flags of the headless Chromium that opens exported pages (tests, screenshots):
#: software WebGL, and no background traffic of the browser itself.
CHROMIUM_ARGS: tuple[str, ...] = (
    "--headless",
    "--no-sandbox",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-quic",
)


def launch_chromium(
    playwright: Any, executable: str | None = None, extra: Sequence[str] = ()
) -> Any:
    """Launch headless Chromium through Playwright with :data:`CHROMIUM_ARGS` and ``extra``.

    Args:
        playwright: A started Playwright (the object of ``with sync_playwright() as p``).
        executable: Path of the Chromium binary (default: ``chromium`` on PATH, Debian's).
        extra: More command-line flags (e.g. ``--disable-webgl``).

    Returns:
        The Playwright ``Browser``; close it when done.

    Raises:
        OptionalDependencyError: No ``executable`` given and ``chromium`` is not on PATH.

    """
    path = executable if executable is not None else shutil.which("chromium")
    if path is None:
        raise OptionalDependencyError(
            "executable=None and `chromium` is not on PATH; install it (apt-get install chromium)"
        )
    return playwright.chromium.launch(executable_path=path, args=[*CHROMIUM_ARGS, *extra])


@contextlib.contextmanager
def chromium(executable: str | None = None) -> Iterator[Any]:
    """Playwright and one headless Chromium (:func:`launch_chromium`), closed on exit.

    Raises:
        OptionalDependencyError: ``chromium`` is not on PATH.
        ImportError: playwright (python) is not installed.

    """
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch_chromium(p, executable)
        try:
            yield browser
        finally:
            browser.close()
