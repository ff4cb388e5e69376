"""The calibration page's figures come from its own commands (seeded and stepped: the same every
time): Fig. S5's row for photocell_spread=0.1, and the servo table of its transcript."""

from __future__ import annotations

import io
import re
from pathlib import Path

import pytest

from particlebot.cli import main
from tests.support.repo import REPO_ROOT

PAGE = REPO_ROOT / "docs" / "calibration.md"


def section() -> str:
    return PAGE.read_text(encoding="utf-8")


@pytest.mark.e2e
def test_the_fig_s5_row_is_what_the_readme_command_measures(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    command = re.search(
        r"particlebot calibrate sensors --radio '(virtual://9[^']*)' --check", section()
    )
    assert command is not None
    monkeypatch.chdir(tmp_path)
    assert main(["calibrate", "sensors", "--radio", command.group(1), "--check", "--no-plot"]) == 0
    out = capsys.readouterr().out
    found = re.search(
        r"RMS error: raw (\S+) cm, calibrated (\S+) cm; worst particle's mean: raw (\S+) cm, "
        r"calibrated (\S+) cm",
        out,
    )
    assert found is not None, out
    raw, calibrated, worst_raw, worst_calibrated = found.groups()
    row = next(line for line in section().splitlines() if "`photocell_spread=0.1` (gamma" in line)
    assert f"{raw} → {calibrated} cm" in row
    assert f"{worst_raw} → {worst_calibrated} cm" in row


def test_the_servo_transcript_is_what_its_answers_give(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    text = section()
    answers = re.findall(r"holding \d+ us\. Radius in mm \[[\d.]+\]: ([\d.]+)", text)
    table = re.search(r"Wrote and read back particle 7's table: ([\d, ]+) us", text)
    assert len(answers) == 2 and table is not None
    # The transcript shows the first two answers; the made-up servo of the picture gave these.
    radii = ["74.8", "84.2", "92.8", "100.4", "106.8", "112.4", "117.4", "121.3", "124.2"]
    assert answers == radii[:2]
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("sys.stdin", io.StringIO("\n".join(radii) + "\n\n"))
    assert main(["calibrate", "servo", "3", "--radio", "virtual://3"]) == 0
    assert f"particle 3's table: {table.group(1)} us" in capsys.readouterr().out
