"""Shared fixtures. ``shared_data`` points at ../shared/data (real recordings, reference
values); CI always has it, so there a missing folder is a failure, never a skip."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings

# Hypothesis profiles: ``ci`` (loaded when the environment variable CI is set) is derandomized
# (a fixed seed, so a CI failure reproduces locally with CI=1) and runs about 25 examples per
# test with no per-example deadline, which keeps the property/fuzz layer within its time budget
# on shared runners; ``dev`` is Hypothesis' default randomized search, also without a deadline
# (our examples call into numerics whose first call compiles or loads data).
settings.register_profile("ci", derandomize=True, max_examples=25, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

SHARED_DATA = (Path(__file__).resolve().parents[1] / ".." / "shared" / "data").resolve()


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"{SHARED_DATA} is missing in CI")
        pytest.skip(f"{SHARED_DATA} not available outside CI")
    return SHARED_DATA
