"""`particlebot study` from the command line: one-line errors, nothing written in vain, --list."""

from __future__ import annotations

from pathlib import Path

import pytest

from particlebot.cli import main


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    try:
        code = main(["study", *argv])
    except SystemExit as exc:  # argparse's own errors
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "the following arguments are required: NAME"),
        (["dead", "--bogus"], "unrecognized arguments: --bogus"),
        (["nope"], "invalid choice: 'nope'"),
        (
            ["dead", "--gaps", "0.3"],
            "--gaps does not apply to study dead (its sweep is --fractions)",
        ),
        (["speed", "--free", "1"], "--free does not apply to study speed"),
        (["dead", "--sizes", "1o"], "--sizes: '1o' is not a whole number"),
        (["dead", "--workers", "two"], "argument --workers: invalid int value: 'two'"),
        (["dead", "--workers", "0"], "--workers: 0 is below 1"),
        (["dead", "--workers", "2", "--scheduler", "tcp://h:8786"], "--workers sizes the local"),
        (["noise", "--noise", "nan"], "--noise: nan is not a standard deviation"),
        (["dead", "--set", "bogus=1"], "--set: 'bogus' is not a number of the model (attraction"),
        (["dead", "--set", "shear"], "--set: expected NAME=VALUE, got 'shear'"),
        (["dead", "--set", "neighbour_search=1"], "'neighbour_search' is not a number of the"),
        (["dead", "--set", "shear=-1"], "--set: shear must be a number 0..1e+09, not -1.0"),
        (["dead", "--set", "shear=nan"], "--set: shear must be a number 0..1e+09, not nan"),
        (["dead", "--set", "r_min=0.1"], "--set: r_min is fixed in the studies"),
        (["dead", "--set", "update_cycles=1.5"], "update_cycles must be a whole number >= 1"),
        (["dead", "--set", "shear=20,shear=30"], "--set: shear given twice"),
    ],
)
def test_bad_options_get_one_line_and_status_2(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, _out, err = run([*argv, "--results", str(tmp_path / "r")] if argv else argv, capsys)
    assert code == 2
    assert message in err
    assert err.count("\n") == 1 and err.startswith("particlebot: ")
    assert not (tmp_path / "r").exists()


def test_list_shows_the_plan_without_running(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, _ = run(["gap", "--quick", "--list", "--results", str(tmp_path / "r")], capsys)
    assert code == 0
    assert "gap: 12 runs in 6 cells x 2 seeds, 3600 s simulated each" in out
    assert "N=100: 0/6 runs finished" in out
    assert not (tmp_path / "r").exists()
