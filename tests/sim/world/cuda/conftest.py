"""The CUDA backend's tests run in numba-cuda's simulator: switched on here, before anything
imports numba.cuda."""

from __future__ import annotations

import pytest

from particlebot.sim.world.cuda.device import use_simulator

use_simulator()


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Without the simulator (numba.cuda already imported for a real GPU) the tests still run,
    on the GPU; with neither, they are skipped."""
    from numba import cuda

    if not cuda.is_available():
        skip = pytest.mark.skip(reason="neither a CUDA GPU nor numba-cuda's simulator")
        for item in items:
            if "/cuda/" in str(item.fspath):
                item.add_marker(skip)
