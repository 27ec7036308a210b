"""The simulator's second world: seeded random rigs, and recipes of the rigs in the issues.

The presets render the world the detector was designed for (an exponential flash on a
linear sensor). `random_rig` draws rigs from a wider world, so that benchmarks and tests
stop being matched to the detector's model: flash pulses of other shapes, tone curves,
black levels and clipping, long GOPs and B-frames, short exposures, NTSC rates, rolling
mains flicker, crowds of movers, jittered and quantised stamps, drops and drifts. Same
seed, same scenario (and the same frames; see `scenario`).

Distributions of `random_rig` (U: uniform, logU: log-uniform, p: probability):

=================  ==========================================================================
rig                cameras U{2..12} (first = reference); duration as given (20 s);
                   flashes U{6..16} at irregular instants in [8 %, 92 %] of the recording,
                   >= 400 ms apart, strength U(0.25, 0.8); one pulse shape per rig (one
                   strobe), each kind p 1/4: exponential (decay U(0.2, 1) ms), xenon
                   (linear rise U(10, 80) us, decay U(0.13, 1.3) ms: 0.3-3 ms to a
                   tenth), LED (rectangle U(0.1, 2) ms), slow rise (raised-cosine rise
                   U(0.1, 1) ms, decay U(0.2, 1) ms); mains flicker p 1/2: depth
                   logU(0.5 %, 10 %), 100 or 120 Hz, sine or rectified waveform, random
                   phase; players U{4..30}, radius 0.4-0.55 m or (p 1/4) 0.8-2.5 m;
                   puck U(20, 45) m/s; colour p 1/4.
size               U over 320x180, 480x270, 640x360, 960x540, 1280x720, 1920x1080 with
                   height <= ``max_height``; hidden rows r0 U(1, 6) %, r1 U(0.5, 4) % of
                   the height.
rate               U over 25, 29.97 (30000/1001), 30, 50, 59.94 (60000/1001) fps.
exposure           logU(0.5, 16) ms, at most 95 % of the frame period.
readout            upside down p 1/5.
stamps             U over: MP4 90 kHz; MKV 1 ms; MP4 quantised to 1 ms; MP4 jittered
                   (std U(0.05, 1) ms).
drops              none p 0.6, else a fraction U(0.2 %, 3 %).
clock              drift U(-50, 50) ppm; non-reference cameras p 0.3 a drift changing by
                   U(-0.01, 0.01) ppm/s; first frame at camera time U(0, 100) s, at world
                   time U(-3 %, 3 %) of the duration.
coverage           each flash missed with probability U(0, 0.3) (per camera).
sensor             flash gain U(0.7, 1.3); noise U(0.5, 2.5) DN; tone linear, sRGB or gamma
                   (p 1/3 each); black level 0 (p 1/2) or U(4, 16) DN; white level
                   U(200, 450) (bright ice and flash rows clip below ~300); vignetting 0
                   (p 1/2) or U(0.1, 0.5).
encoder            crf U{18..30}; keyint x264's 250, 60 or 600; bframes x264's 3, 0 or 2;
                   preset medium, veryfast or fast.
pose               looks at a point of the ice from 15-35 m away and 10-18 m up, field of
                   view 50-80 degrees (redrawn until the image stays below the horizon).
=================  ==========================================================================

`with_preflashes` fires a rig's flashes as TTL flashes do: a weak pre-flash a few tens of ms
before each, which some cameras do not see. `with_fast_readout` gives a rig's sensors a
readout faster than their frame period (a sensor built for 50-120 fps run at 25-30 reads
its rows in a fraction of the frame and idles in a long vertical blanking), which
`random_rig` never draws. `with_flash_powers` fires a rig's flashes at two powers, some
pulses 2-3 ms long and the rest 0.05-0.3 ms (a speedlight's power setting, or two
strobes), where `random_rig` draws each rig's pulse lengths from one range.
`with_exposure_changes` gives some cameras one auto-exposure change mid-recording.

`RECIPES` names fixed rigs: the independent-footage rigs of the honest-numbers issue's
table, the real-light issue's cases and frame rates outside `random_rig`'s (15-24 and
120-240 fps), re-created with second-world settings (xenon or LED pulses, a tone curve, crf
18-30); their seed draws only those settings, the flash instants and the scene.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections.abc import Callable

import numpy as np

from flashsync.errors import FlashsyncError
from flashsync.simulation.scenario import CameraSpec, FlashSpec, Scenario, check_scenario
from flashsync.simulation.scene import rink_to_image

NTSC_30 = 30000 / 1001
NTSC_60 = 60000 / 1001
NTSC_24 = 24000 / 1001
RATES = (25.0, NTSC_30, 30.0, 50.0, NTSC_60)
SIZES = ((320, 180), (480, 270), (640, 360), (960, 540), (1280, 720), (1920, 1080))
PULSES = ("exponential", "xenon", "led", "slow rise")
STAMPS = ("mp4 90 kHz", "mkv 1 ms", "quantised 1 ms", "jittered")


def pulse(kind: str, world_ms: float, strength: float, rng: np.random.Generator) -> FlashSpec:
    """A flash of one of the `PULSES` kinds with its shape drawn as in `random_rig`."""
    if kind == "exponential":
        return FlashSpec(world_ms, strength, decay_ms=rng.uniform(0.2, 1.0))
    if kind == "xenon":
        return FlashSpec(world_ms, strength, decay_ms=rng.uniform(0.13, 1.3), rise_ms=rng.uniform(0.01, 0.08))
    if kind == "led":
        return FlashSpec(world_ms, strength, decay_ms=0.0, hold_ms=rng.uniform(0.1, 2.0))
    if kind == "slow rise":
        return FlashSpec(
            world_ms, strength, decay_ms=rng.uniform(0.2, 1.0), rise_ms=rng.uniform(0.1, 1.0), rise="cosine"
        )
    raise FlashsyncError(f"unknown pulse kind {kind!r}; choose one of {', '.join(PULSES)}")


def flash_instants(
    rng: np.random.Generator, count: int, start_ms: float, stop_ms: float, min_gap_ms: float
) -> np.ndarray:
    """`count` irregular instants in [start_ms, stop_ms], at least `min_gap_ms` apart, ms."""
    count = max(1, min(count, 1 + int((stop_ms - start_ms) // min_gap_ms)))
    slack = max(stop_ms - start_ms - (count - 1) * min_gap_ms, 0.0)
    return start_ms + np.sort(rng.uniform(0.0, slack, count)) + np.arange(count) * min_gap_ms


def random_pose(rng: np.random.Generator, width: int, height: int) -> dict:
    """``position_m``, ``look_at_m`` and ``hfov_deg`` of a camera above the rink whose
    image stays below the horizon."""
    for _ in range(100):
        look = (float(rng.uniform(8.0, 52.0)), float(rng.uniform(6.0, 24.0)))
        bearing, distance = rng.uniform(0.0, 2.0 * np.pi), rng.uniform(15.0, 35.0)
        pose = dict(
            position_m=(
                look[0] + distance * np.cos(bearing),
                look[1] + distance * np.sin(bearing),
                float(rng.uniform(10.0, 18.0)),
            ),
            look_at_m=look,
            hfov_deg=float(rng.uniform(50.0, 80.0)),
        )
        pose["position_m"] = tuple(float(v) for v in pose["position_m"])
        try:
            rink_to_image(CameraSpec("pose", width, height, 25.0, **pose))
        except FlashsyncError:
            continue
        return pose
    raise FlashsyncError("no camera pose below the horizon found in 100 draws")


def _stamps(kind: str, rng: np.random.Generator) -> dict:
    """Container and stamp fields of a camera for one of the `STAMPS` kinds."""
    if kind == "mkv 1 ms":
        return dict(container="mkv")
    if kind == "quantised 1 ms":
        return dict(container="mp4", quantize_ms=1.0)
    if kind == "jittered":
        return dict(container="mp4", jitter_ms=float(rng.uniform(0.05, 1.0)))
    return dict(container="mp4")


def _sensor(rng: np.random.Generator) -> dict:
    """Sensor response and encoder fields, drawn as in `random_rig`."""
    return dict(
        flash_gain=float(rng.uniform(0.7, 1.3)),
        noise_std=float(rng.uniform(0.5, 2.5)),
        tone=str(rng.choice(["linear", "srgb", "gamma"])),
        black_level=0.0 if rng.random() < 0.5 else float(rng.uniform(4.0, 16.0)),
        white_level=float(rng.uniform(200.0, 450.0)),
        vignetting=0.0 if rng.random() < 0.5 else float(rng.uniform(0.1, 0.5)),
        crf=int(rng.integers(18, 31)),
        keyint=[None, 60, 600][rng.integers(3)],
        bframes=[None, 0, 2][rng.integers(3)],
        x264_preset=[None, "veryfast", "fast"][rng.integers(3)],
    )


def _clock(rng: np.random.Generator, duration_ms: float, reference: bool) -> dict:
    """Clock fields: drift, a drifting drift (not on the reference), first frame."""
    drift = float(rng.uniform(-50.0, 50.0))
    rate = float(rng.uniform(-0.01, 0.01)) if not reference and rng.random() < 0.3 else 0.0
    start = float(rng.uniform(0.0, 100_000.0))
    world_first = float(rng.uniform(-0.03, 0.03)) * duration_ms
    offset = world_first - (1.0 + drift * 1e-6) * start - 0.5 * rate * 1e-9 * start**2
    return dict(drift_ppm=drift, drift_rate_ppm_per_s=rate, start_ms=start, offset_ms=offset)


def _hidden_rows(rng: np.random.Generator, height: int) -> dict:
    return dict(r0=int(round(height * rng.uniform(0.01, 0.06))), r1=int(round(height * rng.uniform(0.005, 0.04))))


def random_camera(
    rng: np.random.Generator, name: str, duration_ms: float, max_height: int = 1080, reference: bool = False
) -> CameraSpec:
    """One camera drawn as in `random_rig`."""
    sizes = [s for s in SIZES if s[1] <= max_height]
    if not sizes:
        raise FlashsyncError(f"max_height {max_height} is below the smallest size {SIZES[0][1]} rows")
    width, height = sizes[rng.integers(len(sizes))]
    fps = RATES[rng.integers(len(RATES))]
    exposure = min(float(np.exp(rng.uniform(np.log(0.5), np.log(16.0)))), 0.95 * 1000.0 / fps)
    return CameraSpec(
        name,
        width,
        height,
        fps,
        exposure_ms=round(exposure, 3),
        flipped=bool(rng.random() < 0.2),
        drop_fraction=0.0 if rng.random() < 0.6 else float(rng.uniform(0.002, 0.03)),
        miss_probability=float(rng.uniform(0.0, 0.3)),
        **_hidden_rows(rng, height),
        **_clock(rng, duration_ms, reference),
        **_stamps(STAMPS[rng.integers(len(STAMPS))], rng),
        **_sensor(rng),
        **random_pose(rng, width, height),
    )


def random_rig(
    seed: int, max_height: int = 1080, duration_ms: float = 20_000.0, cameras: tuple[int, int] = (2, 12)
) -> Scenario:
    """A random rig of the second world (distributions in the module docstring).

    Parameters
    ----------
    seed : int
        Seed of every choice; the same seed gives the same scenario.
    max_height : int
        Largest image height drawn, rows (540 keeps a benchmark fast).
    duration_ms : float
        Recording length of every camera, ms.
    cameras : (int, int)
        Fewest and most cameras.

    Returns
    -------
    Scenario
        Named ``rig-<seed>``; the first camera is the reference.

    Examples
    --------
    >>> rig = random_rig(3, max_height=540)
    >>> rig == random_rig(3, max_height=540)
    True
    """
    rng = np.random.default_rng([seed, 2017])
    n = int(rng.integers(cameras[0], cameras[1] + 1))
    specs = tuple(random_camera(rng, f"cam{i + 1}", duration_ms, max_height, reference=i == 0) for i in range(n))
    kind = PULSES[rng.integers(len(PULSES))]
    instants = flash_instants(rng, int(rng.integers(6, 17)), 0.08 * duration_ms, 0.92 * duration_ms, 400.0)
    flashes = tuple(pulse(kind, round(float(t), 3), round(float(rng.uniform(0.25, 0.8)), 3), rng) for t in instants)
    flicker = rng.random() < 0.5
    large = rng.random() < 0.25
    scenario = Scenario(
        f"rig-{seed}",
        specs,
        duration_ms=duration_ms,
        flashes=flashes,
        flicker_depth=float(np.exp(rng.uniform(np.log(0.005), np.log(0.10)))) if flicker else 0.0,
        flicker_hz=float(rng.choice([100.0, 120.0])),
        flicker_phase=float(rng.uniform(0.0, 2.0 * np.pi)),
        flicker_waveform=str(rng.choice(["sine", "rectified"])),
        n_players=int(rng.integers(4, 31)),
        player_radius_m=(0.8, 2.5) if large else (0.4, 0.55),
        puck_speed_mps=float(rng.uniform(20.0, 45.0)),
        color=bool(rng.random() < 0.25),
        seed=int(seed),
    )
    check_scenario(scenario, f"random rig {seed}")
    return scenario


def _recipe_camera(
    rng: np.random.Generator,
    name: str,
    width: int,
    height: int,
    fps: float,
    exposure_ms: float,
    duration_ms: float,
    reference: bool = False,
    **fields,
) -> CameraSpec:
    """A camera of a recipe: the given geometry, rate and exposure; second-world sensor and
    encoder (tone sRGB or gamma, crf 18-30), a random pose and clock; `fields` override."""
    sensor = _sensor(rng)
    sensor["tone"] = str(rng.choice(["srgb", "gamma"]))
    spec = CameraSpec(
        name,
        width,
        height,
        fps,
        exposure_ms=exposure_ms,
        **_hidden_rows(rng, height),
        **_clock(rng, duration_ms, reference),
        **sensor,
        **random_pose(rng, width, height),
    )
    return dataclasses.replace(spec, **{"drift_rate_ppm_per_s": 0.0, **fields})


def _recipe(name: str, seed: int, duration_ms: float, cameras: list[tuple], flashes: int = 12, **scene) -> Scenario:
    """A scenario of a recipe: cameras as ``(name, width, height, fps, exposure_ms,
    fields)``, xenon or LED flashes at irregular instants, the scene fields given."""
    rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
    specs = tuple(
        _recipe_camera(rng, cam, w, h, fps, exp, duration_ms, reference=i == 0, **fields)
        for i, (cam, w, h, fps, exp, fields) in enumerate(cameras)
    )
    kind = ("xenon", "led")[rng.integers(2)]
    instants = flash_instants(rng, flashes, 0.08 * duration_ms, 0.92 * duration_ms, 400.0) if flashes else []
    pulses = tuple(pulse(kind, round(float(t), 3), round(float(rng.uniform(0.3, 0.7)), 3), rng) for t in instants)
    scene.setdefault("n_players", int(rng.integers(6, 15)))
    scenario = Scenario(name, specs, duration_ms=duration_ms, flashes=pulses, seed=seed, **scene)
    check_scenario(scenario, f"recipe {name}")
    return scenario


def _four_ms_drops(seed: int, duration_ms: float) -> Scenario:
    ms = dict(container="mkv")
    return _recipe(
        "four-ms-drops",
        seed,
        duration_ms,
        [
            ("cam1", 960, 540, 25.0, 6.0, dict(ms, drop_fraction=0.01)),
            ("cam2", 960, 540, 25.0, 6.0, dict(ms, drop_fraction=0.02)),
            ("cam3", 640, 360, 25.0, 4.0, dict(ms, drop_fraction=0.01)),
            ("cam4", 640, 360, 25.0, 3.0, dict(ms, drop_fraction=0.02)),
        ],
    )


def _three_rates_flipped(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "three-rates-flipped",
        seed,
        duration_ms,
        [
            ("cam1", 640, 360, 25.0, 5.0, {}),
            ("cam2", 640, 360, 30.0, 4.0, dict(flipped=True)),
            ("cam3", 640, 360, 50.0, 3.0, {}),
        ],
    )


def _twin_flipped(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "twin-flipped",
        seed,
        duration_ms,
        [("cam1", 640, 360, 25.0, 4.0, {}), ("cam2", 640, 360, 25.0, 4.0, dict(flipped=True))],
    )


def _twin_drops(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "twin-drops",
        seed,
        duration_ms,
        [("cam1", 640, 360, 25.0, 4.0, {}), ("cam2", 640, 360, 25.0, 4.0, dict(drop_fraction=0.05))],
    )


def _line_locked(seed: int, duration_ms: float) -> Scenario:
    """Three 25 fps cameras line-locked to the mains: one clock (no drift between them) and
    frames that start within 0.3 ms of one phase, so a flash falls on nearly the same row of
    each; only a flash at a frame's turn splits a band."""
    rng = np.random.default_rng([seed, zlib.crc32(b"line-locked")])

    def locked(first_frame_ms: float) -> dict:
        start = float(rng.uniform(0.0, 100_000.0))
        return dict(drift_ppm=0.0, start_ms=start, offset_ms=first_frame_ms - start)

    cameras = [("cam1", 640, 360, 25.0, 4.0, locked(0.0))]
    for name, exposure in (("cam2", 3.0), ("cam3", 2.0)):
        first = 40.0 * int(rng.integers(-20, 21)) + float(rng.uniform(0.0, 0.3))
        cameras.append((name, 640, 360, 25.0, exposure, locked(first)))
    return _recipe("line-locked", seed, duration_ms, cameras)


