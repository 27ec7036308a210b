"""The cameras tiled in one H.264 video, in sync: at each tick every tile shows its camera's
frame that covers the tick, with a line across the row exposed at that instant.

One output frame per tick (:mod:`flashsync.ticks`: ``start + k / rate``, end exclusive).
Each tile shows the frame :func:`~flashsync.ticks.locate_ticks` gives for the tick, scaled
to fit a common cell (aspect kept, centred), with a magenta line across the row whose
exposure ends at the tick, and a caption: camera, frame, tick time (global clock, ms).
In the vertical blanking or a dropped frame the tile keeps the last frame that started,
without a line, and the caption says where the tick fell; before or after a camera's
recording the tile is dark. Each video is decoded forward once, streaming, and the
montage is encoded as it goes (libx264 through PyAV), so memory does not grow with the
length of the videos or of the montage.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, closing
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
from av.video.reformatter import VideoReformatter

from flashsync.atomic import atomic_output
from flashsync.errors import InputError, NotEnoughDataError
from flashsync.io.files import existing_file
from flashsync.model import SyncModel
from flashsync.ticks import AFTER, BEFORE, LOCATED, REASONS, locate_ticks, model_ticks_ms, tick_period_ms
from flashsync.timestamps import median_step_ms, open_video, video_stream, video_timestamps

#: Output containers by file extension.
CONTAINERS = {".mp4": "mp4", ".mkv": "matroska", ".mov": "mov"}
#: The widest and tallest frame libx264 encodes, px.
X264_MAX_SIDE_PX = 16384
#: Colour of the exposed-row line, BGR.
LINE_COLOR = (255, 0, 255)
BACKGROUND = 24
CAPTION_COLOR = (255, 255, 255)

Progress = Callable[[str, int], Callable[[int], None]]


@dataclass(frozen=True)
class Tile:
    """Where a camera's frames go in the montage.

    Attributes
    ----------
    camera : str
    left, top : int
        Top-left corner of the scaled image in the montage, px.
    width, height : int
        Size of the scaled image, px.
    scale : float
        Montage px per camera px.
    cell_left, cell_top, cell_width, cell_height : int
        The cell the image is centred in, px.
    """

    camera: str
    left: int
    top: int
    width: int
    height: int
    scale: float
    cell_left: int
    cell_top: int
    cell_width: int
    cell_height: int

    def montage_row(self, row: float) -> float:
        """Montage y (px, pixel centres at integers) of a camera's stored-image row."""
        return self.top + (row + 0.5) * self.scale - 0.5


@dataclass(frozen=True)
class MontageSummary:
    """What :func:`write_montage` wrote: ``frames`` (one per tick) of ``width`` x ``height``
    px at ``rate_hz``, from ``start_ms`` (global clock) on."""

    path: Path
    frames: int
    width: int
    height: int
    rate_hz: float
    start_ms: float


