"""`particlebot replay`: feed a log back through the console (or print what it held)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from particlebot.commands._common import fail, has_terminal, opened_swarm, run_headless
from particlebot.logs.jsonl import LogError
from particlebot.logs.replay import ReplayRadio
from particlebot.options import SPEED, float_arg
from particlebot.radio import RadioError
from particlebot.resets import reset_cause
from particlebot.swarm.campaigns import state_name

PROGRESS_EVERY_S = 2.0
"""How often a replay without the console says how far it got."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("log", help="a .jsonl session log")
    parser.add_argument(
        "--speed",
        type=float_arg(SPEED),
        help="times real time, or max (default 1 in the console, max with --no-ui)",
    )
    parser.add_argument("--no-ui", action="store_true", help="print a summary instead")


def run(args: argparse.Namespace) -> int:
    ui = not args.no_ui and has_terminal()
    # Without a console nobody watches the pace: as fast as possible unless asked otherwise.
    speed = args.speed if args.speed is not None else (1.0 if ui else math.inf)
    try:
        radio = ReplayRadio(Path(args.log), speed)
    except (RadioError, LogError) as exc:
        return fail(str(exc))
    with opened_swarm(radio, None) as swarm:
        if ui:
            announced = False

            def tick() -> int | None:
                nonlocal announced
                if radio.finished and not announced:
                    announced = True
                    swarm.note(f"Replay of {args.log} finished; q quits")
                return None

            from particlebot.console.app import ConsoleApp  # Textual only when shown

            app = ConsoleApp(
                swarm,
                log_path=str(args.log),
                on_tick=tick,
                read_only=True,
            )
            try:
                return app.run() or 0
            except KeyboardInterrupt:
                return 0
        pace = "as fast as possible" if math.isinf(speed) else f"at {speed:g}x real time"
        print(
            f"Replaying {radio.total_packets} packets ({radio.span_s:.1f} s of log) from "
            f"{args.log} {pace}",
            flush=True,
        )

        def progress() -> None:
            done = radio.position_s / radio.span_s if radio.span_s > 0 else 1.0
            print(f"  {done:4.0%}  {radio.position_s:.1f} of {radio.span_s:.1f} s", flush=True)

        try:
            run_headless(
                swarm,
                lambda: 0 if radio.finished else None,
                report=progress,
                report_every_s=PROGRESS_EVERY_S,
            )
        except KeyboardInterrupt:
            return 0
        # Let the receive thread hand over the last packets before summarising.
        swarm.session.close()
        print(f"Replayed {radio.total_packets} packets from {args.log}")
        print(swarm.tracker.counters_text())
        tracker = swarm.tracker
        for row in tracker.rows():
            status = row.status
            line = (
                f"particle {row.id:>3}  state {state_name(status.state) if status else '?':<11}"
                f"  S_n {status.s_n if status else '-':>3}  intensity {row.intensity}"
            )
            if status is not None:
                line += f"  resets {status.resets} ({reset_cause(status.last_reset_cause)})"
            flags = row.flags(tracker.clock(), tracker.silent_after, tracker.host_hash)
            print(line + "".join(f"  {flag}" for flag in flags))
        return 0
