"""The Rerun web viewer shows a flashsync recording: headless Chromium, software GPU.

Serves the tiny scenario's recording with ``rerun --serve-web`` on localhost, opens it in
Debian's Chromium driven by playwright (no browser download) and checks the screenshot:
the viewer's canvas fills the page and the views show data -- the camera videos fill the
top half of the default layout, so most pixels differ from the background, unlike the
welcome screen or views still loading (about 5 %).
"""

import importlib.util
import os
import signal
import subprocess
import time
import urllib.parse
import urllib.request
from pathlib import Path

import cv2
import numpy as np
import pytest
from test_viz import RERUN, free_port, quiet_rerun, tiny  # noqa: F401 (shared fixtures)

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
VIEWPORT = {"width": 1024, "height": 640}
SETTLE_S, TIMEOUT_S = 10.0, 150.0

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("playwright") is None or not CHROMIUM.exists(),
    reason="needs the playwright package and Debian's /usr/bin/chromium",
)


def busy_fraction(png: bytes) -> float:
    """Fraction of pixels more than 8 levels away from the most common colour."""
    image = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR).reshape(-1, 3)
    colors, counts = np.unique(image, axis=0, return_counts=True)
    background = colors[counts.argmax()].astype(int)
    return float(np.mean(np.any(np.abs(image.astype(int) - background) > 8, axis=1)))


@pytest.fixture
def served(tiny):  # noqa: F811 (the imported fixture)
    """``rerun --serve-web`` on the recording; yields the viewer's address, then stops it."""
    web_port, grpc_port = free_port(), free_port()
    server = subprocess.Popen(
        [
            str(RERUN),
            "--serve-web",
            "--bind",
            "127.0.0.1",
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            str(tiny["rrd"]),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        address = f"http://127.0.0.1:{web_port}/"
        deadline = time.monotonic() + 60
        while True:
            try:
                urllib.request.urlopen(address, timeout=5).close()
                break
            except OSError:
                assert server.poll() is None and time.monotonic() < deadline, "no web viewer"
                time.sleep(0.5)
        source = urllib.parse.quote(f"rerun+http://127.0.0.1:{grpc_port}/proxy", safe="")
        yield f"{address}?url={source}"
    finally:
        os.killpg(server.pid, signal.SIGTERM)  # the `rerun` script and the viewer binary
        server.wait(timeout=30)


def test_web_viewer_renders_the_recording(served, tmp_path):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        try:
            page = browser.new_page(viewport=VIEWPORT)
            page.set_default_timeout(120_000)  # software rendering on a busy machine is slow
            page.goto(served, wait_until="load")
            page.wait_for_selector("canvas")
            time.sleep(SETTLE_S)  # the viewer's wasm, then the data and the videos
            started = time.monotonic()
            while busy_fraction(png := page.screenshot()) < 0.2 and time.monotonic() - started < TIMEOUT_S:
                time.sleep(3)
            (tmp_path / "viewer.png").write_bytes(png)
            canvas = page.locator("canvas").first.bounding_box()
        finally:
            browser.close()
    assert canvas["width"] * canvas["height"] > 0.9 * VIEWPORT["width"] * VIEWPORT["height"]
    image = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    assert image.shape[:2] == (VIEWPORT["height"], VIEWPORT["width"])
    assert image.std() > 30, "blank page"
    assert busy_fraction(png) > 0.2, f"views show no data; see {tmp_path / 'viewer.png'}"
