"""The base station's end of a simulated swarm for tests and benchmarks: numbered frames out,
every frame heard in (reassembled per radio, as a console does). The console reaches a swarm
through particlebot.radio.virtual and particlebot.radio.emulated instead."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from particlebot.firmware.native import firmware_constants
from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    FRAME_OVERHEAD,
    MAX_PAYLOAD,
    Frame,
    Message,
    Ping,
    Status,
    StreamDecoder,
    encode_frame,
)
from particlebot.sim.air.medium import AirPacket, char_cycles
from particlebot.sim.clock import seconds
from particlebot.sim.swarm.swarm import SimSwarm


@dataclass(frozen=True)
class HeardFrame:
    """A frame the base station received, when its last byte was in, and from which radio."""

    time_s: float
    source: int
    frame: Frame


def broadcast_answers_s() -> float:
    """Within this, every particle has answered a broadcast PING: while it knows no group size a
    particle answers in a random one of the firmware's reply slots, so that a swarm's answers do
    not all reach the base station's radio at once; the last one takes a frame's time at 9600
    baud after its slot."""
    constants = firmware_constants()
    slots_s = constants.ping_slots_unknown * constants.ping_slot_ms / 1000
    return slots_s + seconds(round((MAX_PAYLOAD + FRAME_OVERHEAD) * char_cycles()))


def packet_frames(packet: AirPacket) -> list[Frame]:
    """The whole frames inside one RF packet (frames split across packets are not counted)."""
    return StreamDecoder().feed(packet.data)


class BaseStation:
    """The base station's end of a SimSwarm, driven from the caller's thread: numbered frames
    out, every frame heard in (reassembled per radio, as a console does)."""

    def __init__(self, swarm: SimSwarm) -> None:
        self.swarm = swarm
        self.seq = 0
        self.decoder = StreamDecoder()
        self.heard: list[HeardFrame] = []
        self.sent: list[tuple[float, bytes]] = []
        """Each frame sent, with the time it was handed to the base station's radio."""
        swarm.add_base_listener(self._on_packet)

    def _on_packet(self, source: int, data: bytes, time_s: float) -> None:
        for frame in self.decoder.feed(data, source):
            self.heard.append(HeardFrame(time_s, source, frame))

    def send(self, message: Message) -> float:
        """Broadcasts message from the base station; returns the time it was handed over."""
        raw = encode_frame(message, BASE_STATION_ID, self.seq)
        self.seq = (self.seq + 1) % 256
        self.swarm.send_from_base(raw)
        self.sent.append((self.swarm.time_s, raw))
        return self.swarm.time_s

    def frames(
        self, kind: type[Message] | None = None, since_s: float = 0.0
    ) -> list[tuple[HeardFrame, Message]]:
        """Frames heard at or after since_s whose message is a kind (any message if None)."""
        found = []
        for heard in self.heard:
            message = heard.frame.message
            if heard.time_s < since_s or message is None:
                continue
            if kind is None or isinstance(message, kind):
                found.append((heard, message))
        return found

    def statuses(self, since_s: float = 0.0) -> dict[int, Status]:
        """The latest STATUS of each particle id heard since since_s."""
        latest: dict[int, Status] = {}
        for heard, message in self.frames(Status, since_s):
            assert isinstance(message, Status)
            latest[heard.frame.sender] = message
        return latest

    def ping_all(
        self, timeout_s: float = 1.5, ids: Sequence[int] | None = None, attempts: int = 3
    ) -> dict[int, Status]:
        """A STATUS from every particle (default: the swarm's ids) asked for now: one broadcast
        PING, whose answers spread over up to broadcast_answers_s(), then PINGs to each silent one
        (an answer can be lost, or dropped by a full radio buffer), which answer at once. Missing
        ids did not answer."""
        wanted = set(self.swarm.ids if ids is None else ids)
        asked = self.send(Ping(target=BROADCAST_ID))
        first = min(timeout_s, broadcast_answers_s())
        waits = [first] + [(timeout_s - first) / max(1, attempts - 1)] * (attempts - 1)
        for wait_s in waits:
            self.swarm.run_until_true(lambda: wanted <= set(self.statuses(asked)), wait_s)
            missing = wanted - set(self.statuses(asked))
            if not missing:
                break
            for particle_id in sorted(missing):
                self.send(Ping(target=particle_id))
        return {k: v for k, v in self.statuses(asked).items() if k in wanted}
