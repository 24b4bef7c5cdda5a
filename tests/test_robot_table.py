"""Legged robots from GitHub that the project has never seen, run as a new user would.

Each robot is run from the command line in a folder of its own (not the project's), with at
most ``--foot`` and ``--inertia``: ``stand``, ``gait`` with every pattern for its number of
legs, ``simulate`` (``--robust`` once the command has it), ``timeline gait`` and ``gait
--html``. Every cell must exit 0; the cells known to fail today are marked ``xfail`` with
their cause (:data:`KNOWN`). :func:`test_table_page` writes the table to
``docs/guide/robots.md``.

The robots whose licence allows it ship under ``tests/data/<robot>/`` (with the licence and a
README saying where they come from); the others (:data:`FETCHED`) are fetched from GitHub at
a pinned commit by tests marked ``network``, skipped offline. ``HEXAPOD_KIN_ROBOT_MIRROR``
may name a folder holding them as ``<owner>+<repo>/<path>`` (read, never written).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
PAGE = ROOT / "docs" / "guide" / "robots.md"
BEGIN, END = "<!-- robot table: begin (tests/test_robot_table.py) -->", "<!-- robot table: end -->"
#: CPU seconds one command may take before it counts as failed.
CELL_TIMEOUT = 900


@dataclass(frozen=True)
class Robot:
    """A robot of the table: where it comes from and the options a user gives it."""

    name: str
    legs: int
    source: str  # under tests/data, or "<owner>/<repo>@<commit>:<path>" (fetched)
    origin: str
    licence: str
    feet: tuple[str, ...] = ()
    inertia: str | None = None
    note: str = ""

    @property
    def fetched(self) -> bool:
        return "@" in self.source

    def options(self) -> list[str]:
        out = [f"--foot={' '.join(self.feet)}"] if self.feet else []
        return out + ([f"--inertia={self.inertia}"] if self.inertia else [])


def _feet(fmt: str, names: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(fmt.format(n) for n in names)


ROBOTS = (
    Robot(
        "Kraby",
        6,
        "kraby/hexapod.urdf",
        "erdnaxe/kraby",
        "MIT",
        note="base frame at ground level",
    ),
    Robot(
        "hexaross",
        6,
        "hexaross/hexapod_description/urdf/hexapod.urdf",
        "Hexapod-h-da/hexaross",
        "MIT",
        feet=_feet("leg{}_rubber_tip:0.1427,-0.1474,0", ("1", "2", "3", "4", "5", "6")),
        note="no foot frames: the rubber tip's far end",
    ),
    Robot(
        "hexa",
        6,
        "hexa/hexa_description/urdf/hexapod.urdf.xacro",
        "olli-io/hexapod-ros2-control",
        "Apache-2.0",
        note="ROS 2 xacro reading a YAML through $(find)",
    ),
    Robot(
        "RARL hexapod-sim",
        6,
        "chrismailer/hexapod-sim@666d788248312b2ae858d018449394a926d3cc79:"
        "urdf/hexapod_simplified.urdf",
        "chrismailer/hexapod-sim",
        "none stated (fetched)",
        feet=_feet("link_{}_3:0.14735,0,0", ("1", "2", "3", "4", "5", "6")),
        note="two legs on the x axis",
    ),
    Robot(
        "CHAMP",
        4,
        "champ/champ_description/urdf/champ.urdf",
        "chvmp/champ",
        "BSD-3-Clause",
    ),
    Robot(
        "MIT Mini Cheetah",
        4,
        "mini_cheetah/mini_cheetah.urdf",
        "Derek-TH-Wang/mini_cheetah_urdf",
        "BSD (package.xml)",
        feet=_feet("shank_{}:0,0,-0.18", ("fr", "fl", "hr", "hl")),
        inertia="point",
        note="continuous joints; inertias that break I1 + I2 >= I3",
    ),
    Robot(
        "Mini Pupper",
        4,
        "mini_pupper/mini_pupper_description/urdf/mini_pupper/mini_pupper_description.urdf.xacro",
        "mangdangroboticsclub/mini_pupper_ros",
        "Apache-2.0",
        note="ROS xacro; joints limited to 1.5 rad/s",
    ),
    Robot(
        "SpotMicroAI",
        4,
        "chvmp/spotmicro_description@395276f036f1d0c56852fe06e5c8377efb964aee:"
        "urdf/spotmicroai.urdf",
        "chvmp/spotmicro_description",
        "GPL-3.0 launch files, CC-BY-3.0 meshes, URDF unstated (fetched)",
        inertia="point",
        note="inertias of 100-1000 kg m^2 on 0.05-0.2 kg links",
    ),
)

#: The patterns ``gait`` offers (walks open loop): the statically stable ones. For four legs
#: that is ``crawl`` (``wave`` was the same gait and went); ``trot``/``pace`` are refused by
#: the open-loop planner with their reason (:func:`test_unstable_patterns_refused_with_reason`)
#: and walk under the closed-loop controller (``hexapod-kin control``).
PATTERNS = {6: ("tripod", "wave", "ripple"), 4: ("crawl",)}


def _cells(robot: Robot) -> list[str]:
    return [
        "stand",
        *(f"gait {p}" for p in PATTERNS[robot.legs]),
        "simulate",
        "timeline gait",
        "gait --html",
    ]


#: Cells that fail today, with their cause (the ``xfail`` reasons; see issue 31). A cell
#: that passes is reported as XPASS, and leaves this list when it passes everywhere. The
#: ``--robust`` ensemble walks its three ±3 mm bump members under the closed-loop controller
#: (hexapod_kin.robust), commanded the plan's mean twist since session 8; the figures below are
#: session 7's unless a reason says session 8 (10 s walks; the plan's flat replay with the
#: project's settings passes for each, within 0.15 %).
_CONTROLLER = "the controller (hexapod_kin.control) does not walk it over the ensemble's bumps: "
_ROBUST_FAILS = {
    "Kraby": "MuJoCo's default contact with zero armature fails its replay on swing strikes "
    "(10 s tripod: leg 0 at 0.93 s; travel -0.60 / -0.46 %, within 1 %): three stance feet "
    "sink twice as far as the six that settled (2.5 vs 1.2 mm) and the body tilts towards the "
    "swing corner, so that foot flies 2.2 mm lower than the settled body allows for (2 mm "
    "allowed). The sway to the support's incentre (sway=1; its CoM stands at 0.73 of the "
    "tripod triangles' inradius) removes the strikes but not the failure (session 9, the "
    "whole ensemble): heading 0.54 / 0.78 deg with MuJoCo's contact (friction 1; limit 0.5), "
    "travel +1.07 % (zero armature, friction 0.6). The controlled bump members (torque kind "
    "since the one default_kind rule) fail with or without the sway: -41 / -79 / -23 % with "
    "it; without it (b240a52) seed 1 falls, 33 non-foot contacts, heading 118 deg",
    "CHAMP": "its feet are now the round ends of its lower-leg meshes (17.5 mm spheres fitted "
    "to the STL's end, planned and simulated: no lower leg in the ground, session 9); what "
    "fails is its thighs meeting its base: the base mesh is an H (plates 290 mm wide at the "
    "ends and the middle, a 30 mm spine where the hips sit), MuJoCo collides its convex hull "
    "(a 290 x 500 mm box) which the thighs clear by 1.7-2.8 mm at rest, and the crawl's sway "
    "rolls the hips by 12 deg (0.087 to 0.30 rad): a thigh is in it from 0.16 s, up to 7.5 mm "
    "(the CLI's plain simulate: +17.4 % travel, 88 mm slip, four base-thigh contacts). Cut "
    "into convex slabs (commit 78af3cb, reverted) the rear thighs, pitched back beside the "
    "rear plates 1.7 mm off, still meet them: the plan needs the body's collision shapes",
    "Mini Pupper": "MuJoCo's default contact with zero armature, friction 1, fails its replay "
    "(travel -1.52 %; the other seven replays -0.10 to -0.98 %); the controlled bump members, "
    "commanded the plan's mean twist of its CoM (session 8: 37.2 mm in 10 s where the nominal "
    "twist asked 55.4 mm), walk +1.01 % of it (0.38 mm; heading 0.99 deg, no fall; the three "
    "seeds alike: its walk stays on the flat square around the start)",
    "SpotMicroAI": _CONTROLLER + "its 10 s plan is 0.72 of a 13.9 s crawl cycle, whose CoM "
    "ends 38 mm forward and 50 mm aside (the sway); commanded that mean twist (session 8) the "
    "controlled members walk -6.59 % of it with a 4.29 deg heading error and a swing strike "
    "(the three seeds alike: the walk stays on the flat square around the start); the flat "
    "replay with the project's settings passes (+0.06 %), and so do its eight replayed members "
    "(session 8, --inertia point: worst +0.85 %, no strike)",
}
KNOWN: dict[tuple[str, str], str] = {(name, "simulate"): why for name, why in _ROBUST_FAILS.items()}

FETCHED = tuple(r for r in ROBOTS if r.fetched)


# ------------------------------------------------------------------------ sources
def _fetch(robot: Robot, into: Path) -> Path:
    """The fetched robot's file: from ``HEXAPOD_KIN_ROBOT_MIRROR`` or GitHub, else skip."""
    repo, _, rest = robot.source.partition("@")
    commit, _, path = rest.partition(":")
    target = into / repo.replace("/", "+") / path
    if target.is_file():
        return target
    mirror = os.environ.get("HEXAPOD_KIN_ROBOT_MIRROR")
    if mirror and (Path(mirror) / repo.replace("/", "+") / path).is_file():
        return Path(mirror) / repo.replace("/", "+") / path
    url = f"https://raw.githubusercontent.com/{repo}/{commit}/{path}"
    try:
        with urllib.request.urlopen(url, timeout=20) as reply:  # noqa: S310 (https, pinned)
            text = reply.read(4_000_000)
    except OSError as exc:
        pytest.skip(f"{robot.name}: cannot fetch {url} ({exc}); needs the network")
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_bytes(text)
    return target


