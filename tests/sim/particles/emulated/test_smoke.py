"""The real firmware image in simavr: STATUS frames, servo pulses, commands, watchdog, EEPROM."""

from __future__ import annotations

import itertools
import subprocess
from collections.abc import Iterator

import pytest

from particlebot.protocol import (
    BASE_STATION_ID,
    DEFINITION_HASH,
    PARAM_SPECS,
    UNASSIGNED_ID,
    Frame,
    Message,
    Method,
    Param,
    Ping,
    SetId,
    Start,
    State,
    Status,
    Stop,
    StreamDecoder,
    encode_frame,
)
from particlebot.sim.particles.emulated.harness import ParticleSim, default_elf

pytestmark = pytest.mark.usefixtures("built_images")

MCUSR_POWER_ON = 0x01
MCUSR_WATCHDOG = 0x08
CONTRACTED_US = PARAM_SPECS[Param.SERVO_CAL_0].default
ROUND_S = PARAM_SPECS[Param.ROUND_MS].default / 1000
STATUS_PERIOD_S = PARAM_SPECS[Param.STATUS_PERIOD_MS].default / 1000
# An edge of the servo pulse waits while another interrupt (Timer0, Serial1) finishes; the longest,
# Serial1's transmit interrupt, takes ~120 cycles (15 us). benchmarks/bench_sim.py saw 14.25 us.
SERVO_JITTER_US = 20
# Photocell voltages all different, so a mix-up of the A0..A5 channels shows.
LIGHT_MV = (400, 900, 1400, 1900, 2400, 2900)


@pytest.fixture
def particle() -> Iterator[ParticleSim]:
    with ParticleSim(light_mv=LIGHT_MV) as sim:
        yield sim


@pytest.fixture
def faulty_particle() -> Iterator[ParticleSim]:
    with ParticleSim(default_elf(faults=True), light_mv=LIGHT_MV) as sim:
        yield sim


class Base:
    """The base station's side of the link: numbered frames out, decoded frames in."""

    def __init__(self, sim: ParticleSim) -> None:
        self.sim = sim
        self.seq = 0
        self.decoder = StreamDecoder()
        self.frames: list[tuple[float, Frame]] = []
        """Each frame received, with the time its last byte arrived."""
        self.first_byte_s: list[float] = []
        """For each of frames, the time its first byte arrived."""
        self._seen = 0

    def send(self, message: Message) -> None:
        self.sim.send_uart(encode_frame(message, BASE_STATION_ID, self.seq))
        self.seq = (self.seq + 1) % 256

    def run(self, seconds: float) -> None:
        self.sim.run_for(seconds * 1e6)
        for index in range(self._seen, len(self.sim.uart)):
            byte = self.sim.uart[index]
            for frame in self.decoder.feed(bytes([byte.value])):
                self.frames.append((byte.time_s, frame))
                self.first_byte_s.append(self.sim.uart[index + 1 - len(frame.raw)].time_s)
        self._seen = len(self.sim.uart)

    def statuses(self, since_s: float = 0.0) -> list[tuple[float, Frame, Status]]:
        found = []
        for time_s, frame in self.frames:
            if time_s >= since_s and isinstance(frame.message, Status):
                found.append((time_s, frame, frame.message))
        return found

    def ping(self, target: int = UNASSIGNED_ID) -> tuple[Frame, Status]:
        """Asks for a STATUS and returns the one that answers it. The default target is a blank
        particle's id: a PING to its id is answered at once (a broadcast one within 0.6 s)."""
        asked_at = self.sim.time_s
        self.send(Ping(target=target))
        self.run(0.3)
        answers = self.statuses(since_s=asked_at)
        assert answers, "no STATUS within 300 ms of a PING"
        _, frame, status = answers[0]
        return frame, status


