"""The swarm knows who is in it: STOP after a restart at 50 % loss, duplicate ids, renamed
particles, the fleet file's roster, on virtual particles through the Swarm API."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest

from particlebot import IdInUse, State, Swarm
from particlebot.fleet import Fleet, ParticleRecord, load_fleet, save_fleet
from particlebot.radio.virtual import VirtualRadio
from particlebot.sim.swarm import SimSwarm, SwarmConfig
from particlebot.swarm.campaigns import Verdict
from particlebot.swarm.results import StopReport
from particlebot.swarm.roster import STOPPED_STATES
from particlebot.swarm.tracker import STOP_GRACE_S
from tests.support.truth import true_states

SEEDS = 50
HALF_LOSS = 0.5
RESTART_COUNT = 10


def a_swarm(count: int, seed: int = 1, loss: float = 0.0) -> SimSwarm:
    """Virtual particles that outlive the base-station sessions opened on them."""
    return SimSwarm(SwarmConfig(count=count, seed=seed, loss=loss, kinematics=False))


def session(world: SimSwarm, **options: object) -> Swarm:
    """A base-station session on the world, stepping it (as at speed=max)."""
    return Swarm(VirtualRadio(world, url="virtual://"), log_dir=None, **options)  # type: ignore[arg-type]


def restart_and_stop(seed: int, grace: float) -> tuple[StopReport, list[State]]:
    """A session starts a run of RESTART_COUNT particles at half loss and is closed (the console
    quit, the laptop rebooted); a new session with this grace period presses STOP 0.5 s after
    it opens. Its report, and what the particles really do."""
    world = a_swarm(RESTART_COUNT, seed, HALF_LOSS)
    with session(world) as first:
        first.wait_for(count=RESTART_COUNT, timeout=60)
        first.send_start("D", cycle_steps=75)
        first.sleep(4.0)
    with session(world, stop_grace=grace) as second:  # knows nobody yet
        second.sleep(0.5)
        report = second.stop()
    return report, true_states(world)


@pytest.mark.slow
@pytest.mark.parametrize("grace", [STOP_GRACE_S, 0.0], ids=["default-grace", "no-grace"])
def test_stop_right_after_a_restart_at_half_loss_is_never_confirmed_falsely(grace: float) -> None:
    verdicts: Counter[Verdict] = Counter()
    false = 0
    for seed in range(1, SEEDS + 1):
        report, states = restart_and_stop(seed, grace)
        verdicts[report.verdict] += 1
        assert report.confirmed == (report.verdict is Verdict.CONFIRMED)
        false += report.confirmed and any(state not in STOPPED_STATES for state in states)
    assert false == 0
    if grace:
        # ...and not by never confirming anything: STOP keeps going out through the grace
        # period, so every particle stops, and one that answered is heard.
        assert verdicts[Verdict.CONFIRMED] >= SEEDS - 2
    else:
        # Without it, particles the base station has not heard may still move: the particles
        # heard may confirm, but the outcome says that nobody vouches for the rest.
        assert verdicts[Verdict.CONFIRMED] == 0
        assert verdicts[Verdict.UNCONFIRMED] >= SEEDS // 2


def test_without_a_fleet_stop_waits_for_as_many_as_were_seen_together() -> None:
    world = a_swarm(5)
    with session(world) as first:
        first.wait_for(count=5)
        first.start("D", cycle_steps=75)
        first.sleep(4.0)
    # Particle 5 falls out of range; a new session hears the four others, whose STATUS says
    # that five estimated together. Without the grace period, only that floor is left.
    gone = 4  # particle 5's index
    world.air.drop = lambda packet, receiver: gone in (packet.source, receiver)
    with session(world, stop_grace=0) as second:
        second.wait_for(count=4)
        assert second.tracker.largest_group == 5
        report = second.stop()
    assert not report.confirmed
    assert report.stopped == (1, 2, 3, 4) and report.never_heard == 1
    assert "4 particle(s) confirmed, but 5 were seen together; 1 never answered" in report.text


def test_two_radios_answering_as_one_id_are_flagged_at_once() -> None:
    world = a_swarm(4)
    with session(world, stop_grace=0) as swarm:
        swarm.wait_for(count=4)
        # Particle 3 is given id 2 by force (a person sure that 2 is gone; it is not).
        swarm.set_id(3, 2, force=True)
        renamed_at = swarm.now()
        assert swarm.wait_until(lambda: sum(p.id == 2 for p in swarm.particles()) == 2, 5)
        flagged_after = swarm.now() - renamed_at
        twos = [p for p in swarm.particles() if p.id == 2]
        assert all("DUPLICATE" in p.flags for p in twos)
        assert {p.radio for p in twos} == {"virtual-02", "virtual-03"}
        notes = "\n".join(swarm.notes())
        assert re.search(
            r"DUPLICATE id 2: radios virtual-0[23] and virtual-0[23] both answer", notes
        )
        # Each radio answers for itself: STOP is confirmed by both. (Without a fleet file and
        # within STOP_GRACE_S of opening, the verdict cannot vouch for particles not heard.)
        swarm.start("A")
        report = swarm.stop()
        assert report.stopped == (1, 2, 2, 4) and not report.unconfirmed
        assert report.verdict is Verdict.UNCONFIRMED
    # The next STATUS of the other particle 2 (every 2 s +-25 %) was enough.
    assert flagged_after <= 2.6


def test_a_renamed_particle_leaves_no_row_behind_and_the_fleet_follows(tmp_path: Path) -> None:
    fleet_file = tmp_path / "fleet.toml"
    fleet = Fleet.new()
    for particle in range(1, 5):
        fleet.record(ParticleRecord(particle, note=f"body {particle}"))
    save_fleet(fleet, fleet_file)
    world = a_swarm(4)
    with session(world, stop_grace=0, fleet=fleet_file) as swarm:
        swarm.wait_for()  # every particle of the fleet
        with pytest.raises(IdInUse, match="id 4 is in use"):
            swarm.set_id(3, 4)
        swarm.set_id(3, 12)
        assert [p.id for p in swarm.particles()] == [1, 2, 4, 12]
        assert "Particle 3 now answers as 12 (radio virtual-03): row 3 dropped" in "\n".join(
            swarm.notes()
        )
        # The old row would wait for particle 3 for ever: STOP is confirmed instead.
        swarm.start("A")
        report = swarm.stop()
        assert report.confirmed and report.stopped == (1, 2, 4, 12)
    stored = load_fleet(fleet_file)
    assert stored.roster_ids() == [1, 2, 4, 12]
    record = stored.get(12)
    assert record is not None and record.note == "body 3"


def test_the_fleet_is_the_roster_a_stop_waits_for(tmp_path: Path) -> None:
    fleet_file = tmp_path / "fleet.toml"
    fleet = Fleet.new()
    for particle in (1, 2, 3, 5):
        fleet.record(ParticleRecord(particle))
    save_fleet(fleet, fleet_file)
    world = a_swarm(4)  # ids 1-4: particle 5 is switched off, 4 is not in the fleet
    with session(world, stop_grace=0, fleet=fleet_file) as swarm:
        swarm.wait_for(count=4)
        flags = {p.id: p.flags for p in swarm.particles()}
        assert flags[5] == ("NOT HEARD",)
        assert flags[4] == ("NOT IN FLEET",)
        assert "Particle 4 is not in the fleet file" in "\n".join(swarm.notes())
        report = swarm.stop()
        assert not report.confirmed
        assert [(u.particle, u.reason) for u in report.unconfirmed] == [
            (5, "in the fleet, never heard in this session")
        ]
        swarm.forget(5)
        assert swarm.stop().confirmed
