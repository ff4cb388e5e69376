"""Running `particlebot` as a person would, in a child process, and checking that a refusal is
one line on stderr with a non-zero status and no traceback."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from particlebot.cli import main

HOST = Path(__file__).resolve().parents[2] / "host"


def particlebot(
    *args: str, cwd: Path, timeout: float = 300, stdin: str | None = None
) -> subprocess.CompletedProcess[str]:
    """`particlebot ARGS` from this source tree, in `cwd`."""
    env = {**os.environ, "PYTHONPATH": f"{HOST}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    env.pop("PARTICLEBOT_RADIO", None)
    return subprocess.run(
        [sys.executable, "-m", "particlebot.cli", *args],
        cwd=cwd,
        env=env,
        input=stdin,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def assert_refused(done: subprocess.CompletedProcess[str], complaint: str) -> None:
    """A refusal: a non-zero status other than a signal's, and `complaint` in the one line."""
    assert done.returncode not in (0, -signal.SIGSEGV), done
    assert done.returncode > 0, done
    assert "Traceback" not in done.stderr, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert complaint in lines[0], lines[0]


def refusal(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """The exit status and stderr of `particlebot ARGV` run in this process (quicker than a
    child process where only the message and status matter)."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse ends the process itself
        code = exc.code if isinstance(exc.code, int) else 1
    return code, capsys.readouterr().err


def assert_refused_here(
    argv: list[str], complaint: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """As assert_refused, for `particlebot ARGV` run in this process."""
    code, err = refusal(argv, capsys)
    assert code > 0, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert complaint in lines[0], lines[0]
