#!/usr/bin/env python3
"""Measures the world's fidelity to the paper: speed toward the light (Table S3, 0 % dead) with the
published controller, beside what each suspect of a difference changes (the published code's stale
neighbour search among them) and how the speed is measured; plots it."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numba
import numpy as np

from particlebot.protocol import Method
from particlebot.sim.particles.model.firmware import FirmwareController, FirmwareSettings
from particlebot.sim.particles.model.published import PublishedController, PublishedSettings
from particlebot.sim.scenarios.placement import algorithm5
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world.params import NeighbourSearch
from particlebot.studies.definitions import FAR_LAMP_M
from particlebot.studies.packing import densest_packing_diameter_m
from particlebot.studies.published import TABLE_S3_MM_S, speed_to_percent_diameter_per_cycle

R_MIN = PhysicsParams().r_min
SAMPLE_S = 60.0
"""The centroid's distance to the light is sampled this often (the published CSV's interval)."""
STALE = NeighbourSearch.PUBLISHED_STALE_GRID


@dataclass(frozen=True)
class Variant:
    """One way of running the published model: our defaults, or one suspect changed."""

    name: str
    physics: dict[str, Any] = field(default_factory=dict)
    controller: dict[str, Any] = field(default_factory=dict)
    placement: str = "algorithm5"
    """'algorithm5' (SI Algorithm 5) or 'published-code' (what the published code does)."""
    lamp_dpd: float | None = None
    """The lamp this many DPD from the first particle (the published main: 3.5); None: 20 m
    beyond the densest-packing edge, as the studies put it, so that no swarm reaches it."""
    precision: str = "float64"


VARIANTS = [
    Variant("ours (published defaults)"),
    Variant("magnets uncut (0.6 m, the published reach)", physics={"magnet_cutoff": 0.6}),
    Variant("magnets cut at 5 cm", physics={"magnet_cutoff": 0.05}),
    Variant("attraction 1x (fitted A)", physics={"attraction": 1.5884e-5}),
    Variant("static friction 1x mu g", physics={"static_factor": 1.0}),
    Variant("no phase noise", controller={"phase_noise": 0.0}),
    Variant("shear 20 (does not boil)", physics={"shear": 20.0}),
    Variant("float32", precision="float32"),
    Variant("the published code's placement", placement="published-code"),
    Variant("lamp at 3.5 DPD (published main)", lamp_dpd=3.5),
    Variant("published stale grid (magnets cut at 1 cm)", physics={"neighbour_search": STALE}),
    Variant(
        "published stale grid, magnets uncut (the published search)",
        physics={"neighbour_search": STALE, "magnet_cutoff": 1.0},
    ),
    Variant(
        "published search, code's placement, lamp 16/8 DPD",
        physics={"neighbour_search": STALE, "magnet_cutoff": 1.0},
        placement="published-code",
        lamp_dpd=-1.0,
    ),
    Variant(
        "published search, re-listed every 30 min (staler)",
        physics={"neighbour_search": STALE, "magnet_cutoff": 1.0, "sort_interval": 1800.0},
    ),
    Variant(
        "static friction 1x mu g and no phase noise",
        physics={"static_factor": 1.0},
        controller={"phase_noise": 0.0},
    ),
    *(
        Variant(f"attraction {times}x (fitted A)", physics={"attraction": times * 1.5884e-5})
        for times in (2, 4, 6)
    ),
]
SENSITIVITY = [
    Variant("published defaults"),
    *(Variant(f"torque limit {c:g} (0.5)", physics={"torque_limit": c}) for c in (0.4, 0.6, 0.8)),
    *(Variant(f"servo max speed {v:g} (0.1)", physics={"max_speed": v}) for v in (0.05, 0.2)),
    *(Variant(f"mu {m:g} (0.4)", physics={"mu": m}) for m in (0.3, 0.5)),
    Variant("static friction 1.5 mu g (2)", physics={"static_factor": 1.5}),
    Variant("static friction 1 mu g (2)", physics={"static_factor": 1.0}),
    *(Variant(f"spring {k:g} (1000)", physics={"spring": k}) for k in (500.0, 2000.0)),
    *(Variant(f"damping {d:g} (10)", physics={"damping": d}) for d in (5.0, 20.0)),
    *(Variant(f"shear {s:g} (40)", physics={"shear": s}) for s in (20.0, 30.0, 50.0)),
    *(
        Variant(f"magnet clamp {f:g} N (2.5)", physics={"magnet_clamp_force": f})
        for f in (2.0, 3.0)
    ),
    *(
        Variant(f"attraction {times}x fitted (3x)", physics={"attraction": times * 1.5884e-5})
        for times in (2, 4)
    ),
    Variant("dt 0.005 s (0.01)", physics={"dt": 0.005}),
    *(Variant(f"phase noise {n:g} rise (0.3)", controller={"phase_noise": n}) for n in (0.0, 0.15)),
    *(Variant(f"rise {r:g} s (2)", controller={"rise_s": r}) for r in (1.5, 3.0)),
    *(Variant(f"Nx {nx} (5)", controller={"nx": nx}) for nx in (4, 6)),
    Variant("phase updated every 10 cycles (1)", controller={"update_cycles": 10}),
    Variant("constrained contraction (off)", physics={"constrain_contraction": True}),
    Variant("+ torque limit 0.7, shear 30", physics={"torque_limit": 0.7, "shear": 30.0}),
    Variant("+ torque limit 0.8, shear 30", physics={"torque_limit": 0.8, "shear": 30.0}),
    Variant("+ torque limit 0.7, damping 5", physics={"torque_limit": 0.7, "damping": 5.0}),
    Variant("+ torque limit 0.8, dt 0.005 s", physics={"torque_limit": 0.8, "dt": 0.005}),
    Variant(
        "+ torque limit 0.65, shear 30, no phase noise",
        physics={"torque_limit": 0.65, "shear": 30.0},
        controller={"phase_noise": 0.0},
    ),
]
"""One published number at a time, below and above its value (in brackets), then pairs of the
numbers that move the two sizes apart ("+"): how each moves the speeds of 10 and 100 particles
(`--sensitivity`)."""


LIGHT_FACT = {11: 16.0, 101: 8.0, 1001: 4.0, 10001: 2.0}
"""The published main's lamp distance in DPD by swarm size (up to the key): lamp_dpd -1."""


