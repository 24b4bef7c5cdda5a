"""Build the report: every comparison and experiment, written as Markdown and standalone HTML.

``reproduce(out)`` writes ``report.md`` (figures in ``figures/``, claims linked to the seed
texts copied to ``seeds/``), ``report.html`` (standalone, offline: :mod:`.html`), the
animations ``step.html``/``walk.html`` and ``verdicts.json``. A run with the inputs of an
earlier build replays it (:mod:`.replay`). Nothing heavy is imported at module level.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._io import atomic_write
from ..exceptions import ParameterError
from . import replay
from .data import LABELS, LEGEND, STATUSES, Verdict, load_claims, seed_file

__all__ = ["SECTIONS", "Report", "reproduce"]

#: Report sections: (key, title, introduction).
SECTIONS: tuple[tuple[str, str, str], ...] = (
    (
        "tables",
        "1. The Khalil tables (3-DOF leg, SCARA)",
        "Seeds 000 and 001 use α2 = −90° with symbolic lengths, seed 003 uses α2 = +90° with "
        "50/100/100 mm. hexapod_kin's `hexabot_leg` is the −90° table; the `differs` verdict "
        "says, computed, what the +90° choice does to the FK.",
    ),
    (
        "transforms",
        "2. Every ʲ⁻¹Tⱼ and ⁰Tⱼ, symbolically",
        "Each seed matrix is compared entry by entry with `hexapod_kin.symbolic.derive` of the "
        "seed's own table (α2 sign and lengths as the seed chose). The full derivations are at "
        "the end of the section.",
    ),
    (
        "jacobian",
        "3. Jacobian (direct, indirect), det J factored, singular families",
        "The families are read off the factors of det J; the heat maps scan σ_min over two "
        "joints and label every flagged sample with its family.",
    ),
    (
        "step",
        "4. The x-only step (foot velocity [A sin 2πt/T, 0, 0])",
        "`hexapod_kin.seeds.seed_experiment`: resolved rate, RK4, closed loop on the exact "
        "reference; the plain Euler + solve loop the seeds used is the baseline in the drift "
        "panel.",
    ),
    (
        "leg2",
        "5. The 2-DOF leg of seed 002 (FK, IK, Table I replayed)",
        "FK numbers by Pinocchio (and the table product), the seed's IK Eqs. 9-12 evaluated as "
        "written, and `ik.analytic`; Table I is `seeds.seed002_schedule`.",
    ),
    (
        "pendulum",
        "6. The pendulum of seed 001 (undamped, damped)",
        "`dynamics.pendulum_experiment` (0.5 m, 1 kg, θ0 = 30°; the seed gives no length or "
        "mass): the period against the exact elliptic-integral period.",
    ),
    ("beyond", "7. Beyond the seeds: the hexapod standing and walking", ""),
)


def _section(v: Verdict) -> str:
    if v.kind == "table":
        return "tables"
    if v.kind in ("generic",) or (v.kind == "matrix" and "T" in v.claim.split("-")[-1]):
        return "transforms"
    if v.seed == "002":
        return "leg2"
    if v.claim.endswith(("step", "phase", "velocity-factor")):
        return "step"
    if "pend" in v.claim:
        return "pendulum"
    return "jacobian"


@dataclass(frozen=True)
class Report:
    """A built report: its folder, ``report.md``, ``report.html``, verdicts and other facts.

    Attributes:
        seconds: Wall time of this run in [s] (of the replay when replayed).
        replayed_from: UTC time (``YYYY-MM-DDTHH:MM:SSZ``) of the build this run copied
            (:mod:`.replay`), or ``None``: computed by this run.
        build_seconds: Wall time in [s] of the build that computed the report.

    """

    out: Path
    markdown: Path
    html: Path
    verdicts: tuple[Verdict, ...]
    facts: dict[str, Any]
    seconds: float
    replayed_from: str | None = None
    build_seconds: float | None = None

    @property
    def counts(self) -> dict[str, int]:
        """Number of verdicts per status."""
        counted = Counter(v.status for v in self.verdicts)
        return {**dict.fromkeys(STATUSES, 0), **counted}

    def summary(self) -> str:
        """One line: how many claims agree, are wrong, underdetermined, differ, failed."""
        c = self.counts
        text = (
            f"{len(self.verdicts)} claims checked: {c['agrees']} agree, {c['wrong']} "
            f"seed is wrong, {c['underdetermined']} underdetermined (the seed leaves a "
            f"deciding value open), {c['differs']} differ (convention)"
        )
        return text + (f", {c['error']} NOT COMPUTED" if c["error"] else "")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: paths, counts, verdicts, facts, seconds, replayed_from, build_seconds."""
        return {
            "out": str(self.out),
            "markdown": str(self.markdown),
            "html": str(self.html),
            "summary": self.summary(),
            "counts": self.counts,
            "seconds": self.seconds,
            "replayed_from": self.replayed_from,
            "build_seconds": self.build_seconds,
            "verdicts": [v.to_dict() for v in self.verdicts],
            "facts": self.facts,
        }


