"""`particlebot stats SOURCE...`: the paper's Table S2 (speeds toward the lamp and a one-tailed
t-test) for tracks and simulator runs, one row per source, with a plot of each."""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from particlebot.commands._common import fail
from particlebot.options import DURATION, LENGTH_CM, SPAN_S, float_arg

if TYPE_CHECKING:
    from particlebot.analysis.stats import StatsResult

DESCRIPTION = """\
Samples each source's centroid every --interval-s (30 s, SI S6), puts the origin at the first
sample and the lamp on +y, and runs a one-tailed t-test on the steps toward the lamp (H0: mean
step 0). Average speed is the mean step per interval (what the t-test tests), peak speed the
largest; both in mm/s and in % of the contracted diameter per cycle = mm/s x cycle / diameter.
"Cycle" is the period at which each particle repeats expansion, contraction and pause: by default
the source's own (12 s for the published simulator, whose Tables S3/S4 use it), else 9 s, the
paper's experiments (T = 3 s + pause 6 s; S6 calls 30 s about 3.5 cycles). Give --cycle-s for
your own runs: T + t_p = T (N + 1) / 2 for a wave of N. SOURCE: a TRACK.csv (particlebot track), a
simulator CSV in the published format ('Seed, N' first line), a session log of a simulated radio
(its particles' true centres from START to STOP, its cycle from their commanded radii) or a
folder holding any of them."""


def add_arguments(stats: argparse.ArgumentParser) -> None:
    stats.description = DESCRIPTION
    stats.add_argument(
        "sources", nargs="+", metavar="SOURCE", help="TRACK.csv, CSV, session log or folder"
    )
    stats.add_argument(
        "--interval-s",
        type=float_arg(DURATION),
        default=30.0,
        help="sampling interval (30, as in S6)",
    )
    stats.add_argument(
        "--average-s",
        type=float_arg(SPAN_S),
        default=0.0,
        help="average the centroid over this window around each sample (0: one frame, as S6)",
    )
    stats.add_argument(
        "--cycle-s",
        type=float_arg(DURATION),
        help="cycle period for %%D/cycle (default: the source's, else 9 = the paper's runs)",
    )
    stats.add_argument(
        "--diameter-cm",
        type=float_arg(LENGTH_CM),
        help="contracted diameter for %%D/cycle (default: the firmware's 15.5)",
    )
    stats.add_argument(
        "--lamp",
        metavar="X,Y",
        help="lamp position in every source's own coordinates, cm (default: from the source)",
    )
    stats.add_argument(
        "--accept",
        default="",
        help="track quality flags to use anyway, e.g. lamp,edge (default: only ok frames)",
    )
    stats.add_argument("--csv", metavar="TABLE", help="also write the table as CSV")
    stats.add_argument("--plot-dir", help="where plots go (default: beside each source)")
    stats.add_argument("--no-plot", action="store_true", help="no plots")


TABLE_COLUMNS = (
    ("source", "{name}", 28),
    ("kind", "{kind}", 9),
    ("steps", "{steps}", 5),
    ("cycle s", "{cycle_s:g}", 7),
    ("avg %D/cyc", "{average_pct:.2f}", 10),
    ("peak %D/cyc", "{peak_pct:.2f}", 11),
    ("avg mm/s", "{average_mm_s:.3f}", 8),
    ("peak mm/s", "{peak_mm_s:.3f}", 9),
    ("p (1-tailed)", "{p_value:.4e}", 12),
)


def _cells(result: StatsResult) -> list[str]:
    values = {
        "name": result.name,
        "kind": result.kind,
        "steps": result.steps,
        "cycle_s": result.cycle_s,
        "average_pct": result.average_pct,
        "peak_pct": result.peak_pct,
        "average_mm_s": result.average_mm_s,
        "peak_mm_s": result.peak_mm_s,
        "p_value": result.p_value,
    }
    return [template.format(**values) for _, template, _ in TABLE_COLUMNS]


