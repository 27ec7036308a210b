"""The Rerun web viewer shows the shipped 4-camera sample readably at its default layout.

The sample is synced, restamped and validated, its recording served with ``rerun
--serve-web`` on 127.0.0.1 and opened at 1600x1000 in Debian's Chromium (software GPU)
driven by playwright (no browser download). What a user looks at is checked without OCR:
the panels' names from the recording's blueprint, where each panel is from its container
shares, and in each panel's pixels that there is what must be read there -- several
separate tick labels on each axis, a lane label per camera, a video or a "starts at" label
per camera. Then a click on flash 2's line in the flash log must show every camera's
frame of that flash.

``FLASHSYNC_SCREENSHOT=path.png`` also writes the screenshot after the click there (how
``docs/viewer.png`` is made).
"""

import importlib.util
import os
import shutil
import subprocess
import time
import urllib.parse
import urllib.request
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest
from test_viz import free_port, quiet_rerun, read_blueprint, views  # noqa: F401 (fixture)

import viz
from flashsync.io import events_to_frame, load_homographies, load_plane_outline
from flashsync.pipeline import all_events, detect_videos, synchronize
from tracking_adapter.restamp import restamp
from tracking_adapter.validate import validate

SAMPLES = Path(__file__).parents[1] / "samples"
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
VIEWPORT = {"width": 1600, "height": 1000}
CONTENT_Y = (35, 971)
"""Rows of the viewer's panels at this viewport: below its top bar, above the time slider."""
TITLE_PX, LOG_FIRST_ROW_PX, LOG_ROW_PX = 26, 82, 19.9
SETTLE_S, TIMEOUT_S, RETRY_S = 12.0, 150.0, 20.0
"""Seconds for the viewer to load before a first screenshot (each takes seconds in software),
and at most."""

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("playwright") is None or not CHROMIUM.exists(),
    reason="needs the playwright package and Debian's /usr/bin/chromium",
)


@pytest.fixture(scope="module")
def sample(tmp_path_factory, quiet_rerun):  # noqa: F811 (the imported fixture)
    """The shipped sample through the whole chain, and its recording."""
    videos = sorted(SAMPLES.glob("cam*.m*"))
    detections = detect_videos(videos, estimate_readout=True)
    model, _ = synchronize(detections)
    restamped = restamp(pd.read_csv(SAMPLES / "detections.csv"), model)
    homographies = load_homographies(SAMPLES / "homographies.json")
    triples = validate(restamped, model, homographies).triples
    path = tmp_path_factory.mktemp("sample") / "sample.rrd"
    viz.save_recording(
        path,
        model,
        videos=videos,
        events=events_to_frame(all_events(detections)),
        detections=restamped,
        homographies=homographies,
        validation=triples,
        plane_outline_m=load_plane_outline(SAMPLES / "homographies.json"),
    )
    return {"model": model, "rrd": path}


