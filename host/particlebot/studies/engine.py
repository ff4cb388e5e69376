"""Runs a study's missing runs on Dask (a local cluster or an existing one), keeping each result."""

from __future__ import annotations

import asyncio
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, TextIO

import dask
from distributed import Client, Future, LocalCluster, WorkerPlugin, as_completed, get_worker
from distributed.client import FutureCancelledError
from distributed.scheduler import KilledWorker

from particlebot.errors import ParticlebotError
from particlebot.studies.progress import Progress
from particlebot.studies.runners import Runner, execute
from particlebot.studies.spec import RunRecord, RunSpec
from particlebot.studies.store import ResultStore

WORKER_DEATHS_ALLOWED = 3
"""A run whose worker process dies (killed for memory, a crash, a node lost) goes back to the
scheduler and runs on another worker, this many times: Dask's allowed-failures, set on the local
cluster's scheduler (an existing cluster keeps its own setting, 3 unless changed)."""
EXCEPTION_RETRIES = 1
"""A run that raises is tried once more (Dask's retries=): a full disk or a file system hiccup on
a cluster passes; a deterministic error fails twice and is recorded."""
PROGRESS_TOPIC = "particlebot-run-progress"
"""Dask event topic on which workers report how far their runs are."""
PROGRESS_EVERY_S = 5.0
"""A run reports at most this often: a 10,000-particle run takes ten minutes or more, and a
cluster of hundreds of workers should not flood the scheduler."""
LOG = logging.getLogger(__name__)


class ClusterError(ParticlebotError, RuntimeError):
    """The Dask cluster cannot be reached or lost; the message is one line."""


@dataclass
class StudyOutcome:
    total: int
    reused: int
    """Runs found finished in the results folder."""
    ran: int = 0
    failed: dict[str, str] = field(default_factory=dict)
    """run id -> the error, one line."""
    interrupted: bool = False

    @property
    def finished(self) -> int:
        return self.reused + self.ran


class StudyWorkerSetup(WorkerPlugin):
    """Prepares every worker, including ones that join or restart later: warms the runner up
    (numba compiles once per process, or loads its on-disk cache) off the worker's event loop;
    on a local cluster, also leaves Ctrl-C to the client, which shuts the cluster down in order
    (a terminal sends SIGINT to the whole process group, and a worker that raised
    KeyboardInterrupt would print a traceback over the progress line)."""

    name = "particlebot-study"

    def __init__(self, runner: Runner, ignore_interrupts: bool) -> None:
        self.runner = runner
        self.ignore_interrupts = ignore_interrupts

    async def setup(self, worker: object) -> None:
        if self.ignore_interrupts and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        await asyncio.get_running_loop().run_in_executor(None, self.runner.warm_up)


def check_scheduler(address: str) -> None:
    """ClusterError unless a Dask scheduler answers at address (within dask_client's timeout)."""
    with dask_client(address):
        pass


@contextmanager
def dask_client(
    scheduler: str | None, workers: int | None = None, verbose: bool = False
) -> Iterator[Client]:
    """A client of the cluster at scheduler (tcp://HOST:8786), or of a new local cluster of
    `workers` processes (default: one per core), one thread each: a run is single-threaded (the
    runner sets numba's threads), so a process per core keeps every core busy without
    oversubscribing them."""
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
        except Exception as exc:
            # Something else answers there (a web server): Dask reads its bytes as a message's
            # length and fails in ways of its own ("Unable to allocate 3.07 EiB").
            raise ClusterError(
                f"{scheduler} answers, but not as a Dask scheduler ({type(exc).__name__})"
            ) from None
        try:
            yield client
        finally:
            client.close()
        return
    cluster = _local_cluster(workers or os.cpu_count() or 1, verbose)
    try:
        client = Client(cluster)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()


def _local_cluster(workers: int, verbose: bool = False) -> LocalCluster:
    in_main_thread = threading.current_thread() is threading.main_thread()
    # Worker processes inherit an ignored SIGINT (the plugin covers restarted ones).
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if in_main_thread else None
    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": WORKER_DEATHS_ALLOWED}):
            return LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                # Any free port: a fixed one (None means 8787) makes a second study on the same
                # machine print a four-line warning that it took another.
                dashboard_address=":0",
                # A run that raises is reported by the study (one line, report.md, failed/);
                # the workers' own "Compute Failed" blocks with tracebacks only with --verbose.
                silence_logs=logging.INFO if verbose else logging.CRITICAL,
            )
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)


class ReportToClient:
    """The progress a run gets on a worker: sends {run, start, now} (shares of its steps) as a
    Dask event, at most every PROGRESS_EVERY_S; start is the share at the first report, so a
    run resumed from its snapshot does not count its earlier part as work done now."""

    def __init__(self, run_id: str, every_s: float = PROGRESS_EVERY_S) -> None:
        self.run_id = run_id
        self.every_s = every_s
        self.start: float | None = None
        self.last_sent = -float("inf")

    def __call__(self, share: float) -> None:
        if self.start is None:
            self.start = share
        now = time.monotonic()
        if now - self.last_sent < self.every_s:
            return
        self.last_sent = now
        message = {"run": self.run_id, "start": self.start, "now": share}
        get_worker().log_event(PROGRESS_TOPIC, message)