def _hd(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "hd",
        seed,
        duration_ms,
        [
            ("cam1", 1920, 1080, NTSC_30, 2.0, dict(drift_ppm=0.0)),
            ("cam2", 1280, 720, NTSC_30, 4.0, dict(drift_ppm=8.0)),
            ("cam3", 1280, 720, NTSC_60, 3.0, dict(drift_ppm=10.0)),
        ],
    )


def _twelve(seed: int, duration_ms: float) -> Scenario:
    rates = (25.0, 30.0, 50.0)
    exposures = (4.0, 2.0, 6.0, 3.0, 5.0, 4.0)
    return _recipe(
        "twelve",
        seed,
        duration_ms,
        [(f"cam{i + 1}", 320, 180, rates[i % 3], exposures[i % 6], dict(miss_probability=0.3)) for i in range(12)],
        flashes=16,
    )


#: The real-light issue's rigs use linear sensors, as its footage did: a tone curve
#: compresses 3 % of flicker in linear light to about 1.4 % (sRGB or gamma 1/2.2 at
#: mid-grey), under the detector's smallest change.
_LINEAR = dict(tone="linear")


def _rolling_flicker(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "rolling-flicker",
        seed,
        duration_ms,
        [("cam1", 640, 360, 30.0, 0.5, _LINEAR), ("cam2", 640, 360, 25.0, 1.0, _LINEAR)],
        flicker_depth=0.03,
        flicker_hz=100.0,
    )