def layout(sizes: dict[str, tuple[int, int]], cell: tuple[int, int] | None = None) -> list[Tile]:
    """Tiles on a grid of ``ceil(sqrt(n))`` columns, cameras in order, row by row.

    Parameters
    ----------
    sizes : dict of str to (width, height)
        Each camera's frame size, px.
    cell : (width, height), optional
        Cell size, px; default the largest width by the largest height. Rounded up to
        even numbers (H.264 in 4:2:0 needs them).
    """
    cell_width, cell_height = cell or (max(w for w, _ in sizes.values()), max(h for _, h in sizes.values()))
    cell_width, cell_height = cell_width + cell_width % 2, cell_height + cell_height % 2
    columns = math.ceil(math.sqrt(len(sizes)))
    tiles = []
    for index, (camera, (width, height)) in enumerate(sizes.items()):
        scale = min(cell_width / width, cell_height / height)
        tile_width, tile_height = max(round(width * scale), 1), max(round(height * scale), 1)
        cell_left, cell_top = (index % columns) * cell_width, (index // columns) * cell_height
        tiles.append(
            Tile(
                camera,
                cell_left + (cell_width - tile_width) // 2,
                cell_top + (cell_height - tile_height) // 2,
                tile_width,
                tile_height,
                tile_height / height,
                cell_left,
                cell_top,
                cell_width,
                cell_height,
            )
        )
    return tiles


def frame_rate_hz(model: SyncModel, name: str) -> float:
    """Camera ``name``'s frame rate on the global clock (median step between frames), Hz, to
    0.001 Hz."""
    clock = model.camera(name)
    if clock.n_frames < 2:
        raise NotEnoughDataError(
            model.named(f"camera {name} has one frame in the model: no frame rate to take; give the rate of the ticks")
        )
    return round(1000.0 / (clock.alpha * median_step_ms(clock.frame_times_ms)), 3)


def named_videos(paths: Sequence[str | Path], model: SyncModel) -> dict[str, Path]:
    """Camera name (file stem) -> video, each checked against the model: a camera the
    model has, the number of frames the model has. A one-line error otherwise."""
    videos: dict[str, Path] = {}
    for path in map(Path, paths):
        if path.stem in videos:
            raise InputError(
                f"{path}: two videos are named {path.stem}; camera names are file stems and must be unique: rename one"
            )
        existing_file(path)
        if path.stem not in model.cameras:
            raise InputError(
                f"{path}: camera {path.stem!r} is not in the model (it has "
                f"{', '.join(model.cameras)}); give the videos the model was made from"
            )
        count, expected = len(video_timestamps(path)), model.cameras[path.stem].n_frames
        if count != expected:
            raise InputError(
                f"{path}: {count} frames, but the model has {expected} for camera "
                f"{path.stem!r}; give the video the model was made from"
            )
        videos[path.stem] = path
    return videos


def write_montage(
    videos: Sequence[str | Path],
    model: SyncModel,
    output: str | Path,
    rate_hz: float | None = None,
    start_ms: float | None = None,
    end_ms: float | None = None,
    *,
    cell: tuple[int, int] | None = None,
    crf: int = 20,
    progress: Progress | None = None,
) -> MontageSummary:
    """Write the videos tiled, in sync, one frame per tick, to an H.264 file (atomically).

    Parameters
    ----------
    videos : sequence of paths
        Videos of cameras in ``model`` (camera = file stem), tiled in this order.
    model : SyncModel
        The synchronisation model.
    output : str or Path
        ``.mp4``, ``.mkv`` or ``.mov``.
    rate_hz : float, optional
        Ticks (output frames) per second; the montage plays in real time. Default: the
        highest frame rate of the cameras tiled, so that every frame is shown.
    start_ms, end_ms : float, optional
        First tick and exclusive end, global clock, ms; default the span covered by any
        of these cameras (:func:`~flashsync.ticks.model_ticks_ms`).
    cell : (width, height), optional
        Size of each camera's cell, px (:func:`layout`).
    crf : int
        x264 constant rate factor (0 lossless .. 51 worst).
    progress : callable, optional
        ``progress(name, total)`` returns a function called with 1 after each frame.

    Returns
    -------
    MontageSummary

    Examples
    --------
    >>> write_montage(["cam1.mp4", "cam2.mkv"], load_model("sync.json"), "synced.mp4",
    ...               25.0, 10_000.0, 14_000.0).frames                    # doctest: +SKIP
    100
    """
    output = Path(output)
    if output.suffix.lower() not in CONTAINERS:
        raise InputError(f"{output}: cannot write '{output.suffix}' video; name it {', '.join(CONTAINERS)}")
    if rate_hz is not None:
        tick_period_ms(rate_hz)  # a bad rate fails before decoding
    named = named_videos(videos, model)
    if rate_hz is None:
        rate_hz = max(frame_rate_hz(model, name) for name in named)
    ticks = model_ticks_ms(model, rate_hz, start_ms, end_ms, cameras=list(named))
    tiles = layout({name: (model.cameras[name].width, model.cameras[name].height) for name in named}, cell)
    width = max(t.cell_left + t.cell_width for t in tiles)
    height = max(t.cell_top + t.cell_height for t in tiles)
    if max(width, height) > X264_MAX_SIDE_PX:
        raise InputError(
            f"{tiles[0].cell_width}x{tiles[0].cell_height}: cells of this size make a montage of {width}x{height} "
            f"px, over the {X264_MAX_SIDE_PX} px a side x264 encodes; give smaller cells",
            parameter="cell",
        )
    located = {name: locate_ticks(model.cameras[name], ticks) for name in named}
    update = progress("montage", len(ticks)) if progress else None
    with ExitStack() as stack:
        readers = [stack.enter_context(closing(_TileReader(path, tile))) for path, tile in zip(named.values(), tiles)]
        temporary = stack.enter_context(atomic_output(output))
        container = stack.enter_context(av.open(str(temporary), "w", format=CONTAINERS[output.suffix.lower()]))
        rate = Fraction(rate_hz).limit_denominator(1001)
        stream = container.add_stream("libx264", rate=rate)
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        stream.codec_context.time_base = 1 / rate
        stream.options = {"crf": str(crf), "preset": "veryfast"}
        canvas = np.empty((height, width, 3), dtype=np.uint8)
        for k, tick in enumerate(ticks):
            canvas[:] = BACKGROUND
            for reader in readers:
                frame, row, reason = (values[k] for values in located[reader.tile.camera])
                _draw_tile(canvas, reader, int(frame), float(row), int(reason), float(tick))
            image = av.VideoFrame.from_ndarray(canvas, format="bgr24")
            image.pts, image.time_base = k, 1 / rate
            container.mux(stream.encode(image))
            if update:
                update(1)
        container.mux(stream.encode())
    return MontageSummary(output, len(ticks), width, height, float(rate_hz), float(ticks[0]))


def _draw_tile(canvas: np.ndarray, reader: _TileReader, frame: int, row: float, reason: int, tick_ms: float) -> None:
    """One camera's tile at one tick: its frame, the exposed row's line, the caption."""
    tile = reader.tile
    if reason in (BEFORE, AFTER):
        caption = f"{tile.camera}  {REASONS[reason]}"
    else:
        canvas[tile.top : tile.top + tile.height, tile.left : tile.left + tile.width] = reader.image(frame)
        caption = f"{tile.camera}  frame {frame}" + ("" if reason == LOCATED else f" ({REASONS[reason]})")
    if reason == LOCATED:
        y = tile.montage_row(row)
        shift = 4  # 1/16 px sub-pixel precision
        thickness = max(2, round(tile.height / 180))
        cv2.line(
            canvas,
            (tile.left << shift, round(y * (1 << shift))),
            ((tile.left + tile.width - 1) << shift, round(y * (1 << shift))),
            LINE_COLOR,
            thickness,
            cv2.LINE_AA,
            shift,
        )
    _caption(canvas, tile, f"{caption}  t = {tick_ms:.1f} ms")


def _caption(canvas: np.ndarray, tile: Tile, text: str) -> None:
    """White text on a dark box at the top left of the cell, scaled to fit its width."""
    font, scale = cv2.FONT_HERSHEY_SIMPLEX, max(tile.cell_height / 450, 0.35)
    (text_width, text_height), baseline = cv2.getTextSize(text, font, scale, 1)
    if text_width > tile.cell_width - 8:
        scale *= (tile.cell_width - 8) / text_width
        (text_width, text_height), baseline = cv2.getTextSize(text, font, scale, 1)
    left, top = tile.cell_left + 2, tile.cell_top + 2
    canvas[top : top + text_height + baseline + 4, left : left + text_width + 4] //= 4
    cv2.putText(canvas, text, (left + 2, top + text_height + 2), font, scale, CAPTION_COLOR, 1, cv2.LINE_AA)


class _TileReader:
    """A video decoded forward once; the current frame scaled to its tile."""

    def __init__(self, path: Path, tile: Tile) -> None:
        self.path, self.tile = path, tile
        self._container = open_video(path)
        stream = video_stream(self._container)
        stream.thread_type = "AUTO"
        self._frames: Iterator[av.VideoFrame] = self._container.decode(stream)
        self._scaler = VideoReformatter()  # keeps its scaling context: 3-5x faster
        self._index, self._image = -1, None

    def image(self, frame: int) -> np.ndarray:
        """Frame ``frame`` (0-based, presentation order, never before the last one asked
        for) as BGR at the tile's size."""
        if frame != self._index:
            try:
                for _ in range(frame - self._index - 1):
                    next(self._frames)
                decoded = next(self._frames)
            except StopIteration:
                raise InputError(f"{self.path}: ends before frame {frame}; is the file complete?") from None
            except av.FFmpegError as error:
                raise InputError(f"{self.path}: cannot decode ({error.strerror}); is the file complete?") from None
            self._image = self._scaler.reformat(
                decoded, self.tile.width, self.tile.height, "bgr24", interpolation="AREA"
            ).to_ndarray()
            self._index = frame
        return self._image

    def close(self) -> None:
        self._container.close()
