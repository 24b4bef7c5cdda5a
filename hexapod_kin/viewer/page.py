"""The self-contained offline page: :func:`render_html`, :func:`export_html`, :func:`iframe`.

The page inlines meshcat's bundle and the scene (msgpack commands, meshes without normals),
gzipped and base64, unpacked by the page itself (no fetch; the bundle runs from a ``blob:``
URL), so it opens from disk with no network: its Content-Security-Policy forbids every fetch.
"""

from __future__ import annotations

import base64
import functools
import gzip
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._io import atomic_write
from .._page import fill, frame, page, script_json
from ..exceptions import ParameterError
from .objects import bundle, pack
from .scene import PARTS, Scene, build_for, resolve_triad_frames

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model


# ====================================================================== self-contained HTML
#: The page may run its own inline code and decode data: URIs, and fetch nothing else.
_CSP = (
    "default-src 'none'; script-src 'unsafe-inline' blob:; style-src 'unsafe-inline'; "
    "img-src data: blob:; worker-src blob:"
)
#: The page's style sheet.
_STYLE = """body { margin: 0; overflow: hidden; font-family: sans-serif; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
#hk-panel { position: absolute; left: 8px; top: 8px; padding: 6px 10px; border-radius: 6px;
  background: rgba(255,255,255,0.82); color: #222; font-size: 13px; line-height: 1.5; }
#hk-panel b { font-size: 14px; }
#hk-panel button, #hk-panel select { font-size: 12px; }
#hk-help { color: #555; font-size: 11px; }"""

