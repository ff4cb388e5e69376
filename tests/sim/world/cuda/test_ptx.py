"""Every kernel compiles for a real GPU (PTX for sm_90, both precisions) without one: numba's
CUDA typing and NVVM check what the simulator only interprets."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

MISSING = ("DynamicLibNotFoundError", "NvvmSupportError", "NvrtcSupportError")


@pytest.mark.slow
def test_every_kernel_compiles_to_ptx() -> None:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    done = subprocess.run(
        [sys.executable, "-m", "particlebot.sim.world.cuda.ptx"],
        capture_output=True, text=True, env=env, timeout=600, check=False,
    )  # fmt: skip
    out = done.stdout + done.stderr
    if any(name in out for name in MISSING):
        pytest.skip("no NVVM / NVRTC here (numba-cuda's CUDA packages)")
    assert done.returncode == 0, out
    assert "every kernel compiles to PTX" in out
