"""Shared test settings: hypothesis profiles picked by HYPOTHESIS_PROFILE, the requires_spin marker."""

from __future__ import annotations

import os
import shutil

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile("dev", max_examples=60, deadline=None)
settings.register_profile("ci", max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow],
                          print_blob=True, derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "dev"))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip tests marked requires_spin when spin or gcc is missing (CI installs both)."""
    missing = [tool for tool in ("spin", "gcc") if shutil.which(tool) is None]
    if not missing:
        return
    skip = pytest.mark.skip(reason=f"requires {' and '.join(missing)} (apt-get install spin gcc)")
    for item in items:
        if "requires_spin" in item.keywords:
            item.add_marker(skip)
