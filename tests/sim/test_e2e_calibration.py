"""Both calibrations on the real firmware image in simavr: the servo pulse on D9 while each point
is held, the table written through the image's own monotonicity check; photocells with a spread
fitted, corrected by the image's fixed-point arithmetic, and V_x captured."""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from particlebot.calibration.bench import Bench, calibrate_sensors, readings_meta
from particlebot.calibration.photocells import GAMMA_PARAMS
from particlebot.calibration.placements import Placement, SimulatedPlacer, ring, trials
from particlebot.calibration.positions import check_positions
from particlebot.calibration.prompts import Prompter
from particlebot.calibration.readings import Readings, ReadingsWriter
from particlebot.calibration.servo import TABLE_PARAMS, target_radii_mm
from particlebot.calibration.servo_bench import ServoBench, calibrate_servo
from particlebot.protocol import PARAM_SPECS, Param, State
from particlebot.radio.emulated import EmulatedRadio
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.swarm.api import Swarm
from tests.sim.particles.emulated.test_smoke import SERVO_JITTER_US

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

DEFAULT_TABLE = [PARAM_SPECS[p].default for p in TABLE_PARAMS]


def transmission(pulse: float) -> float:
    """A made-up servo: radius (mm) for a pulse."""
    return 72 + 52 * math.sin(math.pi / 2 * (pulse - 940) / 880)


@pytest.fixture
def emulated() -> Iterator[tuple[Swarm, SimSwarm]]:
    # keep_history: the servo pulses stay recorded for the test to read.
    world = SimSwarm(
        SwarmConfig(level=Level.EMULATED, count=3, keep_history=True, photocell_spread=0.12, seed=3)
    )
    swarm = Swarm(
        EmulatedRadio(world, url="emulated://3", owns_swarm=True), log_dir=None, stepped=True
    )
    try:
        yield swarm, world
    finally:
        swarm.close()


def test_servo_calibration_holds_each_pulse_on_d9_and_writes_a_table_the_image_takes(
    emulated: tuple[Swarm, SimSwarm],
) -> None:
    swarm, world = emulated
    sim = world.emulated.sims[1]  # particle 2
    held: list[int] = []

    def measure(prompt: str) -> str:
        if "holding" not in prompt:
            return ""  # the review: Enter writes
        # A person takes a moment to measure; meanwhile every pulse on the servo pin is the
        # held one.
        swarm.sleep(0.3)
        now = world.time_s
        widths = [p.width_us for p in sim.servo_pulses if p.start_s > now - 0.2]
        assert len(widths) >= 8
        pulse = round(float(np.median(widths)))
        assert all(abs(w - pulse) <= SERVO_JITTER_US for w in widths)
        said = int(prompt.split("holding ")[1].split(" us")[0])
        assert abs(said - pulse) <= 3  # what the prompt says is what goes out (1 us ticks)
        held.append(pulse)
        return f"{transmission(pulse):.2f}"

    bench = ServoBench(swarm, 2, Prompter(measure), io.StringIO())
    outcome = calibrate_servo(bench, pulses=None, fleet_path=None)
    assert all(abs(h - d) <= 3 for h, d in zip(held, DEFAULT_TABLE, strict=True))
    back = [swarm.get(param, of=2).values[2] for param in TABLE_PARAMS]
    assert back == list(outcome.table.pulses)
    targets = target_radii_mm(
        PARAM_SPECS[Param.RADIUS_MIN_UM].default, PARAM_SPECS[Param.RADIUS_MAX_UM].default
    )
    assert max(abs(transmission(p) - t) for p, t in zip(back, targets, strict=True)) < 0.6
    # Let go: contracted, at the new table's first pulse.
    swarm.sleep(0.3)
    assert swarm.particle(2).state == State.IDLE  # type: ignore[union-attr]
    last = [p.width_us for p in sim.servo_pulses if p.start_s > world.time_s - 0.1]
    assert last and all(abs(w - back[0]) <= SERVO_JITTER_US for w in last)


def test_photocell_calibration_on_the_image_makes_eq14_hold(
    emulated: tuple[Swarm, SimSwarm], tmp_path: Path
) -> None:
    swarm, world = emulated
    ids = [1, 2, 3]
    out = io.StringIO()
    swarm.wait_for(count=3, timeout=30)
    bench = Bench(swarm, SimulatedPlacer(swarm.radio, out), out, frames=1, settle_s=0.3)

    def measured(plan: list[Placement], name: str) -> Readings:
        meta = readings_meta("test", "emulated://3", 28.0, 2)
        writer = ReadingsWriter(tmp_path / name, meta)
        try:
            return Readings(bench.measure_all(plan, writer), meta)
        finally:
            writer.close()

    outcome = calibrate_sensors(
        measured(ring(ids, [20, 50, 100]), "s.csv"), 28.0, bench=bench, fleet_path=None
    )
    truth = world.light.photocells
    assert truth is not None
    fitted = np.array(
        [[c.gamma if c else np.nan for c in fit.cells] for fit in outcome.calibration.fits]
    )
    assert np.abs(fitted - truth.gamma).max() < 0.03
    for pid in ids:
        assert (
            swarm.get(GAMMA_PARAMS[2], of=pid).values[pid]
            == (outcome.calibration.corrections[pid].gamma_milli[2])
        )
    check = check_positions(measured(trials(ids, [0.0, 40.0, 80.0], 1), "c.csv"), 28.0)
    # Millivolts, then the ADC: one more rounding than on virtual particles.
    assert check.rms_after() < 2.0
    assert check.rms_before() > 3 * check.rms_after()
