"""A study's results as numbers to compare: per-cell mean +- sd, CSV, Markdown beside the paper."""

from __future__ import annotations

import csv
import io
import itertools
import math
from collections import defaultdict
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from particlebot.studies import published as paper
from particlebot.studies.definitions import PublishedTable, Study, StudyOptions
from particlebot.studies.packing import densest_packing_diameters
from particlebot.studies.published import Published
from particlebot.studies.spec import CellValue, RunRecord, RunSpec

PRINTED_RESOLUTION = 0.005
"""The paper prints two decimals: a published sd of 0.00 means "below 0.005", so a band is never
narrower than this either side of the mean."""


@dataclass(frozen=True)
class CellStats:
    """One metric over the seeds of one cell."""

    particles: int
    value: float
    """The sweep's value (0.0 for a study without a sweep)."""
    metric: str
    planned: int
    """Runs the study asks for in this cell."""
    values: tuple[float, ...]
    """The finished runs' values, in seed order."""

    @property
    def runs(self) -> int:
        return len(self.values)

    @property
    def mean(self) -> float:
        return float(np.mean(self.values)) if self.values else math.nan

    @property
    def sd(self) -> float:
        """Sample standard deviation over seeds (ddof = 1), as papers report spreads of runs."""
        return float(np.std(self.values, ddof=1)) if len(self.values) > 1 else math.nan


def cell_value(study: Study, cell: Mapping[str, CellValue]) -> float:
    if study.sweep is None:
        return 0.0
    return float(cell[study.sweep.key])


def collect(
    study: Study, specs: Sequence[RunSpec], records: dict[str, RunRecord]
) -> list[CellStats]:
    """Per-cell statistics of every metric, over the runs of `specs` that have finished (cells
    with none finished are kept, empty, so a report shows what is missing)."""
    planned: dict[tuple[int, float], int] = defaultdict(int)
    values: dict[tuple[int, float, str], list[tuple[int, float]]] = defaultdict(list)
    for spec in specs:
        cell = (int(spec.cell_dict["particles"]), cell_value(study, spec.cell_dict))
        planned[cell] += 1
        record = records.get(spec.run_id)
        if record is None:
            continue
        for metric in study.metrics:
            if metric.key in record.metrics:
                values[(*cell, metric.key)].append((spec.seed, record.metrics[metric.key]))
            elif metric.derived_from in record.metrics and metric.factor is not None:
                value = record.metrics[metric.derived_from] * metric.factor(cell[0])
                values[(*cell, metric.key)].append((spec.seed, value))
    stats = []
    for (n, value), count in planned.items():
        for metric in study.metrics:
            seeded = sorted(values.get((n, value, metric.key), []))
            stats.append(CellStats(n, value, metric.key, count, tuple(v for _, v in seeded)))
    return stats


def within_band(ours: float, published: Published) -> bool:
    """Our mean inside the paper's mean +- one sd (at least the printed resolution)."""
    return abs(ours - published.mean) <= max(published.sd, PRINTED_RESOLUTION) + 1e-12


