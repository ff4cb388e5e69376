"""Base-station XBee 802.15.4 in API mode (AP=1 or 2) through digi-xbee: xbee:///dev/ttyUSB0."""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any, Self

import serial
from digi.xbee.devices import Raw802Device
from digi.xbee.exception import XBeeException
from digi.xbee.models.address import XBee64BitAddress
from digi.xbee.models.mode import OperatingMode
from digi.xbee.packets.raw import RX16Packet, RX64Packet
from digi.xbee.serial import XBeeSerialPort

from particlebot.options import NON_NEGATIVE, POSITIVE
from particlebot.radio._port import LIST_PORTS_HINT, open_serial, port_present, quiet_hint
from particlebot.radio.base import (
    InvalidRadioUrlError,
    LinkState,
    NoResponseError,
    Packet,
    PortLostError,
    Radio,
    RadioError,
    RadioUrl,
    WrongModeError,
)
from particlebot.radio.faults import FAULT_OPTIONS

_log = logging.getLogger(__name__)

_PROBE_FRAME_ID = 0x52


def at_command_frame(command: bytes, frame_id: int = _PROBE_FRAME_ID, value: bytes = b"") -> bytes:
    """An unescaped API frame 0x08 (local AT command): `command` queried, or set to value."""
    body = bytes([0x08, frame_id]) + command + value
    return bytes([0x7E, len(body) >> 8, len(body) & 0xFF]) + body + bytes([0xFF - sum(body) & 0xFF])


def escape(frame: bytes) -> bytes:
    """An API frame as API mode 2 sends it: every byte after the start delimiter that could be
    mistaken for a control byte is sent as 0x7D, byte ^ 0x20."""
    out = bytearray(frame[:1])
    for byte in frame[1:]:
        if byte in (0x7E, 0x7D, 0x11, 0x13):
            out += bytes([0x7D, byte ^ 0x20])
        else:
            out.append(byte)
    return bytes(out)


def unescape(data: bytes) -> bytes:
    out = bytearray()
    escaped = False
    for byte in data:
        if escaped:
            out.append(byte ^ 0x20)
            escaped = False
        elif byte == 0x7D:
            escaped = True
        else:
            out.append(byte)
    return bytes(out)


def probe_mode(port: str, baud: int, *, api_timeout: float = 0.6, guard_s: float = 1.1) -> int:
    """Asks the radio on port for its AP setting; returns 1 or 2 or raises with advice.

    digi-xbee can tell these cases apart too, but only after 7-8 s and with a generic message; a
    person who plugged in a transparent radio needs to hear "set AP" at once.
    """
    link = open_serial(port, baud, timeout=0.05)
    try:
        link.reset_input_buffer()
        link.write(at_command_frame(b"AP"))
        reply = read_until(link, api_timeout, lambda got: _api_mode_in(got) is not None)
        mode = _api_mode_in(reply)
        if mode in (1, 2):
            return mode
        if mode == 0:  # only reachable if a radio answers frames while set transparent
            raise _wrong_mode(port)
        # No API answer: is it a transparent radio? Command mode needs a quiet guard time on both
        # sides of "+++" (GT, 1 s by default).
        time.sleep(guard_s)
        link.reset_input_buffer()
        link.write(b"+++")
        reply = read_until(link, guard_s + 0.6, lambda got: b"OK\r" in got)
        if b"OK\r" in reply:
            link.write(b"ATCN\r")  # leave command mode so the radio keeps working
            link.flush()
            raise _wrong_mode(port)
    finally:
        link.close()
    raise NoResponseError(
        f"No XBee answered on {port} at {baud} baud, neither to an API frame nor to +++. Check "
        f"that this is the XBee's port ({LIST_PORTS_HINT}) and that baud= matches the radio's "
        "BD setting (BD=3 is 9600)."
    )


def _wrong_mode(port: str) -> WrongModeError:
    return WrongModeError(
        f"The XBee on {port} is in transparent mode (AP=0). Either use serial://{port}?baud=9600, "
        f"or set AP=1 (API) or AP=2 (API with escapes) with XCTU to use xbee://{port}."
    )


def read_until(link: serial.Serial, timeout: float, done: Callable[[bytes], bool]) -> bytes:
    """What the link delivers until done(everything so far) or timeout seconds pass."""
    got = b""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        got += link.read(max(1, link.in_waiting))
        if done(got):
            break
    return got


def _api_mode_in(data: bytes) -> int | None:
    """The AP value in an AT response to our probe, if data holds one."""
    plain = unescape(data)
    marker = bytes([0x88, _PROBE_FRAME_ID]) + b"AP\x00"
    at = plain.find(marker)
    if at < 0 or at + len(marker) >= len(plain):
        return None
    return plain[at + len(marker)]


class _WatchedSerialPort(XBeeSerialPort):
    """digi-xbee's port, except that a vanished device is reported instead of spun on.

    Upstream's reader thread keeps reading a dead port, logging thousands of errors a second,
    while is_open() stays True; here the first failure sets `lost` and reading idles.
    """

    def __init__(self, baud: int, port: str, lost: threading.Event) -> None:
        super().__init__(baud, port, timeout=0.1)
        self.lost = lost

    def wait_for_frame(self, operating_mode: OperatingMode) -> bytearray | None:
        if self.lost.is_set():
            time.sleep(0.05)
            return None
        try:
            frame: bytearray | None = super().wait_for_frame(operating_mode)
            return frame
        except (serial.SerialException, OSError, TypeError) as exc:
            _log.debug("XBee port read failed: %s", exc)
            self.lost.set()
            return None


