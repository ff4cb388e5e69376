"""`particlebot simulate` end to end: a quick run, a scenario file, a published .cfg, bad input
in one line with nothing written, and Ctrl-C followed by --resume."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from particlebot.cli import main
from particlebot.sim.world.world import PARALLEL_FROM
from tests.support.repo import REPO_ROOT

REPO = REPO_ROOT
SUMMARY_KEYS = {
    "particles", "steps", "wall_s", "particle_steps_per_s", "realtime_factor", "centroid_start",
    "centroid_end", "distance_to_light_start", "distance_to_light_end",
}  # fmt: skip


def last_json(text: str) -> dict[str, object]:
    data = json.loads(text.strip().splitlines()[-1])
    assert isinstance(data, dict)
    return data


def test_a_quick_run_from_flags_ends_with_one_json_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "quick"
    argv = ["simulate", "--particles", "8", "--duration", "3", "--seed", "2"]
    argv += ["--lamp", "-2,0.5,0.3"]
    code = main([*argv, "--dump-interval", "1", "-o", str(folder), "--json"])

    assert code == 0
    summary = last_json(capsys.readouterr().out)
    assert summary.keys() >= SUMMARY_KEYS
    assert summary["particles"] == 8 and summary["steps"] == 300
    assert summary["finished"] is True
    distance = summary["distance_to_light_start"]
    centroid = summary["centroid_start"]
    assert isinstance(distance, float) and isinstance(centroid, list)
    assert distance == pytest.approx(((centroid[0] + 2) ** 2 + (centroid[1] - 0.5) ** 2) ** 0.5)
    scenario = (folder / "scenario.toml").read_text()
    assert "height = 0.3" in scenario and "seed = 2" in scenario
    assert len((folder / "run.csv").read_text().splitlines()) == 2 + 4


@pytest.mark.slow
def test_threads_sets_how_many_threads_a_large_swarm_steps_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = numba.get_num_threads()  # numba's count is per thread: pytest's own, here
    argv = ["simulate", "--particles", str(PARALLEL_FROM), "--duration", "0.5"]
    assert main([*argv, "--threads", "1", "-o", str(tmp_path / "one"), "--json"]) == 0
    assert last_json(capsys.readouterr().out)["threads"] == 1
    assert numba.get_num_threads() == before  # the override does not outlive its run
    assert main([*argv, "-o", str(tmp_path / "default"), "--json"]) == 0
    # Without --threads the world picks one thread or all from the step times it measures.
    assert last_json(capsys.readouterr().out)["threads"] in {1, before}


def test_a_published_cfg_runs_as_is(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cfg = tmp_path / "tiny.cfg"
    cfg.write_text("# a tiny run\nnCells\n6\nnDead\n-1\nradFactor\n1.5\nmax_time\n2\nseed\n5\n"
                   "dump_interval\n1\ncsv_filename\ntiny_data.csv\n")  # fmt: skip

    code = main(["simulate", str(cfg), "-o", str(tmp_path / "run"), "--json"])

    assert code == 0
    summary = last_json(capsys.readouterr().out)
    assert summary["particles"] == 5 and summary["objects"] == 1
    lines = (tmp_path / "run" / "tiny_data.csv").read_text().splitlines()
    assert lines[0] == "Seed, 5" and len(lines) == 2 + 3


def test_flags_change_a_scenario_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = REPO / "scenarios" / "carry.toml"

    code = main(
        ["simulate", str(scenario), "--particles", "6", "--duration", "1", "--dump-interval",
         "0.5", "-o", str(tmp_path / "run"), "--json"]
    )  # fmt: skip

    assert code == 0
    summary = last_json(capsys.readouterr().out)
    assert summary["particles"] == 6 and summary["objects"] == 1 and summary["steps"] == 100


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--particles", "0"], "--particles: must be a whole number >= 1"),
        (["--duration", "nan"], "--duration: must be a number > 0"),
        (["--seed", "-1"], "--seed: must be a whole number 0.."),
        (["--lamp", "1"], "--lamp: must be X,Y or X,Y,H"),
        (["--lamp", "1,inf"], "--lamp: must be a number"),
        (["--lamp", "1,2,-3"], "--lamp: must be a number > 0"),
        (["--controller", "magic"], "invalid choice"),
        (["no-such-file.toml"], "no such scenario file"),
        (["--resume", "nowhere"], "not a run folder"),
        (["--threads", "0"], "--threads: must be a whole number >= 1"),
        (["--threads", "100000"], "--threads 100000: numba here runs at most"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_nothing_written(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    message: str,
) -> None:
    folder = tmp_path / "run"
    monkeypatch.chdir(tmp_path)  # where a default runs/ folder would appear

    with pytest.raises(SystemExit) as stopped:
        code = main(["simulate", *argv, "-o", str(folder)] if "--resume" not in argv else
                    ["simulate", *argv])  # fmt: skip
        raise SystemExit(code)

    assert stopped.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("particlebot: simulate: ")
    assert message in err[0]
    assert not folder.exists() and not (tmp_path / "runs").exists()


def test_a_bad_scenario_file_names_file_line_and_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[swarm]\nparticles = 5\n\n[lamp]\nx = -2\nhieght = 0.3\n")

    code = main(["simulate", str(path), "-o", str(tmp_path / "run")])

    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"particlebot: simulate: {path}:6: lamp.hieght: unknown key (did you mean 'height'?); "
        "keys here: x, y, height"
    ]
    assert not (tmp_path / "run").exists()


def run_cli(*argv: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "particlebot.cli", "simulate", *argv],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.slow
def test_ctrl_c_keeps_a_snapshot_and_resume_finishes_the_same_run(tmp_path: Path) -> None:
    quick = ["--particles", "20", "--dump-interval", "20", "--seed", "4"]
    # Far too long to finish before the signal, whatever the machine's load.
    stopped = run_cli(*quick, "--duration", "100000", "-o", "stopped", "--json", cwd=tmp_path)
    assert stopped.stderr is not None
    # The progress bar's first line comes after the first chunk of steps: the run is running.
    for line in stopped.stderr:
        if line.startswith("simulate "):
            break
    stopped.send_signal(signal.SIGINT)
    out, err = stopped.communicate(timeout=240)

    assert stopped.returncode == 130, err
    summary = last_json(out)
    assert summary["finished"] is False
    assert "continue with: particlebot simulate --resume stopped" in out
    assert (tmp_path / str(summary["snapshot"])).exists()
    stop_s = summary["t_s"]
    assert isinstance(stop_s, float) and 0 < stop_s < 100000

    # Resumed to an end two rows past the stop, it equals a run that went there at once.
    end = str((int(stop_s // 20) + 2) * 20)
    resumed = run_cli("--resume", "stopped", "--duration", end, "--json", cwd=tmp_path)
    out, err = resumed.communicate(timeout=240)
    assert resumed.returncode == 0, err
    assert last_json(out)["steps"] == int(end) * 100
    straight = run_cli(*quick, "--duration", end, "-o", "straight", cwd=tmp_path)
    assert straight.wait(timeout=240) == 0, straight.communicate()[1]

    csv = (tmp_path / "stopped" / "run.csv").read_text()
    assert csv == (tmp_path / "straight" / "run.csv").read_text()
    assert len(csv.splitlines()) == 2 + int(end) // 20 + 1
    assert f"duration_s = {float(end)!r}" in (tmp_path / "stopped" / "scenario.toml").read_text()


def test_resume_with_an_end_before_the_snapshot_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "run"
    assert main(["simulate", "--particles", "5", "--duration", "2", "-o", str(folder)]) == 0
    capsys.readouterr()

    code = main(["simulate", "--resume", str(folder), "--duration", "1"])

    assert code == 2
    assert "is at 2 s already" in capsys.readouterr().err


def test_render_films_a_run_folder_with_per_particle_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "run"
    argv = ["simulate", "--particles", "6", "--duration", "4", "--dump-interval", "1"]
    assert main([*argv, "--per-particle", "-o", str(folder)]) == 0
    video = tmp_path / "run.mp4"

    code = main(["render", str(folder), "-o", str(video), "--size", "320x180", "--fps", "1"])

    assert code == 0, capsys.readouterr().err
    assert video.stat().st_size > 0
    truth = video.with_suffix(".truth.csv").read_text().splitlines()
    assert len(truth) >= 1 + 4  # a header, then a frame per second of the run
