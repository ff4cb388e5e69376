"""`particlebot track`, `stats` and `render` from the command line: outputs, and one clear line
(exit 2, no traceback) for every bad input."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from particlebot.analysis.synthetic import BlobSpec, breathing_blob
from particlebot.analysis.trackfile import read_track
from particlebot.cli import main
from particlebot.sim.runs.simcsv import write_published_csv
from tests.analysis.conftest import Clip

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_track_then_stats_on_a_synthetic_run(
    paper_clip: Clip, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / paper_clip.path.name
    video.symlink_to(paper_clip.path)
    overlay = tmp_path / "seen.avi"
    assert main(["track", str(video), "--rate", "0", "--overlay", str(overlay)]) == 0
    out = capsys.readouterr().out
    track_path = tmp_path / "paper.track.csv"
    assert f"Track: {track_path} (61 frames analysed: 61 ok" in out
    assert "Lamp: (55." in out
    track = read_track(track_path)
    assert len(track.t_s) == len(paper_clip.truth)
    assert track.t_s[1] == pytest.approx(1 / paper_clip.fps, abs=1e-3)
    assert track.meta["geometry"] == "field 285x160 cm, camera straight down"
    assert (tmp_path / "paper.sheet.png").read_bytes()[:8] == PNG_MAGIC
    capture = cv2.VideoCapture(str(overlay))
    assert int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) == 61
    capture.release()

    # 40 s of drift at 3 mm/s, sampled every 10 s; the lamp comes from the track's header.
    assert (
        main(["stats", str(track_path), "--interval-s", "10", "--csv", str(tmp_path / "t.csv")])
        == 0
    )
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("paper.track.csv "))
    cells = row.split()
    assert cells[1:4] == ["track", "4", "9"]
    assert 1.5 < float(cells[6]) < 4.5  # mm/s, the region's breathing included
    assert "(the track's header)" in out
    assert (tmp_path / "paper.track.stats.png").read_bytes()[:8] == PNG_MAGIC
    assert (tmp_path / "t.csv").read_text().splitlines()[1].startswith("paper.track.csv,track,4,9,")


@pytest.mark.slow
def test_track_with_marked_points_on_a_tilted_camera(
    tilted_clip: Clip, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    points = []
    for corner in [(0.0, 0.0), (285.0, 0.0), (285.0, 160.0), (0.0, 160.0)]:
        ((u, v),) = tilted_clip.geometry.to_image([corner])
        # "--point=" form: a corner outside the picture has a negative pixel coordinate.
        points.append(f"--point={u:.1f},{v:.1f}={corner[0]:g},{corner[1]:g}")
    output = tmp_path / "t.csv"
    code = main(
        ["track", str(tilted_clip.path), "-o", str(output), "--no-sheet", "--rate", "0.5", *points]
    )
    assert code == 0, capsys.readouterr().err
    track = read_track(output)
    assert "4 marked floor points" in track.meta["geometry"]
    assert len(track.t_s) == 21  # every third frame of 61
    truth = tilted_clip.truth[::3]
    error = np.hypot(
        track.x_cm - [t.region_x_cm for t in truth], track.y_cm - [t.region_y_cm for t in truth]
    )
    assert float(error.max()) < 3.0


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("missing.mp4", None, "no such video"),
        ("empty.mp4", b"", "is empty"),
        ("notes.avi", b"not a video", "cannot decode"),
        ("", None, "is a folder"),
    ],
)
def test_a_video_that_cannot_be_tracked_gets_one_line(
    name: str,
    content: bytes | None,
    message: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    assert main(["track", str(path)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.glob("*.track.csv"))


def test_bad_geometry_options_get_one_line(
    paper_clip: Clip, capsys: pytest.CaptureFixture[str]
) -> None:
    for options, message in [
        (["--field", "285"], "--field must look like"),
        (["--point", "1,1=0,0"], "at least 4 marked points"),
        (["--lamp", "10,20,-3"], "--lamp must look like X,Y,R"),
        (["--checkerboard", str(paper_clip.path)], "no checkerboard with 9x6"),
    ]:
        assert main(["track", str(paper_clip.path), *options]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err


def test_stats_errors_get_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "session.jsonl").write_text("{}\n")
    for argv, message in [
        (["stats", str(tmp_path / "nothing.csv")], "no such file"),
        (["stats", str(tmp_path / "session.jsonl")], "no positions in this log"),
        (["stats", str(tmp_path), "--interval-s", "0"], "--interval-s: must be a number > 0"),
        (["stats", str(tmp_path), "--lamp", "1"], "--lamp must look like"),
    ]:
        code: object
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse refuses an option's value itself
            code = exc.code
        assert code == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err


def test_render_writes_a_video_its_truth_and_how_to_track_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "blob.avi"
    argv = [
        "render",
        "-o",
        str(video),
        "--size",
        "480x270",
        "--duration-s",
        "2",
        "--fps",
        "2",
        "--tilt",
        "1,0,0",
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "5 frames at 2 fps, 480x270" in out
    assert out.count("--point=") == 4
    assert (tmp_path / "blob.truth.csv").read_text().splitlines()[0].startswith("t_s,mean_x_cm")
    assert main(["render", "-o", str(tmp_path / "x.gif")]) == 2
    assert "write videos as .mp4 or .avi" in capsys.readouterr().err


@pytest.mark.e2e
def test_a_simulator_run_filmed_and_tracked_gives_the_row_its_csv_gives(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A run in the published format (metres, y up), light in a config file beside it.
    spec = BlobSpec(
        duration_s=240, fps=0.5, speed_mm_s=2.0, seed=2, start_cm=(150, 80), lamp_cm=(20, 30)
    )
    frames = breathing_blob(spec)
    folder = tmp_path / "run-2"
    folder.mkdir()
    write_published_csv(
        folder / "run.csv",
        2,
        [f.t_s for f in frames],
        np.array([f.x_cm / 100 for f in frames]),
        np.array([-f.y_cm / 100 for f in frames]),
        np.array([f.r_cm / 100 for f in frames]),
        light_m=(0.2, -0.3),
    )
    (folder / "config.txt").write_text("light_x\n0.2\nlight_y\n-0.3\n")
    video = tmp_path / "filmed.avi"
    assert main(["render", str(folder), "-o", str(video), "--size", "640x360", "--fps", "0.5"]) == 0
    assert main(["track", str(video), "--rate", "0", "--no-sheet"]) == 0
    capsys.readouterr()
    assert (
        main(
            [
                "stats",
                str(folder),
                str(tmp_path / "filmed.track.csv"),
                "--no-plot",
                "--cycle-s",
                "9",
            ]
        )
        == 0
    )
    rows = [
        line.split()
        for line in capsys.readouterr().out.splitlines()
        if "  track  " in line or "simulator" in line
    ]
    (csv_row,) = [r for r in rows if r[1] == "simulator"]
    (video_row,) = [r for r in rows if r[1] == "track"]
    assert csv_row[2] == video_row[2] == "8"  # 4 minutes of 30 s steps
    assert float(video_row[6]) == pytest.approx(float(csv_row[6]), rel=0.05)  # average mm/s
    assert float(csv_row[6]) == pytest.approx(2.0, rel=0.1)


def test_track_says_which_frames_it_dropped_in_the_csv_and_the_summary(
    paper_clip: Clip, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / paper_clip.path.name
    video.symlink_to(paper_clip.path)
    # A spike threshold below the region's own breathing sway drops some honest frames.
    assert main(["track", str(video), "--rate", "0", "--no-sheet", "--spike-cm", "0.2"]) == 0
    out = capsys.readouterr().out
    assert "Dropped (not written as the track): " in out
    track = read_track(tmp_path / "paper.track.csv")
    spiked = [q == "spike" for q in track.quality]
    assert any(spiked)
    assert np.isnan(track.x_cm[spiked]).all() and np.isfinite(track.x_cm[~np.array(spiked)]).all()
    assert track.meta["dropped"].startswith(f"{sum(spiked)} frames, coordinates left empty: ")
