"""Light in world time, integrated analytically over exposure windows.

A row integrates light over its exposure window ``[start, end]`` (world time, ms). Every
light source here has a closed-form integral, so rendered bands and the ground truth stay
exact to rounding, whatever the window:

- a flash pulse (`FlashSpec`): a rise over ``rise_ms`` (linear or raised-cosine), a hold
  at its peak for ``hold_ms``, then an exponential decay with time constant ``decay_ms``
  (0: it switches off at once). The classic flash is an instant rise and a decay; a xenon
  tube rises in tens of microseconds; an LED strobe is a rectangle (hold only);
- the scene's ambient light: steps of light switches times mains flicker
  ``1 + m g(omega w + phase)``, where the waveform ``g`` has mean 0 and peak-to-peak 2:
  a sine, or a rectified sine ``2 (|sin(theta / 2)| - 2 / pi)`` (the lamp output of
  full-wave rectified mains: a DC part, and cusps at every zero crossing of the mains).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.simulation.scenario import FLICKER_WAVEFORMS, FlashSpec, LightSwitch


@dataclass(frozen=True)
class Lighting:
    """Scene lighting in world time.

    Attributes
    ----------
    flashes : tuple of FlashSpec
    switches : tuple of LightSwitch
    flicker_depth : float
        Modulation depth m of ``1 + m g(2 pi flicker_hz w / 1000 + flicker_phase)``.
    flicker_hz : float
        Flicker frequency, Hz (twice the mains frequency).
    flicker_phase : float
        Radians.
    flicker_waveform : {'sine', 'rectified'}
        Waveform ``g``: ``sin`` or ``2 (|sin(theta / 2)| - 2 / pi)``.
    """

    flashes: tuple[FlashSpec, ...] = ()
    switches: tuple[LightSwitch, ...] = ()
    flicker_depth: float = 0.0
    flicker_hz: float = 100.0
    flicker_phase: float = 0.0
    flicker_waveform: str = "sine"


def pulse_area_ms(flash: FlashSpec) -> float:
    """Integral of the pulse at peak intensity 1, ms: ``rise_ms / 2 + hold_ms + decay_ms``."""
    return flash.rise_ms / 2.0 + flash.hold_ms + flash.decay_ms


def flash_remaining(x_ms: np.ndarray, flash: FlashSpec) -> np.ndarray:
    """Fraction of a flash's light still to come ``x_ms`` after it fires.

    Parameters
    ----------
    x_ms : ndarray
        Time since the firing instant, ms (negative: before it).
    flash : FlashSpec

    Returns
    -------
    ndarray
        1 up to the firing instant, falling to 0 when the pulse is over; same shape as `x_ms`.
    """
    x = np.asarray(x_ms, dtype=float)
    r, h, d = flash.rise_ms, flash.hold_ms, flash.decay_ms
    area = pulse_area_ms(flash)
    rem = np.ones_like(x)
    if r > 0:
        u = np.clip(x, 0.0, r)
        given = u * u / (2.0 * r) if flash.rise == "linear" else u / 2.0 - r / (2.0 * np.pi) * np.sin(np.pi * u / r)
        rem = rem - given / area
    if h > 0:
        rem = rem - np.clip(x - r, 0.0, h) / area
    after = x >= r + h
    if d > 0:
        tail = (d / area) * np.exp(-(np.maximum(x, r + h) - r - h) / d)
    else:
        tail = np.zeros_like(x)
    return np.where(after, tail, rem)


def flash_light(start_w: np.ndarray, end_w: np.ndarray, flash: FlashSpec) -> np.ndarray:
    """Flash light integrated over exposure windows.

    Parameters
    ----------
    start_w, end_w : ndarray
        World times of the start and end of the windows, ms.
    flash : FlashSpec

    Returns
    -------
    ndarray
        ``strength`` times the fraction of the pulse's light inside the window: 0 before
        the flash, ``strength`` for a window holding all of it.
    """
    tau = flash.world_ms
    a = np.maximum(start_w, tau)
    lit = end_w > tau
    light = flash.strength * (flash_remaining(a - tau, flash) - flash_remaining(np.maximum(end_w, tau) - tau, flash))
    return np.where(lit, light, 0.0)


def flash_reaches(flash: FlashSpec, start_w_ms: float, end_w_ms: float) -> bool:
    """Whether `flash_light` can be other than exactly 0 in a window within ``[start, end]``
    (world ms): the flash fires before `end`, and its tail has not underflowed to 0 by
    `start` (``exp(-750)`` is 0 in double precision)."""
    spent_ms = flash.world_ms + flash.rise_ms + flash.hold_ms + 750.0 * flash.decay_ms
    return flash.world_ms < end_w_ms and start_w_ms < spent_ms


def half_light_ms(flash: FlashSpec) -> float:
    """Time after the firing instant when the flash has given half of its light, ms.

    The leading edge of a band at half its rise is the row whose exposure ends then, for
    any exposure longer than the pulse. Closed form except in a raised-cosine rise, where
    it is found by bisection to 1e-12 ms.
    """
    r, h, d = flash.rise_ms, flash.hold_ms, flash.decay_ms
    half = pulse_area_ms(flash) / 2.0
    if half > r / 2.0 + h:  # in the decay: d exp(-y / d) = half
        return r + h + d * np.log(2.0 * d / pulse_area_ms(flash))
    if half > r / 2.0:  # on the hold
        return r + half - r / 2.0
    if flash.rise == "linear":
        return float(np.sqrt(2.0 * r * half))
    lo, hi = 0.0, r
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        if mid / 2.0 - r / (2.0 * np.pi) * np.sin(np.pi * mid / r) < half:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _waveform_integral(theta: np.ndarray, waveform: str) -> np.ndarray:
    """Antiderivative of the zero-mean flicker waveform ``g`` at phase `theta` (radians)."""
    if waveform == "sine":
        return -np.cos(theta)
    if waveform != "rectified":
        raise ValueError(f"unknown flicker waveform {waveform!r}; use one of {FLICKER_WAVEFORMS}")
    # 2 (|sin(theta / 2)| - 2 / pi): |sin| over each whole half-turn of theta / 2 gives 2.
    half = theta / 2.0
    turns = np.floor(half / np.pi)
    abs_sin = 2.0 * (2.0 * turns + 1.0 - np.cos(half - turns * np.pi))
    return 2.0 * abs_sin - 4.0 / np.pi * theta


def ambient_light(start_w: np.ndarray, end_w: np.ndarray, lighting: Lighting) -> np.ndarray:
    """Mean scene illumination over exposure windows (1 without switches or flicker).

    Parameters
    ----------
    start_w, end_w : ndarray
        World times of the start and end of the windows, ms.
    lighting : Lighting

    Returns
    -------
    ndarray
        ``mean over the window of S(w) (1 + m g(omega w + phase))`` where ``S`` is the
        product of the factors of the switches before ``w``.
    """
    omega = 2.0 * np.pi * lighting.flicker_hz / 1000.0
    m, phase = lighting.flicker_depth, lighting.flicker_phase

    def integral(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return (y - x) + (m / omega) * (
            _waveform_integral(omega * y + phase, lighting.flicker_waveform)
            - _waveform_integral(omega * x + phase, lighting.flicker_waveform)
        )

    switches = sorted(lighting.switches, key=lambda s: s.world_ms)
    edges = [-np.inf] + [s.world_ms for s in switches] + [np.inf]
    total = np.zeros(np.broadcast(start_w, end_w).shape)
    level = 1.0
    for k in range(len(edges) - 1):
        if k > 0:
            level *= switches[k - 1].factor
        x = np.clip(start_w, edges[k], edges[k + 1])
        y = np.clip(end_w, edges[k], edges[k + 1])
        total += level * integral(x, y)
    return total / (end_w - start_w)