_NEAR = dict(_LINEAR, position_m=(30.0, -4.0, 10.0), look_at_m=(30.0, 12.0), hfov_deg=60.0)
_FAR_SIDE = dict(_LINEAR, position_m=(30.0, 34.0, 10.0), look_at_m=(30.0, 18.0), hfov_deg=60.0)


def _action_cams(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "action-cams",
        seed,
        duration_ms,
        [("cam1", 640, 360, 120.0, 2.0, {}), ("cam2", 640, 360, 30.0, 4.0, {}), ("cam3", 640, 360, 240.0, 1.0, {})],
    )


def _slow_rates(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "slow-rates",
        seed,
        duration_ms,
        [("cam1", 640, 360, 15.0, 10.0, {}), ("cam2", 640, 360, 20.0, 8.0, {}), ("cam3", 640, 360, NTSC_24, 10.0, {})],
    )


def _large_movers(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "large-movers",
        seed,
        duration_ms,
        [("cam1", 320, 240, 25.0, 8.0, _NEAR), ("cam2", 320, 240, 30.0, 8.0, _FAR_SIDE)],
        n_players=10,
        player_radius_m=(0.55, 1.1),
    )


def _long_pair(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "long-pair",
        seed,
        duration_ms,
        [
            ("cam1", 320, 240, 25.0, 8.0, _NEAR),
            ("cam2", 320, 240, 30.0, 8.0, dict(_FAR_SIDE, drift_ppm=12.0, drift_rate_ppm_per_s=0.01)),
        ],
        flashes=30,
        n_players=10,
        player_radius_m=(0.55, 1.1),
    )


