"""Ground truth of a rendered scenario, in the terms of the sync model.

The first camera is the reference. The global clock ``s`` is the reference camera's
clock shifted so that the reference has ``alpha = 1`` and ``beta = 0``::

    s = (w - offset_ref) / (1 + drift_ref) - r0_ref * T_row_ref

A row's global time is the world time at which its exposure ends, mapped onto ``s``.
With ``drift_rate = 0``, camera ``c`` obeys the model exactly::

    s_c(f, q) = alpha_c * t_f + beta_c + q * row_time_c

where ``t_f`` is the true camera time of frame ``f`` and ``q`` the readout row
(``q = height - 1 - row`` for a flipped camera).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flashsync.errors import FlashsyncError
from flashsync.simulation.light import half_light_ms
from flashsync.simulation.scenario import CameraSpec, Scenario, clock_world_ms
from flashsync.simulation.scene import make_scene


@dataclass(frozen=True)
class CameraTruth:
    """True parameters of one camera and the frames it wrote.

    Attributes
    ----------
    name, file : str
        Camera name and video file name.
    width, height, r0, r1 : int
        Image size (px) and hidden rows.
    fps : float
    exposure_ms : float
        Exposure of the first written frame, ms.
    flipped : bool
        Readout runs bottom-up in stored-image rows.
    drift_ppm, drift_rate_ppm_per_s, offset_ms, start_ms : float
        Clock: ``w = (1 + drift) t + offset + drift_rate t**2 / 2``, first frame at ``start_ms``.
    alpha, beta_ms, row_time_ms : float
        Sync model parameters (readout rows; global clock).
    frame_index : list of int
        Sensor frame number of each written frame (dropped ones are missing).
    frame_times_ms : list of float
        True camera time of each written frame, ms.
    stamps_ms : list of float
        Container stamp of each written frame, ms.
    flashes_seen : dict
        ``{flash index: [file frame indices showing it]}``.
    exposure_changes : list of (int, float)
        ``(file frame index, exposure_ms)`` where the exposure differs from the written
        frame before it (a change at a dropped sensor frame shows at the next written one);
        empty for a steady exposure. See `exposure_of_ms`.
    """

    name: str
    file: str
    width: int
    height: int
    fps: float
    r0: int
    r1: int
    flipped: bool
    exposure_ms: float
    drift_ppm: float
    drift_rate_ppm_per_s: float
    offset_ms: float
    start_ms: float
    alpha: float
    beta_ms: float
    row_time_ms: float
    frame_index: list = field(default_factory=list)
    frame_times_ms: list = field(default_factory=list)
    stamps_ms: list = field(default_factory=list)
    flashes_seen: dict = field(default_factory=dict)
    exposure_changes: list = field(default_factory=list)

    def exposure_of_ms(self, frame: int | np.ndarray) -> np.ndarray:
        """Exposure (ms) of frames `frame` (0-based indices in the written file), same shape."""
        frame = np.asarray(frame)
        exposure = np.full(frame.shape, float(self.exposure_ms))
        for first, exposure_ms in self.exposure_changes:
            exposure[frame >= first] = exposure_ms
        return exposure

    @property
    def sensor_row_ms(self) -> float:
        """Readout time of one row, ms of camera time."""
        return 1000.0 / self.fps / (self.r0 + self.height + self.r1)

    def world_ms(self, t_ms: float | np.ndarray) -> np.ndarray:
        """World time (ms) of camera time `t_ms` (ms)."""
        return clock_world_ms(t_ms, self.offset_ms, self.drift_ppm, self.drift_rate_ppm_per_s)


def _params(ref: CameraSpec, cam: CameraSpec) -> tuple[float, float, float]:
    """alpha, beta_ms, row_time_ms of `cam` relative to `ref` (CameraSpec, drift_rate ignored)."""
    k_ref = 1.0 + ref.drift_ppm * 1e-6
    k = 1.0 + cam.drift_ppm * 1e-6
    alpha = k / k_ref
    row = k * cam.row_time_ms / k_ref
    beta = (k * cam.r0 * cam.row_time_ms + cam.offset_ms - ref.offset_ms) / k_ref - ref.r0 * ref.row_time_ms
    return alpha, beta, row


def camera_truth(
    camera: CameraSpec,
    file: str,
    frame_index: np.ndarray,
    frame_times_ms: np.ndarray,
    stamps_ms: np.ndarray,
    flashes_seen: dict,
    reference: CameraSpec,
) -> CameraTruth:
    """Collect a camera's truth record (see `CameraTruth`).

    Parameters
    ----------
    camera, reference : CameraSpec
        The camera and the scenario's reference camera.
    file : str
        Video file name.
    frame_index : ndarray of int, shape (F,)
        Sensor frame numbers written.
    frame_times_ms, stamps_ms : ndarray, shape (F,)
        True camera times and container stamps of those frames, ms.
    flashes_seen : dict
        ``{flash index: [file frame indices]}``.

    Returns
    -------
    CameraTruth
    """
    alpha, beta, row = _params(reference, camera)
    exposures = camera.exposure_at_ms(frame_times_ms)
    return CameraTruth(
        name=camera.name,
        file=file,
        width=camera.width,
        height=camera.height,
        fps=camera.fps,
        r0=camera.r0,
        r1=camera.r1,
        flipped=camera.flipped,
        exposure_ms=float(exposures[0]) if len(exposures) else camera.exposure_ms,
        drift_ppm=camera.drift_ppm,
        drift_rate_ppm_per_s=camera.drift_rate_ppm_per_s,
        offset_ms=camera.offset_ms,
        start_ms=camera.start_ms,
        alpha=alpha,
        beta_ms=beta,
        row_time_ms=row,
        frame_index=[int(f) for f in frame_index],
        frame_times_ms=[float(t) for t in frame_times_ms],
        stamps_ms=[float(t) for t in stamps_ms],
        flashes_seen={int(k): [int(f) for f in v] for k, v in flashes_seen.items()},
        exposure_changes=[(int(j), float(exposures[j])) for j in np.flatnonzero(np.diff(exposures)) + 1],
    )


@dataclass(frozen=True)
class GroundTruth:
    """What the simulator knows and a synchroniser should find.

    Attributes
    ----------
    reference : str
        Name of the reference camera.
    cameras : dict of str to CameraTruth
        In scenario order.
    flashes : list of dict
        Per flash: ``world_ms``, ``global_ms`` (the firing instant on the global clock),
        ``half_rise_global_ms`` (when its light reaches half its full integral, the
        instant a half-rise band edge marks, for any pulse shape), ``strength``, the
        pulse shape (``decay_ms``, ``rise_ms``, ``rise``, ``hold_ms``), ``seen_by``
        (camera names).
    switches : list of dict
        Per light switch: ``world_ms``, ``global_ms``, ``factor``.
    scenario : dict
        The rendered scenario, as `Scenario.to_dict`.
    """

    reference: str
    cameras: dict
    flashes: list
    switches: list
    scenario: dict

    def _camera(self, name: str) -> CameraTruth:
        if name not in self.cameras:
            raise FlashsyncError(f"no camera '{name}' in the ground truth; cameras: {', '.join(self.cameras)}")
        return self.cameras[name]

    def global_from_world_ms(self, w_ms: float | np.ndarray) -> np.ndarray:
        """Global time (ms) of world times `w_ms` (ms)."""
        ref = self.cameras[self.reference]
        return (np.asarray(w_ms, dtype=float) - ref.offset_ms) / (
            1.0 + ref.drift_ppm * 1e-6
        ) - ref.r0 * ref.sensor_row_ms

    def global_time_ms(self, camera: str, frame: int | np.ndarray, row: float | np.ndarray) -> np.ndarray:
        """Global time of the end of exposure of stored-image rows.

        Computed from the world time of the true frame time, so it holds with clock
        drift rates too.

        Parameters
        ----------
        camera : str
        frame : int or ndarray of int
            0-based index of the frame in the written file.
        row : float or ndarray
            Stored-image row, top = 0 (fractional allowed); broadcast with `frame`.

        Returns
        -------
        ndarray
            ``t_global_ms`` on the reference camera's clock, ms.

        Examples
        --------
        >>> truth.global_time_ms("cam2", [0, 0, 5], [0.0, 179.0, 90.5])  # doctest: +SKIP
        """
        cam = self._camera(camera)
        row = np.asarray(row, dtype=float)
        q = cam.height - 1 - row if cam.flipped else row
        t = np.asarray(cam.frame_times_ms)[np.asarray(frame)] + (cam.r0 + q) * cam.sensor_row_ms
        return self.global_from_world_ms(cam.world_ms(t))

    def save(self, path: str | Path) -> None:
        """Write ``truth.json`` atomically (:func:`flashsync.io.truth.save_ground_truth`)."""
        from flashsync.io.truth import save_ground_truth  # it reads these records: imported late

        save_ground_truth(self, path)


def ground_truth(scenario: Scenario, cameras: list[CameraTruth]) -> GroundTruth:
    """Assemble the `GroundTruth` of a rendered scenario.

    Parameters
    ----------
    scenario : Scenario
    cameras : list of CameraTruth
        In scenario order (the first is the reference).

    Returns
    -------
    GroundTruth
    """
    partial = GroundTruth(cameras[0].name, {c.name: c for c in cameras}, [], [], scenario.to_dict())
    flashes = []
    for k, fl in enumerate(scenario.flashes):
        flashes.append(
            {
                "world_ms": fl.world_ms,
                "global_ms": float(partial.global_from_world_ms(fl.world_ms)),
                "half_rise_global_ms": float(partial.global_from_world_ms(fl.world_ms + half_light_ms(fl))),
                "strength": fl.strength,
                "decay_ms": fl.decay_ms,
                "rise_ms": fl.rise_ms,
                "rise": fl.rise,
                "hold_ms": fl.hold_ms,
                "seen_by": [c.name for c in cameras if c.flashes_seen.get(k)],
            }
        )
    switches = [
        {"world_ms": s.world_ms, "global_ms": float(partial.global_from_world_ms(s.world_ms)), "factor": s.factor}
        for s in scenario.switches
    ]
    return GroundTruth(partial.reference, partial.cameras, flashes, switches, partial.scenario)


def puck_image_px(truth: GroundTruth, homography: np.ndarray, t_global_ms: np.ndarray) -> np.ndarray:
    """Where the scenario's puck is in a camera's image at instants of the true global
    clock: its rink position then, through the inverse of the camera's image -> rink
    homography (``homographies.json``).

    Parameters
    ----------
    truth : GroundTruth
    homography : array of shape (3, 3)
        The camera's image px -> rink m.
    t_global_ms : ndarray, shape (n,)
        Instants, true global clock, ms.

    Returns
    -------
    ndarray, shape (n, 2)
        Image x (column) and stored-image row, px.
    """
    ref = truth.cameras[truth.reference]
    world = (np.asarray(t_global_ms, dtype=float) + ref.r0 * ref.sensor_row_ms) * (
        1.0 + ref.drift_ppm * 1e-6
    ) + ref.offset_ms
    scenario = truth.scenario
    puck = make_scene(scenario["seed"], scenario["n_players"], scenario["puck_speed_mps"]).puck
    rink = puck.position(world)
    image = np.linalg.inv(np.asarray(homography, dtype=float)) @ np.vstack([rink.T, np.ones(len(rink))])
    return (image[:2] / image[2]).T
