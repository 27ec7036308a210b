"""Scenario records and named presets (scenario files: :mod:`flashsync.io.scenario`).

A scenario is everything the simulator needs to render a set of videos: the cameras
(sensor geometry, clock, container, pose), the flashes and light switches in world
time, the scene lighting and a seed. Same scenario, same seed: the same frames. The H.264
files are the same from a fresh process; after another scenario was encoded in the same
process, the same frames and stamps have encoded differently (state somewhere in the
PyAV/FFmpeg encode path), so tests hold for any such encode, not for one file.

Clocks. World time ``w`` and camera time ``t`` are in milliseconds; camera ``c`` maps
its time onto world time with::

    w = (1 + drift_c) * t + offset_c + 0.5 * drift_rate_c * t**2

with ``drift_c = drift_ppm * 1e-6`` and ``drift_rate_c = drift_rate_ppm_per_s * 1e-9``
(per ms). Frame ``f`` of camera ``c`` starts its readout at camera time
``start_ms + f * 1000 / fps``; readout row ``q`` ends its exposure at
``t_f + (r0 + q) * T_row`` with ``T_row = 1000 / fps / (r0 + height + r1)``.

Every option beyond the first presets (pulse shapes, sensor response, encoder settings,
flicker waveform, player sizes, stamp faults) is off by default: a scenario that does not
set them renders exactly as before they existed.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from dataclasses import dataclass

import numpy as np

from flashsync.errors import FlashsyncError
from flashsync.montage import X264_MAX_SIDE_PX
from flashsync.simulation.scene import rink_to_image

CONTAINERS = ("mp4", "mkv")
RISES = ("linear", "cosine")
TONES = ("linear", "srgb", "gamma")
FLICKER_WAVEFORMS = ("sine", "rectified")
X264_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower", "veryslow")
#: Most sensor frames a simulated camera records (11 hours at 25 fps): the simulator holds
#: per-frame arrays, and a longer render is a typo, not a test.
MAX_FRAMES = 1_000_000
#: Latest camera time a simulated recording reaches, ms (about 31 years): later stamps lose
#: their fraction of a ms or overflow a container's time base.
MAX_STAMP_MS = 1e12

_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")


def clock_world_ms(
    t_ms: float | np.ndarray, offset_ms: float, drift_ppm: float, drift_rate_ppm_per_s: float = 0.0
) -> np.ndarray:
    """Map camera time onto world time.

    Parameters
    ----------
    t_ms : float or ndarray
        Camera time, ms.
    offset_ms : float
        World time at camera time 0, ms.
    drift_ppm : float
        Rate error of the camera clock, ppm (world runs ``1 + drift`` times faster).
    drift_rate_ppm_per_s : float
        Change of the drift per second of camera time, ppm/s.

    Returns
    -------
    ndarray
        World time, ms, same shape as `t_ms`.
    """
    t = np.asarray(t_ms, dtype=float)
    rate = drift_rate_ppm_per_s * 1e-9
    return (1.0 + drift_ppm * 1e-6) * t + offset_ms + 0.5 * rate * t * t


@dataclass(frozen=True)
class FlashSpec:
    """One flash pulse, fired at ``world_ms``.

    By default ``I(w) = A exp(-(w - world_ms) / decay_ms)`` for ``w >= world_ms`` (an
    instant rise). In general the pulse rises over ``rise_ms`` to its peak (linearly, or
    as a raised cosine ``(1 - cos(pi x / rise_ms)) / 2``), holds it for ``hold_ms`` and
    decays exponentially with ``decay_ms`` (0: it switches off at once). A xenon flash
    tube: a linear rise of a few tens of microseconds and a decay of 0.1–1.3 ms (0.3–3 ms
    to a tenth); an LED strobe: a rectangle, ``hold_ms`` 0.1–2 and ``decay_ms`` 0.

    Attributes
    ----------
    world_ms : float
        Firing instant (start of the rise), world time, ms.
    strength : float
        Integral of the pulse: the relative brightening of a row whose exposure holds the
        whole flash, for a camera of flash gain 1 (0.5 makes such rows 1.5x brighter).
    decay_ms : float
        Decay time constant, ms (>= 0).
    rise_ms : float
        Duration of the rise, ms (>= 0; 0: instant).
    rise : {'linear', 'cosine'}
        Shape of the rise.
    hold_ms : float
        Time at the peak between rise and decay, ms (>= 0).
    """

    world_ms: float
    strength: float = 0.5
    decay_ms: float = 0.5
    rise_ms: float = 0.0
    rise: str = "linear"
    hold_ms: float = 0.0

    @property
    def shape(self) -> str:
        """A name for the pulse shape: ``exponential``, ``rectangular``, ``linear rise``,
        ``cosine rise`` (with a hold or decay after it)."""
        if self.rise_ms == 0:
            return "rectangular" if self.decay_ms == 0 else "exponential"
        return f"{self.rise} rise"


@dataclass(frozen=True)
class LightSwitch:
    """A step of the scene illumination at a world instant.

    Attributes
    ----------
    world_ms : float
        Instant of the step, world time, ms.
    factor : float
        Illumination after the step divided by illumination before it (1.6 switches a
        light on, 1 / 1.6 switches it off again).
    """

    world_ms: float
    factor: float = 1.6


@dataclass(frozen=True)
class CameraSpec:
    """One rolling-shutter camera: sensor, clock, container and pose.

    Attributes
    ----------
    name : str
        Camera name and file stem of its video.
    width, height : int
        Visible image size, px (even).
    fps : float
        Nominal frame rate, frames per second of camera time.
    r0, r1 : int
        Hidden rows read before and after the visible rows.
    exposure_ms : float
        Exposure of each row, ms (at most one frame period).
    start_ms : float
        Camera time of the first frame, ms (the first container stamp, >= 0).
    offset_ms : float
        World time at camera time 0, ms.
    drift_ppm : float
        Clock rate error, ppm.
    drift_rate_ppm_per_s : float
        Change of the drift per second, ppm/s (must be 0 for the reference camera).
    flipped : bool
        Mounted upside down: the stored image is upright, readout runs bottom-up.
    container : {'mp4', 'mkv'}
        File format. MP4 stores 90 kHz stamps, MKV 1 ms stamps.
    quantize_ms : float or None
        Round the stamps to this step before storing them (1 for 1 ms RTP-style clocks).
    jitter_ms : float
        Standard deviation of Gaussian noise added to each stamp, ms.
    dropped_frames : tuple of int
        Sensor frame indices that are not written.
    frame_gaps : tuple of (int, int)
        Runs ``(first sensor frame, count)`` of frames not written (recording gaps).
    stamp_rate_changes : tuple of (int, float)
        ``(sensor frame, factor)``: from that frame's time on, the stamps advance
        ``factor`` times as fast as the camera's clock (a muxer bug; cumulative). The
        sensor keeps its rate.
    exposure_changes : tuple of (int, float)
        ``(sensor frame, exposure_ms)``: from that frame on, each row is exposed that many
        ms (auto-exposure; not cumulative; at most one frame period). A frame exposed ``E``
        ms sees flash light scaled by ``exposure_ms / E``: the camera's gain keeps the
        ambient level, so a flash stands out more in a shorter exposure.
    drop_fraction : float
        Fraction of further frames dropped at random.
    n_frames : int or None
        Number of sensor frames; None takes the scenario's duration.
    flash_gain : float
        Response of the camera to flash light, relative to its ambient exposure (at
        ``exposure_ms``; see `exposure_changes`).
    noise_std : float
        Sensor noise, DN.
    crf : int
        x264 constant rate factor (0 lossless .. 51 worst).
    keyint : int or None
        Longest GOP (frames between key frames); None: x264's default (250).
    bframes : int or None
        Most consecutive B-frames; None: x264's default (3, placed adaptively); 0: none.
    x264_preset : str or None
        x264 speed preset (``ultrafast`` .. ``veryslow``); None: ``medium``.
    open_gop : bool
        x264's open GOPs: key frames are recovery points (not IDR), and the B-frames shown
        before one are coded after it, referencing the GOP before.
    tone : {'linear', 'srgb', 'gamma'}
        Tone curve applied to linear light before quantisation (see `sensor`).
    black_level : float
        Stored value of no light (pedestal), DN.
    white_level : float
        Linear light that saturates the sensor, DN of reflectance at illumination 1
        (255: the default camera; lower values clip bright rows and flashes).
    vignetting : float
        Relative loss of light in the image corners, ``1 - vignetting * rho**2``.
    gain_steps : tuple of (float, float)
        Auto-exposure steps ``(world_ms, factor)``: frames starting after the instant
        are multiplied by the factor (cumulative).
    missed_flashes : tuple of int
        Indices of flashes this camera does not see.
    miss_probability : float
        Probability that it misses any other flash.
    position_m : (float, float, float)
        Camera centre in rink metres; z is the height above the ice.
    look_at_m : (float, float)
        Point of the ice at the image centre, metres.
    hfov_deg : float
        Horizontal field of view, degrees.
    """

    name: str
    width: int
    height: int
    fps: float
    r0: int = 0
    r1: int = 0
    exposure_ms: float = 10.0
    start_ms: float = 0.0
    offset_ms: float = 0.0
    drift_ppm: float = 0.0
    drift_rate_ppm_per_s: float = 0.0
    flipped: bool = False
    container: str = "mp4"
    quantize_ms: float | None = None
    jitter_ms: float = 0.0
    dropped_frames: tuple = ()
    frame_gaps: tuple = ()
    stamp_rate_changes: tuple = ()
    exposure_changes: tuple = ()
    drop_fraction: float = 0.0
    n_frames: int | None = None
    flash_gain: float = 1.0
    noise_std: float = 1.0
    crf: int = 23
    keyint: int | None = None
    bframes: int | None = None
    x264_preset: str | None = None
    open_gop: bool = False
    tone: str = "linear"
    black_level: float = 0.0
    white_level: float = 255.0
    vignetting: float = 0.0
    gain_steps: tuple = ()
    missed_flashes: tuple = ()
    miss_probability: float = 0.0
    position_m: tuple = (30.0, -12.0, 14.0)
    look_at_m: tuple = (30.0, 12.0)
    hfov_deg: float = 70.0

    @property
    def rows_total(self) -> int:
        """``R = r0 + height + r1``, rows."""
        return self.r0 + self.height + self.r1

    @property
    def frame_period_ms(self) -> float:
        """Frame period, ms of camera time."""
        return 1000.0 / self.fps

    @property
    def row_time_ms(self) -> float:
        """Readout time of one row ``T_row``, ms of camera time."""
        return self.frame_period_ms / self.rows_total

    def world_ms(self, t_ms: float | np.ndarray) -> np.ndarray:
        """World time (ms) of camera time `t_ms` (ms); see `clock_world_ms`."""
        return clock_world_ms(t_ms, self.offset_ms, self.drift_ppm, self.drift_rate_ppm_per_s)

    def exposure_at_ms(self, t_frame_ms: float | np.ndarray) -> np.ndarray:
        """Exposure (ms) of the frames whose true camera times are `t_frame_ms` (ms), same
        shape: ``exposure_ms``, then each of ``exposure_changes`` from its sensor frame on
        (frame ``f`` at ``start_ms + f * frame_period_ms``; half a period of slack)."""
        t = np.asarray(t_frame_ms, dtype=float)
        exposure = np.full(t.shape, float(self.exposure_ms))
        for frame, exposure_ms in sorted(self.exposure_changes):
            exposure[t >= self.start_ms + (frame - 0.5) * self.frame_period_ms] = exposure_ms
        return exposure


@dataclass(frozen=True)
class Scenario:
    """A scene seen by several cameras, with flashes and lighting events.

    The first camera is the reference of the ground truth (alpha = 1, beta = 0).

    Attributes
    ----------
    name : str
        Scenario name.
    cameras : tuple of CameraSpec
        Cameras, reference first.
    duration_ms : float
        Recording length of each camera without `n_frames`, ms of camera time.
    flashes : tuple of FlashSpec
        Flashes, world time.
    switches : tuple of LightSwitch
        Steps of the scene illumination, world time.
    flicker_depth : float
        Mains flicker modulation depth m (0 = off): illumination ``1 + m g(...)``, the
        waveform ``g`` of mean 0 and peak-to-peak 2 (see `light`).
    flicker_hz : float
        Flicker frequency, Hz (100 or 120: twice the mains frequency).
    flicker_phase : float
        Flicker phase at world time 0, radians.
    flicker_waveform : {'sine', 'rectified'}
        ``sine``, or the rectified sine of a lamp on full-wave rectified mains (a DC part
        and cusps at the mains' zero crossings).
    n_players : int
        Number of players skating on the rink.
    player_radius_m : (float, float)
        Range of the players' disc radii, metres (drawn uniformly).
    puck_speed_mps : float
        Puck speed, m/s.
    color : bool
        Render BGR colour video instead of grey.
    seed : int
        Seed of every random choice (scene, noise, drops, misses, jitter).
    """

    name: str
    cameras: tuple
    duration_ms: float = 3000.0
    flashes: tuple = ()
    switches: tuple = ()
    flicker_depth: float = 0.0
    flicker_hz: float = 100.0
    flicker_phase: float = 0.0
    flicker_waveform: str = "sine"
    n_players: int = 8
    player_radius_m: tuple = (0.4, 0.55)
    puck_speed_mps: float = 36.0
    color: bool = False
    seed: int = 0

    def frame_count(self, camera: CameraSpec) -> int:
        """Number of sensor frames of `camera` (before drops)."""
        if camera.n_frames is not None:
            return camera.n_frames
        return int(self.duration_ms * camera.fps / 1000.0)

    def to_dict(self) -> dict:
        """Plain dict (lists, numbers, strings) with the field names as keys."""
        return json.loads(json.dumps(dataclasses.asdict(self)))


def check_scenario(scenario: Scenario, source: str) -> None:
    """Raise `FlashsyncError` naming `source` if `scenario` cannot be rendered.

    Parameters
    ----------
    scenario : Scenario
        Scenario to check.
    source : str
        What to name in the message (a file or ``scenario 'tiny'``).
    """

    def require(ok: bool, what: str) -> None:
        if not ok:
            raise FlashsyncError(f"{source}: {what}")

    require(len(scenario.cameras) > 0, "no cameras; add at least one under 'cameras'")
    names = [c.name for c in scenario.cameras]
    require(len(set(names)) == len(names), f"duplicate camera names in {names}; make them unique")
    require(scenario.duration_ms > 0, "duration_ms must be positive")
    require(scenario.n_players >= 0, "n_players must be >= 0")
    require(scenario.flicker_hz > 0, "flicker_hz must be positive")
    require(0 <= scenario.flicker_depth < 1, "flicker_depth must be in [0, 1)")
    require(scenario.flicker_waveform in FLICKER_WAVEFORMS, f"flicker_waveform must be one of {FLICKER_WAVEFORMS}")
    radius = scenario.player_radius_m
    require(
        len(radius) == 2 and 0 < radius[0] <= radius[1], "player_radius_m must be [min, max] metres with 0 < min <= max"
    )
    for k, fl in enumerate(scenario.flashes):
        require(
            fl.decay_ms >= 0 and fl.rise_ms >= 0 and fl.hold_ms >= 0 and fl.strength >= 0,
            f"flash {k}: decay_ms, rise_ms, hold_ms and strength must be >= 0",
        )
        require(
            fl.decay_ms + fl.rise_ms + fl.hold_ms > 0,
            f"flash {k}: the pulse has no duration; give decay_ms, rise_ms or hold_ms",
        )
        require(fl.rise in RISES, f"flash {k}: rise must be one of {RISES}")
    for k, sw in enumerate(scenario.switches):
        require(sw.factor > 0, f"switch {k}: factor must be positive")
    ref = scenario.cameras[0]
    require(
        ref.drift_rate_ppm_per_s == 0,
        f"reference camera {ref.name} must have drift_rate_ppm_per_s 0; put another camera first",
    )
    for c in scenario.cameras:
        where = f"camera {c.name}"
        require(
            isinstance(c.name, str) and _NAME.match(c.name) is not None,
            f"camera name {c.name!r} is not a plain file stem (letters, digits, _ . -)",
        )
        require(
            c.width > 0 and c.height > 0 and c.width % 2 == 0 and c.height % 2 == 0,
            f"{where}: width and height must be positive and even, got {c.width}x{c.height}",
        )
        require(
            c.width <= X264_MAX_SIDE_PX and c.height <= X264_MAX_SIDE_PX,
            f"{where}: width and height must be at most {X264_MAX_SIDE_PX} (x264's limit), got {c.width}x{c.height}",
        )
        require(c.fps > 0, f"{where}: fps must be positive")
        require(c.r0 >= 0 and c.r1 >= 0, f"{where}: r0 and r1 must be >= 0")
        require(
            0 < c.exposure_ms <= c.frame_period_ms,
            f"{where}: exposure_ms must be in (0, {c.frame_period_ms:.3f}] (one frame period)",
        )
        require(c.start_ms >= 0, f"{where}: start_ms must be >= 0 (stamps are non-negative)")
        require(c.container in CONTAINERS, f"{where}: container must be one of {CONTAINERS}")
        require(c.quantize_ms is None or c.quantize_ms > 0, f"{where}: quantize_ms must be positive")
        require(c.jitter_ms >= 0 and c.noise_std >= 0, f"{where}: jitter_ms and noise_std must be >= 0")
        require(0 <= c.drop_fraction < 1, f"{where}: drop_fraction must be in [0, 1)")
        require(0 <= c.miss_probability <= 1, f"{where}: miss_probability must be in [0, 1]")
        require(c.n_frames is None or c.n_frames > 0, f"{where}: n_frames must be positive")
        require(
            c.n_frames is not None or math.isfinite(scenario.duration_ms * c.fps),
            f"{where}: duration_ms times fps is too large to count its frames; lower duration_ms or fps",
        )
        count = scenario.frame_count(c)
        length = f"n_frames {c.n_frames}" if c.n_frames is not None else f"duration_ms {scenario.duration_ms:g}"
        require(
            count <= MAX_FRAMES,
            f"{where}: {length} at {c.fps:g} fps is {count:.3g} frames, over the simulator's limit of {MAX_FRAMES} "
            "frames a camera; lower it",
        )
        require(
            c.start_ms + count * c.frame_period_ms <= MAX_STAMP_MS,
            f"{where}: start_ms {c.start_ms:g} and {length} end at {c.start_ms + count * c.frame_period_ms:.3g} ms, "
            f"past the simulator's limit of {MAX_STAMP_MS:g} ms; lower start_ms",
        )
        require(count > 0, f"{where}: records no frame; raise duration_ms")
        require(0 <= c.crf <= 51, f"{where}: crf must be in 0..51")
        require(c.keyint is None or c.keyint >= 1, f"{where}: keyint must be >= 1")
        require(c.bframes is None or 0 <= c.bframes <= 16, f"{where}: bframes must be in 0..16")
        require(
            c.x264_preset is None or c.x264_preset in X264_PRESETS,
            f"{where}: x264_preset must be one of {', '.join(X264_PRESETS)}",
        )
        require(c.tone in TONES, f"{where}: tone must be one of {TONES}")
        require(
            0 <= c.black_level < 255 and c.white_level > 0,
            f"{where}: black_level must be in [0, 255) and white_level positive",
        )
        require(0 <= c.vignetting < 1, f"{where}: vignetting must be in [0, 1)")
        require(
            all(len(g) == 2 and g[1] >= 1 for g in c.frame_gaps),
            f"{where}: frame_gaps must be pairs [first sensor frame, count >= 1]",
        )
        require(
            all(len(s) == 2 and s[1] > 0 for s in c.stamp_rate_changes),
            f"{where}: stamp_rate_changes must be pairs [sensor frame, factor > 0]",
        )
        require(
            all(len(e) == 2 and e[0] >= 0 and float(e[0]).is_integer() for e in c.exposure_changes)
            and len({e[0] for e in c.exposure_changes}) == len(c.exposure_changes),
            f"{where}: exposure_changes must be pairs [sensor frame >= 0, exposure_ms], one a frame",
        )
        require(
            all(0 < e[1] <= c.frame_period_ms for e in c.exposure_changes),
            f"{where}: exposure_changes' exposures must be in (0, {c.frame_period_ms:.3f}] ms (one frame period)",
        )
        require(
            all(0 <= k < len(scenario.flashes) for k in c.missed_flashes),
            f"{where}: missed_flashes must be indices of flashes (0..{len(scenario.flashes) - 1})",
        )
        require(
            all(len(s) == 2 and s[1] > 0 for s in c.gain_steps),
            f"{where}: gain_steps must be pairs [world_ms, factor > 0]",
        )
        require(
            len(c.position_m) == 3 and c.position_m[2] > 0,
            f"{where}: position_m must be [x, y, z] with z > 0 (above the ice)",
        )
        require(len(c.look_at_m) == 2, f"{where}: look_at_m must be [x, y]")
        require(0 < c.hfov_deg < 170, f"{where}: hfov_deg must be in (0, 170)")
        try:
            rink_to_image(c)
        except FlashsyncError as err:
            raise FlashsyncError(f"{source}: {err}") from None


def _flash_schedule(rng, start_ms, stop_ms, count, min_gap_ms, strengths=(0.35, 0.7), decay_ms=0.5):
    """Up to `count` flashes at irregular instants in [start_ms, stop_ms], `min_gap_ms` apart or more."""
    count = max(1, min(count, 1 + int((stop_ms - start_ms) // min_gap_ms)))
    slack = max(stop_ms - start_ms - (count - 1) * min_gap_ms, 0.0)
    offsets = np.sort(rng.uniform(0.0, slack, count)) + np.arange(count) * min_gap_ms
    return tuple(
        FlashSpec(
            world_ms=round(float(start_ms + o), 3), strength=round(float(rng.uniform(*strengths)), 3), decay_ms=decay_ms
        )
        for o in offsets
    )


def _tiny(duration_ms: float = 2400.0) -> Scenario:
    rng = np.random.default_rng(11)
    cams = (
        CameraSpec(
            "cam1",
            320,
            180,
            25.0,
            r0=8,
            r1=4,
            exposure_ms=10.0,
            start_ms=0.0,
            position_m=(30.0, -10.0, 14.0),
            look_at_m=(30.0, 12.0),
            hfov_deg=80.0,
        ),
        CameraSpec(
            "cam2",
            320,
            180,
            30.0,
            r0=6,
            r1=6,
            exposure_ms=8.0,
            start_ms=1334.5,
            offset_ms=-1234.5,
            drift_ppm=15.0,
            container="mkv",
            flash_gain=0.9,
            position_m=(-6.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
            hfov_deg=70.0,
        ),
    )
    flashes = _flash_schedule(rng, 0.12 * duration_ms, 0.92 * duration_ms, 4, 0.12 * duration_ms)
    return Scenario("tiny", cams, duration_ms=duration_ms, flashes=flashes, n_players=4, seed=1)


def _sample(duration_ms: float = 8000.0) -> Scenario:
    rng = np.random.default_rng(2024)
    cams = (
        CameraSpec(
            "cam1",
            640,
            360,
            30.0,
            r0=12,
            r1=8,
            exposure_ms=10.0,
            start_ms=0.0,
            drift_ppm=5.0,
            crf=28,
            noise_std=1.5,
            position_m=(30.0, -11.0, 15.0),
            look_at_m=(30.0, 11.0),
            hfov_deg=80.0,
        ),
        CameraSpec(
            "cam2",
            480,
            270,
            25.0,
            r0=10,
            r1=6,
            exposure_ms=16.0,
            start_ms=4471.7,
            offset_ms=-4321.7,
            drift_ppm=-10.0,
            container="mkv",
            drop_fraction=0.01,
            flash_gain=1.2,
            crf=28,
            noise_std=1.5,
            position_m=(-7.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
            hfov_deg=75.0,
        ),
        CameraSpec(
            "cam3",
            512,
            288,
            50.0,
            r0=14,
            r1=10,
            exposure_ms=8.0,
            start_ms=12115.6,
            offset_ms=-12345.6,
            drift_ppm=20.0,
            flash_gain=0.8,
            crf=28,
            noise_std=1.5,
            missed_flashes=(4,),
            position_m=(66.0, 33.0, 16.0),
            look_at_m=(44.0, 16.0),
            hfov_deg=75.0,
        ),
        CameraSpec(
            "cam4",
            320,
            240,
            29.97,
            r0=8,
            r1=6,
            exposure_ms=12.0,
            start_ms=7420.3,
            offset_ms=-7000.3,
            drift_ppm=12.0,
            jitter_ms=0.1,
            crf=28,
            noise_std=1.5,
            position_m=(30.0, 42.0, 17.0),
            look_at_m=(30.0, 18.0),
            hfov_deg=70.0,
        ),
    )
    flashes = _flash_schedule(rng, 800.0, duration_ms - 500.0, 7, 450.0, decay_ms=0.5)
    return Scenario("sample", cams, duration_ms=duration_ms, flashes=flashes, n_players=10, color=True, seed=7)


def _paper(duration_ms: float = 60000.0) -> Scenario:
    rng = np.random.default_rng(2017)
    common = dict(fps=25.0, crf=23, noise_std=1.5, drop_fraction=0.003)
    cams = (
        CameraSpec(
            "cam1",
            960,
            540,
            r0=18,
            r1=12,
            exposure_ms=10.0,
            start_ms=0.0,
            position_m=(30.0, -11.0, 15.0),
            look_at_m=(30.0, 11.0),
            hfov_deg=80.0,
            **common,
        ),
        CameraSpec(
            "cam2",
            960,
            540,
            r0=20,
            r1=10,
            exposure_ms=12.0,
            start_ms=23456.0 + 850.0,
            offset_ms=-23456.0,
            drift_ppm=-10.0,
            container="mkv",
            flash_gain=1.1,
            position_m=(-7.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
            hfov_deg=75.0,
            **common,
        ),
        CameraSpec(
            "cam3",
            640,
            360,
            r0=12,
            r1=8,
            exposure_ms=8.0,
            start_ms=41000.5 - 1200.0,
            offset_ms=-41000.5,
            drift_ppm=7.0,
            quantize_ms=1.0,
            flash_gain=0.9,
            position_m=(66.0, 33.0, 16.0),
            look_at_m=(44.0, 16.0),
            hfov_deg=75.0,
            **common,
        ),
        CameraSpec(
            "cam4",
            640,
            360,
            r0=14,
            r1=10,
            exposure_ms=16.0,
            start_ms=12000.0 + 400.0,
            offset_ms=-12000.0,
            drift_ppm=4.0,
            flash_gain=1.0,
            position_m=(30.0, 42.0, 17.0),
            look_at_m=(30.0, 18.0),
            hfov_deg=70.0,
            **common,
        ),
    )
    flashes = _flash_schedule(rng, 0.05 * duration_ms + 900.0, 0.95 * duration_ms - 1300.0, 12, 0.04 * duration_ms)
    return Scenario(
        "paper",
        cams,
        duration_ms=duration_ms,
        flashes=flashes,
        n_players=10,
        flicker_depth=0.02,
        flicker_hz=100.0,
        flicker_phase=0.7,
        seed=17,
    )


_PRESETS = {"sample": _sample, "tiny": _tiny, "paper": _paper}
PRESETS = tuple(_PRESETS)


def preset(name: str, **overrides) -> Scenario:
    """A named scenario.

    Parameters
    ----------
    name : {'sample', 'tiny', 'paper'}
        ``sample``: the shipped demo, 4 cameras, 8 s. ``tiny``: 2 small cameras, 2.4 s,
        for unit tests. ``paper``: 4 cameras at 25 fps, 60 s, for benchmarks.
    **overrides
        Scenario fields to replace. ``duration_ms`` also places the preset's flashes
        within the shorter or longer recording.

    Returns
    -------
    Scenario

    Examples
    --------
    >>> short = preset("tiny", duration_ms=1200, seed=3)
    """
    if name not in _PRESETS:
        raise FlashsyncError(f"unknown scenario preset '{name}'; choose one of {', '.join(PRESETS)}")
    names = [f.name for f in dataclasses.fields(Scenario)]
    for key in overrides:
        if key not in names:
            raise FlashsyncError(f"preset '{name}': unknown field '{key}'; valid fields: {', '.join(names)}")
    builder = _PRESETS[name]
    scenario = builder(overrides.pop("duration_ms")) if "duration_ms" in overrides else builder()
    scenario = dataclasses.replace(scenario, **overrides)
    check_scenario(scenario, f"preset '{name}'")
    return scenario