def _jittered_stamps(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "jittered-stamps",
        seed,
        duration_ms,
        [
            ("cam1", 640, 360, 25.0, 4.0, {}),
            ("cam2", 640, 360, 30.0, 5.0, dict(jitter_ms=1.2)),
            ("cam3", 640, 360, 50.0, 3.0, {}),
        ],
    )


def _stamp_rate_change(seed: int, duration_ms: float) -> Scenario:
    middle = int(duration_ms * 30.0 / 1000.0) // 2
    return _recipe(
        "stamp-rate-change",
        seed,
        duration_ms,
        [("cam1", 640, 360, 25.0, 4.0, {}), ("cam2", 640, 360, 30.0, 5.0, dict(stamp_rate_changes=((middle, 1.5),)))],
    )


def _flash_free(seed: int, duration_ms: float) -> Scenario:
    return _recipe(
        "flash-free",
        seed,
        duration_ms,
        [("cam1", 320, 240, 25.0, 8.0, _NEAR), ("cam2", 320, 240, 30.0, 8.0, _FAR_SIDE)],
        flashes=0,
        flicker_depth=0.05,
        flicker_hz=100.0,
        n_players=20,
    )


#: Named rigs: ``RECIPES[name] = (build(seed, duration_ms) -> Scenario, default duration
#: ms)``. The first six are the rows of the honest-numbers issue's table (``hd``: clocks 8
#: and 10 ppm apart, as in the discrepancy issue); ``rolling-flicker`` (a 30 fps camera with a
#: 0.5 ms exposure under 3 % 100 Hz flicker), ``large-movers`` (ten players 8-16 px in
#: radius at 320x240, three in four dark), ``long-pair`` (the same two cameras for 15
#: minutes, 30 flashes, a drift that changes with time) and ``flash-free`` (5 % flicker,
#: twenty players, no flash) are the real-light issue's, with linear sensors;
#: ``jittered-stamps`` (stamps of one camera jittered by 1.2 ms) and ``stamp-rate-change``
#: (one camera's stamps advance 1.5x as fast from its middle frame on) the stamp faults of
#: the silent-harm issue; ``line-locked`` (three 25 fps cameras on one clock, in one phase)
#: the equal-rate case of a time per row the flashes barely pin; ``action-cams`` (120 and
#: 240 fps cameras beside a 30 fps one: pulses tens of rows long) and ``slow-rates`` (IP and
#: cinema cameras at 15, 20 and 23.976 fps) rates outside the random rigs' 25-59.94.
RECIPES: dict[str, tuple[Callable[[int, float], Scenario], float]] = {
    "four-ms-drops": (_four_ms_drops, 30_000.0),
    "three-rates-flipped": (_three_rates_flipped, 30_000.0),
    "twin-flipped": (_twin_flipped, 30_000.0),
    "twin-drops": (_twin_drops, 30_000.0),
    "hd": (_hd, 40_000.0),
    "twelve": (_twelve, 30_000.0),
    "rolling-flicker": (_rolling_flicker, 30_000.0),
    "large-movers": (_large_movers, 30_000.0),
    "long-pair": (_long_pair, 900_000.0),
    "flash-free": (_flash_free, 30_000.0),
    "jittered-stamps": (_jittered_stamps, 30_000.0),
    "stamp-rate-change": (_stamp_rate_change, 30_000.0),
    "line-locked": (_line_locked, 30_000.0),
    "action-cams": (_action_cams, 12_000.0),
    "slow-rates": (_slow_rates, 30_000.0),
}


