"""What the radios of simulated swarms (virtual://, emulated://) share: URL options, a queue."""

from __future__ import annotations

import queue
from abc import abstractmethod
from typing import Generic, Protocol, TypeVar

from particlebot.options import POSITIVE, OptionError, parse_float
from particlebot.radio import InvalidRadioUrlError, LinkState, Packet, Radio, RadioError, RadioUrl
from particlebot.virtual.light import Lamp


def parse_count(url: RadioUrl, default: int, maximum: int) -> int:
    """How many particles: the part after scheme://."""
    try:
        count = int(url.target or str(default))
    except ValueError:
        raise InvalidRadioUrlError(
            f"{url.text}: the number of particles goes after {url.scheme}://, "
            f"e.g. {url.scheme}://{default}"
        ) from None
    if not 1 <= count <= maximum:
        raise InvalidRadioUrlError(f"{url.text}: 1..{maximum} particles, not {count}")
    return count


def parse_lamp(url: RadioUrl) -> Lamp:
    """lamp=X,Y,H in metres, or the default lamp."""
    if "lamp" not in url.options:
        return Lamp()
    parts = url.options["lamp"].split(",")
    try:
        if len(parts) != 3:
            raise OptionError("three numbers")
        x, y = (parse_float(part) for part in parts[:2])
        height = parse_float(parts[2], POSITIVE)
    except OptionError:
        raise InvalidRadioUrlError(
            f"{url.text}: lamp=X,Y,H in metres, H above the photocells, e.g. lamp=0,0,0.28"
        ) from None
    return Lamp(x, y, height)


class SimulatedSwarm(Protocol):
    """What a SwarmRadio needs of particlebot.virtual.swarm.VirtualSwarm and
    particlebot.sim.swarm.EmulatedSwarm."""

    def node_name(self, node: int, /) -> str: ...

    def epoch(self, sim_s: float | None = None, /) -> float: ...

    def send_from_base(self, data: bytes, /) -> None: ...

    def start(self, speed: float = 1.0) -> None: ...

    def stop(self) -> None: ...

    @property
    def error(self) -> BaseException | None: ...


SwarmT = TypeVar("SwarmT", bound=SimulatedSwarm)


class SwarmRadio(Radio, Generic[SwarmT]):
    """The base station's radio on a simulated swarm's air. The simulation's thread hands packets
    over through a queue; the clock is the simulation's, so the console's ages and timeouts
    follow simulated time when it runs faster or slower than real time."""

    restart_advice = "open it again"
    """What to do once the simulation has failed (a backend names what to rebuild)."""

    def __init__(self, swarm: SwarmT, *, url: str, speed: float | None = None) -> None:
        """speed: step the swarm on its own thread at this pace (else the caller steps it)."""
        super().__init__(url)
        self.swarm = swarm
        self._packets: queue.Queue[Packet] = queue.Queue()
        self._owns_thread = speed is not None
        self._connect()
        if speed is not None:
            self.swarm.start(speed)

    @abstractmethod
    def _connect(self) -> None:
        """Has the swarm hand the base station's packets to _deliver."""

    def _deliver(self, source: int, data: bytes, at: float) -> None:
        self._packets.put(
            Packet(data=data, source=self.swarm.node_name(source), time=self.swarm.epoch(at))
        )

    def _check(self) -> None:
        """Raises RadioError once the simulation's thread has failed: without it nothing more will
        ever be heard, and a radio that just stays quiet would look like a silent swarm."""
        error = self.swarm.error
        if error is not None:
            self._set_link(LinkState.LOST, f"the simulation stopped: {error}")
            raise RadioError(f"The simulated swarm stopped ({error}); {self.restart_advice}")

    def now(self) -> float:
        return self.swarm.epoch()

    def send(self, data: bytes) -> None:
        self._check()
        self.swarm.send_from_base(data)

    def receive(self, timeout: float | None = None) -> Packet | None:
        self._check()
        try:
            return self._packets.get(timeout=timeout)
        except queue.Empty:
            self._check()
            return None

    def close(self) -> None:
        if self._owns_thread:
            self.swarm.stop()
        super().close()
