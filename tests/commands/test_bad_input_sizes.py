"""Sizes beyond the machine: a swarm, a listing or a video too large is refused in one line that
says what it would need and what the machine has, before anything is allocated (no MemoryError,
no hang)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.commands.refusals import assert_refused, particlebot, refusal

HUGE = str(10**30)


@pytest.mark.parametrize(
    ("argv", "complaint"),
    [
        (["simulate", "--particles", "100000000000", "-o", "run"], "would need about 9"),
        (["simulate", "big.toml", "-o", "run"], "particles would need about"),
        (["simulate", "big.cfg", "-o", "run"], "particles would need about"),
        (["study", "speed", "--sizes", "1000000000", "--list"], "--sizes: a swarm of 1,000,000,"),
        (["study", "speed", "--sizes", "10", "--seeds", HUGE, "--list"], "a study holds at most"),
        (["render", "-o", "v.mp4", "--particles", "1000000000"], "particles would need about"),
        (["render", "-o", "v.mp4", "--size", "100000x100000"], "--size must be 64x64 to 8192"),
    ],
)
def test_a_job_beyond_the_machine_is_refused_before_it_starts(
    argv: list[str],
    complaint: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    (tmp_path / "big.toml").write_text(f"[swarm]\nparticles = {HUGE}\n")
    (tmp_path / "big.cfg").write_text(f"nCells\n{HUGE}\n")
    monkeypatch.chdir(tmp_path)
    code, err = refusal(argv, capsys)
    assert code == 2
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    assert complaint in err
    if "would need" in complaint:
        assert "this machine has" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.cfg", "big.toml"]


def test_a_swarm_beyond_the_machine_is_one_line_from_the_command(tmp_path: Path) -> None:
    done = particlebot("simulate", "--particles", HUGE, "-o", "run", cwd=tmp_path, timeout=120)
    assert_refused(done, f"a swarm of {10**30:,} particles would need about")
    assert "this machine has" in done.stderr
    assert list(tmp_path.iterdir()) == []