#: The page's body: the meshcat pane, the panel (``$help``), the script (``$data``).
_BODY = """<div id="meshcat-pane"></div>
<div id="hk-panel"><b id="hk-title"></b><br>
<span id="hk-controls"><button id="hk-play">pause</button>
<label><input type="checkbox" id="hk-loop"> loop</label>
speed <select id="hk-speed"><option>0.25</option><option>0.5</option><option>1</option>
<option>2</option><option>4</option></select>
t = <span id="hk-time">0.000</span> s</span><br>
<span id="hk-help">$help</span></div>
<script>
(function () {
  "use strict";
  var DATA = $data;
  var help = document.getElementById("hk-help");
  function bytes(b64) {
    var s = atob(b64), out = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) { out[i] = s.charCodeAt(i); }
    return out;
  }
  // The scene: meshcat commands (msgpack), each after its uint32 length, gzipped together.
  function inflate(b64) {
    var stream = new Blob([bytes(b64)]).stream().pipeThrough(new DecompressionStream("gzip"));
    return new Response(stream).arrayBuffer();
  }
  function split(buf) {
    var view = new DataView(buf), out = [], at = 0;
    while (at + 4 <= buf.byteLength) {
      var n = view.getUint32(at, true);
      out.push(new Uint8Array(buf.slice(at + 4, at + 4 + n)));
      at += 4 + n;
    }
    return out;
  }
  if (typeof DecompressionStream === "undefined") {
    help.textContent = "this browser cannot unpack the scene (no DecompressionStream): " +
      "open the page in Chrome 80+, Firefox 113+ or Safari 16.4+";
    return;
  }
  // meshcat's bundle, gzipped too, runs from a blob: URL made here (script-src blob:).
  Promise.all([inflate(DATA.bundle), inflate(DATA.scene)]).then(function (parts) {
    var url = URL.createObjectURL(new Blob([parts[0]], { type: "text/javascript" }));
    var tag = document.createElement("script");
    tag.onload = function () { URL.revokeObjectURL(url); start(split(parts[1])); };
    tag.onerror = function () { help.textContent = "could not run meshcat's bundle"; };
    tag.src = url;
    document.head.appendChild(tag);
  }).catch(function (err) {
    help.textContent = "could not unpack the scene: " + err;
  });
  function start(cmds) {
  var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
  var anim = DATA.animation ? cmds.pop() : null;
  cmds.forEach(function (c) { viewer.handle_command_bytearray(c); });
  viewer.scene.traverse(function (o) {  // meshes come without normals: computed here
    var g = o.geometry;
    if (o.isMesh && g && g.isBufferGeometry && g.index && !g.getAttribute("normal")) {
      g.computeVertexNormals();
    }
  });
  var animator = viewer.animator;
  if (anim) {
    viewer.handle_command_bytearray(anim);
    animator.mixer.timeScale = DATA.speed;
  }
  document.getElementById("hk-title").textContent = DATA.title;
  var playBtn = document.getElementById("hk-play"), loopBox = document.getElementById("hk-loop");
  var speedSel = document.getElementById("hk-speed"), timeEl = document.getElementById("hk-time");
  if (!DATA.animation) { document.getElementById("hk-controls").style.display = "none"; }
  loopBox.checked = DATA.loop;
  speedSel.value = String(DATA.speed);
  function setLoop(on) {
    animator.actions.forEach(function (a) { a.repetitions = on ? Infinity : 1; });
  }
  function play() {
    if (animator.actions.length && animator.actions.every(function (a) { return a.paused; })) {
      animator.reset();
    }
    animator.play(); playBtn.textContent = "pause";
  }
  function pause() { animator.pause(); playBtn.textContent = "play"; }
  function seek(t) {
    animator.actions.forEach(function (a) { a.enabled = true; a.paused = false; a.play(); });
    animator.pause(); playBtn.textContent = "play";
    animator.seek(t - DATA.t0); animator.display_progress(t - DATA.t0);
    viewer.render();
  }
  playBtn.onclick = function () { if (animator.playing) { pause(); } else { play(); } };
  loopBox.onchange = function () { setLoop(loopBox.checked); };
  speedSel.onchange = function () { animator.mixer.timeScale = parseFloat(speedSel.value); };
  if (!DATA.play) { playBtn.textContent = "play"; }
  (function tick() {
    timeEl.textContent = (DATA.t0 + (animator.time || 0)).toFixed(3);
    if (DATA.animation && !animator.playing) { playBtn.textContent = "play"; }
    requestAnimationFrame(tick);
  })();
  window.hexapodKin = {
    viewer: viewer, duration: DATA.duration, t0: DATA.t0, parts: DATA.parts,
    play: play, pause: pause, seek: seek, setLoop: setLoop,
    setSpeed: function (s) { animator.mixer.timeScale = s; speedSel.value = String(s); },
    setVisible: function (part, on) {
      viewer.set_property(["meshcat", part], "visible", !!on); viewer.render();
    },
    render: function () { viewer.render(); },
    ready: true
  };
  viewer.render();
  }
})();
</script>
"""


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
        base_poses: Optional world pose of the model's root per sample, (N, 4, 4) or one (4, 4)
            (a floating body, e.g. a walking hexapod).
        trace_frame: Frame(s) whose path is drawn: a name, a sequence of names, ``False`` for
            none; default the tip (every foot for a hexapod).
        frame_triads: ``True`` draws the Khalil frames 0..n of the chain (x red, y green,
            z blue, labelled with the index j); or a sequence of frame names (labelled with
            their position in the sequence).
        singular_mask: Optional (N,) booleans; a red sphere marks the traced point at each
            flagged (near-singular) sample.
        title: Page title (default: the model's name).
        fps: Resample the animation at this rate in [frames/s] (default: the given samples,
            or 60 frames/s above :data:`MAX_SAMPLES` samples).
        loop: Repeat the animation forever (else play once).
        speed: Playback speed factor (> 0).
        play: Start playing when the page opens.
        overlays: Optional mapping ``name -> (N, M, 3)`` array: a polyline of M world points
            [m] per sample, drawn as thin tubes (M = 1: a moving sphere) under
            ``/meshcat/overlays/<name>``.

    Returns:
        The page (:func:`export_html` writes it to a file).

    Raises:
        ConfigurationError: Bad ``times``/``qs``/``base_poses``/``singular_mask``/``overlays``.
        FrameNotFoundError: A frame name does not exist.
        ParameterError: Bad ``fps`` or ``speed``.
        OptionalDependencyError: meshcat is not installed.
        ViewerError: The visual geometry cannot be built.

    """
    if not (isinstance(speed, (int, float)) and math.isfinite(speed) and 0 < speed <= 100):
        raise ParameterError(f"speed={speed!r} is not allowed; give a factor in (0, 100]")
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
    body = fill(_BODY, help=help_text, data=script_json(data))
    return page(label, body, style=_STYLE, policy=_CSP)


def export_html(
    model: Model, times: Any, qs: Any, path: str | os.PathLike[str], **options: Any
) -> Path:
    """Write :func:`render_html` (``options``: its keywords) to ``path`` atomically; return it.

    Raises:
        ParameterError: Bad destination (and every error of :func:`render_html`).

    """
    return atomic_write(path, render_html(model, times, qs, **options))


def iframe(html: str | os.PathLike[str], *, height: int = 480) -> str:
    """An ``<iframe srcdoc=...>`` embedding an exported page (Jupyter, Colab, Binder).

    Args:
        html: Path of a file written by :func:`export_html`.
        height: Frame height in [px] (100..4000).

    Returns:
        The HTML snippet.

    Raises:
        ParameterError: Bad ``height`` or not a file.

    """
    path = Path(html)
    if not path.is_file():
        raise ParameterError(f"html={str(path)!r} is not a file written by export_html")
    return frame(path.read_text(encoding="utf-8"), height=height)
