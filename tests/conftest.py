"""Shared fixtures."""

from __future__ import annotations

import pytest

from hexapod_kin import robots


@pytest.fixture(scope="session")
def preset_models():
    """name -> loaded KinematicModel for every preset (hexapod: the whole robot)."""
    from hexapod_kin import load

    return {name: load(name) for name in robots.names()}
