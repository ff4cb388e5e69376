"""`particlebot plot`: a session log drawn as a PNG (radius, state and intensity per particle)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from particlebot.commands._common import fail
from particlebot.options import NON_NEGATIVE, Bounds, float_arg, int_arg


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("log", help="a .jsonl session log")
    parser.add_argument("-o", "--output", help="PNG file (default: next to the log)")
    parser.add_argument(
        "--run",
        type=int_arg(Bounds(minimum=1, maximum=255)),
        help="only this run: from its START to the next one",
    )
    parser.add_argument(
        "--from",
        dest="start",
        type=float_arg(NON_NEGATIVE),
        metavar="S",
        help="from S seconds after the session started (as on the time axis)",
    )
    parser.add_argument(
        "--to",
        dest="end",
        type=float_arg(NON_NEGATIVE),
        metavar="S",
        help="up to S seconds after the session started",
    )


def write_plot(
    log: Path,
    output: Path | None = None,
    *,
    run: int | None = None,
    start: float | None = None,
    end: float | None = None,
) -> int:
    """Plots log (all of it, one run, or a window) to output (default: next to the log, .png);
    warnings go to stderr."""
    from particlebot.plots import PlotInputError, plot_log  # matplotlib only when drawing

    target = output if output is not None else log.with_suffix(".png")
    try:
        result = plot_log(log, target, run=run, start=start, end=end)
    except PlotInputError as exc:
        return fail(str(exc))
    for warning in result.warnings:
        print(f"particlebot: warning: {warning}", file=sys.stderr)
    print(
        f"Plot: {result.output} ({result.particles} particles, "
        f"{result.status_frames} STATUS frames)"
    )
    return 0


def run(args: argparse.Namespace) -> int:
    return write_plot(
        Path(args.log),
        Path(args.output) if args.output else None,
        run=args.run,
        start=args.start,
        end=args.end,
    )
