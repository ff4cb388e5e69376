"""Extreme numbers (1e308, inf, NaN, 10^400) in options, scenario files and published .cfg files:
refused where they come in, in one line, before anything runs or is written."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.commands.refusals import assert_refused, assert_refused_here, particlebot


@pytest.mark.parametrize(
    ("text", "complaint"),
    [
        ("[lamp]\nx = 1e308\n", "lamp.x: must be a number -10000..10000, not 1e+308"),
        ("[physics]\ndt = 1e-300\n", "physics.dt: must be a number 1e-06..1"),
        ("[physics]\ndt = 100\n", "physics.dt: must be a number 1e-06..1"),
        ("[physics]\nspring = 1e308\n", "physics.spring: must be a number 0..1e+09"),
        ("[physics]\nspring = 1e6\n", "dt 0.01 s is too long for a contact spring of 2e+06"),
        ("[controller.published]\nrise_s = 1e-300\n", "rise_s: must be a number 0.001..10000"),
        ("duration_s = 1e300\n", "duration_s: must be a number > 0 and <= 1e+08"),
        ("duration_s = 0.001\n", "less than one step of physics.dt = 0.01 s"),
        ("seed = 100000000000000000000000\n", "seed: must be a whole number 0.."),
        ("[swarm]\nat = [0, inf]\n", "swarm.at: must be a number -10000..10000, not inf"),
    ],
)
def test_a_scenario_number_beyond_a_real_swarm_is_one_line(
    text: str,
    complaint: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    (tmp_path / "bad.toml").write_text(text)
    monkeypatch.chdir(tmp_path)
    assert_refused_here(["simulate", "bad.toml", "-o", "run"], complaint, capsys)
    assert not (tmp_path / "run").exists()


def test_a_refusal_is_one_line_from_the_command_itself(tmp_path: Path) -> None:
    # As a person meets it: the installed command in a process of its own.
    (tmp_path / "bad.toml").write_text("[physics]\nspring = 1e308\n")
    done = particlebot("simulate", "bad.toml", "-o", "run", cwd=tmp_path)
    assert_refused(done, "physics.spring: must be a number 0..1e+09, not 1e+308")
    assert done.returncode == 2
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("text", "complaint"),
    [
        ("nCells\n10\n\nlight_x\n1e308\n", "light_x, light_y: must be a number -10000..10000"),
        ("nCells\n10\n\nrise_period\n1e-300\n", "rise_period: rise_s must be a number"),
        ("nCells\n10\n\nmax_time\n1e300\n", "max_time: 1e+300 s in steps of 0.01 s"),
    ],
)
def test_a_published_cfg_number_beyond_a_real_swarm_is_one_line(
    text: str,
    complaint: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    (tmp_path / "bad.cfg").write_text(text)
    monkeypatch.chdir(tmp_path)
    assert_refused_here(["simulate", "bad.cfg", "-o", "run"], complaint, capsys)
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("argv", "complaint"),
    [
        (["simulate", "--duration", "1e300"], "--duration: must be a number > 0 and <= 1e+08"),
        (["simulate", "--lamp", "1e308,0"], "--lamp: must be a number -10000..10000"),
        (["render", "-o", "v.mp4", "--fps", "inf"], "--fps: must be a number > 0 and <= 1000"),
        (["render", "-o", "v.mp4", "--fps", "1e9"], "--fps: must be a number > 0 and <= 1000"),
        (["track", "v.mp4", "--particle-diameter-cm", "inf"], "--particle-diameter-cm: must"),
        (["track", "v.mp4", "--camera-height-cm", "nan"], "--camera-height-cm: must be"),
        (["track", "v.mp4", "--camera-height-cm", "-5"], "--camera-height-cm: must be"),
        (["track", "v.mp4", "--lamp-height-cm", "nan"], "--lamp-height-cm: must be"),
        (["stats", "x.csv", "--average-s", "inf"], "--average-s: must be a number 0..1e+08"),
        (
            ["calibrate", "sensors", "--readings", "x.csv", "--distances", "1e308"],
            "--distances: each value must be a number 0..1e+06",
        ),
        (["study", "speed", "--duration", "1e400", "--list"], "--duration: '1e400' is longer"),
        (["study", "speed", "--set", "spring=1e308", "--list"], "spring must be a number 0..1e"),
    ],
)
def test_an_option_beyond_a_real_swarm_is_one_line(
    argv: list[str],
    complaint: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(tmp_path)
    assert_refused_here(argv, complaint, capsys)
    assert list(tmp_path.iterdir()) == []
