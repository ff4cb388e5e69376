"""Servo calibration end to end on virtual particles: each answer is the radius a made-up servo
gives for the pulse the particle really puts out, so the table is right only if every hold was;
then the table written, read back and recorded, and the hold ended however the command ends."""

from __future__ import annotations

import io
import math
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from particlebot.calibration.photocells import CalibrationError
from particlebot.calibration.prompts import NobodyAnswers, Prompter
from particlebot.calibration.servo import POINTS, TABLE_PARAMS, target_radii_mm
from particlebot.calibration.servo_bench import (
    MAX_HOLD_WAIT_S,
    ServoBench,
    calibrate_servo,
)
from particlebot.cli import main
from particlebot.fleet import Fleet, ParticleRecord, load_fleet, save_fleet
from particlebot.protocol import PARAM_SPECS, Param, State
from particlebot.swarm.api import Swarm

DEFAULT_TABLE = [PARAM_SPECS[p].default for p in TABLE_PARAMS]
TARGETS = target_radii_mm(
    PARAM_SPECS[Param.RADIUS_MIN_UM].default, PARAM_SPECS[Param.RADIUS_MAX_UM].default
)
PARTICLE = 2


def transmission(pulse: float) -> float:
    """The made-up servo and linkage: radius (mm) for a pulse, far from the default table."""
    return 70 + 55 * math.sin(math.pi / 2 * (pulse - 950) / 900)


@pytest.fixture
def swarm() -> Iterator[Swarm]:
    with Swarm.open("virtual://3?speed=max&loss=0.1&seed=6", log_dir=None) as opened:
        yield opened


def firmware(swarm: Swarm, particle_id: int = PARTICLE):  # type: ignore[no-untyped-def]
    world = swarm.radio.swarm  # type: ignore[attr-defined]
    return next(p for p in world.native.firmware if p.id == particle_id)


def person(
    swarm: Swarm, script: list[str] | None = None, held: list[int] | None = None
) -> Callable[[str], str]:
    """Answers a prompt as someone measuring the particle would: a point's radius is read off
    the servo pulse the particle puts out now (and it must be holding); `script` answers first
    (b, r, a point number, q ...), one per prompt, where it says something other than ''."""
    queue = list(script or [])

    def ask(prompt: str) -> str:
        if queue:
            word = queue.pop(0)
            if word != "":
                return word
        if "holding" in prompt:
            particle = firmware(swarm)
            pulse = particle.servo_pulse_us
            assert particle.status().state == State.HOLDING
            assert f"holding {pulse} us" in prompt  # what is said is what goes out
            if held is not None:
                held.append(pulse)
            return f"{transmission(pulse):.2f}"
        return ""  # the review: Enter writes

    return ask


def table_of(swarm: Swarm) -> list[int]:
    return [swarm.get(param, of=PARTICLE).values[PARTICLE] for param in TABLE_PARAMS]


def test_the_table_measured_at_held_pulses_gives_every_target_radius(
    swarm: Swarm, tmp_path: Path
) -> None:
    fleet_path = tmp_path / "fleet.toml"
    fleet = Fleet.new()
    fleet.record(ParticleRecord(PARTICLE))
    save_fleet(fleet, fleet_path)
    held: list[int] = []
    out = io.StringIO()
    bench = ServoBench(swarm, PARTICLE, Prompter(person(swarm, held=held)), out)
    outcome = calibrate_servo(bench, pulses=None, fleet_path=fleet_path)
    assert held == DEFAULT_TABLE  # the particle's own table, point by point
    new = table_of(swarm)
    assert new == list(outcome.table.pulses) != DEFAULT_TABLE
    achieved = [transmission(p) for p in new]
    assert max(abs(a - t) for a, t in zip(achieved, TARGETS, strict=True)) < 0.6
    assert load_fleet(fleet_path).particles[PARTICLE].calibration == {
        param.name: value for param, value in zip(TABLE_PARAMS, new, strict=True)
    }
    # The hold is over: the particle rests, its servo at the new table's contracted pulse.
    swarm.sleep(0.5)
    assert firmware(swarm).status().state == State.IDLE
    assert firmware(swarm).servo_pulse_us == new[0]


def test_back_a_point_wrong_answers_and_measuring_again_at_the_review(swarm: Swarm) -> None:
    # Points 0 and 1, then b at point 2: point 1 again; at point 2 two answers that are no
    # radius, then the rest; at the review point 3 measured again before Enter writes.
    script = ["", "", "b", "", "abc", "-4", *[""] * 7, "3", ""]
    held: list[int] = []
    out = io.StringIO()
    bench = ServoBench(swarm, PARTICLE, Prompter(person(swarm, script, held)), out)
    calibrate_servo(bench, pulses=None, fleet_path=None)
    assert held[:4] == [*DEFAULT_TABLE[:2], DEFAULT_TABLE[1], DEFAULT_TABLE[2]]
    assert held[-1] == DEFAULT_TABLE[3]  # measured again at the review
    assert out.getvalue().count("is not a radius in mm") == 2
    achieved = [transmission(p) for p in table_of(swarm)]
    assert max(abs(a - t) for a, t in zip(achieved, TARGETS, strict=True)) < 0.6