def print_table(results: list[StatsResult]) -> None:
    widths = [
        max(width, *(len(_cells(r)[i]) for r in results))
        for i, (_, _, width) in enumerate(TABLE_COLUMNS)
    ]
    print("  ".join(title.ljust(w) for (title, _, _), w in zip(TABLE_COLUMNS, widths, strict=True)))
    for result in results:
        print("  ".join(c.ljust(w) for c, w in zip(_cells(result), widths, strict=True)))


def _plot_path(source: Path, plot_dir: Path | None, name: str) -> Path:
    """Beside the source as SOURCE.stats.png; in --plot-dir named after the row, which says the
    run folder too."""
    if plot_dir is None:
        return source.with_suffix(".stats.png")
    return plot_dir / f"{name.replace('/', '_').rsplit('.', 1)[0]}.stats.png"


def run(args: argparse.Namespace) -> int:
    from particlebot.analysis.geometry import GeometryError, parse_pair
    from particlebot.analysis.sources import SourceError, load_source
    from particlebot.analysis.stats import StatsSettings, analyse

    try:
        lamp = parse_pair(args.lamp, "--lamp") if args.lamp else None
    except GeometryError as exc:
        return fail(str(exc))
    for option in ("interval_s", "cycle_s", "diameter_cm"):
        value = getattr(args, option)
        if value is not None and not value > 0:
            return fail(f"--{option.replace('_', '-')} must be positive")
    if not args.average_s >= 0:
        return fail("--average-s must be 0 or positive")
    settings = StatsSettings(
        interval_s=args.interval_s,
        cycle_s=args.cycle_s,
        lamp_cm=lamp,
        average_s=args.average_s,
        **({} if args.diameter_cm is None else {"min_diameter_cm": args.diameter_cm}),
    )
    accept = frozenset(flag.strip() for flag in args.accept.split(",") if flag.strip())
    plot_dir = Path(args.plot_dir) if args.plot_dir else None
    if plot_dir is not None and not plot_dir.is_dir():
        return fail(f"no such folder: {plot_dir}")

    results = []
    paths = []
    try:
        for source in args.sources:
            for series in load_source(Path(source), accept):
                results.append(analyse(series, settings))
                paths.append(series.path)
    except SourceError as exc:
        return fail(str(exc))

    first = results[0]
    print(
        f"Table S2: centroid every {args.interval_s:g} s, origin at the first sample, lamp on +y; "
        f"steps toward the lamp; %D/cycle of a {first.min_diameter_cm * 10:.0f} mm diameter"
    )
    print_table(results)
    for result in results:
        print(
            f"{result.name}: cycle {result.cycle_s:g} s ({result.cycle_from}); lamp "
            f"{result.lamp_distance_cm:.0f} cm from the start ({result.lamp_from}); "
            f"net {result.net_y_cm:+.1f} cm toward it in {result.duration_s / 60:.1f} min"
        )
        for note in result.notes:
            print(f"  note: {note}")
    if args.csv:
        try:
            with open(args.csv, "w", encoding="utf-8", newline="") as stream:
                writer = csv.writer(stream)
                writer.writerow([title for title, _, _ in TABLE_COLUMNS] + ["interval s"])
                for result in results:
                    writer.writerow([*_cells(result), f"{result.interval_s:g}"])
        except OSError as exc:
            return fail(f"cannot write {args.csv}: {exc.strerror}")
        print(f"Table: {args.csv}")
    if not args.no_plot:
        from particlebot.analysis.statsplot import plot_stats

        for result, path in zip(results, paths, strict=True):
            target = _plot_path(path, plot_dir, result.name)
            try:
                plot_stats(result, target)
            except OSError as exc:
                print(f"particlebot: cannot write {target}: {exc.strerror}", file=sys.stderr)
                continue
            print(f"Plot: {target}")
    return 0
