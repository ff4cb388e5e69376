"""The real firmware in simavr gives every 50 Hz servo frame of a cycle its own eq. 4 step."""

from __future__ import annotations

import itertools
import random
from collections.abc import Iterator

import pytest

from particlebot.firmware.native import settings_image
from particlebot.protocol import (
    BASE_STATION_ID,
    Intensity,
    Method,
    Param,
    Ping,
    Start,
    Stop,
    encode_frame,
)
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.particles.emulated.harness import ParticleSim, ServoPulse
from particlebot.sim.particles.emulated.servo import cycle_profile_us, servo_step_s

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

PARTICLE_ID = 1
ROUND_MS = 200
# Ten steps a cycle: neighbouring steps then differ by 76 us or more, far beyond the edge jitter
# (an edge waits while another interrupt finishes), so a repeated or skipped step cannot hide.
STEP_S = servo_step_s()  # one servo step, as the firmware defines it
CYCLE_STEPS = 10
FRAME_CYCLES = round(STEP_S * CPU_HZ)
# An edge of the pulse waits while another interrupt (Serial1, Timer0) finishes: ~15 us at most.
SERVO_JITTER_US = 20
RUN_S = 1.5
"""Each START: a ramp down from wherever the last run left the body, the round, then cycles."""
MEASURE_FROM_S = 0.8
"""Well after the ramp (<= 0.6 s) and the round; until the next START."""
CLOCK_MS = 1.0
"""Resolution of the particle's clock."""
PHASES = 10
"""STARTs arriving at 10 different instants of the servo frame, 2 ms apart."""


@pytest.fixture
def particle() -> Iterator[ParticleSim]:
    image = settings_image(PARTICLE_ID, {Param.ROUND_MS: ROUND_MS})
    with ParticleSim(eeprom=image, light_mv=(1500, 1600, 1700, 1800, 1900, 2000)) as sim:
        yield sim


def load(sim: ParticleSim, rng: random.Random, seconds: float) -> None:
    """Runs `seconds` while keeping the radio busy both ways: every 50 ms a PING to this particle
    (a 54-byte STATUS goes back), another particle's INTENSITY and some garbage come in."""
    end = sim.cycle + round(seconds * CPU_HZ)
    seq = 0
    while sim.cycle < end:
        sim.send_uart(
            encode_frame(Ping(target=PARTICLE_ID), BASE_STATION_ID, seq % 256)
            + encode_frame(Intensity(run_id=200, round=0, repeat=0, intensity=300), 9, seq % 256)
            + rng.randbytes(rng.randint(0, 16))
        )
        seq += 1
        sim.run_until(min(end, sim.cycle + round(0.05 * CPU_HZ)))


def send_start_at_phase(sim: ParticleSim, run_id: int, phase_ms: float) -> int:
    """Queues START so that its last byte is in phase_ms after a servo frame begins (the rising
    edge of a pulse); returns the cycle at which it is in."""
    frame = encode_frame(
        Start(
            run_id=run_id,
            method=int(Method.COUNTING),
            cycle_steps=CYCLE_STEPS,
            wave_size=1,
            update_interval_s=0,
            phototaxis=0,
        ),
        BASE_STATION_ID,
        run_id,
    )
    on_wire = round(len(frame) * 10 * CPU_HZ / 9600)
    rise = sim.servo_pulses[-1].start_cycle
    received = rise + round(phase_ms * CPU_HZ / 1000)
    while received - on_wire <= sim.cycle + CPU_HZ // 100:
        received += FRAME_CYCLES
    sim.run_until(received - on_wire)
    sim.send_uart(frame)
    return received


def step_errors(pulses: list[ServoPulse], profile: list[float]) -> tuple[int, list[float]]:
    """Fits the back-to-back cycles of CYCLE_STEPS steps to the frames: the frame offset of step 0
    that fits best, and how far each frame's width is from the step it should show."""
    widths = [p.width_us for p in pulses]

    def errors(offset: int) -> list[float]:
        return [abs(w - profile[(j - offset) % CYCLE_STEPS]) for j, w in enumerate(widths)]

    best = min(range(CYCLE_STEPS), key=lambda offset: sum(errors(offset)))
    return best, errors(best)


def test_every_frame_of_a_cycle_shows_the_next_step_whenever_start_arrives(particle):
    """Back-to-back 10-step cycles while the photocells are sampled and the radio is busy both
    ways: frame after frame shows eq. 4's next step, for STARTs landing anywhere in a frame (a
    servo driven from a clock of its own repeats or skips steps at some of these phases)."""
    profile = cycle_profile_us(CYCLE_STEPS)
    assert min(abs(b - a) for a, b in itertools.pairwise(profile)) > 70
    rng = random.Random(11)
    particle.run_for(0.6e6)
    checked = 0
    for run in range(PHASES):
        received = send_start_at_phase(particle, run + 1, phase_ms=1 + 2 * run)
        load(particle, rng, RUN_S - (particle.cycle - received) / CPU_HZ)
        window = [
            p
            for p in particle.servo_pulses
            if received + MEASURE_FROM_S * CPU_HZ <= p.start_cycle < received + RUN_S * CPU_HZ
        ]
        assert len(window) >= 30
        # Not one frame left out: rising edges 20 ms apart (give or take the edge jitter).
        gaps = [(b.start_cycle - a.start_cycle) / 8 for a, b in itertools.pairwise(window)]
        assert all(abs(gap - 20000) <= SERVO_JITTER_US for gap in gaps)
        _, errors = step_errors(window, profile)
        wrong = [i for i, error in enumerate(errors) if error > SERVO_JITTER_US]
        assert not wrong, f"START {1 + 2 * run} ms into a frame: frames {wrong} show another step"
        checked += len(window)
    assert checked >= PHASES * 30


def test_step_zero_goes_out_in_the_first_frame_after_the_common_start(particle):
    """Alone, a particle has S_n = 1 and t_I = 0: step 0 of its first cycle goes out in the first
    frame that begins at or after START + ROUND_MS (the particle's millisecond clock, truncated,
    may stamp START up to a millisecond early), less than a frame after it, and steps 1, 2, ...
    follow frame by frame, wherever in a frame START arrived."""
    profile = cycle_profile_us(CYCLE_STEPS)
    particle.run_for(0.6e6)
    for run, phase_ms in enumerate((1, 7, 13, 19)):
        received = send_start_at_phase(particle, run + 1, phase_ms)
        particle.run_for(0.6e6)
        common_start = received + ROUND_MS * CPU_HZ // 1000
        pulses = [p for p in particle.servo_pulses if p.start_cycle >= received]
        rising = next(i for i, p in enumerate(pulses) if p.width_us > profile[0] + 40)
        step_zero = pulses[rising - 1]
        late_ms = (step_zero.start_cycle - common_start) * 1000 / CPU_HZ
        assert -CLOCK_MS <= late_ms < STEP_S * 1000, f"START {phase_ms} ms into a frame: {late_ms}"
        for k in range(1, CYCLE_STEPS):
            assert abs(pulses[rising - 1 + k].width_us - profile[k]) <= SERVO_JITTER_US, k
        particle.send_uart(encode_frame(Stop(), BASE_STATION_ID, 100 + run))
        particle.run_for(1.0e6)  # the ramp takes at most 0.6 s: at rest for the next START
