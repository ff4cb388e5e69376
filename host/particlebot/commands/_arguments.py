"""Options several subcommands share: the radio, the log folder, message types."""

from __future__ import annotations

import argparse
import os

from particlebot.protocol import MessageType

RADIO_HELP = (
    "radio URL: serial:///dev/ttyUSB0?baud=9600 (transparent XBee), xbee:///dev/ttyUSB0 "
    "(API mode AP=1/2), virtual://10?speed=4 (simulated swarm of the firmware logic), "
    "emulated://5?loss=0.2 (the real firmware image in simavr; needs `make firmware harness`); "
    "default $PARTICLEBOT_RADIO"
)


def add_radio_options(parser: argparse.ArgumentParser) -> None:
    """--radio, --log-dir and --fsync: what every command that opens a radio takes."""
    parser.add_argument("--radio", default=os.environ.get("PARTICLEBOT_RADIO"), help=RADIO_HELP)
    add_log_options(parser)
    parser.add_argument(
        "--fsync", action="store_true", help="sync every log line to disk (survives power cuts)"
    )


def add_log_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--log-dir", default="logs", help="where session logs go (default: ./logs)")


def message_type(text: str) -> str:
    """An argparse `type=`: a message type's name, any case (STATUS, status)."""
    name = text.upper()
    if name not in MessageType.__members__:
        raise argparse.ArgumentTypeError(
            f"no message type '{text}'; types: {', '.join(MessageType.__members__)}"
        )
    return name
