"""particlebot.Swarm on virtual particles: the blocking API, its reports, errors and log."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

import particlebot
from particlebot import NotConfirmed, ParticlesMissing, State, Swarm
from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    Method,
    ParamResult,
    Ping,
    encode_frame,
)
from particlebot.radio import InvalidRadioUrlError
from particlebot.radio.virtual import VirtualRadio
from particlebot.sim.swarm import SimSwarm, SwarmConfig
from tests.support.truth import true_states

LOSSY = "virtual://6?speed=max&loss=0.2&seed=2"


@pytest.mark.slow
def test_the_issue_example_runs_in_simulated_time_under_loss(tmp_path: Path) -> None:
    wall = time.monotonic()
    with particlebot.Swarm.open(LOSSY, log_dir=tmp_path) as swarm:
        opened = swarm.now()
        swarm.wait_for(count=6, timeout=15)
        report = swarm.set("cycle_steps", 150)
        assert report.ok and report.values == dict.fromkeys(range(1, 7), 150)
        assert all(reply.result is ParamResult.OK for reply in report.replies.values())
        run = swarm.start(method="D")
        assert run.method is Method.COUNTING and run.particles == (1, 2, 3, 4, 5, 6)
        swarm.sleep(300)
        assert swarm.now() - opened >= 300
        stop = swarm.stop()
        assert stop.confirmed, stop.text
        assert stop.stopped == (1, 2, 3, 4, 5, 6) and stop.unconfirmed == ()
        assert {p.state for p in swarm.particles()} <= {State.IDLE, State.DONE}
        log = swarm.log_path
    # The calls step the simulation themselves, unpaced: five simulated minutes take less wall
    # time than the 300 s a run paced at real time could not go below (a few seconds idle; the
    # bound leaves room for a machine at any load).
    assert time.monotonic() - wall < 300
    assert log is not None
    records = [json.loads(line) for line in log.read_text().splitlines()]
    assert records[0]["kind"] == "session" and records[-1]["kind"] == "end"
    sent = [r["type"] for r in records if r["kind"] == "tx"]
    assert sent.index("SET_PARAM") < sent.index("START") < sent.index("STOP")
    notes = [r["text"] for r in records if r["kind"] == "note"]
    assert "STOP confirmed by all 6 particles" in notes[-1]


def test_a_seed_gives_the_same_session_every_time(tmp_path: Path) -> None:
    def session(folder: Path) -> list[tuple[float, str]]:
        with Swarm.open(LOSSY, log_dir=folder) as swarm:
            swarm.wait_for(count=6)
            swarm.start("B", cycle_steps=75)
            swarm.sleep(10)
            swarm.stop()
            log = swarm.log_path
        assert log is not None
        records = [json.loads(line) for line in log.read_text().splitlines()]
        first = records[0]["t"]
        return [(round(r["t"] - first, 6), r["hex"]) for r in records if r["kind"] == "rx"]

    one, two = session(tmp_path / "one"), session(tmp_path / "two")
    assert len(one) > 50 and [data for _, data in one] == [data for _, data in two]
    # The same moments too (the log's clock is the epoch plus simulated time: microseconds).
    assert [at for at, _ in one] == pytest.approx([at for at, _ in two], abs=1e-5)


def test_what_cannot_be_done_raises_with_who_and_why() -> None:
    with Swarm.open("virtual://3?speed=max", log_dir=None) as swarm:
        with pytest.raises(ParticlesMissing, match=r"waited 2 s for 4: heard 3 \(1, 2, 3\)"):
            swarm.wait_for(count=4, timeout=2)
        with pytest.raises(ParticlesMissing) as missing:
            swarm.wait_for(ids=[1, 9], timeout=1)
        assert missing.value.missing == (9,)
        with pytest.raises(ValueError, match=r"cycle_steps must be 10..3000, not 5"):
            swarm.set("cycle_steps", 5)
        with pytest.raises(ValueError, match="no parameter 'speed'"):
            swarm.set("speed", 5)
        with pytest.raises(ValueError, match="method 'E' is not A, B, C or D"):
            swarm.start("E")
        swarm.start("A")
        # Parameters are refused while the particles run: each one says so.
        with pytest.raises(NotConfirmed, match="BUSY") as busy:
            swarm.set("count_tolerance", 12)
        assert [item.particle for item in busy.value.unconfirmed] == [1, 2, 3]
        assert swarm.stop().confirmed


def test_stop_names_who_did_not_confirm_and_why() -> None:
    world = SimSwarm(SwarmConfig(count=4, kinematics=False))
    deaf = 2  # particle 3 (index 2) hears nothing from now on, and is not heard
    with Swarm(VirtualRadio(world, url="virtual://4"), log_dir=None, stop_grace=0) as swarm:
        swarm.wait_for(count=4)
        swarm.start("D", cycle_steps=75)
        swarm.sleep(2)
        world.air.drop = lambda packet, receiver: deaf in (packet.source, receiver)
        swarm.sleep(0.5)  # what it sent before is in by now
        report = swarm.stop()
    assert not report.confirmed
    assert report.stopped == (1, 2, 4)
    ((particle, reason),) = [(u.particle, u.reason) for u in report.unconfirmed]
    assert particle == 3 and reason.startswith("no STATUS since the command")
    assert "STOP not confirmed within 10 s by particle(s) 3 (3 confirmed)" in report.text
    assert true_states(world)[2] is not State.IDLE  # it never got STOP


def test_leaving_the_block_by_an_exception_stops_a_running_swarm() -> None:
    world = SimSwarm(SwarmConfig(count=3, kinematics=False))
    with (
        pytest.raises(RuntimeError, match="the script failed"),
        Swarm(VirtualRadio(world, url="virtual://3"), log_dir=None) as swarm,
    ):
        swarm.wait_for(count=3)
        swarm.start("D", cycle_steps=75)
        raise RuntimeError("the script failed")
    assert set(true_states(world)) <= {State.IDLE, State.DONE}


@pytest.mark.parametrize(
    ("url", "complaint"),
    [
        ("virtual://3?loss=1", "loss must be a number >= 0 and < 1"),
        ("virtual://3?delay_ms=-5", "delay_ms must be a number >= 0"),
        ("virtual://3?scenario=nowhere.toml", "nowhere.toml: no such scenario file"),
        ("serial:///dev/null?loss=2", "loss must be"),
        ("replay://x.jsonl?loss=0.1", "unknown option(s) loss"),
    ],
)
def test_fault_options_are_checked_like_every_option(url: str, complaint: str) -> None:
    with pytest.raises(
        InvalidRadioUrlError, match=complaint.replace("(", r"\(").replace(")", r"\)")
    ):
        Swarm.open(url, log_dir=None)


def round_trip(url: str) -> float:
    """Seconds from a GET_PARAM to particle 1 until its answer is in (the radio's clock)."""
    with Swarm.open(url, log_dir=None) as swarm:
        swarm.wait_for(count=2)
        query = swarm.send_get("cycle_steps", 1)
        assert swarm.wait_until(lambda: query.done, 5) and query.finished_at is not None
        assert query.replies  # answered, not timed out
        return query.finished_at - query.started


def test_delay_holds_packets_both_ways_on_the_virtual_base_link() -> None:
    plain = round_trip("virtual://2?speed=max&seed=5")
    delayed = round_trip("virtual://2?speed=max&seed=5&delay_ms=200")
    # 0.2 s out and 0.2 s back. Either answer may also queue behind a STATUS or two on the base
    # radio's 9600-baud link (54 ms each) that the other did not meet.
    assert abs((delayed - plain) - 0.4) <= 2 * 0.054


def test_lost_copies_on_the_virtual_air_follow_the_seed() -> None:
    def losses(seed: int) -> list[bool]:
        world = SimSwarm(SwarmConfig(count=3, loss=0.5, seed=seed))
        world.send_from_base(encode_frame(Ping(target=BROADCAST_ID), BASE_STATION_ID, 0))
        world.run_for(3.0)  # the PING's copies and the answers' (with STATUS reports)
        return [copy.lost for copy in world.air.receptions][:40]

    assert losses(3) == losses(3) != losses(4)
    assert 8 < sum(losses(3)) < 32


def test_a_held_servo_puts_out_its_pulse_until_released() -> None:
    with Swarm.open("virtual://3?speed=max&loss=0.2&seed=4", log_dir=None) as swarm:
        swarm.wait_for(count=3)
        world = swarm.radio.swarm  # type: ignore[attr-defined]
        firmware = world.native.firmware[1]
        held = swarm.hold_servo(2, 1830, 20)
        assert held.state == State.HOLDING and held.status is not None
        assert held.status.servo_pulse_us == 1830 == firmware.servo_pulse_us
        swarm.sleep(5)
        assert firmware.servo_pulse_us == 1830
        released = swarm.release_servo(2)
        assert released.state == State.IDLE
        assert firmware.servo_pulse_us == swarm.get("servo_cal_0", of=2).values[2]
        # The others never held anything.
        assert {p.state for p in swarm.particles() if p.id != 2} == {State.IDLE}


def test_a_hold_is_refused_with_why_running_unknown_or_out_of_range() -> None:
    with Swarm.open("virtual://2?speed=max", log_dir=None) as swarm:
        swarm.wait_for(count=2)
        with pytest.raises(NotConfirmed, match=r"particle 9 did not confirm .*not heard"):
            swarm.hold_servo(9, 1500)
        swarm.start("D")
        with pytest.raises(NotConfirmed, match=r"particle 1 did not confirm .*STOP it first"):
            swarm.hold_servo(1, 1500)
        swarm.stop()
        with pytest.raises(ValueError, match=r"500\.\.2500"):
            swarm.hold_servo(1, 3000)
        with pytest.raises(ValueError, match=r"1\.\.255 s"):
            swarm.hold_servo(1, 1500, 0)


def test_sample_collects_fresh_status_reports_of_each_particle() -> None:
    with Swarm.open("virtual://5?speed=max&loss=0.2&seed=3", log_dir=None) as swarm:
        swarm.wait_for(count=5)
        asked = swarm.now()
        reports = swarm.sample([1, 3, 5], frames=4)
        assert sorted(reports) == [1, 3, 5]
        assert all(len(r) == 4 for r in reports.values())
        # Fresh ones, asked for rather than waited for: far sooner than 4 periods of 2 s.
        assert swarm.now() - asked < 4
        # Four different reports of each, in the order sent.
        for particle_reports in reports.values():
            uptimes = [r.uptime_ms for r in particle_reports]
            assert uptimes == sorted(set(uptimes))
        with pytest.raises(ParticlesMissing, match="7 sent 0"):
            swarm.sample([1, 7], frames=2, timeout=3)
