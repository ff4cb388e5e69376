"""`particlebot run EXPERIMENT.toml`: trials end to end on virtual particles, and bad files."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any

import pytest

from particlebot.cli import main
from particlebot.swarm.api import Swarm

TWO_TRIALS = """\
# Two short trials, rehearsed on a simulated swarm at 20 % loss.
name = "rehearsal"
radio = "virtual://5?speed=max&loss=0.2&seed=4"
between = "pause"
pause_s = 0
notes = "make test"

[[trial]]
name = "counting"
method = "D"
cycle_steps = 75
duration_s = 25
notes = "first"

[[trial]]
name = "linear, tolerance 12"
method = "B"
cycle_steps = 75
duration_s = 10
[trial.set]
count_tolerance = 12
"""


def write(folder: Path, text: str, name: str = "experiment.toml") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def records(log: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in log.read_text().splitlines()]


def test_two_trials_run_one_after_another_with_a_log_each_and_a_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, TWO_TRIALS)
    assert main(["run", str(path), "--log-dir", str(tmp_path / "logs")]) == 0
    out = capsys.readouterr().out
    (folder,) = (tmp_path / "logs").glob("rehearsal-*")
    assert sorted(p.name for p in folder.iterdir()) == [
        "summary.csv",
        "trial-01-01.jsonl",
        "trial-02-01.jsonl",
    ]
    with (folder / "summary.csv").open() as file:
        rows = list(csv.DictReader(file))
    assert [(r["trial"], r["method"], r["stop_confirmed"]) for r in rows] == [
        ("1", "D", "yes"),
        ("2", "B", "yes"),
    ]
    assert [r["particles_lost"] for r in rows] == ["0", "0"]
    assert [float(r["duration_s"]) for r in rows] == pytest.approx([25, 10], abs=0.1)
    # Method D ranks the line and it creeps towards the lamp: ~80 mm a wave.
    assert float(rows[0]["toward_lamp_m"]) > 0.05
    # The table on screen says the same.
    header = next(line for line in out.splitlines() if line.startswith("trial"))
    assert header.split("  ")[0:2] == ["trial", "method"]
    assert "STOP confirmed" in header and "toward lamp m" in header
    # Each trial's log is a session log: the notes, the parameter set, START and STOP.
    first, second = (records(folder / f"trial-0{n}-01.jsonl") for n in (1, 2))
    notes = [r["text"] for r in first if r["kind"] == "note"]
    assert "trial 1 (counting)" in notes[0] and "make test; first" in notes[0]
    sent = [r["type"] for r in second if r["kind"] == "tx"]
    assert sent.index("SET_PARAM") < sent.index("START") < sent.index("STOP")
    assert "seed 5" in next(r["text"] for r in second if r["kind"] == "note")


def test_a_trial_that_cannot_start_is_reported_and_the_file_says_what_follows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = TWO_TRIALS.replace("pause_s = 0\n", "pause_s = 0\nparticles = 6\nwait_s = 2\n")
    path = write(tmp_path, text)
    assert main(["run", str(path), "--log-dir", str(tmp_path / "logs")]) == 1
    out = capsys.readouterr().out
    # Five particles exist; at 20 % loss 2 s may not even hear them all.
    assert len(re.findall(r"could not start: waited 2 s for 6: heard [1-5] \(", out)) == 2
    assert "[2/2] trial 2" in out  # on_failure = "continue" (the default)
    path = write(tmp_path, text.replace("wait_s = 2\n", 'wait_s = 2\non_failure = "stop"\n'))
    assert main(["run", str(path), "--log-dir", str(tmp_path / "stopped")]) == 1
    out = capsys.readouterr().out
    assert "the experiment stops here" in out and "[2/2]" not in out
    assert "trial 1: waited 2 s for 6" in out  # under the summary table


def test_ctrl_c_stops_the_swarm_first_then_ends_the_experiment(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = []
    sleep = Swarm.sleep

    def interrupted_sleep(self: Swarm, seconds: float) -> None:
        calls.append(seconds)
        sleep(self, min(seconds, 5.0))
        raise KeyboardInterrupt  # five seconds into the first trial

    monkeypatch.setattr(Swarm, "sleep", interrupted_sleep)
    path = write(tmp_path, TWO_TRIALS)
    assert main(["run", str(path), "--log-dir", str(tmp_path / "logs")]) == 130
    out = capsys.readouterr().out
    assert "Ctrl-C: sending STOP first" in out
    assert "STOP confirmed by all 5 particles" in out
    assert "[2/2]" not in out and "trial 1: interrupted (Ctrl-C)" in out
    (log,) = (tmp_path / "logs").glob("rehearsal-*/trial-01-01.jsonl")
    kinds = [(r["kind"], r.get("type")) for r in records(log)]
    assert kinds.index(("tx", "STOP")) > kinds.index(("tx", "START"))


@pytest.mark.parametrize(
    ("change", "line", "complaint"),
    [
        (('method = "D"', 'method = "D'), 10, "not valid TOML"),
        (('method = "D"', 'method = "E"'), 10, "trial 1: method: must be A, B, C or D, not 'E'"),
        (("duration_s = 25", "duraton_s = 25"), 12, "unknown key (did you mean 'duration_s'?)"),
        (("duration_s = 10", "duration_s = -1"), 19, "trial 2: duration_s: must be more than 0"),
        (("cycle_steps = 75\nduration_s = 10", "cycle_steps = 5\nduration_s = 10"), 18, "10..3000"),
        (("count_tolerance = 12", "count_tolerance = 9999"), 21, "set.count_tolerance: must be"),
        (("count_tolerance = 12", "count_tolerence = 12"), 21, "did you mean 'count_tolerance'?"),
        (('between = "pause"', 'between = "maybe"'), 4, "between: must be pause or prompt or none"),
        (('radio = "virtual', 'radio = "wireless'), 3, "radio: unknown radio kind 'wireless://'"),
        (("duration_s = 10\n", ""), 15, "trial 2: no duration: write duration_s = SECONDS"),
        (('name = "rehearsal"', "particles = 0"), 2, "particles: must be 1..253, not 0"),
        (("loss=0.2", "loss=2"), 3, "radio: virtual://5?speed=max&loss=2&seed=4: loss must be"),
        (("speed=max", "speed=0"), 3, "speed must be a number > 0 or max, not '0'"),
        (('notes = "make test"', 'fleet = "nowhere.toml"'), 6, "fleet: no fleet file"),
        (("duration_s = 25", "duration_s = 1e300"), 12, "must be at most 86400 s (a day)"),
        (("pause_s = 0", "pause_s = 1e9"), 5, "pause_s: must be at most 86400 s"),
    ],
)  # fmt: skip
def test_a_bad_experiment_file_gets_one_line_naming_file_line_and_key(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    change: tuple[str, str],
    line: int,
    complaint: str,
) -> None:
    old, new = change
    assert old in TWO_TRIALS
    path = write(tmp_path, TWO_TRIALS.replace(old, new, 1))
    assert main(["run", str(path), "--log-dir", str(tmp_path / "logs")]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    (message,) = captured.err.splitlines()
    assert message.startswith(f"particlebot: {path}:{line}: ")
    assert complaint in message
    assert not (tmp_path / "logs").exists()  # nothing ran


def test_files_without_trials_or_a_radio_or_at_all_are_one_line_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for text, complaint in [
        ('radio = "virtual://2"\n', ":1: trial: no trials"),
        ('[[trial]]\nmethod = "A"\nduration_s = 1\n', "say which radio"),
        (
            'radio = "serial:///dev/ttyUSB0"\n[[trial]]\nmethod = "A"\nduration_s = 1\n',
            "particles = N",
        ),
    ]:
        path = write(tmp_path, text)
        assert main(["run", str(path)]) == 2
        (message,) = capsys.readouterr().err.splitlines()
        assert complaint in message
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    assert "missing.toml: no such file" in capsys.readouterr().err


def test_a_prompt_between_runs_waits_for_the_person(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    text = TWO_TRIALS.replace('between = "pause"', 'between = "prompt"')
    text = text.replace("duration_s = 25", "duration_s = 3").replace(
        "duration_s = 10", "duration_s = 3"
    )
    asked: list[str] = []

    def answer(question: str) -> str:
        asked.append(question)
        return ""

    monkeypatch.setattr("builtins.input", answer)
    assert main(["run", str(write(tmp_path, text)), "--log-dir", str(tmp_path / "a")]) == 0
    assert asked == [
        "Put the swarm back for trial 2 (linear, tolerance 12), then press Enter (Ctrl-C ends "
        "the experiment) "
    ]
    capsys.readouterr()

    def closed(question: str) -> str:
        raise EOFError

    monkeypatch.setattr("builtins.input", closed)
    assert main(["run", str(write(tmp_path, text)), "--log-dir", str(tmp_path / "b")]) == 1
    out = capsys.readouterr().out
    assert "nobody can answer the prompt" in out and "[2/2]" not in out


def test_a_radio_given_on_the_command_line_is_checked_before_anything_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, TWO_TRIALS)
    argv = ["run", str(path), "--log-dir", str(tmp_path / "logs")]
    assert main([*argv, "--radio", "emulated://3?delay_ms=nan"]) == 2
    (message,) = capsys.readouterr().err.splitlines()
    assert "delay_ms must be a number >= 0, not 'nan'" in message
    assert not (tmp_path / "logs").exists()


def test_emulated_particles_stand_still_so_no_distance_toward_the_lamp_is_claimed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # kinematics=0: virtual particles that, like emulated ones, stay where they are put.
    text = TWO_TRIALS.replace("seed=4", "seed=4&kinematics=0")
    assert main(["run", str(write(tmp_path, text)), "--log-dir", str(tmp_path / "logs")]) == 0
    (folder,) = (tmp_path / "logs").glob("rehearsal-*")
    with (folder / "summary.csv").open() as file:
        assert [row["toward_lamp_m"] for row in csv.DictReader(file)] == ["-", "-"]
    capsys.readouterr()
