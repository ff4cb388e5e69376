"""`particlebot console`: the live console on a radio, logging everything."""

from __future__ import annotations

import argparse
from pathlib import Path

from particlebot.commands._arguments import add_radio_options
from particlebot.commands._common import fail, has_terminal, opened_swarm
from particlebot.fleet import DEFAULT_FLEET_FILE, FleetFileError
from particlebot.logs.jsonl import LogError
from particlebot.radio import RadioError, parse_radio_url


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_radio_options(parser)
    parser.add_argument("--no-log", action="store_true", help="do not write a session log")
    parser.add_argument(
        "--fleet", help="fleet file: the roster every STOP must hear from (default ./fleet.toml)"
    )


def run(args: argparse.Namespace) -> int:
    if not args.radio:
        return fail(
            "say which radio: --radio serial:///dev/ttyUSB0 (transparent XBee), "
            "--radio xbee:///dev/ttyUSB0 (API mode) or --radio virtual://10"
        )
    try:
        parse_radio_url(args.radio)  # a mistyped URL is worth hearing about first
    except RadioError as exc:
        return fail(str(exc))
    if not has_terminal():
        # Textual would wait forever for keys that cannot come.
        return fail(
            "the console needs a terminal; to record without one: particlebot log --radio URL"
        )
    # Textual is imported only by the commands that show it.
    from particlebot.console.app import ConsoleApp

    try:
        with opened_swarm(
            args.radio, _log_dir(args), fsync=args.fsync, fleet=fleet_file(args), stepped=False
        ) as swarm:
            try:
                code = ConsoleApp(swarm).run()
            except KeyboardInterrupt:
                code = 0
            return code or 0
    except (RadioError, LogError, FleetFileError) as exc:
        return fail(str(exc))


def fleet_file(args: argparse.Namespace) -> Path | None:
    """--fleet FILE, else the experiment folder's fleet.toml if there is one."""
    if args.fleet is not None:
        return Path(args.fleet)
    return DEFAULT_FLEET_FILE if DEFAULT_FLEET_FILE.exists() else None


def _log_dir(args: argparse.Namespace) -> Path | None:
    return None if args.no_log else Path(args.log_dir)
