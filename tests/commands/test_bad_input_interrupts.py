"""Ctrl-C at any moment: exit status 130, one line, no traceback, and what was written is whole
(a video cut short is removed, a run folder that never began is not left behind)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.commands.refusals import refusal


def interrupt(*args: Any, **kwargs: Any) -> Any:
    raise KeyboardInterrupt


def assert_interrupted(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    code, err = refusal(argv, capsys)
    assert code == 130, err
    assert "Traceback" not in err
    assert "KeyboardInterrupt" not in err
    return err


def test_ctrl_c_while_simulate_loads_its_kernels_is_130_and_leaves_no_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # As if Ctrl-C came while numba compiled or loaded the kernels for the world.
    monkeypatch.setattr("particlebot.sim.scenarios.build.build_world", interrupt)
    assert_interrupted(["simulate", "--duration", "1", "-o", str(tmp_path / "run")], capsys)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_before_any_command_handles_it_is_130_in_one_line(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # A command with no handling of its own (stats reading its sources, say).
    monkeypatch.setattr("particlebot.commands.stats.run", interrupt)
    err = assert_interrupted(["stats", "x.csv"], capsys)
    assert err == "particlebot: interrupted\n"


def test_ctrl_c_while_render_writes_leaves_no_video_and_no_truth(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from particlebot.analysis.render import Renderer

    drawn = Renderer.render
    count = [0]

    def render_then_stop(self: Renderer, frame: Any) -> Any:
        count[0] += 1
        if count[0] == 3:
            raise KeyboardInterrupt
        return drawn(self, frame)

    monkeypatch.setattr(Renderer, "render", render_then_stop)
    video = tmp_path / "blob.avi"
    argv = ["render", "-o", str(video), "--size", "160x90", "--duration-s", "2", "--fps", "5"]
    assert_interrupted(argv, capsys)
    assert count[0] == 3
    assert list(tmp_path.iterdir()) == []
