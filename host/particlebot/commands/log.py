"""`particlebot log`: record a radio to a log file without a console (Ctrl-C or kill ends it)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from particlebot.commands._common import fail, run_headless, sigterm_as_interrupt, station
from particlebot.logs.jsonl import LogError
from particlebot.radio import RadioError


def run(args: argparse.Namespace) -> int:
    if not args.radio:
        return fail("say which radio to record: --radio URL (see particlebot console --help)")
    try:
        with (
            sigterm_as_interrupt(),
            station(args.radio, Path(args.log_dir), fsync=args.fsync) as base,
        ):
            print(f"Recording {base.radio.url} to {base.log_path}; Ctrl-C ends.", flush=True)
            deadline = None if args.duration is None else time.monotonic() + args.duration

            def until() -> int | None:
                # Without a console, warnings (a silent port, a reset, a foreign firmware) would
                # go unseen until someone reads the log.
                for note in base.model.new_notes():
                    if note.level != "info":
                        print(f"{note.level}: {note.text}", flush=True)
                if base.session.error is not None:
                    return fail(str(base.session.error))
                if deadline is not None and time.monotonic() >= deadline:
                    return 0
                return None

            def report() -> None:
                print(
                    f"{len(base.model.particles)} particles  {base.model.counters_text()}",
                    flush=True,
                )

            try:
                return run_headless(base.model, until, report=report)
            except KeyboardInterrupt:
                return 0
    except (RadioError, LogError) as exc:
        return fail(str(exc))
