"""`particlebot log`: record a radio to a log file without a console (Ctrl-C or kill ends it)."""

from __future__ import annotations

import argparse
from pathlib import Path

from particlebot.commands._arguments import add_radio_options
from particlebot.commands._common import fail, opened_swarm, run_headless, sigterm_as_interrupt
from particlebot.logs.jsonl import LogError
from particlebot.options import POSITIVE, float_arg
from particlebot.radio import RadioError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_radio_options(parser)
    parser.add_argument("--duration", type=float_arg(POSITIVE), help="stop after this many seconds")


def run(args: argparse.Namespace) -> int:
    if not args.radio:
        return fail("say which radio to record: --radio URL (see particlebot log --help)")
    try:
        with (
            sigterm_as_interrupt(),
            opened_swarm(args.radio, Path(args.log_dir), fsync=args.fsync) as swarm,
        ):
            print(f"Recording {swarm.url} to {swarm.log_path}; Ctrl-C ends.", flush=True)
            deadline = None if args.duration is None else swarm.now() + args.duration
            tracker = swarm.tracker

            def until() -> int | None:
                # Without a console, warnings (a silent port, a reset, a foreign firmware) would
                # go unseen until someone reads the log.
                for note in tracker.new_notes():
                    if note.level != "info":
                        print(f"{note.level}: {note.text}", flush=True)
                if swarm.session.error is not None:
                    return fail(str(swarm.session.error))
                if deadline is not None and swarm.now() >= deadline:
                    return 0
                return None

            def report() -> None:
                heard = sum(1 for row in tracker.rows() if row.heard)
                print(f"{heard} particles  {tracker.counters_text()}", flush=True)

            try:
                return run_headless(swarm, until, report=report)
            except KeyboardInterrupt:
                return 0
    except (RadioError, LogError) as exc:
        return fail(str(exc))
