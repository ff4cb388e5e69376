"""The `particlebot` command: argument parsing shared by every subcommand, then a thin dispatch."""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence

from particlebot.protocol import DEFINITION_HASH

RADIO_HELP = (
    "radio URL: serial:///dev/ttyUSB0?baud=9600 (transparent XBee), xbee:///dev/ttyUSB0 "
    "(API mode AP=1/2), virtual://10?speed=4 (simulated swarm of the firmware logic), "
    "emulated://5?loss=0.2 (the real firmware image in simavr; needs `make firmware harness`); "
    "default $PARTICLEBOT_RADIO"
)


# Subcommands whose modules add their own parser (their heavy imports wait for run()).
SELF_REGISTERING = ("track", "stats", "render")


def _radio_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--radio", default=os.environ.get("PARTICLEBOT_RADIO"), help=RADIO_HELP)
    _log_options(parser)
    parser.add_argument(
        "--fsync", action="store_true", help="sync every log line to disk (survives power cuts)"
    )


def _log_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--log-dir", default="logs", help="where session logs go (default: ./logs)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="particlebot",
        description="Base station for particle robots: console, logging, virtual swarm.",
        epilog=f"protocol definition hash {DEFINITION_HASH:08X}",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    console = commands.add_parser("console", help="live table of every particle, with commands")
    _radio_options(console)
    console.add_argument("--no-log", action="store_true", help="do not write a session log")

    log = commands.add_parser("log", help="record a radio to a log without the console")
    _radio_options(log)
    log.add_argument("--duration", type=float, help="stop after this many seconds")

    export = commands.add_parser("export", help="write a log's frames as CSV")
    export.add_argument("log", help="a .jsonl session log")
    export.add_argument("-o", "--output", help="CSV file (default: next to the log; - stdout)")
    export.add_argument(
        "--type", action="append", help="only this message type (STATUS, ...); repeatable"
    )

    plot = commands.add_parser("plot", help="draw a log as a PNG: radius, state, intensity")
    plot.add_argument("log", help="a .jsonl session log")
    plot.add_argument("-o", "--output", help="PNG file (default: next to the log)")

    replay = commands.add_parser("replay", help="feed a log back through the console")
    replay.add_argument("log", help="a .jsonl session log")
    replay.add_argument("--speed", default="1", help="times real time, or max (default 1)")
    replay.add_argument("--no-ui", action="store_true", help="print a summary instead")

    demo = commands.add_parser("demo", help="a virtual swarm at a lamp: START (method D), STOP")
    demo.add_argument("--particles", type=int, default=10, help="how many (default 10)")
    demo.add_argument("--speed", type=float, help="times real time (default 2 live, 20 headless)")
    demo.add_argument("--run-s", type=float, default=12.0, help="simulated seconds of cycling")
    demo.add_argument("--seed", type=int, default=1, help="random seed of the particles")
    demo.add_argument("--no-ui", action="store_true", help="print a summary, no live console")
    demo.add_argument("--no-log", action="store_true", help="do not write a session log")
    _log_options(demo)
    for name in SELF_REGISTERING:
        importlib.import_module(f"particlebot.commands.{name}").add_parser(commands)
    return parser


def _dispatch(command: str) -> Callable[[argparse.Namespace], int]:
    # Each subcommand's module is imported only when used, so `export` never loads Textual.
    if command in SELF_REGISTERING:
        return importlib.import_module(f"particlebot.commands.{command}").run
    if command == "console":
        from particlebot.commands.console import run
    elif command == "log":
        from particlebot.commands.log import run
    elif command == "export":
        from particlebot.commands.export import run
    elif command == "plot":
        from particlebot.commands.plot import run
    elif command == "replay":
        from particlebot.commands.replay import run
    else:
        from particlebot.commands.demo import run
    return run


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return _dispatch(args.command)(args)


if __name__ == "__main__":
    sys.exit(main())
