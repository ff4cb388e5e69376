"""tools/pool_summaries.py: summaries of disjoint runs pooled equal the summary of all the runs."""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from particlebot.studies.definitions import STUDIES
from particlebot.studies.report import CellStats, csv_text

TOOL = Path(__file__).resolve().parents[2] / "tools" / "pool_summaries.py"


def _summary(values: dict[float, list[float]]) -> str:
    """The dead study's summary.csv of 10,000 particles with these speeds per dead fraction."""
    stats = [
        CellStats(10_000, fraction, "speed_mm_s", len(runs), tuple(runs))
        for fraction, runs in values.items()
    ]
    return csv_text(STUDIES["dead"], stats)


def _pool(tmp_path: Path, *summaries: str) -> subprocess.CompletedProcess[str]:
    paths = []
    for i, text in enumerate(summaries):
        paths.append(tmp_path / f"summary-{i}.csv")
        paths[-1].write_text(text)
    return subprocess.run(
        [sys.executable, str(TOOL), *map(str, paths)], capture_output=True, text=True, check=False
    )


def test_pooled_summaries_equal_the_summary_of_every_run(tmp_path: Path) -> None:
    rng = np.random.default_rng(4)
    # Six seeds then five, one then two, and a cell only the first summary has.
    first = {
        0.0: list(rng.normal(0.63, 0.01, 6)),
        0.1: [0.44],
        0.5: list(rng.normal(0.01, 1e-3, 3)),
    }
    second = {0.0: list(rng.normal(0.62, 0.02, 5)), 0.1: [0.45, 0.43]}
    done = _pool(tmp_path, _summary(first), _summary(second))
    assert done.returncode == 0, done.stderr
    every = {f: first[f] + second.get(f, []) for f in first}
    want = {row["dead_fraction"]: row for row in csv.DictReader(io.StringIO(_summary(every)))}
    got = {row["dead_fraction"]: row for row in csv.DictReader(io.StringIO(done.stdout))}
    assert got.keys() == want.keys()
    for fraction, row in want.items():
        assert int(got[fraction]["runs"]) == int(row["runs"])
        assert float(got[fraction]["mean"]) == pytest.approx(float(row["mean"]), rel=1e-5)
        assert float(got[fraction]["sd"]) == pytest.approx(float(row["sd"]), rel=1e-4)
        assert got[fraction]["paper_mean"] == row["paper_mean"]
        assert got[fraction]["within_paper_band"] == row["within_paper_band"]


def test_a_file_that_is_not_a_summary_is_one_line_and_exit_2(tmp_path: Path) -> None:
    done = _pool(tmp_path, "particles,speed\n10,0.3\n")
    assert done.returncode == 2
    assert done.stderr.strip().endswith("not a study's summary.csv")
    assert len(done.stderr.strip().splitlines()) == 1
    broken = _summary({0.0: [0.6, 0.61]}).replace(",2,2,", ",two,2,")
    done = _pool(tmp_path, broken)
    assert done.returncode == 2 and "line 2: not a summary row" in done.stderr
