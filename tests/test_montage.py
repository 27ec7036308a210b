"""flashsync montage: the cameras tiled in sync, read back with PyAV: frame count, size,
the line across the exposed row, the frame shown in each tile."""

import re
import shutil
from fractions import Fraction

import av
import numpy as np
import pytest
from cli_run import one_error_line, run

from flashsync.cli import main
from flashsync.io import load_model
from flashsync.montage import layout, write_montage
from flashsync.simulation.encode import write_video
from flashsync.ticks import AFTER, BEFORE, LOCATED, locate_ticks, tick_times_ms

VIDEOS = ("r.mp4", "f.mkv", "s.mp4")


def decoded(path, **size):
    """Every frame of a video as BGR arrays (optionally scaled like the montage's tiles)."""
    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="bgr24", interpolation="AREA", **size) for frame in container.decode(video=0)]


def line_row(tile):
    """Montage y of the magenta line in a tile region (centroid of the rows' magenta-ness
    over the region's right half, clear of the caption), or None without a line."""
    pixels = tile[:, tile.shape[1] // 2 :].astype(float)
    magenta = ((pixels[..., 0] + pixels[..., 2]) / 2 - pixels[..., 1]).mean(axis=1)
    magenta -= np.median(magenta)
    peak = int(np.argmax(magenta))
    if magenta[peak] < 60:
        return None
    near = np.arange(max(peak - 3, 0), min(peak + 4, len(magenta)))
    weight = np.clip(magenta[near] - magenta[peak] / 4, 0, None)
    return float(np.sum(near * weight) / np.sum(weight))


@pytest.fixture(scope="module")
def montage(synced_scenario, tmp_path_factory):
    """25 Hz from 0 to 4000 ms on the global clock (the recordings end near 3200 ms)."""
    output = tmp_path_factory.mktemp("montage") / "synced.mp4"
    code = main(
        [
            "montage",
            *(str(synced_scenario / name) for name in VIDEOS),
            "--model",
            str(synced_scenario / "sync.json"),
            "--rate",
            "25",
            "--start-ms",
            "0",
            "--end-ms",
            "4000",
            "-o",
            str(output),
        ]
    )
    assert code == 0
    return output, decoded(output)


def test_montage_has_one_frame_per_tick_at_the_rate(montage):
    path, frames = montage
    assert len(frames) == 100  # 4000 ms at 25 Hz, end exclusive
    assert frames[0].shape == (360, 640, 3)  # 2 x 2 cells of 320 x 180
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name == "h264" and stream.average_rate == 25
        assert stream.frames in (0, 100)


def test_lines_cross_the_row_exposed_at_each_tick(synced_scenario, montage):
    """In every tile of every frame: the line lies on the row the model says ends its
    exposure at the tick (within a pixel), and is absent where no row is exposed."""
    model = load_model(synced_scenario / "sync.json")
    _, frames = montage
    ticks = tick_times_ms(25.0, 0.0, 4000.0)
    tiles = layout({name: (model.cameras[name].width, model.cameras[name].height) for name in model.cameras})
    errors, absent = [], 0
    for tile in tiles:
        _, row, reason = locate_ticks(model.camera(tile.camera), ticks)
        for k, image in enumerate(frames):
            found = line_row(image[tile.top : tile.top + tile.height, tile.left : tile.left + tile.width])
            if reason[k] == LOCATED:
                assert found is not None, (tile.camera, k)
                errors.append(found + tile.top - tile.montage_row(row[k]))
            else:
                assert found is None, (tile.camera, k, reason[k])
                absent += 1
    errors = np.array(errors)
    assert len(errors) > 150 and absent > 50
    assert np.abs(errors).max() < 1.0 and np.sqrt(np.mean(errors**2)) < 0.4, errors


def test_each_tile_shows_the_frame_covering_the_tick(synced_scenario, montage):
    """A tile matches its camera's frame that ``locate`` gives better than the frames before
    and after it (the upside-down camera that drops frames too); before and after its
    recording a tile is dark."""
    model = load_model(synced_scenario / "sync.json")
    _, frames = montage
    ticks = tick_times_ms(25.0, 0.0, 4000.0)
    tiles = layout({name: (model.cameras[name].width, model.cameras[name].height) for name in model.cameras})
    for tile, name in zip(tiles, VIDEOS):
        source = decoded(synced_scenario / name, width=tile.width, height=tile.height)
        frame, row, reason = locate_ticks(model.camera(tile.camera), ticks)
        keep = np.ones(tile.height, dtype=bool)
        keep[: tile.height // 8] = False  # the caption
        checked = 0
        for k, image in enumerate(frames):
            shown = image[tile.top : tile.top + tile.height, tile.left : tile.left + tile.width].astype(float)
            if reason[k] in (BEFORE, AFTER):
                assert shown[keep].mean() < 30, (tile.camera, k)
                continue
            rows = keep.copy()
            if reason[k] == LOCATED:
                line = round(tile.montage_row(row[k])) - tile.top
                rows[max(line - 3, 0) : line + 4] = False
            candidates = [f for f in (frame[k] - 1, frame[k], frame[k] + 1) if 0 <= f < len(source)]
            stack = np.stack([source[f][rows].astype(float) for f in candidates])
            moved = np.ptp(stack, axis=0).max(axis=-1) > 24  # where the candidates differ
            if moved.sum() < 30:  # a few pixels of a lossy encode decide nothing (s, tick 24: 22 pixels, the
                continue  # located frame ahead by 6.2 on main and behind by 3.2 with a line drawn 0.3 rows up)
            distance = {f: np.abs(shown[rows][moved] - image_f[moved]).mean() for f, image_f in zip(candidates, stack)}
            nearest = sorted(distance.values())
            if nearest[1] - nearest[0] < 3.0:  # a few moving pixels that the encoding blurs: no decision
                continue
            assert min(distance, key=distance.get) == frame[k], (tile.camera, k, distance)
            checked += 1
        assert checked > 30, tile.camera


def test_tiles_of_different_sizes_fill_a_common_cell():
    tiles = layout({"a": (320, 180), "b": (256, 144), "c": (240, 180)})
    assert [(t.width, t.height) for t in tiles] == [(320, 180), (320, 180), (240, 180)]
    assert [(t.cell_left, t.cell_top) for t in tiles] == [(0, 0), (320, 0), (0, 180)]
    assert tiles[2].left == 40 and tiles[1].scale == 1.25
    assert tiles[1].montage_row(0.0) == pytest.approx(0.125)  # row 0's centre, 1.25 px tall


def test_default_rate_and_span_follow_the_cameras_given(synced_scenario, tmp_path, capsys):
    code, _, err = run(
        capsys,
        "montage",
        synced_scenario / "s.mp4",
        "--model",
        synced_scenario / "sync.json",
        "--cell",
        "120x90",
        "-o",
        tmp_path / "s.mkv",
    )
    assert code == 0, err
    frames = decoded(tmp_path / "s.mkv")
    model = load_model(synced_scenario / "sync.json")
    clock = model.camera("s")
    span_ms = clock.t_global_ms(clock.n_frames - 1, clock.height - 1) - clock.t_global_ms(0, 0.0)
    assert abs(len(frames) - span_ms / 20.0) <= 1  # 50 Hz, s's own frame rate
    assert frames[0].shape == (90, 120, 3)
    rate = re.search(r"at ([0-9.]+) Hz", err)
    assert rate and float(rate.group(1)) == pytest.approx(50.0, abs=0.01)  # s's rate on the global clock


def test_an_interrupted_montage_leaves_no_file(synced_scenario, tmp_path):
    def progress(name, total):
        def update(done):
            update.count += done
            if update.count == 5:
                raise KeyboardInterrupt

        update.count = 0
        return update

    with pytest.raises(KeyboardInterrupt):
        write_montage(
            [synced_scenario / name for name in VIDEOS],
            load_model(synced_scenario / "sync.json"),
            tmp_path / "synced.mp4",
            25.0,
            progress=progress,
        )
    assert not list(tmp_path.iterdir())


def test_montage_refuses_bad_input(synced_scenario, tmp_path, capsys):
    model = synced_scenario / "sync.json"
    videos = [synced_scenario / name for name in VIDEOS]
    shutil.copy(synced_scenario / "r.mp4", tmp_path / "x.mp4")
    (tmp_path / "short").mkdir()
    write_video(
        tmp_path / "short" / "r.mp4", [np.zeros((180, 320), np.uint8)] * 10, np.arange(10) * 3600, Fraction(1, 90000)
    )
    cases = [
        ([*videos, "--model", tmp_path / "nope.json"], ["nope.json", "no such model file"]),
        ([tmp_path / "x.mp4", "--model", model], ["x.mp4", "'x' is not in the model"]),
        ([tmp_path / "r.mp4", "--model", model], ["r.mp4", "no such file"]),
        ([tmp_path / "short" / "r.mp4", "--model", model], ["r.mp4", "10 frames", "model has 80"]),
        ([*videos, "--model", model, "--rate", 0], ["--rate 0", "positive"]),
        ([*videos, "--model", model, "--rate", "nan"], ["--rate nan", "positive"]),
        ([*videos, "--model", model, "--start-ms", 3000, "--end-ms", 1000], ["--end-ms 1000", "not after"]),
        ([*videos, "--model", model, "--cell", "big"], ["--cell big", "WIDTHxHEIGHT"]),
    ]
    for options, words in cases:
        code, _, err = run(capsys, "montage", *options, "-o", tmp_path / "out" / "synced.mp4")
        assert code == 1, options
        one_error_line(err, *words)
    code, _, err = run(capsys, "montage", *videos, "--model", model, "-o", tmp_path / "out" / "synced.avi")
    assert code == 1
    one_error_line(err, "synced.avi", ".mp4")
    assert not (tmp_path / "out").exists()
