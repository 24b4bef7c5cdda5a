"""A damaged compiled-code cache is rebuilt, never fatal, and gives the same bits.

numba's disk cache (``NUMBA_CACHE_DIR``) is filled by a first process; then its files are
truncated, emptied, overwritten with random bytes or swapped, and the next process must print
one warning line, compute the same bytes as the first, and leave a cache that the process after
it loads quietly.
"""

from __future__ import annotations

import hashlib
import os
import random
import subprocess
import sys
from pathlib import Path

CODE = r"""
import hashlib, hexapod_kin as hk
leg = hk.load("hexabot_leg")
poses = leg.fk_batch(leg.random_q(1000, seed=3))
print(hashlib.sha256(poses.tobytes()).hexdigest())
"""


def _run(cache: Path) -> tuple[str, str]:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache / "numba"))
    env["HEXAPOD_KIN_CACHE_DIR"] = str(cache / "hk")
    res = subprocess.run(
        [sys.executable, "-c", CODE], env=env, capture_output=True, text=True, timeout=600
    )
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stdout.strip(), res.stderr


def _damage(files: list[Path], how: str) -> None:
    rng = random.Random(7)
    if how == "swap":
        data = [f.read_bytes() for f in files]
        for f, d in zip(files, data[1:] + data[:1]):
            f.write_bytes(d)
        return
    for f in files:
        if how == "truncate":
            f.write_bytes(f.read_bytes()[: max(1, f.stat().st_size // 3)])
        elif how == "empty":
            f.write_bytes(b"")
        elif how == "random":
            f.write_bytes(bytes(rng.randrange(256) for _ in range(400)))


def test_damaged_numba_cache_is_rebuilt(tmp_path: Path) -> None:
    """One cache, emptied then overwritten with random bytes (each rebuild checked in turn).

    (Truncated and swapped files fail the same two ways, EOFError or UnpicklingError: they
    were checked by hand; each rebuild costs a compile, so the suite runs these two.)
    """
    digest, err = _run(tmp_path)
    assert "compiling batch kernels" in err
    for how in ("empty", "random"):
        files = sorted(p for p in (tmp_path / "numba").rglob("*") if p.suffix in (".nbi", ".nbc"))
        assert files, "numba wrote no cache files"
        _damage(files, how)
        before = {f: hashlib.sha256(f.read_bytes()).hexdigest() for f in files}
        again, err = _run(tmp_path)
        assert again == digest, how  # the same bytes as the undamaged run
        warnings = [ln for ln in err.splitlines() if "could not be loaded" in ln]
        assert len(warnings) <= 1, err
        if how != "swap" or warnings:  # a swap of two same-shaped entries may still load
            assert len(warnings) == 1, (how, err)
            assert any(
                hashlib.sha256(f.read_bytes()).hexdigest() != before[f] for f in files if f.exists()
            )  # the cache was rewritten
        third, err = _run(tmp_path)
        assert third == digest and "could not be loaded" not in err and "compiling" not in err
