"""Compiles every kernel for a real GPU (to PTX) without one: numba's CUDA typing and NVVM see
the code the simulator only interprets. `python -m particlebot.sim.world.cuda.ptx` (needs
NVVM, which numba-cuda's CUDA packages bring; not the simulator)."""

from __future__ import annotations

import sys
from typing import Any

import numba
import numpy as np

ARCH = (9, 0)
"""Compute capability compiled for (Hopper; any recent one checks the same typing)."""


def signatures(ftype: type[np.floating[Any]]) -> dict[str, tuple[Any, ...]]:
    """Each kernel's argument types, as DeviceSwarms launches it, for velocities in ftype."""
    i64 = np.zeros(2, dtype=np.int64)
    i32 = np.zeros(2, dtype=np.int32)
    f2 = np.zeros((2, 2))
    rows = np.zeros((2, 2), dtype=ftype)
    flags = np.zeros((2, 2), dtype=np.uint8)
    pushes = np.zeros((2, 1, 2))
    n = 1
    t = numba.typeof
    return {
        "kinematics": (t(n), t(n), t(f2), t(i64), t(i64), t(i32), t(f2), t(rows), t(rows),
                       t(flags), t(f2), t(f2), t(np.zeros(2))),
        "count_cells": (t(n), t(f2), t(i32), t(f2), t(i64), t(i64), t(i64), t(i64), t(i32)),
        "scan_tiles": (t(n), t(i32), t(i64), t(i64)),
        "scan_tiles_up": (t(n), t(i64), t(i64), t(i64)),
        "add_offsets": (t(n), t(i64), t(i64)),
        "set_end": (t(i64), t(n), t(i64)),
        "clear": (t(n), t(i32)),
        "scatter": (t(n), t(i64), t(i64), t(i32), t(i64)),
        "order_cells": (t(n), t(i64), t(i64)),
        "pairs": (t(n), t(f2), t(rows), t(rows), t(flags), t(i32), t(f2), t(i64), t(i64),
                  t(i64), t(i64), t(i64), t(i64)),
        "settle": (t(n), t(f2), t(rows), t(rows), t(i32), t(f2), t(f2), t(i64), t(i64), t(f2),
                   t(i64), t(i64), t(f2), t(i64), t(i64), t(pushes)),
        "objects_move": (t(n), t(f2), t(i64), t(i64), t(f2)),
        "objects_settle": (t(n), t(f2), t(i64), t(i64), t(i64), t(i64), t(pushes), t(f2),
                           t(f2), t(i64), t(i64), t(f2), t(i64), t(i64), t(f2)),
    }  # fmt: skip


class _Hopper:
    """Stands in for the current device where numba-cuda asks for one while compiling a device
    function (only its compute capability is read)."""

    compute_capability = ARCH


def main() -> int:
    from numba import cuda
    from numba.cuda import dispatcher

    from particlebot.sim.world.cuda import kernels as ck

    dispatcher.get_current_device = _Hopper  # no driver needed

    for ftype in (np.float64, np.float32):
        for name, signature in signatures(ftype).items():
            kernel = getattr(ck, name.removesuffix("_up"))
            try:
                cuda.compile_ptx(kernel.py_func, signature, cc=ARCH)
            except Exception as exc:  # a typing or NVVM error: name the kernel, then fail
                print(f"{name} ({np.dtype(ftype).name}): {type(exc).__name__}: {exc}")
                return 1
    print(f"every kernel compiles to PTX for sm_{ARCH[0]}{ARCH[1]}, float64 and float32")
    return 0


if __name__ == "__main__":
    sys.exit(main())
