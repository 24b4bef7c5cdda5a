"""The restricted ``srepr`` reader of the symbolic cache: round trips, and nothing runs."""

from __future__ import annotations

from pathlib import Path

import pytest
import sympy as sp

from hexapod_kin.symbolic._reader import CacheFormatError, read_srepr

q1, q2 = sp.symbols("q1 q2", real=True)
d3 = sp.Symbol("d3", positive=True)

EXPRESSIONS = [
    -d3 * sp.sin(q1) ** 2 * sp.cos(q2) + sp.Rational(1, 3) * sp.sqrt(2) * q2,
    sp.Float(0.25) * sp.pi + sp.atan2(q1, q2) - sp.Float("-1.5e-300"),
    sp.ImmutableMatrix([[q1, 0], [sp.E, -1]]),
    sp.Poly(q1**2 + q2, q1),
    sp.Eq(q1, 2),
    sp.Piecewise((q1, q1 > 0), (q2, True)),
    sp.Abs(q1) + sp.Max(q1, q2) + sp.exp(-q2),
    sp.oo,
    sp.true,
]


@pytest.mark.parametrize("expr", EXPRESSIONS, ids=range(len(EXPRESSIONS)))
def test_round_trip(expr: sp.Basic) -> None:
    back = read_srepr(sp.srepr(expr))
    assert back == expr and sp.srepr(back) == sp.srepr(expr)


PLANTED = [
    "__import__('os').system('touch /tmp/hk_planted')",
    "Symbol('x').__class__.__mro__",
    "Add(lambda: 1)",
    "[x for x in ()]",
    "open('/etc/passwd')",
    "Symbol('x', evaluate=True)",
    "Integer(1) + Integer(2)",
    "Float('1', precision=__import__('os'))",
    "Symbol(Symbol('x'))",
    "Pow(Integer(10), Integer(100000000))",
    "exec('1')",
    "Integer(" + "9" * 5000 + ")",
    "Add(" * 100_000 + ")" * 100_000,
]


@pytest.mark.parametrize("text", PLANTED, ids=range(len(PLANTED)))
def test_planted_text_is_refused(text: str) -> None:
    with pytest.raises(CacheFormatError):
        read_srepr(text)


def test_planted_code_never_runs(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    with pytest.raises(CacheFormatError):
        read_srepr(f"__import__('pathlib').Path({str(marker)!r}).touch()")
    assert not marker.exists()


@pytest.mark.slow
def test_planted_cache_entry_is_discarded_not_run(tmp_path: Path, monkeypatch) -> None:
    """Code planted in a stored expression of the symbolic cache never runs: the next
    ``derive`` (a new process) discards the entry with one warning line and recomputes."""
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, HEXAPOD_KIN_CACHE_DIR=str(tmp_path / "hk"))
    argv = [sys.executable, "-m", "hexapod_kin", "derive", "hexabot_leg", "--budget", "60"]
    first = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    files = list((tmp_path / "hk" / "symbolic").glob("*.json"))
    assert files
    marker = tmp_path / "ran"
    planted = f"__import__('pathlib').Path({str(marker)!r}).touch()"
    from hexapod_kin import _cache

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "hk"))  # the user's own secret
    for f in files:  # the seal recomputed: what refuses the code is the reader itself
        text = json.dumps(json.loads(f.read_text()))
        head = '"__sympy__": "'
        data = json.loads(text.replace(head, head + planted.replace('"', '\\"') + "#", 1))
        data["seal"] = _cache.seal("symbolic", data["key"], data["body"])
        f.write_text(json.dumps(data))
    again = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert not marker.exists()
    warned = [ln for ln in again.stderr.splitlines() if "damaged or was edited" in ln]
    assert len(warned) == 1 and warned[0].startswith("hexapod-kin: warning:"), again.stderr
    det = [ln for ln in first.stdout.splitlines() if "det" in ln.lower()]
    assert det and det == [ln for ln in again.stdout.splitlines() if "det" in ln.lower()]


def _entry(pairs: list, name: str) -> dict:
    return next(v for k, v in pairs if k == name)


@pytest.mark.slow
@pytest.mark.parametrize("what", ["p", "det", "family"])
def test_edited_cache_values_are_recomputed(tmp_path: Path, monkeypatch, what: str) -> None:
    """An edited value in the symbolic cache (a plausible expression, no code, the seal
    recomputed) is checked against the table before use: discarded with one CacheWarning
    and recomputed."""
    import json

    import hexapod_kin as hk
    from hexapod_kin.exceptions import CacheWarning
    from hexapod_kin.symbolic import cache, clear_memory, derive

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "hk"))
    clear_memory()
    first = derive(hk.robots.hexabot_leg(), budget=None)
    (path,) = list(cache.cache_dir().glob("*.json"))
    data = json.loads(path.read_text())
    stages = data["body"]["__dict__"]
    if what == "p":  # the foot's position: q1 becomes q2 in p only
        entry = _entry(_entry(stages, "kinematics")["__dict__"], "p")
        key, old, new = "__matrix__", "cos(Symbol('q1'", "cos(Symbol('q2'"
    elif what == "det":  # det(J Jt) with sin(q3) turned into cos(q3)
        entry = _entry(_entry(stages, "determinant")["__dict__"], "gram")
        key, old, new = "__sympy__", "sin(Symbol('q3'", "cos(Symbol('q3'"
    else:  # a family's factor that is no factor of det J
        entry = _entry(stages, "families")["__tuple__"][-1]["__family__"]["factor"]
        key, old, new = "__sympy__", "Symbol('q3'", "Symbol('q1'"
    assert old in entry[key]
    entry[key] = entry[key].replace(old, new)
    from hexapod_kin import _cache

    data["seal"] = _cache.seal("symbolic", data["key"], data["body"])
    path.write_text(json.dumps(data))
    clear_memory()
    from hexapod_kin.symbolic import cached

    with pytest.warns(CacheWarning, match="do not match the table"):
        assert cached(hk.robots.hexabot_leg()) is None  # the read-only look checks it too
    with pytest.warns(CacheWarning, match="do not match the table"):
        again = derive(hk.robots.hexabot_leg(), budget=None)
    assert sp.simplify(again.det - first.det) == 0
    assert [f.name for f in again.families] == [f.name for f in first.families]
    clear_memory()


@pytest.mark.parametrize("name", ["hexabot_leg", "scara", "coxa_tibia_leg"])
def test_cached_derivation_is_the_computed_one(tmp_path: Path, monkeypatch, name: str) -> None:
    """Read back from the cache, a derivation is the one computed, expression for expression
    (the reader does not distribute ``-1`` over the sums the tidied forms keep factored), and
    its own entry passes the check against the table (no warning: e.g. the 2-DOF leg, whose
    Jacobian has more rows than joints)."""
    import warnings

    import hexapod_kin as hk
    from hexapod_kin.symbolic import clear_memory, derive

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "hk"))
    chain = getattr(hk.robots, name)()
    clear_memory()
    fresh = derive(chain, budget=None)
    clear_memory()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = derive(chain, budget=None)
    clear_memory()
    assert back.cached and not fresh.cached
    for field in ("p", "J_direct", "J_indirect", "det", "gram", "transforms", "cumulative"):
        assert sp.srepr(getattr(back, field)) == sp.srepr(getattr(fresh, field)), field
    assert [sp.srepr(f.factor) for f in back.families] == [
        sp.srepr(f.factor) for f in fresh.families
    ]
    assert back.text() == fresh.text()
