"""`particlebot run EXPERIMENT.toml`: the trials of an experiment file, one after another."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from particlebot.commands._common import fail, sigterm_as_interrupt
from particlebot.experiments.plan import (
    Experiment,
    ExperimentFileError,
    check_radio_url,
    is_simulated,
    load_experiment,
)
from particlebot.fileio import make_folder
from particlebot.radio import RadioError
from particlebot.swarm.api import method_letter


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "experiment", type=Path, help="the experiment file (TOML; README shows one)"
    )
    parser.add_argument("--radio", help="radio URL, instead of the file's radio =")
    parser.add_argument("--log-dir", type=Path, help="where the experiment's log folder goes")
    parser.add_argument(
        "--check", action="store_true", help="check the file and list its trials; run nothing"
    )


def run(args: argparse.Namespace) -> int:
    # The runner brings the simulator along: imported here, so that --help stays quick.
    from particlebot.experiments.runner import Runner, expected_particles

    try:
        experiment = load_experiment(args.experiment)
    except ExperimentFileError as exc:
        return fail(str(exc))
    url = args.radio or experiment.radio
    if not url:
        return fail(f'{experiment.path}: say which radio: radio = "URL" in the file, or --radio')
    try:
        check_radio_url(url)
    except RadioError as exc:
        return fail(str(exc))
    if expected_particles(experiment, url) is None and experiment.fleet is None:
        return fail(
            f"{experiment.path}: say how many particles each trial needs: particles = N (or "
            'fleet = "fleet.toml")'
        )
    if args.check:
        print(plan_text(experiment, url))
        return 0
    log_dir = args.log_dir or experiment.log_dir or Path("logs")
    runner = Runner(experiment, url, log_dir, out=sys.stdout)
    make_folder(runner.folder)  # one line (OutputError), before any trial, if it cannot be made
    with sigterm_as_interrupt():
        outcome = runner.run()
    if outcome.error is not None:
        return fail(outcome.error)
    if outcome.interrupted:
        return 130
    return 0 if outcome.ok else 1


def plan_text(experiment: Experiment, url: str) -> str:
    lines = [
        f"{experiment.path}: {experiment.name}, {experiment.runs} run(s) on {url}"
        + (" (a fresh simulated swarm each run)" if is_simulated(url) else "")
    ]
    for trial in experiment.trials:
        options = [f"method {method_letter(trial.method)}", f"{trial.duration_s:g} s"]
        options += [
            f"{name}={value}"
            for name, value in (
                ("cycle", trial.cycle_steps),
                ("wave", trial.wave_size),
                ("update", trial.update_interval_s),
            )
            if value
        ]
        if trial.phototaxis:
            options.append("phototaxis")
        options += [f"{param.name.lower()}={value}" for param, value in trial.settings.items()]
        times = f" x{trial.repetitions}" if trial.repetitions > 1 else ""
        lines.append(f"  {trial.number}. {trial.name}{times}: {', '.join(options)}")
    return "\n".join(lines)
