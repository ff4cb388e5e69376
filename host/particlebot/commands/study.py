"""`particlebot study NAME`: one of the paper's simulation studies, run on Dask, reported."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import NoReturn, TextIO

from particlebot.commands._common import fail, sigterm_as_interrupt
from particlebot.devices import DEVICES, DeviceError
from particlebot.fileio import write_text
from particlebot.studies.definitions import (
    PLACEMENTS,
    STUDIES,
    RawOptions,
    Study,
    StudyOptionError,
    StudyOptions,
    resolve,
)
from particlebot.studies.runners import Runner, SimulatorRunner
from particlebot.studies.spec import RunSpec
from particlebot.studies.store import ResultStore

SWEEP_FLAGS = {study.sweep.flag: study.name for study in STUDIES.values() if study.sweep}
INTERRUPTED = 130


class _OneLineParser(argparse.ArgumentParser):
    """Bad options get one line on stderr and exit status 2, not the usage block."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"particlebot: study: {message} (see particlebot study --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The study command's parser on its own (main() and its tests)."""
    parser = _OneLineParser(prog="particlebot study")
    add_arguments(parser)
    return parser


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = (
        "Run one of the paper's simulation studies (SI S9) on a Dask cluster; every finished run "
        "is kept, so rerunning the same command resumes it."
    )
    parser.epilog = "studies: " + "; ".join(
        f"{s.name}: {s.title.lower()} ({s.source})" for s in STUDIES.values()
    )
    parser.add_argument("name", metavar="NAME", choices=sorted(STUDIES), help=", ".join(STUDIES))
    what = parser.add_argument_group("what to run (default: the paper's parameters)")
    what.add_argument("--quick", action="store_true", help="a preset that takes minutes")
    what.add_argument("--sizes", metavar="LIST", help="swarm sizes, e.g. 10,100,1000")
    for flag, name in SWEEP_FLAGS.items():
        sweep = STUDIES[name].sweep
        assert sweep is not None
        scale = " (fractions)" if sweep.scale == 100 else ""
        label = sweep.label.replace("%", "%%")
        what.add_argument(flag, metavar="LIST", help=f"{name}: {label}{scale}")
    what.add_argument("--seeds", metavar="N", help="runs per cell (random configurations)")
    what.add_argument(
        "--first-seed", metavar="K", help="seed of the first run of each cell (default 1)"
    )
    what.add_argument(
        "--duration", metavar="TIME", help="simulated time per run: 7200, 90min, 2h, 4500cycles"
    )
    what.add_argument(
        "--skip", metavar="TIME", help="speed studies: time left out at the start (default 30min)"
    )
    what.add_argument(
        "--placement", metavar="NAME", help=f"initial placement: {', '.join(PLACEMENTS)}"
    )
    what.add_argument(
        "--set",
        metavar="NAME=VALUE,...",
        dest="overrides",
        help="change published numbers: the world's (static_factor=1, shear=20, magnet_cutoff=0.6, "
        "...) or the controller's phase_noise, update_cycles",
    )
    where = parser.add_argument_group("where")
    where.add_argument(
        "--results", metavar="DIR", help="results folder (default results/NAME[-quick])"
    )
    where.add_argument(
        "--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, tcp://HOST:8786"
    )
    where.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes (default: one per core)"
    )
    where.add_argument(
        "--run-folders",
        metavar="DIR",
        help="keep every run's CSV and snapshots here (a path all workers can write)",
    )
    where.add_argument(
        "--device",
        choices=DEVICES,
        default="cpu",
        help="where the runs step: cpu (default), cuda (a GPU: without --scheduler the runs go "
        "as ensembles, many in one launch; with one, each worker's runs on its own GPU), or auto",
    )
    modes = parser.add_argument_group("instead of running")
    modes.add_argument("--list", action="store_true", help="show the runs and how many are done")
    modes.add_argument("--report-only", action="store_true", help="report what has finished")
    modes.add_argument(
        "--pool",
        nargs="+",
        metavar="SUMMARY",
        help="pool summary.csv files of disjoint runs cell by cell into --results DIR's "
        "summary.csv (without --results: print it)",
    )
    parser.add_argument("--verbose", action="store_true", help="show Dask's own log messages")


