"""The particlebot command: demo, export, replay, and error messages for wrong radios."""

from __future__ import annotations

import asyncio
import csv
from importlib.metadata import version
from pathlib import Path

import pytest

from particlebot.cli import main
from particlebot.commands.demo import DemoResult, DemoScript, unresolved_neighbours
from particlebot.console.app import ConsoleApp
from particlebot.protocol import DEFINITION_HASH
from particlebot.radio.virtual import VirtualRadio
from particlebot.sim.scenarios import presets
from particlebot.sim.swarm import SimSwarm, SwarmConfig
from particlebot.swarm.api import Swarm


def test_the_demo_without_a_terminal_prints_a_summary_and_succeeds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["demo", "--particles", "6", "--run-s", "4", "--log-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "every S_n equals the particle's rank" in out
    assert "STOP confirmed by all 6 particles" in out
    (log,) = tmp_path.glob("*.jsonl")
    assert f"Log: {log}" in out


def test_the_demo_script_drives_the_live_console_to_a_clean_end() -> None:
    world = SimSwarm(SwarmConfig(scenario=presets.line(5)))
    radio = VirtualRadio(world, url="virtual://5", speed=20.0)
    swarm = Swarm(radio, log_dir=None)
    script = DemoScript(swarm, world, cycle_steps=75, locomote_s=2.0)
    app = ConsoleApp(swarm, script=script, linger_s=0.1)

    async def run() -> int | None:
        async with app.run_test(size=(140, 40)) as pilot:
            while app.is_running:
                await pilot.pause(0.1)
        return app.return_value

    try:
        code = asyncio.run(asyncio.wait_for(run(), timeout=60))
    finally:
        swarm.close()
    assert script.stop_report is not None and script.stop_report.confirmed
    assert code == 0
    assert [r.s_n for r in script.results()] == [1, 2, 3, 4, 5]


def test_export_and_replay_read_the_log_the_demo_wrote(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["demo", "--particles", "3", "--run-s", "1", "--log-dir", str(tmp_path)]) == 0
    (log,) = tmp_path.glob("*.jsonl")
    capsys.readouterr()
    csv_path = tmp_path / "out.csv"
    assert main(["export", str(log), "-o", str(csv_path), "--type", "STATUS"]) == 0
    rows = list(csv.DictReader(csv_path.open()))
    assert rows and {row["type"] for row in rows} == {"STATUS"}
    assert {row["sender"] for row in rows} == {"1", "2", "3"}
    assert main(["replay", str(log), "--speed", "max", "--no-ui"]) == 0
    out = capsys.readouterr().out
    for particle in (1, 2, 3):
        assert f"particle   {particle}  state IDLE" in out


@pytest.mark.parametrize(
    ("argv", "complaint"),
    [
        (["console"], "say which radio"),
        (["console", "--radio", "/dev/ttyUSB0"], "Did you mean serial:///dev/ttyUSB0"),
        (["log", "--radio", "serial:///nonexistent/ttyUSB9"], "No serial port"),
        (["console", "--radio", "carrier-pigeon://1"], "unknown radio kind"),
        (["export", "/nonexistent/log.jsonl"], "no log file"),
    ],
)
def test_wrong_radios_and_files_get_a_message_saying_what_to_do(
    argv: list[str],
    complaint: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("PARTICLEBOT_RADIO", raising=False)
    assert main(argv) == 2
    assert complaint in capsys.readouterr().err


@pytest.mark.parametrize("command", ["console", "log"])
def test_the_radio_help_names_every_kind_of_radio(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        main([command, "--help"])
    # argparse wraps the help to the terminal's width; compare it as one line.
    text = " ".join(capsys.readouterr().out.split())
    for example in ("serial://", "xbee://", "virtual://10", "emulated://5"):
        assert example in text


def _result(particle_id: int, rank: int, s_n: int, intensity: int) -> DemoResult:
    return DemoResult(
        particle_id=particle_id,
        start_distance=0.155 * rank,
        end_distance=0.155 * rank,
        rank=rank,
        s_n=s_n,
        state="IDLE",
        intensity=intensity,
    )


def test_a_mismatch_from_readings_within_the_counting_tolerance_is_explained() -> None:
    results = [_result(1, 1, 1, 900), _result(2, 2, 2, 171), _result(3, 3, 2, 165)]
    lines = unresolved_neighbours(results)
    assert len(lines) == 1
    assert "particles 2 and 3 read 171 and 165" in lines[0]


def test_neighbours_whose_readings_differ_enough_are_not_blamed() -> None:
    results = [_result(1, 1, 1, 900), _result(2, 2, 2, 700), _result(3, 3, 3, 650)]
    assert unresolved_neighbours(results) == []


def test_version_names_the_package_and_the_protocol(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as ended:
        main(["--version"])
    assert ended.value.code == 0
    assert capsys.readouterr().out == (
        f"particlebot {version('particlebot')} (protocol definition {DEFINITION_HASH:08X})\n"
    )
