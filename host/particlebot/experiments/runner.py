"""Runs an experiment's trials one after another through the Swarm API, and sums them up."""

from __future__ import annotations

import csv
import datetime
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO
from urllib.parse import urlencode

from particlebot.errors import ParticlebotError
from particlebot.experiments.measure import lamp_distance
from particlebot.experiments.plan import Experiment, Trial, is_simulated
from particlebot.fleet import FleetFileError
from particlebot.logs.jsonl import LogError
from particlebot.radio import RadioError, parse_radio_url
from particlebot.swarm.api import Swarm, method_letter
from particlebot.swarm.campaigns import ids_text
from particlebot.swarm.results import NotConfirmed, ParticlesMissing, StopReport, SwarmError

PROGRESS_S = 30.0
"""A running trial says how far it got this often (the radio's time)."""


class ExperimentStopped(ParticlebotError):  # noqa: N818 (reads as what happened)
    """A trial could not start and the file says on_failure = "stop"."""


@dataclass
class TrialResult:
    trial: Trial
    repetition: int
    log: Path | None
    seed: int | None = None
    started: bool = False
    problem: str | None = None
    """Why it could not start, or was cut short."""
    run_id: int | None = None
    duration_s: float | None = None
    """From START confirmed to STOP sent, in the radio's time."""
    stop: StopReport | None = None
    lost: list[int] = field(default_factory=list)
    """Particles in the run that did not confirm STOP, or reset during it."""
    toward_lamp_m: float | None = None
    """How much nearer the lamp the swarm's centroid came (simulated radios)."""

    @property
    def label(self) -> str:
        if self.trial.repetitions == 1:
            return str(self.trial.number)
        return f"{self.trial.number}.{self.repetition}"

    @property
    def ok(self) -> bool:
        return self.started and self.stop is not None and self.stop.confirmed

    @property
    def row(self) -> dict[str, str]:
        """The summary's cells (also the CSV's)."""
        stop = "-" if self.stop is None else ("yes" if self.stop.confirmed else "NO")
        lost = "-" if not self.started else str(len(self.lost))
        if self.lost:
            lost += f" ({ids_text(self.lost)})"
        return {
            "trial": self.label,
            "name": self.trial.name,
            "method": method_letter(self.trial.method),
            "duration_s": "-" if self.duration_s is None else f"{self.duration_s:.0f}",
            "stop_confirmed": stop,
            "particles_lost": lost,
            "toward_lamp_m": "-" if self.toward_lamp_m is None else f"{self.toward_lamp_m:.3f}",
            "problem": self.problem or "",
        }


@dataclass
class Outcome:
    results: list[TrialResult]
    folder: Path
    interrupted: bool = False
    stopped_early: bool = False
    error: str | None = None
    """Why the experiment could not go on (the radio, the log, the fleet file)."""

    @property
    def ok(self) -> bool:
        return (
            not self.interrupted
            and not self.stopped_early
            and self.error is None
            and all(result.ok for result in self.results)
        )


def trial_url(url: str, index: int) -> tuple[str, int | None]:
    """A simulated radio's URL with a seed of its own for the index-th run (counted from 0):
    every run starts from a fresh swarm, and repetitions differ. A real radio's is unchanged."""
    if not is_simulated(url):
        return url, None
    parsed = parse_radio_url(url)
    options = dict(parsed.options)
    seed = int(options.get("seed", "1"), 0) + index
    options["seed"] = str(seed)
    return f"{parsed.scheme}://{parsed.target}?{urlencode(options, safe=',/:')}", seed


def expected_particles(experiment: Experiment, url: str) -> int | None:
    """How many particles a trial waits for: the file's, else a simulation's count (None: the
    fleet's roster)."""
    if experiment.particles is not None:
        return experiment.particles
    if is_simulated(url):
        target = parse_radio_url(url).target
        return int(target) if target.isdigit() else None
    return None


