"""Table S3 through the paper's camera, beside ours and the paper's: the direct reading (each
cell's true speed times 21.06 / camera height) from the dead study's summaries, and the filmed
runs of research/paper_camera.py; a CSV, a figure and the markdown tables of
docs/studies-camera.md.

    PYTHONPATH=host python research/paper_camera_report.py \
        --summary data/studies/dead-10-100.csv --summary data/studies/dead-10-100-high.csv \
        --summary data/studies/dead-1000.csv --summary data/studies/dead-1000-high.csv \
        --summary data/studies/dead-10000-pooled.csv \
        --filmed data/studies/camera/camera-runs.csv \
        --out data/studies/camera --figure docs/studies/camera.png
    PYTHONPATH=host python research/paper_camera_report.py \
        --summary data/studies/dead-published-blob.csv \
        --placement "the published code's placement" \
        --out data/studies/camera/published-placement \
        --figure docs/studies/camera-published-placement.png
"""

from __future__ import annotations

import argparse
import csv
import math
import statistics
import sys
from collections import defaultdict
from dataclasses import dataclass, fields
from pathlib import Path

from particlebot.studies.published import TABLE_S3_MM_S, Published, paper_camera_factor
from particlebot.studies.report import within_band

Cell = tuple[int, float]


def read_summaries(paths: list[Path]) -> dict[Cell, tuple[int, float, float]]:
    """(particles, dead fraction) -> (runs, mean, sd) of speed_mm_s, later files winning."""
    cells: dict[Cell, tuple[int, float, float]] = {}
    for path in paths:
        with path.open(encoding="utf-8", newline="") as stream:
            for row in csv.DictReader(stream):
                if row["metric"] != "speed_mm_s" or not row["mean"]:
                    continue
                cell = (int(row["particles"]), float(row["dead_fraction"]))
                cells[cell] = (int(row["runs"]), float(row["mean"]), float(row["sd"] or "nan"))
    return cells


def read_filmed(path: Path) -> dict[Cell, list[dict[str, float]]]:
    runs: dict[Cell, list[dict[str, float]]] = defaultdict(list)
    if not path.is_file():
        return runs
    with path.open(encoding="utf-8", newline="") as stream:
        for row in csv.DictReader(stream):
            cell = (int(row["particles"]), float(row["dead_fraction"]))
            runs[cell].append({k: float(v) for k, v in row.items()})
    return runs


def _mean_sd(values: list[float]) -> tuple[float, float]:
    sd = statistics.stdev(values) if len(values) > 1 else float("nan")
    return statistics.fmean(values), sd


def _pm(mean: float, sd: float) -> str:
    return f"{mean:.2f}" if sd != sd else f"{mean:.2f} ± {sd:.2f}"


def _mark(mean: float, ref: Published) -> str:
    return "✓" if within_band(mean, ref) else "✗"


