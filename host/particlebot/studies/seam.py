"""The one place the studies touch the simulator: a run's setup in, its outcome out."""

from __future__ import annotations

import importlib.util
from pathlib import Path

from particlebot.studies.spec import RunSpec, SimOutcome

SIMULATOR_MODULE = "particlebot.sim.world"


class SimulatorUnavailableError(RuntimeError):
    """The simulator (issue 7) is not in this build, or this seam does not call it yet."""


def check_simulator() -> None:
    """Raises SimulatorUnavailableError, with the reason in one line, unless run_one can work."""
    if importlib.util.find_spec(SIMULATOR_MODULE) is None:
        raise SimulatorUnavailableError(
            f"the simulator ({SIMULATOR_MODULE}, issue 7) is not in this build yet, so studies "
            "cannot run; nothing was run"
        )
    raise SimulatorUnavailableError(
        f"the simulator ({SIMULATOR_MODULE}) is installed but particlebot.studies.seam does not "
        "call it yet; nothing was run"
    )


def warm_up() -> None:
    """Compiles (or loads from numba's on-disk cache) the simulator's kernels in this process, so
    that the first run a worker gets is not also the one that pays for compilation.

    To be filled when the simulator lands: simulate a tiny scenario (a few particles, a few steps)
    with the kernels' cache=True, so that the compiled code lands in the shared cache once and
    every later process loads it.
    """
    check_simulator()


def run_one(spec: RunSpec, run_dir: Path | None = None) -> SimOutcome:
    """Simulates spec.setup and returns what the study's measure needs.

    run_dir: where the run keeps the published CSV and its npz snapshots (a path every worker can
    write, to keep them, and so that a retried run resumes from its last snapshot); None: a
    temporary folder, removed afterwards.

    To be filled when the simulator lands (the whole adapter lives here):
      1. build the simulator's scenario from spec.setup, field by field (WorldSetup mirrors it):
         place the swarm (placement, particles, seed), then shift the lamp, obstacles, passive
         object and free-particle region by the placement's centroid (the setup's frame has its
         origin there) and check that the obstacles do not cut into the placement;
      2. run it for setup.duration_s with the CSV every setup.dump_interval_s, into run_dir;
      3. return SimOutcome: the CSV's Time, Centroid X/Y, Distance columns (shifted back to the
         study frame), the final positions of every particle, the passive object's first and
         last position, and the simulator's summary (steps, wall_s, ...).
    """
    check_simulator()
    raise AssertionError("unreachable")  # pragma: no cover