#: x264 constant rate factor of :func:`second_world`'s cameras (the middle of the recipes' 18-30).
SECOND_WORLD_CRF = 23


def second_world(scenario: Scenario, seed: int = 0, pulses: tuple[str, ...] | None = None) -> Scenario:
    """`scenario` re-dressed in the second world, all else kept (clocks, geometry, stamps,
    exposures, hidden rows, white levels, the flashes' instants and strengths): each
    camera's sensor as a recipe's (tone sRGB or gamma, black level U(4, 16) DN, noise
    U(0.5, 2.5) DN, flash gain U(0.7, 1.3)) encoded by x264 at crf
    :data:`SECOND_WORLD_CRF`, and every flash a xenon or an LED pulse, its shape drawn as in
    `random_rig`: one kind per rig, or the kinds of `pulses` (of `PULSES`) in turn.

    Examples
    --------
    >>> from flashsync.simulation import preset
    >>> {c.tone for c in second_world(preset("tiny")).cameras} <= {"srgb", "gamma"}
    True
    """
    rng = np.random.default_rng([seed, zlib.crc32(b"second world")])
    cameras = tuple(
        dataclasses.replace(
            camera,
            tone=str(rng.choice(["srgb", "gamma"])),
            black_level=float(rng.uniform(4.0, 16.0)),
            noise_std=float(rng.uniform(0.5, 2.5)),
            flash_gain=float(rng.uniform(0.7, 1.3)),
            crf=SECOND_WORLD_CRF,
        )
        for camera in scenario.cameras
    )
    kinds = pulses or (("xenon", "led")[rng.integers(2)],)
    flashes = tuple(
        pulse(kinds[i % len(kinds)], flash.world_ms, flash.strength, rng) for i, flash in enumerate(scenario.flashes)
    )
    dressed = dataclasses.replace(scenario, cameras=cameras, flashes=flashes)
    check_scenario(dressed, f"{scenario.name} in the second world")
    return dressed