@pytest.fixture
def served(sample):
    """``rerun --serve-web`` on the recording; yields the viewer's address, then stops it."""
    web_port, grpc_port = free_port(), free_port()
    server = subprocess.Popen(
        [
            str(viz.recording.rerun_program()),
            "--serve-web",
            "--bind",
            "127.0.0.1",
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            str(sample["rrd"]),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{web_port}/", timeout=5).close()
                break
            except OSError:
                assert server.poll() is None and time.monotonic() < deadline, "no web viewer"
                time.sleep(0.5)
        yield viz.viewer_url(web_port, grpc_port)
    finally:
        server.terminate()
        server.wait(timeout=30)


def panel_rects(blueprint: dict[str, dict]) -> dict[str, tuple[int, int, int, int]]:
    """Each view's name -> (x0, y0, x1, y1) px at :data:`VIEWPORT`, from the container shares."""
    names = {
        path[1:]: parts["ViewBlueprint:display_name"][0]
        for path, parts in blueprint.items()
        if "ViewBlueprint:display_name" in parts
    }
    rects = {}

    def place(item: str, x0: float, y0: float, x1: float, y1: float) -> None:
        if item in names:
            rects[names[item]] = tuple(round(v) for v in (x0, y0, x1, y1))
            return
        parts = blueprint["/" + item]
        children = list(parts["ContainerBlueprint:contents"])
        kind = parts["ContainerBlueprint:container_kind"][0]
        if kind == 4:  # grid
            columns = parts["ContainerBlueprint:grid_columns"][0]
            rows = -(-len(children) // columns)
            for i, child in enumerate(children):
                w, h = (x1 - x0) / columns, (y1 - y0) / rows
                place(
                    child,
                    x0 + w * (i % columns),
                    y0 + h * (i // columns),
                    x0 + w * (i % columns + 1),
                    y0 + h * (i // columns + 1),
                )
            return
        key = "ContainerBlueprint:col_shares" if kind == 2 else "ContainerBlueprint:row_shares"
        shares = np.asarray(parts.get(key) or [1.0] * len(children), dtype=float)
        edges = np.concatenate([[0.0], np.cumsum(shares / shares.sum())])
        for child, a, b in zip(children, edges[:-1], edges[1:]):
            if kind == 2:
                place(child, x0 + a * (x1 - x0), y0, x0 + b * (x1 - x0), y1)
            else:
                place(child, x0, y0 + a * (y1 - y0), x1, y0 + b * (y1 - y0))

    root = bytes(blueprint["/viewport"]["ViewportBlueprint:root_container"][0])
    root_path = next(path[1:] for path in blueprint if path.startswith("/container/") and path.endswith(_uuid(root)))
    place(root_path, 0, CONTENT_Y[0], VIEWPORT["width"], CONTENT_Y[1])
    return rects


def _uuid(raw: bytes) -> str:
    hexa = raw.hex()
    return f"{hexa[:8]}-{hexa[8:12]}-{hexa[12:16]}-{hexa[16:20]}-{hexa[20:]}"


def text_runs(gray: np.ndarray, axis: int, dark: int = 170, gap: int = 3) -> int:
    """Separate runs of text (dark pixels) along ``axis`` of a crop: rows (0) or columns (1)."""
    has_ink = (gray < dark).any(axis=1 - axis)
    runs, blank = 0, gap
    for ink in has_ink:
        if ink and blank >= gap:
            runs += 1
        blank = 0 if ink else blank + 1
    return runs


def busy_fraction(image: np.ndarray) -> float:
    """Fraction of pixels more than 8 levels away from the crop's most common colour."""
    pixels = image.reshape(-1, 3)
    colors, counts = np.unique(pixels, axis=0, return_counts=True)
    background = colors[counts.argmax()].astype(int)
    return float(np.mean(np.any(np.abs(pixels.astype(int) - background) > 8, axis=1)))


def crop(image: np.ndarray, rect, inset=(0, TITLE_PX, 0, 0)) -> np.ndarray:
    x0, y0, x1, y1 = rect
    return image[y0 + inset[1] : y1 - inset[3], x0 + inset[0] : x1 - inset[2]]


def cursor_x(gray: np.ndarray, rect) -> int:
    """Column of the time cursor in a time view: the leftmost dark line through its height."""
    x0, y0, x1, y1 = rect
    plot = gray[y0 + TITLE_PX + 20 : y1 - 30, x0:x1]
    return x0 + int(np.argmax((plot < 120).mean(axis=0) > 0.8))


def screenshot(page, until, path: Path, again=None) -> np.ndarray:
    """A screenshot once ``until(image)`` holds (the wasm, the data and the videos load);
    ``again()``, where given, is done again every :data:`RETRY_S` until then (a click the
    viewer missed while it was busy: on a loaded machine the flash log's first click was
    lost once, and the test waited out its timeout)."""
    started = last = time.monotonic()
    while True:
        png = page.screenshot()
        image = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
        if until(image) or time.monotonic() - started > TIMEOUT_S:
            path.write_bytes(png)
            return image
        if again is not None and time.monotonic() - last > RETRY_S:
            again()
            last = time.monotonic()
        time.sleep(1)


def test_default_layout_reads_at_first_glance(sample, served, tmp_path):
    from playwright.sync_api import sync_playwright

    model = sample["model"]
    cameras = list(model.cameras)
    found = views(read_blueprint(sample["rrd"]))
    rects = panel_rects(read_blueprint(sample["rrd"]))
    assert set(cameras) <= set(rects)
    title = {
        key: next(name for name in rects if name.startswith(key))
        for key in (
            "residuals of the solve (ms)",
            "validation error (m)",
            "flash events per camera",
            "plane (m), top view as cam1 sees it",
            "flash log",
        )
    }
    assert len({rects[name] for name in cameras}) == 4  # a row of four videos
    assert all(found[name]["ViewBlueprint:space_origin"] == [f"cameras/{name}"] for name in cameras)
    timeline = viz.timeline.Timeline.of(model)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        try:
            page = browser.new_page(viewport=VIEWPORT)
            page.set_default_timeout(120_000)  # software rendering on a busy machine is slow
            page.goto(served, wait_until="load")
            page.wait_for_selector("canvas")
            time.sleep(SETTLE_S)
            first = timeline.first_camera
            start = screenshot(
                page, lambda image: busy_fraction(crop(image, rects[first])) > 0.3, tmp_path / "start.png"
            )
            x0, y0, _, _ = rects[title["flash log"]]
            row = 2 + 4 * 2  # two lines on time 0, then four per flash

            def click_flash_2():
                page.mouse.click(x0 + 52, y0 + LOG_FIRST_ROW_PX + row * LOG_ROW_PX)

            click_flash_2()
            time.sleep(SETTLE_S / 2)  # the videos seek and decode
            flash = screenshot(
                page,
                lambda image: all(busy_fraction(crop(image, rects[name])) > 0.3 for name in cameras),
                tmp_path / "flash2.png",
                again=click_flash_2,
            )
            canvas = page.locator("canvas").first.bounding_box()
        finally:
            browser.close()
    if os.environ.get("FLASHSYNC_SCREENSHOT"):
        shutil.copy(tmp_path / "flash2.png", os.environ["FLASHSYNC_SCREENSHOT"])
    where = f"see {tmp_path}"
    assert canvas["width"] * canvas["height"] > 0.95 * VIEWPORT["width"] * VIEWPORT["height"]
    gray = cv2.cvtColor(start, cv2.COLOR_BGR2GRAY)
    # At 0 the first camera's video plays; the others say when theirs starts.
    for name in cameras:
        panel = crop(start, rects[name])
        if name == timeline.first_camera:
            assert busy_fraction(panel) > 0.3, where
        else:
            assert 0.002 < busy_fraction(panel) < 0.1 and text_runs(crop(gray, rects[name]), 0) == 1, where
    # One time cursor through the stacked views, at 0 and at flash 2.
    stacked = [
        rects[title[key]] for key in ("flash events per camera", "residuals of the solve (ms)", "validation error (m)")
    ]
    for image in (gray, cv2.cvtColor(flash, cv2.COLOR_BGR2GRAY)):
        columns = [cursor_x(image, rect) for rect in stacked]
        assert max(columns) - min(columns) <= 2, (columns, where)
    assert cursor_x(cv2.cvtColor(flash, cv2.COLOR_BGR2GRAY), stacked[1]) > cursor_x(gray, stacked[1]) + 100
    # Each plot: several labelled ticks on its value axis (left of the time cursor, at 0,
    # the plot's left edge) and on its time axis.
    for key in ("residuals of the solve (ms)", "validation error (m)"):
        x0, y0, x1, y1 = rects[title[key]]
        cursor = cursor_x(gray, rects[title[key]]) - x0
        assert 10 < cursor < 80, (key, where)
        value_axis = gray[y0 + TITLE_PX : y1 - 22, x0 + 2 : x0 + cursor - 1]
        time_axis = gray[y1 - 20 : y1 - 2, x0 + cursor + 10 : x1 - 10]
        assert text_runs(value_axis, 0) >= 3, (key, where)
        assert text_runs(time_axis, 1, gap=8) >= 6, (key, where)
    # A labelled lane per camera (the labels start left of the time cursor at 0).
    x0, y0, x1, y1 = rects[title["flash events per camera"]]
    lane_labels = gray[y0 + TITLE_PX + 16 : y1, x0 + 2 : cursor_x(gray, stacked[0]) - 2]
    assert text_runs(lane_labels, 0) >= len(cameras), where
    # The plane's metre labels along two sides, and its flash log lines.
    x0, y0, x1, y1 = rects[title["plane (m), top view as cam1 sees it"]]
    assert text_runs(gray[y0 + TITLE_PX : y1, x0 + 2 : x0 + 60], 0) >= 3, where
    x0, y0, x1, y1 = rects[title["flash log"]]
    assert text_runs(gray[y0 + LOG_FIRST_ROW_PX - 10 : y1, x0 + 100 : x1 - 20], 0) >= 8, where
    # After the click on flash 2: every camera shows its frame of the flash, and the plane
    # its trail of the puck.
    for name in cameras:
        assert busy_fraction(crop(flash, rects[name])) > 0.3, (name, where)
    assert busy_fraction(crop(flash, rects[title["plane (m), top view as cam1 sees it"]])) > busy_fraction(
        crop(start, rects[title["plane (m), top view as cam1 sees it"]])
    ), where
