"""Legged locomotion: foot paths, standing poses, and (soon) gaits of the whole robot.

* :mod:`.paths` — one leg's step cycle (:func:`foot_path`, :func:`foot_step`).
* :mod:`.stand` — standing poses and the hexapod's body sway (:func:`demo_trajectory`).
"""

from __future__ import annotations

from .paths import FootStep, foot_path, foot_step
from .stand import default_configuration, demo_trajectory, frame_poses, standing_base

__all__ = [
    "FootStep",
    "default_configuration",
    "demo_trajectory",
    "foot_path",
    "foot_step",
    "frame_poses",
    "standing_base",
]
