"""Damaged run folders on `simulate --resume`: the damaged file is named, the run goes on from
the latest snapshot that reads whole, and a snapshot is never unpickled (a run folder from
someone else cannot run code)."""

from __future__ import annotations

import io
import pickle
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tests.commands.refusals import assert_refused_here, refusal

SCENARIO = """\
name = "damaged"
duration_s = 2.0
[swarm]
particles = 4
[output]
dump_interval_s = 0.5
snapshot_interval_s = 1.0
"""


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run folder with snapshots at 0, 1 and 2 s."""
    from particlebot.cli import main

    root = tmp_path_factory.mktemp("run")
    (root / "s.toml").write_text(SCENARIO)
    assert main(["simulate", str(root / "s.toml"), "-o", str(root / "run")]) == 0
    return root / "run"


@pytest.fixture
def run(finished_run: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "run"
    shutil.copytree(finished_run, folder)
    return folder


def snapshots(folder: Path) -> list[Path]:
    return sorted((folder / "snapshots").glob("step-*.npz"))


def resume(folder: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    return refusal(["simulate", "--resume", str(folder), "--duration", "3"], capsys)


def test_the_folder_has_the_snapshots_these_tests_damage(run: Path) -> None:
    assert [p.name for p in snapshots(run)] == [
        "step-000000000.npz", "step-000000100.npz", "step-000000200.npz",
    ]  # fmt: skip


@pytest.mark.parametrize(
    "damage", ["truncated", "bit flipped", "arrays cut short", "strings", "full of NaN"]
)
def test_a_damaged_latest_snapshot_is_named_and_the_run_goes_on_from_the_one_before(
    damage: str, run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    latest = snapshots(run)[-1]
    data = latest.read_bytes()
    if damage == "truncated":
        latest.write_bytes(data[: len(data) // 2])
    elif damage == "bit flipped":
        middle = len(data) // 2
        latest.write_bytes(data[:middle] + bytes([data[middle] ^ 0xFF]) + data[middle + 1 :])
    else:
        with np.load(latest, allow_pickle=False) as loaded:
            arrays = {name: loaded[name] for name in loaded.files}
        if damage == "full of NaN":  # once a segfault in the kernels' cell arithmetic
            arrays["pos"] = np.full_like(arrays["pos"], np.nan)
            arrays["vel"] = np.full_like(arrays["vel"], np.nan)
        elif damage == "arrays cut short":
            arrays["pos"] = arrays["pos"][:, :2]
        else:
            arrays["pos"] = np.array("x")
        np.savez_compressed(latest, **arrays)

    code, err = resume(run, capsys)

    assert code == 0, err
    assert "Traceback" not in err
    assert f"note: {latest}" in err
    assert "resuming from step-000000100.npz" in err
    assert (run / "snapshots" / "step-000000300.npz").is_file()  # it went on to 3 s


def test_when_no_snapshot_reads_the_line_names_the_file(
    run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for path in snapshots(run):
        path.write_bytes(b"PK\x03\x04 not really")
    assert_refused_here(
        ["simulate", "--resume", str(run)], f"{snapshots(run)[-1]}: damaged", capsys
    )


def test_a_snapshot_holding_a_pickle_is_refused_without_unpickling_it(
    run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    marker = tmp_path / "code-ran"
    # A pickle that, loaded, would run code of its choosing: here it only creates a file.
    payload = pickle.dumps(_Touch(marker))
    for path in snapshots(run):
        buffer = io.BytesIO()
        np.savez(buffer, setup=np.frombuffer(payload, dtype=np.uint8), pos=np.zeros((2, 4)))
        path.write_bytes(buffer.getvalue())

    assert_refused_here(
        ["simulate", "--resume", str(run)], "whose set-up is a pickle (it could run code)", capsys
    )
    assert not marker.exists()
    assert zipfile.is_zipfile(snapshots(run)[-1])  # left as it was


class _Touch:
    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self) -> tuple[object, tuple[str]]:
        return (_touch, (str(self.path),))


def _touch(path: str) -> None:
    Path(path).touch()


def test_an_empty_view_json_is_drawn_again(run: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (run / "view.json").write_text("")
    code, err = resume(run, capsys)
    assert code == 0, err
    assert f"note: {run / 'view.json'} was damaged" in err
    assert (run / "view.json").read_text().startswith("{")


def test_a_binary_csv_is_named_and_left_alone(
    run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    garbage = bytes(range(256)) * 4
    (run / "run.csv").write_bytes(garbage)
    assert_refused_here(
        ["simulate", "--resume", str(run), "--duration", "3"],
        f"{run / 'run.csv'} is damaged (not text)",
        capsys,
    )
    assert (run / "run.csv").read_bytes() == garbage


@pytest.mark.parametrize("content", ["", "header only"])
def test_a_csv_without_rows_keeps_its_header_and_says_what_is_lost(
    content: str, run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = (run / "run.csv").read_text().splitlines()
    (run / "run.csv").write_text("" if not content else "\n".join(lines[:2]) + "\n")

    code, err = resume(run, capsys)

    assert code == 0, err
    assert "holds no rows from the run's start to 2 s" in err
    after = (run / "run.csv").read_text().splitlines()
    assert after[:2] == lines[:2]  # the published header, as it was written
    assert [row.split(",")[0] for row in after[2:]] == ["2.500000", "3.000000"]


@pytest.mark.parametrize(
    ("edit", "complaint"),
    [
        (("particles = 4", "particles = 40"), "swarm.particles 4 -> 40"),
        (("[output]", "[physics]\ndt = 0.02\n\n[output]"), "physics.dt 0.01 -> 0.02"),
    ],
)
def test_an_edited_scenario_is_refused_saying_what_changed(
    edit: tuple[str, str], complaint: str, run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario = run / "scenario.toml"
    text = scenario.read_text()
    assert edit[0] in text
    scenario.write_text(text.replace(edit[0], edit[1], 1))
    assert_refused_here(["simulate", "--resume", str(run)], complaint, capsys)
