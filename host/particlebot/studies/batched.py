"""A study's runs as GPU ensembles: many runs' worlds stepped side by side in one launch.

`particlebot study ... --device cuda` without --scheduler comes here instead of the Dask engine:
the pending runs are opened (placed, or resumed from their run folders) on the CPU, grouped by
the steps they have left into batches of at most BATCH_PARTICLES particles, and each batch is
moved to the GPU as one Ensemble. Every run keeps its own folder, CSV observer, snapshots, seed
and controller; results are measured and stored as the Dask path stores them, under the same
runner name (the model is the same; the summary records the device). Ctrl-C stops between
chunks of steps: finished runs are kept, the batch's others start again next time (or resume
from their last periodic snapshot, with --run-folders).
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Sequence
from contextlib import ExitStack
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from particlebot.studies.engine import StudyOutcome, pending
from particlebot.studies.progress import Progress
from particlebot.studies.runners import record_of
from particlebot.studies.spec import RunSpec
from particlebot.studies.store import ResultStore

if TYPE_CHECKING:
    from particlebot.sim.runs.run import Run
    from particlebot.studies.seam import Framed

BATCH_PARTICLES = 2_000_000
"""Particles of one ensemble at most: Table S3's 10,000-particle row (99 runs, 990,000
particles) is one batch; a GPU of 16 GB holds it several times over (about 150 bytes a
particle with the grid and the commands buffered)."""
CHUNK_STEPS = 500
"""Steps between progress reports and between checks for Ctrl-C."""


def run_batched(
    specs: Sequence[RunSpec],
    store: ResultStore,
    runner_name: str,
    *,
    run_folders: Path | None = None,
    label: str = "study",
    stream: TextIO | None = None,
    batch_particles: int = BATCH_PARTICLES,
) -> StudyOutcome:
    """Runs what the results folder lacks as GPU ensembles (see the module's description)."""
    from particlebot.studies import seam

    store.prepare()
    finished, _ = store.load_finished(runner_name)
    todo = pending(specs, finished)
    outcome = StudyOutcome(total=len({spec.run_id for spec in specs}), reused=0)
    outcome.reused = outcome.total - len(todo)
    if not todo:
        return outcome
    progress = Progress(
        label, outcome.total, outcome.reused, sum(spec.cost for spec in todo), stream=stream
    )
    progress.start()
    try:
        with ExitStack() as stack:
            scratch = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="pb-study-")))
            for batch in _batches(todo, batch_particles):
                opened = []
                for spec in batch:
                    folder = (run_folders or scratch) / spec.run_id
                    try:
                        framed, run = seam.open_run(spec.setup, folder, run_folders is not None)
                    except (ValueError, OSError, RuntimeError) as exc:
                        _failed(spec, f"{type(exc).__name__}: {exc}", store, progress, outcome)
                        continue
                    opened.append((spec, framed, run, folder))
                # Resumed runs may have other steps left than fresh ones: an ensemble each.
                groups: dict[int, list[tuple[RunSpec, Framed, Run, Path]]] = {}
                for entry in opened:
                    run = entry[2]
                    groups.setdefault(run.total_steps - run.world.steps, []).append(entry)
                for left, group in groups.items():
                    _run_group(group, left, store, runner_name, progress, outcome)
    except KeyboardInterrupt:
        outcome.interrupted = True
    finally:
        progress.close()
    return outcome


def _run_group(
    group: Sequence[tuple[RunSpec, Framed, Run, Path]],
    left: int,
    store: ResultStore,
    runner_name: str,
    progress: Progress,
    outcome: StudyOutcome,
) -> None:
    """Steps a group of opened runs `left` steps as one ensemble, then measures and stores
    each."""
    from particlebot.sim.world.cuda.ensemble import Ensemble
    from particlebot.studies import seam

    began = time.perf_counter()
    ensemble = Ensemble([run.world for _, _, run, _ in group])
    while left > 0:
        step = min(CHUNK_STEPS, left)
        ensemble.step(step)
        left -= step
        for spec, _, run, _ in group:
            progress.running(spec.run_id, spec.cost, 0.0, run.world.steps / max(1, run.total_steps))
    wall = time.perf_counter() - began
    for spec, framed, run, folder in group:
        try:
            summary = run.advance()  # (nothing left to step: the snapshot, pictures, summary)
            result = seam.outcome_of(spec.setup, framed, run, summary, folder)
            result.summary["device_cuda"] = 1.0
            result.summary["ensemble_runs"] = float(len(group))
            record = record_of(runner_name, spec, result, wall)
        except (ValueError, OSError, RuntimeError) as exc:
            _failed(spec, f"{type(exc).__name__}: {exc}", store, progress, outcome)
            continue
        store.write(record)
        outcome.ran += 1
        progress.advance(spec.cost, run_id=spec.run_id)


def _batches(todo: Sequence[RunSpec], budget: int) -> list[list[RunSpec]]:
    """Runs of the same length, largest first, in batches of at most `budget` particles (a run
    larger than the budget alone)."""
    by_length: dict[float, list[RunSpec]] = {}
    for spec in sorted(todo, key=lambda s: -s.setup.particles):
        by_length.setdefault(spec.setup.duration_s, []).append(spec)
    batches: list[list[RunSpec]] = []
    for runs in by_length.values():
        batch: list[RunSpec] = []
        size = 0
        for spec in runs:
            count = spec.setup.particles + spec.setup.free_particles
            if batch and size + count > budget:
                batches.append(batch)
                batch, size = [], 0
            batch.append(spec)
            size += count
        if batch:
            batches.append(batch)
    return batches


def _failed(
    spec: RunSpec, error: str, store: ResultStore, progress: Progress, outcome: StudyOutcome
) -> None:
    store.write_failure(spec, error)
    outcome.failed[spec.run_id] = error
    progress.advance(spec.cost, failed=True, run_id=spec.run_id)
