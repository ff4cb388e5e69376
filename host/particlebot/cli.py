"""The `particlebot` command: argument parsing shared by every subcommand, then a thin dispatch."""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence
from importlib.metadata import PackageNotFoundError, version
from typing import NoReturn

from particlebot.options import NON_NEGATIVE, POSITIVE, SPEED, Bounds, float_arg, int_arg
from particlebot.protocol import DEFINITION_HASH, MessageType
from particlebot.virtual import MAX_PARTICLES

RADIO_HELP = (
    "radio URL: serial:///dev/ttyUSB0?baud=9600 (transparent XBee), xbee:///dev/ttyUSB0 "
    "(API mode AP=1/2), virtual://10?speed=4 (simulated swarm of the firmware logic), "
    "emulated://5?loss=0.2 (the real firmware image in simavr; needs `make firmware harness`); "
    "default $PARTICLEBOT_RADIO"
)


class Parser(argparse.ArgumentParser):
    """argparse that reports a mistake in one line (what is wrong, where the help is) instead of
    the usage block followed by the error."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")


def package_version() -> str:
    try:
        return version("particlebot")
    except PackageNotFoundError:  # running from a source tree that was never installed
        return "unknown"


def message_type(text: str) -> str:
    """An argparse `type=`: a message type's name, any case (STATUS, status)."""
    name = text.upper()
    if name not in MessageType.__members__:
        raise argparse.ArgumentTypeError(
            f"no message type '{text}'; types: {', '.join(MessageType.__members__)}"
        )
    return name


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
    parser = Parser(
        prog="particlebot",
        description="Base station for particle robots: console, logging, virtual swarm.",
        epilog=f"protocol definition hash {DEFINITION_HASH:08X}",
    )
    parser.add_argument(
        "--version",
        action="version",
        version=f"particlebot {package_version()} (protocol definition {DEFINITION_HASH:08X})",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    console = commands.add_parser("console", help="live table of every particle, with commands")
    _radio_options(console)
    console.add_argument("--no-log", action="store_true", help="do not write a session log")
    console.add_argument(
        "--fleet", help="fleet file: the roster every STOP must hear from (default ./fleet.toml)"
    )

    log = commands.add_parser("log", help="record a radio to a log without the console")
    _radio_options(log)
    log.add_argument("--duration", type=float_arg(POSITIVE), help="stop after this many seconds")

    export = commands.add_parser("export", help="write a log's frames as CSV")
    export.add_argument("log", help="a .jsonl session log")
    export.add_argument("-o", "--output", help="CSV file (default: next to the log; - stdout)")
    export.add_argument(
        "--type",
        action="append",
        type=message_type,
        help="only this message type (STATUS, ...); repeatable",
    )
    export.add_argument("--notes", action="store_true", help="add the console's notes, a row each")

    plot = commands.add_parser("plot", help="draw a log as a PNG: radius, state, intensity")
    plot.add_argument("log", help="a .jsonl session log")
    plot.add_argument("-o", "--output", help="PNG file (default: next to the log)")
    plot.add_argument(
        "--run",
        type=int_arg(Bounds(minimum=1, maximum=255)),
        help="only this run: from its START to the next one",
    )
    plot.add_argument(
        "--from",
        dest="start",
        type=float_arg(NON_NEGATIVE),
        metavar="S",
        help="from S seconds after the session started (as on the time axis)",
    )
    plot.add_argument(
        "--to",
        dest="end",
        type=float_arg(NON_NEGATIVE),
        metavar="S",
        help="up to S seconds after the session started",
    )

    replay = commands.add_parser("replay", help="feed a log back through the console")
    replay.add_argument("log", help="a .jsonl session log")
    replay.add_argument(
        "--speed",
        type=float_arg(SPEED),
        help="times real time, or max (default 1 in the console, max with --no-ui)",
    )
    replay.add_argument("--no-ui", action="store_true", help="print a summary instead")

    demo = commands.add_parser("demo", help="a virtual swarm at a lamp: START (method D), STOP")
    demo.add_argument(
        "--particles",
        type=int_arg(Bounds(minimum=1, maximum=MAX_PARTICLES)),
        default=10,
        help=f"how many, 1..{MAX_PARTICLES} (default 10)",
    )
    demo.add_argument(
        "--speed",
        type=float_arg(SPEED),
        help="times real time, or max (default 2 live, 20 headless)",
    )
    demo.add_argument(
        "--run-s", type=float_arg(POSITIVE), default=12.0, help="simulated seconds of cycling"
    )
    demo.add_argument(
        "--seed", type=int_arg(NON_NEGATIVE), default=1, help="random seed of the particles"
    )
    demo.add_argument("--no-ui", action="store_true", help="print a summary, no live console")
    demo.add_argument("--no-log", action="store_true", help="do not write a session log")
    _log_options(demo)

    # Fleet tools and experiments: each module adds its own options.
    from particlebot.commands import flash, radio
    from particlebot.commands import fleet as fleet_command
    from particlebot.commands import run as run_command

    flash.add_arguments(commands.add_parser("flash", help="firmware and an id onto Fio v3 boards"))
    radio.add_arguments(commands.add_parser("radio", help="configure XBee radios for the fleet"))
    fleet_command.add_arguments(commands.add_parser("fleet", help="create or list the fleet file"))

    # Parsed by particlebot.commands.study itself (main() hands it over): per-study options.
    commands.add_parser("study", help="run one of the paper's simulation studies on Dask")

    for name in SELF_REGISTERING:
        importlib.import_module(f"particlebot.commands.{name}").add_parser(commands)
    run_command.add_arguments(commands.add_parser("run", help="run an experiment file's trials"))
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
    elif command in ("flash", "radio", "fleet", "run"):
        run = importlib.import_module(f"particlebot.commands.{command}").run
    else:
        from particlebot.commands.demo import run
    return run


def main(argv: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["study"]:
        from particlebot.commands.study import main as study

        return study(argv[1:])
    args = build_parser().parse_args(argv)
    return _dispatch(args.command)(args)


if __name__ == "__main__":
    sys.exit(main())
