"""studies/pooling.py and `particlebot study NAME --pool`: summaries of disjoint runs pooled equal
the summary of all the runs."""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np
import pytest

from particlebot.commands import study
from particlebot.studies.definitions import STUDIES
from particlebot.studies.pooling import PoolingError, pool_summaries
from particlebot.studies.report import CellStats, csv_text


def _summary(values: dict[float, list[float]]) -> str:
    """The dead study's summary.csv of 10,000 particles with these speeds per dead fraction."""
    stats = [
        CellStats(10_000, fraction, "speed_mm_s", len(runs), tuple(runs))
        for fraction, runs in values.items()
    ]
    return csv_text(STUDIES["dead"], stats)


def _files(tmp_path: Path, *summaries: str) -> list[Path]:
    paths = []
    for i, text in enumerate(summaries):
        paths.append(tmp_path / f"summary-{i}.csv")
        paths[-1].write_text(text)
    return paths


def test_pooled_summaries_equal_the_summary_of_every_run(tmp_path: Path) -> None:
    rng = np.random.default_rng(4)
    # Six seeds then five, one then two, and a cell only the first summary has.
    first = {
        0.0: list(rng.normal(0.63, 0.01, 6)),
        0.1: [0.44],
        0.5: list(rng.normal(0.01, 1e-3, 3)),
    }
    second = {0.0: list(rng.normal(0.62, 0.02, 5)), 0.1: [0.45, 0.43]}
    text = pool_summaries(_files(tmp_path, _summary(first), _summary(second)))
    every = {f: first[f] + second.get(f, []) for f in first}
    want = {row["dead_fraction"]: row for row in csv.DictReader(io.StringIO(_summary(every)))}
    got = {row["dead_fraction"]: row for row in csv.DictReader(io.StringIO(text))}
    assert got.keys() == want.keys()
    for fraction, row in want.items():
        assert int(got[fraction]["runs"]) == int(row["runs"])
        assert float(got[fraction]["mean"]) == pytest.approx(float(row["mean"]), rel=1e-5)
        assert float(got[fraction]["sd"]) == pytest.approx(float(row["sd"]), rel=1e-4)
        assert got[fraction]["paper_mean"] == row["paper_mean"]
        assert got[fraction]["within_paper_band"] == row["within_paper_band"]


def test_a_file_that_is_not_a_summary_is_refused_naming_it(tmp_path: Path) -> None:
    (other,) = _files(tmp_path, "particles,speed\n10,0.3\n")
    with pytest.raises(PoolingError, match=re.escape("not a study's summary.csv")):
        pool_summaries([other])
    broken = _summary({0.0: [0.6, 0.61]}).replace(",2,2,", ",two,2,")
    (path,) = _files(tmp_path, broken)
    with pytest.raises(PoolingError, match="line 2: not a summary row"):
        pool_summaries([path])
    with pytest.raises(PoolingError, match=re.escape("missing.csv")):
        pool_summaries([tmp_path / "missing.csv"])


def test_the_study_command_pools_into_the_results_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    paths = _files(tmp_path, _summary({0.0: [0.6, 0.62]}), _summary({0.0: [0.61]}))
    out = tmp_path / "pooled"
    assert study.main(["dead", "--pool", *map(str, paths), "--results", str(out)]) == 0
    rows = list(csv.DictReader((out / "summary.csv").open(newline="")))
    assert [(r["dead_fraction"], r["runs"], r["mean"]) for r in rows] == [("0", "3", "0.61")]
    assert str(out / "summary.csv") in capsys.readouterr().out


def test_the_study_command_refuses_another_studys_summary_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (path,) = _files(tmp_path, _summary({0.0: [0.6]}))
    assert study.main(["gap", "--pool", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"particlebot: study gap: --pool: {path} is not a summary of this study"
    (broken,) = _files(tmp_path, "particles,speed\n")
    assert study.main(["dead", "--pool", str(broken)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