def test_ctrl_c_mid_way_ends_the_hold_and_writes_nothing(swarm: Swarm) -> None:
    answered = person(swarm)
    calls = 0

    def interrupted(prompt: str) -> str:
        nonlocal calls
        calls += 1
        if calls == 4:
            raise KeyboardInterrupt
        return answered(prompt)

    bench = ServoBench(swarm, PARTICLE, Prompter(interrupted), io.StringIO())
    with pytest.raises(KeyboardInterrupt):
        calibrate_servo(bench, pulses=None, fleet_path=None)
    assert swarm.particle(PARTICLE).state == State.IDLE  # type: ignore[union-attr]
    assert firmware(swarm).servo_pulse_us == DEFAULT_TABLE[0]
    assert table_of(swarm) == DEFAULT_TABLE


def test_radii_that_do_not_follow_the_pulse_are_never_written(swarm: Swarm) -> None:
    radii = iter([80, 84, 88, 92, 90, 100, 104, 108, 112])

    def ask(prompt: str) -> str:
        if "holding" in prompt:
            return str(next(radii))
        raise EOFError  # the review: nobody there to measure again

    bench = ServoBench(swarm, PARTICLE, Prompter(ask), io.StringIO())
    with pytest.raises(CalibrationError, match=r"point 4 \(90 mm.*nothing was written"):
        calibrate_servo(bench, pulses=None, fleet_path=None)
    assert table_of(swarm) == DEFAULT_TABLE
    assert swarm.particle(PARTICLE).state == State.IDLE  # type: ignore[union-attr]


def test_nobody_answering_ends_the_hold(swarm: Swarm) -> None:
    def closed(prompt: str) -> str:
        raise EOFError

    bench = ServoBench(swarm, PARTICLE, Prompter(closed), io.StringIO())
    with pytest.raises(NobodyAnswers):
        calibrate_servo(bench, pulses=None, fleet_path=None)
    assert swarm.particle(PARTICLE).state == State.IDLE  # type: ignore[union-attr]


@pytest.mark.slow
def test_a_hold_is_renewed_while_the_person_measures_then_let_go(swarm: Swarm) -> None:
    out = io.StringIO()
    bench = ServoBench(swarm, PARTICLE, Prompter(person(swarm)), out)
    bench.find()
    bench.hold(1600)
    start = swarm.now()
    while swarm.now() - start < 90:  # longer than any one SERVO_HOLD lasts in the firmware
        bench.keep_alive()
    assert firmware(swarm).servo_pulse_us == 1600
    while swarm.now() - start < MAX_HOLD_WAIT_S + 1:
        bench.keep_alive()
    swarm.sleep(0.5)
    assert firmware(swarm).status().state == State.IDLE
    assert "the servo rests now" in out.getvalue()


def run_command(args: list[str], answers: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "particlebot.cli", "calibrate", "servo", *args],
        input=answers,
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=120,
        check=False,
    )


@pytest.mark.e2e
def test_the_command_takes_its_answers_from_stdin_and_draws_the_table(tmp_path: Path) -> None:
    radii = "\n".join(f"{transmission(p):.1f}" for p in DEFAULT_TABLE)
    done = run_command(["2", "--radio", "virtual://3", "-o", "servo.csv"], radii + "\n\n", tmp_path)
    assert done.returncode == 0, done.stderr
    assert "Wrote and read back particle 2's table" in done.stdout
    assert (tmp_path / "servo.png").stat().st_size > 0
    rows = (tmp_path / "servo.csv").read_text().splitlines()
    assert rows[0] == "point,pulse_us,radius_mm,table_pulse_us,table_radius_mm"
    assert len(rows) == 1 + POINTS


@pytest.mark.e2e
def test_the_command_with_nobody_to_answer_says_so_in_one_line(tmp_path: Path) -> None:
    done = run_command(["2", "--radio", "virtual://3"], "", tmp_path)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "particlebot: calibrate servo: nobody can answer the prompt (no input): stopped, nothing "
        "more was written; answer on a terminal, or give the answers on stdin"
    ]


def test_a_table_that_would_not_be_monotonic_ends_the_command_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    radii = ["80", "84", "88", "92", "90", "100", "104", "108", "112"]  # point 4 shrinks
    monkeypatch.setattr("sys.stdin", io.StringIO("\n".join(radii) + "\n"))
    assert main(["calibrate", "servo", "2", "--radio", "virtual://3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "point 4 (90 mm at 1370 us) is not above point 3" in err[0]
    assert err[0].endswith("nothing was written")
    assert not (tmp_path / "calibration").exists()