def expected_raw(mv: int) -> int:
    """The ATmega32U4's 10-bit conversion with AVcc = 3.3 V as reference (datasheet 24.7)."""
    return min(1023, mv * 1024 // 3300)


def test_idle_particle_sends_valid_status_frames_with_the_hosts_definition(particle):
    base = Base(particle)
    base.run(5.0)

    statuses = base.statuses()
    assert len(statuses) >= 2
    assert base.decoder.stats.bad_crc == 0
    assert base.decoder.stats.bad_length == 0
    assert base.decoder.stats.skipped_bytes == 0
    for _, frame, status in statuses:
        assert status.definition_hash == DEFINITION_HASH
        assert frame.sender == UNASSIGNED_ID  # blank EEPROM
        assert status.state == State.IDLE
        assert status.last_reset_cause & MCUSR_POWER_ON
    times = [time_s for time_s, _, _ in statuses]
    for earlier, later in itertools.pairwise(times):
        # STATUS_PERIOD_MS with up to 25 % jitter either way
        assert 0.75 * STATUS_PERIOD_S - 0.05 <= later - earlier <= 1.25 * STATUS_PERIOD_S + 0.1
    # Frames are numbered one after the other.
    seqs = [frame.seq for _, frame, _ in statuses]
    assert all((b - a) % 256 >= 1 for a, b in itertools.pairwise(seqs))


def test_commands_reach_the_particle_at_the_pace_of_a_9600_baud_line(particle):
    base = Base(particle)
    while not base.statuses():  # the first periodic STATUS, well clear of the next one
        base.run(0.1)
    base.run(0.05)
    ping = encode_frame(Ping(target=UNASSIGNED_ID), BASE_STATION_ID, 0)
    sent_s = particle.time_s
    particle.send_uart(ping)
    base.run(0.1)

    replies = [i for i, (_, f) in enumerate(base.frames) if base.first_byte_s[i] > sent_s]
    assert replies, "no answer to PING"
    # 10 bits per byte: the particle cannot answer before the PING's last byte is in.
    on_the_wire_s = len(ping) * 10 / 9600
    assert on_the_wire_s <= base.first_byte_s[replies[0]] - sent_s <= on_the_wire_s + 0.01


def test_each_photocell_is_read_from_its_own_pin(particle):
    base = Base(particle)
    base.run(1.5)
    _, status = base.ping()

    for k, mv in enumerate(LIGHT_MV):
        assert abs(status.sensors[k] - expected_raw(mv)) <= 2, f"sensor A{k}"
    assert status.sensor_faults == 0
    assert abs(status.intensity - sum(status.sensors) / len(status.sensors)) <= 1


def test_servo_gets_a_contracted_pulse_every_20_ms_while_idle(particle):
    particle.run_for(3e6)

    pulses = [p for p in particle.servo_pulses if p.start_s >= 0.5]
    assert 120 <= len(pulses) <= 126  # 2.5 s of 50 Hz frames
    widths = sorted(pulse.width_us for pulse in pulses)
    assert widths[0] >= 500 and widths[-1] <= 2500
    # A few edges come late (SERVO_JITTER_US); the median pulse is the commanded one.
    assert abs(widths[len(widths) // 2] - CONTRACTED_US) <= 1
    assert all(abs(width - CONTRACTED_US) <= SERVO_JITTER_US for width in widths)
    periods_us = [(b.start_s - a.start_s) * 1e6 for a, b in itertools.pairwise(pulses)]
    assert max(abs(period - 20000) for period in periods_us) <= SERVO_JITTER_US
    assert sorted(periods_us)[len(periods_us) // 2] == pytest.approx(20000, abs=1)


def test_start_sets_the_particle_cycling_and_stop_contracts_it_within_a_second(particle):
    base = Base(particle)
    base.run(1.0)
    # Alone, the particle is nearest the light (S_n = 1): it starts cycling at the common start.
    base.send(
        Start(
            run_id=7,
            method=Method.COUNTING,
            cycle_steps=50,
            wave_size=1,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    base.run(0.2)
    start_s = particle.time_s
    _, status = base.ping()
    assert status.state == State.ESTIMATING
    assert status.run_id == 7

    base.run(ROUND_S + 0.3)
    _, status = base.ping()
    assert status.state == State.CYCLING
    assert status.s_n == 1
    expanding = [p for p in particle.servo_pulses if p.start_s > start_s + ROUND_S]
    assert max(p.width_us for p in expanding) > CONTRACTED_US + 50

    base.send(Stop())
    stop_s = particle.time_s
    base.run(1.0)
    _, status = base.ping()
    assert status.state == State.IDLE
    after = [p for p in particle.servo_pulses if p.start_s > stop_s + 1.0]
    assert len(after) >= 10
    assert all(abs(p.width_us - CONTRACTED_US) <= SERVO_JITTER_US for p in after)


def test_watchdog_resets_a_hung_particle_which_keeps_its_id(faulty_particle):
    base = Base(faulty_particle)
    base.run(1.0)
    base.send(SetId(target=UNASSIGNED_ID, new_id=42))
    base.run(0.5)
    frame, before = base.ping(42)
    assert frame.sender == 42
    assert faulty_particle.resets == []

    faulty_particle.set_fault_pin(True)
    hung_at = faulty_particle.time_s
    reset = faulty_particle.run_until_reset(timeout_us=1e6)
    faulty_particle.set_fault_pin(False)  # before the rebooted firmware reaches its loop
    assert reset is not None and reset.by_watchdog
    assert 0.2 <= reset.time_s - hung_at <= 0.3  # WDTO_250MS
    assert len(faulty_particle.resets) == 1

    base.run(1.5)
    frame, after = base.ping(42)
    assert frame.sender == 42
    assert after.last_reset_cause & MCUSR_WATCHDOG
    assert after.resets == min(255, before.resets + 1)
    assert after.uptime_ms < 2500  # counted from the reset


def test_normal_build_ignores_the_fault_pin(particle):
    particle.set_fault_pin(True)
    particle.run_for(1.5e6)
    assert particle.resets == []


def test_eeprom_image_carries_the_id_to_the_next_power_up(particle):
    base = Base(particle)
    base.run(1.0)
    base.send(SetId(target=UNASSIGNED_ID, new_id=17))
    base.run(0.5)
    image = particle.eeprom()

    with ParticleSim(eeprom=image, light_mv=LIGHT_MV) as reborn:
        base = Base(reborn)
        base.run(1.0)
        frame, status = base.ping(17)
        assert frame.sender == 17
        assert status.last_reset_cause & MCUSR_POWER_ON


def test_firmware_image_fits_the_flash_and_ram_budget():
    sections = {}
    listing = subprocess.run(
        ["avr-size", "-A", str(default_elf())], capture_output=True, text=True, check=True
    ).stdout
    for line in listing.splitlines():
        words = line.split()
        if len(words) == 3 and words[0].startswith("."):
            sections[words[0]] = int(words[1])
    flash = sections.get(".text", 0) + sections.get(".data", 0)
    ram = sections.get(".data", 0) + sections.get(".bss", 0) + sections.get(".noinit", 0)
    assert flash <= 16 * 1024, f"flash {flash} B"
    assert ram <= 1024, f"static RAM {ram} B"


def test_same_inputs_replay_exactly_and_the_noise_input_changes_the_seed():
    def uart_cycles(noise_mv: int) -> list[int]:
        with ParticleSim(light_mv=LIGHT_MV, noise_mv=noise_mv) as sim:
            sim.run_for(2.5e6)  # the first STATUS falls within one STATUS_PERIOD_MS
            return [byte.cycle for byte in sim.uart]

    first = uart_cycles(300)
    assert first, "no STATUS in the first period"
    assert uart_cycles(300) == first
    assert uart_cycles(310) != first
