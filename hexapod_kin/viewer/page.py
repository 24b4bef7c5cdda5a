"""The self-contained offline page: :func:`render_html`, :func:`export_html`, :func:`iframe`.

The page inlines meshcat's bundle and the scene (msgpack commands, meshes without normals),
gzipped and base64, unpacked by the page itself (no fetch; the bundle runs from a ``blob:``
URL), so it opens from disk with no network: its Content-Security-Policy forbids every fetch.
"""

from __future__ import annotations

import base64
import functools
import gzip
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._io import atomic_write
from .._page import fill, frame, page, script_json
from ..exceptions import ParameterError, positive
from .objects import bundle, pack
from .scene import PARTS, Scene, build_for, resolve_triad_frames

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model


#: The page may run its own inline code and decode data: URIs, and fetch nothing else.
_CSP = (
    "default-src 'none'; script-src 'unsafe-inline' blob:; style-src 'unsafe-inline'; "
    "img-src data: blob:; worker-src blob:"
)


@functools.lru_cache(maxsize=2)
def _template(name: str) -> str:
    """``page.css`` or ``page.html`` (holes ``$help``, ``$data``), beside this module."""
    return (Path(__file__).parent / name).read_text(encoding="utf-8")


@functools.lru_cache(maxsize=1)
def _bundle_gz() -> str:
    """Meshcat's JavaScript bundle gzipped, base64 (about 0.3 MB instead of 0.85 MB)."""
    return base64.b64encode(gzip.compress(bundle().encode("utf-8"), 9, mtime=0)).decode("ascii")


def _scene_blob(static: list[dict[str, Any]], animation: dict[str, Any] | None) -> bytes:
    """The page's scene: each command (msgpack) after its uint32 LE length, gzipped, no mtime."""
    cmds = static + ([animation] if animation is not None else [])
    parts = []
    for cmd in cmds:
        packed = pack(cmd)
        parts += [len(packed).to_bytes(4, "little"), packed]
    return gzip.compress(b"".join(parts), compresslevel=9, mtime=0)


def render_html(
    model: Model,
    times: Any,
    qs: Any,
    *,
    base_poses: Any = None,
    trace_frame: Any = None,
    frame_triads: Any = False,
    singular_mask: Any = None,
    title: str | None = None,
    fps: float | None = None,
    loop: bool = True,
    speed: float = 1.0,
    play: bool = True,
    overlays: Any = None,
) -> str:
    """The self-contained animated HTML page of a trajectory (opens from disk, no network).

    A panel with play/pause, loop, speed and the time; for scripts the page exposes
    ``window.hexapodKin`` (``seek(t)``, ``play()``, ``pause()``, ``setVisible(part, on)``,
    ``setLoop(on)``, ``setSpeed(s)``).

    Args:
        model: A loaded model (``hexapod_kin.load(...)``).
        times: Sample times (N,) in [s], strictly increasing.
        qs: Joint configurations (N, nq) in [rad] / [m]. A single (nq,) shows a still pose.
        base_poses: World pose of the root per sample, (N, 4, 4) or one (4, 4) (a floating
            body, e.g. a walking hexapod).
        trace_frame: Frame(s) whose path is drawn (``False``: none; default the tip, or every
            foot of a hexapod).
        frame_triads: ``True`` draws the Khalil frames 0..n (x red, y green, z blue, labelled
            j); or a sequence of frame names (labelled by position).
        singular_mask: (N,) booleans; a red sphere marks the traced point at each flagged
            (near-singular) sample.
        title: Page title (default: the model's name).
        fps: Resample the animation at this rate in [frames/s] (default: the given samples,
            or 60 frames/s above :data:`MAX_SAMPLES` samples).
        loop: Repeat the animation forever (else play once).
        speed: Playback speed factor (> 0).
        play: Start playing when the page opens.
        overlays: ``name -> (N, M, 3)``: a polyline of M world points [m] per sample, drawn
            as thin tubes (M = 1: a moving sphere) under ``/meshcat/overlays/<name>``.

    Raises:
        ConfigurationError: Bad ``times``/``qs``/``base_poses``/``singular_mask``/``overlays``.
        FrameNotFoundError: A frame name does not exist.
        ParameterError: Bad ``fps`` or ``speed``.
        OptionalDependencyError: meshcat is not installed.
        ViewerError: The visual geometry cannot be built.

    """
    speed = positive("speed", speed, at_most=100.0)
    script = _bundle_gz()  # first: no work without meshcat
    built = build_for(
        model,
        times,
        qs,
        base_poses=base_poses,
        trace_frame=trace_frame,
        frame_triads=frame_triads,
        singular_mask=singular_mask,
        fps=fps,
        play=play,
        loop=loop,
        overlays=overlays,
        scene=Scene(model, normals=False),  # the page computes the normals
    )
    label = title if title is not None else f"hexapod_kin: {model.name}"
    data = {
        "title": label,
        "bundle": script,
        "scene": base64.b64encode(_scene_blob(built.static, built.animation)).decode("ascii"),
        "animation": built.animation is not None,
        "duration": built.duration,
        "t0": built.t0,
        "loop": bool(loop),
        "speed": float(speed),
        "play": bool(play),
        "parts": list(PARTS),
    }
    help_text = "drag: orbit · right-drag: pan · wheel: zoom"
    if resolve_triad_frames(model, frame_triads):
        help_text += " · triads x/y/z = red/green/blue, label = Khalil frame index"
    if built.static and singular_mask is not None and np.any(singular_mask):
        help_text += " · red spheres: near-singular samples"
    body = fill(_template("page.html"), help=help_text, data=script_json(data))
    return page(label, body, style=_template("page.css").removesuffix("\n"), policy=_CSP)


def export_html(
    model: Model, times: Any, qs: Any, path: str | os.PathLike[str], **options: Any
) -> Path:
    """Write :func:`render_html` (``options``: its keywords) to ``path`` atomically; return it.

    Raises:
        ParameterError: Bad destination (and every error of :func:`render_html`).

    """
    return atomic_write(path, render_html(model, times, qs, **options))


def iframe(html: str | os.PathLike[str], *, height: int = 480) -> str:
    """An ``<iframe srcdoc=...>`` embedding the page ``html`` wrote by :func:`export_html`.

    ``height``: in [px] (100..4000).

    Raises:
        ParameterError: Bad ``height`` or not a file.

    """
    path = Path(html)
    if not path.is_file():
        raise ParameterError(f"html={str(path)!r} is not a file written by export_html")
    return frame(path.read_text(encoding="utf-8"), height=height)
