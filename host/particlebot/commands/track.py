"""`particlebot track VIDEO`: the swarm's centroid in floor centimetres, frame by frame, as a
TRACK.csv, with a contact sheet (and optionally a video) of what the tracker saw."""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from particlebot.commands._common import fail
from particlebot.options import DISTANCE_CM, FRAME_RATE, LENGTH_CM, Bounds, float_arg
from particlebot.progress import ProgressBar

if TYPE_CHECKING:
    from particlebot.analysis.geometry import FloorGeometry
    from particlebot.analysis.tracker import (
        Circle,
        Detection,
        SwarmTracker,
        TrackerSettings,
        TrackResult,
    )
    from particlebot.analysis.video import Image, VideoSource

DESCRIPTION = """\
Finds the swarm in every analysed frame (SI S6's pipeline: edges and brightness above the local
floor, the lamp's head masked, rims closed, the outer perimeter filled) and writes its centroid in
floor centimetres from the field's top-left corner, y down the image. Camera geometry: --field
(a camera looking straight down whose picture spans that many cm; default the paper's 285x160), or
four or more --point U,V=X,Y (pixel = floor cm, e.g. tape marks at the field's corners), or
--checkerboard PICTURE of a board lying on the floor, taken by the same camera."""


def add_arguments(track: argparse.ArgumentParser) -> None:
    track.description = DESCRIPTION
    track.add_argument("video", help="the run's video (.mp4, .avi, anything FFmpeg decodes)")
    track.add_argument("-o", "--output", help="TRACK.csv (default: VIDEO.track.csv beside it)")
    where = track.add_argument_group("camera geometry")
    where.add_argument("--field", default="285x160", help="WxH cm the picture spans (285x160)")
    where.add_argument(
        "--point",
        action="append",
        default=[],
        metavar="U,V=X,Y",
        help="a marked floor point: pixel U,V is floor X,Y cm; 4 or more replace --field "
        "(write --point=U,V=X,Y when U or V is negative)",
    )
    where.add_argument("--checkerboard", metavar="PICTURE", help="picture of a board on the floor")
    where.add_argument("--board", default="9x6", help="its inner corners, columns x rows (9x6)")
    where.add_argument(
        "--square-cm", type=float_arg(LENGTH_CM), default=5.0, help="its square size (5 cm)"
    )
    where.add_argument(
        "--board-origin-cm",
        default="0,0",
        metavar="X,Y",
        help="floor position of its top-left inner corner (rows along floor x)",
    )
    where.add_argument(
        "--camera-height-cm",
        type=float_arg(LENGTH_CM),
        default=225.0,
        help="lens above the floor (225)",
    )
    where.add_argument(
        "--outline-height-cm",
        type=float_arg(DISTANCE_CM),
        default=0.0,
        help="height of the particles' outline above the floor, to undo parallax (0)",
    )
    what = track.add_argument_group("what to track")
    what.add_argument(
        "--rate",
        type=float_arg(Bounds(minimum=0, maximum=FRAME_RATE.maximum)),
        default=2.0,
        help="frames analysed per second of video (2; 0 = every frame)",
    )
    what.add_argument(
        "--fps", type=float_arg(FRAME_RATE), help="the video's frame rate, if its file is wrong"
    )
    what.add_argument(
        "--lamp",
        default="auto",
        metavar="auto|none|X,Y[,R]",
        help="find the lamp's head (auto), none, or mask R cm (15) around floor X,Y",
    )
    what.add_argument(
        "--lamp-height-cm",
        type=float_arg(DISTANCE_CM),
        default=35.0,
        help="height of the lamp's head (35)",
    )
    what.add_argument(
        "--ignore",
        action="append",
        default=[],
        metavar="X,Y,R",
        help="a floor circle that is never swarm (an obstacle); repeatable",
    )
    what.add_argument(
        "--particle-diameter-cm",
        type=float_arg(LENGTH_CM),
        help="contracted diameter (default: the firmware's R_min x 2 = 15.5)",
    )
    what.add_argument(
        "--spike-cm",
        type=float_arg(LENGTH_CM),
        help="drop a frame whose centroid lies this far from its neighbours' median "
        "(default: R_max - R_min + 1 = 5 cm, past the region's breathing sway)",
    )
    out = track.add_argument_group("pictures")
    out.add_argument("--sheet", help="contact sheet PNG (default: VIDEO.sheet.png)")
    out.add_argument("--no-sheet", action="store_true", help="write no contact sheet")
    out.add_argument("--overlay", metavar="VIDEO", help="also write every analysed frame drawn")