def with_preflashes(
    scenario: Scenario,
    delay_ms: float = 60.0,
    share: float = 0.3,
    jitter_ms: float = 1.0,
    blind: tuple[str, ...] | None = None,
    seed: int = 0,
) -> Scenario:
    """`scenario` fired by TTL flashes: before each flash a pre-flash of its pulse at
    ``share`` of its strength, ``delay_ms`` earlier give or take a normal deviate of std
    ``jitter_ms`` (per flash); the cameras of ``blind`` do not see the pre-flashes (by
    default each camera p 1/2, drawn from ``seed``). A camera's ``missed_flashes`` stay
    missed (their pre-flashes are not); its ``miss_probability`` applies to the pre-flashes
    too.

    Examples
    --------
    >>> from flashsync.simulation import preset
    >>> tiny = preset("tiny")
    >>> len(with_preflashes(tiny, blind=("cam2",)).flashes) == 2 * len(tiny.flashes)
    True
    """
    rng = np.random.default_rng([seed, zlib.crc32(b"pre-flashes")])
    if blind is None:
        blind = tuple(camera.name for camera in scenario.cameras if rng.random() < 0.5)
    early = [
        dataclasses.replace(
            flash,
            world_ms=round(flash.world_ms - delay_ms - float(rng.normal(0.0, jitter_ms)), 3),
            strength=round(share * flash.strength, 3),
        )
        for flash in scenario.flashes
    ]
    # flash i is now 2 i + 1, its pre-flash 2 i
    flashes = tuple(f for pair in zip(early, scenario.flashes) for f in pair)
    cameras = tuple(
        dataclasses.replace(
            camera,
            missed_flashes=tuple(2 * i + 1 for i in camera.missed_flashes)
            + (tuple(range(0, len(flashes), 2)) if camera.name in blind else ()),
        )
        for camera in scenario.cameras
    )
    fired = dataclasses.replace(scenario, cameras=cameras, flashes=flashes)
    check_scenario(fired, f"{scenario.name} with pre-flashes")
    return fired


