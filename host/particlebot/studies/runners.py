"""Who executes a run on a worker: the simulator through the seam, or a stand-in in tests."""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Protocol

from particlebot.studies.spec import RunRecord, RunSpec, ShareDone, SimOutcome, describe


class Runner(Protocol):
    """Turns a spec into an outcome on a worker. Must pickle small: Dask sends it with each run."""

    @property
    def name(self) -> str:
        """Recorded in each result: a resumed study only counts results its own runner made."""

    def warm_up(self) -> None:
        """Called once in every worker process before its first run (and the client's, for a
        local cluster): compile what needs compiling."""

    def __call__(self, spec: RunSpec, progress: ShareDone | None = None) -> SimOutcome: ...


@dataclass(frozen=True)
class SimulatorRunner:
    """The real thing: every run through seam.run_one."""

    run_folders: Path | None = None
    """Keep each run's CSV and snapshots in run_folders/RUN_ID (a path every worker can write)."""
    device: str = "cpu"
    """Where each run's world steps (World's device): "cuda" gives every run the worker's GPU
    (the one CUDA_VISIBLE_DEVICES shows it)."""

    @property
    def name(self) -> str:
        return "simulator"

    def warm_up(self) -> None:
        from particlebot.studies import seam  # numba and the world: only where runs happen

        seam.warm_up()

    def __call__(self, spec: RunSpec, progress: ShareDone | None = None) -> SimOutcome:
        import numba

        from particlebot.studies import seam

        folder = None if self.run_folders is None else self.run_folders / spec.run_id
        # One thread per run, set here in the thread that runs it (numba's count is per thread):
        # a study runs a process per core, and a worker whose numba started with a thread per
        # core (it reads NUMBA_NUM_THREADS once, at import, and a spawned worker imports the
        # CLI, so numba, before Dask applies the cluster's environment) made 10,000-particle
        # runs ten times slower, every core's threads fighting over it.
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            return seam.run_one(spec, folder, progress, self.device)
        finally:
            numba.set_num_threads(threads)


def execute(runner: Runner, spec: RunSpec, progress: ShareDone | None = None) -> RunRecord:
    """The task a worker runs: simulate, measure there (only numbers and the short centroid track
    travel back, never particle arrays), and stamp who did it. progress hears how far the run is
    (the engine passes one that reports to the client)."""
    start = time.perf_counter()
    outcome = runner(spec, progress)
    return record_of(runner.name, spec, outcome, time.perf_counter() - start)


def record_of(runner: str, spec: RunSpec, outcome: SimOutcome, wall_s: float) -> RunRecord:
    """A run's result as the store keeps it: measured, stamped with who made it and where."""
    metrics = spec.measure.evaluate(spec.setup, outcome)
    return RunRecord(
        run_id=spec.run_id,
        study=spec.study,
        cell=spec.cell_dict,
        seed=spec.seed,
        runner=runner,
        metrics=metrics,
        summary=dict(outcome.summary),
        track=outcome.track.to_json(),
        setup=asdict(spec.setup),
        measure=describe(spec.measure),
        wall_s=wall_s,
        worker=_worker_address(),
        pid=os.getpid(),
    )


def _worker_address() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return "local"
