"""The catalogue of effects the discrepancy workflow can add to the time model.

The plainest model (every effect off) predicts the time of each band edge of camera ``c``
in frame ``f`` at readout row ``q`` as::

    t0_c + f * P_c + q * P_c / H_c  =  tau_k - beta_c + [trailing] * E

``P_c`` is the camera's median frame step (its nominal frame period), ``H_c`` its image
height, ``tau_k`` the flash's global time, ``beta_c`` the camera's shift (0 for the
reference) and ``E`` one exposure shared by all cameras (a trailing edge is the row whose
exposure *starts* at the flash, docs/architecture.md). Its frame clock ``t0_c + f * P_c``
also predicts the stamps.

An effect either adds a column to this linear model for one camera (``t`` is the model's
frame time minus the camera's mid time, ``q`` the readout row) or changes how the model's
quantities are computed (frame slots, frame period, readout rows). Effects marked "others"
apply to every camera but the reference, whose clock and exposure define the global ones:

==============  ==========================================  ======================================
effect          residual structure it explains              how the model changes
==============  ==========================================  ======================================
dropped_frames  steps of whole frame periods at the frame   frame slots counted from the stamp
                gaps, in stamps and edges                   gaps instead of the frame index
frame_clock     stamps scattered about a steady clock (a    frame clock offset and period fitted
                sawtooth locked to the stamp grid, or       to the stamps (robust least squares)
                jitter) and the period error that leaves    instead of the median step
                in the median step
flipped         band edges on the wrong side: a trend       readout rows reversed, leading and
                against the row of twice the time per row   trailing edges swapped
row_time        a trend against the readout row             column ``-q``: time per row minus
                                                            nominal, ms per row
drift           a trend against time                        column ``-t`` (others): alpha - 1
drift_rate      a curvature against time                    column ``-t**2`` (others), with drift:
                                                            half the drift's change per ms
exposure        a constant gap between a camera's trailing  column ``[trailing]`` (others):
                and leading edges' residuals                exposure minus the reference's, ms
saturation      the edges of bands clipped at white: the    columns ``[saturated] * (+1 trailing,
                leading ones early, the trailing ones late, -1 leading)`` on bands in one frame
                the farther the deeper the clip (the        and on bands split across two, that
                longer the band), the trailing ones the     times ``c`` (``c``: the band's length
                farther under a pulse's tail                over its clipped kind's median, ms)
                                                            and ``[saturated and trailing] * c``:
                                                            how far a clipped band's edges move
                                                            out per kind, ms, the share of ``c``
                                                            they move by, and the share the
                                                            trailing edge moves farther
stamp_rate      from one frame on, edges run away at a      frame times at one rate throughout
                steady rate: the stamps changed rate, the   (one of the stamps' segments', the
                sensor did not                              best fit), with dropped_frames and
                                                            frame_clock (segments fitted)
pulse_shape     a band longer than the camera's others has  columns ``[trailing] * w`` and
                its trailing edge late and its leading      ``-[leading] * w`` (``w``: the band's
                edge early, by shares of the excess ``w``   excess length, ms): the shares of it
                                                            on the trailing and the leading edge
flicker         the camera's rolling mains flicker: its     the camera's time per row is the
                period in rows off the one the model's      flicker's, ``(1000 / hz) /
                time per row predicts                       period_rows``, instead of frame
                                                            period / height
==============  ==========================================  ======================================

Rolling mains flicker is a third stream of evidence besides the edges and the stamps: where
a camera saw it (:attr:`~flashsync.diagnose.measure.Measurement.flicker`), its period in
rows is ``(1000 / hz) / T_row``, so every model predicts it from the camera's time per row,
and the model is scored on it (Gaussian, the flicker's standard deviation, 1 % at the
least). ``flicker`` times the camera's rows by it, with no parameter; ``row_time`` fits a
time per row to the edges and the flicker together. Where the flashes leave the time per
row loose (cameras at one frame rate with a steady phase, few flashes: the design notes'
trap) the flicker is what fixes it.

``dropped_frames``, ``frame_clock`` and ``stamp_rate`` switch on parts of the pipeline's frame clock
(:func:`flashsync.frame_clock.fit_frame_clock`). An effect describes what it found from the
fitted model's :class:`CameraEstimate` of the camera, never from the fit itself.

The flash's pulse shape: the detector marks each edge at half of the band's own rise, the
same instant of the flash in every camera whatever its decay, as long as the band shows the
plateau the detector takes for its level. On the simulator's second world (xenon tails of
0.2-1.3 ms, tone curves) that fails on some bands: on its HD rig (320x180, 12 s) two of the
59.94 fps camera's bands come out 0.6 and 2.1 ms longer than its others, their trailing
edges 0.44 and 1.75 ms late against the truth and their leading edges 0.2-0.3 ms early,
while the other cameras' bands of the same flashes are as long as ever: neither a pulse
length shared by the cameras that saw the flash nor a rise/fall difference per camera, but
a widening per band. Its evidence is each band's own excess length where it is beyond an
ordinary band's (:attr:`~flashsync.diagnose.measure.Edges.excess_ms`), so ``pulse_shape`` fits the shares
of it on the trailing and on the leading edge per camera. Every late trailing edge seen
there belongs to a band split across two frames (its trailing edge in the next frame's
top 35 rows); where such a band is no longer than the camera's other split bands, the
excess does not show its delay and the effect cannot take it up. A rectangular pulse that
outlasts the exposure (an LED strobe at full power over a short exposure) widens its band
to its own length, its leading edge early and its trailing edge late by half the excess
each; the detector read its pulse so, which is evidence too where the band is as long
(:data:`~flashsync.diagnose.measure.PULSE_LENGTH_SHARE`; ``tests/test_diagnose.py``'s
strobed pair names the effect first, with shares of 0.47-0.52, in either world).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

DROPPED_FRAMES = "dropped_frames"
FRAME_CLOCK = "frame_clock"
FLIPPED = "flipped"
ROW_TIME = "row_time"
DRIFT = "drift"
DRIFT_RATE = "drift_rate"
EXPOSURE = "exposure"
STAMP_RATE = "stamp_rate"
SATURATION = "saturation"
PULSE_SHAPE = "pulse_shape"
FLICKER = "flicker"

#: Scopes: an effect applies to every camera, or to every camera but the reference (whose
#: clock and exposure define the global ones).
EVERY_CAMERA = "every camera"
OTHER_CAMERAS = "cameras but the reference"


@dataclass(frozen=True)
class Features:
    """The model's quantities for each edge, arrays of shape (n_edges,).

    Attributes
    ----------
    camera : int array
        Camera index.
    t_ms : float array
        Model frame time minus the camera's mid time, ms.
    q : float array
        Readout row under the model's readout direction.
    trailing : bool array
        Trailing edge under the model's readout direction.
    saturated : bool array
        The edge's band clipped at white.
    excess_ms : float array
        The edge's band's length minus its camera's median of its kind where it is widened, ms.
    clip_ms : float array
        The same for every band clipped at white, ms (0 for the others).
    split : bool array
        The edge's band is split across two frames.
    """

    camera: np.ndarray
    t_ms: np.ndarray
    q: np.ndarray
    trailing: np.ndarray
    saturated: np.ndarray
    excess_ms: np.ndarray
    clip_ms: np.ndarray
    split: np.ndarray


@dataclass(frozen=True)
class CameraEstimate:
    """One camera under a fitted model, in plain numbers.

    Attributes
    ----------
    camera : str
    reference : bool
        The reference camera.
    flipped : bool
        Reads bottom-up under the model.
    frame_period_ms, median_step_ms : float
        The model's frame period and the camera's median stamp step, ms.
    missing_frames : int
        Frame slots without a frame under the model.
    rate_changes : list of (int, float, float)
        Where the stamps change rate under the model's frame clock: (first frame, period
        before, period after), ms.
    stamp_rms_ms : float
        RMS of the stamps about the model's frame clock, ms.
    drift_ppm, drift_rate_ppm_per_s : float
        Clock drift at mid time and its change.
    shift_ms : float
    row_time_ms, nominal_row_time_ms : float
        Time per row under the model and frame period / height, ms.
    exposure_ms : float
    saturation_ms : float
        How far the edges of a clipped band of its kind's median length move out (leading
        earlier, trailing later), ms.
    saturation_share : float
        And the share of a clipped band's length over that median that each edge moves out by.
    pulse_trailing, pulse_leading : float
        Shares of a band's excess length that its trailing edge is late and its leading edge
        early by.
    longest_excess_ms : float
        The largest excess length of the camera's bands, ms.
    flicker_hz, flicker_depth, flicker_period_rows : float
        The camera's rolling mains flicker: frequency (Hz), depth of its fundamental as the
        rows saw it, period in readout rows; NaN where it saw none.
    flicker_row_time_ms : float
        The time per row that period tells, ms; NaN where none.
    effects : list of str
        The effects the model has on this camera.
    """

    camera: str
    reference: bool
    flipped: bool
    frame_period_ms: float
    median_step_ms: float
    missing_frames: int
    rate_changes: list[tuple[int, float, float]]
    stamp_rms_ms: float
    drift_ppm: float
    drift_rate_ppm_per_s: float
    shift_ms: float
    row_time_ms: float
    nominal_row_time_ms: float
    exposure_ms: float
    saturation_ms: float
    saturation_share: float
    pulse_trailing: float
    pulse_leading: float
    longest_excess_ms: float
    flicker_hz: float
    flicker_depth: float
    flicker_period_rows: float
    flicker_row_time_ms: float
    effects: list[str]

    @property
    def readout(self) -> str:
        return "bottom-up" if self.flipped else "top-down"


@dataclass(frozen=True)
class Effect:
    """One effect of the catalogue.

    Attributes
    ----------
    name : str
        Key, e.g. ``"drift"``.
    title : str
        Words for reports, e.g. ``"clock drift"``.
    explains : str
        The residual structure it explains.
    changes : str
        How it changes the model.
    scope : str
        :data:`EVERY_CAMERA` or :data:`OTHER_CAMERAS`.
    describe : callable
        ``describe(camera, reference)``: what the effect came out as on a camera of a fitted
        model, one phrase, from the :class:`CameraEstimate` of that camera and of the
        reference.
    column : callable or None
        ``column(features)``: the design column it adds for a camera (before restricting it
        to that camera's edges), scaled so that its coefficient is the parameter, shape
        (n_edges,), or several as shape (n_edges, k) (the parameters keyed by the name,
        then by the name and ``.1``, ``.2``...); None for an effect that changes how the
        model's quantities are computed.
    implies : tuple of str
        Effects added with it.
    """

    name: str
    title: str
    explains: str
    changes: str
    scope: str
    describe: Callable[[CameraEstimate, CameraEstimate], str]
    column: Callable[[Features], np.ndarray] | None = None
    implies: tuple[str, ...] = ()


def _describe_drops(camera: CameraEstimate, reference: CameraEstimate) -> str:
    missing = camera.missing_frames
    return f"{missing} missing frame{'s' if missing != 1 else ''} (stamp gaps of whole frame periods)"


def _describe_frame_clock(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return (
        f"frame period {camera.frame_period_ms:.4f} ms (median step {camera.median_step_ms:.4f}), "
        f"stamps scatter {camera.stamp_rms_ms:.3f} ms RMS about it"
    )


def _saturation_columns(f: Features) -> np.ndarray:
    """The saturation effect's columns, shape (n_edges, 4): how far a clipped band's edges of
    its kind's median length move out (leading earlier, trailing later), ms, on a band in one
    frame; the share of ``clip_ms`` they move out by; the same offset on a band split across
    two frames (its kind's median is another band's, so its offset is another); the share of
    ``clip_ms`` a trailing edge moves beyond the leading one's (a pulse's tail: the deeper
    the clip, the farther down the tail the trailing edge's half level falls)."""
    out = np.where(f.saturated, np.where(f.trailing, 1.0, -1.0), 0.0)
    return np.column_stack(
        [out * ~f.split, out * f.clip_ms, out * f.split, np.where(f.saturated & f.trailing, f.clip_ms, 0.0)]
    )


def _describe_saturation(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return (
        f"edges of clipped bands {camera.saturation_ms:+.3f} ms out (leading earlier, trailing later) "
        f"and {camera.saturation_share:.2f} of a band's length over its clipped kind's median"
    )


def _describe_pulse_shape(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return (
        f"bands up to {camera.longest_excess_ms:.3f} ms longer than the camera's others: trailing edges "
        f"{camera.pulse_trailing:.2f} of it late, leading edges {camera.pulse_leading:.2f} of it early"
    )


def _describe_flicker(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return (
        f"{camera.flicker_hz:.0f} Hz, depth {100 * camera.flicker_depth:.1f} %, period "
        f"{camera.flicker_period_rows:.2f} rows: time per row {camera.flicker_row_time_ms:.5f} ms "
        f"(nominal {camera.nominal_row_time_ms:.5f})"
    )


def _describe_stamp_rate(camera: CameraEstimate, reference: CameraEstimate) -> str:
    changes = ", ".join(f"at frame {f} ({a:.3f} -> {b:.3f} ms)" for f, a, b in camera.rate_changes)
    return f"stamps change rate {changes}; frames at one rate of {camera.frame_period_ms:.4f} ms throughout"


def _describe_flip(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return f"reads {camera.readout}"


def _describe_row_time(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return f"time per row {camera.row_time_ms:.5f} ms (nominal {camera.nominal_row_time_ms:.5f})"


def _describe_drift(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return f"drift {camera.drift_ppm:.2f} ppm"


def _describe_drift_rate(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return f"drift {camera.drift_ppm:.2f} ppm at mid time, changing {camera.drift_rate_ppm_per_s:.3f} ppm/s"


def _describe_exposure(camera: CameraEstimate, reference: CameraEstimate) -> str:
    return f"exposure {camera.exposure_ms:.3f} ms vs {reference.exposure_ms:.3f} ms on the reference"


CATALOGUE: dict[str, Effect] = {
    effect.name: effect
    for effect in (
        Effect(
            DROPPED_FRAMES,
            "dropped frames",
            "steps of whole frame periods at the frame gaps, in stamps and edges",
            "frame slots counted from the stamp gaps (round(gap / median step)) instead of the frame index",
            EVERY_CAMERA,
            _describe_drops,
        ),
        Effect(
            FRAME_CLOCK,
            "timestamp quantisation / jitter",
            "stamps scattered about a steady clock (a sawtooth locked to the stamp grid, or "
            "jitter) and the period error that leaves in the median step",
            "frame clock offset and period from a robust least-squares fit to the stamps instead of the median step",
            EVERY_CAMERA,
            _describe_frame_clock,
        ),
        Effect(
            FLIPPED,
            "flipped readout",
            "band edges on the wrong side: a trend against the row of twice the time per row "
            "and a gap between leading and trailing edges",
            "readout rows reversed (q = height - 1 - row), leading and trailing edges swapped",
            EVERY_CAMERA,
            _describe_flip,
        ),
        Effect(
            ROW_TIME,
            "time per row",
            "a trend of the residuals against the readout row",
            "adds the camera's time per row minus the nominal frame period / height, ms per row",
            EVERY_CAMERA,
            _describe_row_time,
            column=lambda f: -f.q,
        ),
        Effect(
            DRIFT,
            "clock drift",
            "a trend of the residuals against time",
            "adds the camera's clock rate minus one (alpha - 1) about its mid time",
            OTHER_CAMERAS,
            _describe_drift,
            column=lambda f: -f.t_ms,
        ),
        Effect(
            DRIFT_RATE,
            "drift-rate change",
            "a curvature of the residuals against time",
            "adds half the rate of change of the drift (per ms), with the drift itself",
            OTHER_CAMERAS,
            _describe_drift_rate,
            column=lambda f: -(f.t_ms**2),
            implies=(DRIFT,),
        ),
        Effect(
            EXPOSURE,
            "exposure",
            "a constant gap between a camera's trailing and leading edges' residuals: its "
            "mid-exposure times are off the reference's",
            "adds the camera's exposure minus the reference's (on its trailing edges), ms",
            OTHER_CAMERAS,
            _describe_exposure,
            column=lambda f: f.trailing.astype(np.float64),
        ),
        Effect(
            SATURATION,
            "saturation",
            "the edges of bands clipped at white off the others': the clipped plateau pulls the "
            "half-level crossing of the leading edge early and of the trailing edge late",
            "adds how far a clipped band's edges move out (ms, leading ones earlier) and the share "
            "of its length over its clipped kind's median that they move out by (a deeper clip "
            "makes a longer band)",
            EVERY_CAMERA,
            _describe_saturation,
            column=lambda f: _saturation_columns(f),
        ),
        Effect(
            PULSE_SHAPE,
            "flash pulse shape",
            "bands widened beyond any ordinary band of the camera (seen under xenon tails on "
            "bands split across two frames): their trailing edges late, their leading edges early",
            "adds the shares of each band's excess length (ms) that its trailing edge is late "
            "and its leading edge early by",
            EVERY_CAMERA,
            _describe_pulse_shape,
            column=lambda f: np.column_stack(
                [np.where(f.trailing, f.excess_ms, 0.0), np.where(f.trailing, 0.0, -f.excess_ms)]
            ),
        ),
        Effect(
            STAMP_RATE,
            "stamp rate change",
            "from one frame on, the edges run away from the model at a steady rate while the "
            "stamps about their own clock do not: the stamps changed rate, the sensor did not",
            "frame times at one rate throughout (that of one of the stamps' segments, whichever fits "
            "the edges best) instead of the stamps' own rate in each segment",
            EVERY_CAMERA,
            _describe_stamp_rate,
            implies=(DROPPED_FRAMES, FRAME_CLOCK),
        ),
        Effect(
            FLICKER,
            "rolling mains flicker",
            "the camera's rolling mains flicker: its period in rows off the one the model's time "
            "per row predicts ((1000 / hz) / time per row)",
            "times the camera's rows by the flicker: time per row (1000 / hz) / period in rows "
            "instead of frame period / height",
            EVERY_CAMERA,
            _describe_flicker,
        ),
    )
}
