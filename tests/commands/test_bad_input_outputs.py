"""Outputs that cannot go where they are asked (a file where a folder belongs, a place such as
/proc, a full disk): one line naming the path and the reason, a non-zero exit, and nothing
half-written. (Tests run as root, for whom a read-only folder is writable: /proc and a file in
the folder's place stand in for it.)"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from particlebot.fileio import OutputError, write_text
from tests.commands.refusals import assert_refused, assert_refused_here, particlebot

PROC = Path("/proc")
needs_proc = pytest.mark.skipif(not (PROC / "self").is_dir(), reason="needs Linux's /proc")


@pytest.fixture
def a_file(tmp_path: Path) -> Path:
    path = tmp_path / "a-file"
    path.write_text("mine\n")
    return path


def test_a_run_folder_under_a_file_is_one_line_and_nothing_is_made(
    a_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["simulate", "--duration", "1", "-o", str(a_file / "run")]
    assert_refused_here(argv, f"cannot write {a_file / 'run'}: Not a directory", capsys)
    assert a_file.read_text() == "mine\n"


@needs_proc
def test_a_run_folder_under_proc_is_one_line_from_the_command(tmp_path: Path) -> None:
    done = particlebot("simulate", "--duration", "1", "-o", "/proc/particlebot/run", cwd=tmp_path)
    assert_refused(done, "cannot write /proc/particlebot: No such file or directory")
    assert list(tmp_path.iterdir()) == []


@needs_proc
@pytest.mark.parametrize("where", ["/proc/fleet.toml", "a-file/fleet.toml"])
def test_a_fleet_file_that_cannot_be_written_is_one_line(
    where: str, a_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(a_file.parent)
    assert_refused_here(["fleet", "init", "--fleet", where], f"cannot write {where}", capsys)
    assert sorted(p.name for p in a_file.parent.iterdir()) == ["a-file"]


def test_an_atomic_write_that_fails_leaves_the_old_file_and_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "summary.json"
    target.write_text("old\n")

    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OutputError, match=f"cannot write {target}: No space left on device"):
        write_text(target, "new\n")
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]


def test_a_csv_row_the_disk_refuses_is_cut_back_to_the_last_whole_row(tmp_path: Path) -> None:
    from particlebot.sim.runs.csvlog import CsvLog
    from particlebot.sim.world.bodies import BodyState

    path = tmp_path / "run.csv"
    log = CsvLog.create(path, seed=1, bodies=1, per_particle=False)
    one = np.zeros(1)
    state = BodyState(0.0, one, one, one, one, one, one > 0, one == 0, one > 0, one > 0,
                      np.zeros((0, 5)))  # fmt: skip
    log.write(state, (0.0, 0.0), 1.0)
    whole = path.read_bytes()

    class HalfThenFull:
        """A file on a disk that takes 5 bytes of the next row, then is full."""

        def __init__(self, inner: Any) -> None:
            self.inner = inner
            self.taken = False

        def tell(self) -> int:
            return self.inner.tell()

        def truncate(self, size: int) -> int:
            return self.inner.truncate(size)

        def write(self, data: bytes) -> int:
            if self.taken:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            self.taken = True
            return self.inner.write(data[:5])

        def close(self) -> None:
            self.inner.close()

    log._stream = HalfThenFull(log._stream)  # type: ignore[assignment]
    with pytest.raises(OutputError, match="No space left on device"):
        log.write(state, (0.0, 0.0), 1.0)
    log.close()
    assert path.read_bytes() == whole  # no torn line


EXPERIMENT = """\
name = "rehearsal"
radio = "virtual://3?speed=max"
[[trial]]
method = "D"
duration_s = 5
"""


@pytest.mark.parametrize("log_dir", ["a-file", "/proc"], ids=["a file", "proc"])
def test_a_log_folder_that_cannot_be_made_stops_run_before_any_trial(
    log_dir: str, a_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    if log_dir == "/proc" and not (PROC / "self").is_dir():
        pytest.skip("needs Linux's /proc")
    monkeypatch.chdir(a_file.parent)
    (a_file.parent / "e.toml").write_text(EXPERIMENT)
    argv = ["run", "e.toml", "--log-dir", log_dir]
    assert_refused_here(argv, f"cannot write {log_dir}/rehearsal-", capsys)
    assert sorted(p.name for p in a_file.parent.iterdir()) == ["a-file", "e.toml"]
