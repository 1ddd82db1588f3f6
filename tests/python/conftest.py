"""Shared fixtures: where the workspace, the `qrm` binary and shared/ are."""
import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def qrm_bin() -> str:
    """The CLI built from this checkout (release if present, else debug, else built now)."""
    explicit = os.environ.get("QRM_BIN")
    if explicit:
        return explicit
    for profile in ("release", "debug"):
        exe = ROOT / "target" / profile / "qrm"
        if exe.exists():
            return str(exe)
    subprocess.run(["cargo", "build", "-q"], cwd=ROOT, check=True)
    return str(ROOT / "target" / "debug" / "qrm")


@pytest.fixture(scope="session")
def mrclam_dir() -> pathlib.Path:
    d = ROOT.parent / "shared" / "data" / "mrclam-dataset7"
    if not d.is_dir():
        pytest.skip("shared/data/mrclam-dataset7 not found beside the checkout")
    return d


@pytest.fixture()
def tmpdir_path(tmp_path: pathlib.Path) -> pathlib.Path:
    return tmp_path


def have(tool: str) -> bool:
    return shutil.which(tool) is not None
