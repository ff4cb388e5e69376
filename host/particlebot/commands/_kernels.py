"""The simulator's kernels made ready before a command's own work: when numba's cache does not
hold them, the command says so and compiles them under a progress line of their own, so that
its run's progress bar and ETA start after the compile instead of counting it."""

from __future__ import annotations

import sys
import time
from typing import TextIO

from particlebot.progress import ProgressBar


def prepare_kernels(stream: TextIO | None = None, force: bool = False) -> bool:
    """Compiles the kernels when the cache lacks them (always with force); whether it did."""
    from particlebot.sim.warmup import COMPILE_USUAL_S, cache_folder, kernels_cached, warm_up

    out = stream if stream is not None else sys.stderr
    if not force and kernels_cached():
        return False
    print(
        f"compiling the simulator's kernels (once, about {COMPILE_USUAL_S:.0f} s)",
        file=out,
        flush=True,
    )
    began = time.monotonic()
    bar = ProgressBar("compiling", 1, unit="stages", stream=out)
    bar.start(show_now=False)  # its first line comes with the first stage, which gives the total
    try:

        def report(done: int, total: int, stage: str) -> None:
            bar.total = total
            bar.update(done, stage)

        warm_up(report)
    finally:
        bar.finish()
    print(
        f"kernels compiled in {time.monotonic() - began:.0f} s, cached in {cache_folder()}",
        file=out,
        flush=True,
    )
    return True
