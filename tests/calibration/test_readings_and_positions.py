"""The readings file (written, read back, refused with one line) and Fig. S5's estimates."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from particlebot.calibration.photocells import CalibrationError
from particlebot.calibration.positions import check_positions, floor_distance_cm
from particlebot.calibration.readings import (
    Reading,
    Readings,
    ReadingsError,
    read_readings,
    write_readings,
)
from particlebot.sim.world.light import Lamp, LightField

HEADER = "id,distance_cm,A0,A1,A2,A3,A4,A5"


def test_a_readings_file_round_trips(tmp_path: Path) -> None:
    rows = [
        Reading(1, 3, 20.0, None, (950.2, 951, 949, 948.5, 952, 953), 951.4, 0, 5),
        Reading(2, 3, 40.0, None, (900.0, 901, 0, 899, 902, 903), 901.0, 4, 5),
    ]
    path = tmp_path / "r.csv"
    write_readings(Readings(rows, {"lamp_height_cm": "28", "kind": "calibration"}), path)
    back = read_readings(path)
    assert back.rows == rows
    assert back.lamp_height_cm == 28
    assert back.meta["kind"] == "calibration"
    # Stuck sensors (faults bit 2) are not healthy, and stay out of the raw intensity.
    assert not back.rows[1].healthy(2)
    assert back.rows[1].raw_intensity() == pytest.approx((900 + 901 + 899 + 902 + 903) / 5)


def test_a_hand_written_file_needs_only_id_distance_and_the_six_readings(tmp_path: Path) -> None:
    path = tmp_path / "hand.csv"
    path.write_text(f"{HEADER}\n4,0,980,981,979,980,980,980\n4,50,800,801,799,800,800,800\n")
    readings = read_readings(path)
    assert [r.distance_cm for r in readings.rows] == [0.0, 50.0]
    assert readings.rows[0].intensity is None and readings.lamp_height_cm is None


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "no column header"),
        ("id,A0,A1,A2,A3,A4,A5\n1,1,2,3,4,5,6\n", "the header lacks distance_cm or lux"),
        ("id,distance_cm,A0\n1,2,3\n", "the header lacks A1, A2"),
        (f"{HEADER}\n", "no readings below the header"),
        (f"{HEADER}\n1,20,980,980,980,980,980\n", ":2: 7 cells where the header names 8"),
        (f"{HEADER}\n1,nan,980,980,980,980,980,980\n", ":2: distance_cm must be a number"),
        (f"{HEADER}\n1,-5,980,980,980,980,980,980\n", ":2: distance_cm must be a number 0..inf"),
        (f"{HEADER}\n0,20,980,980,980,980,980,980\n", ":2: id must be a number 1..253"),
        (f"{HEADER}\n2.5,20,980,980,980,980,980,980\n", ":2: id must be a whole number"),
        (f"{HEADER}\n1,20,980,1024,980,980,980,980\n", ":2: A1 must be a number 0..1023"),
        (f"{HEADER},lux\n1,20,980,980,980,980,980,980,100\n", "give distance_cm or lux"),
        (
            "id,distance_cm,lux,A0,A1,A2,A3,A4,A5\n1,20,,1,1,1,1,1,1\n1,,100,1,1,1,1,1,1\n",
            "some rows give distance_cm and others lux",
        ),
    ],
)
def test_a_bad_readings_file_gets_one_line_with_where(
    tmp_path: Path, text: str, message: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ReadingsError, match=message) as caught:
        read_readings(path)
    assert "\n" not in str(caught.value)


def test_a_missing_file_or_a_folder_is_one_line_too(tmp_path: Path) -> None:
    with pytest.raises(ReadingsError, match="no such readings file"):
        read_readings(tmp_path / "missing.csv")
    with pytest.raises(ReadingsError, match="is a folder"):
        read_readings(tmp_path)
    (tmp_path / "binary.csv").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ReadingsError, match="not a text"):
        read_readings(tmp_path / "binary.csv")


@pytest.mark.parametrize("ground_cm", [0.0, 15.5, 62.0, 124.0])
def test_eqs_14_15_give_back_the_distance_an_ideal_cell_read(ground_cm: float) -> None:
    field = LightField(Lamp(0, 0, 0.28))
    value = field.reading(ground_cm / 100, 0.0)
    reference = field.reading(0.0, 0.0)  # 980, right under the lamp
    assert floor_distance_cm(value, reference, 0.0, 28.0) == pytest.approx(ground_cm, abs=1e-6)
    # A reference elsewhere on the line gives the same answer.
    elsewhere = field.reading(0.3, 0.0)
    assert floor_distance_cm(value, elsewhere, 30.0, 28.0) == pytest.approx(ground_cm, abs=1e-6)
    assert math.isnan(floor_distance_cm(1023, reference, 0.0, 28.0))


def line_readings(trials: int, offset: float = 0.0) -> Readings:
    """A line of four particles 15.5 cm apart; particle 2 reads as if `offset` cm further, and
    1 cm further again in each later trial."""
    field = LightField(Lamp(0, 0, 0.28), direction_gain=0.0)
    rows = []
    for trial in range(1, trials + 1):
        for index in range(4):
            distance = 15.5 * index
            seen = distance + (offset + trial - 2 if index == 1 else 0.0)
            values = tuple(float(v) for v in field.sensor_values(seen / 100, 0.0))
            rows.append(Reading(trial, index + 1, distance, None, values, intensity=values[0]))
    return Readings(rows, {"lamp_height_cm": "28"})


def test_fig_s5_estimates_each_particle_per_trial_with_the_nearest_as_reference() -> None:
    check = check_positions(line_readings(3, offset=5.0), 28.0)
    assert check.reference_id == 1 and check.trials == 3
    second = check.particles[1]
    assert second.true_cm == 15.5 and len(second.before_cm) == 3
    assert second.before_mean - second.true_cm == pytest.approx(5.0, abs=0.6)
    assert second.before_sd > 0
    assert check.worst_before() == pytest.approx(5.0, abs=0.6)
    assert check.rms_before() < check.worst_before()
    assert check.has_after


def test_a_check_refuses_moved_particles_lux_and_a_trial_without_its_reference() -> None:
    readings = line_readings(2)
    moved = Readings([*readings.rows, Reading(3, 2, 40.0, None, readings.rows[1].sensors)])
    with pytest.raises(CalibrationError, match=r"particle 2 stands at 15\.5 and at 40 cm"):
        check_positions(moved, 28.0)
    no_reference = Readings([r for r in readings.rows if not (r.step == 2 and r.id == 1)])
    with pytest.raises(CalibrationError, match="trial 2 has no reading of the reference"):
        check_positions(no_reference, 28.0)
    lux = Readings([Reading(1, 1, None, 10.0, (1.0,) * 6), Reading(1, 2, None, 5.0, (1.0,) * 6)])
    with pytest.raises(CalibrationError, match="not lux"):
        check_positions(lux, 28.0)