def _circle(text: str, what: str, default_radius: float | None = None) -> Circle:
    from particlebot.analysis.geometry import GeometryError
    from particlebot.analysis.tracker import Circle

    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
        if len(values) == 2 and default_radius is not None:
            values.append(default_radius)
        if len(values) != 3 or not all(math.isfinite(v) for v in values) or values[2] <= 0:
            raise ValueError
    except ValueError:
        raise GeometryError(f"{what} must look like X,Y,R (cm, R > 0), not {text!r}") from None
    return Circle(*values)


def _geometry(args: argparse.Namespace, image_size: tuple[int, int]) -> FloorGeometry:
    from particlebot.analysis import geometry as g
    from particlebot.analysis.video import VideoError, as_image, open_video

    if args.checkerboard:
        import cv2

        picture_path = Path(args.checkerboard)
        read = cv2.imread(str(picture_path)) if picture_path.is_file() else None
        if read is not None:
            picture = as_image(read)
        else:
            with open_video(picture_path) as video:  # a frame of a video will do
                picture = video.first
        if (picture.shape[1], picture.shape[0]) != image_size:
            raise VideoError(
                f"the checkerboard picture is {picture.shape[1]}x{picture.shape[0]}, the video "
                f"{image_size[0]}x{image_size[1]}: take both at the same resolution"
            )
        cols, rows = (int(v) for v in g.parse_pair(args.board, "--board", "x"))
        geometry = g.from_checkerboard(
            picture,
            (cols, rows),
            args.square_cm,
            g.parse_pair(args.board_origin_cm, "--board-origin-cm"),
        )
    elif args.point:
        geometry = g.from_points(
            [g.parse_point(p) for p in args.point],
            image_size,
            camera_height_cm=args.camera_height_cm,
        )
    else:
        width, height = g.parse_field(args.field)
        geometry = g.from_field(width, height, image_size, args.camera_height_cm)
    geometry = replace(geometry, camera_height_cm=args.camera_height_cm)
    return geometry.at_height(args.outline_height_cm)


def _settings(args: argparse.Namespace) -> TrackerSettings:
    from particlebot.analysis.tracker import TrackerSettings

    options: dict[str, Any] = {
        "lamp_height_cm": args.lamp_height_cm,
        "ignore": tuple(_circle(text, "--ignore") for text in args.ignore),
    }
    if args.lamp == "none":
        options["lamp"] = "none"
    elif args.lamp != "auto":
        options["lamp"] = _circle(args.lamp, "--lamp", default_radius=15.0)
    if args.spike_cm is not None:
        options["spike_cm"] = args.spike_cm
    if args.particle_diameter_cm is not None:  # (its parser refuses what is not > 0)
        options["particle_diameter_cm"] = args.particle_diameter_cm
    return TrackerSettings(**options)


def _metadata(
    source: VideoSource, geometry: FloorGeometry, result: TrackResult, step: int
) -> dict[str, str]:
    from particlebot.analysis.trackfile import QUALITY_FLAGS

    lamps = result.lamps
    meta = {
        "video": source.path.name,
        "video_size": f"{source.size[0]}x{source.size[1]}",
        "video_fps": f"{source.fps:g}",
        "analysed": f"every {step} frame(s), {source.fps / step:g} per second",
        "geometry": geometry.description,
        "lamp_cm": "none",
    }
    if geometry.residual_cm is not None:
        meta["geometry_residual_cm"] = f"{geometry.residual_cm:.2f}"
    if lamps:
        x, y = lamps[0].floor_cm
        meta["lamp_cm"] = f"{x:.1f},{y:.1f}"
        meta["lamp_found"] = "given" if lamps[0].given else "the brightest still blob"
        if len(lamps) > 1:
            meta["other_lamps_cm"] = "; ".join(
                f"{lamp.floor_cm[0]:.1f},{lamp.floor_cm[1]:.1f}" for lamp in lamps[1:]
            )
    dropped = result.dropped()
    meta["dropped"] = _dropped_text(dropped) if dropped else "none"
    for flag, meaning in QUALITY_FLAGS.items():
        meta[f"quality {flag}"] = meaning
    return meta


def _dropped_text(dropped: list[Detection]) -> str:
    """'3 frames, coordinates left empty: 120 (jump), 121 (jump), 300 (spike)'."""
    listed = ", ".join(f"{d.frame} ({d.quality})" for d in dropped[:50])
    more = f", and {len(dropped) - 50} more" if len(dropped) > 50 else ""
    return f"{len(dropped)} frames, coordinates left empty: {listed}{more}"