def published_code_placement(count: int, rng: np.random.Generator) -> np.ndarray:
    """What the published code's CONFIG_RANDOM does (facts from its source, our code): tangent
    to a random placed disc in a random direction (drawn again while it overlaps), then turned
    about that disc in 10 degree steps until the next step would overlap; the third disc at the
    first two's midpoint plus R_min sideways (so it overlaps both by 0.59 R_min)."""
    placed = [np.zeros(2)]
    step = math.radians(10.0)
    for i in range(1, count):
        xy = np.array(placed)
        if i == 2:
            d = (xy[1] - xy[0]) / np.linalg.norm(xy[1] - xy[0])
            side = np.array([d[1], -d[0]]) if rng.integers(2) else np.array([-d[1], d[0]])
            placed.append((xy[0] + xy[1]) / 2 + side * R_MIN)
            continue
        while True:
            anchor = xy[rng.integers(i)]
            theta = rng.uniform(0.0, 2 * math.pi)

            def at(angle: float, anchor: np.ndarray = anchor) -> np.ndarray:
                return anchor + 2 * R_MIN * np.array([math.cos(angle), math.sin(angle)])

            def blocked(p: np.ndarray, xy: np.ndarray = xy) -> bool:
                return bool((np.hypot(*(xy - p).T) < 2 * R_MIN - 1e-12).any())

            if blocked(at(theta)):
                continue
            turned = theta
            while turned - theta < 2 * math.pi and not blocked(at(turned + step)):
                turned += step
            placed.append(at(turned))
            break
    return np.array(placed)


def lamp_dpd(variant: Variant, count: int) -> float | None:
    """The variant's lamp distance in DPD for this size (-1: the published main's table)."""
    if variant.lamp_dpd is not None and variant.lamp_dpd < 0:
        return next(f for most, f in sorted(LIGHT_FACT.items()) if count <= most)
    return variant.lamp_dpd


def speed_run(variant: Variant, count: int, seed: int, duration: float) -> np.ndarray:
    """The centroid's distance to the light (m) every SAMPLE_S from 0 to `duration` of one run."""
    rng = np.random.default_rng(seed)
    if variant.placement == "published-code":
        xy = published_code_placement(count, rng)
    else:
        xy = algorithm5(count, R_MIN, rng).xy
    dpd = densest_packing_diameter_m(count)
    factor = lamp_dpd(variant, count)
    lamp_x = -(factor * dpd if factor is not None else dpd / 2 + FAR_LAMP_M)
    world = World(
        xy[:, 0], xy[:, 1],
        controller=PublishedController(PublishedSettings(**variant.controller)),
        params=PhysicsParams(**variant.physics), lamp=Lamp(lamp_x, 0.0), seed=seed,
        precision=variant.precision,  # type: ignore[arg-type]
    )  # fmt: skip
    track = [world.light_distance()]
    for _ in range(round(duration / SAMPLE_S)):
        world.run(SAMPLE_S)
        track.append(world.light_distance())
    return np.array(track)


