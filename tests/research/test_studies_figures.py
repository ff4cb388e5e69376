"""research/studies_figures.py redraws docs/studies' figures from the study data the repo keeps in
data/studies, whose README names every file there."""

from __future__ import annotations

import csv
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.repo import REPO_ROOT

SCRIPT = REPO_ROOT / "research" / "studies_figures.py"
DATA = REPO_ROOT / "data" / "studies"


def _figures(out: Path, names: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(SCRIPT), str(DATA), str(out), "--figures", names],
        capture_output=True, text=True, check=False,
    )  # fmt: skip


def test_the_readme_names_every_kept_file_and_every_file_it_names_is_kept() -> None:
    readme = (DATA / "README.md").read_text(encoding="utf-8")
    kept = {p.name for p in DATA.iterdir()} - {"README.md"}
    for name in kept:
        assert f"`{Path(name).stem}." in readme or f"`{name}/" in readme, name
    first_cells = [line.split("|")[1] for line in readme.splitlines() if line.startswith("| `")]
    named = {n for cell in first_cells for n in re.findall(r"`([\w.-]+\.(?:csv|md))`", cell)}
    assert named <= kept, named - kept


def test_every_study_csv_is_a_summary() -> None:
    for path in DATA.glob("*.csv"):
        with path.open(newline="") as stream:
            header = next(csv.reader(stream))
        if "paper_mean" in header:
            assert {"particles", "metric", "runs", "planned", "mean", "sd"} <= set(header), path


@pytest.mark.slow
def test_the_dead_figures_redraw_from_the_kept_data_alone(tmp_path: Path) -> None:
    done = _figures(tmp_path, "dead")
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["dead-variants.png", "dead.png"]
    # The 10,000-particle row of Table S3 has every column, 0-80 % dead, in the pooled summary.
    with (DATA / "dead-10000-pooled.csv").open(newline="") as stream:
        rows = [r for r in csv.DictReader(stream) if r["metric"] == "speed_mm_s" and r["mean"]]
    fractions = [float(r["dead_fraction"]) for r in rows if r["particles"] == "10000"]
    assert fractions == [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]


def test_an_unknown_figure_is_one_line_and_exit_2(tmp_path: Path) -> None:
    done = _figures(tmp_path, "dead,nope")
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "studies_figures: --figures: not a figure: nope "
        "(choose from dead, speed, shear, dashpot, placement, gap, noise)"
    )
    assert not any(tmp_path.iterdir())
