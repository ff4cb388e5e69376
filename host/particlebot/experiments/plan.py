"""The experiment file (TOML): trials to run one after another; mistakes named by file:line:key."""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from particlebot.errors import ParticlebotError
from particlebot.fleet import FleetFileError, load_fleet
from particlebot.protocol import PARAM_SPECS, Method, Param
from particlebot.radio import RadioError, parse_radio_url
from particlebot.radio.faults import faults_from_url
from particlebot.swarm.api import method_of
from particlebot.toml_lines import key_lines, line_of

BETWEEN = ("pause", "prompt", "none")
"""What happens between two trials: a pause of pause_s seconds, a question to the person (to
put the swarm back), or nothing."""
ON_FAILURE = ("continue", "stop")
"""What a trial that cannot start (particles missing, START not confirmed) does to the rest."""
SIMULATED = ("virtual", "emulated")
LONGEST_S = 86_400.0
"""No wait, pause or trial lasts more than a day: a longer one is a typo (1e300 would never end)."""

_TOP_KEYS = {
    "name": "a name for the experiment (its log folder is named after it)",
    "radio": "the radio URL (--radio overrides it)",
    "fleet": "the fleet file: its particles are the roster",
    "particles": "how many particles must answer before a trial starts",
    "wait_s": "how long to wait for them (seconds)",
    "on_failure": "continue or stop",
    "between": "pause, prompt or none",
    "pause_s": "the pause between trials (seconds)",
    "log_dir": "where the experiment's log folder goes",
    "notes": "free text, written into every trial's log",
    "trial": "the trials, one [[trial]] table each",
}
_TRIAL_KEYS = {
    "name": "a name for the trial",
    "method": "A, B, C or D",
    "cycle_steps": "servo steps of 20 ms per cycle (0: each particle's stored value)",
    "wave_size": "N of eq. 3 (0: automatic)",
    "update_interval_s": "seconds between re-estimations (0: stored value)",
    "phototaxis": "true or false",
    "duration_s": "how long the particles run (seconds of the radio's time)",
    "repetitions": "how many times the trial runs",
    "between": "pause, prompt or none, before each of its runs",
    "pause_s": "the pause before each of its runs (seconds)",
    "notes": "free text, written into its log",
    "set": "parameters set (and confirmed) on every particle before START",
}


class ExperimentFileError(ParticlebotError):
    """What is wrong with an experiment file, in one line: `FILE:LINE: key: what to write`."""


@dataclass(frozen=True)
class Trial:
    number: int
    name: str
    method: Method
    duration_s: float
    cycle_steps: int = 0
    wave_size: int = 0
    update_interval_s: int = 0
    phototaxis: bool = False
    repetitions: int = 1
    between: str = "pause"
    pause_s: float = 0.0
    notes: str = ""
    settings: dict[Param, int] = field(default_factory=dict)


@dataclass(frozen=True)
class Experiment:
    path: Path
    name: str
    radio: str | None
    fleet: Path | None
    particles: int | None
    wait_s: float
    on_failure: str
    log_dir: Path | None
    notes: str
    trials: tuple[Trial, ...]

    @property
    def runs(self) -> int:
        """Trials times their repetitions."""
        return sum(trial.repetitions for trial in self.trials)