class _Raw802WithoutLookups(Raw802Device):
    """Raw802Device that never looks up the sender of a packet.

    For every RX16 packet upstream's reader asks the sender for its 64-bit address (remote AT
    SH) and waits for the answer inside the receive thread: a 4 s stall per packet from a
    particle with MY set (digi-xbee issues #296/#298). With no network object it skips that;
    sources are read from the packets themselves and ids travel in the payload anyway.
    """

    def get_network(self) -> None:
        return None


class XBeeRadio(Radio):
    """Broadcasts frames as TX64 to 0xFFFF and receives RX16/RX64 packets with their sources."""

    def __init__(
        self,
        port: str,
        baud: int = 9600,
        *,
        url: str | None = None,
        sync_timeout: float = 2.0,
        probe_timeout: float = 0.6,
        guard_s: float = 1.1,
        retry_s: float = 1.0,
    ) -> None:
        super().__init__(url or f"xbee://{port}?baud={baud}")
        self.port = port
        self.baud = baud
        self.sync_timeout = sync_timeout
        self.probe_timeout = probe_timeout
        self.guard_s = guard_s
        self.retry_s = retry_s
        self.api_mode = 0
        self._packets: queue.Queue[Packet] = queue.Queue()
        self._lost = threading.Event()
        self._lock = threading.Lock()
        self._closed = False
        self._next_retry = 0.0
        self._device: _Raw802WithoutLookups | None = self._open_device()

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        url.check_options({"baud", "timeout", "probe", "guard", "retry", *FAULT_OPTIONS})
        if not url.target:
            raise InvalidRadioUrlError(f"{url.text}: no port given; e.g. xbee:///dev/ttyUSB0")
        return cls(
            url.target,
            url.get_int("baud", 9600, POSITIVE),
            url=url.text,
            sync_timeout=url.get_float("timeout", 2.0, POSITIVE),
            probe_timeout=url.get_float("probe", 0.6, POSITIVE),
            guard_s=url.get_float("guard", 1.1, NON_NEGATIVE),
            retry_s=url.get_float("retry", 1.0, POSITIVE),
        )

    @property
    def quiet_hint(self) -> str | None:
        return quiet_hint(self.baud)

    def _open_device(self) -> _Raw802WithoutLookups:
        self.api_mode = probe_mode(
            self.port, self.baud, api_timeout=self.probe_timeout, guard_s=self.guard_s
        )
        self._lost.clear()
        device = _Raw802WithoutLookups(
            comm_iface=_WatchedSerialPort(self.baud, self.port, self._lost)
        )
        device.set_sync_ops_timeout(self.sync_timeout)
        try:
            device.open()
        except XBeeException as exc:
            # A failed open() can leave the port open and the reader running.
            device.close()
            raise RadioError(
                f"The XBee on {self.port} answered but digi-xbee could not open it ({exc}). "
                "It must be an XBee Series 1 (802.15.4) in API mode 1 or 2 with a non-empty NI."
            ) from exc
        device.add_packet_received_callback(self._on_packet)
        return device

    def _on_packet(self, packet: Any) -> None:
        if isinstance(packet, RX16Packet):
            source = f"{packet.x16bit_source_addr}"
        elif isinstance(packet, RX64Packet):
            source = f"{packet.x64bit_source_addr}"
        else:
            return
        self._packets.put(Packet(data=bytes(packet.rf_data), source=source, time=self.now()))

    def send(self, data: bytes) -> None:
        with self._lock:
            device = self._device
            if device is None or self._lost.is_set():
                raise PortLostError(
                    f"{self.port} is not connected; waiting for it to come back "
                    "(plug the XBee in again)"
                )
            try:
                # Async: a broadcast has no acknowledgement worth waiting for, and a blocking send
                # would stall STOP repeats behind the TX status.
                device.send_data_async_64(XBee64BitAddress.BROADCAST_ADDRESS, data)
            except XBeeException as exc:
                self._lost.set()
                raise PortLostError(f"{self.port} vanished while sending ({exc})") from exc

    def receive(self, timeout: float | None = None) -> Packet | None:
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._closed:
            self._check_link()
            remaining = 0.1 if deadline is None else deadline - time.monotonic()
            if remaining <= 0:
                return None
            try:
                return self._packets.get(timeout=min(remaining, 0.1))
            except queue.Empty:
                continue
        return None

    def _check_link(self) -> None:
        if self._device is not None and not self._lost.is_set() and port_present(self.port):
            return
        if self._device is not None:
            self._lost.set()
            with self._lock:
                device, self._device = self._device, None
            _close_quietly(device)
            self._next_retry = time.monotonic()
            self._set_link(
                LinkState.LOST,
                f"{self.port} vanished. Was the USB cable pulled? Waiting for it to come back; "
                "the log keeps running.",
            )
        now = time.monotonic()
        if now < self._next_retry or self._closed or not port_present(self.port):
            return
        self._next_retry = now + self.retry_s
        try:
            device = self._open_device()
        except RadioError as exc:
            _log.debug("XBee not back yet: %s", exc)
            return
        with self._lock:
            if self._closed:
                _close_quietly(device)
                return
            self._device = device
        self._set_link(LinkState.CONNECTED, f"{self.port} is back; receiving again")

    def close(self) -> None:
        self._closed = True
        with self._lock:
            device, self._device = self._device, None
        if device is not None:
            _close_quietly(device)
        super().close()


def _close_quietly(device: Raw802Device) -> None:
    try:
        device.close()
    except (XBeeException, serial.SerialException, OSError) as exc:
        _log.debug("closing XBee: %s", exc)
