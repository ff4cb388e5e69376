"""`particlebot export`: a session log as CSV, one row per frame."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from particlebot.commands._arguments import message_type
from particlebot.commands._common import fail
from particlebot.logs.export import export_csv, export_csv_file
from particlebot.logs.jsonl import LogError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("log", help="a .jsonl session log")
    parser.add_argument("-o", "--output", help="CSV file (default: next to the log; - stdout)")
    parser.add_argument(
        "--type",
        action="append",
        type=message_type,
        help="only this message type (STATUS, ...); repeatable",
    )
    parser.add_argument("--notes", action="store_true", help="add the console's notes, a row each")


def run(args: argparse.Namespace) -> int:
    log = Path(args.log)
    types = args.type or None
    if args.output == "-":
        try:
            return _to_stdout(log, types, args.notes)
        except LogError as exc:
            return fail(str(exc))
    output = Path(args.output) if args.output else log.with_suffix(".csv")
    try:
        rows = export_csv_file(log, output, types, notes=args.notes)
    except LogError as exc:
        return fail(str(exc))
    except OSError as exc:
        return fail(f"cannot write {output}: {exc.strerror or exc}")
    print(f"Wrote {rows} rows to {output}")
    return 0


def _to_stdout(log: Path, types: list[str] | None, notes: bool) -> int:
    # A reader that leaves early (`| head`) or a full disk behind `>` is cli.main's business.
    export_csv(log, sys.stdout, types, notes=notes)
    sys.stdout.flush()
    return 0
