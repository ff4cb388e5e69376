"""The `emulated://K` radio: URL checks, and the Swarm API driving emulated particles."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from particlebot.cli import main
from particlebot.protocol import State
from particlebot.radio import InvalidRadioUrlError, RadioError, open_radio, parse_radio_url
from particlebot.radio.emulated import emulated_config
from particlebot.sim.scenarios.scenario import PlacementKind
from particlebot.sim.swarm import Level
from particlebot.swarm.api import Swarm


@pytest.mark.parametrize(
    "url",
    [
        "emulated://0",
        "emulated://33",
        "emulated://five",
        "emulated://5?loss=1.5",
        "emulated://5?delay_ms=-1",
        "emulated://5?lamp=0,0",
        "emulated://5?colour=red",
        "emulated://5?speed=0",
    ],
)
def test_bad_emulated_urls_are_refused_with_advice(url: str) -> None:
    with pytest.raises(InvalidRadioUrlError):
        open_radio(url)


def test_emulated_url_options_reach_the_swarm_configuration() -> None:
    config = emulated_config(
        parse_radio_url("emulated://7?loss=0.2&delay_ms=5&spacing=0.2&start=0.3&seed=4")
    )
    assert config.level is Level.EMULATED
    swarm = config.resolved_scenario().swarm
    assert swarm.particles == 7 and swarm.placement is PlacementKind.LINE
    assert swarm.spacing == 0.2 and swarm.at == (0.3, 0.0)
    assert config.loss == 0.2
    assert config.delay_us == 5000
    assert config.seed == 4 and config.scenario.seed == 4
    assert not config.keep_history  # a console may run for hours


def test_a_missing_firmware_image_is_reported_with_the_command_that_builds_it() -> None:
    with pytest.raises(RadioError, match="make firmware harness"):
        open_radio("emulated://2?elf=build/firmware/no-such-image.elf")


@pytest.mark.e2e
@pytest.mark.usefixtures("built_images")
def test_the_swarm_api_finds_starts_and_stops_emulated_particles_at_20_percent_loss() -> None:
    # speed=max: the calls below step the emulated swarm themselves, as fast as it runs.
    with Swarm.open("emulated://3?speed=max&loss=0.2&seed=2", log_dir=None) as swarm:
        heard = swarm.wait_for(count=3, timeout=30)
        assert [p.id for p in heard] == [1, 2, 3]
        report = swarm.set("cycle_steps", 75)
        assert report.values == {1: 75, 2: 75, 3: 75}
        run = swarm.start("D")
        assert run.particles == (1, 2, 3)

        def ranked() -> bool:
            return all(p.run_id == run.run_id and p.s_n for p in swarm.particles())

        assert swarm.wait_until(ranked, timeout=30)
        assert [p.s_n for p in swarm.particles()] == [1, 2, 3]
        stop = swarm.stop()
        assert stop.confirmed, stop.text
        assert stop.stopped == (1, 2, 3)
        assert all(p.state == State.IDLE for p in swarm.particles())


@pytest.mark.e2e
@pytest.mark.usefixtures("built_images")
def test_an_experiment_runs_on_emulated_particles_and_says_how_far_they_moved(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    experiment = tmp_path / "experiment.toml"
    experiment.write_text(
        'radio = "emulated://2?speed=max&loss=0.1"\n'
        "[[trial]]\n"
        'method = "D"\n'
        "cycle_steps = 50\n"
        "duration_s = 6\n"
    )
    assert main(["run", str(experiment), "--log-dir", str(tmp_path / "logs")]) == 0
    out = capsys.readouterr().out
    assert "run 1 started by 2 particle(s)" in out
    (folder,) = (tmp_path / "logs").glob("experiment-*")
    with (folder / "summary.csv").open() as file:
        (row,) = csv.DictReader(file)
    assert (row["stop_confirmed"], row["particles_lost"]) == ("yes", "0")
    # The image's servo moves its body in the world: the centroid's change is known.
    assert abs(float(row["toward_lamp_m"])) < 0.05
