"""The README's promises: its first commands, .ci/run calling the same test command, and every
Python example running as written."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
BLOCKS = re.findall(r"```python\n(.*?)```", README, re.S)


def test_readme_first_block_and_ci_agree():
    block = README.split("```bash\n", 1)[1].split("```", 1)[0].strip().splitlines()
    assert len(block) == 2
    demo, tests = block
    assert "'.[viewer,plots]'" in demo and demo.endswith("hexapod-kin reproduce --out report")
    assert "pytest" in tests
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert tests in ci


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_examples_run(index, tmp_path):
    os.symlink(ROOT / "examples", tmp_path / "examples")
    run = subprocess.run(
        [sys.executable, "-c", BLOCKS[index]],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
