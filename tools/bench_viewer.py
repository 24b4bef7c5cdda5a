"""Viewer benchmark: building an animation, ours vs meshcat-python's own Animation API.

Same model, same trajectory, same placements (computed once, outside the timings):

* ours: :func:`hexapod_kin.viewer.scene_commands` tracks as float32 typed arrays
  (``times``/``values``), msgpack'ed;
* peer: ``meshcat.animation.Animation`` filled with ``at_frame(...)[path].set_transform(T)``
  (one dict per key frame), lowered and msgpack'ed — what ``Visualizer.set_animation`` sends.

Reported: build time (best of ``repeat``) and bytes of the ``set_animation`` message; plus
the full ``export_html`` time and file size for context.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any


def _best(fn: Any, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _case(name: str, samples: int, repeat: int) -> list[dict[str, Any]]:
    import umsgpack
    from meshcat.animation import Animation
    from meshcat.path import Path as MPath

    from hexapod_kin import gait, load, viewer
    from hexapod_kin.viewer.objects import bundle
    from hexapod_kin.viewer.scene import Scene
    from hexapod_kin.viewer.trajectory import clip

    model = load(name)
    times, qs, base = gait.demo_trajectory(model, 4.0, samples)
    scene = Scene(model)
    poses = scene.placements(qs, base)
    paths = [v.path for v in scene.visuals]
    fps = (len(times) - 1) / (times[-1] - times[0])

    def ours() -> bytes:
        clips = [clip(p, times, poses[:, j]) for j, p in enumerate(paths)]
        msg = {
            "type": "set_animation",
            "path": "",
            "animations": clips,
            "options": {"play": True, "repetitions": 1},
        }
        return bytes(umsgpack.packb(msg))

    def peer() -> bytes:
        anim = Animation(default_framerate=fps)
        root = type("Root", (), {"path": MPath()})()
        for i in range(len(times)):
            frame = anim.at_frame(root, i)
            for j, p in enumerate(paths):
                frame[p.lstrip("/")].set_transform(poses[i, j])
        msg = {
            "type": "set_animation",
            "path": "",
            "animations": anim.lower(),
            "options": {"play": True, "repetitions": 1},
        }
        return bytes(umsgpack.packb(msg))

    t_ours, t_peer = _best(ours, repeat), _best(peer, repeat)
    b_ours, b_peer = len(ours()), len(peer())
    rows: list[dict[str, Any]] = [
        {
            "case": f"{name} {len(paths)} geoms x {len(times)} samples "
            f"({len(times) * len(paths)} keys)",
            "ours_ms": round(1e3 * t_ours, 2),
            "meshcat_ms": round(1e3 * t_peer, 2),
            "time_ratio": round(t_peer / t_ours, 2),
            "ours_bytes": b_ours,
            "meshcat_bytes": b_peer,
            "size_ratio": round(b_peer / b_ours, 2),
        }
    ]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.html"

        def export() -> None:
            viewer.export_html(model, times, qs, out, base_poses=base)

        t_html = _best(export, max(1, repeat // 2))
        rows.append(
            {
                "case": f"{name} export_html ({len(times)} samples)",
                "ms": round(1e3 * t_html, 1),
                "html_bytes": out.stat().st_size,
                "bundle_bytes": len(bundle()),
            }
        )
    return rows


def _mesh_page(name: str) -> dict[str, Any]:
    """Size of a mesh robot's page against its peer: the bundle plus the mesh files it used
    to embed as they are (meshcat's ``_meshfile_geometry``, before the compact geometry)."""
    from hexapod_kin import load, viewer
    from hexapod_kin.viewer.objects import bundle

    model = load(name)
    files = sum(
        Path(go.meshPath).stat().st_size for go in model.geometry_model("visual").geometryObjects
    )
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.html"
        t0 = time.perf_counter()
        viewer.export_html(model, [0.0], model.neutral()[None, :], out)
        ms = 1e3 * (time.perf_counter() - t0)
        size = out.stat().st_size
    peer = len(bundle().encode("utf-8")) + files
    return {
        "case": f"{name} page (still pose)",
        "ms": round(ms, 1),
        "html_bytes": size,
        "bundle_plus_mesh_files_bytes": peer,
        "size_ratio": round(peer / size, 2),
    }


def run(quick: bool) -> list[dict[str, Any]]:
    repeat = 1 if quick else 5
    rows: list[dict[str, Any]] = []
    for name, samples in (("hexabot_leg", 121), ("hexapod", 121 if quick else 481)):
        rows += _case(name, samples, repeat)
    rows.append(_mesh_page("erd:panda"))
    return rows


if __name__ == "__main__":
    for row in run(quick=False):
        print("  ".join(f"{k}={v}" for k, v in row.items()))