def with_flash_powers(
    scenario: Scenario,
    share: float = 0.3,
    full_ms: tuple[float, float] = (2.0, 3.0),
    low_ms: tuple[float, float] = (0.05, 0.3),
    seed: int = 0,
) -> Scenario:
    """`scenario` with its flashes fired at two powers, as a speedlight's power setting
    does (the pulse lengthens with the power, about 0.05 ms at 1/32 and 2-4 ms to a tenth
    at full): each flash p ``share`` at full power, its pulse U(*full_ms*) long, else at a
    low power, U(*low_ms*) long, lengths in ms to a tenth of the peak (a rectangle's
    hold; ``ln 10`` decays of a pulse that decays, its hold dropped). The shape's kind,
    its rise, the instant and the strength (the pulse's integral) are kept: a full-power
    flash spreads the same light over a longer time.

    Examples
    --------
    >>> from flashsync.simulation import preset
    >>> fired = with_flash_powers(preset("tiny"), share=1.0, full_ms=(2.0, 2.0))
    >>> {round(f.decay_ms * math.log(10), 3) for f in fired.flashes}
    {2.0}
    """
    rng = np.random.default_rng([seed, zlib.crc32(b"flash powers")])
    flashes = []
    for flash in scenario.flashes:
        length = float(rng.uniform(*(full_ms if rng.random() < share else low_ms)))
        if flash.decay_ms == 0:
            flashes.append(dataclasses.replace(flash, hold_ms=round(length, 4)))
        else:
            flashes.append(dataclasses.replace(flash, hold_ms=0.0, decay_ms=round(length / math.log(10), 4)))
    fired = dataclasses.replace(scenario, flashes=tuple(flashes))
    check_scenario(fired, f"{scenario.name} with flashes at two powers")
    return fired