MEASURES = ("ends, skip-end", "fit, skip-end", "ends, 0-end", "ends, 0-skip")
"""Ways of turning a distance track into a speed (mm/s): the change between two samples over
the time between them (from `skip` to the end: ours and the SI's words; the whole run; only
the part left out), or the slope of a least-squares line through the samples from skip on."""


def speeds(track: np.ndarray, skip: float) -> dict[str, float]:
    """Every measure of MEASURES for one track (toward the light is positive)."""
    first = round(skip / SAMPLE_S)
    t = np.arange(track.size) * SAMPLE_S
    end = t[-1]
    slope = np.polyfit(t[first:], track[first:], 1)[0]
    return {
        MEASURES[0]: (track[first] - track[-1]) / (end - skip) * 1000.0,
        MEASURES[1]: -slope * 1000.0,
        MEASURES[2]: (track[0] - track[-1]) / end * 1000.0,
        MEASURES[3]: (track[0] - track[first]) / skip * 1000.0 if skip > 0 else math.nan,
    }


def firmware_line(seconds: float) -> dict[str, float]:
    """A line of 5 particles 1 m from the lamp's foot, run by the firmware controller (each
    method): how far its centroid came toward the lamp."""
    moved = {}
    for method in Method:
        x = 1.0 + np.arange(5) * (2 * R_MIN + 0.5e-3)
        controller = FirmwareController(FirmwareSettings(method=method, update_interval_s=60))
        world = World(x, np.zeros(5), controller=controller, lamp=Lamp(0.0, 0.0), seed=1)
        start = world.light_distance()
        world.run(seconds)
        moved[method.name] = (start - world.light_distance()) * 1000.0
    return moved


