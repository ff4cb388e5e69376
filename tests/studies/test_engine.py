"""Studies on a real Dask LocalCluster of two worker processes: results, resuming, dying workers."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from distributed import LocalCluster

from particlebot.commands.study import main
from particlebot.fileio import finished_files
from particlebot.studies.definitions import STUDIES, RawOptions, resolve
from particlebot.studies.engine import (
    ClusterError,
    StudyOutcome,
    dask_client,
    run_pending,
    run_study,
)
from particlebot.studies.progress import Progress
from particlebot.studies.spec import RunSpec
from particlebot.studies.store import ResultStore
from tests.support.repo import REPO_ROOT
from tests.support.standin import StandInRunner

# Hang guards, an order of magnitude above the time on an idle machine (a study starts Python
# processes that import numba): a loaded machine must not fail them.
pytestmark = [pytest.mark.timeout(900), pytest.mark.dask]
DEADLINE_S = 300.0

QUICK_DEAD = ["dead", "--quick", "--sizes", "10,100", "--fractions", "0,0.5", "--seeds", "2"]


def quick_specs(seeds: int = 2) -> list[RunSpec]:
    study = STUDIES["dead"]
    return study.specs(
        resolve(study, RawOptions(sizes="10,100", values="0,0.5", seeds=str(seeds), quick=True))
    )


def finished(results: Path) -> dict[str, int]:
    """Run id -> modification time of its result file (none before the folder exists; a result
    still being written, under its temporary name, is not finished)."""
    runs = finished_files(results / "runs", "*.json")
    return {path.stem: path.stat().st_mtime_ns for path in runs}


def test_a_tiny_study_runs_end_to_end_on_two_worker_processes(tmp_path: Path) -> None:
    warm = tmp_path / "warm"
    warm.mkdir()
    progress = io.StringIO()
    results = tmp_path / "results"
    argv = [*QUICK_DEAD, "--results", str(results), "--workers", "2"]
    assert main(argv, runner=StandInRunner(warm_dir=warm), stream=progress) == 0
    records = [json.loads(path.read_text()) for path in (results / "runs").glob("*.json")]
    assert sorted(r["run_id"] for r in records) == sorted(s.run_id for s in quick_specs())
    # Every run ran in a Dask worker process that had warmed up before it.
    warmed = {int(path.name) for path in warm.iterdir()}
    assert {r["pid"] for r in records} <= warmed
    assert all(r["worker"].startswith("tcp://") and r["pid"] != os.getpid() for r in records)
    assert "8/8 runs" in progress.getvalue()
    report = (results / "report.md").read_text()
    assert "## Table S3" in report and "| | paper | 1.24 ± 0.44 | 0.17 ± 0.30 |" in report
    # 4 cells, each with the true speed and the paper-camera reading derived from it.
    assert len((results / "summary.csv").read_text().splitlines()) == 1 + 4 * 2
    assert (results / "plot.png").stat().st_size > 10_000
    assert json.loads((results / "study.json").read_text())["runs"] == [
        s.run_id for s in quick_specs()
    ]


def test_a_dying_worker_is_replaced_and_a_raising_run_is_kept_for_the_next_invocation(
    tmp_path: Path,
) -> None:
    specs = quick_specs()
    crashing, raising = specs[1].run_id, specs[2].run_id
    store = ResultStore(tmp_path / "results")
    runner = StandInRunner(
        crash_once=frozenset({crashing}), raise_for=frozenset({raising}), marker_dir=tmp_path
    )
    outcome = run_study(specs, store, runner, workers=2, stream=io.StringIO())
    crashed_in = int((tmp_path / f"{crashing}.crashed").read_text())
    record = json.loads((store.runs / f"{crashing}.json").read_text())
    assert record["pid"] != crashed_in, "the retry ran in a new worker process"
    assert outcome.ran == len(specs) - 1
    assert list(outcome.failed) == [raising]
    assert "fails" in outcome.failed[raising]
    assert (store.failed / f"{raising}.json").exists()
    before = finished(store.root)

    again = run_study(specs, store, StandInRunner(), workers=2, stream=io.StringIO())
    assert (again.reused, again.ran, again.failed) == (len(specs) - 1, 1, {})
    after = finished(store.root)
    assert set(after) == {s.run_id for s in specs}
    assert all(after[run_id] == mtime for run_id, mtime in before.items()), "nothing reran"
    assert not (store.failed / f"{raising}.json").exists()


def test_an_interrupted_study_keeps_what_finished_and_resumes_with_the_rest(
    tmp_path: Path,
) -> None:
    results = tmp_path / "results"
    specs = quick_specs(seeds=3)
    tickets = tmp_path / "tickets"
    tickets.mkdir()
    # The first three runs finish; every later one is held, so the study cannot end before the
    # interrupt, however loaded the machine.
    # The study takes Ctrl-C as a terminal's user would, even where pytest was started in the
    # background of a non-interactive shell, which starts it (and so this child) ignoring SIGINT.
    code = (
        "import signal, sys\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "from pathlib import Path\n"
        "from particlebot.commands.study import main\n"
        "from tests.support.standin import StandInRunner\n"
        f"runner = StandInRunner(hold_after=3, ticket_dir=Path({str(tickets)!r}))\n"
        "sys.exit(main(sys.argv[1:], runner=runner))\n"
    )
    argv = [*QUICK_DEAD[:-1], "3", "--results", str(results), "--workers", "2"]
    # A session of its own, so that SIGINT goes to the whole group as a terminal's Ctrl-C does.
    study = subprocess.Popen(
        [sys.executable, "-c", code, *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        cwd=REPO_ROOT,  # (the stand-in runner lives in tests/support, importable from the root)
    )
    deadline = time.monotonic() + DEADLINE_S
    while len(finished(results)) < 3:
        assert study.poll() is None and time.monotonic() < deadline, study.communicate()
        time.sleep(0.05)
    os.killpg(study.pid, signal.SIGINT)
    _out, err = study.communicate(timeout=DEADLINE_S)
    assert study.returncode == 130, err
    assert "Traceback" not in err
    before = finished(results)
    assert len(before) == 3
    assert f"Interrupted: {len(before)} of {len(specs)} runs are kept" in err

    outcome = run_study(
        specs, ResultStore(results), StandInRunner(), workers=2, stream=io.StringIO()
    )
    assert (outcome.reused, outcome.ran) == (len(before), len(specs) - len(before))
    after = finished(results)
    assert set(after) == {s.run_id for s in specs}
    assert all(after[run_id] == mtime for run_id, mtime in before.items())


def test_an_existing_cluster_gets_the_same_runs_and_stays_up(tmp_path: Path) -> None:
    specs = quick_specs(seeds=1)
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster:
        address = cluster.scheduler_address
        store = ResultStore(tmp_path / "results")
        outcome = run_study(specs, store, StandInRunner(), scheduler=address, stream=io.StringIO())
        assert (outcome.ran, outcome.failed) == (len(specs), {})
        assert set(finished(store.root)) == {s.run_id for s in specs}
        with pytest.raises(ClusterError, match=r"could not prepare.*no simulator here"):
            run_study(
                quick_specs(seeds=2),
                store,
                StandInRunner(warm_up_fails=True),
                scheduler=address,
                stream=io.StringIO(),
            )
        assert cluster.status.name == "running"


def test_a_run_still_going_reports_its_share_to_the_client(tmp_path: Path) -> None:
    spec = quick_specs(seeds=1)[0]
    tickets = tmp_path / "tickets"
    tickets.mkdir()
    # The run says it is half way, then is held until the test has seen the report.
    runner = StandInRunner(hold_after=0, ticket_dir=tickets, reports_share=0.5)
    store = ResultStore(tmp_path / "results")
    store.prepare()
    progress = Progress("dead", 1, 0, spec.cost, stream=io.StringIO())
    outcome = StudyOutcome(total=1, reused=0)
    with dask_client(None, workers=1) as client:
        study = threading.Thread(
            target=run_pending, args=(client, runner, [spec], store, progress, outcome)
        )
        study.start()
        deadline = time.monotonic() + DEADLINE_S
        while spec.run_id not in progress.in_flight:
            assert study.is_alive() and time.monotonic() < deadline, outcome
            time.sleep(0.05)
        assert progress.in_flight[spec.run_id] == (spec.cost, 0.5, 0.5)
        assert progress.share_done() == 0.5 and outcome.ran == 0
        (tickets / "go").touch()
        study.join(timeout=60)
    assert outcome.ran == 1 and progress.in_flight == {}
    assert progress.share_done() == 1.0


def test_a_study_whose_every_run_fails_says_why_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    specs = quick_specs(seeds=1)
    results = tmp_path / "results"
    runner = StandInRunner(raise_for=frozenset(spec.run_id for spec in specs))
    argv = [*QUICK_DEAD[:-1], "1", "--results", str(results), "--workers", "2"]
    assert main(argv, runner=runner, stream=io.StringIO()) == 1
    last = capsys.readouterr().err.strip().splitlines()[-1]
    # No report.md to point at: the line itself carries an error, and where the others are.
    assert not (results / "report.md").exists()
    assert last.startswith(f"{len(specs)} of {len(specs)} runs failed, the first with RuntimeError")
    assert f"on purpose (each run's error: {results / 'failed'})" in last
