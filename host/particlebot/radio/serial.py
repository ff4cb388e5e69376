"""Transparent-mode XBee (any byte pipe to the particles) via pyserial: serial:///dev/ttyUSB0."""

from __future__ import annotations

import contextlib
import threading
import time
from typing import Self

import serial

from particlebot.options import POSITIVE
from particlebot.radio._port import open_serial, port_present, quiet_hint
from particlebot.radio.base import (
    InvalidRadioUrlError,
    LinkState,
    Packet,
    PortLostError,
    Radio,
    RadioUrl,
)
from particlebot.radio.faults import FAULT_OPTIONS

# API frame types an XBee 802.15.4 radio emits towards its host; used only to warn that a radio
# is in API mode while being read as transparent.
_API_RX_TYPES = frozenset({0x80, 0x81, 0x88, 0x89, 0x8A})


def contains_api_frame(data: bytes) -> bool:
    """Whether data holds a complete, checksum-valid unescaped XBee API frame a radio sends."""
    start = data.find(0x7E)
    while start != -1 and start + 4 <= len(data):
        length = (data[start + 1] << 8) | data[start + 2]
        end = start + 3 + length
        if 2 <= length <= 120 and end < len(data) and data[start + 3] in _API_RX_TYPES:
            body = data[start + 3 : end + 1]
            if sum(body) & 0xFF == 0xFF:
                return True
        start = data.find(0x7E, start + 1)
    return False


class SerialRadio(Radio):
    """Reads and writes raw bytes; a vanished port is reported and reopened when it returns."""

    def __init__(
        self, port: str, baud: int = 9600, *, url: str | None = None, retry_s: float = 0.5
    ) -> None:
        super().__init__(url or f"serial://{port}?baud={baud}")
        self.port = port
        self.baud = baud
        self.retry_s = retry_s
        self._lock = threading.Lock()
        self._closed = False
        self._next_retry = 0.0
        self._recent = b""
        self._api_warned = False
        self._serial: serial.Serial | None = open_serial(port, baud, timeout=0.1)

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        url.check_options({"baud", "retry", *FAULT_OPTIONS})
        if not url.target:
            raise InvalidRadioUrlError(
                f"{url.text}: no port given; e.g. serial:///dev/ttyUSB0?baud=9600"
            )
        return cls(
            url.target,
            url.get_int("baud", 9600, POSITIVE),
            url=url.text,
            retry_s=url.get_float("retry", 0.5, POSITIVE),
        )

    @property
    def quiet_hint(self) -> str | None:
        return quiet_hint(self.baud)

    def send(self, data: bytes) -> None:
        with self._lock:
            port = self._serial
            if port is None:
                raise PortLostError(
                    f"{self.port} is not connected; waiting for it to come back "
                    "(plug the XBee in again)"
                )
            try:
                port.write(data)
            except (serial.SerialException, OSError) as exc:
                self._lost_locked(exc)
                raise PortLostError(f"{self.port} vanished while sending ({exc})") from exc

    def receive(self, timeout: float | None = None) -> Packet | None:
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._closed:
            remaining = 0.1 if deadline is None else deadline - time.monotonic()
            if remaining <= 0:
                return None
            with self._lock:
                port = self._serial
            if port is None:
                if not self._try_reopen():
                    time.sleep(min(remaining, self.retry_s, 0.1))
                continue
            try:
                port.timeout = min(remaining, 0.1)
                first = port.read(1)
                data = first + port.read(port.in_waiting) if first else b""
            except (serial.SerialException, OSError, TypeError, AttributeError) as exc:
                # TypeError/AttributeError: pyserial touching a handle close() just released.
                if self._closed:
                    return None
                with self._lock:
                    self._lost_locked(exc)
                continue
            if data:
                self._check_api_mode(data)
                return Packet(data=data, source=None, time=self.now())
            if not port_present(self.port):
                with self._lock:
                    self._lost_locked(OSError(f"{self.port} disappeared"))
        return None

    def close(self) -> None:
        self._closed = True
        with self._lock:
            port, self._serial = self._serial, None
        if port is not None:
            with contextlib.suppress(serial.SerialException, OSError, AttributeError):
                port.cancel_read()
            port.close()
        super().close()

    def _lost_locked(self, exc: BaseException) -> None:
        port, self._serial = self._serial, None
        if port is None:
            return
        with contextlib.suppress(serial.SerialException, OSError):
            port.close()
        self._next_retry = time.monotonic()
        self._set_link(
            LinkState.LOST,
            f"{self.port} vanished ({exc}). Was the USB cable pulled? Waiting for it to come "
            "back; the log keeps running.",
        )

    def _try_reopen(self) -> bool:
        now = time.monotonic()
        if now < self._next_retry or self._closed:
            return False
        self._next_retry = now + self.retry_s
        if not port_present(self.port):
            return False
        try:
            port = open_serial(self.port, self.baud, timeout=0.1)
        except Exception:  # any failure just means "not back yet"
            return False
        with self._lock:
            if self._closed:
                port.close()
                return False
            self._serial = port
        self._set_link(LinkState.CONNECTED, f"{self.port} is back; receiving again")
        return True

    def _check_api_mode(self, data: bytes) -> None:
        if self._api_warned:
            return
        self._recent = (self._recent + data)[-512:]
        if contains_api_frame(self._recent):
            self._api_warned = True
            self._set_link(
                LinkState.WARNING,
                f"The radio on {self.port} speaks API frames (AP=1 or 2): open it as "
                f"xbee://{self.port}, or set AP=0 (transparent) with XCTU to use serial://.",
            )