def execute_reporting(runner: Runner, spec: RunSpec) -> RunRecord:
    """execute on a Dask worker, with the run's progress sent to the client."""
    return execute(runner, spec, ReportToClient(spec.run_id))


def _progress_handler(
    progress: Progress, by_run: dict[str, RunSpec]
) -> Callable[[tuple[float, Any]], None]:
    def heard(event: tuple[float, Any]) -> None:
        _timestamp, message = event
        try:
            spec = by_run[message["run"]]
            start, now = float(message["start"]), float(message["now"])
        except (KeyError, TypeError, ValueError):
            return  # another client's runs on a shared cluster, or not ours at all
        progress.running(spec.run_id, spec.cost, start, now)

    return heard


def is_local(client: Client) -> bool:
    return isinstance(client.cluster, LocalCluster)


def pending(specs: Sequence[RunSpec], finished: dict[str, RunRecord]) -> list[RunSpec]:
    """The runs still to do, dearest first (they set how long the study takes)."""
    todo = {spec.run_id: spec for spec in specs if spec.run_id not in finished}
    return sorted(todo.values(), key=lambda spec: spec.cost, reverse=True)


def run_pending(
    client: Client,
    runner: Runner,
    todo: Sequence[RunSpec],
    store: ResultStore,
    progress: Progress,
    outcome: StudyOutcome,
) -> None:
    """Submits todo and writes each result the moment it arrives. Ctrl-C cancels what is left
    and returns with outcome.interrupted set; everything written stays."""
    try:
        client.register_plugin(StudyWorkerSetup(runner, ignore_interrupts=is_local(client)))
    except Exception as exc:  # raised in a worker: its type is whatever the runner raised
        first = (str(exc).strip().splitlines() or [""])[0]
        raise ClusterError(
            f"the workers could not prepare for the runs ({type(exc).__name__}: {first}); "
            "is particlebot installed there, at the same commit?"
        ) from None
    client.subscribe_topic(
        PROGRESS_TOPIC, _progress_handler(progress, {spec.run_id: spec for spec in todo})
    )
    by_key: dict[str, RunSpec] = {}
    futures: list[Future] = []
    for spec in todo:
        # The key is the run itself: two clients asking for the same run share one task.
        key = f"{runner.name}-{spec.run_id}"
        by_key[key] = spec
        futures.append(
            client.submit(execute_reporting, runner, spec, key=key, retries=EXCEPTION_RETRIES)
        )
    progress.start()
    try:
        for future in as_completed(futures):
            spec = by_key[str(future.key)]
            record, error = _result_of(future)
            if record is not None:
                store.write(record)
                outcome.ran += 1
            else:
                store.write_failure(spec, error)
                outcome.failed[spec.run_id] = error
            future.release()
            progress.advance(spec.cost, failed=record is None, run_id=spec.run_id)
    except KeyboardInterrupt:
        outcome.interrupted = True
        client.cancel(futures)
    finally:
        client.unsubscribe_topic(PROGRESS_TOPIC)
        progress.close()


def _result_of(future: Future) -> tuple[RunRecord | None, str]:
    """The record, or why there is none in one line. Asks the future itself rather than its
    status: a result lost with a dying worker sends a finished future back to pending (Dask
    recomputes it), and result() waits for the final word."""
    try:
        return future.result(), ""
    except KilledWorker:
        return None, (
            f"the worker process running it died {WORKER_DEATHS_ALLOWED} times "
            "(out of memory, or a crash in compiled code)"
        )
    except FutureCancelledError:
        return None, "cancelled by the cluster"
    except Exception as exc:  # raised by the run on the worker: any type
        text = str(exc).strip().splitlines()
        return None, f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def run_study(
    specs: Sequence[RunSpec],
    store: ResultStore,
    runner: Runner,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    label: str = "study",
    stream: TextIO | None = None,
    verbose: bool = False,
) -> StudyOutcome:
    """Runs what the results folder lacks, on the cluster at scheduler or a local one."""
    store.prepare()
    finished, _ = store.load_finished(runner.name)
    todo = pending(specs, finished)
    outcome = StudyOutcome(total=len({spec.run_id for spec in specs}), reused=0)
    outcome.reused = outcome.total - len(todo)
    if not todo:
        return outcome
    if scheduler is None:
        # Compile once here, so the local workers load numba's cache instead of all compiling.
        runner.warm_up()
    progress = Progress(
        label, outcome.total, outcome.reused, sum(spec.cost for spec in todo), stream=stream
    )
    with dask_client(scheduler, workers, verbose) as client:
        run_pending(client, runner, todo, store, progress, outcome)
    return outcome
