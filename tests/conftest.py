"""Shared fixtures. ``shared_data`` points at ../shared/data (real recordings, reference
values); CI always has it, so there a missing folder is a failure, never a skip."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

SHARED_DATA = (Path(__file__).resolve().parents[1] / ".." / "shared" / "data").resolve()


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"{SHARED_DATA} is missing in CI")
        pytest.skip(f"{SHARED_DATA} not available outside CI")
    return SHARED_DATA
