"""The wheel installs one import package, ``amigo_gym``, with the pretrained models as package data."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> zipfile.ZipFile:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(out), str(ROOT)],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (whl,) = out.glob("*.whl")
    return zipfile.ZipFile(whl)


def test_wheel_has_one_top_level_package(wheel: zipfile.ZipFile) -> None:
    tops = {n.split("/")[0] for n in wheel.namelist() if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"amigo_gym"}


def test_wheel_lists_every_subpackage(wheel: zipfile.ZipFile) -> None:
    """Every folder of amigo_gym/ with an __init__.py is in the wheel (pyproject lists packages by hand)."""
    names = set(wheel.namelist())
    for init in (ROOT / "amigo_gym").rglob("__init__.py"):
        rel = init.relative_to(ROOT).as_posix()
        assert rel in names, f"{rel} missing from the wheel: add its package to [tool.setuptools] packages"


def test_wheel_ships_agents_data(wheel: zipfile.ZipFile) -> None:
    """Every file of the repository's agents/ (hyperparameters, pretrained models, manifests) is package data."""
    names = set(wheel.namelist())
    for f in (ROOT / "agents").rglob("*"):
        if f.is_file() and f.suffix in (".zip", ".json", ".yml"):
            rel = "amigo_gym/agents/" + f.relative_to(ROOT / "agents").as_posix()
            assert rel in names, f"{rel} missing from the wheel"
