"""Leg design sweeps: scores against closed forms and Pinocchio, Dask, resume, CLI."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, optimize

import hexapod_kin as hk
from hexapod_kin.exceptions import ConfigurationError, ParameterError
from hexapod_kin.ik import analytic_batch
from hexapod_kin.params import JointLimits
from hexapod_kin.sweep import (
    PARAMETERS,
    DesignSpace,
    Range,
    design_chain,
    pareto_front,
    reachable,
    read_results,
    score_designs,
    sweep,
    volume_closed_form,
)
from hexapod_kin.sweep.designs import DEFAULTS
from hexapod_kin.sweep.scores import sigmas

PI = math.pi


def row(**kw: float) -> np.ndarray:
    d = {**DEFAULTS, **kw}
    return np.array([d[p] for p in PARAMETERS])


# ---------------------------------------------------------------- closed-form volume
def seed_leg_volume(c: float, r: float) -> float:
    """Hand derivation: a disk of radius r centred at distance c < r from the axis, revolved.

    At height z the disk's chord is [c − s, c + s], s = √(r² − z²); revolved it is the full
    disk of radius c + s while c − s < 0, else the annulus (c − s, c + s). So
    V = ∫ π (c + s)² dz − ∫_{|z| > z0} π (c − s)² dz, z0 = √(r² − c²).
    """

    def s_int(z: float) -> float:  # ∫ √(r² − z²) dz
        return 0.5 * (z * math.sqrt(max(r * r - z * z, 0)) + r * r * math.asin(z / r))

    full = math.pi * (2 * r * c * c + 2 * c * (s_int(r) - s_int(-r)) + 4 * r**3 / 3)
    z0 = math.sqrt(r * r - c * c)

    def f(z: float) -> float:  # ∫ (c − s)² dz
        return c * c * z - 2 * c * s_int(z) + r * r * z - z**3 / 3

    return full - 2 * math.pi * (f(r) - f(z0))


def test_seed_leg_volume_is_0_05637():
    v = volume_closed_form(0.05, 0.10, 0.10)
    assert v == pytest.approx(seed_leg_volume(0.05, 0.20), rel=1e-12)
    assert abs(v - 0.05637) < 1e-5  # the figure of the issue (voxels gave 0.0574, +1.9 %)


def _quadrature_volume(l1, l2, l3, lo1, hi1, lo3, hi3):
    """Independent: per height, split ρ at every candidate endpoint and test membership."""
    c = [math.cos(lo3), math.cos(hi3)]
    qs = np.linspace(lo3, hi3, 200001)
    cmax, cmin = max(np.cos(qs).max(), *c), min(np.cos(qs).min(), *c)
    ro = math.sqrt(l2 * l2 + l3 * l3 + 2 * l2 * l3 * cmax)
    ri = math.sqrt(max(l2 * l2 + l3 * l3 + 2 * l2 * l3 * cmin, 0))
    delta = min(hi1 - lo1, 2 * PI)

    def ins(x, z):
        return ri * ri <= (x - l1) ** 2 + z * z <= ro * ro

    def section(z):
        so = math.sqrt(max(ro * ro - z * z, 0))
        si = math.sqrt(max(ri * ri - z * z, 0))
        cuts = sorted({0.0, *(abs(l1 + a * e) for a in (-1, 1) for e in (so, si))})
        tot = 0.0
        for a, b in zip(cuts[:-1], cuts[1:]):
            m = 0.5 * (a + b)
            p, n = ins(m, z), ins(-m, z)
            w = delta * (p + n) - 2 * max(delta - PI, 0) * (p and n)
            tot += 0.5 * w * (b * b - a * a)
        return tot

    return integrate.quad(section, -ro, ro, limit=400, epsabs=1e-13, epsrel=1e-11)[0]


@pytest.mark.parametrize(
    "args",
    [
        (0.05, 0.10, 0.10, -PI, PI, -PI, PI),
        (0.03, 0.12, 0.08, -PI, PI, -PI, PI),  # a hole: |l2 − l3| > 0
        (0.10, 0.10, 0.05, -PI, PI, -PI, PI),  # l1 beyond the inner radius
        (0.05, 0.10, 0.10, -1.0, 1.0, -PI, PI),  # hip range < π
        (0.03, 0.12, 0.08, -2.5, 2.5, 0.3, 2.0),  # hip range > π, ankle range in (0, π)
    ],
)
def test_closed_form_volume_against_quadrature(args):
    l1, l2, l3, lo1, hi1, lo3, hi3 = args
    exact = volume_closed_form(l1, l2, l3, lo1, hi1, -PI, PI, lo3, hi3)
    assert exact == pytest.approx(_quadrature_volume(*args), rel=2e-7)


def test_monte_carlo_within_error_bars_of_closed_form():
    rows = np.array(
        [
            row(),
            row(l1=0.03, l2=0.12, l3=0.08),
            row(q1_lower=-1.0, q1_upper=1.0),
            row(l1=0.03, l2=0.12, l3=0.08, q1_lower=-2.5, q1_upper=2.5, q3_lower=0.3, q3_upper=2.0),
        ]
    )
    s = score_designs(rows, mc_samples=200_000, seed=3)
    assert np.all(s["volume_exact"] == 1) and np.all(s["volume_se"] == 0)
    for i in range(len(rows)):
        exact = volume_closed_form(*rows[i, :3], *rows[i, 6:12])
        assert s["volume"][i] == exact
        assert abs(s["volume_mc"][i] - exact) < 4 * s["volume_mc_se"][i]
        assert s["volume_mc_se"][i] / exact < 0.004


def test_knee_limits_have_no_closed_form_and_mc_matches_analytic_batch():
    r = row(q2_lower=-0.5, q2_upper=2.0, q3_lower=-2.5, q3_upper=-0.2)
    assert math.isnan(volume_closed_form(*r[:3], *r[6:12]))
    s = score_designs(r[None], mc_samples=100_000, seed=1)
    assert s["volume_exact"][0] == 0 and s["volume"][0] == s["volume_mc"][0]
    # independent estimate: other random points, the package's closed-form IK with limits
    chain = hk.robots.hexabot_leg(
        *r[:3], limits=tuple(JointLimits(r[6 + 2 * j], r[7 + 2 * j]) for j in range(3))
    )
    rng = np.random.default_rng(99)
    n, big, reach = 100_000, r[0] + r[1] + r[2], r[1] + r[2]
    rho = big * np.sqrt(rng.random(n))
    phi = rng.uniform(-PI, PI, n)
    pts = np.stack([rho * np.cos(phi), rho * np.sin(phi), rng.uniform(-reach, reach, n)], 1)
    hits = analytic_batch(chain, pts, within_limits=True).reachable
    vcyl = PI * big * big * 2 * reach
    p = hits.mean()
    v2, se2 = vcyl * p, vcyl * math.sqrt(p * (1 - p) / n)
    assert abs(s["volume"][0] - v2) < 4 * math.hypot(se2, s["volume_se"][0])
    # and the membership tests agree point by point
    assert np.array_equal(reachable(r, pts[:20000]), hits[:20000])


def test_designs_differing_by_one_percent_rank_correctly():
    base = row()
    v0 = volume_closed_form(*base[:3])
    l1b = optimize.brentq(lambda x: volume_closed_form(x, 0.1, 0.1) - 1.01 * v0, 0.05, 0.07)
    pair = np.array([base, row(l1=l1b)])
    knee = dict(q2_lower=-0.3, q2_upper=2.5)  # no closed form: Monte-Carlo only
    scale = 1.01 ** (1 / 3)
    kpair = np.array([row(**knee), row(l1=0.05 * scale, l2=0.1 * scale, l3=0.1 * scale, **knee)])
    for seed in range(5):
        s = score_designs(pair, seed=seed)  # default 10,000 samples
        assert s["volume"][1] / s["volume"][0] == pytest.approx(1.01, rel=1e-12)
        assert s["volume_mc"][1] > s["volume_mc"][0]
        d = s["volume_mc"][1] - s["volume_mc"][0]
        assert abs(d - 0.01 * v0) < 0.5 * 0.01 * v0
        k = score_designs(kpair, seed=seed)
        assert k["volume"][1] > k["volume"][0]
        assert k["volume"][1] / k["volume"][0] == pytest.approx(1.01, rel=1e-9)


# ---------------------------------------------------------------- Jacobian, membership
def test_jacobian_and_sigmas_against_pinocchio():
    rng = np.random.default_rng(0)
    for l1, l2, l3 in [(0.05, 0.1, 0.1), (0.03, 0.13, 0.07)]:
        model = hk.load(hk.robots.hexabot_leg(l1, l2, l3))
        for q in rng.uniform(-PI, PI, (20, 3)):
            jp = np.asarray(model.jacobian(q, "local_world_aligned"))[:3]
            sv = np.linalg.svd(jp, compute_uv=False)
            smin, manip = sigmas(l1, l2, l3, q)
            assert smin == pytest.approx(sv[-1], rel=1e-9, abs=1e-14)
            assert manip == pytest.approx(np.prod(sv), rel=1e-9, abs=1e-15)


def test_membership_against_analytic_batch_with_limits():
    rng = np.random.default_rng(5)
    r = row(
        l1=0.04,
        l2=0.11,
        l3=0.09,
        q1_lower=-1.2,
        q1_upper=2.0,
        q2_lower=-1.0,
        q2_upper=1.5,
        q3_lower=0.1,
        q3_upper=2.8,
    )
    chain = hk.robots.hexabot_leg(
        *r[:3], limits=tuple(JointLimits(r[6 + 2 * j], r[7 + 2 * j]) for j in range(3))
    )
    pts = rng.uniform(-0.25, 0.25, (30000, 3))
    ref = analytic_batch(chain, pts, within_limits=True).reachable
    assert 0.05 < ref.mean() < 0.5
    assert design_chain(r) == chain
    assert np.array_equal(reachable(r, pts), ref)


# ---------------------------------------------------------------- stride
def _stride_root_find(r: np.ndarray) -> float:
    """Independent: the line leaves the reach circle (ρ − l1)² + h² = (l2 + l3)² (brentq)."""
    l1, l2, l3, h, _, yaw = r[:6]
    a = math.sqrt((l2 + l3) ** 2 - h * h)
    b = math.sqrt(max((l2 - l3) ** 2 - h * h, 0))
    rho0 = l1 + b + r[12] * (a - b)
    d = np.array([math.cos(yaw), -math.sin(yaw)])

    def g(t):
        return (np.hypot(*(np.array([rho0, 0.0]) + t * d)) - l1) ** 2 + h * h - (l2 + l3) ** 2

    big = 2 * (l1 + l2 + l3)
    return optimize.brentq(g, 0, big, xtol=1e-15) - optimize.brentq(g, -big, 0, xtol=1e-15)


def test_best_design_for_seed_total_length_and_its_stride(tmp_path):
    space = DesignSpace(
        {"l1": Range(0.01, 0.09, 9), "l2": Range(0.05, 0.19, 15), "height": 0.1}, total=0.25
    )
    res = sweep(space, mc_samples=2000, out=tmp_path / "t.json")
    best = res.summary["best"]
    r = row(**{p: best[p] for p in PARAMETERS})
    assert best["l1"] + best["l2"] + best["l3"] == pytest.approx(0.25)
    assert best["stride"] == pytest.approx(_stride_root_find(r), rel=1e-10)
    # the closed form of a walking direction perpendicular to the leg: a chord of radius ρ_out
    l1, l2, l3, h = r[:4]
    a = math.sqrt((l2 + l3) ** 2 - h * h)
    b = math.sqrt(max((l2 - l3) ** 2 - h * h, 0))
    rho0 = l1 + (a + b) / 2
    assert best["stride"] == pytest.approx(2 * math.sqrt((l1 + a) ** 2 - rho0**2), rel=1e-10)
    # it is the maximum of that closed form over the feasible grid
    t = res.table
    chord = [
        2
        * math.sqrt(
            (t["l1"][i] + math.sqrt((0.25 - t["l1"][i]) ** 2 - 0.01)) ** 2
            - (
                t["l1"][i]
                + (
                    math.sqrt((0.25 - t["l1"][i]) ** 2 - 0.01)
                    + math.sqrt(max((t["l2"][i] - t["l3"][i]) ** 2 - 0.01, 0))
                )
                / 2
            )
            ** 2
        )
        for i in range(res.n)
    ]
    assert best["stride"] == pytest.approx(max(chord), rel=1e-10)
    assert np.allclose(t["stride"], chord, rtol=1e-10)
    assert json.loads((tmp_path / "t.json").read_text())["best"]["index"] == best["index"]


def test_stride_limited_by_the_hip_and_through_the_hip_axis():
    rows = np.array([row(q1_lower=-0.5, q1_upper=0.5), row(mount_yaw=0.0), row(height=0.2)])
    s = score_designs(rows, mc_samples=100)
    a = math.sqrt(0.2**2 - 0.1**2)
    rho0 = 0.05 + a / 2
    assert s["stride"][0] == pytest.approx(2 * rho0 * math.tan(0.5), rel=1e-10)
    assert s["limit_margin"][0] == pytest.approx(0.5 - math.atan(0.9 * math.tan(0.5)), rel=1e-9)
    # walking along the leg: the whole diameter of the ground disk, through the hip axis
    assert s["stride"][1] == pytest.approx(2 * (0.05 + a), rel=1e-10)
    half_step = 0.5 * 0.9 * s["stride"][1] / 63
    assert s["axis_distance"][1] == pytest.approx(half_step, rel=1e-6)
    assert s["sigma_min"][1] <= s["axis_distance"][1] + 1e-15
    # ground out of reach
    assert s["feasible"][2] == 0 and s["stride"][2] == 0


# ---------------------------------------------------------------- designs, Pareto
def test_design_generation():
    sp = DesignSpace({"l1": Range(0.03, 0.06, 4), "l2": Range(0.08, 0.12, 3)})
    d = sp.designs()
    assert d.shape == (12, len(PARAMETERS))
    assert set(np.round(d[:, 0], 12)) == {0.03, 0.04, 0.05, 0.06}
    lhs = sp.designs("lhs", samples=50, seed=2)
    for j, rg in ((0, (0.03, 0.06)), (1, (0.08, 0.12))):
        strata = np.floor((lhs[:, j] - rg[0]) / (rg[1] - rg[0]) * 50).astype(int)
        assert sorted(strata) == list(range(50))  # one sample per stratum
    assert np.array_equal(lhs, sp.designs("lhs", samples=50, seed=2))
    tot = DesignSpace({"l1": Range(0.05, 0.2, 4), "l2": Range(0.05, 0.2, 4)}, total=0.25)
    t = tot.designs()
    assert np.all(t[:, 2] > 0) and np.allclose(t[:, :3].sum(1), 0.25)
    with pytest.raises(ParameterError, match="bogus"):
        DesignSpace({"bogus": 1.0})
    with pytest.raises(ParameterError, match="q2_lower"):
        DesignSpace({"q2_lower": 1.0, "q2_upper": 0.0}).designs()


def test_pareto_front_against_brute_force():
    rng = np.random.default_rng(1)
    f = np.round(rng.random((300, 3)), 1)  # ties included
    table = {
        "stride": f[:, 0],
        "volume": f[:, 1],
        "sigma_min": f[:, 2],
        "feasible": (rng.random(300) > 0.1).astype(float),
    }
    mask = pareto_front(table)
    ok = table["feasible"] > 0
    for i in range(300):
        dominated = np.any(ok & np.all(f >= f[i], 1) & np.any(f > f[i], 1))
        assert mask[i] == (ok[i] and not dominated)


# ---------------------------------------------------------------- execution
SPACE = DesignSpace(
    {"l1": Range(0.03, 0.07, 4), "l2": Range(0.08, 0.12, 4), "q2_lower": Range(-PI, -1.0, 2)}
)
#: 10,000 Monte-Carlo samples per design: the tests below compare tables between runs
#: (byte for byte), which any sample count tells apart; the accuracy tests above use more.
OPTS = {"mc_samples": 10_000, "chunk_size": 2, "seed": 7}


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("local") / "l.csv"
    return sweep(SPACE, out=out, **OPTS)


@pytest.fixture(scope="module")
def dask_client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1", dashboard_address=None
    )
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


def test_parquet_json_and_csv_tables_agree(local_run, tmp_path):
    """Each run writes the one table asked for (format by extension) and nothing else."""
    pytest.importorskip("pyarrow")
    assert set(local_run.files) == {"csv"}
    assert sorted(p.name for p in Path(local_run.files["csv"]).parent.iterdir()) == ["l.csv"]
    csv = read_results(local_run.files["csv"])
    for name in ("t.parquet", "t.json"):
        res = sweep(SPACE, out=tmp_path / name, **{**OPTS, "chunk_size": 16})
        assert list(res.files.values()) == [str(tmp_path / name)]
        other = read_results(tmp_path / name)
        assert list(other) == list(csv) == list(local_run.table)
        for k in csv:
            assert np.array_equal(csv[k], other[k]) and np.array_equal(csv[k], local_run.table[k])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.json", "t.parquet"]
    summary = json.loads((tmp_path / "t.json").read_text())
    assert (
        summary["n_designs"] == 32
        and summary["best"]["index"] == local_run.summary["best"]["index"]
    )
    with pytest.raises(ParameterError, match=r"\.csv, \.parquet, \.json"):
        sweep(SPACE, out=tmp_path / "t.xlsx", **OPTS)


def test_dask_table_equals_local(local_run, dask_client, tmp_path):
    res = sweep(SPACE, client=dask_client, out=tmp_path / "d.csv", **OPTS)
    assert res.scored == res.n == 32
    assert Path(res.files["csv"]).read_bytes() == Path(local_run.files["csv"]).read_bytes()
    # through the scheduler address (what --scheduler ADDR does), other chunking
    addr = dask_client.scheduler.address
    res2 = sweep(SPACE, scheduler=addr, **{**OPTS, "chunk_size": 5})
    for k, v in local_run.table.items():
        assert np.array_equal(res2.table[k], v)


def test_same_table_whatever_threads_and_chunks(local_run):
    res = sweep(SPACE, workers=1, **{**OPTS, "chunk_size": 7})
    for k, v in local_run.table.items():
        assert np.array_equal(res.table[k], v)


def test_dask_worker_killed_mid_sweep(local_run, dask_client, tmp_path):
    pids = list(dask_client.run(os.getpid).values())
    killed: list[int] = []

    def kill(_k: int) -> None:
        if not killed:
            os.kill(pids[0], signal.SIGKILL)
            killed.append(pids[0])

    res = sweep(SPACE, client=dask_client, out=tmp_path / "k.csv", on_chunk=kill, **OPTS)
    assert killed
    assert killed[0] not in dask_client.run(os.getpid).values()  # the nanny replaced it
    assert Path(res.files["csv"]).read_bytes() == Path(local_run.files["csv"]).read_bytes()


def _cli(out: Path) -> list[str]:
    return [
        sys.executable,
        "-m",
        "hexapod_kin",
        "sweep",
        "--l1",
        "0.03:0.07:4",
        "--l2",
        "0.08:0.12:4",
        f"--q2-lower={-PI!r}:-1.0:2",
        "--height",
        "0.1",
        "--mc-samples",
        str(OPTS["mc_samples"]),
        "--chunk-size",
        "2",
        "--seed",
        "7",
        "--no-progress",
        "--out",
        str(out),
        "--json",
    ]


def _run_until_chunks(cmd: list[str], parts: Path, n: int, sig: int) -> int:
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    guard = time.monotonic() + 900  # guards a hang only (never a speed): generous
    while len(list(parts.glob("chunk_*.npz"))) < n and proc.poll() is None:
        if time.monotonic() > guard:
            proc.kill()
            pytest.fail(f"hang: fewer than {n} chunks after 900 s")
        time.sleep(0.01)
    proc.send_signal(sig)
    proc.communicate(timeout=600)
    return proc.returncode


@pytest.mark.slow
def test_interrupted_cli_sweep_resumes_to_the_same_table(local_run, tmp_path):
    out = tmp_path / "s.csv"
    parts = tmp_path / ".s.csv.sweep-parts"  # the hidden sidecar of the chunks
    rc = _run_until_chunks(_cli(out), parts, 1, signal.SIGINT)  # Ctrl-C
    assert rc in (130, -signal.SIGINT)  # a shell's $? = 130 for both
    have = len(list(parts.glob("chunk_*.npz")))
    rc = _run_until_chunks(_cli(out), parts, have + 2, signal.SIGKILL)
    assert rc == -signal.SIGKILL
    have = len(list(parts.glob("chunk_*.npz")))
    assert 0 < have < 16 and not out.exists()
    done = subprocess.run(_cli(out), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["scored"] == 32 - 2 * have
    assert out.read_bytes() == Path(local_run.files["csv"]).read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.csv"]  # the sidecar is gone


def test_other_sweep_over_an_interrupted_one_is_refused(local_run, tmp_path):
    out = tmp_path / "i.csv"

    def stop(k: int) -> None:
        if k == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep(SPACE, out=out, workers=1, on_chunk=stop, **OPTS)
    assert not out.exists() and (tmp_path / ".i.csv.sweep-parts").is_dir()
    with pytest.raises(ConfigurationError, match="different sweep"):
        sweep(SPACE, out=out, **{**OPTS, "seed": 8})
    res = sweep(SPACE, out=out, **OPTS)  # the same sweep finishes it
    assert res.scored == 32 - 2 * 2
    assert out.read_bytes() == Path(local_run.files["csv"]).read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["i.csv"]


def test_readme_example_runs_with_the_default_height(tmp_path, capsys, monkeypatch):
    """``sweep --l2 … --l3 … --out designs.csv --plot sweep.png`` as the README has it."""
    from hexapod_kin.cli import main
    from hexapod_kin.sweep import DEFAULTS

    monkeypatch.chdir(tmp_path)
    argv = "sweep --l2 0.08:0.12:5 --l3 0.08:0.12:5 --out designs.csv --plot sweep.png"
    assert main(argv.split()) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["designs.csv", "sweep.png"]
    table = read_results(tmp_path / "designs.csv")
    assert DEFAULTS["height"] == 0.10
    assert len(table["index"]) == 25 and np.all(table["height"] == 0.10)
    assert "height = 0.1 m" in capsys.readouterr().out


def test_cli_errors_are_one_line(tmp_path):
    from hexapod_kin.cli import main

    assert main(["sweep", "--l1", "a:b", "--height", "0.1", "--out", str(tmp_path / "x.csv")]) == 2
    assert (
        main(
            [
                "sweep",
                "--l1",
                "0.05",
                "--height",
                "0.1",
                "--workers",
                "99",
                "--out",
                str(tmp_path / "y.csv"),
            ]
        )
        == 2
    )


def test_cli_plot(tmp_path, capsys, drawn):
    """The front panel draws the table's feasible designs, and circles the non-dominated ones."""
    import csv

    from hexapod_kin.cli import main

    png = tmp_path / "f.png"
    assert (
        main(
            [
                "sweep",
                "--l1",
                "0.02:0.08:4",
                "--l2",
                "0.06:0.14:3",
                "--total",
                "0.25",
                "--height",
                "0.1",
                "--mc-samples",
                "2000",
                "--out",
                str(tmp_path / "p.csv"),
                "--plot",
                str(png),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "best (max stride)" in text and "±" in text
    with open(tmp_path / "p.csv", newline="", encoding="utf-8") as fh:
        rows = [r for r in csv.DictReader(fh) if float(r["feasible"]) > 0]
    designs = np.array([[float(r[k]) for k in ("stride", "volume", "sigma_min")] for r in rows])
    dots, circles = drawn[-1].axes[3].collections[:2]  # panels first, then colour bars
    np.testing.assert_allclose(dots.get_offsets(), designs[:, :2], rtol=1e-12)
    # brute force: a design is on the front iff no other is >= on all three and > on one
    front = [not any(np.all(o >= d) and np.any(o > d) for o in designs) for d in designs]
    np.testing.assert_allclose(circles.get_offsets(), designs[front, :2], rtol=1e-12)
    assert 0 < sum(front) < len(designs)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["swap", "edit", "truncate"])
def test_damaged_chunks_are_scored_again(local_run, tmp_path, damage):
    """Chunks are checked against what they claim: swapped, edited or truncated ones are
    discarded with one CacheWarning and scored again; the table equals the undamaged run."""
    from hexapod_kin.exceptions import CacheWarning

    out = tmp_path / "d.csv"
    parts = tmp_path / ".d.csv.sweep-parts"

    def stop(k: int) -> None:
        if k == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep(SPACE, out=out, workers=1, on_chunk=stop, **OPTS)
    files = sorted(parts.glob("chunk_*.npz"))
    assert len(files) >= 2
    a, b = files[0], files[1]
    if damage == "swap":
        da, db = a.read_bytes(), b.read_bytes()
        a.write_bytes(db)
        b.write_bytes(da)
    elif damage == "edit":
        with np.load(a) as z:
            arrays = {k: np.array(z[k]) for k in z.files}
        arrays["scores"][0, 0] += 1e-3  # a plausible value, digest left as it was
        with open(a, "wb") as fh:
            np.savez(fh, **arrays)
    else:
        a.write_bytes(a.read_bytes()[:50])
    with pytest.warns(CacheWarning, match="not hold what (it claims|they claim)"):
        res = sweep(SPACE, out=out, workers=1, **OPTS)
    assert out.read_bytes() == Path(local_run.files["csv"]).read_bytes()
    assert res.scored >= 2


def test_a_huge_sweep_is_estimated_and_refused(tmp_path):
    big = DesignSpace({"l2": Range(0.05, 0.15, 3000), "l3": Range(0.05, 0.15, 3000)})
    with pytest.raises(ParameterError, match="9000000 designs: estimated") as err:
        sweep(big, out=tmp_path / "x.csv")
    assert err.value.parameter == "samples"
    assert not list(tmp_path.iterdir())  # refused before anything is written


def test_grid_head_is_the_full_grids_head():
    """``designs(first=k)`` builds only k grid points: the first k of the meshgrid order."""
    space = DesignSpace({"l1": Range(0.03, 0.07, 3), "l2": Range(0.08, 0.12, 4), "height": 0.09})
    full = space.designs()
    axes = np.meshgrid(np.linspace(0.03, 0.07, 3), np.linspace(0.08, 0.12, 4), indexing="ij")
    assert np.array_equal(full[:, 0], axes[0].ravel()) and np.array_equal(
        full[:, 1], axes[1].ravel()
    )
    assert np.array_equal(space.designs(first=5), full[:5])


@pytest.mark.parametrize(
    "kw, match",
    [({"seed": -1}, "seed=-1"), ({"mc_samples": 0, "allow_large": True}, "mc_samples=0")],
)
def test_refused_sweep_leaves_nothing(tmp_path, kw, match):
    """Refused before the first chunk: no sidecar folder blocks the corrected call."""
    space = DesignSpace({"l1": Range(0.03, 0.07, 2)})
    with pytest.raises(ParameterError, match=match):
        sweep(space, out=tmp_path / "r.csv", **kw)
    assert not list(tmp_path.iterdir())
    assert sweep(space, out=tmp_path / "r.csv", mc_samples=500).n == 2


@pytest.mark.parametrize("name, value", [("l2", 1e300), ("height", 2e3), ("mount_yaw", 1e300)])
def test_absurd_designs_are_refused(name, value):
    """Beyond 1 km or 1000 rad the closed forms overflow (NaN scores): refused up front."""
    with pytest.raises(ParameterError, match=f"{name}="):
        DesignSpace({name: value}).designs()


def test_a_zip_bomb_chunk_is_not_inflated(tmp_path):
    """A chunk whose member would inflate far beyond its scores' size is discarded unread."""
    import io
    import tracemalloc
    import zipfile

    from hexapod_kin.exceptions import CacheWarning

    # fewer Monte-Carlo samples than OPTS and four designs in two chunks, the bomb in one
    # (the resumed sweep runs under tracemalloc, which slows it many-fold); the undamaged
    # table is this sweep's own, run beside it
    opts = {**OPTS, "mc_samples": 4_000}
    space = DesignSpace({"l1": Range(0.03, 0.07, 2), "l2": Range(0.08, 0.12, 2)})
    undamaged = sweep(space, out=tmp_path / "u.csv", workers=1, **opts)
    out = tmp_path / "z.csv"

    def stop(k: int) -> None:
        if k == 1:  # every chunk stored, the table not yet written
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep(space, out=out, workers=1, on_chunk=stop, **opts)
    assert len(list(out.parent.glob(".z.csv.sweep-parts/chunk_*.npz"))) == 2
    chunk = tmp_path / ".z.csv.sweep-parts" / "chunk_00000.npz"
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (1 << 23, 1)}
    )
    with zipfile.ZipFile(chunk, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("scores.npy", header.getvalue() + bytes(8 << 23))  # 64 MiB in ~64 kB
    assert chunk.stat().st_size < 1 << 17
    tracemalloc.start()
    try:
        with pytest.warns(CacheWarning, match="chunk_00000.npz"):
            res = sweep(space, out=out, workers=1, **opts)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 << 20  # the 64 MiB never inflated (scoring itself peaks near 40 MiB)
    assert res.scored == 2
    assert out.read_bytes() == Path(undamaged.files["csv"]).read_bytes()


def test_yes_runs_a_sweep_beyond_the_estimate_limits(tmp_path, monkeypatch, capsys):
    """The refusal is the estimate's (limits lowered here so a small sweep is "too large"):
    ``--yes`` runs it, and nothing is written by the refused run."""
    from hexapod_kin.cli import main
    from hexapod_kin.sweep import run

    monkeypatch.setattr(run, "MAX_HOURS", 1e-12)
    argv = ["sweep", "--l1", "0.03:0.07:2", "--mc-samples", "500", "--out", str(tmp_path / "y.csv")]
    assert main(argv) == 2
    assert "2 designs: estimated" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())
    assert main([*argv, "--yes", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["n_designs"] == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["y.csv"]


def test_a_result_in_hand_counts_though_its_worker_died_since(local_run, monkeypatch, tmp_path):
    """Dask marks a finished future "lost" when the worker holding it dies, also after
    as_completed gathered its result: that result is kept (the race failed the killed-worker
    test above under load); a lost future without a result is still refused."""
    import distributed

    from hexapod_kin.sweep import run as sweep_run

    class Future:
        def __init__(self, value, status):
            self.value, self.status = value, status

        def cancel(self):
            pass

    class Client:
        def __init__(self, status, keep):
            self.status, self.keep = status, keep

        def submit(self, fn, designs, options, key, pure):
            return Future(fn(designs, options) if self.keep else None, self.status)

    def as_completed(futures, with_results):
        return [(f, f.value) for f in futures]

    monkeypatch.setattr(distributed, "as_completed", as_completed)
    res = sweep_run.sweep(SPACE, client=Client("lost", True), out=tmp_path / "a.csv", **OPTS)
    np.testing.assert_array_equal(res.table["index"], local_run.table["index"])
    for name in res.table:
        np.testing.assert_array_equal(res.table[name], local_run.table[name])
    with pytest.raises(ConfigurationError, match="lost sweep chunk"):
        sweep_run.sweep(SPACE, client=Client("lost", False), out=tmp_path / "b.csv", **OPTS)
