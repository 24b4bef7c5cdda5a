"""The default run's file order (conftest's ``LONGEST_FIRST``) names files that exist."""

from __future__ import annotations

from pathlib import Path

from conftest import LONGEST_FIRST


def test_longest_first_names_existing_test_files_once() -> None:
    here = Path(__file__).resolve().parent
    assert len(set(LONGEST_FIRST)) == len(LONGEST_FIRST)
    missing = [name for name in LONGEST_FIRST if not (here / name).is_file()]
    assert not missing, f"conftest.LONGEST_FIRST names files that are gone: {missing}"