@pytest.fixture(scope="module")
def fetched_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("robots")


_RESULTS: dict[tuple[str, str], tuple[int, str]] = {}


def _argv(robot: Robot, source: str, cell: str) -> list[str]:
    opts = robot.options()
    if cell == "stand":
        return ["stand", source, *opts]
    if cell.startswith("gait ") and cell != "gait --html":
        return ["gait", source, "--pattern", cell.split()[1], *opts]
    if cell == "simulate":
        return ["simulate", source, *(["--robust"] if _robust() else []), *opts]
    if cell == "timeline gait":
        return ["timeline", "gait", source, "-o", "walk.csv", *opts]
    assert cell == "gait --html"
    return ["gait", source, "--html", "walk.html", *opts]


_ROBUST: list[bool] = []


def _robust() -> bool:
    """Whether ``simulate`` has ``--robust`` yet (else plain ``simulate``, marked pending)."""
    if not _ROBUST:
        out = subprocess.run(
            [sys.executable, "-m", "hexapod_kin", "simulate", "--help"],
            capture_output=True,
            text=True,
            timeout=300,
        ).stdout
        _ROBUST.append("--robust" in out)
    return _ROBUST[0]


def _reason(stderr: str) -> str:
    """The one line that says why (the last ``hexapod-kin:`` line that is not a warning)."""
    lines = [
        ln for ln in stderr.splitlines() if ln.startswith("hexapod-kin:") and "warning:" not in ln
    ]
    if not lines:
        tail = [ln for ln in stderr.splitlines() if ln.strip()]
        return tail[-1][:200] if tail else ""
    return re.sub(r"^hexapod-kin: (error: |not achieved: )?", "", lines[-1])[:300]


