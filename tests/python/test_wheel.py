"""The installed wheel is portable and says what it is (issue 19: it was tagged
manylinux_2_35 — symbols up to GLIBC_2.35, so no install on RHEL 8/9, Debian 11 or Ubuntu
20.04 — and its metadata had no license or readme and a placeholder repository URL)."""
import importlib.metadata
import os
import pathlib
import re

import pytest

import qrm

DIST = importlib.metadata.distribution("qrm-robotics")


def test_the_wheel_is_tagged_for_old_glibc():
    expected = os.environ.get("QRM_WHEEL_TAG")
    if not expected:
        pytest.skip("QRM_WHEEL_TAG not set (scripts/test sets it for the wheel it builds)")
    tags = [line.split(": ", 1)[1] for line in DIST.read_text("WHEEL").splitlines() if line.startswith("Tag: ")]
    assert tags and all(expected in t or "manylinux2014" in t for t in tags), tags


def test_the_native_module_needs_no_glibc_newer_than_its_tag():
    """The symbol versions the module asks for (read from its ELF dynamic symbol table
    strings) are at most 2.17 when the tag says so."""
    expected = os.environ.get("QRM_WHEEL_TAG")
    if not expected:
        pytest.skip("QRM_WHEEL_TAG not set")
    wanted = tuple(int(x) for x in re.search(r"manylinux_(\d+)_(\d+)", expected).groups())
    so = next(pathlib.Path(qrm.__file__).parent.glob("_qrm*.so"))
    versions = {tuple(int(x) for x in v.split(b".")) for v in re.findall(rb"GLIBC_(\d+\.\d+)", so.read_bytes())}
    assert versions and max(versions) <= wanted, sorted(versions)[-3:]


def test_the_metadata_names_license_readme_and_authors():
    meta = DIST.metadata
    assert meta["License-Expression"] == "MIT OR Apache-2.0"
    assert "Qualitative relational maps" in (meta.get_payload() or "")
    assert meta["Author"] or meta["Author-email"]
    text = DIST.read_text("METADATA") or ""
    assert "example.invalid" not in text
