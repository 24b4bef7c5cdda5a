"""Every code block of docs/getting-started.md and docs/guide/*.md runs as written.

Each page runs in a fresh folder of its own (the cwd), holding copies of the clone's
``examples/`` and ``tests/data/`` (the pages name them from a clone's root). In order:

* a block whose first line is a comment naming a file (``# cal.yaml: ...``) is written to
  that file (YAML, TOML, JSON and CSV examples the other blocks use);
* the page's ``python`` blocks run one after the other in one interpreter (one namespace);
* every line of its ``bash`` blocks runs: ``hexapod-kin ARGS`` as ``python -m hexapod_kin
  ARGS`` and must exit 0; install lines (``pip``, ``python3 -m venv``, ``python3 -m pip``)
  are not run, and none may install ``hexapod-kin`` from PyPI (it is not there).
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "docs" / "getting-started.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]
BLOCK = re.compile(r"^```([\w-]*)\n(.*?)^```", re.S | re.M)
FILE_LINE = re.compile(r"^# ([\w.-]+\.(?:yaml|yml|toml|json|csv))\b")
INSTALL = re.compile(r"^(pip|\S*/pip|python3? -m (venv|pip|build)\b|\S*python3? -m (venv|pip))")
#: CPU-heavy pages get this many seconds per command before failing.
TIMEOUT = 900


def blocks(page: Path) -> list[tuple[str, str]]:
    """The page's fenced blocks: (language, text)."""
    return [(lang, body) for lang, body in BLOCK.findall(page.read_text())]


def commands(text: str) -> list[str]:
    """A bash block's command lines (``\\`` continuations joined, comments and blanks out)."""
    joined = re.sub(r"\\\n\s*", " ", text)
    out = []
    for line in joined.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            out.append(line)
    return out


def _ids(page: Path) -> str:
    return str(page.relative_to(ROOT / "docs"))


def test_no_install_from_pypi() -> None:
    """No page's first command installs a package that PyPI does not have."""
    for page in [*PAGES, ROOT / "docs" / "index.md"]:
        for lang, body in blocks(page):
            for line in commands(body) if lang in ("bash", "sh", "console") else []:
                assert not re.search(r"pip install ['\"]?hexapod[-_]kin", line), (page, line)


def test_no_page_names_a_file_it_does_not_give() -> None:
    """A file a command reads (``--calibration X``, a plan) is written by a block of its page."""
    for page in PAGES:
        given = {m.group(1) for _, b in blocks(page) if (m := FILE_LINE.match(b))}
        for lang, body in blocks(page):
            if lang != "bash":
                continue
            for line in commands(body):
                for name in re.findall(r"--calibration\s+(\S+)", line):
                    assert name in given, (page.name, line)


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES, ids=_ids)
def test_page_runs(page: Path, tmp_path: Path) -> None:
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    shutil.copytree(ROOT / "tests" / "data", tmp_path / "tests" / "data")
    found = blocks(page)
    for _, body in found:
        m = FILE_LINE.match(body)
        if m:
            (tmp_path / m.group(1)).write_text(body)
    python = [body for lang, body in found if lang == "python"]
    if python:
        script = "\n".join(
            f"exec(compile({body!r}, '<{page.name} block {i}>', 'exec'))"
            for i, body in enumerate(python, 1)
        )
        done = subprocess.run(
            [sys.executable, "-c", script],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
        )
        assert done.returncode == 0, f"{page.name}: python blocks: {done.stderr[-2000:]}"
    for lang, body in found:
        if lang != "bash":
            continue
        for line in commands(body):
            if INSTALL.match(line):
                continue
            argv = shlex.split(line, comments=True)
            assert argv[0] == "hexapod-kin", f"{page.name}: a command the test cannot run: {line}"
            if argv[1] in SERVERS:
                _serves_until_ctrl_c(page, line, [sys.executable, "-m", "hexapod_kin", *argv[1:]])
                continue
            done = subprocess.run(
                [sys.executable, "-m", "hexapod_kin", *argv[1:]],
                cwd=tmp_path,
                capture_output=True,
                text=True,
                timeout=TIMEOUT,
            )
            assert done.returncode == 0, f"{page.name}: `{line}`: {done.stderr[-1500:]}"


#: Commands that serve until Ctrl-C: they must come up (address printed) and end with 130.
SERVERS = ("view", "drive")


def _serves_until_ctrl_c(page: Path, line: str, argv: list[str]) -> None:
    import signal
    import time

    env = {**__import__("os").environ, "BROWSER": "true"}  # no browser opened by the test
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    deadline = time.monotonic() + TIMEOUT  # guards a hang only (never a speed)
    out = ""
    while time.monotonic() < deadline and "127.0.0.1" not in out and proc.poll() is None:
        out += proc.stdout.readline()  # type: ignore[union-attr]
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=TIMEOUT)
    assert "127.0.0.1" in out, f"{page.name}: `{line}`: {out} {err}"
    assert proc.returncode in (130, -signal.SIGINT), f"{page.name}: `{line}`: {err}"