def reproduce(
    out: str | Path, *, quick: bool = False, animations: bool = True, cache: bool = True
) -> Report:
    """Redo every result of the four seeds, compare, and write the report into ``out``.

    ``quick``: reduced sizes; ``animations``: the step and walk animations (the ``viewer``
    extra); ``cache``: replay an earlier build with the same inputs (:mod:`.replay`).

    Raises:
        ParameterError: A file of ``out`` cannot be written (found before the build; the
            folders this call made are removed).

    """
    start = time.perf_counter()
    out = Path(out)
    made = _new_folders(out)
    try:
        _probe(out)  # a full disk or a read-only folder refused at once, not after the build
        return _reproduce(out, quick=quick, animations=animations, cache=cache, start=start)
    except BaseException:
        for folder in made:  # deepest first; only the folders this call made, when empty
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise


def _new_folders(out: Path) -> list[Path]:
    """The folders a build makes that do not exist yet (``out``'s parents too), deepest first."""
    new = [d for d in (out / "figures", out / "seeds") if not d.exists()]
    d = out
    while not d.exists() and d != d.parent:
        new.append(d)
        d = d.parent
    return new


def _probe(out: Path) -> None:
    """Make ``out`` and write one byte in it (then remove it): a write that will fail, fails now."""

    def refuse(why: str) -> ParameterError:
        text, allowed = f"out={str(out)!r}: {why}", "a folder that can be written"
        return ParameterError(text, parameter="out", value=str(out), allowed=allowed)

    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise refuse(f"cannot make the folder ({exc.strerror or exc})") from None
    try:
        atomic_write(out / ".hexapod-kin-write-probe", b"\n", sync=False).unlink()
    except (OSError, ParameterError) as exc:
        why = str(exc).split("cannot write it (")[-1].split(")")[0]
        raise refuse(f"cannot write in it ({why}); nothing was written") from None


def _reproduce(out: Path, *, quick: bool, animations: bool, cache: bool, start: float) -> Report:
    """The body of :func:`reproduce` (``out`` made and writable)."""
    try:
        parts: dict[str, Any] | None = replay.key_parts(
            quick=quick, animations=animations, digest=replay.source_digest()
        )
    except Exception:  # noqa: BLE001 - unreadable source: build, do not keep
        parts = None
    key = replay.run_key(parts) if parts is not None else None
    if cache and key is not None:
        entry = replay.lookup(key)  # a damaged entry: None, with one CacheWarning
        if entry is not None:
            rep = _replayed(entry, out, start)
            if rep is not None:
                return rep
    rep, written = _build(out, quick=quick, animations=animations, start=start)
    if parts is not None and key is not None and _storable(rep, parts):
        record = {
            "summary": rep.summary(),
            "counts": rep.counts,
            "seconds": rep.seconds,
            "verdicts": [v.fields() for v in rep.verdicts],
            "facts": rep.facts,
        }
        replay.save(key, parts, out, written, record)
    return rep


def _storable(rep: Report, parts: dict[str, Any]) -> bool:
    """A complete build whose inputs did not change while it ran (the source is re-read)."""
    unwritten = "step_animation" in rep.facts or "walk_animation" in rep.facts.get("hexapod", {})
    if rep.counts["error"] or unwritten:
        return False
    try:
        now = replay.key_parts(**parts["options"], digest=replay.source_digest())
        return now == json.loads(json.dumps(parts))
    except Exception:  # noqa: BLE001 - cannot tell: do not keep
        return False


