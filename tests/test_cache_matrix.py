"""Every cache × every damage (issue 25): recomputed with one warning, or refused; never wrong.

Caches (each filled once per module, then copied per case):

* ``symbolic`` — a derivation of the symbolic cache (``symbolic/cache.py``); the command is
  ``derive``; the entry damaged is the 2-DOF leg's, the other entry the 3-DOF leg's.
* ``families`` — the singular families kept as numbers (``singularity/families.py``); the
  command is ``families_for(derive=True)``; two entries: two row selections of one model.
* ``replay`` — a seed-report replay entry (``report/replay.py``: manifest + files); the command
  is ``reproduce``, its build replaced by a stand-in that writes the report the entry holds
  (a real build takes ~20 s; what is tested is that a damaged entry is never replayed).
* ``figures`` — the figure files of that replay entry (the report's figure cache).
* ``numba`` — numba's compiled-code cache (subprocesses: numba loads once per process); the
  command computes ``fk_batch`` (its kernel loaded first, the cache checked then) and then
  calls the small compiled ``wrap_angle``, whose cache files are the ones damaged (so a
  rebuild is one small compile); only the damages that make numba fail to load
  (``NUMBA_DAMAGES``): nothing reads numba's files. These cases run in the slow step (the
  default run's damaged numba caches are ``test_hostile_round3_cli``'s).

Damages: ``truncate`` (a file cut to a third), ``empty``, ``random`` (random bytes), ``swap``
(two entries' contents exchanged; for a replay entry two files exchanged *together with their
manifest lines*, so each file still matches its line), ``edit`` (one value changed in place,
any checksum left as it was), ``plant`` (code where data is read: a ``srepr`` (symbolic), a
factor text (families), a script as a figure or
listed under a path that leaves the report folder (replay); where a reader parses the data
(symbolic, families, replay, figures) the seal is recomputed, so what refuses is the reader
itself). ``X-resealed``: the
damage with the seal recomputed, for caches that check what an entry claims beyond its seal
(a derivation against the table, a family ``q_k = value`` against the model's rank, a
manifest's verdicts against ``report.md``, a figure against the copy ``report.html`` inlines
under its name).

Each case asserts: the result equals the undamaged one bit for bit, exactly one
:class:`~hexapod_kin.exceptions.CacheWarning`, the planted code did not run (its marker file
does not exist), and the run after it uses the rewritten cache without a warning.
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import random
import shutil
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import hexapod_kin as hk
from hexapod_kin.exceptions import CacheWarning

DAMAGES = ("truncate", "empty", "random", "swap", "edit", "plant")
CACHES = ("symbolic", "families", "replay", "figures", "numba")
#: Damages also made with the seal recomputed, where a check beyond the seal catches them.
RESEALED = (
    ("symbolic", "edit"),
    ("families", "edit"),
    ("replay", "edit"),
    ("figures", "edit"),
    ("figures", "swap"),
)
#: numba's cache is used as numba documents it and nothing reads its files (issue 30): a file
#: that fails to load is handled; a swapped, edited or planted one is numba's trusted input
#: (the user's own cache folder), out of this matrix.
NUMBA_DAMAGES = ("truncate", "empty", "random")
CASES = [(c, d) for c in CACHES for d in DAMAGES if c != "numba" or d in NUMBA_DAMAGES]
CASES += [(c, f"{d}-resealed") for c, d in RESEALED]
#: An edit resealed by someone without the per-user secret (the keyed seal catches it).
CASES += [(c, "forged") for c in ("symbolic", "families")]


def _cut(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: max(1, path.stat().st_size // 3)])


def _noise(path: Path) -> None:
    path.write_bytes(random.Random(7).randbytes(400))


def _swap(a: Path, b: Path) -> None:
    da, db = a.read_bytes(), b.read_bytes()
    a.write_bytes(db)
    b.write_bytes(da)


def _raw(path: Path, how: str) -> bool:
    """The damages that need no knowledge of the format; False for the others."""
    if how == "truncate":
        _cut(path)
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "random":
        _noise(path)
    else:
        return False
    return True


def _planted(marker: Path) -> str:
    return f"__import__('pathlib').Path({str(marker)!r}).touch()"


def _reseal(kind: str, data: dict[str, Any], how: str) -> None:
    """The seal after a damage ``how``: left as it was (``edit``), recomputed with the user's
    secret (a knowing edit: the content checks must catch it), or ``forged`` by someone
    without the secret (the same scheme with a guessed key: the keyed seal catches it)."""
    import hmac

    from hexapod_kin import _cache

    if how == "edit":
        return
    if how != "forged":
        data["seal"] = _cache.seal(kind, data["key"], data["body"])
        return
    h = hmac.new(b"", digestmod=hashlib.sha256)
    body = json.dumps(data["body"], sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    for chunk in (kind.encode(), data["key"].encode(), body.encode()):
        h.update(len(chunk).to_bytes(8, "big"))
        h.update(chunk)
    data["seal"] = h.hexdigest()


def _caught(call: Callable[[], Any]) -> tuple[Any, list[str]]:
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        out = call()
    return out, [str(w.message) for w in seen if issubclass(w.category, CacheWarning)]


# ---------------------------------------------------------------------------- symbolic
def _fingerprint(d: Any) -> str:
    import sympy as sp

    parts = [d.p, d.J_direct, d.J_indirect, d.det, d.gram, *d.transforms, d.rows, d.agree]
    parts += [(f.name, f.factor, f.verified) for f in d.families]
    return sp.srepr(parts) + repr(d.incomplete)


class Symbolic:
    """The 2-DOF leg's derivation (file ``a``), the 3-DOF leg's beside it (``b``)."""

    def fill(self, root: Path) -> None:
        from hexapod_kin.symbolic import clear_memory, derive

        clear_memory()
        derive(hk.robots.coxa_tibia_leg(), budget=None)
        (self.a,) = [p.name for p in (root / "symbolic").glob("*.json")]
        derive(hk.robots.hexabot_leg(), budget=None)
        (self.b,) = [p.name for p in (root / "symbolic").glob("*.json") if p.name != self.a]

    def run(self, root: Path) -> str:
        from hexapod_kin.symbolic import clear_memory, derive

        clear_memory()
        return _fingerprint(derive(hk.robots.coxa_tibia_leg(), budget=None))

    def damage(self, root: Path, how: str, marker: Path) -> None:
        path = root / "symbolic" / self.a
        if _raw(path, how):
            return
        if how == "swap":
            return _swap(path, root / "symbolic" / self.b)
        data = json.loads(path.read_text())
        stages = data["body"]["__dict__"]
        kin = next(v for k, v in stages if k == "kinematics")["__dict__"]
        p = next(v for k, v in kin if k == "p")
        if how.startswith("edit"):  # the foot's position: q1 becomes q2 in one entry of p
            assert "cos(Symbol('q1'" in p["__matrix__"]
            p["__matrix__"] = p["__matrix__"].replace("cos(Symbol('q1'", "cos(Symbol('q2'", 1)
        elif how == "forged":
            p["__matrix__"] = p["__matrix__"].replace("cos(Symbol('q1'", "cos(Symbol('q2'", 1)
        else:  # plant: code in place of an expression, the seal recomputed
            p["__matrix__"] = _planted(marker)
        _reseal("symbolic", data, how)
        path.write_text(json.dumps(data))


# ---------------------------------------------------------------------------- families
class Families:
    """Families of the 2-DOF leg for rows x, z (file ``a``) and y, z (``b``)."""

    A, B = ("x", "z"), ("y", "z")

    def _call(self, rows: tuple[str, ...]) -> Any:
        from hexapod_kin.singularity.families import families_for
        from hexapod_kin.symbolic import clear_memory

        clear_memory()
        model = hk.load(hk.robots.coxa_tibia_leg())  # a new model: no families in memory
        return families_for(model, rows, derive=True, budget=60.0)

    def fill(self, root: Path) -> None:
        self._call(self.A)
        (self.a,) = [p.name for p in (root / "families").glob("*.json")]
        self._call(self.B)
        (self.b,) = [p.name for p in (root / "families").glob("*.json") if p.name != self.a]

    def run(self, root: Path) -> str:
        fams = self._call(self.A)
        assert fams.families
        return json.dumps([f.to_dict() for f in fams.families])

    def damage(self, root: Path, how: str, marker: Path) -> None:
        path = root / "families" / self.a
        if _raw(path, how):
            return
        if how == "swap":
            return _swap(path, root / "families" / self.b)
        data = json.loads(path.read_text())
        body = data["body"]
        if how.startswith(("edit", "forged")):  # a family moved: q2 = -pi/2 becomes q2 = -1
            assert body["families"][0]["value"] == pytest.approx(-1.5707963267948966)
            body["families"][0]["value"] = -1.0
        else:  # plant: code as a factor text
            body["families"][0]["factor"] = _planted(marker)
        _reseal("families", data, how)
        path.write_text(json.dumps(data))


# ---------------------------------------------------------------------------- replay, figures
def _png(seed: int) -> bytes:
    return b"\x89PNG\r\n\x1a\n" + random.Random(seed).randbytes(300)


class Replay:
    """A report replay entry: ``report.md``, ``report.html``, two figures, a seed text."""

    figures = False

    def _files(self) -> dict[str, bytes]:
        rows = [
            "| c1 | 000 | Eq. 1 | agrees: 1 = 1 |",
            "| c2 | 001 | Eq. 2 | seed is wrong: 2 ≠ 3 |",
        ]
        a, b = _png(1), _png(2)
        html = "".join(
            f'<img alt="{n}" src="data:image/png;base64,{base64.b64encode(d).decode()}">'
            for n, d in (("a", a), ("b", b))
        )
        return {
            "report.md": ("\n".join(rows) + "\n").encode(),
            "report.html": f"<html><body>{html}</body></html>".encode(),
            "figures/a.png": a,
            "figures/b.png": b,
            "seeds/000.txt": b"the seed's own text\n",
        }

    def _report(self, out: Path) -> tuple[Any, list[Path]]:
        from hexapod_kin.report import Report
        from hexapod_kin.report.data import Verdict

        written = []
        for rel, data in self._files().items():
            (out / rel).parent.mkdir(parents=True, exist_ok=True)
            (out / rel).write_bytes(data)
            written.append(out / rel)
        fields = dict(where="", kind="value", claimed="1", computed="1", reason="", method="")
        verdicts = (
            Verdict(claim="c1", seed="000", status="agrees", **fields),
            Verdict(claim="c2", seed="001", status="wrong", **fields),
        )
        facts = {"walk_min_margin_m": 0.0128, "scan_family_counts": {"leg": {"q3 = 0": 12}}}
        rep = Report(out, out / "report.md", out / "report.html", verdicts, facts, 1.5, None, 1.5)
        (out / "verdicts.json").write_text(json.dumps(rep.to_dict(), default=str))
        return rep, written

    def _reproduce(self, out: Path) -> Any:
        from hexapod_kin.report import build, reproduce

        built: list[Path] = []

        def stand_in(folder: Path, **kw: Any) -> Any:
            built.append(folder)
            return self._report(folder)

        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(build, "_build", stand_in)
            rep = reproduce(out, quick=True, animations=False)
        self.built = bool(built)
        return rep

    def fill(self, root: Path) -> None:
        from hexapod_kin.report import replay

        self.n = 0
        self._reproduce(root.parent / "fill-out")
        (self.entry,) = [p.name for p in replay.runs_dir().iterdir()]
        rep = self._reproduce(root.parent / "fill-replayed")
        assert rep.replayed_from is not None and not self.built

    def run(self, root: Path) -> str:
        self.n += 1
        out = root.parent / f"out-{self.n}"
        rep = self._reproduce(out)
        files = {
            p.relative_to(out).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(out.rglob("*"))
            if p.is_file() and p.name != "verdicts.json"
        }
        verdicts = [v.to_dict() for v in rep.verdicts]
        return json.dumps([files, rep.summary(), rep.facts, verdicts], sort_keys=True)

    def damage(self, root: Path, how: str, marker: Path) -> None:
        from hexapod_kin.report import replay

        folder = root / "report" / "runs" / self.entry
        manifest = folder / "manifest.json"
        record = json.loads(manifest.read_text())
        files = folder / "files"
        if self.figures:
            target, other = "figures/a.png", "figures/b.png"
        else:
            target, other = {
                "truncate": ("manifest", ""),
                "empty": ("report.md", ""),
                "random": ("report.html", ""),
            }.get(how, ("report.md", "seeds/000.txt"))
        path = manifest if target == "manifest" else files / target
        if _raw(path, how):
            return
        if how.startswith("swap"):  # two files and their manifest lines: each matches its line
            _swap(path, files / other)
            lines = record["files"]
            lines[target], lines[other] = lines[other], lines[target]
        elif how.startswith("edit") and self.figures:  # one byte of a figure
            data = bytearray(path.read_bytes())
            data[100] ^= 0x01
            path.write_bytes(bytes(data))
            if how == "edit-resealed":
                record["files"][target] = {
                    "sha256": hashlib.sha256(data).hexdigest(),
                    "size": len(data),
                }
        elif how == "edit":  # a fact the report returns, e.g. the walk's margin
            record["facts"]["walk_min_margin_m"] = 0.5
        elif how == "edit-resealed":  # a verdict counted as agreeing
            record["verdicts"][1]["status"] = "agrees"
        elif how == "plant" and self.figures:  # a script in place of a figure
            script = (_planted(marker) + "\n").encode()
            path.write_bytes(script)
            record["files"][target] = {
                "sha256": hashlib.sha256(script).hexdigest(),
                "size": len(script),
            }
        else:  # plant: a script listed with a path that leaves the report folder
            script = (_planted(marker) + "\n").encode()
            (folder / "planted.py").write_bytes(script)
            record["files"]["../../planted.py"] = {
                "sha256": hashlib.sha256(script).hexdigest(),
                "size": len(script),
            }
        if how.endswith("resealed") or how == "plant":
            record["seal"] = replay.seal(record)
        manifest.write_text(json.dumps(record))


class Figures(Replay):
    """The figures of a report replay entry (the report's figure cache)."""

    figures = True


# ---------------------------------------------------------------------------- numba
#: ``fk_batch`` loads its kernel, then ``wrap_angle`` is called as an area of its own: in the
#: package every compile happens inside an area's first call (``run_blocks``).
NUMBA_CODE = r"""
import hashlib, hexapod_kin as hk
from hexapod_kin._kernels import run_blocks
from hexapod_kin._kmath import wrap_angle
leg = hk.load("hexabot_leg")
poses = leg.fk_batch(leg.random_q(300, seed=3))
wrapped = run_blocks("wrap", lambda a, b: wrap_angle(7.0), 1, 1, 1)[-1]
print(hashlib.sha256(poses.tobytes()).hexdigest(), repr(wrapped))
"""


class Numba:
    """numba's cache: the kernel of ``fk_batch`` and the small ``wrap_angle``, ``sincos``."""

    def _env(self, root: Path) -> dict[str, str]:
        env = dict(os.environ, NUMBA_CACHE_DIR=str(root / "numba"))
        env["HEXAPOD_KIN_CACHE_DIR"] = str(root / "hk")
        return env

    def _proc(self, root: Path) -> tuple[str, str]:
        res = subprocess.run(
            [sys.executable, "-c", NUMBA_CODE],
            env=self._env(root),
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert res.returncode == 0, res.stderr[-2000:]
        return res.stdout.strip(), res.stderr

    def fill(self, root: Path) -> None:
        out, err = self._proc(root)  # compiles
        assert "compiling batch kernels" in err and "Warning" not in err, err

    def run(self, root: Path) -> tuple[str, list[str]]:
        out, err = self._proc(root)
        return out, [ln for ln in err.splitlines() if "CacheWarning:" in ln]

    def file(self, root: Path, name: str, suffix: str) -> Path:
        (path,) = (root / "numba").glob(f"*/_kmath.{name}-*{suffix}")
        return path

    def damage(self, root: Path, how: str, marker: Path) -> None:
        nbc, nbi = self.file(root, "wrap_angle", ".1.nbc"), self.file(root, "wrap_angle", ".nbi")
        if how == "empty":
            nbi.write_bytes(b"")
        elif _raw(nbc, how):
            return


HARNESS: dict[str, Any] = {
    "symbolic": Symbolic,
    "families": Families,
    "replay": Replay,
    "figures": Figures,
    "numba": Numba,
}


# ---------------------------------------------------------------------------- the matrix
@pytest.fixture(scope="module")
def filled(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Per cache: the harness, its pristine filled cache folder and the undamaged result."""
    return {}


def _prepare(filled: dict[str, Any], name: str, tmp: Path) -> tuple[Any, Path, Any]:
    if name not in filled:
        h = HARNESS[name]()
        pristine = tmp / f"pristine-{name}" / "cache"
        pristine.mkdir(parents=True)
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("HEXAPOD_KIN_CACHE_DIR", str(pristine))
            if name == "numba":
                h.fill(pristine)
                base, said = h.run(pristine)  # loaded, quietly
            else:
                h.fill(pristine)
                base, said = _caught(lambda: h.run(pristine))
        assert not said, said
        filled[name] = (h, pristine, base)
    return filled[name]


#: numba's cases (a child compiles the kernels into a fresh folder, then a child per case
#: compiles one again) run in the slow step: the keyed seal that catches them is the default
#: run's in ``test_hostile_round3_cli`` (a flipped byte, an emptied index, a foreign file, a
#: missing seal).
NUMBA_SLOW = {("numba", d) for d in NUMBA_DAMAGES}


@pytest.mark.parametrize(
    ("cache", "damage"),
    [
        pytest.param(c, d, id=f"{c}-{d}", marks=[pytest.mark.slow] if (c, d) in NUMBA_SLOW else [])
        for c, d in CASES
    ],
)
@pytest.mark.slow
def test_damaged_cache(
    filled: dict[str, Any],
    tmp_path_factory: pytest.TempPathFactory,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    cache: str,
    damage: str,
) -> None:
    h, pristine, base = _prepare(filled, cache, tmp_path_factory.getbasetemp())
    root = tmp_path / "cache"
    shutil.copytree(pristine, root)
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(root))
    marker = tmp_path / "planted-code-ran"
    h.damage(root, damage.replace("-resealed", "") if cache == "numba" else damage, marker)
    if cache == "numba":
        again, said = h.run(root)
        # the run after: quiet (one case per kind of repair: each run is a process)
        third, quiet = h.run(root) if damage in ("swap", "plant") else (base, [])
    else:
        again, said = _caught(lambda: h.run(root))
        third, quiet = _caught(lambda: h.run(root))
    assert again == base  # bit for bit the undamaged result
    assert len(said) == 1, said  # one warning line
    assert not marker.exists()  # the planted code never ran
    assert third == base and not quiet, quiet  # the rewritten cache is used quietly
    if cache in ("replay", "figures"):
        assert not (tmp_path / "planted.py").exists() and not (root / "planted.py").exists()


@pytest.mark.slow  # a child compiles the kernels into fresh caches
def test_numba_cache_is_rebuilt_when_loading_fails(
    filled: dict[str, Any], tmp_path_factory: pytest.TempPathFactory, tmp_path: Path
) -> None:
    """The kernel's data file swapped with ``sincos``'s: the folder's keyed seal no longer
    matches (issue 35), so the swapped files are removed before numba may load them (had they
    been loaded, numba would run ``sincos``'s code as the kernel; that failure is caught too:
    "could not be loaded"). One warning, the kernel compiled again: the same bits, and the
    next run is quiet."""
    h, pristine, base = _prepare(filled, "numba", tmp_path_factory.getbasetemp())
    root = tmp_path / "cache"
    shutil.copytree(pristine, root)
    (kernel,) = (root / "numba").glob("*/_kernels.pose_jacobian_kernel-*.1.nbc")
    _swap(kernel, h.file(root, "sincos", ".1.nbc"))
    again, said = h.run(root)
    assert again == base
    assert len(said) == 1, said
    assert "edited or swapped" in said[0] and "compiled afresh" in said[0], said
    third, quiet = h.run(root)
    assert third == base and not quiet, quiet


# ---------------------------------------------------------------------------- faults
def _small_files() -> None:  # pragma: no cover - in the child, before exec
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


@pytest.mark.slow  # a child compiles the kernels into fresh caches
def test_numba_cache_that_cannot_be_written_compiles_in_memory(
    filled: dict[str, Any], tmp_path_factory: pytest.TempPathFactory, tmp_path: Path
) -> None:
    """numba's cache folder as on a full disk (no file can grow past 4 kB): the kernels are
    compiled in memory with one warning, the same bits, and no temporary file is left."""
    h, _, base = _prepare(filled, "numba", tmp_path_factory.getbasetemp())
    res = subprocess.run(
        [sys.executable, "-c", NUMBA_CODE],
        env=h._env(tmp_path),
        capture_output=True, text=True, timeout=600, preexec_fn=_small_files,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    said = [ln for ln in res.stderr.splitlines() if "CacheWarning:" in ln]
    assert len(said) == 1 and "cannot be written" in said[0], res.stderr[-3000:]
    assert res.stdout.strip() == base
    assert not [p for p in tmp_path.rglob("*") if ".tmp" in p.name]


@pytest.mark.slow
def test_package_cache_on_a_full_disk_leaves_no_temporary_file(tmp_path: Path) -> None:
    """``HEXAPOD_KIN_CACHE_DIR`` where no file can grow past 4 kB: ``derive`` answers as with
    a working cache, and no temporary file is left (issue 35)."""
    env = dict(os.environ, HEXAPOD_KIN_CACHE_DIR=str(tmp_path / "full"))
    argv = [sys.executable, "-m", "hexapod_kin", "derive", "hexabot_leg"]
    full = subprocess.run(
        argv, env=env, capture_output=True, text=True, timeout=600, preexec_fn=_small_files
    )
    env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp_path / "working")
    working = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=600)
    assert full.returncode == working.returncode == 0, full.stderr[-2000:]
    assert full.stdout == working.stdout and "Traceback" not in full.stderr
    assert not [p for p in (tmp_path / "full").rglob("*") if ".tmp" in p.name]
    assert list((tmp_path / "working" / "symbolic").glob("*.json"))  # it does cache there


def test_cache_folder_that_is_a_regular_file_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``HEXAPOD_KIN_CACHE_DIR`` naming a regular file: one warning that says so (not a
    "damaged entry"), nothing cached, the answer unchanged."""
    from hexapod_kin import _cache
    from hexapod_kin.symbolic import clear_memory, derive

    plain = tmp_path / "a-file"
    plain.write_text("not a folder")
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(plain))
    monkeypatch.setattr(_cache, "_SECRETS", {})
    clear_memory()
    d, said = _caught(lambda: derive(hk.robots.coxa_tibia_leg(), budget=None))
    assert len(said) == 1 and "is not a folder" in said[0], said
    assert plain.read_text() == "not a folder" and d.complete
    clear_memory()