def with_fast_readout(scenario: Scenario, fractions: tuple[float, float] = (0.45, 0.75), seed: int = 0) -> Scenario:
    """`scenario` with sensors that read out faster than their frame period: each camera's
    rows down to its last visible one (``r0 + height``) are read in a fraction U(*fractions*)
    of its frame period, the hidden rows after them (``r1``) grown to fill the rest (never
    shrunk), all else kept.

    Examples
    --------
    >>> from flashsync.simulation import preset
    >>> fast = with_fast_readout(preset("tiny"), (0.5, 0.5))
    >>> [round((c.r0 + c.height) / c.rows_total, 2) for c in fast.cameras]
    [0.5, 0.5]
    """
    rng = np.random.default_rng([seed, zlib.crc32(b"fast readout")])
    cameras = []
    for camera in scenario.cameras:
        read = camera.r0 + camera.height
        total = int(round(read / rng.uniform(*fractions)))
        cameras.append(dataclasses.replace(camera, r1=max(camera.r1, total - read)))
    fast = dataclasses.replace(scenario, cameras=tuple(cameras))
    check_scenario(fast, f"{scenario.name} with a fast readout")
    return fast


def with_exposure_changes(
    scenario: Scenario,
    share: float = 0.5,
    shorter: tuple[float, float] = (0.4, 0.7),
    longer: tuple[float, float] = (1.4, 2.0),
    seed: int = 0,
) -> Scenario:
    """`scenario` with auto-exposure at work: each camera p ``share`` changes its exposure
    once, at a sensor frame U over the middle half of its recording, to a factor
    U(*shorter*) or (p 1/2) U(*longer*) of the exposure it had there (ms to 3 decimals, at
    most one frame period); all else kept.

    Examples
    --------
    >>> from flashsync.simulation import preset
    >>> changed = with_exposure_changes(preset("tiny"), share=1.0, shorter=(0.5, 0.5), longer=(0.5, 0.5))
    >>> [(c.exposure_ms, c.exposure_changes[0][1]) for c in changed.cameras]
    [(10.0, 5.0), (8.0, 4.0)]
    """
    rng = np.random.default_rng([seed, zlib.crc32(b"exposure changes")])
    cameras = []
    for camera in scenario.cameras:
        n = scenario.frame_count(camera)
        changes, frame = rng.random() < share, int(rng.integers(n // 4, max(3 * n // 4, n // 4 + 1)))
        factor = rng.uniform(*(longer if rng.random() < 0.5 else shorter))
        if changes:
            old = float(camera.exposure_at_ms(camera.start_ms + frame * camera.frame_period_ms))
            exposure = min(round(old * factor, 3), camera.frame_period_ms)
            camera = dataclasses.replace(camera, exposure_changes=camera.exposure_changes + ((frame, exposure),))
        cameras.append(camera)
    changed = dataclasses.replace(scenario, cameras=tuple(cameras))
    check_scenario(changed, f"{scenario.name} with exposure changes")
    return changed


def recipe(name: str, seed: int = 0, duration_ms: float | None = None) -> Scenario:
    """The named rig of `RECIPES`, its random settings drawn from `seed`.

    Parameters
    ----------
    name : str
    seed : int
    duration_ms : float, optional
        Recording length, ms; the recipe's own (30 s, 40 s for ``hd``, 15 min for
        ``long-pair``) by default.

    Examples
    --------
    >>> [c.fps for c in recipe("hd").cameras] == [NTSC_30, NTSC_30, NTSC_60]
    True
    """
    if name not in RECIPES:
        raise FlashsyncError(f"unknown rig recipe '{name}'; choose one of {', '.join(RECIPES)}")
    build, default_ms = RECIPES[name]
    return build(seed, default_ms if duration_ms is None else duration_ms)
