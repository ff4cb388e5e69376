"""Photocell calibration end to end on virtual particles (the firmware logic): readings, fit,
corrections written and confirmed, V_x captured, the fleet file, Fig. S5 and method A itself."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from particlebot.calibration.bench import Bench, calibrate_sensors, readings_meta
from particlebot.calibration.photocells import GAIN_PARAMS, GAMMA_PARAMS
from particlebot.calibration.placements import (
    PersonPlacer,
    Placement,
    SimulatedPlacer,
    ring,
    trials,
)
from particlebot.calibration.positions import check_positions
from particlebot.calibration.prompts import NobodyAnswers, Prompter, Quit
from particlebot.calibration.readings import Readings, ReadingsWriter, read_readings
from particlebot.cli import main
from particlebot.experiments.measure import place
from particlebot.fleet import Fleet, ParticleRecord, load_fleet, save_fleet
from particlebot.protocol import Param
from particlebot.swarm.api import Swarm

IDS = [1, 2, 3, 4, 5, 6]
URL = "virtual://6?speed=max&photocell_spread=0.12&seed=5"
LINE_CM = [15.5 * k for k in range(len(IDS))]


def make_fleet(path: Path, ids: list[int]) -> Path:
    fleet = Fleet.new()
    for particle_id in ids:
        fleet.record(ParticleRecord(particle_id))
    save_fleet(fleet, path)
    return path


def measured(bench: Bench, plan: list[Placement], path: Path) -> Readings:
    meta = readings_meta("test", bench.swarm.url, 28.0, bench.frames)
    writer = ReadingsWriter(path, meta)
    try:
        rows = bench.measure_all(plan, writer)
    finally:
        writer.close()
    return Readings(rows, meta, path)


def method_a_ranks(swarm: Swarm) -> list[int]:
    """S_n each particle works out by method A for itself, standing on the line."""
    place(swarm.radio, {pid: (d / 100, 0.0) for pid, d in zip(IDS, LINE_CM, strict=True)})
    swarm.sleep(1)
    swarm.start("A", cycle_steps=75)
    swarm.sleep(4)  # past the 3 s estimation round
    fresh = swarm.sample(IDS, 1)
    swarm.stop()
    return [fresh[pid][0].s_n for pid in IDS]


def test_calibrated_virtual_particles_follow_one_law_and_rank_themselves_right(
    tmp_path: Path,
) -> None:
    fleet_path = make_fleet(tmp_path / "fleet.toml", IDS)
    out = io.StringIO()
    with Swarm.open(URL, log_dir=None, fleet=fleet_path) as swarm:
        swarm.wait_for(count=len(IDS))
        bench = Bench(swarm, SimulatedPlacer(swarm.radio, out), out, frames=3)
        readings = measured(bench, ring(IDS, [20, 40, 70, 100]), tmp_path / "sensors.csv")
        outcome = calibrate_sensors(readings, 28.0, bench=bench, fleet_path=fleet_path)

        truth = swarm.radio.swarm.light.photocells  # type: ignore[attr-defined]
        fitted = np.array(
            [[c.gamma if c else np.nan for c in fit.cells] for fit in outcome.calibration.fits]
        )
        assert np.abs(fitted - truth.gamma).max() < 0.03
        for pid, correction in outcome.calibration.corrections.items():
            for param in (GAMMA_PARAMS[0], GAIN_PARAMS[5]):
                assert swarm.get(param, of=pid).values[pid] == correction.params()[param]
        assert outcome.written == IDS
        assert outcome.reference_value is not None
        assert abs(outcome.reference_value - 980) <= 3  # the law is centred on these cells
        assert swarm.get(Param.REF_VALUE).values == dict.fromkeys(IDS, outcome.reference_value)

        check = check_positions(measured(bench, trials(IDS, LINE_CM, 3), tmp_path / "c.csv"), 28)
        after_ranks = method_a_ranks(swarm)
    assert check.rms_after() < 1.5
    assert check.rms_before() > 2 * check.rms_after()
    # The firmware's own method A, with the corrections and the V_x captured: every particle
    # knows its place.
    assert after_ranks == [1, 2, 3, 4, 5, 6]
    fleet = load_fleet(fleet_path)
    assert fleet.photocells is not None
    assert fleet.photocells.scale == pytest.approx(outcome.calibration.law.scale)
    record = fleet.particles[3].calibration
    assert record["SENSOR_GAMMA_0"] == outcome.calibration.corrections[3].gamma_milli[0]
    assert record["REF_VALUE"] == outcome.reference_value
    assert record["REF_DISTANCE_MM"] == 280
    assert "Reference point: particle 1 reads" in out.getvalue()


@pytest.mark.e2e
def test_the_command_calibrates_checks_and_writes_its_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fleet_path = make_fleet(tmp_path / "fleet.toml", [1, 2, 3, 4])
    csv_path = tmp_path / "out" / "s.csv"
    code = main(
        [
            "calibrate",
            "sensors",
            "--radio",
            "virtual://4?photocell_spread=0.1&seed=2",
            "--fleet",
            str(fleet_path),
            "--distances",
            "25,50,90",
            "--frames",
            "2",
            "--check",
            "--trials",
            "2",
            "-o",
            str(csv_path),
            "--log-dir",
            str(tmp_path / "logs"),
        ]
    )
    out = capsys.readouterr().out
    assert code == 0, out
    assert "Fitted 4 particle(s) on 3 light levels" in out
    assert f"Recorded in {fleet_path}" in out
    for name in ("s.csv", "s.png", "s-check.csv", "s-check.png"):
        assert (tmp_path / "out" / name).stat().st_size > 0
    assert len(read_readings(csv_path).rows) == 4 * 3
    assert load_fleet(fleet_path).photocells is not None
    rms_line = next(line for line in out.splitlines() if line.startswith("RMS error"))
    # The files redraw and refit without particles.
    check_csv = tmp_path / "out" / "s-check.csv"
    assert main(["calibrate", "check", "--readings", str(check_csv), "--no-plot"]) == 0
    assert rms_line in capsys.readouterr().out
    assert main(["calibrate", "sensors", "--readings", str(csv_path), "--no-plot"]) == 0
    assert "Fitted 4 particle(s)" in capsys.readouterr().out


def test_line_readings_rotate_every_particle_through_the_places(tmp_path: Path) -> None:
    code = main(
        [
            "calibrate",
            "sensors",
            "--radio",
            "virtual://3?photocell_spread=0.1",
            "--line",
            "--distances",
            "10,40,80",
            "--steps",
            "3",
            "--no-write",
            "--frames",
            "1",
            "--no-plot",
            "-o",
            str(tmp_path / "line.csv"),
            "--log-dir",
            str(tmp_path),
        ]
    )
    assert code == 0
    rows = read_readings(tmp_path / "line.csv").rows
    places = {pid: sorted(r.distance_cm or 0.0 for r in rows if r.id == pid) for pid in (1, 2, 3)}
    assert all(seen == [10.0, 40.0, 80.0] for seen in places.values())


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sensors", "--radio", "virtual://3", "--distances", "40"], "two or more different"),
        (
            ["sensors", "--radio", "virtual://3", "--line", "--distances", "0,15.5"],
            "one distance per particle: 2 distances for 3 particles",
        ),
        (["sensors", "--radio", "virtual://3", "--ids", "42"], "missing 42"),
        (["sensors", "--radio", "virtual://3", "--lux", "10,100"], "placed by distance"),
        (["sensors", "--radio", "virtual://3", "--distances", "20,nan"], "--distances"),
        (["sensors", "--readings", "missing.csv"], "no such readings file"),
        (["sensors"], "say which radio"),
        (["check", "--radio", "virtual://3", "--positions", "0,15"], "one position per particle"),
        (["check", "--radio", "virtual://2", "--trials", "0"], "--trials"),
        (["servo", "2", "--radio", "virtual://3", "--pulses", "1000,1100"], "9 pulses, not 2"),
        (["servo", "42", "--radio", "virtual://3"], "particle 42 did not answer"),
        (["servo", "0", "--radio", "virtual://3"], "1..253"),
    ],
)
def test_bad_input_gets_one_line_and_status_2(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    assert run_cli(["calibrate", *args]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err


def run_cli(args: list[str]) -> int:
    """main(), with argparse's exit for a bad option turned into its status."""
    try:
        return main(args)
    except SystemExit as exit_:
        return int(exit_.code or 0)


