"""README's examples run as written: the Swarm API script and the experiment file, output too."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from particlebot.cli import main
from tests.support.repo import REPO_ROOT

README = REPO_ROOT / "README.md"

pytestmark = pytest.mark.e2e


def code_block(language: str, section: str = "## Experiments as code") -> str:
    """The first ```language block after the section's heading."""
    text = README.read_text(encoding="utf-8")
    found = re.search(rf"```{language}\n(.*?)```", text[text.index(section) :], re.S)
    assert found, f"README has no {language} block under {section}"
    return found.group(1)


def test_the_api_example_runs_as_written(tmp_path: Path) -> None:
    # As README says to run it: a file of its own, run by the environment's Python in a folder
    # of the researcher's, outside the clone (so nothing but the installed package is imported).
    example = tmp_path / "example.py"
    example.write_text(code_block("python"), encoding="utf-8")
    ran = subprocess.run(
        [sys.executable, example.name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert ran.returncode == 0, ran.stderr
    lines = ran.stdout.splitlines()
    assert re.fullmatch(
        r"run 1, method COUNTING: STOP confirmed by all 10 particles in .* s", lines[0]
    )
    assert [line.split(":")[0] for line in lines[1:11]] == [f"particle {i}" for i in range(1, 11)]
    assert all(line.endswith(", IDLE") for line in lines[1:11])
    (log,) = (tmp_path / "logs").glob("*.jsonl")
    assert lines[11] == f"log: {log.relative_to(tmp_path)}"


def test_the_experiment_file_runs_as_written_and_prints_the_summary_shown(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    experiment = tmp_path / "experiment.toml"
    experiment.write_text(code_block("toml"), encoding="utf-8")
    assert main(["run", str(experiment), "--log-dir", str(tmp_path / "logs")]) == 0
    out = capsys.readouterr().out
    text = README.read_text(encoding="utf-8")
    table = text[text.index("trial  method  duration s") :].split("```")[0].strip()
    assert table in out  # seeded and stepped: the same figures every time
    (folder,) = (tmp_path / "logs").glob("phototaxis-*")
    assert len(list(folder.glob("trial-*.jsonl"))) == 4
