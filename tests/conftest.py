"""Shared fixtures."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

# test tooling shared with tools/ (headless Chromium launcher)
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))

from hexapod_kin import robots


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
