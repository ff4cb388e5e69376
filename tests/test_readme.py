"""The manual's examples run as written: README's Swarm API script, every code block of the
documentation site marked runnable, and the experiment file with the summary its page shows."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from particlebot.cli import main
from tests.support.repo import REPO_ROOT

ROOT = REPO_ROOT
README = ROOT / "README.md"
DOCS = ROOT / "docs"
EXPERIMENTS_PAGE = DOCS / "experiments.md"

pytestmark = pytest.mark.e2e

# A block is runnable when the line before its opening fence is this comment (invisible on the
# site); it runs as a script of its own in an empty folder.
RUNNABLE = re.compile(r"^<!-- runnable -->\n```python\n(.*?)^```", re.S | re.M)


def code_block(path: Path, language: str, section: str) -> str:
    """The first ```language block after the section's heading."""
    text = path.read_text(encoding="utf-8")
    found = re.search(rf"```{language}\n(.*?)```", text[text.index(section) :], re.S)
    assert found, f"{path.name} has no {language} block under {section}"
    return found.group(1)


def runnable_blocks() -> list[tuple[str, str]]:
    """(page:line, code) of every block of the site marked runnable."""
    blocks = []
    for page in sorted(DOCS.rglob("*.md")):
        text = page.read_text(encoding="utf-8")
        for found in RUNNABLE.finditer(text):
            line = text.count("\n", 0, found.start()) + 1
            blocks.append((f"{page.relative_to(DOCS)}:{line}", found.group(1)))
    return blocks


def run_script(code: str, folder: Path) -> subprocess.CompletedProcess[str]:
    # As the manual says to run it: a file of its own, run by the environment's Python in a
    # folder of the researcher's, outside the clone (so nothing but the installed package is
    # imported).
    script = folder / "example.py"
    script.write_text(code, encoding="utf-8")
    return subprocess.run(
        [sys.executable, script.name],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )


def test_the_readme_api_example_runs_as_written(tmp_path: Path) -> None:
    ran = run_script(code_block(README, "python", "## Experiments as code"), tmp_path)
    assert ran.returncode == 0, ran.stderr
    lines = ran.stdout.splitlines()
    assert re.fullmatch(
        r"run 1, method COUNTING: STOP confirmed by all 10 particles in .* s", lines[0]
    )
    assert [line.split(":")[0] for line in lines[1:11]] == [f"particle {i}" for i in range(1, 11)]
    assert all(line.endswith(", IDLE") for line in lines[1:11])
    (log,) = (tmp_path / "logs").glob("*.jsonl")
    assert lines[11] == f"log: {log.relative_to(tmp_path)}"


def test_the_site_has_runnable_examples() -> None:
    # The marker is easy to lose in an edit; the pages that show scripts keep at least these.
    pages = {where.split(":")[0] for where, _ in runnable_blocks()}
    assert {"getting-started.md", "experiments.md"} <= pages


@pytest.mark.parametrize(
    ("where", "code"), [pytest.param(where, code, id=where) for where, code in runnable_blocks()]
)
def test_a_runnable_example_of_the_site_runs_as_written(
    where: str, code: str, tmp_path: Path
) -> None:
    ran = run_script(code, tmp_path)
    assert ran.returncode == 0, f"{where}:\n{ran.stderr}"
    assert ran.stdout.strip(), f"{where} printed nothing"


def test_the_experiment_file_runs_as_written_and_prints_the_summary_shown(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    section = "## `particlebot run`: an experiment file"
    experiment = tmp_path / "experiment.toml"
    experiment.write_text(code_block(EXPERIMENTS_PAGE, "toml", section), encoding="utf-8")
    assert main(["run", str(experiment), "--log-dir", str(tmp_path / "logs")]) == 0
    out = capsys.readouterr().out
    text = EXPERIMENTS_PAGE.read_text(encoding="utf-8")
    table = text[text.index("trial  method  duration s") :].split("```")[0].strip()
    shown, printed = table.splitlines(), out[out.index("trial  method  duration s") :].splitlines()
    assert printed[0] == shown[0]
    # Seeded and stepped, so one machine prints the same figures every time; but another CPU
    # target rounds the world's arithmetic differently in the last bits (numba's generic target
    # has no fused multiply-add), contacts amplify that over 60 s, and a run's "toward lamp m"
    # moves within the spread of the seeds (0.023-0.104 m here; 0.098 became 0.103). The rest
    # of each row is exact, and every run moved toward the lamp.
    for want, got in zip(shown[1:], printed[1 : len(shown)], strict=True):
        *labels, toward = want.split()
        *got_labels, got_toward = got.split()
        assert got_labels == labels
        assert float(got_toward) > 0 and abs(float(got_toward) - float(toward)) < 0.1
    (folder,) = (tmp_path / "logs").glob("phototaxis-*")
    assert len(list(folder.glob("trial-*.jsonl"))) == 4