def run_cell(robot: Robot, cell: str, where: Path, fetched_dir: Path) -> tuple[int, str]:
    """Run one cell from ``where`` (a folder of its own); (exit status, one-line reason)."""
    key = (robot.name, cell)
    if key not in _RESULTS:
        source = str(_fetch(robot, fetched_dir) if robot.fetched else DATA / robot.source)
        argv = [sys.executable, "-m", "hexapod_kin", *_argv(robot, source, cell)]
        try:
            done = subprocess.run(
                argv, cwd=where, capture_output=True, text=True, timeout=CELL_TIMEOUT
            )
            _RESULTS[key] = (done.returncode, _reason(done.stderr) if done.returncode else "")
        except subprocess.TimeoutExpired:
            _RESULTS[key] = (-1, f"no answer within {CELL_TIMEOUT} s")
    return _RESULTS[key]


def _params() -> list[object]:
    out = []
    for robot in ROBOTS:
        for cell in _cells(robot):
            marks = [pytest.mark.network] if robot.fetched else []
            if (robot.name, cell) in KNOWN:
                marks.append(pytest.mark.xfail(strict=False, reason=KNOWN[robot.name, cell]))
            out.append(pytest.param(robot, cell, marks=marks, id=f"{robot.name}:{cell}"))
    return out


