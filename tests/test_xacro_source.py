"""ROS xacro sources expanded without ROS: ``$(find PKG)`` from ``package_dirs`` entries."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

import hexapod_kin as hk
from hexapod_kin.exceptions import SourceError
from hexapod_kin.sources import resolve_source

DATA = Path(__file__).resolve().parent / "data"
HEXA = DATA / "hexa" / "hexa_description"
XACRO = Path("urdf") / "hexapod.urdf.xacro"


def test_find_resolves_from_the_folder_above_and_name_equals_path(tmp_path: Path) -> None:
    """The package found above the file, or given as NAME=PATH under another folder name,
    gives the same URDF; its dimensions come from the YAML read through $(find)."""
    import numpy as np
    import yaml

    above = resolve_source(HEXA / XACRO)
    moved = tmp_path / "elsewhere"
    shutil.copytree(HEXA, moved)
    named = resolve_source(moved / XACRO, package_dirs=[f"hexa_description={moved}"])
    assert above.text == named.text
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = hk.load(HEXA / XACRO).model
    assert model.nv == 18
    geometry = yaml.safe_load((HEXA / "config" / "geometry.yaml").read_text())
    knee = model.jointPlacements[model.getJointId("l_rear_tibia_joint")].translation
    assert float(np.linalg.norm(knee)) == pytest.approx(float(geometry["leg"]["femur_length"]))


def test_missing_package_is_one_clear_error(tmp_path: Path) -> None:
    moved = tmp_path / "pkg"
    shutil.copytree(HEXA, moved)  # folder not named hexa_description: $(find) cannot find it
    with pytest.raises(SourceError, match=r"\$\(find hexa_description\).*--package-dir "):
        resolve_source(moved / XACRO)
    with pytest.raises(SourceError, match="is not a directory"):
        resolve_source(moved / XACRO, package_dirs=["hexa_description=/no/such/folder"])


def test_xacro_loads_a_walking_robot() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        wb = hk.gait.as_whole_body(HEXA / XACRO)
    assert wb.n_legs == 6
