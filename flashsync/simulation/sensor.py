"""A camera's response: from linear light to stored values (DN) before rounding.

Linear light is in DN of the default camera: a surface of reflectance ``rho`` (DN) under
illumination 1 gives ``rho``. The response divides it by the camera's white level (the
linear light that saturates the sensor), clips to [0, 1] (highlights and bright flash rows
clip), applies the tone curve and lifts the result onto the black level (pedestal)::

    DN = black + (255 - black) * tone(clip(linear * shading / white, 0, 1))

The default (linear tone, black 0, white 255, no vignetting) is the identity up to the
clipping at 0 and 255, so a flash scales DN exactly. With a tone curve it does not: the
relative change of a band depends on the scene's brightness under it.
"""

from __future__ import annotations

import numpy as np

from flashsync.simulation.scenario import CameraSpec


def tone_curve(v: np.ndarray, tone: str) -> np.ndarray:
    """Map linear values in [0, 1] to encoded values in [0, 1].

    Parameters
    ----------
    v : ndarray
        Linear light relative to white.
    tone : {'linear', 'srgb', 'gamma'}
        ``srgb``: IEC 61966-2-1 (a linear toe, then ``1.055 v^(1/2.4) - 0.055``);
        ``gamma``: ``v^(1/2.2)``.

    Returns
    -------
    ndarray, same shape and dtype as `v`
    """
    if tone == "linear":
        return v
    if tone == "gamma":
        return np.power(v, 1.0 / 2.2, dtype=v.dtype)
    if tone == "srgb":
        return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4, dtype=v.dtype) - 0.055).astype(
            v.dtype
        )
    raise ValueError(f"unknown tone curve {tone!r}")


def shading(camera: CameraSpec) -> np.ndarray | None:
    """Vignetting of a camera: ``1 - vignetting * rho**2`` with ``rho`` the distance from
    the image centre over the half-diagonal (1 at the corners); shape (height, width),
    float32; None without vignetting."""
    if camera.vignetting == 0:
        return None
    y = (np.arange(camera.height) - (camera.height - 1) / 2.0) / (camera.height / 2.0)
    x = (np.arange(camera.width) - (camera.width - 1) / 2.0) / (camera.width / 2.0)
    rho2 = (y[:, None] ** 2 * camera.height**2 + x[None, :] ** 2 * camera.width**2) / (
        camera.height**2 + camera.width**2
    )
    return (1.0 - camera.vignetting * rho2).astype(np.float32)


def sensor_response(linear: np.ndarray, camera: CameraSpec) -> np.ndarray:
    """Stored values (DN, not yet rounded) of linear light (see the module docstring).

    Parameters
    ----------
    linear : ndarray, float32, shape (height, width) or (height, width, 3)
        Linear light, DN at the default white level; vignetting already applied.
    camera : CameraSpec
        Uses ``tone``, ``black_level`` and ``white_level``.

    Returns
    -------
    ndarray, float32, same shape
    """
    black, white = camera.black_level, camera.white_level
    v = np.clip(linear, 0.0, white)
    if camera.tone == "linear":
        return v * np.float32((255.0 - black) / white) + np.float32(black)
    v /= white
    return tone_curve(v, camera.tone) * np.float32(255.0 - black) + np.float32(black)