class _Reader:
    """Typed access to one table of the file; every mistake names file, line and key."""

    def __init__(self, path: Path, lines: dict[str, int], where: str, label: str) -> None:
        """lines: key_lines of the file; where: the table's dotted path ("" at the top)."""
        self.path = path
        self.lines = lines
        self.where = where
        self.label = label

    def error(self, key: str, text: str) -> ExperimentFileError:
        line = line_of(self.lines, f"{self.where}.{key}" if self.where else key)
        name = f"{self.label}{key}" if key else self.label.rstrip(": ")
        return ExperimentFileError(f"{self.path}:{line}: {name}: {text}")

    def only(self, table: dict[str, Any], known: dict[str, str]) -> None:
        for key in table:
            if key not in known:
                close = difflib.get_close_matches(key, known, n=1)
                hint = f" (did you mean '{close[0]}'?)" if close else ""
                raise self.error(key, f"unknown key{hint}; known here: {', '.join(sorted(known))}")

    def text(self, table: dict[str, Any], key: str, default: str) -> str:
        value = table.get(key, default)
        if not isinstance(value, str):
            raise self.error(key, f"must be text in quotes, not {value!r}")
        return value

    def choice(
        self, table: dict[str, Any], key: str, default: str, choices: tuple[str, ...]
    ) -> str:
        value = self.text(table, key, default).strip().lower()
        if value not in choices:
            raise self.error(key, f"must be {' or '.join(choices)}, not '{value}'")
        return value

    def number(
        self, table: dict[str, Any], key: str, default: float | None, *, positive: bool = False
    ) -> float | None:
        value = table.get(key, default)
        if value is None:
            return None
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise self.error(key, f"must be a number of seconds, not {value!r}")
        if value < 0 or (positive and value == 0):
            raise self.error(
                key, f"must be {'more than' if positive else 'at least'} 0, not {value}"
            )
        if value > LONGEST_S:
            raise self.error(key, f"must be at most {LONGEST_S:.0f} s (a day), not {value:g}")
        return float(value)

    def whole(
        self, table: dict[str, Any], key: str, default: int | None, low: int, high: int
    ) -> int | None:
        value = table.get(key, default)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be a whole number, not {value!r}")
        if not low <= value <= high:
            raise self.error(key, f"must be {low}..{high}, not {value}")
        return value


