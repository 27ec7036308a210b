"""Text report of a :class:`~flashsync.diagnose.workflow.Diagnosis`: one line per step, the
verdict on the noise and the final model per camera. ``Diagnosis.to_dict()`` is the JSON."""

from __future__ import annotations

from flashsync.diagnose.workflow import THRESHOLD, Diagnosis
from flashsync.pipeline import FASTEST_READOUT
from flashsync.solve import DRIFT_PRIOR_STD


def format_diagnosis(diagnosis: Diagnosis) -> str:
    """The diagnosis as aligned text.

    Examples
    --------
    >>> print(format_diagnosis(diagnose(detect_videos(["a.mp4", "b.mp4"]))))  # doctest: +SKIP
    """
    d = diagnosis
    lines = [
        f"{len(d.cameras)} cameras (reference {d.reference}), {d.n_flashes} flashes, "
        f"{d.n_edges} band edges; an effect is added where it lowers the BIC by more than "
        f"{THRESHOLD:g} and shrinks the RMS of the edges or the stamps or the flicker's gap",
        f"{'step':>4}  {'effect':<32} {'camera':<10} {'RMS before ms':>13} {'after ms':>9}  evidence",
        f"{0:>4}  {'plain model':<32} {'':<10} {'':>13} {d.initial_rms_ms:>9.4f}  "
        "shift per camera, one exposure, time per row = period / height, frame index x median step",
    ]
    for number, step in enumerate(d.steps, start=1):
        title = f"out: {step.title}" if step.removed else step.title
        lines.append(
            f"{number:>4}  {title:<32} {step.camera:<10} {step.rms_before_ms:>13.4f} "
            f"{step.rms_after_ms:>9.4f}  {step.evidence}"
        )
    if not d.steps:
        lines.append(
            "      no effect of the catalogue, alone or paired on one camera, lowers the BIC by "
            "more than the threshold and shrinks the RMS of the edges or the stamps or the flicker's gap"
        )
    if d.sync_shape:
        lines.append(
            " " * 6 + "in sync's shape".ljust(32) + f" {'every':<10} {d.found_rms_ms:>13.4f} "
            f"{d.final_rms_ms:>9.4f}  the effects above with every camera's time per row, exposure and drift "
            f"free under sync's priors (time per row a readout in {100 * FASTEST_READOUT:.0f}-100 % of the frame or "
            "its flicker's, "
            f"drift 0 ± {DRIFT_PRIOR_STD * 1e6:.0f} ppm)"
            + (
                f", and {', '.join(d.sync_readouts)} read the other way up, as sync reads "
                f"{'it' if len(d.sync_readouts) == 1 else 'them'}"
                if d.sync_readouts
                else ""
            )
        )
    lines += [d.verdict, f"model written (-o): {d.written}", d.agreement]
    lines.append(
        f"{'camera':<11} {'readout':<9} {'period ms':>10} {'missing':>7} {'drift ppm':>9} "
        f"{'ppm/s':>7} {'T_row ms':>9} {'exposure ms':>11} {'RMS ms':>7}"
    )
    for model, final in zip(d.model, d.residuals["final"]):
        name = model["camera"] + ("*" if model["reference"] else "")
        lines.append(
            f"{name:<11} {model['readout']:<9} {model['frame_period_ms']:>10.4f} "
            f"{model['missing_frames']:>7d} {model['drift_ppm']:>9.2f} "
            f"{model['drift_rate_ppm_per_s']:>7.3f} {model['row_time_ms']:>9.5f} "
            f"{model['exposure_ms']:>11.3f} {final['rms_ms']:>7.4f}"
        )
    lines += [f"warning: {warning}" for warning in d.warnings]
    return "\n".join(lines)
