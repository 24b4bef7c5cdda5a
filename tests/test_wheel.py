"""The wheel: built from a copy of the repository, installed in a fresh venv outside it, run there.

The venv sees the test environment's dependencies (a ``.pth`` file adds its site-packages
after the venv's own), never the repository: the wheel is installed in the venv's own
site-packages, the commands run from a temporary folder with no ``PYTHONPATH``, and the test
checks that ``hexapod_kin`` is imported from the venv.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


def _can_build() -> bool:
    import setuptools

    major, minor = (int(x) for x in setuptools.__version__.split(".")[:2])
    return (major, minor) >= (70, 1) or importlib.util.find_spec("wheel") is not None


def _env(tmp: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp / "cache")
    env["MPLBACKEND"] = "Agg"
    return env


def _parent_pth() -> str:
    """A .pth that adds the test environment's site-packages after the venv's own.

    The parent's own .pth files are replayed (e.g. Pinocchio's ``cmeel.pth``) except the
    editable install of hexapod_kin: its finder would serve ``hexapod_kin.*`` submodules
    from the repository.
    """
    lines: list[str] = []
    for parent in sorted({sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}):
        lines.append(parent)
        for pth in sorted(Path(parent).glob("*.pth")):
            if pth.name.startswith("__editable__") or "hexapod_kin" in pth.name:
                continue
            for line in pth.read_text().splitlines():
                if not line.strip() or line.startswith("#"):
                    continue
                if line.startswith(("import ", "import\t")):
                    lines.append(line)
                else:
                    lines.append(str((Path(parent) / line.strip()).resolve()))
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    if not _can_build():
        if os.environ.get("CI"):
            pytest.fail("building the wheel needs `wheel` (the test extra installs it)")
        pytest.skip("building the wheel offline needs the `wheel` package (test extra)")
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "CHANGELOG.md", "hexapod_kin"):
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, src / name,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))  # fmt: skip
        elif (ROOT / name).is_file():
            shutil.copy2(ROOT / name, src / name)
    dist = tmp / "dist"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(dist), str(src)],
        check=True, cwd=tmp, env=_env(tmp), capture_output=True,
    )  # fmt: skip
    (wheel,) = dist.glob("hexapod_kin-*.whl")
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    # install into the empty venv first (nothing else visible), then let it see the deps
    subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps",
         "--force-reinstall", "--no-index", "-q", str(wheel)],
        check=True, cwd=tmp, env=_env(tmp), capture_output=True,
    )  # fmt: skip
    site = Path(
        subprocess.run(
            [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            check=True, capture_output=True, text=True,
        ).stdout.strip()
    )  # fmt: skip
    (site / "zz_test_environment.pth").write_text(_parent_pth())
    return tmp, wheel, venv


def test_wheel_holds_every_data_file(installed):
    _, wheel, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    pkg = ROOT / "hexapod_kin"
    data = [
        p.relative_to(ROOT).as_posix()
        for p in pkg.rglob("*")
        if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts
    ]
    assert "hexapod_kin/py.typed" in data
    missing = [d for d in data if d not in names]
    assert not missing
    from hexapod_kin import __version__

    assert re.search(rf"hexapod_kin-{re.escape(__version__)}-py3-none-any\.whl$", wheel.name)
    meta = zipfile.ZipFile(wheel).read(f"hexapod_kin-{__version__}.dist-info/METADATA").decode()
    assert f"\nVersion: {__version__}\n" in meta


def test_reproduce_and_quick_tour_in_fresh_venv(installed):
    tmp, _, venv = installed
    py = venv / "bin" / "python"
    where = subprocess.run(
        [str(py), "-c", "import hexapod_kin; print(hexapod_kin.__file__)"],
        check=True, capture_output=True, text=True, cwd=tmp, env=_env(tmp),
    ).stdout.strip()  # fmt: skip
    assert Path(where).is_relative_to(venv), where
    out = tmp / "rep"
    done = subprocess.run(
        [str(venv / "bin" / "hexapod-kin"), "reproduce", "--quick", "--no-animations",
         "--out", str(out)],
        capture_output=True, text=True, cwd=tmp, env=_env(tmp),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert re.search(r"verdicts: \d+ claims checked", done.stdout), done.stdout
    assert (out / "report.html").is_file() and (out / "verdicts.json").is_file()
    readme = (ROOT / "README.md").read_text()
    tour = re.search(r"```python\n(.*?)```", readme, re.S)
    assert tour is not None
    script = tmp / "tour.py"
    script.write_text(
        tour.group(1) + "\nimport sys\nprint('from', *sorted({str(getattr(m, '__file__', None))"
        " for n, m in sys.modules.items() if n.split('.')[0] == 'hexapod_kin'}))\n"
    )
    done = subprocess.run(
        [str(py), str(script)], capture_output=True, text=True, cwd=tmp, env=_env(tmp)
    )
    assert done.returncode == 0, done.stderr[-2000:]
    files = done.stdout.split("from ", 1)[1].split()
    assert len(files) > 10 and all(Path(f).is_relative_to(venv) for f in files), files