# ------------------------------------------------------------------------ the tests
@pytest.mark.slow
@pytest.mark.parametrize(("robot", "cell"), _params())
def test_cell(robot: Robot, cell: str, tmp_path: Path, fetched_dir: Path) -> None:
    status, why = run_cell(robot, cell, tmp_path, fetched_dir)
    assert status == 0, f"{robot.name}: {cell}: exit {status}: {why}"


@pytest.mark.slow
def test_unstable_patterns_refused_with_reason(tmp_path: Path, fetched_dir: Path) -> None:
    """A shipped quadruped's trot and pace: exit 1 from the open-loop planner, saying why."""
    robot = next(r for r in ROBOTS if r.name == "MIT Mini Cheetah")
    for pattern in ("trot", "pace"):
        status, why = run_cell(robot, f"gait {pattern}", tmp_path, fetched_dir)
        _RESULTS.pop((robot.name, f"gait {pattern}"))  # not a cell of the table
        assert status == 1, (pattern, status, why)
        assert "statically stable" in why and "balance controller" in why, why


def test_robots_cover_the_issue() -> None:
    """8 robots or more from outside the project: 3+ hexapods, 4+ quadrupeds; each shipped
    one has its licence and a README naming its origin."""
    assert len(ROBOTS) >= 8
    assert sum(r.legs == 6 for r in ROBOTS) >= 3 and sum(r.legs == 4 for r in ROBOTS) >= 4
    for robot in ROBOTS:
        if robot.fetched:
            continue
        folder = DATA / robot.source.split("/")[0]
        assert (DATA / robot.source).is_file()
        assert (folder / "LICENSE").is_file() or "package.xml" in robot.licence
        assert robot.origin in (folder / "README.md").read_text()
    text = (DATA / "mini_cheetah" / "mini_cheetah.urdf").read_text()
    assert 'type="continuous"' in text and 'type="revolute"' not in text