def boiling(path: Path, count: int = 3000) -> dict[str, dict[str, float]]:
    """Particle speeds in an actuating Algorithm-5 blob: the published contact model at its
    dt = 0.01 s, with half the shear, and at half the time step; their distributions plotted."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases: list[tuple[str, dict[str, Any]]] = [
        ("published: shear 40, dt 0.01 s", {}),
        ("shear 20, dt 0.01 s", {"shear": 20.0}),
        ("shear 40, dt 0.005 s", {"dt": 0.005}),
    ]
    xy = algorithm5(count, R_MIN, np.random.default_rng(1)).xy
    figures: dict[str, dict[str, float]] = {}
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    for label, physics in cases:
        world = World(xy[:, 0], xy[:, 1], controller=PublishedController(),
                      params=PhysicsParams(**physics), lamp=Lamp(-30.0, 0.0), seed=1)  # fmt: skip
        world.run(60.0)
        speeds = []
        for _ in range(20):
            world.run(0.5)
            state = world.state()
            speeds.append(np.hypot(state.vx, state.vy))
        v = np.sort(np.concatenate(speeds))
        figures[label] = {
            "mean_m_s": float(v.mean()),
            "p99_m_s": float(np.quantile(v, 0.99)),
            "faster_than_0.1_m_s": float(np.mean(v > 0.1)),
        }
        share = 1.0 - np.arange(v.size) / v.size
        ax.loglog(np.maximum(v, 1e-5), share, label=label)
    ax.axvline(0.0222, color="grey", ls=":", lw=1)
    ax.text(0.0222, 2e-4, " mu g dt: what sliding\n friction takes in a step", fontsize=8)
    ax.set_xlabel("particle speed (m/s), 3,000 particles, samples over 10 s after 60 s")
    ax.set_ylabel("share of particles faster")
    ax.set_xlim(1e-5, 10)
    ax.set_ylim(1e-4, 1.1)
    ax.legend(fontsize=8)
    ax.set_title("The published contact model boils in a blob at dt = 0.01 s")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return figures


def plot(results: dict[str, dict[int, list[float]]], path: Path) -> None:
    """Per size: every variant's speeds (dots, mean +- sd) beside the paper's band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sizes = sorted({n for per in results.values() for n in per})
    fig, axes = plt.subplots(1, len(sizes), figsize=(6.5 * len(sizes), 5.2), sharey=True)
    names = list(results)
    for ax, n in zip(np.atleast_1d(axes), sizes, strict=True):
        paper = TABLE_S3_MM_S[n][0.0]
        ax.axvspan(paper.mean - paper.sd, paper.mean + paper.sd, color="gold", alpha=0.35)
        ax.axvline(paper.mean, color="goldenrod")
        for row, name in enumerate(names):
            speeds = np.array(results[name].get(n, []))
            if speeds.size == 0:
                continue
            y = len(names) - 1 - row
            ax.plot(speeds, np.full(speeds.size, y) + np.linspace(-0.15, 0.15, speeds.size), "o",
                    ms=3, color="tab:blue", alpha=0.6)  # fmt: skip
            ax.errorbar(speeds.mean(), y, xerr=speeds.std(ddof=1), fmt="D", color="black",
                        ms=5, capsize=3)  # fmt: skip
        ax.set_yticks(range(len(names)), names[::-1])
        ax.axvline(0.0, color="grey", lw=0.8)
        ax.set_xlabel("speed toward the light, 30 min - 2 h (mm/s)")
        seeds = len(results[names[0]].get(n, []))
        ax.set_title(f"{n} particles, 0 % dead, {seeds} seeds\n"
                     f"gold: the paper's {paper.mean:.2f} ± {paper.sd:.2f} mm/s")  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_sensitivity(results: dict[str, dict[int, list[float]]], path: Path) -> None:
    """Left: each variant's mean speed with 10 particles (x) against 100 (y), beside the paper's
    pair. Right: each variant's speeds as multiples of the defaults', beside the multiples the
    paper's numbers would need; rows sorted by the 100-particle multiple."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    small, large = 10, 100
    paper = {n: TABLE_S3_MM_S[n][0.0] for n in (small, large)}
    colours = {small: "tab:blue", large: "tab:orange"}
    names = list(results)
    mean = {name: {n: float(np.mean(results[name][n])) for n in (small, large)} for name in names}
    sem = {
        name: {n: float(np.std(results[name][n], ddof=1) / np.sqrt(len(results[name][n])))
               for n in (small, large)}
        for name in names
    }  # fmt: skip
    base = mean[names[0]]
    fig, (ax, bars) = plt.subplots(1, 2, figsize=(16, 8.2), width_ratios=(1, 1.1))
    ax.add_patch(plt.Rectangle(
        (paper[small].mean - paper[small].sd, paper[large].mean - paper[large].sd),
        2 * paper[small].sd, 2 * paper[large].sd, color="gold", alpha=0.35, lw=0,
    ))  # fmt: skip
    ax.plot(paper[small].mean, paper[large].mean, "*", ms=16, color="goldenrod",
            label="Table S3 (mean; box: ±1 sd)")  # fmt: skip
    top = 1.05 * max([1.8] + [m[n] for m in mean.values() for n in (small, large)])
    ax.plot([0, top], [0, top], color="grey", lw=0.8, ls="--", label="as fast at 100 as at 10")
    ratio = paper[large].mean / paper[small].mean
    ax.plot([0, top], [0, top * ratio], color="goldenrod", lw=0.8, ls=":",
            label=f"the paper's ratio, 100 / 10 = {ratio:.2f}")  # fmt: skip
    # Pairs ("+") are drawn apart and lettered: they crowd the paper's box.
    letters = iter("ABCDEFGHIJKLMNOPQRSTUVWXYZ")
    shown = {
        name: f"{next(letters)}: {name[2:]}" if name.startswith("+") else name for name in names
    }
    for name in names:
        x, y = mean[name][small], mean[name][large]
        default, pair = name == names[0], name.startswith("+")
        ax.errorbar(x, y, xerr=sem[name][small], yerr=sem[name][large],
                    fmt="D" if pair else "o", color="black" if default else
                    ("tab:red" if pair else "tab:blue"), ms=6 if default or pair else 4,
                    elinewidth=0.8, zorder=3)  # fmt: skip
        far = abs(x - base[small]) > 0.12 or abs(y - base[large]) > 0.12
        if pair:
            ax.annotate(shown[name][0], (x, y), xytext=(5, -9), textcoords="offset points",
                        fontsize=9, color="tab:red", fontweight="bold")  # fmt: skip
        elif default or far:
            ax.annotate(name, (x, y), xytext=(5, 3), textcoords="offset points", fontsize=7.5,
                        fontweight="bold" if default else "normal")  # fmt: skip
    ax.set_xlim(-0.05, top)
    ax.set_ylim(-0.05, top)
    ax.set_aspect("equal")
    ax.set_xlabel(f"speed toward the light, {small} particles (mm/s)")
    ax.set_ylabel(f"speed toward the light, {large} particles (mm/s)")
    ax.set_title(
        "Blue: one published number changed (named when it moved a speed by more\n"
        "than 0.12 mm/s; all on the right); red: pairs, lettered; bars: standard error"
    )
    ax.legend(loc="upper left", fontsize=8)

    singles = [name for name in names[1:] if not name.startswith("+")]
    pairs = [name for name in names[1:] if name.startswith("+")]
    rows = sorted(singles, key=lambda name: mean[name][large] / base[large]) + pairs[::-1]
    row_y = np.arange(len(rows))
    for offset, n in ((-0.2, small), (0.2, large)):
        multiple = [mean[name][n] / base[n] for name in rows]
        error = [sem[name][n] / base[n] for name in rows]
        bars.barh(row_y + offset, multiple, height=0.4, xerr=error, color=colours[n], alpha=0.8,
                  error_kw={"elinewidth": 0.6}, label=f"{n} particles")  # fmt: skip
        needed = paper[n].mean / base[n]
        bars.axvline(needed, color=colours[n], ls="--", lw=1.2,
                     label=f"the paper's {n}: x{needed:.2f} ours")  # fmt: skip
    bars.axvline(1.0, color="black", lw=0.8)
    bars.set_yticks(row_y, [shown[name] for name in rows], fontsize=8)
    for label, name in zip(bars.get_yticklabels(), rows, strict=True):
        label.set_color("tab:red" if name.startswith("+") else "black")
    if pairs:
        bars.axhline(len(singles) - 0.5, color="grey", lw=0.8)
    bars.set_xlabel("speed as a multiple of ours with the published defaults")
    bars.set_title(f"Defaults: {base[small]:.2f} mm/s (10 particles), {base[large]:.2f} (100)")
    bars.legend(loc="lower right", fontsize=8)
    seeds = len(results[names[0]][small])
    fig.suptitle(f"Which published number could explain Table S3? 0 % dead, {seeds} seeds per "
                 "point, 2 h, the first 30 min left out")  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100])
    parser.add_argument("--seeds", type=int, default=11)
    parser.add_argument("--duration", type=float, default=7200.0, help="simulated s")
    parser.add_argument("--skip", type=float, default=1800.0, help="left out at the start (s)")
    parser.add_argument("--variants", type=int, nargs="*", help="indices into the list (all)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", type=Path, default=Path("docs/world"), help="figure and JSON")
    parser.add_argument("--speeds-only", action="store_true",
                        help="no firmware line, no boiling figure (they take minutes)")  # fmt: skip
    parser.add_argument("--sensitivity", action="store_true",
                        help="run SENSITIVITY (one number changed at a time) at 10 and 100 "
                        "particles instead; writes sensitivity.json and .png")  # fmt: skip
    parser.add_argument("--replot", action="store_true",
                        help="with --sensitivity: redraw the figure from --out's JSON")  # fmt: skip
    args = parser.parse_args()
    if not 0 <= args.skip < args.duration or args.seeds < 2:
        parser.error("need 0 <= --skip < --duration and at least 2 seeds")
    if args.duration % SAMPLE_S or args.skip % SAMPLE_S:
        parser.error(f"--duration and --skip must be multiples of {SAMPLE_S:g} s")
    if args.replot:
        if not args.sensitivity:
            parser.error("--replot redraws the --sensitivity figure; give both")
        if not (args.out / "sensitivity.json").is_file():
            parser.error(f"--replot: no sensitivity.json in {args.out}")
        stored = json.loads((args.out / "sensitivity.json").read_text())["speeds_mm_s"]
        runs = {name: {int(n): v for n, v in per.items()} for name, per in stored.items()}
        plot_sensitivity(runs, args.out / "sensitivity.png")
        print(f"redrew sensitivity.png in {args.out}")
        return 0
    if args.sensitivity:
        args.sizes, args.speeds_only = [10, 100], True
    table = SENSITIVITY if args.sensitivity else VARIANTS
    if args.variants and not all(0 <= i < len(table) for i in args.variants):
        parser.error(f"--variants are indices 0 to {len(table) - 1}")
    chosen = [table[i] for i in args.variants] if args.variants else table
    jobs = [(v, n, s) for n in args.sizes for v in chosen for s in range(args.seeds)]
    print(f"{len(jobs)} runs on {args.workers} processes; load {os.getloadavg()[0]:.1f}")
    began = time.perf_counter()
    results: dict[str, dict[int, list[float]]] = {v.name: {} for v in chosen}
    measured: dict[str, dict[int, dict[str, list[float]]]] = {v.name: {} for v in chosen}
    # One numba thread per process: a process per core, each with a thread per core, makes
    # swarms of 2,048 particles and more wait on each other's threads (docs/studies.md).
    with ProcessPoolExecutor(
        args.workers, initializer=numba.set_num_threads, initargs=(1,)
    ) as pool:
        futures = [pool.submit(speed_run, v, n, s, args.duration) for v, n, s in jobs]
        for done, ((v, n, _), future) in enumerate(zip(jobs, futures, strict=True), start=1):
            by_measure = speeds(future.result(), args.skip)
            results[v.name].setdefault(n, []).append(by_measure[MEASURES[0]])
            for name, value in by_measure.items():
                measured[v.name].setdefault(n, {}).setdefault(name, []).append(value)
            print(f"\r{done}/{len(jobs)} runs, {time.perf_counter() - began:.0f} s", end="",
                  file=sys.stderr, flush=True)  # fmt: skip
    print(file=sys.stderr)
    for n in args.sizes:
        paper = TABLE_S3_MM_S[n][0.0]
        print(f"\n{n} particles (paper {paper.mean:.2f} ± {paper.sd:.2f} mm/s)")
        print(f"  {'':<58} " + "  ".join(f"{m:>15}" for m in MEASURES))
        for v in chosen:
            s = np.array(results[v.name][n])
            inside = "in" if abs(s.mean() - paper.mean) <= paper.sd else "out"
            cells = "  ".join(
                f"{np.mean(x):6.3f} ± {np.std(x, ddof=1):5.3f}"
                for x in measured[v.name][n].values()
            )
            percent = speed_to_percent_diameter_per_cycle(float(s.mean()))
            print(f"  {v.name:<58} {cells}  ({inside}; {percent:.2f} %Dmin/cycle)")
    (args.out).mkdir(parents=True, exist_ok=True)
    summary = {"duration_s": args.duration, "skip_s": args.skip, "speeds_mm_s": results,
               "measures_mm_s": measured, "load": os.getloadavg()[0]}  # fmt: skip
    if args.sensitivity:
        stored = args.out / "sensitivity.json"
        if args.variants and stored.is_file():  # a few rerun or added: merged into the rest
            earlier = json.loads(stored.read_text())
            order = [v.name for v in SENSITIVITY]
            for key in ("speeds_mm_s", "measures_mm_s"):
                merged = {**earlier[key], **summary[key]}
                summary[key] = {name: merged[name] for name in order if name in merged}
        if SENSITIVITY[0].name not in summary["speeds_mm_s"]:
            parser.error("the figure compares with the defaults: run --variants 0 too")
        stored.write_text(json.dumps(summary, indent=1))
        results = {name: {int(n): v for n, v in per.items()}
                   for name, per in summary["speeds_mm_s"].items()}  # fmt: skip
        plot_sensitivity(results, args.out / "sensitivity.png")
        print(f"wrote sensitivity.json and sensitivity.png into {args.out}")
        return 0
    if args.speeds_only:
        (args.out / "fidelity.json").write_text(json.dumps(summary, indent=1))
        plot(results, args.out / "fidelity.png")
        print(f"wrote fidelity.json and fidelity.png into {args.out}")
        return 0
    line = firmware_line(300.0)
    print("\nfirmware controller, line of 5, 5 min: " +
          ", ".join(f"{m} {mm:.0f} mm" for m, mm in line.items()) + " toward the lamp")  # fmt: skip
    (args.out / "fidelity.json").write_text(
        json.dumps({**summary, "firmware_line_mm": line}, indent=1)
    )
    plot(results, args.out / "fidelity.png")
    boil = boiling(args.out / "boiling.png")
    for label, figures in boil.items():
        print(f"{label}: " + ", ".join(f"{k} {v:.3g}" for k, v in figures.items()))
    print(f"wrote fidelity.json, fidelity.png and boiling.png into {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