def options_from(study: Study, args: argparse.Namespace) -> StudyOptions:
    values = None
    for flag, name in SWEEP_FLAGS.items():
        given = getattr(args, flag.lstrip("-").replace("-", "_"))
        if given is None:
            continue
        if name != study.name:
            own = f" (its sweep is {study.sweep.flag})" if study.sweep else ""
            raise StudyOptionError(f"{flag} does not apply to study {study.name}{own}")
        values = given
    if args.workers is not None and args.workers < 1:
        raise StudyOptionError(f"--workers: {args.workers} is below 1")
    if args.workers is not None and args.scheduler is not None:
        raise StudyOptionError("--workers sizes the local cluster; an existing one has its own")
    return resolve(
        study,
        RawOptions(
            sizes=args.sizes,
            values=values,
            seeds=args.seeds,
            first_seed=args.first_seed,
            duration=args.duration,
            skip=args.skip,
            placement=args.placement,
            quick=args.quick,
            overrides=args.overrides,
        ),
    )


def main(argv: Sequence[str], runner: Runner | None = None, stream: TextIO | None = None) -> int:
    """The command from its own arguments; tests pass a stand-in runner and a stream for the
    progress line."""
    return run(build_parser().parse_args(argv), runner, stream)


def run(
    args: argparse.Namespace, runner: Runner | None = None, stream: TextIO | None = None
) -> int:
    study = STUDIES[args.name]
    logging.getLogger("distributed").setLevel(logging.INFO if args.verbose else logging.ERROR)
    try:
        with sigterm_as_interrupt():
            return _study(study, args, runner, stream)
    except StudyOptionError as exc:
        return fail(f"study {study.name}: {exc}")
    except KeyboardInterrupt:
        print("particlebot study: interrupted before any run started", file=sys.stderr)
        return INTERRUPTED


def _study(
    study: Study, args: argparse.Namespace, runner: Runner | None, stream: TextIO | None
) -> int:
    if args.pool:
        return _pool(study, [Path(p) for p in args.pool], args.results)
    options = options_from(study, args)
    specs = study.specs(options)
    default = f"results/{study.name}" + ("-quick" if options.quick else "")
    store = ResultStore(Path(args.results or default))
    try:
        # With a scheduler the workers' GPUs count, not this machine's: they check their own.
        remote_gpu = args.scheduler is not None and args.device == "cuda"
        from particlebot.sim.world.cuda.device import resolve as resolve_device

        device = "cuda" if remote_gpu else resolve_device(args.device)
    except DeviceError as exc:
        return fail(f"study {study.name}: {exc}")
    if runner is None:
        folders = Path(args.run_folders) if args.run_folders else None
        runner = SimulatorRunner(folders, device)
    if args.list:
        return _list(study, options, specs, store, runner.name)
    if args.report_only:
        planned = {spec.run_id for spec in specs}
        failed = {k: v for k, v in store.load_failures().items() if k in planned}
        return _report(study, options, specs, store, runner.name, failed)
    from particlebot.studies.engine import ClusterError, check_scheduler, run_study

    try:
        if args.scheduler is not None:
            check_scheduler(args.scheduler)  # before a line is printed or a file written
    except ClusterError as exc:
        return fail(str(exc))
    try:
        store.prepare()
        store.write_document(
            "study.json",
            {
                "study": study.name,
                "options": asdict(options),
                "runner": runner.name,
                "runs": [spec.run_id for spec in specs],
            },
        )
    except OSError as exc:
        return fail(f"cannot write results to {store.root}: {exc.strerror or exc}")
    print(_plan_line(study, options, specs), file=sys.stderr)
    if isinstance(runner, SimulatorRunner) and args.scheduler is None:
        # Local workers share this machine's numba cache: compiled once here, announced, instead
        # of in every worker at once while the ETA counts it as work.
        from particlebot.commands._kernels import prepare_kernels

        prepare_kernels(stream)
    try:
        if device == "cuda" and args.scheduler is None and isinstance(runner, SimulatorRunner):
            from particlebot.studies.batched import run_batched

            outcome = run_batched(
                specs, store, runner.name, run_folders=runner.run_folders, label=study.name,
                stream=stream,
            )  # fmt: skip
        else:
            outcome = run_study(
                specs,
                store,
                runner,
                scheduler=args.scheduler,
                workers=args.workers,
                label=study.name,
                stream=stream,
                verbose=args.verbose,
            )
    except ClusterError as exc:
        return fail(str(exc))
    _report(study, options, specs, store, runner.name, outcome.failed)
    if outcome.interrupted:
        print(
            f"Interrupted: {outcome.finished} of {outcome.total} runs are kept in {store.root}; "
            "run the same command again to finish the rest.",
            file=sys.stderr,
        )
        return INTERRUPTED
    if outcome.failed:
        # The first error in the line itself: when every run failed there is no report.md.
        first = next(iter(outcome.failed.values()))
        print(
            f"{len(outcome.failed)} of {outcome.total} runs failed, the first with {first} "
            f"(each run's error: {store.failed}); run the same command again to retry them.",
            file=sys.stderr,
        )
        return 1
    return 0


