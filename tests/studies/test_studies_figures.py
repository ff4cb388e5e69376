"""tools/studies_figures.py redraws docs/studies' figures from the summaries the repo keeps."""

from __future__ import annotations

import csv
import importlib.util
import subprocess
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "studies_figures.py"
DOCS = ROOT / "docs" / "studies"


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("studies_figures", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_kept_summary_is_in_docs_and_is_a_summary() -> None:
    for folder, name in _tool().DOCS_SUMMARIES.items():
        path = DOCS / name
        assert path.is_file(), f"{folder}: {path} is missing"
        with path.open(newline="") as stream:
            header = next(csv.reader(stream))
        assert {"particles", "metric", "runs", "mean", "sd"} <= set(header), name


def test_the_dead_figures_redraw_from_docs_alone(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, str(TOOL), str(DOCS), str(tmp_path), "--figures", "dead"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["dead-variants.png", "dead.png"]
    tool = _tool()
    # The 10,000-particle row comes from its summary: every column of Table S3 is there.
    row = tool.read(DOCS / "dead-10000-all", "speed_mm_s")[10_000]
    assert [value for value, *_ in row] == [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]


def test_an_unknown_figure_is_one_line_and_exit_2(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, str(TOOL), str(DOCS), str(tmp_path), "--figures", "dead,nope"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "studies_figures: --figures: not a figure: nope "
        "(choose from dead, speed, shear, dashpot, placement, gap, noise)"
    )
    assert not any(tmp_path.iterdir())
