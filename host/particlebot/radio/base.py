"""What every radio backend is: the Radio interface, its packets and link events, its URL, and
the errors it raises. Backends import this module; particlebot.radio re-exports it and opens
the backend a URL names."""

from __future__ import annotations

import enum
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Self

from particlebot.closing import ClosedOnExit
from particlebot.errors import ParticlebotError
from particlebot.options import ANY, SPEED, Bounds, OptionError, parse_float, parse_int


@dataclass(frozen=True)
class Packet:
    """Bytes that arrived together: one RF packet (API mode, virtual) or one serial read."""

    data: bytes
    # Who sent it as far as the radio can tell (an XBee address); None on a transparent link,
    # where bytes of every sender arrive in one stream.
    source: Hashable | None
    time: float


class LinkState(enum.Enum):
    CONNECTED = "connected"
    LOST = "lost"
    WARNING = "warning"
    CLOSED = "closed"


@dataclass(frozen=True)
class LinkEvent:
    state: LinkState
    message: str
    time: float


class RadioError(ParticlebotError):
    """A radio problem; the message always says what to do about it."""


class InvalidRadioUrlError(RadioError):
    pass


class PortNotFoundError(RadioError):
    pass


class PortBusyError(RadioError):
    pass


class PortPermissionError(RadioError):
    pass


class WrongModeError(RadioError):
    pass


class NoResponseError(RadioError):
    pass


class PortLostError(RadioError):
    pass


class ReadOnlyRadioError(RadioError):
    pass


@dataclass(frozen=True)
class RadioUrl:
    """`scheme://target?key=value&...`, e.g. serial:///dev/ttyUSB0?baud=9600 or virtual://10."""

    text: str
    scheme: str
    target: str
    options: dict[str, str]
    caller_steps: bool = False
    """A simulated radio is stepped by whoever opened it (particlebot.Swarm at speed=max), never
    by a thread of its own: the same run every time for a seed."""

    def get_float(self, key: str, default: float, bounds: Bounds = ANY) -> float:
        """Option key as a finite number within bounds (default when absent)."""
        value = self.options.get(key)
        if value is None:
            return default
        try:
            return parse_float(value, bounds)
        except OptionError as exc:
            raise InvalidRadioUrlError(f"{self.text}: {key} {exc}") from None

    def get_int(self, key: str, default: int, bounds: Bounds = ANY) -> int:
        """Option key as a whole number within bounds (default when absent)."""
        value = self.options.get(key)
        if value is None:
            return default
        try:
            return parse_int(value, bounds)
        except OptionError as exc:
            raise InvalidRadioUrlError(f"{self.text}: {key} {exc}") from None

    def get_speed(self) -> float:
        """speed=K: K times real time; speed=max: as fast as possible (math.inf)."""
        return self.get_float("speed", 1.0, SPEED)

    def check_options(self, allowed: set[str]) -> None:
        unknown = sorted(set(self.options) - allowed)
        if unknown:
            raise InvalidRadioUrlError(
                f"{self.text}: unknown option(s) {', '.join(unknown)}; "
                f"{self.scheme}:// takes {', '.join(sorted(allowed)) or 'no options'}"
            )


class Radio(ClosedOnExit, ABC):
    """A base-station radio: broadcasts application frames and hands over what it hears.

    Backends report link changes (a port that vanished and came back) to link listeners instead
    of raising from receive(), so one session survives an unplugged USB cable.
    """

    faults_on_link: bool = True
    """Whether open_radio adds the URL's loss= and delay_ms= between the host and this radio
    (particlebot.radio.faults); simulations model them on their air instead, a replay has none."""

    def __init__(self, url: str) -> None:
        self.url = url
        self._link_state = LinkState.CONNECTED
        self._link_listeners: list[Callable[[LinkEvent], None]] = []
        self._link_lock = threading.Lock()

    @classmethod
    @abstractmethod
    def from_url(cls, url: RadioUrl) -> Self: ...

    @abstractmethod
    def send(self, data: bytes) -> None:
        """Broadcasts one application frame; raises PortLostError while the port is gone."""

    @abstractmethod
    def receive(self, timeout: float | None = None) -> Packet | None:
        """Next packet heard, or None after timeout seconds (None: wait until one comes)."""

    def close(self) -> None:
        self._set_link(LinkState.CLOSED, f"{self.url} closed")

    def now(self) -> float:
        """The clock packets are stamped with (seconds since the epoch; simulated for virtual)."""
        return time.time()

    @property
    def quiet_hint(self) -> str | None:
        """What to check when this radio hears nothing at all (None: nothing to suggest)."""
        return None

    @property
    def link_state(self) -> LinkState:
        return self._link_state

    def add_link_listener(self, listener: Callable[[LinkEvent], None]) -> None:
        with self._link_lock:
            self._link_listeners.append(listener)

    def _set_link(self, state: LinkState, message: str) -> None:
        with self._link_lock:
            if state is not LinkState.WARNING:
                if state is self._link_state:
                    return
                self._link_state = state
            listeners = list(self._link_listeners)
        event = LinkEvent(state=state, message=message, time=self.now())
        for listener in listeners:
            listener(event)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.url!r})"