def _replayed(entry: Any, out: Path, start: float) -> Report | None:
    """The report of a replayed entry (its files copied into ``out``), or None (unusable)."""
    rec = entry.record
    try:
        verdicts = tuple(Verdict.from_fields(v) for v in rec["verdicts"])
        facts, built, build_seconds = dict(rec["facts"]), str(rec["built"]), float(rec["seconds"])
    except Exception:  # noqa: BLE001 - a manifest we cannot read back: build
        return None
    if any(v.status == "error" for v in verdicts):
        return None
    replay.restore(entry, out)
    md_path, html_path = out / "report.md", out / "report.html"
    seconds = time.perf_counter() - start
    rep = Report(out, md_path, html_path, verdicts, facts, seconds, built, build_seconds)
    atomic_write(out / "verdicts.json", json.dumps(rep.to_dict(), indent=1, default=str))
    return rep


def _build(out: Path, *, quick: bool, animations: bool, start: float) -> tuple[Report, list[Path]]:
    """Compute and write the report: the :class:`Report` and the files but ``verdicts.json``."""
    from .._budget import prestart

    # the numeric half's child, importing Pinocchio and its experiments while sympy loads here
    prestart(("hexapod_kin.report._worker", "hexapod_kin.seeds", "hexapod_kin.dynamics.pendulum"))
    from . import figures
    from ._worker import NumericHalf
    from .checks import Context, evaluate

    fdir = out / "figures"
    fdir.mkdir(parents=True, exist_ok=True)
    figs: dict[str, list[Path]] = {k: [] for k, _, _ in SECTIONS}
    anims: dict[str, list[Path]] = {k: [] for k, _, _ in SECTIONS}
    stills: dict[str, tuple[Path, str]] = {}
    facts: dict[str, Any] = {}
    claims, seeds = load_claims()
    ctx = Context(quick=quick, claims=claims)
    # two halves at once: the experiments and their figures in a child process (no sympy)
    # while the derivations and the checks run here
    half = NumericHalf(ctx, fdir, out, animations, 1.5 if quick else 3.0)
    try:
        # the derivations first: the heat maps label their samples with the families derived
        derivations = {k: ctx.printed(k) for k in _PRINTED}
        half.experiments()  # the checks compare claims with the step and the pendulum
        verdicts = tuple(evaluate(claims, ctx))
        maps, counts = figures.heat_maps(ctx, fdir, 21 if quick else 61)
        leg2 = figures.leg2_figure(ctx, fdir)
        drawn = half.figures()
    finally:
        half.close()
    figs["step"].append(drawn["step"])
    facts["step"] = ctx.step.to_dict()
    if animations:
        stills["step"] = drawn["step_still"]
        if isinstance(drawn["step_animation"], str):
            facts["step_animation"] = drawn["step_animation"]
        else:
            anims["step"].append(drawn["step_animation"])
    facts["scan_family_counts"] = counts
    figs["jacobian"] += maps
    figs["leg2"].append(leg2)
    walk_paths, facts["hexapod"], walk_still = drawn["walk"]
    if walk_still is not None:
        stills["walk"] = walk_still
    figs["pendulum"].append(drawn["pendulum"])
    facts["pendulum"] = {k: v for k, v in ctx.pendulum.to_dict().items() if not isinstance(v, dict)}
    figs["beyond"] += [p for p in walk_paths if p.suffix == ".png"]
    anims["beyond"] += [p for p in walk_paths if p.suffix == ".html"]
    copies = _copy_seeds(seeds, out)
    md_path, html_path = out / "report.md", out / "report.html"
    parts = (Report(out, md_path, html_path, verdicts, facts, 0.0), seeds, figs, anims)
    atomic_write(md_path, _markdown(*parts, derivations))
    atomic_write(html_path, _html(*parts, derivations, stills))
    seconds = time.perf_counter() - start
    rep = Report(out, md_path, html_path, verdicts, facts, seconds, None, seconds)
    atomic_write(out / "verdicts.json", json.dumps(rep.to_dict(), indent=1, default=str))
    written = [md_path, html_path, *copies, *(p for p, _ in stills.values())]
    written += [p for k in figs for p in figs[k] + anims[k]]
    return rep, written


