"""Which backend a World runs on: "cpu", "cuda", or "auto" (CUDA when a real GPU is present)."""

from __future__ import annotations

import ctypes.util
import os
from typing import Literal

from particlebot.devices import DEVICES, Device, DeviceError

__all__ = ["DEVICES", "Device", "DeviceError", "gpu_present", "simulated", "use_simulator"]


def simulated() -> bool:
    """Whether numba-cuda runs its simulator (NUMBA_ENABLE_CUDASIM=1): kernels then run as Python
    on the CPU, right but slow."""
    return os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


def use_simulator() -> bool:
    """Switches numba-cuda to its simulator, for tests and smoke runs without a GPU; only
    possible before anything imports numba.cuda (numba read its environment at import, hence
    the reload). Returns whether the simulator is on."""
    import sys

    if "numba.cuda" not in sys.modules:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
        from numba.core import config

        config.reload_config()
    return simulated()


def gpu_present() -> bool:
    """Whether a real CUDA GPU can be used (never true in the simulator)."""
    if simulated():
        return False
    # Without the driver's library there is no GPU: answered without importing numba.cuda
    # (seconds, which every `simulate --device auto` would pay).
    if ctypes.util.find_library("cuda") is None and ctypes.util.find_library("nvcuda") is None:
        return False
    try:
        from numba import cuda

        return bool(cuda.is_available())
    except Exception:  # a missing or broken driver means no GPU, whatever it raises
        return False


def resolve(device: str) -> Literal["cpu", "cuda"]:
    """The backend for a request: "auto" takes CUDA only when a real GPU is present; "cuda"
    takes it when a GPU or the simulator is there, else DeviceError."""
    if device not in DEVICES:
        raise DeviceError(f"device must be one of {', '.join(DEVICES)}, not {device!r}")
    if device == "cpu":
        return "cpu"
    if device == "auto":
        return "cuda" if gpu_present() else "cpu"
    if simulated() or gpu_present():
        return "cuda"
    raise DeviceError(
        "no CUDA GPU here (numba.cuda.is_available() is False); use --device cpu, or set "
        "NUMBA_ENABLE_CUDASIM=1 to run the CUDA kernels in numba-cuda's simulator (slow)"
    )