def test_a_person_is_told_where_each_particle_goes_and_enter_takes_the_readings(
    tmp_path: Path,
) -> None:
    out = io.StringIO()
    plan = ring([1, 2, 3], [20, 60, 100])
    told: list[str] = []
    with Swarm.open("virtual://3?speed=max&photocell_spread=0.1", log_dir=None) as swarm:
        swarm.wait_for(count=3)

        def person(prompt: str) -> str:
            # Does what the last instruction said, then presses Enter.
            told.append(out.getvalue().splitlines()[-1])
            placement = plan[len(told) - 1]
            place(swarm.radio, {i: (d / 100, 0.0) for i, d in placement.distances_cm.items()})
            return ""

        bench = Bench(swarm, PersonPlacer(Prompter(person), out), out, frames=2)
        readings = measured(bench, plan, tmp_path / "r.csv")
        outcome = calibrate_sensors(readings, 28.0, bench=None, fleet_path=None)
    assert told[1].startswith("Step 2 of 3: put particles 1-3 on a circle 60 cm from")
    assert len(outcome.calibration.fits) == 3


@pytest.mark.parametrize(("answer", "raised"), [("q", Quit), (None, NobodyAnswers)])
def test_a_person_who_quits_or_is_not_there_stops_it_before_anything_is_written(
    tmp_path: Path, answer: str | None, raised: type[Exception]
) -> None:
    def person(prompt: str) -> str:
        if answer is None:
            raise EOFError
        return answer

    out = io.StringIO()
    with Swarm.open("virtual://2?speed=max", log_dir=None) as swarm:
        swarm.wait_for(count=2)
        bench = Bench(swarm, PersonPlacer(Prompter(person), out), out)
        with pytest.raises(raised):
            measured(bench, ring([1, 2], [20, 60]), tmp_path / "r.csv")
        assert swarm.get(Param.SENSOR_GAIN_0).values == {1: 1000, 2: 1000}
    # The readings file is there, with its header: nothing half written.
    assert (tmp_path / "r.csv").read_text().count("\n") == len(readings_meta("", "", 1, 1)) + 2


def test_a_readings_file_that_cannot_be_fitted_or_written_gets_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    one = tmp_path / "one.csv"
    one.write_text("id,distance_cm,A0,A1,A2,A3,A4,A5\n1,40,900,901,902,903,904,905\n")
    four = tmp_path / "four.csv"
    four.write_text(
        "id,distance_cm,A0,A1,A2,A3,A4,A5\n"
        + "".join(
            f"{i},{d},{v},{v},{v},{v},{v},{v}\n"
            for i in (1, 2, 3, 4)
            for d, v in ((20, 950), (80, 700))
        )
    )
    for args, message in (
        (["--readings", str(one)], "particle 1 has readings at one distance only (40 cm)"),
        (["--readings", str(four), "--radio", "virtual://2"], "missing 3, 4"),
    ):
        assert run_cli(["calibrate", "sensors", *args]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