def _pool(study: Study, summaries: Sequence[Path], results: str | None) -> int:
    """Pools the summaries into one (studies/pooling.py), checked to be this study's."""
    from particlebot.studies.pooling import PoolingError, pool_summaries
    from particlebot.studies.report import csv_text

    try:
        text = pool_summaries(summaries)
    except PoolingError as exc:
        return fail(f"study {study.name}: --pool: {exc}")
    if text.partition("\n")[0] != csv_text(study, []).partition("\n")[0]:
        return fail(f"study {study.name}: --pool: {summaries[0]} is not a summary of this study")
    if results is None:
        sys.stdout.write(text)
        return 0
    target = Path(results) / "summary.csv"
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        write_text(target, text)
    except OSError as exc:
        return fail(f"cannot write {target}: {exc.strerror or exc}")
    print(f"Pooled {len(summaries)} summaries: {target}")
    return 0


def _plan_line(study: Study, options: StudyOptions, specs: Sequence[RunSpec]) -> str:
    cells = len({spec.cell for spec in specs})
    return (
        f"{study.name}: {len(specs)} runs in {cells} cells x {options.seeds} seeds, "
        f"{options.duration_s:g} s simulated each, {sum(s.cost for s in specs):.2g} particle-steps"
    )


def _list(
    study: Study, options: StudyOptions, specs: Sequence[RunSpec], store: ResultStore, runner: str
) -> int:
    finished, _ = store.load_finished(runner)
    print(_plan_line(study, options, specs))
    by_size: dict[int, list[RunSpec]] = {}
    for spec in specs:
        by_size.setdefault(int(spec.cell_dict["particles"]), []).append(spec)
    for n, runs in by_size.items():
        done = sum(spec.run_id in finished for spec in runs)
        cost = sum(spec.cost for spec in runs if spec.run_id not in finished)
        print(f"  N={n:,}: {done}/{len(runs)} runs finished, {cost:.2g} particle-steps left")
    print(f"results: {store.root}")
    return 0


def _report(
    study: Study,
    options: StudyOptions,
    specs: Sequence[RunSpec],
    store: ResultStore,
    runner: str,
    failed: dict[str, str],
) -> int:
    """Writes report.md, summary.csv and plot.png from every finished run of this study."""
    from particlebot.studies.figures import plot_study
    from particlebot.studies.report import collect, csv_text, markdown

    finished, found = store.load_finished(runner)
    stats = collect(study, specs, finished)
    if not any(cell.values for cell in stats):
        print(f"No finished runs of this study in {store.root} yet: nothing to report.")
        return 0 if not failed else 1
    try:
        store.root.mkdir(parents=True, exist_ok=True)
        write_text(store.root / "summary.csv", csv_text(study, stats))
        write_text(store.root / "report.md", markdown(study, options, stats, failed, runner))
        notes = [] if runner == "simulator" else [f"made by the {runner}, not the simulator"]
        if options.overrides:
            notes.append("changed: " + ", ".join(f"{k} = {v:g}" for k, v in options.overrides))
        note = "; ".join(notes)
        plot_study(study, stats, store.root / "plot.png", note)
    except OSError as exc:
        return fail(f"cannot write the report to {store.root}: {exc.strerror or exc}")
    for path in found.unreadable:
        print(f"particlebot study: warning: {path} is not a complete result; rerun to redo it")
    done = sum(len(cell.values) for cell in stats if cell.metric == study.metric.key)
    print(f"Report of {done} runs: {store.root / 'report.md'}, summary.csv, plot.png")
    return 0
