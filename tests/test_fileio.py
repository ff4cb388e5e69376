"""particlebot.fileio: an output is replaced whole or left as it was, and no temporary file
stays behind either way."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np
import pytest

from particlebot.fileio import atomic_open, atomic_path, finished_files, write_bytes, write_text


class WriterError(Exception):
    pass


def test_write_text_replaces_the_file_and_leaves_nothing_beside_it(tmp_path: Path) -> None:
    target = tmp_path / "summary.json"
    target.write_text("old\n")
    write_text(target, "new\n")
    assert target.read_text() == "new\n"
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]


def test_a_writer_that_fails_halfway_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "run.csv"
    target.write_text("header\nrow 1\n")
    with pytest.raises(WriterError), atomic_open(target) as stream:
        stream.write("header\nrow 1\nrow 2 cut sh")
        raise WriterError
    assert target.read_text() == "header\nrow 1\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]


def test_a_new_file_does_not_appear_until_it_is_whole(tmp_path: Path) -> None:
    target = tmp_path / "track.csv"
    with atomic_open(target) as stream:
        stream.write("t,x,y\n")
        assert not target.exists()
        # pathlib's "*.csv" sees the temporary (a dot-file); finished_files does not.
        assert [p.name for p in tmp_path.glob("*.csv")] != []
        assert finished_files(tmp_path, "*.csv") == []
    assert target.read_text() == "t,x,y\n"
    assert finished_files(tmp_path, "*.csv") == [target]
    assert finished_files(tmp_path / "absent", "*.csv") == []


def test_atomic_path_keeps_the_suffix_for_writers_that_choose_a_format_by_it(
    tmp_path: Path,
) -> None:
    target = tmp_path / "step-000000010.npz"
    with atomic_path(target) as temporary:
        assert temporary.suffix == ".npz" and temporary.parent == tmp_path
        np.savez_compressed(temporary, x=np.arange(3))
    with np.load(target) as data:
        assert data["x"].tolist() == [0, 1, 2]
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


def test_modes_private_when_asked_and_as_open_gives_otherwise(tmp_path: Path) -> None:
    private = tmp_path / "fleet.toml"
    write_bytes(private, b"key = 1\n", mode=0o600)
    assert stat.S_IMODE(private.stat().st_mode) == 0o600
    plain = tmp_path / "plain.txt"
    write_text(plain, "x")
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(plain.stat().st_mode) == 0o666 & ~umask


def test_an_unwritable_folder_raises_and_leaves_nothing(tmp_path: Path) -> None:
    missing = tmp_path / "no-such-folder" / "out.txt"
    with pytest.raises(OSError):
        write_text(missing, "x")
    assert list(tmp_path.iterdir()) == []
