"""Session hooks of the whole suite: the simulator's kernels compiled before the first test, when
numba's cache lacks them, so that no test's timeout counts a compile (minutes on a loaded
machine) and the suite says what it is doing meanwhile."""

from __future__ import annotations

import sys

import pytest


def pytest_collection_finish(session: pytest.Session) -> None:
    # Collection imported every selected test module: the simulator is among their imports
    # exactly when a selected test may step a world.
    if not any(name.startswith("particlebot.sim.world") for name in sys.modules):
        return
    from particlebot.commands._kernels import prepare_kernels
    from particlebot.sim.warmup import kernels_cached

    if kernels_cached():
        return
    capture = session.config.pluginmanager.getplugin("capturemanager")
    if capture is None:
        prepare_kernels(sys.stderr)
        return
    with capture.global_and_fixture_disabled():
        prepare_kernels(sys.stderr)