def load_experiment(path: Path) -> Experiment:
    """The experiment in path, every value checked; ExperimentFileError (one line) if not."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ExperimentFileError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise ExperimentFileError(f"{path}: a folder, not an experiment file") from None
    except OSError as exc:
        raise ExperimentFileError(f"{path}: cannot read it ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise ExperimentFileError(f"{path}: not a text file") from None
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        at = re.search(r"\(at line (\d+), column (\d+)\)", message)
        line = at.group(1) if at else "1"
        what = re.sub(r"\s*\(at line \d+, column \d+\)", "", message)
        if at:
            what += f" (column {at.group(2)})"
        raise ExperimentFileError(f"{path}:{line}: not valid TOML: {what}") from None
    return _experiment(path, document, key_lines(text))


def _experiment(path: Path, document: dict[str, Any], lines: dict[str, int]) -> Experiment:
    top = _Reader(path, lines, "", "")
    top.only(document, _TOP_KEYS)
    radio = document.get("radio")
    if radio is not None:
        radio = top.text(document, "radio", "")
        try:
            check_radio_url(radio)
        except RadioError as exc:
            raise top.error("radio", str(exc)) from None
    folder = path.parent
    fleet = None
    if "fleet" in document:
        fleet = folder / top.text(document, "fleet", "")
        try:
            load_fleet(fleet)  # read again by each trial: found wanting before the first
        except FleetFileError as exc:
            raise top.error("fleet", str(exc)) from None
    log_dir = document.get("log_dir")
    between = top.choice(document, "between", "pause", BETWEEN)
    pause_s = top.number(document, "pause_s", 0.0) or 0.0
    raw_trials = document.get("trial")
    if raw_trials is None:
        raise ExperimentFileError(f"{path}:1: trial: no trials; add one [[trial]] table per trial")
    if not isinstance(raw_trials, list) or not all(isinstance(t, dict) for t in raw_trials):
        raise top.error("trial", "write each trial as a [[trial]] table")
    trials = tuple(
        _trial(path, lines, number, table, between, pause_s)
        for number, table in enumerate(raw_trials, start=1)
    )
    particles = top.whole(document, "particles", None, 1, 253)
    return Experiment(
        path=path,
        name=top.text(document, "name", path.stem),
        radio=radio,
        fleet=fleet,
        particles=particles,
        wait_s=top.number(document, "wait_s", 15.0, positive=True) or 15.0,
        on_failure=top.choice(document, "on_failure", "continue", ON_FAILURE),
        log_dir=None if log_dir is None else folder / top.text(document, "log_dir", ""),
        notes=top.text(document, "notes", ""),
        trials=trials,
    )


def _trial(
    path: Path,
    lines: dict[str, int],
    number: int,
    table: dict[str, Any],
    between: str,
    pause_s: float,
) -> Trial:
    read = _Reader(path, lines, f"trial[{number}]", f"trial {number}: ")
    read.only(table, _TRIAL_KEYS)
    if "method" not in table:
        raise read.error("", 'no method: write method = "D" (or A, B, C)')
    if "duration_s" not in table:
        raise read.error("", "no duration: write duration_s = SECONDS")
    try:
        method = method_of(read.text(table, "method", "D"))
    except ValueError:
        raise read.error("method", f"must be A, B, C or D, not '{table['method']}'") from None
    duration = read.number(table, "duration_s", None, positive=True)
    assert duration is not None

    def start_option(key: str, param: Param) -> int:
        spec = PARAM_SPECS[param]
        value = read.whole(table, key, 0, 0, spec.max) or 0
        if value and value < spec.min:
            raise read.error(key, f"must be {spec.min}..{spec.max}, or 0 for the stored value")
        return value

    phototaxis = table.get("phototaxis", False)
    if not isinstance(phototaxis, bool):
        raise read.error("phototaxis", f"must be true or false, not {phototaxis!r}")
    return Trial(
        number=number,
        name=read.text(table, "name", f"trial {number}"),
        method=method,
        duration_s=duration,
        cycle_steps=start_option("cycle_steps", Param.CYCLE_STEPS),
        wave_size=start_option("wave_size", Param.WAVE_SIZE),
        update_interval_s=start_option("update_interval_s", Param.UPDATE_INTERVAL_S),
        phototaxis=phototaxis,
        repetitions=read.whole(table, "repetitions", 1, 1, 1000) or 1,
        between=read.choice(table, "between", between, BETWEEN),
        pause_s=read.number(table, "pause_s", pause_s) or 0.0,
        notes=read.text(table, "notes", ""),
        settings=_settings(path, lines, number, table.get("set", {})),
    )


def _settings(path: Path, lines: dict[str, int], number: int, table: object) -> dict[Param, int]:
    read = _Reader(path, lines, f"trial[{number}].set", f"trial {number}: set.")
    if not isinstance(table, dict):
        raise read.error("", "write the parameters as a [trial.set] table under the trial")
    settings: dict[Param, int] = {}
    names = {param.name.lower(): param for param in Param}
    for key in table:
        param = names.get(key.lower())
        if param is None:
            close = difflib.get_close_matches(key.lower(), names, n=1)
            hint = (
                f" (did you mean '{close[0]}'?)"
                if close
                else "; `particlebot console` lists them with 'params'"
            )
            raise read.error(key, f"no such parameter{hint}")
        spec = PARAM_SPECS[param]
        value = read.whole(table, key, None, spec.min, spec.max)
        assert value is not None
        settings[param] = value
    return settings


def is_simulated(url: str) -> bool:
    return parse_radio_url(url).scheme in SIMULATED


def check_radio_url(url: str) -> None:
    """The URL's options checked without opening the radio, so that a mistake shows before the
    first trial rather than at it; RadioError says what is wrong. A real radio's own options
    (baud, ...) are checked when it opens."""
    parsed = parse_radio_url(url)
    if parsed.scheme == "virtual":
        from particlebot.radio.virtual import virtual_config

        virtual_config(parsed)
    elif parsed.scheme == "emulated":
        from particlebot.radio.emulated import emulated_config

        emulated_config(parsed)
    if parsed.scheme in SIMULATED:
        parsed.get_speed()
    faults_from_url(parsed)
