"""Shared fixtures."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

# no background compiles from the command lines the tests start (hexapod_kin._tier): each
# would compile a kernel area for tens of seconds; tests/test_tier.py checks them on purpose
os.environ["HEXAPOD_KIN_BACKGROUND"] = "0"

# test tooling shared with tools/ (headless Chromium launcher)
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))

from hexapod_kin import robots


@pytest.fixture(scope="session")
def preset_models():
    """name -> loaded KinematicModel for every preset (hexapod: the whole robot)."""
    from hexapod_kin import load

    return {name: load(name) for name in robots.names()}


def _jit(mode):
    from hexapod_kin import _tier

    before = _tier.set_mode(mode)
    try:
        yield
    finally:
        _tier.set_mode(before)


@pytest.fixture
def jit_always():
    """Compiled tier for every kernel call of the test (tests of the compiled code itself)."""
    yield from _jit("always")


@pytest.fixture
def jit_never():
    """Interpreted tier for every kernel call of the test (the same source run by Python)."""
    yield from _jit("never")


@pytest.fixture
def jit_auto():
    """The default tier rule, whatever the environment sets (``HEXAPOD_KIN_JIT``)."""
    yield from _jit("auto")


@pytest.fixture(scope="module")
def own_cache_dir(tmp_path_factory):
    """A fresh ``HEXAPOD_KIN_CACHE_DIR`` for a whole test module (``pytestmark`` it)."""
    mp = pytest.MonkeyPatch()
    path = tmp_path_factory.mktemp("cache")
    mp.setenv("HEXAPOD_KIN_CACHE_DIR", str(path))
    yield path
    mp.undo()