def run_folder(log_dir: Path, name: str, now: datetime.datetime | None = None) -> Path:
    """log_dir/NAME-YYYYmmdd-HHMMSS, never an existing folder."""
    slug = re.sub(r"[^A-Za-z0-9_.-]+", "-", name).strip("-") or "experiment"
    stamp = (now or datetime.datetime.now()).strftime("%Y%m%d-%H%M%S")
    folder = log_dir / f"{slug}-{stamp}"
    counter = 1
    while folder.exists():
        folder = log_dir / f"{slug}-{stamp}-{counter}"
        counter += 1
    return folder


class Runner:
    """Runs every trial of an experiment on a radio, writing a log per trial into one folder.

    Each run of a trial opens the radio afresh: its own session log, and on a simulated radio a
    fresh swarm (seeded per run) in its starting place, as a person would put the particles back.
    """

    def __init__(
        self,
        experiment: Experiment,
        url: str,
        log_dir: Path,
        *,
        out: TextIO,
        ask: Callable[[str], str] | None = None,
        wall_sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.experiment = experiment
        self.url = url
        self.folder = run_folder(log_dir, experiment.name)
        self.out = out
        self.ask = ask
        """Asks the person between runs (default: input() on the terminal)."""
        self.wall_sleep = wall_sleep
        self.expected = expected_particles(experiment, url)
        self.results: list[TrialResult] = []

    def say(self, text: str) -> None:
        print(text, file=self.out, flush=True)

    def run(self) -> Outcome:
        """Every trial; on Ctrl-C the swarm is stopped first, then the outcome says so."""
        outcome = Outcome(self.results, self.folder)
        total = self.experiment.runs
        index = 0
        self.say(
            f"Experiment {self.experiment.name}: {len(self.experiment.trials)} trial(s), "
            f"{total} run(s) on {self.url}; logs in {self.folder}"
        )
        try:
            for trial in self.experiment.trials:
                for repetition in range(1, trial.repetitions + 1):
                    if index:
                        self._between(trial)
                    index += 1
                    self.say(
                        f"[{index}/{total}] trial {trial.number} ({trial.name}), method "
                        f"{method_letter(trial.method)}, {trial.duration_s:g} s"
                        + (f", repetition {repetition} of {trial.repetitions}")
                    )
                    self._run_one(trial, repetition, index - 1)
        except KeyboardInterrupt:
            outcome.interrupted = True
        except ExperimentStopped:
            outcome.stopped_early = True
        except (RadioError, LogError, FleetFileError, SwarmError) as exc:
            outcome.error = str(exc)
            if self.results and self.results[-1].problem is None:
                self.results[-1].problem = outcome.error
        self._write_summary()
        return outcome

    def _between(self, trial: Trial) -> None:
        if trial.between == "prompt":
            try:
                (self.ask or input)(
                    f"Put the swarm back for trial {trial.number} ({trial.name}), then press "
                    "Enter (Ctrl-C ends the experiment) "
                )
            except EOFError:  # no terminal, or its input closed: nobody can answer
                self.say(
                    "\n  nobody can answer the prompt (no input): the experiment stops here; "
                    'between = "pause" runs without a person'
                )
                raise ExperimentStopped from None
        elif trial.between == "pause" and trial.pause_s > 0:
            self.say(f"  pause of {trial.pause_s:g} s")
            self.wall_sleep(trial.pause_s)

    def _run_one(self, trial: Trial, repetition: int, index: int) -> None:
        url, seed = trial_url(self.url, index)
        log_name = f"trial-{trial.number:02d}-{repetition:02d}.jsonl"
        result = TrialResult(trial, repetition, self.folder / log_name, seed)
        self.results.append(result)
        with Swarm.open(
            url, log_dir=self.folder, log_name=log_name, fleet=self.experiment.fleet
        ) as swarm:
            try:
                self._trial(swarm, trial, result)
            except KeyboardInterrupt:
                result.problem = "interrupted (Ctrl-C)"
                self.say("  Ctrl-C: sending STOP first (Ctrl-C again leaves at once)")
                self._stop(swarm, result)
                raise
            finally:
                self._print_notes(swarm)
        if not result.started and self.experiment.on_failure == "stop":
            self.say('  the experiment stops here (on_failure = "stop")')
            raise ExperimentStopped

    def _trial(self, swarm: Swarm, trial: Trial, result: TrialResult) -> None:
        experiment = self.experiment
        swarm.note(
            f"experiment {experiment.name}, trial {trial.number} ({trial.name}), repetition "
            f"{result.repetition} of {trial.repetitions}"
            + (f", seed {result.seed}" if result.seed is not None else "")
            + "".join(f"; {text}" for text in (experiment.notes, trial.notes) if text)
        )
        try:
            swarm.wait_for(count=self.expected, timeout=experiment.wait_s)
            for param, value in trial.settings.items():
                swarm.set(param, value)
            run = swarm.start(
                trial.method,
                cycle_steps=trial.cycle_steps,
                wave_size=trial.wave_size,
                update_interval_s=trial.update_interval_s,
                phototaxis=trial.phototaxis,
            )
        except (ParticlesMissing, NotConfirmed) as exc:
            result.problem = str(exc)
            self.say(f"  could not start: {exc}")
            if swarm.tracker.moving_ids() or swarm.tracker.run_active:
                self._stop(swarm, result)  # some may have started
            return
        result.started = True
        result.run_id = run.run_id
        start_distance = lamp_distance(swarm.radio)
        self.say(f"  run {run.run_id} started by {len(run.particles)} particle(s)")
        began = swarm.now()
        while (left := trial.duration_s - (swarm.now() - began)) > 0:
            swarm.sleep(min(PROGRESS_S, left))
            self._print_notes(swarm)
            if swarm.now() - began < trial.duration_s:
                self.say(f"  {swarm.now() - began:.0f} of {trial.duration_s:g} s")
        result.duration_s = swarm.now() - began
        self._stop(swarm, result)
        end_distance = lamp_distance(swarm.radio)
        if start_distance is not None and end_distance is not None:
            result.toward_lamp_m = start_distance - end_distance
        reset = {row.id for row in swarm.tracker.rows() if row.reset_in_run == run.run_id}
        stopped = set(result.stop.stopped) if result.stop else set()
        result.lost = sorted((set(run.particles) - stopped) | reset)

    def _stop(self, swarm: Swarm, result: TrialResult) -> None:
        try:
            report = swarm.stop()
        except KeyboardInterrupt:
            self.say("  left without STOP confirmed: particles may still be moving")
            raise
        result.stop = report
        self.say(f"  {report.text}")

    def _print_notes(self, swarm: Swarm) -> None:
        for note in swarm.tracker.new_notes():
            if note.level != "info":
                self.say(f"  {note.level}: {note.text}")

    # ---- the summary -------------------------------------------------------------------------

    def _write_summary(self) -> None:
        rows = [result.row for result in self.results]
        self.say(summary_table(rows))
        if not rows:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        path = self.folder / "summary.csv"
        with path.open("w", newline="", encoding="utf-8") as file:
            writer = csv.DictWriter(file, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        self.say(f"Summary: {path}")


COLUMNS = (
    ("trial", "trial"),
    ("method", "method"),
    ("duration_s", "duration s"),
    ("stop_confirmed", "STOP confirmed"),
    ("particles_lost", "particles lost"),
    ("toward_lamp_m", "toward lamp m"),
)


def summary_table(rows: list[dict[str, str]]) -> str:
    """The summary as aligned text, with what went wrong under the table."""
    if not rows:
        return "No trial ran."
    widths = [max(len(title), *(len(row[key]) for row in rows)) for key, title in COLUMNS]
    lines = [
        "  ".join(title.ljust(width) for (_, title), width in zip(COLUMNS, widths, strict=True))
    ]
    for row in rows:
        lines.append(
            "  ".join(
                row[key].ljust(width) for (key, _), width in zip(COLUMNS, widths, strict=True)
            )
        )
    for row in rows:
        if row["problem"]:
            lines.append(f"trial {row['trial']}: {row['problem']}")
    return "\n".join(line.rstrip() for line in lines)