def _copy_seeds(seeds: dict[str, str], out: Path) -> list[Path]:
    """Copy the shipped seed texts into ``out/seeds/`` (the Markdown links there)."""
    paths = []
    (out / "seeds").mkdir(parents=True, exist_ok=True)
    for title in seeds.values():
        src = seed_file(title)
        paths.append(atomic_write(out / "seeds" / src.name, src.read_bytes()))
    return paths


#: The derivations printed in the report, in its order.
_PRINTED = ("leg", "leg+", "scara")


_DERIV = {
    "leg": "hexabot_leg (α2 = −90°, seeds 000/001)",
    "leg+": "hexabot_leg(alpha2=+π/2) (seed 003)",
    "scara": "scara (seed 003)",
}


#: Labels of the hexapod's figures (``facts["hexapod"]``).
_HEXAPOD = {
    "stand_height_m": "standing height [m]",
    "stand_mass_kg": "mass [kg]",
    "stand_forces_z_N": "vertical foot forces [N]",
    "stand_force_residual_N": "force balance residual [N]",
    "stand_peak_torque_Nm": "peak joint torque standing [N·m]",
    "walk_duration_s": "walk duration [s]",
    "walk_min_margin_m": "minimum static stability margin [m]",
    "walk_max_slip_m": "maximum stance-foot slip [m]",
    "walk_ik_ok": "every foot reached inside the joint limits",
    "walk_animation": "walk animation",
}

#: A block of computed figures: ``("p", text)`` (prose, Markdown code spans allowed) or
#: ``("table", caption, header, rows)``.
Block = tuple[Any, ...]


def _value(v: Any) -> str:
    """A computed figure as text (never a Python ``repr``)."""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return ", ".join(_value(x) for x in v)
    return str(v)


def _facts(key: str, rep: Report) -> list[Block]:
    """The computed figures of a section, as prose and tables (rendered by MD and HTML)."""
    f = rep.facts
    if key == "jacobian":
        rows = [
            [robot, family, str(n)]
            for robot, fams in f["scan_family_counts"].items()
            for family, n in fams.items()
        ]
        header = ["robot", "family", "samples"]
        return [("table", "Scan: flagged samples labelled by family", header, rows)]
    if key == "step":
        s = f["step"]
        runs = (
            ("closed loop, RK4 (hexapod_kin)", s),
            ("plain Euler + solve (the seeds' loop)", s["baseline_euler_solve"]),
        )
        rows = [
            [run, *(f"{r[k]:.2e}" for k in ("drift_y", "drift_z", "error_x"))] for run, r in runs
        ]
        header = ["run", "drift y", "drift z", "x error"]
        return [("table", "Drift of the x-only step [m]", header, rows)]
    if key == "pendulum":
        p = f["pendulum"]
        return [
            (
                "p",
                f"Undamped period {p['period']:.9f} s vs exact {p['period_exact']:.9f} s; "
                f"damped period {p['damped_period']:.6f} s; decay rate {p['decay_rate']:.5f} 1/s "
                f"vs b/(2I) = {p['decay_rate_exact']:.5f} 1/s.",
            )
        ]
    if key == "beyond":
        rows = [[_HEXAPOD.get(k, k.replace("_", " ")), _value(v)] for k, v in f["hexapod"].items()]
        return [("table", "The hexapod standing and walking", ["figure", "value"], rows)]
    return []


def _md_table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return out + ["| " + " | ".join(str(x).replace("|", "/") for x in r) + " |" for r in rows]


def _md_derivation(title: str, printed: dict[str, Any]) -> list[str]:
    """A derivation (:meth:`~.checks.Context.printed`) as Markdown: matrices as tables."""
    from .html import pretty_entry

    out = ["", f"#### Derivation of {title}", ""] + [f"- {line}" for line in printed["header"]]
    for item in printed["items"]:
        if "rows" in item:
            rows = [[pretty_entry(x) for x in r] for r in item["rows"]]
            header = [f"col {j + 1}" for j in range(len(rows[0]))]
            out += ["", f"{item['label']} =", ""] + _md_table(header, rows)
        else:
            out += ["", f"{item['label']} = {pretty_entry(item['value'])}"]
    return out + [""] + [f"- {line}" for line in printed["footer"]]


