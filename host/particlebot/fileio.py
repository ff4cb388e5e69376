"""Files written whole or not at all: every output the package writes goes through a temporary
name in the target's own folder, is flushed to disk, and only then renamed over the target; a
place that cannot be written is one line (OutputError)."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from particlebot.errors import ParticlebotError

# Why the same folder: rename is atomic only within one file system, and a reader (a resume, a
# study's store, a person's file manager) sees either the old file or the new one, never half.
# Why fsync before the rename: after a power cut the rename could otherwise reach the disk before
# the data, leaving an empty file under the good name. The temporary name starts with a dot and
# ends in ".tmp" plus the target's own suffix, so that writers that pick a format from the suffix
# (numpy's .npz, ffmpeg, matplotlib) write the target's format. pathlib's glob does not skip
# dot-files ("*.json" matches ".r.json.x1.tmp.json"), and another process's temporary may vanish
# between listing and reading: readers of a folder that a writer may be filling list it with
# finished_files(), which leaves temporaries out.


class OutputError(ParticlebotError, OSError):
    """An output that cannot be written where it was asked for; the message names the path and
    the reason ("cannot write runs/x: Read-only file system"). An OSError too, so that callers
    which catch OSError around a write keep working."""


def cannot_write(path: Path | str, exc: OSError) -> OutputError:
    """The one-line error for an OSError met while writing `path`."""
    if isinstance(exc, OutputError):
        return exc
    reason = exc.strerror or str(exc)
    where = exc.filename if isinstance(exc.filename, str) and exc.filename else str(path)
    return OutputError(f"cannot write {where}: {reason}")


def make_folder(path: Path | str) -> Path:
    """Creates a folder (and its parents) for outputs; OutputError naming it, and why, when it
    cannot be (a file in its place, read-only, a place such as /proc)."""
    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise OutputError(f"cannot write {folder}: a file is in the way") from None
    except OSError as exc:
        raise cannot_write(folder, exc) from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write {folder}: Permission denied")
    return folder


def temporary_beside(path: Path) -> Path:
    """A new, empty file next to `path` whose name no output glob matches (made 0600)."""
    folder = path.parent if str(path.parent) else Path(".")
    try:
        handle, name = tempfile.mkstemp(
            dir=folder, prefix=f".{path.name}.", suffix=f".tmp{path.suffix}"
        )
    except OSError as exc:  # the temporary's name is ours, not the user's: name the target
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from None
    os.close(handle)
    return Path(name)


def finished_files(folder: Path, pattern: str) -> list[Path]:
    """The files in `folder` matching `pattern`, sorted, without the temporaries of writes still
    under way (names that start with a dot); an empty list where the folder does not exist."""
    if not folder.is_dir():
        return []
    return sorted(path for path in folder.glob(pattern) if not path.name.startswith("."))


def _sync_folder(folder: Path) -> None:
    """Makes a rename inside `folder` durable (a no-op where folders cannot be opened)."""
    with contextlib.suppress(OSError):
        handle = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(handle)
        finally:
            os.close(handle)


def _commit(temporary: Path, path: Path, mode: int | None) -> None:
    if mode is not None:
        os.chmod(temporary, mode)
    else:
        # mkstemp makes files 0600; an ordinary output gets the mode a plain open() would give.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)
    os.replace(temporary, path)
    _sync_folder(path.parent if str(path.parent) else Path("."))


@contextlib.contextmanager
def atomic_path(path: Path, mode: int | None = None) -> Iterator[Path]:
    """Yields a temporary path beside `path` for a writer that wants a file name (np.savez,
    ffmpeg, savefig); when the block ends without an exception, the file is synced and renamed
    over `path`, else removed. `mode` sets its permissions (default: as open() would)."""
    temporary = temporary_beside(path)
    try:
        yield temporary
        with open(temporary, "rb+") as stream:
            os.fsync(stream.fileno())
        _commit(temporary, path, mode)
    except BaseException as exc:
        temporary.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise cannot_write(path, exc) from exc
        raise


@contextlib.contextmanager
def atomic_open(
    path: Path, *, mode: int | None = None, newline: str | None = None
) -> Iterator[IO[str]]:
    """A text file (UTF-8) open for writing that replaces `path` when the block ends without an
    exception, and leaves `path` as it was otherwise."""
    with (
        atomic_path(path, mode) as temporary,
        temporary.open("w", encoding="utf-8", newline=newline) as stream,
    ):
        yield stream


def write_text(
    path: Path, text: str, *, mode: int | None = None, newline: str | None = None
) -> None:
    """`path` holds `text` (UTF-8), whole, or keeps what it held."""
    with atomic_open(path, mode=mode, newline=newline) as stream:
        stream.write(text)


def write_bytes(path: Path, data: bytes, *, mode: int | None = None) -> None:
    """`path` holds `data`, whole, or keeps what it held."""
    with atomic_path(path, mode) as temporary:
        temporary.write_bytes(data)
