"""A run's video: top-view frames drawn while it runs (kept as PNGs in the run folder, so a
stopped run resumes its film too), encoded as MP4 or GIF by the ffmpeg of the imageio-ffmpeg
wheel when the run ends."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

from particlebot.errors import ParticlebotError
from particlebot.fileio import atomic_path
from particlebot.sim.runs.pictures import Frame, View, draw_swarm, picture_size
from particlebot.videowriter import H264_OUTPUT

FPS = 10
FRAME_WIDTH_IN = 9.6
"""960 pixels wide at 100 dpi, as high as the run's view needs."""


class VideoError(ParticlebotError, RuntimeError):
    """ffmpeg could not encode the frames."""


def frame_every(total_steps: int, frames: int) -> int:
    """Steps between frames for about `frames` frames over the run."""
    return max(1, total_steps // frames)


def frame_path(folder: Path, index: int) -> Path:
    return folder / f"{index:06d}.png"


def write_frame(folder: Path, index: int, frame: Frame, view: View) -> None:
    folder.mkdir(exist_ok=True)
    width, height = picture_size(view, FRAME_WIDTH_IN)
    # Whole pixels, an even number each way (H.264's colour subsampling wants that).
    figure = draw_swarm(frame, view, (width, round(height * 50) / 50))
    with atomic_path(frame_path(folder, index)) as temporary:
        figure.savefig(temporary)


def encode(
    folder: Path,
    output: Path,
    fps: int = FPS,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """The PNG frames of `folder`, in order, as output (.mp4: H.264; .gif); progress(frames
    encoded, frames) as ffmpeg reports them (a long film takes minutes)."""
    import imageio_ffmpeg

    frames = sorted(folder.glob("[0-9]*.png"))
    if not frames:
        raise VideoError(f"no frames in {folder}")
    # Frames are numbered without gaps (one every so many steps, resumed runs included), from 0
    # or from where --video was first asked for.
    first = min(int(p.stem) for p in frames)
    command = [
        imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-loglevel", "error", "-framerate", str(fps),
        "-start_number", str(first), "-i", str(folder / "%06d.png"),
        "-progress", "pipe:1", "-nostats",
    ]  # fmt: skip
    if output.suffix.lower() == ".gif":
        # One palette made for the whole film: smaller and cleaner than the default one.
        palette = "scale=640:-1:flags=lanczos,split[a][b];[a]palettegen[p];[b][p]paletteuse"
        command += ["-vf", palette]
    else:
        command += H264_OUTPUT
    with atomic_path(output) as temporary:
        returncode, errors = _run_ffmpeg([*command, str(temporary)], len(frames), progress)
        if returncode != 0:
            raise VideoError(f"ffmpeg could not write {output.name}: {errors.strip()[-300:]}")
    return output


def _run_ffmpeg(
    command: list[str], frames: int, progress: Callable[[int, int], None] | None
) -> tuple[int, str]:
    """Runs ffmpeg, passing on the frame counts its `-progress` lines give; (exit status,
    stderr)."""
    with tempfile.TemporaryFile("w+") as errors:
        ffmpeg = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=errors, stdin=subprocess.DEVNULL, text=True
        )
        assert ffmpeg.stdout is not None
        try:
            if progress is not None:
                progress(0, frames)
            for line in ffmpeg.stdout:
                key, _, value = line.strip().partition("=")
                if key == "frame" and value.isdigit() and progress is not None:
                    progress(min(int(value), frames), frames)
        except BaseException:
            ffmpeg.kill()
            raise
        finally:
            returncode = ffmpeg.wait()
        errors.seek(0)
        return returncode, errors.read()


def discard(folder: Path) -> None:
    shutil.rmtree(folder, ignore_errors=True)