def _md_cells(cells: str) -> list[str]:
    """A matrix verdict as two Markdown tables (differing entries in bold)."""
    from .html import pretty_entry

    data = json.loads(cells)
    differ = {(int(i), int(j)) for i, j in data.get("differ", [])}
    out = []
    for name, rows in (("seed", data["seed"]), ("hexapod_kin", data["ours"])):
        shown = [[pretty_entry(str(v)) for v in row] for row in rows]
        body = [
            [f"**{x}**" if (i, j) in differ else x for j, x in enumerate(r)]
            for i, r in enumerate(shown)
        ]
        header = data.get("header") or [f"col {j + 1}" for j in range(len(rows[0]) if rows else 0)]
        out += ["", f"{name} (differing entries in bold):", ""] + _md_table(header, body)
    return out


def _span(lines: str) -> tuple[str, str]:
    """The first line of a passage ``"first-last"`` and ``"line a"`` or ``"lines a–b"``."""
    first, _, last = lines.partition("-")
    return first, f"line {first}" if first == last else f"lines {first}–{last}"


def _markdown(
    rep: Report,
    seeds: dict[str, str],
    figs: dict[str, list[Path]],
    anims: dict[str, list[Path]],
    derivations: dict[str, dict[str, Any]],
) -> str:
    lines = [
        "# hexapod_kin reproduces the four lab reports",
        "",
        f"**{rep.summary()}.** Every verdict is computed (see `hexapod_kin/report/`): the "
        "seeds' claims are data in `claims.toml`, each with its passage in the seed's text "
        "(shipped in `hexapod_kin/report/seeds/`, copied to `seeds/` here).",
        "",
        "Seeds:",
        "",
    ]
    lines += [f"- **{k}**: [{v}](seeds/{seed_file(v).name})" for k, v in seeds.items()]
    lines += ["", "Verdicts:", ""]
    lines += [f"- **{label}**: {text}" for _, label, text in LEGEND]
    lines += ["", "| claim | seed | where | verdict |", "|---|---|---|---|"]
    for v in rep.verdicts:
        short = v.text if len(v.text) < 160 else v.text[:157] + "..."
        lines.append(f"| {v.claim} | {v.seed} | {v.where} | {short.replace('|', '/')} |")
    for key, title, intro in SECTIONS:
        lines += ["", f"## {title}", ""]
        if intro:
            lines += [intro, ""]
        for v in [v for v in rep.verdicts if _section(v) == key]:
            lines += [f"### {v.claim} — seed {v.seed}, {v.where}", ""]
            if v.lines and v.seed in seeds:  # a link to the shipped seed text
                name = seed_file(seeds[v.seed]).name
                first, span = _span(v.lines)
                lines += [f"- passage: [{name}, {span}](seeds/{name}#L{first})"]
            if v.cells:
                lines += _md_cells(v.cells) + [""]
            else:
                lines += [f"- seed: `{v.claimed}`", f"- hexapod_kin: `{v.computed}`"]
            lines += [f"- **verdict: {v.text}**", f"- compared: {v.method}", ""]
        for block in _facts(key, rep):
            if block[0] == "p":
                lines += ["", block[1]]
            else:
                lines += ["", f"{block[1]}:", ""] + _md_table(block[2], block[3])
        for p in figs[key]:
            lines += ["", f"![{p.stem}](figures/{p.name})"]
        for p in anims[key]:
            lines += ["", f"Animation: [{p.name}]({p.name}) (self-contained, opens offline)"]
        if key == "transforms":
            for k, printed in derivations.items():
                lines += _md_derivation(_DERIV[k], printed)
    return "\n".join(lines) + "\n"


