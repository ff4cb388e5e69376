"""Writing outputs whole or not at all: a file is written under a temporary name beside it and
renamed over its place only when complete, and a place that cannot be written is one line."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from particlebot.errors import ParticlebotError

_UMASK = os.umask(0o022)
os.umask(_UMASK)  # read once, at import, before any thread of ours creates files


class OutputError(ParticlebotError):
    """An output that cannot be written where it was asked for; the message names the path and
    the reason ("particlebot: cannot write runs/x: Read-only file system")."""


def cannot_write(path: Path | str, exc: OSError) -> OutputError:
    """The one-line error for an OSError met while writing `path`."""
    reason = exc.strerror or str(exc)
    where = exc.filename if isinstance(exc.filename, str) and exc.filename else str(path)
    return OutputError(f"cannot write {where}: {reason}")


@contextlib.contextmanager
def atomic_open(path: Path | str, mode: str = "w", **kwargs: Any) -> Iterator[IO[Any]]:
    """A file object for `path` that appears there only when the block ends without an error:
    until then it is a hidden temporary file in the same folder (so the rename cannot cross
    file systems), removed on any error or Ctrl-C. mode is "w" or "wb"; OutputError when the
    folder cannot take it."""
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open writes whole files: mode 'w' or 'wb', not {mode!r}")
    target = Path(path)
    try:
        handle, temporary = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=".partial", dir=target.parent
        )
    except OSError as exc:
        raise cannot_write(target, exc) from None
    try:
        with os.fdopen(handle, mode, **kwargs) as stream:
            yield stream
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, 0o666 & ~_UMASK)  # mkstemp's 0600 is for secrets, not outputs
        os.replace(temporary, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        if isinstance(exc, OSError):
            raise cannot_write(target, exc) from None
        raise


def atomic_write_bytes(path: Path | str, data: bytes) -> None:
    """Writes `data` to `path` whole or not at all (see atomic_open)."""
    with atomic_open(path, "wb") as stream:
        stream.write(data)


def atomic_write_text(path: Path | str, text: str, encoding: str = "utf-8") -> None:
    """Writes `text` to `path` whole or not at all (see atomic_open)."""
    with atomic_open(path, "w", encoding=encoding, newline="") as stream:
        stream.write(text)


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
