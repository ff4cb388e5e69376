"""What the radios of simulated swarms (virtual://, emulated://) share: URL options, a queue."""

from __future__ import annotations

import queue
from abc import abstractmethod
from typing import Generic, Protocol, TypeVar

from particlebot.options import POSITIVE, Bounds, OptionError, parse_float
from particlebot.radio import InvalidRadioUrlError, LinkState, Packet, Radio, RadioError, RadioUrl
from particlebot.radio.faults import LinkFaults
from particlebot.sim.world.light import Lamp
from particlebot.sim.world.photocells import MAX_SPREAD

PHOTOCELL_SPREAD = Bounds(minimum=0, maximum=MAX_SPREAD)


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


def parse_photocell_spread(url: RadioUrl) -> float:
    """photocell_spread=S: every simulated photocell its own gamma (1 +- S) and resistance, as
    real CdS cells have (something to calibrate); 0, the default, makes them all ideal."""
    return url.get_float("photocell_spread", 0.0, PHOTOCELL_SPREAD)


class SimulatedSwarm(Protocol):
    """What a SwarmRadio needs of particlebot.virtual.swarm.VirtualSwarm and
    particlebot.sim.swarm.EmulatedSwarm."""

    def node_name(self, node: int, /) -> str: ...

    def epoch(self, sim_s: float | None = None, /) -> float: ...

    def send_from_base(self, data: bytes, /) -> None: ...

    def start(self, speed: float = 1.0) -> None: ...

    def stop(self) -> None: ...

    def run_for(self, seconds: float, /) -> None: ...

    @property
    def error(self) -> BaseException | None: ...


SwarmT = TypeVar("SwarmT", bound=SimulatedSwarm)


class SwarmRadio(Radio, Generic[SwarmT]):
    """The base station's radio on a simulated swarm's air. The simulation's thread hands packets
    over through a queue; the clock is the simulation's, so the console's ages and timeouts
    follow simulated time when it runs faster or slower than real time."""

    restart_advice = "open it again"
    """What to do once the simulation has failed (a backend names what to rebuild)."""
    faults_on_link = False  # the simulation models loss on its air

    def __init__(
        self,
        swarm: SwarmT,
        *,
        url: str,
        speed: float | None = None,
        link_faults: LinkFaults | None = None,
    ) -> None:
        """speed: step the swarm on its own thread at this pace (else the caller steps it).
        link_faults: delay (or loss) between the base station and its radio."""
        super().__init__(url)
        self.swarm = swarm
        self.speed = speed
        self.link_faults = link_faults
        self._packets: queue.Queue[Packet] = queue.Queue()
        self._owns_thread = speed is not None
        self._connect()
        if speed is not None:
            self.swarm.start(speed)

    @property
    def stepped_by_caller(self) -> bool:
        """Whether the caller advances the simulation (advance) rather than a thread."""
        return not self._owns_thread

    def step_by_caller(self) -> None:
        """Stops the stepping thread: from now on the caller advances the simulation, as
        fast as it can and in step with its own work (particlebot.Swarm does at speed=max)."""
        if self._owns_thread:
            self.swarm.stop()
            self._owns_thread = False

    def advance(self, seconds: float) -> None:
        """Runs the simulation for seconds of its time (only when stepped_by_caller)."""
        if self._owns_thread:
            raise RuntimeError("the simulation steps on its own thread")
        self._check()
        end = self.now() + seconds
        faults = self.link_faults
        # Delayed sends leave when they are due, not at the end of the step.
        while faults is not None and (due := faults.next_send_due()) is not None and due < end:
            self.swarm.run_for(max(0.0, due - self.now()))
            # The simulation moves in steps of its own: within one of them counts as due.
            faults.release_sends(due, self.swarm.send_from_base)
        self.swarm.run_for(max(0.0, end - self.now()))

    @abstractmethod
    def _connect(self) -> None:
        """Has the swarm hand the base station's packets to _deliver."""

    def _deliver(self, source: int, data: bytes, at: float) -> None:
        packet = Packet(data=data, source=self.swarm.node_name(source), time=self.swarm.epoch(at))
        passed = packet if self.link_faults is None else self.link_faults.incoming(packet)
        if passed is not None:
            self._packets.put(passed)

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
        if self.link_faults is None:
            self.swarm.send_from_base(data)
        else:
            self.link_faults.outgoing(data, self.now(), self.swarm.send_from_base)

    def receive(self, timeout: float | None = None) -> Packet | None:
        self._check()
        faults = self.link_faults
        if faults is not None:
            faults.release_sends(self.now(), self.swarm.send_from_base)
            held = faults.due_packet(self.now())
            if held is not None:
                return held
            if faults.next_due() is not None:
                # On the simulation's clock, which may run faster than the wall's: look again
                # soon rather than sleep through what falls due.
                timeout = 0.005 if timeout is None else min(timeout, 0.005)
        try:
            return self._packets.get(timeout=timeout)
        except queue.Empty:
            self._check()
            return None

    def close(self) -> None:
        if self._owns_thread:
            self.swarm.stop()
        super().close()
