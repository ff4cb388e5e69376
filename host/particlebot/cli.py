"""The `particlebot` command: a table of subcommands, each a module with its own options."""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys
from collections.abc import Sequence
from typing import NoReturn, Protocol, cast

from particlebot import __version__, resources
from particlebot.errors import ParticlebotError
from particlebot.protocol import DEFINITION_HASH

# Subcommand -> what it does. Each is the module particlebot.commands.<name> (a dash becomes an
# underscore) with add_arguments(parser) and run(args) -> exit status; a module imports what only
# its run() needs inside run(), so building this parser stays fast and `export` never loads
# Textual. A new command is a module and a line here.
COMMANDS: dict[str, str] = {
    # the base station
    "console": "live table of every particle, with commands",
    "log": "record a radio to a log without the console",
    "run": "run an experiment file's trials",
    "demo": "a blob of virtual particles finds a lamp in 2-D (phototaxis), measured as Table S2",
    # session logs
    "export": "write a log's frames as CSV",
    "plot": "draw a log as a PNG: radius, state, intensity",
    "replay": "feed a log back through the console",
    # the fleet
    "flash": "firmware and an id onto Fio v3 boards",
    "radio": "configure XBee radios for the fleet",
    "fleet": "create or list the fleet file",
    # simulation
    "simulate": "a swarm in the simulated world: scenario file or flags, run folder",
    "study": "run one of the paper's simulation studies on Dask",
    "setup": "compile the simulator's kernels into numba's cache ahead of the first run",
    # analysis
    "track": "track the swarm on video: centroid per frame as TRACK.csv, contact sheet",
    "stats": "Table S2 for tracks and simulator runs: speeds toward the lamp, t-test, plots",
    "render": "a synthetic top-view video with known centroids (tracker ground truth)",
    "calibrate": "calibrate photocells and servo tables; check position estimates (Fig. S5)",
}


class Parser(argparse.ArgumentParser):
    """argparse that reports a mistake in one line (what is wrong, where the help is) instead of
    the usage block followed by the error."""

    def error(self, message: str) -> NoReturn:
        # "particlebot: demo: ...", like every other one-line error the commands print.
        command = self.prog.removeprefix("particlebot").strip()
        where = f"{command}: " if command else ""
        self.exit(2, f"particlebot: {where}{message} (see {self.prog} --help)\n")


def version_text() -> str:
    """What --version prints: the package's version, the protocol definition hash the host
    speaks, and the firmware image flash and emulated particles use by default."""
    image = resources.firmware_image()
    manifest = resources.firmware_manifest()
    if manifest is not None:
        firmware = f"firmware image {image} (definition {manifest.definition_hash:08X})"
    elif image.exists():
        firmware = f"firmware image {image}"
    else:
        firmware = f"no firmware image at {image}"
    return f"particlebot {__version__} (protocol definition {DEFINITION_HASH:08X})\n{firmware}"


class _PrintVersion(argparse.Action):
    """--version as written by version_text(), line breaks kept (argparse's own would wrap)."""

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        print(version_text())
        parser.exit(0)


class Command(Protocol):
    """What a module under particlebot.commands provides."""

    def add_arguments(self, parser: argparse.ArgumentParser) -> None: ...

    def run(self, args: argparse.Namespace) -> int: ...


def command_module(name: str) -> Command:
    return cast(Command, importlib.import_module(f"particlebot.commands.{name.replace('-', '_')}"))


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="particlebot",
        description="Particle robots: base station, fleet tools, simulator and analysis.",
        epilog=f"protocol definition hash {DEFINITION_HASH:08X}",
    )
    parser.add_argument(
        "--version", action=_PrintVersion, nargs=0, help="show the versions and exit"
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, summary in COMMANDS.items():
        command_module(name).add_arguments(commands.add_parser(name, help=summary))
    return parser


# What writing to a closed pipe or a full or failing disk behind `>` raises. Such an error has no
# file name; one with a name is about a file a command opened itself, which it reports itself.
STDOUT_ERRNOS = frozenset({errno.EPIPE, errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


INTERRUPTED = 130
"""The exit status of a command stopped by Ctrl-C (128 + SIGINT), as shells report it."""


def main(argv: Sequence[str] | None = None) -> int:
    command = ""
    try:
        args = build_parser().parse_args(argv)
        command = args.command
        return command_module(command).run(args)
    except ParticlebotError as exc:
        # A command that does not catch an error of ours itself still says it in one line.
        where = f"{command}: " if command else ""
        print(f"particlebot: {where}{exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # Ctrl-C before a command's own handling begins (while it imports numba, say), or in
        # one that has none: what it wrote is whole (outputs go through particlebot.fileio).
        print("particlebot: interrupted", file=sys.stderr)
        return INTERRUPTED
    except OSError as exc:
        if exc.errno not in STDOUT_ERRNOS or exc.filename is not None:
            raise
        # Python would flush what is left in stdout's buffer again at exit and fail again, with
        # a traceback of its own: it goes nowhere instead.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        if exc.errno == errno.EPIPE:
            return 0  # the reader took what it wanted and left (`| head`), as with any filter
        print(f"particlebot: cannot write the output: {exc.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
