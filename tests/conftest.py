"""Shared fixtures."""

from __future__ import annotations

import os
import shutil
import signal
import sys
from pathlib import Path

import pytest

# test tooling shared with tools/ (headless Chromium launcher)
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))

from hexapod_kin import robots

PACKAGE = Path(__file__).resolve().parent.parent / "hexapod_kin"


def pytest_configure(config: pytest.Config) -> None:
    """Compile the package's bytecode once, before any test starts a command as a child.

    Hundreds of tests run ``hexapod-kin`` as a child process. Where Python writes no bytecode
    (``PYTHONDONTWRITEBYTECODE``, common in containers and CI images) each child would compile
    the sources of every module it imports, 0.1-0.25 s of CPU per command; an editable
    install (``pip install -e``, the README's) does not compile them either. The files are
    ``__pycache__/*.pyc`` beside the sources, as Python itself writes them (git ignores them;
    a changed source is still recompiled, its timestamp no longer matching). Run once, by
    xdist's controller (or the only process); without the setting, the first import writes
    them.

    A run started with Ctrl-C ignored (``nohup pytest &`` from a shell without job control:
    the shell sets SIGINT to "ignore", and every child inherits that) would leave the tests that
    send a command Ctrl-C waiting for a child that cannot hear it; the run gets Python's default
    handler back, so that its children start with the default disposition, as from a terminal.
    """
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if not sys.dont_write_bytecode or hasattr(config, "workerinput"):
        return
    import compileall

    compileall.compile_dir(PACKAGE, quiet=2)


#: The test files that take longest in the default run, longest first (CPU of each file's
#: tests with their children, plus the browser tests' waits; measured in session 8). xdist's
#: ``--dist loadfile`` hands whole files to the workers in collection order (pyproject's
#: ``--no-loadscope-reorder`` keeps that order instead of sorting files by their number of
#: tests, which left files of a few long tests to the end). Longest first leaves only short
#: files for the end, so that neither worker idles long while the other finishes one.
#: A file not listed runs after these, in the usual order.
LONGEST_FIRST = (
    "test_hostile_cli.py",
    "test_sweep.py",
    "test_drive_browser.py",
    "test_gait.py",
    "test_hostile_round3_cli.py",
    "test_readme.py",
    "test_simulate.py",
    "test_cache_matrix.py",
    "test_control.py",
    "test_exit_status.py",
    "test_gait_physics.py",
    "test_symbolic.py",
    "test_report_replay.py",
    "test_drive.py",
    "test_faults.py",
    "test_singularity.py",
    "test_symbolic_budget.py",
    "test_viewer.py",
    "test_symbolic_compare.py",
    "test_report.py",
    "test_legged.py",
    "test_erd_all.py",
    "test_export.py",
    "test_motion.py",
    "test_simulate_robot.py",
    "test_size_rule.py",
    "test_one_of_each.py",
    "test_ik_solver.py",
    "test_reader.py",
    "test_fromurdf.py",
    "test_report_worker.py",
    "test_cli_fuzz.py",
    "test_gate.py",
    "test_timeline.py",
    "test_environment.py",
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Run the files of :data:`LONGEST_FIRST` first, in its order (a stable sort: each file's
    tests keep their order, and the other files theirs)."""
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


@pytest.fixture(scope="session")
def preset_models():
    """name -> loaded KinematicModel for every preset (hexapod: the whole robot)."""
    from hexapod_kin import load

    return {name: load(name) for name in robots.names()}


@pytest.fixture(scope="module")
def own_cache_dir(tmp_path_factory):
    """A fresh ``HEXAPOD_KIN_CACHE_DIR`` for a whole test module (``pytestmark`` it)."""
    mp = pytest.MonkeyPatch()
    path = tmp_path_factory.mktemp("cache")
    mp.setenv("HEXAPOD_KIN_CACHE_DIR", str(path))
    yield path
    mp.undo()


@pytest.fixture
def drawn(monkeypatch):
    """The figures written through ``plots.save_figure`` (still written), in order.

    Tests read what a figure draws (line and image data) instead of a file's header.
    """
    from hexapod_kin import plots

    figs = []
    real = plots.save_figure

    def keep(fig, path, *args, **kwargs):
        figs.append(fig)
        return real(fig, path, *args, **kwargs)

    monkeypatch.setattr(plots, "save_figure", keep)
    return figs


def _need(what: str) -> None:
    """Skip a browser test without ``what``; under CI (which installs it) fail instead."""
    if os.environ.get("CI"):
        pytest.fail(f"CI is set but {what} is missing (.ci/run installs it)")
    pytest.skip(f"{what} is missing (apt-get install chromium; pip install playwright); skipped")


@pytest.fixture(scope="module")
def playwright_api():
    """``(playwright, chromium path)``: Debian's Chromium driven by Playwright (one per module)."""
    path = shutil.which("chromium")
    if path is None:
        _need("`chromium` on PATH")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _need("playwright (python)")
    with sync_playwright() as p:
        yield p, path


@pytest.fixture(scope="module")
def browser(playwright_api):
    """A headless Chromium (``tools/headless.launch_chromium``) for a whole test module."""
    from headless import launch_chromium

    b = launch_chromium(*playwright_api)
    yield b
    b.close()
