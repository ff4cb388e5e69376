"""Servo calibration on the real image: SERVO_HOLD puts the held pulse on D9 and STATUS says so;
the hold ends by itself, on STOP, and is refused while the particle runs."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from particlebot.protocol import (
    PARAM_SPECS,
    UNASSIGNED_ID,
    Method,
    Param,
    ServoHold,
    Start,
    State,
    Status,
    Stop,
)
from particlebot.sim.particles.emulated.harness import ParticleSim
from tests.sim.particles.emulated.test_smoke import SERVO_JITTER_US, Base

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

CONTRACTED_US = PARAM_SPECS[Param.SERVO_CAL_0].default
FRAME_S = 0.020


@pytest.fixture
def particle() -> Iterator[ParticleSim]:
    with ParticleSim() as sim:
        yield sim


def answer_to(base: Base, message: ServoHold | Stop) -> Status:
    """The STATUS the particle sends within 100 ms of message (SERVO_HOLD answers at once)."""
    asked_s = base.sim.time_s
    base.send(message)
    base.run(0.1)
    answers = base.statuses(since_s=asked_s)
    assert answers, "no STATUS answered"
    return answers[0][2]


def widths_between(sim: ParticleSim, start_s: float, end_s: float) -> list[float]:
    return [p.width_us for p in sim.servo_pulses if start_s <= p.start_s < end_s]


def test_a_held_pulse_goes_out_until_its_time_is_up(particle: ParticleSim) -> None:
    base = Base(particle)
    base.run(0.5)
    held_s = particle.time_s
    status = answer_to(base, ServoHold(target=UNASSIGNED_ID, pulse_us=1800, hold_s=2))
    assert (status.state, status.servo_pulse_us) == (State.HOLDING, 1800)
    base.run(2.2)
    # From the frame after the command to the end of the 2 s: every pulse is the held one.
    held = widths_between(particle, held_s + 2 * FRAME_S, held_s + 2.0 - FRAME_S)
    assert len(held) >= 95
    assert all(abs(width - 1800) <= SERVO_JITTER_US for width in held)
    # Then back to the contracted pulse, and STATUS says so.
    after = widths_between(particle, held_s + 2.0 + 2 * FRAME_S, particle.time_s)
    assert after and all(abs(width - CONTRACTED_US) <= SERVO_JITTER_US for width in after)
    _, status = base.ping()
    assert (status.state, status.servo_pulse_us) == (State.IDLE, CONTRACTED_US)


def test_stop_ends_a_hold_and_a_running_particle_refuses_one(particle: ParticleSim) -> None:
    base = Base(particle)
    base.run(0.5)
    answer_to(base, ServoHold(target=UNASSIGNED_ID, pulse_us=2200, hold_s=30))
    base.run(0.2)
    stopped_s = particle.time_s
    base.send(Stop())
    base.run(0.3)
    after = widths_between(particle, stopped_s + 2 * FRAME_S, particle.time_s)
    assert after and all(abs(width - CONTRACTED_US) <= SERVO_JITTER_US for width in after)

    base.send(
        Start(
            run_id=1,
            method=Method.DIRECT,
            cycle_steps=75,
            wave_size=1,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    base.run(0.2)
    status = answer_to(base, ServoHold(target=UNASSIGNED_ID, pulse_us=2200, hold_s=30))
    assert status.state == State.ESTIMATING
    assert status.servo_pulse_us == CONTRACTED_US
