"""Virtual particles end to end: the firmware logic in the world and on the air, with a host."""

from __future__ import annotations

import math

import pytest

from particlebot.protocol import Method, Start, State, encode_frame
from particlebot.radio import InvalidRadioUrlError, LinkState, open_radio
from particlebot.radio.virtual import VirtualRadio
from particlebot.session import Session
from particlebot.sim.particles.native import FirmwareParticle, native_factory
from particlebot.sim.scenarios import presets
from particlebot.sim.swarm import SimSwarm, SwarmConfig
from particlebot.swarm.tracker import SwarmTracker
from tests.sim.particles.native.delegate import Delegate
from tests.support.fakes import wait_until


def test_method_d_gives_every_particle_its_rank_by_distance_and_stop_is_confirmed() -> None:
    radio = open_radio("virtual://8?speed=max&start=0.2&seed=3")
    assert isinstance(radio, VirtualRadio)
    session = Session(radio)
    model = SwarmTracker(session, radio.now)
    session.add_listener(model)
    with session:
        assert wait_until(lambda: len(model.rows()) == 8, timeout=20)
        model.start(Method.COUNTING, cycle_steps=75)

        def every_s_n_in() -> bool:
            model.poll()
            return all(
                row.status is not None
                and row.status.run_id == model.run_id
                and row.status.s_n > 0
                and row.status.state != State.ESTIMATING
                for row in model.rows()
            )

        assert wait_until(every_s_n_in, timeout=30)
        snapshot = sorted(radio.swarm.snapshot(), key=lambda p: p.ground_distance)
        rank = {particle.id: position for position, particle in enumerate(snapshot, start=1)}
        reported = {row.id: row.status.s_n for row in model.rows() if row.status}
        assert reported == rank
        stop = model.stop()

        def stopped() -> bool:
            model.poll()
            return stop.done

        assert wait_until(stopped, timeout=30)
        assert stop.success, stop.outcome
        assert {row.state for row in model.rows()} <= {State.IDLE, State.DONE}
        assert all(p.radius_um == 77500 for p in radio.swarm.snapshot())


def test_the_line_creeps_towards_the_lamp_while_the_particles_cycle() -> None:
    swarm = SimSwarm(SwarmConfig(scenario=presets.line(6, start=0.2)))
    before = [particle.x for particle in swarm.snapshot()]
    start = Start(
        run_id=1,
        method=int(Method.COUNTING),
        cycle_steps=75,
        wave_size=0,
        update_interval_s=0,
        phototaxis=0,
    )
    swarm.send_from_base(encode_frame(start, 0, 0))
    # 3 s round, then waves of T + t_p = 1.5 s + 5 * 0.75 s: four full waves.
    swarm.run_for(3.0 + 4 * 5.25 + 0.5)
    moved = [b - p.x for b, p in zip(before, swarm.snapshot(), strict=True)]
    # In the world each wave moves this line by about 25 mm (the bodies slide against friction
    # where the idealised 1-D model of old moved them 80 mm): four waves, at least 50 mm.
    assert all(distance > 0.05 for distance in moved)
    assert max(moved) - min(moved) < 0.05  # the line stays together


def test_the_swarm_clock_can_run_faster_than_real_time() -> None:
    swarm = SimSwarm(SwarmConfig(count=2))
    swarm.start(speed=math.inf)
    try:
        assert wait_until(lambda: swarm.t > 5.0, timeout=30)
    finally:
        swarm.stop()
    assert swarm.achieved_speed > 1.0


class FailingParticle(Delegate):
    """A particle whose logic raises once simulated time passes fail_at_ms."""

    def __init__(self, inner: FirmwareParticle, fail_at_ms: int) -> None:
        super().__init__(inner)
        self.fail_at_ms = fail_at_ms

    def tick(self, now_ms: int) -> None:
        if now_ms >= self.fail_at_ms:
            raise RuntimeError("particle logic crashed")
        super().tick(now_ms)


def test_a_crashed_swarm_says_so_instead_of_looking_alive() -> None:
    swarm = SimSwarm(
        SwarmConfig(count=2),
        factory=lambda image, seed: FailingParticle(native_factory(image, seed), 3000),
    )
    radio = VirtualRadio(swarm, url="virtual://2", speed=math.inf)
    session = Session(radio)
    links: list[LinkState] = []
    radio.add_link_listener(lambda event: links.append(event.state))
    with session:
        assert wait_until(lambda: session.error is not None, timeout=20)
    assert "particle logic crashed" in str(session.error)
    assert LinkState.LOST in links


def test_url_options_place_the_lamp_and_the_line() -> None:
    radio = open_radio("virtual://3?lamp=1,2,0.35&start=0.5&spacing=0.2&kinematics=0&speed=1")
    assert isinstance(radio, VirtualRadio)
    try:
        snapshot = radio.swarm.snapshot()  # the swarm runs on its own thread: no direct access
        assert [round(p.x, 6) for p in snapshot] == [1.5, 1.7, 1.9]
        assert [p.id for p in snapshot] == [1, 2, 3]
        assert radio.swarm.light.lamp.height == 0.35
    finally:
        radio.close()


@pytest.mark.parametrize(
    ("url", "complaint"),
    [
        ("virtual://ten", "number of particles"),
        ("virtual://0", "1..200"),
        ("virtual://3?lamp=1,2", "lamp=X,Y,H"),
        ("virtual://3?speed=-1", "speed must be a number > 0 or max"),
        ("virtual://3?colour=red", "unknown option"),
    ],
)
def test_bad_virtual_urls_say_what_is_wrong(url: str, complaint: str) -> None:
    with pytest.raises(InvalidRadioUrlError, match=complaint):
        open_radio(url)