def _html(
    rep: Report,
    seeds: dict[str, str],
    figs: dict[str, list[Path]],
    anims: dict[str, list[Path]],
    derivations: dict[str, dict[str, Any]],
    stills: dict[str, tuple[Path, str]] | None = None,
) -> str:
    from .._page import Html, page
    from . import html as H

    e = H.e
    stills = stills or {}
    texts = {k: seed_file(v).read_text(encoding="utf-8") for k, v in seeds.items()}
    cited: dict[str, dict[int, list[str]]] = {}
    for v in rep.verdicts:
        if v.lines:
            a, _, b = v.lines.partition("-")
            marks = cited.setdefault(v.seed, {})
            for n in range(int(a), int(b) + 1):
                marks.setdefault(n, []).append(v.claim if n == int(a) else "")

    def passage(v: Verdict) -> str:
        if not v.lines:
            return ""
        a, span = _span(v.lines)
        return f" (<a href='#{H.line_anchor(v.seed, int(a))}'>{span} of seed {e(v.seed)}</a>)"

    h = [
        "<h1>hexapod_kin reproduces the four lab reports</h1>",
        f"<p><b>{e(rep.summary())}.</b> Every verdict is computed; the seeds' claims are data "
        "(<code>hexapod_kin/report/claims.toml</code>), each linked to its passage in the "
        "seed's text (<a href='#seeds'>section 8</a>, shipped in "
        "<code>hexapod_kin/report/seeds/</code>).</p><ul>",
    ]
    h += [f"<li><a href='#seed-{e(k)}'><b>{e(k)}</b></a>: {e(v)}</li>" for k, v in seeds.items()]
    h.append("</ul><dl class='legend'>")
    h += [f"<dt class='{s}'>{e(label)}</dt><dd>{e(text)}</dd>" for s, label, text in LEGEND]
    h.append("</dl><table><tr><th>claim</th><th>seed</th><th>where</th><th>verdict</th></tr>")
    for v in rep.verdicts:
        where: str = e(H.seed_notation(v.where))
        if v.lines:
            a = v.lines.partition("-")[0]
            where = f"<a href='#{H.line_anchor(v.seed, int(a))}'>{where}</a>"
        h.append(
            f"<tr><td><a href='#{e(v.claim)}'>{e(v.claim)}</a></td><td>{e(v.seed)}</td>"
            f"<td>{where}</td><td class='{v.status}'>{e(LABELS[v.status])}</td></tr>"
        )
    h.append("</table>")
    for key, title, intro in SECTIONS:
        h.append(f"<h2>{e(title)}</h2>")
        if intro:
            h.append(f"<p>{H.inline(intro)}</p>")
        for v in [v for v in rep.verdicts if _section(v) == key]:
            h.append(
                f"<div class='item' id='{e(v.claim)}'><h3>{e(v.claim)} — seed {e(v.seed)}, "
                f"{e(H.seed_notation(v.where))}{passage(v)}</h3>"
            )
            if v.cells:
                h.append(H.matrix_pair(v.cells))
            else:
                h.append(
                    f"<p>seed: <code>{e(H.pretty_entry(v.claimed))}</code></p>"
                    f"<p>hexapod_kin: <code>{e(H.pretty_entry(v.computed))}</code></p>"
                )
            h.append(H.verdict_html(v.text, v.status))
            h.append(f"<p><small>compared: {e(v.method)}</small></p></div>")
        for block in _facts(key, rep):
            if block[0] == "p":
                h.append(f"<p>{H.inline(block[1])}</p>")
            else:
                _, caption, header, rows = block
                h.append(f"<table class='kv'><caption>{H.inline(caption)}</caption><tr>")
                h.append("".join(f"<th>{e(x)}</th>" for x in header) + "</tr>")
                h += ["<tr>" + "".join(f"<td>{e(x)}</td>" for x in r) + "</tr>" for r in rows]
                h.append("</table>")
        h += [f"<p>{H.image(p)}</p>" for p in figs[key]]
        for p in anims[key]:
            still, when = stills.get(p.stem, (None, ""))
            h.append(H.animation(p, still, when))
        if key == "transforms":
            h += [H.derivation_html(_DERIV[k], printed) for k, printed in derivations.items()]
    h.append("<h2 id='seeds'>8. The seeds' texts</h2>")
    h.append(
        "<p>As shipped in <code>hexapod_kin/report/seeds/</code> (unchanged); the lines a "
        "claim cites are shaded, and a claim's link opens its seed at the first line.</p>"
    )
    h.append(H.seed_texts(seeds, texts, cited))
    h.append(H.SCRIPT)
    return page("hexapod_kin reproduces the seeds", Html("\n".join(h)), style=H.CSS)
