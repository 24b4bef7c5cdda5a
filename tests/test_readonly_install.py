"""A read-only install used by another user: the batch APIs and ``scan --grid 91`` work.

The package is copied into a folder nobody but root can write (as a system-wide install
is), and run from there as the unprivileged user ``nobody`` (``setpriv``) with a fresh home
folder: neither the package folder nor ``site-packages`` is writable. numba's cache is used
as numba documents it: ``__pycache__`` beside the sources is not writable, so numba keeps the
machine code in the user's own cache folder (``~/.cache/numba``). Nothing is written into the
install. Once with nothing compiled, once after root ran ``precompile`` there (its cache in
the install's ``__pycache__``, which ``nobody`` reads but cannot write).

Needs root (to switch user) and an interpreter ``nobody`` can run; skipped otherwise.
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

import hexapod_kin

pytestmark = pytest.mark.slow

NOBODY = 65534
SETPRIV = shutil.which("setpriv")

#: The batch calls of the issue, each printing a digest of its result.
PROBE = r"""
import hashlib, sys
import numpy as np
import hexapod_kin as hk
from hexapod_kin.ik import solve_many
from hexapod_kin.singularity import measures_batch

assert hk.__file__.startswith(sys.argv[1]), hk.__file__
leg = hk.load("hexabot_leg")
qs = leg.random_q(2000, seed=0)
poses = leg.fk_batch(qs)
ms = measures_batch(leg, qs)
targets = np.array([leg.fk(q)[:3, 3] for q in leg.random_q(8, seed=1)])
sols = solve_many(leg, targets)
h = hashlib.sha256(poses.tobytes())
h.update(np.ascontiguousarray(ms.sigma_min).tobytes())
h.update(repr([(s.converged, np.asarray(s.q).tobytes()) for s in sols]).encode())
print(h.hexdigest())
"""


def _interpreter() -> str | None:
    """The system's interpreter of this version (a venv's may process ``.pth`` files that
    ``nobody`` cannot read), else this one, if ``nobody`` may run it cleanly."""
    for exe in (f"/usr/bin/python{sys.version_info[0]}.{sys.version_info[1]}", sys.executable):
        probe = subprocess.run(
            [SETPRIV or "setpriv", f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups",
             exe, "-c", "import sys; print(sys.version_info[:2])"],
            capture_output=True, text=True, check=False, cwd="/",
        )  # fmt: skip
        same = probe.stdout.strip() == str(tuple(sys.version_info[:2]))
        if probe.returncode == 0 and same and not probe.stderr:  # e.g. a .pth it cannot read
            return exe
    return None


@pytest.fixture(scope="module")
def install() -> Iterator[dict[str, object]]:
    """The read-only copy of the package, and how to run as ``nobody`` beside it."""
    if os.geteuid() != 0 or SETPRIV is None:
        pytest.skip("needs root and setpriv to run as another user")
    exe = _interpreter()
    if exe is None:
        pytest.skip("no interpreter the user nobody may run")
    base = Path(tempfile.mkdtemp(prefix="hexapod-kin-ro-"))  # pytest's folders are root's only
    os.chmod(base, 0o755)
    site = base / "site"
    src = Path(hexapod_kin.__file__).parent
    shutil.copytree(src, site / "hexapod_kin", ignore=shutil.ignore_patterns("__pycache__"))
    for p in [site, *site.rglob("*")]:  # readable by all, writable by nobody
        mode = 0o555 if p.is_dir() else 0o444
        os.chmod(p, mode)
    # the libraries this interpreter sees (site-packages and what its .pth files add): not the
    # checkout itself, and all of them unwritable by nobody (root's)
    paths = [
        p for p in sys.path
        if p and os.path.isdir(p) and not os.path.isdir(os.path.join(p, "hexapod_kin"))
        and not p.endswith(".zip")
    ]  # fmt: skip
    for p in paths:
        assert not os.stat(p).st_mode & stat.S_IWOTH, p
    yield {"base": base, "site": site, "exe": exe, "pythonpath": [str(site), *paths]}
    for p in [site, *site.rglob("*")]:
        os.chmod(p, 0o755 if p.is_dir() else 0o644)
    shutil.rmtree(base, ignore_errors=True)


def _run(install: dict[str, object], home: Path, args: list[str], user: bool) -> str:
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": str(home),
        "PYTHONPATH": os.pathsep.join(install["pythonpath"]),  # type: ignore[arg-type]
        "LANG": "C.UTF-8",
    }
    prefix = [SETPRIV, f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups"] if user else []
    res = subprocess.run(
        [*prefix, str(install["exe"]), *args],  # type: ignore[list-item]
        env=env, cwd=home, capture_output=True, text=True, timeout=1800, check=False,
    )  # fmt: skip
    assert res.returncode == 0, (args, res.stderr[-3000:])
    assert "Traceback" not in res.stderr and "Permission denied" not in res.stderr, res.stderr
    return res.stdout


def _fresh_home(install: dict[str, object], name: str) -> Path:
    home = Path(str(install["base"])) / name
    home.mkdir()
    os.chown(home, NOBODY, NOBODY)
    return home


def _writable_by_nobody_in(site: Path) -> list[Path]:
    return [p for p in [site, *site.rglob("*")] if p.stat().st_uid == NOBODY]


@pytest.mark.parametrize("precompiled", [False, True], ids=["fresh", "after-root-precompile"])
def test_readonly_install_as_another_user(install: dict[str, object], precompiled: bool) -> None:
    site = Path(str(install["site"]))
    if precompiled:  # root fills the install's own cache, as a package manager would
        root_home = Path(str(install["base"])) / "root-home"
        root_home.mkdir(exist_ok=True)
        _run(install, root_home, ["-m", "hexapod_kin", "precompile"], user=False)
    home = _fresh_home(install, f"home-{precompiled}")
    digest = _run(install, home, ["-c", PROBE, str(site)], user=True).strip()
    scan = _run(install, home, ["-m", "hexapod_kin", "scan", "hexabot_leg", "--grid", "91"], True)
    assert "singular" in scan.lower()
    # the same answers as this (writable) checkout gives, bit for bit
    here = subprocess.run(
        [sys.executable, "-c", PROBE, str(Path(hexapod_kin.__file__).parent)],
        cwd=home, capture_output=True, text=True, timeout=1800, check=True,
    ).stdout.strip()  # fmt: skip
    assert digest == here
    # numba kept its machine code in nobody's own cache folder; nothing written in the install
    assert list((home / ".cache" / "numba").rglob("*.nbi")), "numba cached nothing"
    assert not _writable_by_nobody_in(site)


def test_no_writable_cache_folder_at_all_compiles_in_memory(install: dict[str, object]) -> None:
    """A home folder ``nobody`` cannot write either: numba has no folder to cache in (its
    ``cache=True`` would fail at import); the kernels compile in memory with one warning."""
    home = Path(str(install["base"])) / "home-unwritable"
    home.mkdir()  # root's, mode 0755: not writable by nobody
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": str(home),
        "PYTHONPATH": os.pathsep.join(install["pythonpath"]),  # type: ignore[arg-type]
    }
    code = (
        "import hexapod_kin as hk; leg = hk.load('hexabot_leg'); "
        "print(leg.fk_batch(leg.random_q(100, seed=0)).sum())"
    )
    res = subprocess.run(
        [SETPRIV, f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups",
         str(install["exe"]), "-c", code],
        env=env, cwd="/", capture_output=True, text=True, timeout=1800, check=False,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    said = [ln for ln in res.stderr.splitlines() if "CacheWarning" in ln]
    assert len(said) == 1 and "compiled in memory" in said[0], res.stderr
    assert not list(home.rglob("*"))