def table_markdown(rows: dict[tuple[str, str], tuple[int, str]], robust: bool) -> str:
    """The page's table: one row per robot, one column per command (exit status)."""
    sim = "simulate --robust" if robust else "simulate (--robust pending)"
    lines = [
        "| robot | legs | licence | options | stand | gait (each pattern) | "
        f"{sim} | timeline gait | gait --html |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    reasons: list[str] = []

    def cell(robot: Robot, name: str, label: str = "") -> str:
        status, why = rows.get((robot.name, name), (None, "not run"))
        mark = "–" if status is None else str(status)
        if status not in (0, None):
            reasons.append(f"{len(reasons) + 1}. {robot.name}, `{name}`: exit {status}: {why}")
            return f"{label}{mark} [{len(reasons)}]"
        return f"{label}{mark}"

    for robot in ROBOTS:
        gaits = ", ".join(cell(robot, f"gait {p}", f"{p} ") for p in PATTERNS[robot.legs])
        opts = " ".join(f"`{shlex.quote(o)}`" for o in robot.options()) or "–"
        if robot.feet:
            opts = f"`--foot` ({len(robot.feet)} feet)" + (
                f" `--inertia={robot.inertia}`" if robot.inertia else ""
            )
        lines.append(
            f"| [{robot.name}](https://github.com/{robot.origin}) | {robot.legs} | "
            f"{robot.licence} | {opts} | {cell(robot, 'stand')} | {gaits} | "
            f"{cell(robot, 'simulate')} | {cell(robot, 'timeline gait')} | "
            f"{cell(robot, 'gait --html')} |"
        )
    return "\n".join(lines) + "\n\nWhy a cell is not 0:\n\n" + "\n".join(reasons or ["none"])


@pytest.mark.slow
@pytest.mark.network
def test_table_page(tmp_path: Path, fetched_dir: Path) -> None:
    """Every cell run (the network robots too), the table written between the page's markers."""
    for robot in ROBOTS:
        for cell in _cells(robot):
            where = tmp_path / f"{robot.name}-{cell}".replace(" ", "_")
            where.mkdir()
            run_cell(robot, cell, where, fetched_dir)
    page = PAGE.read_text()
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    new = f"{head}{BEGIN}\n{table_markdown(_RESULTS, _robust())}\n{END}{tail}"
    if new != page:
        PAGE.write_text(new)
    failing = sorted(k for k, (status, _) in _RESULTS.items() if status != 0)
    assert set(failing) <= set(KNOWN), f"cells failing that are not known: {failing}"


def test_absurd_inertias_flagged_and_repaired() -> None:
    """SpotMicroAI's kind of inertia (100 kg m^2 on 0.05 kg: a radius of gyration of
    sqrt(100 / 0.05) = 44.72 m on a 0.1 m robot) is flagged; ``inertia="point"`` repairs it."""
    import warnings

    import hexapod_kin as hk

    path = ROOT / "tests" / "urdf_corpus" / "inertia_gyration.urdf"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = hk.load(path)
    assert [d for d in model.inertia_defects if "44.72 m" in d[1] and d[0] == "arm"]
    assert any("radius of gyration" in str(w.message) for w in caught)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        repaired = hk.load(path, inertia="point")
    assert not repaired.inertia_defects
    assert not any("radius of gyration" in str(w.message) for w in caught)
    inertia = repaired.model.inertias[1]
    assert inertia.mass == pytest.approx(0.05)
    assert inertia.inertia[2, 2] == pytest.approx(0.4 * 0.05 * 0.01**2)  # 2 m r^2 / 5, r = 1 cm


def test_jacobian_of_a_legged_urdf_names_its_leg(capsys: pytest.CaptureFixture[str]) -> None:
    """``jacobian`` of a legged URDF says whose columns it prints (the first limb's end)."""
    import json

    import numpy as np

    import hexapod_kin as hk
    from hexapod_kin.cli import main

    source = str(DATA / "kraby" / "hexapod.urdf")
    assert main(["jacobian", source]) == 0
    out = capsys.readouterr().out
    assert out.startswith("J of frame 'endcap_0' (the first of 6 limbs' ends, --tip picks another)")
    assert main(["jacobian", source, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["tip"] == "endcap_0"
    jac, q = np.asarray(got["jacobian"]), dict(zip(got["joint_names"], got["q"]))
    for tip, nonzero in (("endcap_0", True), ("endcap_3", False)):
        leg = hk.load(source, tip=tip)  # the one limb, built by Pinocchio on its own
        cols = [got["joint_names"].index(n) for n in leg.joint_names]
        ref = leg.jacobian([q[n] for n in leg.joint_names], "local_world_aligned")
        if nonzero:  # the printed columns are this leg's Jacobian ...
            np.testing.assert_allclose(jac[:, cols], ref, atol=1e-12)
        else:  # ... and no other leg moves the printed tip
            assert np.abs(jac[:, cols]).max() == 0.0 and np.abs(ref).max() > 0.01


def test_stick_figure_where_meshes_are_missing() -> None:
    """A robot copied without its meshes is drawn as sticks from joint to joint (to the foot,
    or to the centre of mass of a last link), each stick as long as the model's offset."""
    import warnings

    import numpy as np

    import hexapod_kin as hk
    from hexapod_kin.viewer.scene import Scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = hk.load(DATA / "mini_cheetah" / "mini_cheetah.urdf")
    scene = Scene(model)
    sticks = [g for g in scene.geom.geometryObjects if g.name.startswith("stick_")]
    assert len(scene.visuals) == len(sticks) == 16  # base to 4 hips, 3 links per leg
    m = model.model
    for go in sticks:
        length = 2.0 * go.geometry.halfLength
        end = go.placement.translation * 2.0  # centred on the segment
        assert length == pytest.approx(float(np.linalg.norm(end)))
        axis = go.placement.rotation[:, 2]
        np.testing.assert_allclose(axis * length, end, atol=1e-12)
    lengths = sorted(round(2.0 * g.geometry.halfLength, 6) for g in sticks)
    thigh = float(
        np.linalg.norm(m.jointPlacements[m.getJointId("thigh_fl_to_knee_fl_j")].translation)
    )
    shank_com = float(np.linalg.norm(m.inertias[m.getJointId("thigh_fl_to_knee_fl_j")].lever))
    assert thigh == pytest.approx(0.209) and shank_com == pytest.approx(0.209)
    assert lengths.count(round(thigh, 6)) == 8  # 4 thighs, 4 shanks (to their centre of mass)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        drawn = Scene(hk.load("hexabot_leg"))
    assert not [g for g in drawn.geom.geometryObjects if g.name.startswith("stick_")]
