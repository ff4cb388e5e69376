"""One radio interface for the base station, with backends chosen by a URL-like name."""

from __future__ import annotations

import dataclasses
import importlib
from urllib.parse import parse_qsl, urlsplit

from particlebot.radio.base import (
    InvalidRadioUrlError,
    LinkEvent,
    LinkState,
    NoResponseError,
    Packet,
    PortBusyError,
    PortLostError,
    PortNotFoundError,
    PortPermissionError,
    Radio,
    RadioError,
    RadioUrl,
    ReadOnlyRadioError,
    WrongModeError,
)

__all__ = [
    "BACKENDS",
    "InvalidRadioUrlError",
    "LinkEvent",
    "LinkState",
    "NoResponseError",
    "Packet",
    "PortBusyError",
    "PortLostError",
    "PortNotFoundError",
    "PortPermissionError",
    "Radio",
    "RadioError",
    "RadioUrl",
    "ReadOnlyRadioError",
    "WrongModeError",
    "open_radio",
    "parse_radio_url",
]

# Scheme -> "module:class". Each backend is one module, imported only when its scheme is used, so
# a missing optional dependency of one backend never breaks the others. A new backend is one line.
BACKENDS: dict[str, str] = {
    "serial": "particlebot.radio.serial:SerialRadio",
    "xbee": "particlebot.radio.xbee:XBeeRadio",
    "virtual": "particlebot.radio.virtual:VirtualRadio",
    "emulated": "particlebot.radio.emulated:EmulatedRadio",
    "replay": "particlebot.logs.replay:ReplayRadio",
}


def _examples() -> str:
    return (
        "serial:///dev/ttyUSB0?baud=9600 (transparent XBee), xbee:///dev/ttyUSB0 (API mode), "
        "virtual://10 (simulated swarm), emulated://5 (the firmware image in simavr)"
    )


def parse_radio_url(text: str) -> RadioUrl:
    split = urlsplit(text)
    scheme = split.scheme.lower()
    if not scheme or "://" not in text:
        hint = ""
        if text.startswith(("/dev/", "COM", "com")):
            hint = f" Did you mean serial://{text} or xbee://{text}?"
        raise InvalidRadioUrlError(f"'{text}' is not a radio URL.{hint} Examples: {_examples()}")
    if scheme not in BACKENDS:
        raise InvalidRadioUrlError(
            f"unknown radio kind '{scheme}://'; known: "
            f"{', '.join(k + '://' for k in BACKENDS)}. Examples: {_examples()}"
        )
    # serial:///dev/ttyUSB0 has an empty host and the device as path; serial://COM3 and
    # virtual://10 carry everything in the host part.
    target = split.netloc + split.path
    options = dict(parse_qsl(split.query, keep_blank_values=True))
    return RadioUrl(text=text, scheme=scheme, target=target, options=options)


def open_radio(url: str, *, caller_steps: bool = False) -> Radio:
    """Opens the radio a URL names; raises RadioError with advice if it cannot. caller_steps: see
    RadioUrl (real radios ignore it)."""
    parsed = dataclasses.replace(parse_radio_url(url), caller_steps=caller_steps)
    module_name, _, class_name = BACKENDS[parsed.scheme].partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:  # a dependency of this one backend is missing or broken
        raise RadioError(
            f"The {parsed.scheme}:// backend cannot be loaded ({exc}). Reinstall particlebot "
            "with its dependencies: make venv (or pip install -e .)"
        ) from exc
    backend: type[Radio] = getattr(module, class_name)
    if not backend.faults_on_link:
        return backend.from_url(parsed)
    from particlebot.radio.faults import FaultyRadio, faults_from_url

    faults = faults_from_url(parsed)  # checked before the port is touched
    radio = backend.from_url(parsed)
    return FaultyRadio(radio, faults) if faults.any else radio
