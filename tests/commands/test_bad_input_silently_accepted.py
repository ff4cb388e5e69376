"""Input that used to be taken without a word although it cannot be right: an empty scenario,
a camera below what it films, two particles on one radio address, a port that is not a Dask
scheduler. Each is refused in one line."""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.commands.refusals import assert_refused_here

KEY = "00112233445566778899AABBCCDDEEFF"


@pytest.mark.parametrize("text", ["", "# a scenario\n\n# nothing yet\n"], ids=["empty", "comments"])
def test_a_scenario_with_no_keys_is_refused(
    text: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "s.toml").write_text(text)
    argv = ["simulate", str(tmp_path / "s.toml"), "-o", str(tmp_path / "run")]
    assert_refused_here(argv, "holds no keys (empty, or only comments)", capsys)
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("flags", "complaint"),
    [
        (["--camera-height-cm", "30"], "--lamp-height-cm 35 must be below --camera-height-cm 30"),
        (
            ["--outline-height-cm", "300"],
            "--outline-height-cm 300 must be below --camera-height-cm 225",
        ),
    ],
)
def test_a_camera_below_what_it_films_is_refused(
    flags: list[str], complaint: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert_refused_here(["track", str(tmp_path / "v.mp4"), *flags], complaint, capsys)


def fleet_file(path: Path, particles: str) -> Path:
    path.write_text(f'version = 1\n[radio]\npan_id = 0x1234\nchannel = 0x0C\nkey = "{KEY}"\n')
    with path.open("a") as stream:
        stream.write(particles)
    path.chmod(0o600)
    return path


@pytest.mark.parametrize(
    ("particles", "complaint"),
    [
        (
            '[particles.1]\nradio_address = "0013A20040A1B2C3"\n'
            '[particles.2]\nradio_address = "0013a200:40a1b2c3"\n',
            "[particles.2]: radio_address 0013A20040A1B2C3 is [particles.1]'s already",
        ),
        ("[particles.1]\ncolour = 3\n", "unknown key 'colour' in [particles.1]"),
    ],
)
def test_a_fleet_file_that_cannot_be_right_fails_fleet_show(
    particles: str, complaint: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = fleet_file(tmp_path / "fleet.toml", particles)
    assert_refused_here(["fleet", "show", "--fleet", str(path)], complaint, capsys)


@pytest.fixture
def not_dask() -> Iterator[str]:
    """A local port that answers every connection with a web server's reply."""
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def answer() -> None:
        while True:
            try:
                connection, _ = server.accept()
            except OSError:
                return  # closed: the test is over
            with connection:
                connection.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nhi" * 64)

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{port}"
    server.close()
    thread.join(timeout=5)


def test_a_scheduler_address_that_is_not_dask_is_one_line(
    not_dask: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["study", "speed", "--quick", "--scheduler", not_dask, "--results", str(tmp_path / "r")]
    assert_refused_here(argv, f"{not_dask} answers, but not as a Dask scheduler", capsys)
    assert not (tmp_path / "r").exists()  # refused before anything was written


def test_an_unusual_value_runs_with_a_warning(tmp_path: Path) -> None:
    from particlebot.sim.scenarios.build import build_world
    from particlebot.sim.scenarios.toml_file import parse_scenario

    text = "duration_s = 1\n[swarm]\nparticles = 3\n[physics]\ndt = 0.03\nshear = 0\n"
    built = build_world(parse_scenario(text, tmp_path / "s.toml"))
    assert any("physics.dt: dt x sqrt(spring) is 1.3, near the 2" in n for n in built.notes)
