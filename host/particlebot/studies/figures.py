"""A study's plot in the paper's form: mean per swarm size with a shaded +-1 sd band."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np

from particlebot.studies import published as paper
from particlebot.studies.definitions import Study
from particlebot.studies.published import Published
from particlebot.studies.report import CellStats


def plot_study(study: Study, stats: Sequence[CellStats], path: Path, note: str = "") -> Path:
    """The headline metric against the sweep (against N where there is none), one line per swarm
    size with its ±1 sd band; the paper's published values as points with error bars in the same
    colour (Table S3 and S4 studies), or its stated findings (Fig. S20). A reading of the
    headline (the speed through the paper's camera) is a dashed line in its size's colour."""
    cells = [c for c in stats if c.metric == study.metric.key and c.values]
    readings = {m.key for m in study.metrics if m.derived_from == study.metric.key}
    read = [c for c in stats if c.metric in readings and c.values]
    fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=120)
    published = study.tables[0].values
    if study.sweep is None:
        _against_size(ax, cells, published, read)
    else:
        _against_sweep(ax, study, cells, read)
    ax.axhline(0.0, color="0.6", linewidth=0.8, zorder=0)
    ax.set_ylabel(study.metric.label)
    ax.set_title(f"{study.title} ({study.source})" + (f"\n{note}" if note else ""), fontsize=10)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _band(ax: plt.Axes, x: np.ndarray, means: np.ndarray, sds: np.ndarray, label: str) -> str:
    (line,) = ax.plot(x, means, marker="o", markersize=3.5, label=label)
    ax.fill_between(x, means - sds, means + sds, color=line.get_color(), alpha=0.2, linewidth=0)
    return str(matplotlib.colors.to_hex(line.get_color()))


def _paper_points(
    ax: plt.Axes, points: list[tuple[float, Published]], colour: str, label: str | None
) -> None:
    if not points:
        return
    ax.errorbar(
        [x for x, _ in points],
        [p.mean for _, p in points],
        yerr=[p.sd for _, p in points],
        fmt="s",
        markersize=4.5,
        markerfacecolor="white",
        color=colour,
        capsize=3,
        linewidth=1,
        label=label,
    )


def _reading(
    ax: plt.Axes, x: np.ndarray, row: Sequence[CellStats], colour: str, label: str | None
) -> None:
    """A derived reading of the headline (its cells in the same order as x), dashed."""
    if len(row) == len(x):
        ax.plot(x, [c.mean for c in row], linestyle="--", color=colour, label=label)


def _against_sweep(
    ax: plt.Axes, study: Study, cells: Sequence[CellStats], read: Sequence[CellStats] = ()
) -> None:
    sweep = study.sweep
    assert sweep is not None
    table = study.tables[0].values
    ran = {c.value for c in cells}
    sizes = sorted({c.particles for c in cells})
    span = (max(ran) - min(ran)) * sweep.scale if ran else 0.0
    for index, n in enumerate(sizes):
        row = sorted((c for c in cells if c.particles == n), key=lambda c: c.value)
        x = np.array([c.value * sweep.scale for c in row])
        means = np.array([c.mean for c in row])
        sds = np.nan_to_num(np.array([c.sd for c in row]))
        colour = _band(ax, x, means, sds, f"{n:,} particles")
        mine = sorted((c for c in read if c.particles == n), key=lambda c: c.value)
        _reading(ax, x, mine, colour, f"{n:,}, through the paper's camera" if mine else None)
        # The paper's points where we ran, nudged sideways per size so bars do not hide bands.
        nudge = (index - (len(sizes) - 1) / 2) * 0.012 * span
        points = sorted(
            (v * sweep.scale + nudge, p) for (m, v), p in table.items() if m == n and v in ran
        )
        _paper_points(ax, points, colour, f"{n:,}, paper" if points else None)
        if study.name == "noise":
            _noise_findings(ax, row, colour, labelled=index == 0)
    ax.set_xlabel(sweep.label)


def _noise_findings(ax: plt.Axes, row: Sequence[CellStats], colour: str, labelled: bool) -> None:
    """Fig. S20's two statements drawn against our noise-free speed: -33 % at one diameter, and
    a standstill beyond two."""
    base = next((c for c in row if c.value == 0.0), None)
    if base is None:
        return
    ax.plot(
        [1.0],
        [base.mean * paper.FIG_S20_RELATIVE_SPEED_AT_ONE_DIAMETER],
        marker="D",
        markerfacecolor="none",
        color=colour,
        linestyle="none",
        label="paper: -33 % at 1 diameter" if labelled else None,
    )
    right = max(c.value for c in row)
    if right > paper.FIG_S20_STANDSTILL_BEYOND_DIAMETERS:
        ax.plot(
            [paper.FIG_S20_STANDSTILL_BEYOND_DIAMETERS, right],
            [0.0, 0.0],
            color=colour,
            linewidth=3,
            alpha=0.5,
            label="paper: standstill beyond 2" if labelled else None,
        )


def _against_size(
    ax: plt.Axes,
    cells: Sequence[CellStats],
    published: Mapping[tuple[int, float], Published],
    read: Sequence[CellStats] = (),
) -> None:
    row = sorted(cells, key=lambda c: c.particles)
    x = np.array([float(c.particles) for c in row])
    colour = _band(
        ax,
        x,
        np.array([c.mean for c in row]),
        np.nan_to_num(np.array([c.sd for c in row])),
        "ours",
    )
    mine = sorted(read, key=lambda c: c.particles)
    _reading(ax, x, mine, colour, "ours through the paper's camera" if mine else None)
    ran = {c.particles for c in cells}
    points = sorted((float(n), p) for (n, _), p in published.items() if n in ran)
    _paper_points(ax, points, colour, "paper")
    ax.set_xscale("log")
    ax.set_xlabel("particles")
