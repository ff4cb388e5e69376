"""The particlebot command: demo, export, replay, and error messages for wrong radios."""

from __future__ import annotations

import asyncio
import csv
import json
import tomllib
from pathlib import Path

import pytest
from rich.text import Text
from textual.widgets import Static

import particlebot
from particlebot import resources
from particlebot.cli import main
from particlebot.commands.demo import DemoScript
from particlebot.console.app import ConsoleApp
from particlebot.protocol import DEFINITION_HASH
from particlebot.radio import open_radio
from particlebot.radio.virtual import VirtualRadio
from particlebot.swarm.api import Swarm

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.e2e
def test_the_demo_without_a_terminal_prints_the_runs_table_s2_figures_and_json_last(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["demo", "--run-s", "90", "--no-animation", "--json"]  # ten particles, seed 3
    code = main([*argv, "--log-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "START method A with phototaxis on, 90 s, then STOP" in out
    assert "STOP confirmed by all 10 particles" in out
    assert "one-tailed t-test p = " in out
    (log,) = tmp_path.glob("*.jsonl")
    assert f"Log: {log}" in out
    figures = json.loads(out.strip().splitlines()[-1])
    assert figures["particles"] == 10 and figures["method"] == "A"
    assert figures["simulated_s"] == pytest.approx(90, abs=2)
    assert figures["centroid_toward_lamp_m"] > 0.01  # it crawls toward the lamp
    assert figures["speed_pct_min_diameter_per_cycle"] > 0
    assert 0 <= figures["p_value"] <= 1


def test_the_demo_script_drives_the_live_console_with_its_map_to_a_clean_end() -> None:
    radio = open_radio("virtual://5?scenario=blob&start=0.6&seed=2&speed=20")
    assert isinstance(radio, VirtualRadio)
    swarm = Swarm(radio, log_dir=None)
    script = DemoScript(swarm, method="A", cycle_steps=75, run_s=20.0)
    drawn: list[Text] = []  # every top view the console drew, as drawn

    def world_map(width: int, height: int) -> Text:
        drawn.append(script.world_map(width, height))
        return drawn[-1]

    app = ConsoleApp(swarm, script=script, linger_s=0.1, world_map=world_map)
    maps: list[str] = []

    async def run() -> int | None:
        async with app.run_test(size=(140, 40)) as pilot:
            while app.is_running:
                maps.append(str(app.query_one("#map", Static).render()))
                await pilot.pause(0.1)
        return app.return_value

    try:
        code = asyncio.run(asyncio.wait_for(run(), timeout=60))
    finally:
        swarm.close()
    assert script.stop_report is not None and script.stop_report.confirmed
    assert code == 0
    assert "1 col = " in maps[-1]  # the top view is on the screen beside the table
    # The last one: the lamp, five particles, the centroid (a + between particles, or the
    # particle it falls on reversed) and the scale.
    shown = str(drawn[-1])
    assert shown.count("*") == 1 and "1 col = " in shown
    assert sum(shown.count(c) for c in "O@") == 5
    assert "+" in shown or any("reverse" in str(span.style) for span in drawn[-1].spans)


def test_export_and_replay_read_the_log_the_demo_wrote(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["demo", "--particles", "3", "--run-s", "61", "--no-animation"]
    assert main([*argv, "--log-dir", str(tmp_path)]) == 0
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


def test_version_names_the_package_and_the_protocol(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as ended:
        main(["--version"])
    assert ended.value.code == 0
    first, second = capsys.readouterr().out.splitlines()
    assert (
        first
        == f"particlebot {particlebot.__version__} (protocol definition {DEFINITION_HASH:08X})"
    )
    # A clone flashes what `make firmware` built; a wheel names the definition its image speaks.
    assert second == f"firmware image {resources.firmware_image()}"


def test_the_version_comes_from_one_place() -> None:
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {
        "attr": "particlebot.__version__"
    }
