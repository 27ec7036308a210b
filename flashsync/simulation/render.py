"""Rolling-shutter rendering of frames and of whole scenarios.

Readout row ``q`` of a frame with camera time ``t_f`` ends its exposure at
``t_f + (r0 + q) * T_row`` (camera time) and integrates light over the preceding
exposure ``E`` of its frame (``exposure_ms``, or another from one of the camera's
``exposure_changes`` on). Both ends are mapped to world time with the camera's clock, so
every row sees the flashes, switches and flicker of its own window. Stored-image row
``r = q``, or ``r = height - 1 - q`` for a camera mounted upside down.

The linear light of a pixel is ``reflectance * shading * gain(f) * (ambient(row) +
flash_gain * exposure_ms / E * flash(row))`` plus Gaussian noise: flashes scale the scene
(multiplicatively), they do not add a constant, and stand out more in a shorter exposure
(auto-exposure keeps the ambient level). The camera's response (`sensor`) maps it to DN,
which are rounded and clipped to 0..255; by default that is the identity.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flashsync.atomic import write_text
from flashsync.simulation.encode import container_stamps, write_video
from flashsync.simulation.light import Lighting, ambient_light, flash_light, flash_reaches
from flashsync.simulation.scenario import CameraSpec, FlashSpec, Scenario, check_scenario
from flashsync.simulation.scene import (
    Player,
    Puck,
    Scene,
    apply_homography,
    camera_background,
    camera_homography,
    make_scene,
    rink_outline_m,
    rink_to_image,
)
from flashsync.simulation.sensor import sensor_response, shading
from flashsync.simulation.truth import GroundTruth, camera_truth, ground_truth

_FLASH_SEEN = 0.02  # a frame "sees" a flash when some row gets this fraction of its strength


@dataclass(frozen=True)
class CameraView:
    """What one camera sees of the static scene.

    Attributes
    ----------
    camera : CameraSpec
    homography : ndarray, shape (3, 3)
        Image px -> rink metres.
    to_image : ndarray, shape (3, 3)
        Rink metres -> image px (third coordinate: depth, positive in front).
    background : ndarray, float32, shape (height, width[, 3])
        Reflectance of the rink in this view, DN.
    shading : ndarray, float32, shape (height, width), or None
        Vignetting factor of each pixel (`sensor.shading`); None without vignetting.
    """

    camera: CameraSpec
    homography: np.ndarray
    to_image: np.ndarray
    background: np.ndarray
    shading: np.ndarray | None = None


def camera_view(scene: Scene, camera: CameraSpec, color: bool = False) -> CameraView:
    """Prepare the static view of `camera` on `scene` (see `CameraView`)."""
    h = camera_homography(camera)
    background = camera_background(scene, h, camera.width, camera.height, color)
    return CameraView(camera, h, rink_to_image(camera), background, shading(camera))


def readout_index(camera: CameraSpec, rows: float | np.ndarray) -> np.ndarray:
    """Readout index ``q`` (0 = read first) of stored-image rows `rows` (float or array)."""
    rows = np.asarray(rows, dtype=float)
    return camera.height - 1 - rows if camera.flipped else rows


def exposure_end_ms(camera: CameraSpec, t_frame_ms: float | np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
    """Camera time at which stored-image rows end their exposure.

    Parameters
    ----------
    camera : CameraSpec
    t_frame_ms : float or ndarray, shape (F,)
        True camera times of frames, ms.
    rows : ndarray, optional
        Stored-image rows (fractional allowed); all rows ``0..height-1`` by default.

    Returns
    -------
    ndarray, shape ``t_frame_ms.shape + rows.shape``
        Camera time, ms.
    """
    if rows is None:
        rows = np.arange(camera.height)
    q = readout_index(camera, rows)
    t = np.asarray(t_frame_ms, dtype=float)[..., None]
    return t + (camera.r0 + q) * camera.row_time_ms


def row_light(camera: CameraSpec, t_frame_ms: float, lighting: Lighting) -> np.ndarray:
    """Illumination factor of each stored-image row of a frame.

    Parameters
    ----------
    camera : CameraSpec
    t_frame_ms : float
        True camera time of the frame, ms.
    lighting : Lighting
        Lighting this camera sees (its missed flashes removed).

    Returns
    -------
    ndarray, shape (height,)
        ``ambient + flash_gain * exposure_ms / E * sum of flash light`` (``E`` the
        frame's exposure); 1 for a plain row.
    """
    exposure = camera.exposure_at_ms(t_frame_ms)
    end = exposure_end_ms(camera, t_frame_ms)
    start_w, end_w = camera.world_ms(end - exposure), camera.world_ms(end)
    light = ambient_light(start_w, end_w, lighting)
    gain = camera.flash_gain * (camera.exposure_ms / exposure)  # auto-exposure keeps the ambient level
    for flash in lighting.flashes:
        if flash_reaches(flash, start_w.min(), end_w.max()):  # the others add exactly 0
            light = light + gain * flash_light(start_w, end_w, flash)
    return light


def frame_gain(camera: CameraSpec, t_frame_ms: float) -> float:
    """Auto-exposure gain of a frame: product of the steps before its start (world time)."""
    w = camera.world_ms(t_frame_ms)
    return float(np.prod([f for at, f in camera.gain_steps if at < w]))


def _draw_object(
    refl: np.ndarray, view: CameraView, obj: Player | Puck, t_frame_ms: float, color: np.ndarray | np.float32
) -> None:
    """Composite a moving disc into `refl` in place, each row at its own exposure times."""
    cam = view.camera
    height, width = refl.shape[:2]
    k = obj.blur_samples
    end = exposure_end_ms(cam, t_frame_ms)
    sub = end[:, None] - cam.exposure_at_ms(t_frame_ms) * (np.arange(k) + 0.5) / k
    pos = obj.position(cam.world_ms(sub))  # (height, k, 2) metres: row r at its own times
    img = apply_homography(view.to_image, pos)  # (height, k, 2) px
    gap = np.abs(img[..., 1] - np.arange(height)[:, None])  # rows from each row to the disc
    if np.isnan(gap).all():
        return
    r, j = np.unravel_index(np.nanargmin(gap), gap.shape)
    m_per_px = np.linalg.norm(apply_homography(view.homography, img[r, j] + [1.0, 0.0]) - pos[r, j])
    reach = obj.radius_m / m_per_px + 2.0
    near = np.flatnonzero(np.any(gap <= reach, axis=1))
    if near.size == 0:
        return
    r_lo, r_hi = near[0], near[-1] + 1
    u = img[r_lo:r_hi, :, 0]
    c_lo = int(max(0, np.floor(np.nanmin(u) - reach)))
    c_hi = int(min(width, np.ceil(np.nanmax(u) + reach) + 1))
    if c_lo >= c_hi:
        return
    vv, uu = np.mgrid[r_lo:r_hi, c_lo:c_hi]
    ground = apply_homography(view.homography, np.stack([uu, vv], axis=-1).astype(float))
    dist = np.linalg.norm(ground[:, :, None, :] - pos[r_lo:r_hi, None, :, :], axis=-1)
    coverage = np.clip((obj.radius_m - dist) / m_per_px + 0.5, 0.0, 1.0)
    alpha = np.nan_to_num(coverage).mean(axis=-1).astype(np.float32)
    patch = refl[r_lo:r_hi, c_lo:c_hi]
    if refl.ndim == 3:
        alpha = alpha[..., None]
    patch += alpha * (color - patch)


def _object_color(obj: Player | Puck, color: bool) -> np.ndarray | np.float32:
    """Object reflectance as BGR (3,) or grey scalar."""
    bgr = np.asarray(obj.color, dtype=np.float32)
    return bgr if color else np.float32(bgr @ [0.114, 0.587, 0.299])


def render_frame(
    view: CameraView,
    scene: Scene,
    t_frame_ms: float,
    lighting: Lighting,
    rng: np.random.Generator | None = None,
    objects: bool = True,
) -> np.ndarray:
    """Render one rolling-shutter frame.

    Parameters
    ----------
    view : CameraView
    scene : Scene
    t_frame_ms : float
        True camera time of the frame, ms.
    lighting : Lighting
        Lighting this camera sees.
    rng : numpy.random.Generator, optional
        Source of sensor noise (``camera.noise_std``, DN of linear light, the same on
        every channel of a pixel); no noise without it.
    objects : bool
        Draw players and puck.

    Returns
    -------
    ndarray, uint8, shape (height, width) or (height, width, 3)
        Grey or BGR image, stored-image orientation.
    """
    cam = view.camera
    color = view.background.ndim == 3
    refl = view.background.copy()
    if objects:
        for obj in scene.objects:
            _draw_object(refl, view, obj, t_frame_ms, _object_color(obj, color))
    light = (row_light(cam, t_frame_ms, lighting) * frame_gain(cam, t_frame_ms)).astype(np.float32)
    img = refl * light.reshape((-1,) + (1,) * (refl.ndim - 1))
    if view.shading is not None:
        img *= view.shading[..., None] if color else view.shading
    if rng is not None and cam.noise_std > 0:
        noise = rng.standard_normal(img.shape[:2], dtype=np.float32)
        noise *= cam.noise_std
        img += noise[..., None] if color else noise
    img = sensor_response(img, cam)
    np.rint(img, out=img)
    return np.clip(img, 0, 255, out=img).astype(np.uint8)


def puck_track(view: CameraView, puck: Puck, t_frame_ms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Image position of the puck's blurred centroid in frames, with rolling-shutter skew.

    The puck is seen by the row it lies in, at that row's mid-exposure time; the row is
    found by fixed-point iteration (it converges in a step or two).

    Parameters
    ----------
    view : CameraView
    puck : Puck
    t_frame_ms : ndarray, shape (F,)
        True camera times of frames, ms.

    Returns
    -------
    xy : ndarray, shape (F, 2)
        Image x (column) and stored-image row of the centroid, px.
    visible : ndarray of bool, shape (F,)
        Centroid inside the image.
    """
    cam = view.camera
    t = np.asarray(t_frame_ms, dtype=float)
    half_exposure = cam.exposure_at_ms(t) / 2.0
    row = np.full(t.shape, (cam.height - 1) / 2.0)
    for _ in range(3):
        mid = t + (cam.r0 + readout_index(cam, row)) * cam.row_time_ms - half_exposure
        xy = apply_homography(view.to_image, puck.position(cam.world_ms(mid)))
        row = np.clip(np.nan_to_num(xy[:, 1], nan=-1.0), -1.0, cam.height)
    with np.errstate(invalid="ignore"):
        visible = (xy[:, 0] >= 0) & (xy[:, 0] <= cam.width - 1) & (xy[:, 1] >= 0) & (xy[:, 1] <= cam.height - 1)
    return xy, visible


def flash_frames(camera: CameraSpec, t_frame_ms: np.ndarray, flash: FlashSpec) -> np.ndarray:
    """Which frames show a flash.

    Parameters
    ----------
    camera : CameraSpec
    t_frame_ms : ndarray, shape (F,)
        True camera times of frames, ms.
    flash : FlashSpec

    Returns
    -------
    ndarray of bool, shape (F,)
        Some visible row integrates at least 2 % of the flash's strength.
    """
    end = exposure_end_ms(camera, t_frame_ms)
    start = end - camera.exposure_at_ms(t_frame_ms)[:, None]
    light = flash_light(camera.world_ms(start), camera.world_ms(end), flash)
    return light.max(axis=1) >= _FLASH_SEEN * flash.strength


def camera_rng(scenario: Scenario, index: int, purpose: int) -> np.random.Generator:
    """Random generator of camera `index` for one purpose (0 noise, 1 drops, 2 misses, 3 jitter)."""
    return np.random.default_rng([scenario.seed, index, purpose])


def kept_frames(scenario: Scenario, index: int) -> np.ndarray:
    """Sensor frame indices that camera `index` writes (its drops and gaps removed), shape (F,)."""
    cam = scenario.cameras[index]
    n = scenario.frame_count(cam)
    keep = np.ones(n, dtype=bool)
    keep[[f for f in cam.dropped_frames if 0 <= f < n]] = False
    for first, count in cam.frame_gaps:
        keep[max(first, 0) : max(first + count, 0)] = False
    keep[1:-1] &= camera_rng(scenario, index, 1).random(max(n - 2, 0)) >= cam.drop_fraction
    return np.flatnonzero(keep)


def missed_flashes(scenario: Scenario, index: int) -> list[int]:
    """Indices of the scenario's flashes that camera `index` does not see."""
    cam = scenario.cameras[index]
    draw = camera_rng(scenario, index, 2).random(len(scenario.flashes))
    return sorted(set(cam.missed_flashes) | set(np.flatnonzero(draw < cam.miss_probability).tolist()))


def camera_lighting(scenario: Scenario, index: int) -> Lighting:
    """`Lighting` seen by camera `index`: the scenario's, without its missed flashes."""
    missed = missed_flashes(scenario, index)
    return Lighting(
        flashes=tuple(f for k, f in enumerate(scenario.flashes) if k not in missed),
        switches=tuple(scenario.switches),
        flicker_depth=scenario.flicker_depth,
        flicker_hz=scenario.flicker_hz,
        flicker_phase=scenario.flicker_phase,
        flicker_waveform=scenario.flicker_waveform,
    )


def _reporting(
    frames: Iterable[np.ndarray], name: str, total: int, progress: Callable[[str, int, int], None] | None
) -> Iterator[np.ndarray]:
    """Yield from `frames`, calling ``progress(name, done, total)`` after each."""
    for done, frame in enumerate(frames, start=1):
        yield frame
        if progress is not None:
            progress(name, done, total)


def render_scenario(
    scenario: Scenario, out_dir: str | Path, progress: Callable[[str, int, int], None] | None = None
) -> GroundTruth:
    """Render every camera of a scenario to video files, with ground truth.

    Writes ``<camera>.mp4`` or ``<camera>.mkv`` per camera, ``truth.json``,
    ``detections.csv`` (columns ``camera,frame,x,y,object``: the puck's centroid in each
    frame where it is in view, px) and ``homographies.json`` (``{camera: 3x3 image px ->
    rink metres}`` and ``"plane": {"outline_m": [[x, y], ...]}``, the edge of the ice)
    into `out_dir`, each atomically.

    Parameters
    ----------
    scenario : Scenario
    out_dir : str or Path
        Created if missing.
    progress : callable, optional
        Called as ``progress(camera_name, frames_done, frames_total)``.

    Returns
    -------
    GroundTruth

    Examples
    --------
    >>> truth = render_scenario(preset("tiny"), "out/tiny")  # doctest: +SKIP
    >>> truth.global_time_ms("cam2", [0, 1], [10.5, 90.0])  # doctest: +SKIP
    """
    check_scenario(scenario, f"scenario '{scenario.name}'")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scene = make_scene(scenario.seed, scenario.n_players, scenario.puck_speed_mps, scenario.player_radius_m)
    cameras, homographies, detections = [], {}, []
    for i, cam in enumerate(scenario.cameras):
        view = camera_view(scene, cam, scenario.color)
        lighting = camera_lighting(scenario, i)
        rng = camera_rng(scenario, i, 0)
        frames = kept_frames(scenario, i)
        t_true = cam.start_ms + frames * cam.frame_period_ms
        pts, time_base = container_stamps(cam, t_true, camera_rng(scenario, i, 3))
        path = out / f"{cam.name}.{cam.container}"
        images = (render_frame(view, scene, t, lighting, rng) for t in t_true)
        write_video(
            path,
            _reporting(images, cam.name, len(frames), progress),
            pts,
            time_base,
            crf=cam.crf,
            fps=cam.fps,
            keyint=cam.keyint,
            bframes=cam.bframes,
            preset=cam.x264_preset,
            open_gop=cam.open_gop,
        )
        homographies[cam.name] = view.homography.tolist()
        xy, visible = puck_track(view, scene.puck, t_true)
        detections += [
            (cam.name, j, round(float(x), 3), round(float(y), 3), "puck")
            for j, ((x, y), v) in enumerate(zip(xy, visible))
            if v
        ]
        missed = missed_flashes(scenario, i)
        seen = {
            k: np.flatnonzero(flash_frames(cam, t_true, fl)).tolist()
            for k, fl in enumerate(scenario.flashes)
            if k not in missed
        }
        stamps_ms = pts * 1000.0 * float(time_base)
        cameras.append(camera_truth(cam, path.name, frames, t_true, stamps_ms, seen, scenario.cameras[0]))
    truth = ground_truth(scenario, cameras)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["camera", "frame", "x", "y", "object"])
    writer.writerows(detections)
    write_text(out / "detections.csv", buf.getvalue())
    homographies["plane"] = {"outline_m": rink_outline_m().round(4).tolist()}
    write_text(out / "homographies.json", json.dumps(homographies, indent=1))
    truth.save(out / "truth.json")
    return truth
