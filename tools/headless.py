"""Headless Chromium for the browser tests and the screenshot tool (test tooling, not package).

Debian's ``chromium`` binary driven by Playwright (``executable_path``); never
``playwright install``.
"""

from __future__ import annotations

import shutil
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


def launch_chromium(playwright: Any, executable: str | None = None) -> Any:
    """Launch headless Chromium through Playwright with :data:`CHROMIUM_ARGS`.

    Args:
        playwright: A started Playwright (the object of ``with sync_playwright() as p``).
        executable: Path of the Chromium binary (default: ``chromium`` on PATH, Debian's).

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
    return playwright.chromium.launch(executable_path=path, args=list(CHROMIUM_ARGS))