def _track(
    args: argparse.Namespace,
    source: VideoSource,
    geometry: FloorGeometry,
    settings: TrackerSettings,
    output: Path,
    sheet_path: Path | None,
) -> int:
    from particlebot.analysis.sheet import ContactSheet, Overlay
    from particlebot.analysis.tracker import SwarmTracker, track
    from particlebot.analysis.trackfile import write_track
    from particlebot.analysis.video import VideoWriter

    step = 1 if args.rate == 0 else max(1, round(source.fps / args.rate))
    tracker = SwarmTracker(geometry, settings)
    overlay = Overlay(geometry)
    expected = -(-source.frame_count // step) if source.frame_count > 0 else 0
    sheet = None if sheet_path is None else ContactSheet(expected)
    writer = None
    if args.overlay:
        writer = VideoWriter(Path(args.overlay), source.fps / step, source.size)
    last: list[tuple[int, Image, Detection]] = []

    def on_frame(frame: Image, detection: Detection, tracker: SwarmTracker) -> None:
        ordinal = last[0][0] + 1 if last else 0
        last[:] = [(ordinal, frame, detection)]
        overlay.note(detection)
        panel = sheet is not None and sheet.wants(ordinal)
        if writer is None and not panel:
            return
        drawn = overlay.draw(frame, detection, tracker)
        if writer is not None:
            writer.write(drawn)
        if sheet is not None and panel:
            sheet.offer(ordinal, drawn)

    bar = ProgressBar(f"track {source.path.name}", source.frame_count)
    try:
        result = track(source, tracker, step, progress=bar.update, on_frame=on_frame)
    except BaseException:
        if writer is not None:
            # An error mid-way (a full disk): an overlay cut short may not decode; none instead.
            writer.close()
            writer.path.unlink(missing_ok=True)
            writer = None
        raise
    finally:
        bar.finish()
        if writer is not None:
            writer.close()
    if sheet is not None and last:
        ordinal, frame, detection = last[0]
        sheet.end(ordinal, lambda: overlay.draw(frame, detection, tracker))
    meta = _metadata(source, geometry, result, step)
    # Ctrl-C keeps what was tracked: a long video stopped near its end is still worth its CSV.
    if result.interrupted:
        meta["interrupted"] = f"after {result.frames_read} frames (Ctrl-C)"
    rows = write_track(output, (d.row() for d in result.detections), meta)
    counts = ", ".join(f"{n} {flag}" for flag, n in sorted(result.counts().items()))
    print(
        f"Track: {output} ({rows} frames analysed: {counts}; "
        f"{rows / max(result.seconds, 1e-9):.0f} frames/s)"
    )
    dropped = result.dropped()
    if dropped:
        print(f"Dropped (not written as the track): {_dropped_text(dropped)}")
    if result.lamps:
        x, y = result.lamps[0].floor_cm
        print(f"Lamp: ({x:.1f}, {y:.1f}) cm")
    else:
        print("Lamp: none found (give --lamp X,Y to stats)")
    if sheet is not None and sheet_path is not None and rows:
        sheet.write(sheet_path, f"{source.path.name}: {geometry.description}")
        print(f"Contact sheet: {sheet_path}")
    if writer is not None:
        print(f"Overlay: {args.overlay}")
    return 130 if result.interrupted else 0


def run(args: argparse.Namespace) -> int:
    from particlebot.analysis.geometry import GeometryError
    from particlebot.analysis.video import VideoError, open_video

    video_path = Path(args.video)
    output = Path(args.output) if args.output else video_path.with_suffix(".track.csv")
    sheet = None if args.no_sheet else Path(args.sheet or video_path.with_suffix(".sheet.png"))
    if args.rate < 0:
        return fail("--rate must be 0 (every frame) or positive")
    for flag, height in (
        ("--lamp-height-cm", args.lamp_height_cm),
        ("--outline-height-cm", args.outline_height_cm),
    ):
        # The floor's geometry divides by the camera's height above each of them.
        if height >= args.camera_height_cm:
            return fail(
                f"{flag} {height:g} must be below --camera-height-cm {args.camera_height_cm:g}: "
                "the camera looks down on it"
            )
    try:
        with open_video(video_path, args.fps) as source:
            geometry = _geometry(args, source.size)
            settings = _settings(args)
            return _track(args, source, geometry, settings, output, sheet)
    except (GeometryError, VideoError, ValueError, OSError) as exc:
        return fail(str(exc))
