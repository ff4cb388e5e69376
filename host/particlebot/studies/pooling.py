"""Pools studies' summary.csv files cell by cell (runs, mean and sd of disjoint sets of runs).

A study's own report pools runs from their records (copy the runs/*.json of several results
folders into one and report with --report-only). Pooling is for when only the summaries are
left: the pooled mean and sample sd are exact, up to the six significant digits a summary
keeps. The planned runs add up too (a summary cannot say which seeds it planned, so plans that
overlap count twice). `particlebot study NAME --pool A/summary.csv B/summary.csv` runs it.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from particlebot.errors import ParticlebotError
from particlebot.studies.published import Published
from particlebot.studies.report import within_band


class PoolingError(ParticlebotError, ValueError):
    """A file that cannot be pooled: unreadable, not a summary, or other columns than the first."""


@dataclass
class Group:
    """The runs of one cell: how many finished and were planned, their mean and sample sd."""

    runs: int
    planned: int
    mean: float
    sd: float  # NaN for a single run


def pooled(a: Group, b: Group) -> Group:
    """Two disjoint groups of runs as one: the mean of all, and the sample sd (ddof 1) from the
    groups' sums of squares about the pooled mean."""
    runs = a.runs + b.runs
    if a.runs == 0 or b.runs == 0:
        kept = a if a.runs else b
        return Group(runs, a.planned + b.planned, kept.mean, kept.sd)
    mean = (a.runs * a.mean + b.runs * b.mean) / runs
    squares = sum(
        (g.runs - 1) * (0.0 if math.isnan(g.sd) else g.sd) ** 2 + g.runs * (g.mean - mean) ** 2
        for g in (a, b)
    )
    return Group(runs, a.planned + b.planned, mean, math.sqrt(squares / (runs - 1)))


def _float(text: str) -> float:
    return float(text) if text else math.nan


def _num(value: float) -> str:
    return "" if math.isnan(value) else f"{value:.6g}"


def pool_summaries(paths: Sequence[Path]) -> str:
    """The summary.csv text of every run the summaries at `paths` count, cell by cell, in the
    order the cells first appear; raises PoolingError naming the file (and line) it cannot use."""
    if not paths:
        raise PoolingError("no summaries to pool")
    header: list[str] | None = None
    cells: dict[tuple[str, ...], tuple[Group, list[str]]] = {}
    for path in paths:
        try:
            with path.open(newline="") as f:
                rows = list(csv.reader(f))
        except OSError as error:
            raise PoolingError(f"{path}: {error.strerror or error}") from None
        except (UnicodeDecodeError, csv.Error):
            raise PoolingError(f"{path}: not a study's summary.csv") from None
        if not rows or "runs" not in rows[0] or "paper_mean" not in rows[0]:
            raise PoolingError(f"{path}: not a study's summary.csv")
        if header is not None and rows[0] != header:
            raise PoolingError(f"{path}: other columns than {paths[0]}")
        header = rows[0]
        col = {name: i for i, name in enumerate(header)}
        key_width = col["runs"]  # everything before `runs` names the cell
        for line, row in enumerate(rows[1:], start=2):
            try:
                group = Group(
                    int(row[col["runs"]]), int(row[col["planned"]]),
                    _float(row[col["mean"]]), _float(row[col["sd"]]),
                )  # fmt: skip
            except (ValueError, IndexError, KeyError):
                raise PoolingError(f"{path}, line {line}: not a summary row") from None
            key = tuple(row[:key_width])
            paper = [row[col["paper_mean"]], row[col["paper_sd"]]]
            if key in cells:
                group = pooled(cells[key][0], group)
            cells[key] = (group, paper)
    assert header is not None
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(header)
    for key, (group, (paper_mean, paper_sd)) in cells.items():
        band = ""
        if paper_mean and group.runs:
            published = Published(float(paper_mean), float(paper_sd))
            band = str(within_band(group.mean, published)).lower()
        writer.writerow(
            [*key, group.runs, group.planned, _num(group.mean), _num(group.sd),
             paper_mean, paper_sd, band]
        )  # fmt: skip
    return out.getvalue()
