"""Closed-loop phototaxis with the firmware, measured as Table S2 was (SI S6): for each method and
seed, a swarm of simulated particles STARTed with phototaxis on; the table of speeds and p-values
with the paper's rows beside it, and a picture of every run.

    python research/closed_loop.py                    # 10 virtual particles, A-D, 5 seeds, 30 min
    python research/closed_loop.py --level emulated --particles 5 --scenario line --minutes 10 \\
        --seeds 1
    python research/closed_loop.py --jobs 2 --variant D:COUNT_TOLERANCE=40,UPDATE_INTERVAL_S=360

Virtual particles run the firmware logic, emulated ones the flashed image in simavr; both in the
2-D world, a lamp 35 cm tall (its bulb 28 cm above the photocells, SI S4A), a blob (SI Algorithm
5) or a line starting 1.5 m from its foot. Each run keeps its session log; results.csv, table.md
and closed-loop.png go to --out.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from particlebot.experiments.phototaxis import PhototaxisResult, PhototaxisTrial, run_phototaxis
from particlebot.protocol import Param

# Table S2 of the SI: (method, average, peak % min. diameter/cycle, p-value).
PAPER = [
    ("A", 3.03, 8.96, 3.1309e-07),
    ("A", 1.90, 6.74, 3.1668e-09),
    ("A", 2.61, 7.99, 1.0892e-07),
    ("C", 1.79, 5.02, 3.5582e-07),
    ("D", 3.13, 12.89, 6.7304e-09),
    ("C", 1.95, 6.14, 3.3364e-04),
    ("C", 3.10, 12.13, 3.3641e-04),
    ("B", 2.05, 5.11, 1.2635e-05),
    ("A", 2.25, 8.28, 8.2513e-10),
]


def trials(args: argparse.Namespace) -> list[PhototaxisTrial]:
    duration = args.minutes * 60
    found = [
        PhototaxisTrial(method=m, cycle_steps=args.cycle_steps, duration_s=duration)
        for m in args.methods.split(",")
    ]
    for variant in args.variant:
        method, _, settings = variant.partition(":")
        params = {}
        for setting in filter(None, settings.split(",")):
            name, _, value = setting.partition("=")
            params[Param[name.strip().upper()]] = int(value)
        found.append(
            PhototaxisTrial(
                method=method, cycle_steps=args.cycle_steps, duration_s=duration, params=params
            )
        )
    return found


def url_of(args: argparse.Namespace, seed: int) -> str:
    scheme = "virtual" if args.level == "virtual" else "emulated"
    return (
        f"{scheme}://{args.particles}?speed=max&scenario={args.scenario}&start={args.start}"
        f"&lamp=0,0,{args.lamp_height}&seed={seed}"
    )


def one(job: tuple[str, PhototaxisTrial, Path, str]) -> PhototaxisResult:
    url, trial, folder, name = job
    return run_phototaxis(url, trial, folder, log_name=name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--level", choices=("virtual", "emulated"), default="virtual")
    parser.add_argument("--particles", type=int, default=10)
    parser.add_argument("--scenario", choices=("blob", "line"), default="blob")
    parser.add_argument("--start", type=float, default=1.5, help="m from the lamp's foot")
    parser.add_argument("--lamp-height", type=float, default=0.28, help="m above the photocells")
    parser.add_argument("--methods", default="A,B,C,D")
    parser.add_argument(
        "--variant",
        action="append",
        default=[],
        metavar="M:PARAM=V,...",
        help="also run method M with these parameters set first, e.g. D:COUNT_TOLERANCE=40",
    )
    parser.add_argument("--cycle-steps", type=int, default=150)
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--out", type=Path, default=Path("results/closed-loop"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    jobs = []
    for trial in trials(args):
        for seed in range(1, args.seeds + 1):
            tuned = "-" + "-".join(f"{p.name.lower()}{v}" for p, v in trial.params.items())
            name = f"{trial.label.split()[0]}{tuned if trial.params else ''}-seed{seed}.jsonl"
            jobs.append((url_of(args, seed), trial, args.out, name))
    began = time.monotonic()
    results: list[PhototaxisResult] = []
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for done, result in enumerate(pool.map(one, jobs), start=1):
            results.append(result)
            s = result.stats
            print(
                f"[{done}/{len(jobs)}] {result.trial.label:28s} {result.url.split('seed=')[1]:>3}"
                f"  {s.average_pct:5.2f} %D/cycle (peak {s.peak_pct:5.2f}), p = {s.p_value:.2e}, "
                f"{result.toward_lamp_m * 100:6.1f} cm, {result.done} DONE  "
                f"({time.monotonic() - began:.0f} s)",
                flush=True,
            )
    write_outputs(args, results)


def write_outputs(args: argparse.Namespace, results: list[PhototaxisResult]) -> None:
    with (args.out / "results.csv").open("w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(
            ["method", "seed", "avg_pct", "peak_pct", "avg_mm_s", "p", "cycle_s", "toward_m",
             "done", "log"]
        )  # fmt: skip
        for r in results:
            s = r.stats
            writer.writerow(
                [r.trial.label, r.url.split("seed=")[1], f"{s.average_pct:.3f}",
                 f"{s.peak_pct:.3f}", f"{s.average_mm_s:.4f}", f"{s.p_value:.4e}",
                 f"{s.cycle_s:g}", f"{r.toward_lamp_m:.3f}", r.done, r.log.name]
            )  # fmt: skip
    lines = [
        "| run | method | seed | average %D/cycle | peak %D/cycle | p-value | cycle s | "
        "toward lamp cm | DONE |",
        "| ---: | :--- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for number, r in enumerate(results, start=1):
        s = r.stats
        lines.append(
            f"| {number} | {r.trial.label} | {r.url.split('seed=')[1]} | {s.average_pct:.2f} | "
            f"{s.peak_pct:.2f} | {s.p_value:.2e} | {s.cycle_s:g} | "
            f"{r.toward_lamp_m * 100:.1f} | {r.done} |"
        )
    lines += [
        "",
        "| method | runs | average %D/cycle | peak %D/cycle | p < 0.01 |",
        "| :--- | ---: | ---: | ---: | ---: |",
    ]
    for label in dict.fromkeys(r.trial.label for r in results):
        group = [r for r in results if r.trial.label == label]
        avg = [r.stats.average_pct for r in group]
        peak = [r.stats.peak_pct for r in group]
        significant = sum(r.stats.p_value < 0.01 for r in group)
        lines.append(
            f"| {label} | {len(group)} | {statistics.mean(avg):.2f} ± "
            f"{statistics.stdev(avg) if len(avg) > 1 else 0:.2f} | {statistics.mean(peak):.2f} | "
            f"{significant} of {len(group)} |"
        )
    paper = [a for _, a, _, _ in PAPER]
    lines.append(
        f"| paper (Table S2) | 9 | {statistics.mean(paper):.2f} ± {statistics.stdev(paper):.2f} "
        f"({min(paper):.2f}-{max(paper):.2f}) | {statistics.mean(p for _, _, p, _ in PAPER):.2f} | "
        "9 of 9 |"
    )
    (args.out / "table.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    picture(results, args.out / "closed-loop.png")
    print(f"table: {args.out / 'table.md'}; picture: {args.out / 'closed-loop.png'}")


def picture(results: list[PhototaxisResult], output: Path) -> None:
    """Every run's centroid in the paper's frame (lamp up), and the speeds beside Table S2's."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(13, 5.5), layout="constrained")
    FigureCanvasAgg(figure)
    tracks, speeds = figure.subplots(1, 2, width_ratios=[1, 1.3])
    labels = list(dict.fromkeys(r.trial.label for r in results))
    colours = {label: f"C{i}" for i, label in enumerate(labels)}
    for r in results:
        s = r.stats
        tracks.plot(s.sample_x_cm, s.sample_y_cm, color=colours[r.trial.label], linewidth=1.2,
                    marker=".", markersize=3)  # fmt: skip
    for label in labels:
        tracks.plot([], [], color=colours[label], label=label.replace(", ", ",\n"))
    tracks.plot([0], [0], "ks", markersize=5, label="start (origin)")
    tracks.set_aspect("equal", adjustable="datalim")
    tracks.set_xlabel("x (cm), the lamp's right")
    tracks.set_ylabel("y (cm), toward the lamp")
    tracks.set_title("centroid every 30 s, every run (lamp on +y)")
    tracks.grid(True, alpha=0.3)
    tracks.legend(fontsize=8, loc="upper left")  # the tracks rise from the origin: that is free
    for i, label in enumerate(labels):
        group = [r for r in results if r.trial.label == label]
        avg = [r.stats.average_pct for r in group]
        speeds.scatter(np.full(len(avg), i) + np.linspace(-0.15, 0.15, len(avg)), avg,
                       color=colours[label], zorder=3)  # fmt: skip
        for r, x in zip(group, np.linspace(-0.15, 0.15, len(avg)) + i, strict=True):
            if r.stats.p_value >= 0.01:
                speeds.annotate("n.s.", (x, r.stats.average_pct), fontsize=7,
                                textcoords="offset points", xytext=(3, 3))  # fmt: skip
    paper_x = len(labels)
    speeds.scatter(np.full(len(PAPER), paper_x), [a for _, a, _, _ in PAPER], color="black",
                   marker="D", zorder=3)  # fmt: skip
    speeds.axhspan(1.79, 3.13, color="0.85", zorder=0, label="Table S2's range")
    ticks = [label.replace(" (", "\n(").replace(", ", ",\n") for label in labels]
    speeds.set_xticks(range(len(labels) + 1), [*ticks, "paper\n(Table S2)"], fontsize=7)
    speeds.set_ylabel("average speed toward the lamp (% min. diameter / cycle)")
    speeds.set_title("speed per run (n.s.: not significant at p < 0.01)")
    speeds.grid(True, axis="y", alpha=0.3)
    speeds.legend(fontsize=8)
    figure.savefig(output, dpi=100)


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(130)