@dataclass
class Row:
    """One cell of Table S3: ours true, ours through the paper's camera (direct and filmed),
    the paper's."""

    particles: int
    dead_fraction: float
    runs: int
    true_mean: float
    true_sd: float
    paper_camera_mean: float
    paper_camera_sd: float
    paper_mean: float
    paper_sd: float
    true_within: bool
    paper_camera_within: bool
    filmed_runs: int = 0
    filmed_true_mean: float = math.nan
    filmed_tracked_mean: float = math.nan
    filmed_paper_camera_mean: float = math.nan
    filmed_paper_camera_sd: float = math.nan
    filmed_within: bool | None = None

    @property
    def paper(self) -> Published:
        return Published(self.paper_mean, self.paper_sd)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--summary", action="append", required=True, help="a dead study CSV")
    parser.add_argument("--filmed", help="paper_camera.py's camera-runs.csv (none: no filmed runs)")
    parser.add_argument("--out", required=True, help="folder for table-s3-camera.csv")
    parser.add_argument("--figure", required=True, help="PNG to write")
    parser.add_argument(
        "--placement",
        default="our Algorithm 5 placement",
        help="the summaries' placement, for the figure's title",
    )
    args = parser.parse_args()
    summaries = read_summaries([Path(p) for p in args.summary])
    filmed = read_filmed(Path(args.filmed)) if args.filmed else {}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rows = []
    for (n, fraction), (runs, mean, sd) in sorted(summaries.items()):
        ref = TABLE_S3_MM_S.get(n, {}).get(fraction)
        if ref is None:
            continue
        f = paper_camera_factor(n)
        row = Row(
            n, fraction, runs, mean, sd, mean * f, sd * f, ref.mean, ref.sd,
            within_band(mean, ref), within_band(mean * f, ref),
        )  # fmt: skip
        runs_here = filmed.get((n, fraction), [])
        if runs_here:
            row.filmed_runs = len(runs_here)
            row.filmed_true_mean = statistics.fmean(r["true_mm_s"] for r in runs_here)
            row.filmed_tracked_mean = statistics.fmean(r["tracked_mm_s"] for r in runs_here)
            camera = _mean_sd([r["paper_camera_mm_s"] for r in runs_here])
            row.filmed_paper_camera_mean, row.filmed_paper_camera_sd = camera
            row.filmed_within = within_band(camera[0], ref)
        rows.append(row)
    with (out / "table-s3-camera.csv").open("w", encoding="utf-8", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow([f.name for f in fields(Row)])
        for row in rows:
            writer.writerow([_cell(getattr(row, f.name)) for f in fields(Row)])
    _markdown(rows, filmed)
    _figure(rows, filmed, Path(args.figure), args.placement)
    return 0


def _cell(value: object) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    return "" if value is None else str(value)


def _markdown(rows: list[Row], filmed: dict[Cell, list[dict[str, float]]]) -> None:
    fractions = sorted({r.dead_fraction for r in rows})
    sizes = sorted({r.particles for r in rows})
    by = {(r.particles, r.dead_fraction): r for r in rows}
    print("| particles | | " + " | ".join(f"{f * 100:.0f} %" for f in fractions) + " |")
    print("|---|---|" + "---|" * len(fractions))
    counts = {"true": [0, 0], "paper camera": [0, 0]}
    for n in sizes:
        true_cells, camera_cells, paper_cells = [], [], []
        for f in fractions:
            r = by.get((n, f))
            if r is None:
                true_cells.append("")
                camera_cells.append("")
                paper_cells.append("")
                continue
            true_cells.append(f"{_pm(r.true_mean, r.true_sd)} {_mark(r.true_mean, r.paper)}")
            camera_cells.append(
                f"{_pm(r.paper_camera_mean, r.paper_camera_sd)} "
                f"{_mark(r.paper_camera_mean, r.paper)}"
            )
            paper_cells.append(_pm(r.paper_mean, r.paper_sd))
            counts["true"][0] += r.true_within
            counts["paper camera"][0] += r.paper_camera_within
            counts["true"][1] += 1
            counts["paper camera"][1] += 1
        print(f"| {n:,} | true | " + " | ".join(true_cells) + " |")
        print("| | paper camera | " + " | ".join(camera_cells) + " |")
        print("| | paper | " + " | ".join(paper_cells) + " |")
    print()
    for key, (inside, total) in counts.items():
        print(f"{key}: {inside} of {total} cells inside the paper's band")
    if not filmed:
        return
    print()
    print("| particles | dead | filmed runs | true | tracked | paper camera | paper |")
    print("|---|---|---|---|---|---|---|")
    for (n, f), runs in sorted(filmed.items()):
        ref = TABLE_S3_MM_S[n][f]
        t = _mean_sd([r["true_mm_s"] for r in runs])
        k = _mean_sd([r["tracked_mm_s"] for r in runs])
        c = _mean_sd([r["paper_camera_mm_s"] for r in runs])
        dropped = sum(int(r["dropped"]) for r in runs)
        frames = sum(int(r["frames"]) for r in runs)
        print(
            f"| {n:,} | {f * 100:.0f} % | {len(runs)} ({dropped} of {frames} frames dropped) "
            f"| {_pm(*t)} | {_pm(*k)} | {_pm(*c)} {_mark(c[0], ref)} | {_pm(ref.mean, ref.sd)} |"
        )


def _figure(
    rows: list[Row], filmed: dict[Cell, list[dict[str, float]]], path: Path, placement: str
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    by = {(r.particles, r.dead_fraction): r for r in rows}
    fig, grid = plt.subplots(2, 2, figsize=(12, 8.5))
    axes = grid.ravel()
    colours = {"paper": "black", "true": "tab:blue", "camera": "tab:red"}
    markers = {"paper": "s", "true": "o", "camera": "^"}
    labels = {
        "paper": "paper (Table S3, ±1 sd)",
        "true": "ours, true speed",
        "camera": "ours through the paper's camera (x 21.06 / height)",
    }
    panels = [(axes[0], "n", 0.0), (axes[1], "f", 10), (axes[2], "f", 100), (axes[3], "f", 1000)]
    for ax, kind, fixed in panels:
        if kind == "n":
            keys = sorted(k for k in by if k[1] == fixed)
            xs = [float(k[0]) for k in keys]
            ax.set_xscale("log")
            ax.set_xlabel("particles (0 % dead)")
        else:
            keys = sorted(k for k in by if k[0] == fixed)
            xs = [k[1] * 100 for k in keys]
            ax.set_xlabel(f"dead particles (%), {int(fixed):,} particles")
        for name in ("paper", "true", "camera"):
            if kind == "n":
                x = [v * {"paper": 0.96, "true": 1.0, "camera": 1.04}[name] for v in xs]
            else:
                x = [v + {"paper": -1.0, "true": 0.0, "camera": 1.0}[name] for v in xs]
            mean = {
                "paper": [by[k].paper_mean for k in keys],
                "true": [by[k].true_mean for k in keys],
                "camera": [by[k].paper_camera_mean for k in keys],
            }[name]
            sd = {
                "paper": [by[k].paper_sd for k in keys],
                "true": [by[k].true_sd for k in keys],
                "camera": [by[k].paper_camera_sd for k in keys],
            }[name]
            ax.errorbar(
                x, mean, yerr=sd, capsize=3, color=colours[name], marker=markers[name],
                linestyle="none" if name == "paper" else "-", label=labels[name],
            )  # fmt: skip
        fx, fy = [], []
        for k in keys:
            for run in filmed.get(k, []):
                fx.append(k[0] * 1.09 if kind == "n" else k[1] * 100 + 2.0)
                fy.append(run["paper_camera_mm_s"])
        if fx:
            ax.plot(
                fx, fy, linestyle="none", marker="x", color="tab:orange",
                label="ours filmed, tracked, one pixel scale (each run)",
            )  # fmt: skip
        ax.axhline(0, color="grey", lw=0.5)
        ax.set_ylabel("speed toward the light (mm/s)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(
        "Table S3 read with one pixel scale (the 1,000-particle camera's): "
        f"true x 21.06 / camera height; {placement}"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"figure: {path}", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
