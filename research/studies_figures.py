#!/usr/bin/env python3
"""Draws docs/studies' comparison figures from the summary.csv files of finished study folders:
dead-particle speeds relative to each size's 0 % cell and with one published number changed,
speed against size and against the contact shear, Fig. S18 (gap success against gap size, all
sizes on one plot) and Fig. S20 relative to the noise-free speed. Folders that are missing are
left out of the figures.

A folder that is not there is read from the summary data/studies keeps of it (KEPT_SUMMARIES),
as are the CSVs of the research scripts the figures draw beside the studies (rattling, the
first seconds, packing), so every figure but the dashpot's (whose runs are kept in another form)
redraws from a clone:

    research/studies_figures.py data/studies docs/studies \
        --figures dead,speed,shear,placement,gap,noise
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from particlebot.sim.world.params import PhysicsParams
from particlebot.studies import published as paper

DATA = Path(__file__).resolve().parents[1] / "data" / "studies"
"""The study results the repository keeps (data/studies/README.md says how each was made)."""

Cells = dict[int, list[tuple[float, float, float, int]]]
"""particles -> [(sweep value, mean, sd, runs)] of one metric, sorted by the sweep value."""


KEPT_SUMMARIES = {
    "dead-small": "dead-10-100.csv",
    "dead-high": "dead-10-100-high.csv",
    "dead-1000": "dead-1000.csv",
    "dead-1000-high": "dead-1000-high.csv",
    "dead-10000": "dead-10000.csv",
    "dead-10000-all": "dead-10000-pooled.csv",
    "dead-static1": "dead-10-100-static1.csv",
    "dead-nophasenoise": "dead-10-100-nophasenoise.csv",
    "dead-both": "dead-10-100-both.csv",
    "dead-cand-small": "dead-10-100-cand.csv",
    "dead-cand-1000": "dead-1000-cand.csv",
    "dead-cand-1000b": "dead-1000-cand-b.csv",
    "dead-cand-1000c": "dead-1000-cand-c.csv",
    "dead-cand-10000": "dead-10000-cand.csv",
    "dead-calm-1000": "dead-10-1000-calm.csv",
    "dead-calm-10000": "dead-10000-calm.csv",
    "speed-small": "speed-10-300.csv",
    **{f"dead-mid{s}": "dead-10-10000-shear25.csv" for s in ("", "-1000", "-10000")},
    **{
        f"shear{shear}-{s}": f"dead-10-10000-shear{shear}.csv"
        for shear in ("27.5", "28.5", "29")
        for s in ("small", "1000", "10000")
    },
    **{f"place-pub-{s}": "dead-published-blob.csv" for s in ("small", "1000", "10000")},
    **{f"place-fit-{s}": "dead-published-blob-t0.7-s27.5.csv" for s in ("small", "1000", "10000")},
    **{f"gap-{n}": f"gap-{n}.csv" for n in (10, 100, 1000)},
    **{f"noise-{n}": f"noise-{n}.csv" for n in (100, 1000, 10000)},
}
"""Study folder -> the file in data/studies that keeps its summary.csv (a file may keep several
folders' cells: the folders of one study run in parts). Checked: drawn from these, every figure
but the dashpot's came out byte for byte as drawn from the folders."""


def read(folder: Path, metric: str) -> Cells:
    """One metric of a study folder's summary.csv, or of the file in the folder's parent that
    keeps it (KEPT_SUMMARIES), or of the one data/studies keeps; empty when none is there."""
    path = folder / "summary.csv"
    if not path.is_file() and folder.name in KEPT_SUMMARIES:
        path = folder.parent / KEPT_SUMMARIES[folder.name]
        if not path.is_file():
            path = DATA / KEPT_SUMMARIES[folder.name]
    cells: Cells = defaultdict(list)
    if not path.is_file():
        return cells
    with path.open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    if not rows:
        return cells
    sweep = list(rows[0])[1]  # the sweep's column, or "metric" for a study without one
    for row in rows:
        if row["metric"] != metric or not row["mean"]:
            continue
        sd = float(row["sd"]) if row["sd"] else math.nan
        cells[int(row["particles"])].append(
            (
                0.0 if sweep == "metric" else float(row[sweep]),
                float(row["mean"]),
                sd,
                int(row["runs"]),
            )
        )
    for row_cells in cells.values():
        row_cells.sort()
    return cells


COLOURS = {10: "tab:blue", 30: "tab:purple", 100: "tab:orange", 1000: "tab:green", 10000: "tab:red"}
PUBLISHED_DEAD = (
    "dead-small",
    "dead-high",
    "dead-1000",
    "dead-1000-high",
    "dead-10000-all",  # 0-80 % dead, every seed run (data/studies: the pooled summary)
)
"""Study folders of Table S3 with the published numbers (the first to hold a cell gives it)."""


def gather(results: Path, names: tuple[str, ...], metric: str) -> Cells:
    """One metric from several study folders (sets of sizes, or of columns of the same sizes),
    by size; a cell run in two folders is taken from the first."""
    ours: Cells = defaultdict(list)
    for name in names:
        for n, cells in read(results / name, metric).items():
            have = {value for value, *_ in ours[n]}
            ours[n].extend(cell for cell in cells if cell[0] not in have)
            ours[n].sort()
    return ours


def zero_cells(results: Path, names: tuple[str, ...]) -> dict[int, tuple[float, float, float, int]]:
    """The 0 % dead cell (speed) of every size that has one in these study folders, by size."""
    return {
        n: cells[0]
        for n, cells in sorted(gather(results, names, "speed_mm_s").items())
        if cells and cells[0][0] == 0.0
    }


def count(k: int, noun: str) -> str:
    return f"{k} {noun}" if k == 1 else f"{k} {noun}s"


def seeds_text(runs: list[int]) -> str:
    """How many seeds cells of these run counts have: '3 seeds', or '3-5 seeds' when they differ."""
    lo, hi = min(runs), max(runs)
    return count(lo, "seed") if lo == hi else f"{lo}-{hi} seeds"


def sds_of(cells: list[tuple[float, float, float, int]], scale: float = 1.0) -> list[float]:
    """Each cell's sd over scale; 0 where one run left no sd."""
    return [0.0 if math.isnan(s) else s / scale for _, _, s, _ in cells]


def band(
    ax: plt.Axes, x: list[float], means: list[float], sds: list[float], colour: str, label: str,
    *, alpha: float = 0.2, low: float = -math.inf, high: float = math.inf,
) -> None:  # fmt: skip
    """Our means as a line and mean +- sd as a shaded band (clipped to [low, high])."""
    ax.plot(x, means, "o-", color=colour, ms=3.5, label=label)
    ax.fill_between(
        x,
        [max(low, m - s) for m, s in zip(means, sds, strict=True)],
        [min(high, m + s) for m, s in zip(means, sds, strict=True)],
        color=colour,
        alpha=alpha,
        lw=0,
    )


def paper_zero_column(ax: plt.Axes, marker: str, size: float) -> None:
    """Table S3's 0 % column (mean +- sd by swarm size) as open markers."""
    published = {n: row[0.0] for n, row in paper.TABLE_S3_MM_S.items()}
    ax.errorbar(
        list(published), [c.mean for c in published.values()],
        yerr=[c.sd for c in published.values()], fmt=marker, mfc="white", color="k", ms=size,
        capsize=3, lw=1, label="paper, Table S3 (11 seeds)",
    )  # fmt: skip


def save(fig: plt.Figure, path: Path, layout: bool = True) -> Path:
    """Writes fig; layout=False keeps a layout the caller made (room for a shared legend)."""
    if layout:
        fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def dead_figures(results: Path, out: Path) -> list[Path]:
    ours = gather(results, PUBLISHED_DEAD, "speed_mm_s")
    if not ours:
        return []
    fig, (absolute, relative) = plt.subplots(1, 2, figsize=(11, 4.4), dpi=120)
    for n, cells in sorted(ours.items()):
        colour = COLOURS.get(n, "tab:gray")
        x = [100 * f for f, *_ in cells]
        base = next((m for f, m, _, _ in cells if f == 0.0), math.nan)
        means = [m for _, m, _, _ in cells]
        band(
            absolute,
            x,
            means,
            sds_of(cells),
            colour,
            f"{n:,} ours ({seeds_text([r for *_, r in cells])})",
            alpha=0.18,
        )
        relative.plot(x, [m / base for m in means], "o-", color=colour, ms=3.5, label=f"{n:,} ours")
        published = paper.TABLE_S3_MM_S[n]
        px = [100 * f for f in published if f <= max(f for f, *_ in cells) + 1e-9]
        pm = [published[f / 100].mean for f in px]
        ps = [published[f / 100].sd for f in px]
        absolute.errorbar(
            [v + 0.6 for v in px], pm, yerr=ps, fmt="s", mfc="white", color=colour, ms=4,
            capsize=3, lw=1, label=f"{n:,} paper",
        )  # fmt: skip
        relative.plot(
            px, [m / published[0.0].mean for m in pm], "s--", mfc="white", color=colour, ms=4,
            lw=1, label=f"{n:,} paper",
        )  # fmt: skip
    absolute.set_ylabel("speed toward the light (mm/s)")
    absolute.set_title("Table S3: speed, mean ± 1 sd (ours: band; paper: bars)", fontsize=10)
    relative.set_ylabel("speed / speed with no dead particles")
    relative.set_title("The same, relative to each size's 0 % cell", fontsize=10)
    for ax in (absolute, relative):
        ax.set_xlabel("dead particles (%)")
        ax.axhline(0.0, color="0.6", lw=0.8, zorder=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7.5, ncol=2)
    paths = [save(fig, out / "dead.png")]

    variants = {
        "published defaults": PUBLISHED_DEAD,
        "static friction 1 x μ g (not 2)": ("dead-static1",),
        "no phase noise": ("dead-nophasenoise",),
        "both of these": ("dead-both",),
        "torque limit 0.7 (not 0.5), shear 30 (not 40)": (
            "dead-cand-small",
            "dead-cand-1000",
            "dead-cand-1000b",
            "dead-cand-1000c",
            "dead-cand-10000",
        ),
        "torque limit 0.7, shear 20 (calmer still)": ("dead-calm-1000", "dead-calm-10000"),
    }
    found = {label: gather(results, names, "speed_mm_s") for label, names in variants.items()}
    found = {label: cells for label, cells in found.items() if cells}
    sizes = sorted({n for label, cells in found.items() if label != "published defaults"
                    for n in cells})  # fmt: skip
    if len(found) > 1:
        columns = 2 if len(sizes) == 4 else len(sizes)  # four panels as two rows of two
        rows = math.ceil(len(sizes) / columns)
        fig, axes = plt.subplots(
            rows, columns, figsize=(5.5 * columns, 4.6 * rows), dpi=120, squeeze=False
        )
        order = list(variants)
        handles: dict[str, Any] = {}
        for ax, n in zip(axes.flat, sizes, strict=False):
            published = paper.TABLE_S3_MM_S[n]
            top = max(f for variant in found.values() for f, *_ in variant.get(n, []) if f <= 0.5)
            px = [f for f in published if f <= top + 1e-9]
            handles["paper (Table S3)"] = ax.errorbar(
                [100 * f for f in px], [published[f].mean for f in px],
                yerr=[published[f].sd for f in px], fmt="s", mfc="white", color="k", ms=4,
                capsize=3, lw=1,
            )  # fmt: skip
            seeds = []
            for label, variant in found.items():
                row = [cell for cell in variant.get(n, []) if cell[0] <= top + 1e-9]
                if not row:
                    continue
                seeds += [r for *_, r in row]
                # Side by side around the true x, by a fixed share of the panel's width.
                index = order.index(label)
                shift = (index - (len(order) - 1) / 2) * 0.012 * 100 * max(top, 0.2)
                handles[f"ours, {label}"] = ax.errorbar(
                    [100 * f + shift for f, *_ in row], [m for _, m, _, _ in row],
                    yerr=sds_of(row), fmt="o-", ms=3.5, color=f"C{index}",
                    capsize=2, lw=1,
                )  # fmt: skip
            ax.set_title(f"{n:,} particles ({seeds_text(seeds)} a cell)", fontsize=10)
            ax.set_xlabel("dead particles (%)")
            ax.set_ylabel("speed toward the light (mm/s)")
            ax.axhline(0.0, color="0.6", lw=0.8, zorder=0)
            ax.grid(alpha=0.3)
        for ax in list(axes.flat)[len(sizes) :]:
            ax.set_visible(False)
        # One legend for all panels: a variant has the same colour in each.
        fig.legend(
            list(handles.values()), list(handles), loc="lower center", ncol=2, fontsize=8,
            frameon=False,
        )  # fmt: skip
        fig.suptitle("Table S3 with published numbers changed (2 h, first 30 min left out)")
        fig.tight_layout(rect=(0, 0.02 + 0.022 * math.ceil(len(handles) / 2), 1, 1))
        paths.append(save(fig, out / "dead-variants.png", layout=False))
    return paths


def speed_figure(results: Path, out: Path) -> list[Path]:
    """Speed against swarm size: the speed study's cells, and the dead study's 0 % cells of
    sizes it did not run, beside Table S3's 0 % column."""
    points: dict[int, tuple[float, float, int]] = {}
    for name in ("dead-1000", "dead-10000", "dead-10000-all", "speed-small"):
        for n, cells in read(results / name, "speed_mm_s").items():
            for value, mean, sd, runs in cells:
                if value == 0.0:
                    points[n] = (mean, sd, runs)
    if not points:
        return []
    sizes = sorted(points)
    fig, ax = plt.subplots(figsize=(7.5, 4.6), dpi=120)
    means = [points[n][0] for n in sizes]
    sds = [0.0 if math.isnan(points[n][1]) else points[n][1] for n in sizes]
    ax.plot(sizes, means, "o-", color="tab:blue", ms=4, label="ours, published numbers (± 1 sd)")
    ax.fill_between(
        sizes,
        [m - s for m, s in zip(means, sds, strict=True)],
        [m + s for m, s in zip(means, sds, strict=True)],
        color="tab:blue",
        alpha=0.2,
        lw=0,
    )
    for n in sizes:
        ax.annotate(f"{points[n][2]}", (n, points[n][0]), textcoords="offset points", xytext=(4, 6),
                    fontsize=7, color="tab:blue")  # fmt: skip
    # The same with published numbers changed (the dead study's variants, 0 % cells).
    variants = {
        "torque limit 0.7, shear 30 (the fitted pair)": (
            "dead-cand-small", "dead-cand-1000", "dead-cand-10000",
        ),
        "torque limit 0.7, shear 25": ("dead-mid", "dead-mid-1000", "dead-mid-10000"),
        "torque limit 0.7, shear 20": ("dead-calm-1000", "dead-calm-10000"),
    }  # fmt: skip
    colours = ("tab:purple", "tab:olive", "tab:brown")
    for (label, names), colour in zip(variants.items(), colours, strict=True):
        zero = zero_cells(results, names)
        if zero:
            ax.errorbar(
                list(zero), [m for _, m, _, _ in zero.values()], yerr=sds_of(list(zero.values())),
                fmt="o--", ms=3.5, color=colour, capsize=2, lw=1, label=f"ours, {label}",
            )  # fmt: skip
    paper_zero_column(ax, "s", 4.5)
    ax.set_xscale("log")
    ax.set_xlabel("particles")
    ax.set_ylabel("speed toward the light (mm/s)")
    ax.set_title(
        "Speed against swarm size, 0 % dead (2 h, first 30 min left out; ours: seeds marked)",
        fontsize=10,
    )
    ax.axhline(0.0, color="0.6", lw=0.8, zorder=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return [save(fig, out / "speed.png")]


def rattle_panel(ax: plt.Axes, rattle_csv: Path, swept: str, xlabel: str) -> None:
    """The share of particles that rattle against the number `swept` (a column of
    research/rattle_share.py's CSV), one line per size; the panel is left blank without the CSV."""
    if not rattle_csv.is_file():
        ax.set_axis_off()
        return
    with rattle_csv.open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    for n in sorted({int(r["particles"]) for r in rows}):
        # (a share of 0, none seen, has no place on the log axis: left out)
        mine = sorted(
            (float(r[swept]), float(r["rattling_share"])) for r in rows
            if int(r["particles"]) == n and float(r["rattling_share"]) > 0
        )  # fmt: skip
        ax.semilogy([x for x, _ in mine], [100 * v for _, v in mine], "o-", ms=3.5,
                    color=COLOURS.get(n, "tab:gray"), label=f"{n:,}")  # fmt: skip
    ax.set_xlabel(xlabel)
    ax.set_ylabel("particles faster than 0.1 m/s (%)")
    ax.set_title("Rattling, minutes 5-7 of one run (research/rattle_share.py)", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, title="particles", title_fontsize=8)


SHEAR_SETS = {
    20.0: ("dead-calm-1000", "dead-calm-10000"),
    25.0: ("dead-mid", "dead-mid-1000", "dead-mid-10000"),
    27.5: ("shear27.5-small", "shear27.5-1000", "shear27.5-10000"),
    28.5: ("shear28.5-small", "shear28.5-1000", "shear28.5-10000"),
    29.0: ("shear29-small", "shear29-1000", "shear29-10000"),
    30.0: ("dead-cand-small", "dead-cand-1000", "dead-cand-10000"),
}
"""Study folders of the 0 % cells with torque limit 0.7, by shear (`--set torque_limit=0.7,
shear=S`)."""


def shear_figure(results: Path, out: Path) -> list[Path]:
    """Speed at 0 % dead against the shear (torque limit 0.7) for each size, beside Table S3's
    band, and the share of particles that rattle (research/rattle_share.py's CSV, data/studies)."""
    by_size: dict[int, list[tuple[float, float, float, int]]] = defaultdict(list)
    for shear, names in SHEAR_SETS.items():
        for n, (_, mean, sd, runs) in zero_cells(results, names).items():
            by_size[n].append((shear, mean, sd, runs))
    if not by_size:
        return []
    rattle_csv = DATA / "rattle-shear.csv"
    fig, (left, right) = plt.subplots(1, 2, figsize=(11.5, 4.6), dpi=120)
    for n, cells in sorted(by_size.items()):
        colour = COLOURS.get(n, "tab:gray")
        shears = [c[0] for c in cells]
        left.errorbar(
            shears, [c[1] for c in cells], yerr=sds_of(cells), fmt="o-", ms=3.5, color=colour,
            capsize=2, lw=1, label=f"{n:,} ({count(min(c[3] for c in cells), 'seed')} a point)",
        )  # fmt: skip
        published = paper.TABLE_S3_MM_S[n][0.0]
        left.axhspan(published.mean - published.sd, published.mean + published.sd, color=colour,
                     alpha=0.12, lw=0)  # fmt: skip
        left.axhline(published.mean, color=colour, lw=0.8, ls=":")
    left.set_xlabel("contact shear (1/s; published 40), torque limit 0.7")
    left.set_ylabel("speed toward the light (mm/s), 0 % dead")
    left.set_title("Ours (points, ± 1 sd) against Table S3 (shaded: ± 1 sd)", fontsize=10)
    left.grid(alpha=0.3)
    left.legend(fontsize=8, title="particles", title_fontsize=8)
    rattle_panel(right, rattle_csv, "shear", "contact shear (1/s), torque limit 0.7")
    fig.suptitle("Table S3's 0 % column against the contact shear (2 h, first 30 min left out)")
    return [save(fig, out / "shear.png")]


PLACEMENT_SETS = {
    ("published numbers", "our Algorithm 5"): ("dead-small", "dead-1000", "dead-10000-all"),
    ("published numbers", "the published code's"): (
        "place-pub-small", "place-pub-1000", "place-pub-10000",
    ),
    ("torque limit 0.7, shear 27.5", "our Algorithm 5"): (
        "shear27.5-small", "shear27.5-1000", "shear27.5-10000",
    ),
    ("torque limit 0.7, shear 27.5", "the published code's"): (
        "place-fit-small", "place-fit-1000", "place-fit-10000",
    ),
}  # fmt: skip
"""Study folders of the 0 % cells by (numbers, placement): `--placement blob` or
`--placement published-blob`."""


DASHPOT_SETS = {
    10.0: ("dead-1000", "dead-10000"),
    12.5: ("damp12.5-1000", "damp12.5-10000"),
    15.0: ("damp15-1000", "damp15-10000"),
    17.5: ("damp17.5-1000", "damp17.5-10000"),
    20.0: ("damp20-1000", "damp20-10000"),
}
"""Study folders of the 0 % cells at 1,000 and 10,000 particles with the published numbers but
the dashpot (`--set damping=D`; 10 is the published value)."""


def spread_factors(path: Path) -> dict[tuple[int, float], float]:
    """From research/swarm_start.py's CSV: how many times its starting rms distance from the
    centroid each swarm (particles, dashpot; published shear and torque limit) ends at."""
    if not path.is_file():
        return {}
    runs: dict[tuple[int, float], list[float]] = defaultdict(list)
    with path.open(newline="") as stream:
        for row in csv.DictReader(stream):
            if float(row["shear"]) == PhysicsParams().shear and (
                float(row["torque_limit"]) == PhysicsParams().torque_limit
            ):
                runs[(int(row["particles"]), float(row["damping"]))].append(
                    float(row["rms_radius_m"])
                )
    return {key: radii[-1] / radii[0] for key, radii in runs.items()}


def dashpot_figure(results: Path, out: Path) -> list[Path]:
    """Speed at 0 % dead against the contact dashpot at 1,000 and 10,000 particles, beside Table
    S3's bands, and the share of particles that rattle (research/rattle_share.py's CSV in
    data/studies)."""
    by_size: dict[int, list[tuple[float, float, float, int]]] = defaultdict(list)
    for damping, names in DASHPOT_SETS.items():
        for n, (_, mean, sd, runs) in zero_cells(results, names).items():
            if n in (1000, 10000):
                by_size[n].append((damping, mean, sd, runs))
    if not by_size:
        return []
    spread = spread_factors(DATA / "swarm-start.csv")
    fig, (left, right) = plt.subplots(1, 2, figsize=(11.5, 4.6), dpi=120)
    for n, cells in sorted(by_size.items()):
        colour = COLOURS.get(n, "tab:gray")
        fewest, most = min(c[3] for c in cells), max(c[3] for c in cells)
        seeds = f"{fewest}" if fewest == most else f"{fewest}-{most}"
        left.plot([c[0] for c in cells], [c[1] for c in cells], "o-", ms=4, color=colour,
                  label=f"{n:,} (seeds a point: {seeds})")  # fmt: skip
        for damping, mean, _, _ in cells:
            factor = spread.get((n, damping), 1.0)
            if factor > 2:  # the swarm blew apart in its first seconds (research/swarm_start.py)
                left.annotate(f"blown apart\n(x{factor:.0f} wider)", (damping, mean),
                              xytext=(-4, 8), textcoords="offset points", ha="right",
                              fontsize=7, color=colour)  # fmt: skip
        published = paper.TABLE_S3_MM_S[n][0.0]
        left.axhspan(published.mean - published.sd, published.mean + published.sd, color=colour,
                     alpha=0.12, lw=0)  # fmt: skip
        left.axhline(published.mean, color=colour, lw=0.8, ls=":")
    left.set_xlabel(f"contact dashpot (1/s; published {PhysicsParams().damping:g}), shear 40")
    left.set_ylabel("speed toward the light (mm/s), 0 % dead")
    left.set_title("Ours (points) against Table S3 (shaded: ± 1 sd)", fontsize=10)
    left.grid(alpha=0.3)
    left.legend(fontsize=8, title="particles", title_fontsize=8)
    rattle_panel(right, DATA / "rattle-damping.csv", "damping", "contact dashpot (1/s), shear 40")
    return [save(fig, out / "dashpot.png")]


def placement_figure(results: Path, out: Path) -> list[Path]:
    """Speed against swarm size with our Algorithm 5 and the published code's placement, beside
    Table S3's 0 % column; and how the 10,000-particle swarms pack and move over their runs
    (research/swarm_packing.py's CSV in data/studies)."""
    zero: dict[tuple[str, str], dict[int, tuple[float, float, float, int]]] = {}
    for key, names in PLACEMENT_SETS.items():
        zero[key] = zero_cells(results, names)
    if not any(zero.values()):
        return []
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(16, 4.8), dpi=120)
    colours = {"published numbers": "tab:blue", "torque limit 0.7, shear 27.5": "tab:green"}
    styles = {"our Algorithm 5": ("o", "-"), "the published code's": ("s", "--")}
    for (numbers, placement), cells in zero.items():
        if not cells:
            continue
        marker, line = styles[placement]
        left.errorbar(
            list(cells), [c[1] for c in cells.values()], yerr=sds_of(list(cells.values())),
            fmt=marker + line, ms=4, color=colours[numbers], capsize=2, lw=1,
            label=f"{numbers}, {placement} placement",
        )  # fmt: skip
    paper_zero_column(left, "D", 5)
    left.set_xscale("log")
    runs: dict[int, list[int]] = defaultdict(list)
    for cells in zero.values():
        for n, cell in cells.items():
            runs[n].append(cell[3])
    per_size = ", ".join(
        f"{min(r)}-{max(r)} at {n:,}" if min(r) < max(r) else f"{min(r)} at {n:,}"
        for n, r in sorted(runs.items())
    )
    left.set_xlabel(f"particles\n(seeds a point: {per_size})")
    left.set_ylabel("speed toward the light (mm/s), 0 % dead")
    left.set_title("Speed against size, by placement (2 h, first 30 min left out)", fontsize=10)
    left.grid(alpha=0.3)
    left.legend(fontsize=7)
    packing_csv = DATA / "packing-10000.csv"
    if packing_csv.is_file():
        with packing_csv.open(newline="") as stream:
            rows = list(csv.DictReader(stream))
        labelled: set[str] = set()
        for run in sorted({r["run"] for r in rows}):
            mine = [r for r in rows if r["run"] == run]
            first = mine[0]
            shear, torque = float(first["shear"]), float(first["torque_limit"])
            numbers = (
                "published numbers"
                if (shear, torque) == (PhysicsParams().shear, PhysicsParams().torque_limit)
                else f"torque limit {torque:g}, shear {shear:g}"
            )
            published_code = first["placement"] == "algorithm5-published"
            colour = colours.get(numbers, "tab:gray")
            line = "--" if published_code else "-"
            label = f"{numbers}, {'published code' if published_code else 'our'} placement"
            if label in labelled:
                label = "_"  # one legend entry for the seeds of a configuration
            labelled.add(label)
            minutes = [float(r["minute"]) for r in mine]
            middle.plot(minutes, [float(r["inner_packing"]) for r in mine], line, color=colour,
                        marker=".", label=label)  # fmt: skip
            right.plot(minutes[1:], [float(r["speed_mm_s_since_last"]) for r in mine[1:]], line,
                       color=colour, marker=".", label=label)  # fmt: skip
        middle.set_xlabel("minutes")
        middle.set_ylabel("packing fraction inside half the RMS radius")
        middle.set_title("10,000 particles: how densely the middle packs", fontsize=10)
        middle.grid(alpha=0.3)
        middle.legend(fontsize=7)
        right.axhline(paper.TABLE_S3_MM_S[10000][0.0].mean, color="k", lw=0.8, ls=":",
                      label="paper, minutes 30-120")  # fmt: skip
        right.axvline(30, color="0.5", lw=0.8, ls="-.", label="left out before this")
        bottom, top = right.get_ylim()
        right.set_ylim(bottom, top + 0.35 * (top - bottom))  # room above the lines for the legend
        right.set_xlabel("minutes")
        right.set_ylabel("speed toward the light over the 10 minutes before (mm/s)")
        right.set_title("10,000 particles: speed as the run goes", fontsize=10)
        right.grid(alpha=0.3)
        right.legend(fontsize=7)
    else:
        middle.set_axis_off()
        right.set_axis_off()
    fig.suptitle("Table S3's 0 % column with the published code's sparser placement")
    return [save(fig, out / "placement.png")]


def gap_figure(results: Path, out: Path) -> list[Path]:
    ours = gather(results, ("gap-10", "gap-100", "gap-1000"), "success")
    if not ours:
        return []
    fig, ax = plt.subplots(figsize=(7.5, 4.6), dpi=120)
    for n, cells in sorted(ours.items()):
        colour = COLOURS.get(n, "tab:gray")
        x = [100 * f for f, *_ in cells]
        means = [m for _, m, _, _ in cells]
        runs = min(r for *_, r in cells)
        label = f"{n:,} particles ({count(runs, 'run')})"
        band(ax, x, means, sds_of(cells), colour, label, low=0.0, high=1.0)
    ax.set_xlabel("gap (% of the densest packing diameter)")
    ax.set_ylabel("fraction of the particles through the gap")
    ax.set_ylim(-0.03, 1.03)
    ax.set_title("Fig. S18: passing a narrow gap after 4,500 cycles (mean ± 1 sd)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return [save(fig, out / "gap.png")]


def noise_figure(results: Path, out: Path) -> list[Path]:
    ours = gather(results, ("noise-100", "noise-1000", "noise-10000"), "speed_mm_s")
    if not ours:
        return []
    # A size run only with noise (10,000: one run costs half an hour) takes its noise-free speed
    # from the dead study's 0 % cell, the same world and controller.
    dead = gather(results, PUBLISHED_DEAD, "speed_mm_s")
    for n, cells in ours.items():
        if cells[0][0] != 0.0 and dead.get(n) and dead[n][0][0] == 0.0:
            cells.insert(0, dead[n][0])
    fig, ax = plt.subplots(figsize=(7.5, 4.6), dpi=120)
    for n, cells in sorted(ours.items()):
        colour = COLOURS.get(n, "tab:gray")
        base = next(m for f, m, _, _ in cells if f == 0.0)
        x = [f for f, *_ in cells]
        rel = [m / base for _, m, _, _ in cells]
        runs = min(r for *_, r in cells)
        label = f"{n:,} particles, ours ({count(runs, 'seed')})"
        band(ax, x, rel, sds_of(cells, scale=base), colour, label)
    ax.plot(
        [0.0, 1.0], [1.0, paper.FIG_S20_RELATIVE_SPEED_AT_ONE_DIAMETER], "kD", mfc="white",
        label="paper, 10,000 particles: -33 % at 1 diameter",
    )  # fmt: skip
    # The paper's point as it would sit if its error had been counted in minimum radii (an
    # error of 1 radius is 0.5 diameter): where our curves pass it (docs/studies.md, Fig. S20).
    ax.plot(
        [0.5], [paper.FIG_S20_RELATIVE_SPEED_AT_ONE_DIAMETER], "D", color="0.45", mfc="none",
        label="the paper's point read as 1 minimum radius",
    )  # fmt: skip
    right = max(f for cells in ours.values() for f, *_ in cells)
    ax.plot(
        [paper.FIG_S20_STANDSTILL_BEYOND_DIAMETERS, right], [0.0, 0.0], "k-", lw=3, alpha=0.4,
        label="paper: standstill beyond 2 diameters",
    )  # fmt: skip
    ax.axhline(0.0, color="0.6", lw=0.8, zorder=0)
    ax.set_xlabel("distance-estimation error (sd, minimum particle diameters)")
    ax.set_ylabel("speed / noise-free speed")
    ax.set_title("Fig. S20: speed against sensor noise (2 h, first 30 min left out)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return [save(fig, out / "noise.png")]


FIGURES = {
    "dead": dead_figures,
    "speed": speed_figure,
    "shear": shear_figure,
    "dashpot": dashpot_figure,
    "placement": placement_figure,
    "gap": gap_figure,
    "noise": noise_figure,
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="folder holding the study folders")
    parser.add_argument("out", type=Path, help="where the PNGs go (docs/studies)")
    parser.add_argument(
        "--figures", default=",".join(FIGURES), help=f"which (default: all): {','.join(FIGURES)}"
    )
    args = parser.parse_args()
    names = [name.strip() for name in args.figures.split(",") if name.strip()]
    unknown = [name for name in names if name not in FIGURES]
    if unknown or not names:
        print(f"studies_figures: --figures: not a figure: {', '.join(unknown) or '(none)'}"
              f" (choose from {', '.join(FIGURES)})", file=sys.stderr)  # fmt: skip
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    for name in names:
        for path in FIGURES[name](args.results, args.out):
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
