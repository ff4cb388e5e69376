"""`particlebot export`: a session log as CSV, one row per frame."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from particlebot.commands._common import fail
from particlebot.logs.export import export_csv, export_csv_file
from particlebot.logs.jsonl import LogError


def run(args: argparse.Namespace) -> int:
    log = Path(args.log)
    types = args.type or None
    try:
        if args.output == "-":
            export_csv(log, sys.stdout, types)
            return 0
        output = Path(args.output) if args.output else log.with_suffix(".csv")
        rows = export_csv_file(log, output, types)
    except LogError as exc:
        return fail(str(exc))
    except OSError as exc:
        return fail(f"cannot write {output}: {exc.strerror or exc}")
    print(f"Wrote {rows} rows to {output}")
    return 0