def csv_text(study: Study, stats: Iterable[CellStats]) -> str:
    """Long form, one row per cell and metric, with the paper's value for the headline metric."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    sweep = study.sweep.key if study.sweep is not None else None
    # The paper's value beside each metric a table shows (the headline's: the first table's).
    published: dict[str, Mapping[tuple[int, float], Published]] = {}
    for table in study.tables:
        published.setdefault(table.metric or study.metric.key, table.values)
    writer.writerow(
        [
            "particles",
            *([sweep] if sweep else []),
            *("metric", "runs", "planned", "mean", "sd"),
            *("paper_mean", "paper_sd", "within_paper_band"),
        ]
    )
    for cell in stats:
        ref = published.get(cell.metric, {}).get((cell.particles, cell.value))
        band = "" if ref is None or not cell.values else str(within_band(cell.mean, ref)).lower()
        writer.writerow(
            [
                cell.particles,
                *([f"{cell.value:g}"] if sweep else []),
                *(cell.metric, cell.runs, cell.planned, _num(cell.mean), _num(cell.sd)),
                *(_num(ref.mean) if ref else "", _num(ref.sd) if ref else "", band),
            ]
        )
    return out.getvalue()


def _num(value: float) -> str:
    return "" if math.isnan(value) else f"{value:.6g}"


def markdown(
    study: Study,
    options: StudyOptions,
    stats: Sequence[CellStats],
    failed: dict[str, str],
    runner: str,
) -> str:
    """The study's report: what was run, each table with the paper beside ours, the paper's
    finding and what ours says about it, the DPDs used (gap and carry), and any failures."""
    headline = [cell for cell in stats if cell.metric == study.metric.key]
    planned = sum(cell.planned for cell in headline)
    finished = sum(cell.runs for cell in headline)
    lines = [
        f"# {study.title} ({study.source})",
        "",
        f"{finished} of {planned} runs finished"
        + (f" by the {runner}" if runner != "simulator" else "")
        + f"; {_seeds_text(options.first_seed, options.seeds)}, "
        + f"{options.duration_s:g} s simulated"
        + (f", the first {options.skip_s:g} s left out" if study.uses_skip else "")
        + f", placement {options.placement}"
        + (" (quick preset)" if options.quick else "")
        + (
            "; published numbers changed: "
            + ", ".join(f"{name} = {value:g}" for name, value in options.overrides)
            if options.overrides
            else ""
        )
        + ".",
        "",
    ]
    for table in study.tables:
        shown = table.metric or study.metric.key
        lines += _table(study, table, [cell for cell in stats if cell.metric == shown])
    lines += ["## Finding", "", f"Paper: {study.finding}.", ""]
    lines += [f"Ours: {line}" for line in FINDINGS.get(study.name, _no_finding)(study, stats)]
    lines.append("")
    if study.name in ("gap", "carry", "annex"):
        lines += dpd_table(options.sizes)
    if failed:
        lines += ["## Failed runs (rerun the study to retry them)", ""]
        lines += [f"- `{run_id}`: {error}" for run_id, error in sorted(failed.items())]
        lines.append("")
    return "\n".join(lines)


def _table(study: Study, table: PublishedTable, headline: Sequence[CellStats]) -> list[str]:
    sizes = sorted({cell.particles for cell in headline})
    columns = sorted({cell.value for cell in headline})
    by_cell = {(cell.particles, cell.value): cell for cell in headline}
    has_paper = any(key in table.values for key in by_cell)
    label = next((m.label for m in study.metrics if m.key == table.metric), study.metric.label)
    lines = [f"## {table.title}: {label.split(' (')[0]} ({table.unit})", ""]
    if study.sweep is not None:
        lines += [f"Columns: {study.sweep.label}.", ""]
    if has_paper:
        lines += [
            "Ours: mean ± sd over seeds; ✓ where our mean lies within the paper's ±1 sd "
            f"(at least ±{PRINTED_RESOLUTION}, its printed resolution), ✗ where not; [k/n] where "
            "only k of the n runs have finished.",
            "",
        ]
    header = ["particles", ""] if has_paper else ["particles"]
    header += [study.sweep.column(v) if study.sweep else "speed" for v in columns]
    lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for n in sizes:
        ours, theirs = [], []
        for value in columns:
            ref = table.values.get((n, value))
            ours.append(_ours_text(by_cell.get((n, value)), ref, table))
            theirs.append("" if ref is None else _pm(ref.mean, ref.sd, _decimals(ref, table)))
        if any(theirs):
            lines.append(f"| {n:,} | ours | " + " | ".join(ours) + " |")
            lines.append("| | paper | " + " | ".join(theirs) + " |")
        elif has_paper:
            lines.append(f"| {n:,} | ours | " + " | ".join(ours) + " |")
        else:
            lines.append(f"| {n:,} | " + " | ".join(ours) + " |")
    lines.append("")
    return lines


def _decimals(ref: Published, table: PublishedTable) -> int:
    """As many decimals as the transcription has (0.084 where the paper dropped a zero)."""
    digits = len(repr(abs(ref.mean)).partition(".")[2])
    return max(table.decimals, digits)


def _ours_text(cell: CellStats | None, ref: Published | None, table: PublishedTable) -> str:
    if cell is None or not cell.values:
        return "none yet"
    values = [table.convert(v) for v in cell.values]
    mean = float(np.mean(values))
    sd = float(np.std(values, ddof=1)) if len(values) > 1 else math.nan
    text = _pm(mean, sd, table.decimals)
    if ref is not None:
        text += " ✓" if within_band(mean, ref) else " ✗"
    if cell.runs < cell.planned:
        text += f" [{cell.runs}/{cell.planned}]"
    return text


def _pm(mean: float, sd: float, decimals: int) -> str:
    if math.isnan(sd):
        return f"{mean:.{decimals}f}"
    return f"{mean:.{decimals}f} ± {sd:.{decimals}f}"


def dpd_table(sizes: Iterable[int]) -> list[str]:
    """The densest packing diameters this study used, beside Tables S5/S6 where they have N."""
    lines = [
        "## Densest packing diameters used",
        "",
        "| particles | DPD (diameters) | paper, Table S6 | difference | DPD (cm) "
        "| paper, Table S5 |",
        "|---|---|---|---|---|---|",
    ]
    for n in sorted(sizes):
        ours = densest_packing_diameters(n)
        theirs = paper.TABLE_S6_DPD_DIAMETERS.get(n)
        cm = paper.TABLE_S5_DPD_CM.get(n)
        diff = "" if theirs is None else f"{(ours / theirs - 1) * 100:+.2f} %"
        lines.append(
            f"| {n:,} | {ours:.2f} | {'' if theirs is None else theirs} | {diff} "
            f"| {ours * paper.D_MIN_M * 100:.1f} | {'' if cm is None else cm} |"
        )
    lines.append("")
    return lines


# ---- what our numbers say about each finding -------------------------------------------------

Findings = Callable[[Study, Sequence[CellStats]], list[str]]


def _headline(study: Study, stats: Sequence[CellStats]) -> dict[tuple[int, float], CellStats]:
    return {(c.particles, c.value): c for c in stats if c.metric == study.metric.key and c.values}


def _band_count(study: Study, stats: Sequence[CellStats]) -> list[str]:
    cells = _headline(study, stats)
    published = study.tables[0].values
    compared = [(key, cell) for key, cell in cells.items() if key in published]
    if not compared:
        return ["no cell the paper has a value for has finished yet."]
    outside = [key for key, cell in compared if not within_band(cell.mean, published[key])]
    line = f"{len(compared) - len(outside)} of {len(compared)} cells within the paper's ±1 sd band"
    if outside:
        shown = ", ".join(f"N={n:,} at {_value_text(study, v)}" for n, v in sorted(outside))
        line += f"; outside: {shown}"
    return [line + "."]


def _value_text(study: Study, value: float) -> str:
    return study.sweep.column(value) if study.sweep is not None else "0 % dead"


def _gap_findings(study: Study, stats: Sequence[CellStats]) -> list[str]:
    cells = _headline(study, stats)
    sizes = sorted({n for n, _ in cells})
    gaps = sorted({v for _, v in cells})
    common = [g for g in gaps if all((n, g) in cells for n in sizes)]
    if len(sizes) < 2 or not common:
        return ["needs at least two sizes finished at a common gap to compare."]
    means = {n: float(np.mean([cells[(n, g)].mean for g in common])) for n in sizes}
    grows = all(means[a] <= means[b] for a, b in itertools.pairwise(sizes))
    shown = ", ".join(f"N={n:,}: {means[n]:.2f}" for n in sizes)
    best = max(sizes, key=lambda n: means[n])
    return [
        f"success averaged over the gaps run at every size ({shown}); it "
        + ("grows" if grows else "does not grow")
        + f" with N at every step; best at N={best:,}."
    ]


def _noise_findings(study: Study, stats: Sequence[CellStats]) -> list[str]:
    cells = _headline(study, stats)
    lines = []
    for n in sorted({n for n, _ in cells}):
        base = cells.get((n, 0.0))
        if base is None:
            # A large swarm's noise-free run is often the dead study's 0 % cell instead.
            lines.append(f"N={n:,}: no noise-free run here to compare against (add 0 to --noise).")
            continue
        if base.mean <= 0:
            speed = f"{base.mean:.2f} mm/s"
            lines.append(f"N={n:,}: the noise-free speed is {speed}; nothing to compare against.")
            continue
        parts = []
        one = cells.get((n, 1.0))
        if one is not None:
            parts.append(
                f"at 1 diameter {one.mean / base.mean:.2f} of the noise-free speed "
                f"(paper {paper.FIG_S20_RELATIVE_SPEED_AT_ONE_DIAMETER:.2f})"
            )
        beyond = [c for (m, v), c in cells.items() if m == n and v > 2.0]
        if beyond:
            worst = max(abs(c.mean) for c in beyond) / base.mean
            parts.append(f"beyond 2 diameters at most {worst:.2f} of it (paper: standstill)")
        lines.append(f"N={n:,}: " + ("; ".join(parts) or "no noise level to compare") + ".")
    return lines


def _annex_findings(study: Study, stats: Sequence[CellStats]) -> list[str]:
    speed = _headline(study, stats)
    heading = {
        (c.particles, c.value): c for c in stats if c.metric == "heading_error_deg" and c.values
    }
    lines = []
    for (n, ratio), cell in sorted(speed.items()):
        control = speed.get((n, 0.0))
        if ratio == 0.0 or control is None or control.mean == 0:
            continue
        lines.append(
            f"N={n:,} with {ratio:g}x free particles: speed {cell.mean / control.mean:.2f} of the "
            f"control's, heading {heading[(n, ratio)].mean:+.1f}° vs "
            f"{heading[(n, 0.0)].mean:+.1f}° (paper: unchanged)."
        )
    return lines or ["needs the control (--free 0) and another ratio finished to compare."]


def _no_finding(study: Study, stats: Sequence[CellStats]) -> list[str]:
    return ["see the table and the plot (the paper gives no numbers)."]


FINDINGS: dict[str, Findings] = {
    "dead": _band_count,
    "speed": _band_count,
    "gap": _gap_findings,
    "noise": _noise_findings,
    "annex": _annex_findings,
}


def _seeds_text(first: int, count: int) -> str:
    return f"seed {first}" if count == 1 else f"seeds {first}-{first + count - 1}"
