"""Detections in and out: re-stamping with global times, cross-camera validation and
resampling at common instants (the detections' file formats: :mod:`flashsync.io.detections`).

Examples
--------
>>> from flashsync.io import load_detections, load_homographies, load_model   # doctest: +SKIP
>>> model = load_model("sync.json")                                             # doctest: +SKIP
>>> print(format_summary(restamp_file("dets.csv", "dets_t.csv", model)))        # doctest: +SKIP
>>> report = validate(load_detections("puck.csv"), model,
...                   load_homographies("H.json"))                              # doctest: +SKIP
>>> print(format_report(report))                                                # doctest: +SKIP
>>> from flashsync.ticks import model_ticks_ms                                  # doctest: +SKIP
>>> tracks = resample(load_detections("puck.csv"), model,
...                   model_ticks_ms(model, 100.0)).tracks                      # doctest: +SKIP
"""

from flashsync.lazy import lazy_exports

#: Each exported name and the module that defines it, imported on first use
#: (:mod:`flashsync.lazy`): a command loads only the modules it needs.
_EXPORTS = {
    "ErrorStats": "tracking_adapter.validate",
    "PairValidation": "tracking_adapter.validate",
    "Resampled": "tracking_adapter.resample",
    "RestampSummary": "tracking_adapter.restamp",
    "ValidationReport": "tracking_adapter.validate",
    "format_report": "tracking_adapter.validate",
    "format_resampled": "tracking_adapter.resample",
    "format_summary": "tracking_adapter.restamp",
    "resample": "tracking_adapter.resample",
    "restamp": "tracking_adapter.restamp",
    "restamp_file": "tracking_adapter.restamp",
    "validate": "tracking_adapter.validate",
}

__all__ = [
    "ErrorStats",
    "PairValidation",
    "Resampled",
    "RestampSummary",
    "ValidationReport",
    "format_report",
    "format_resampled",
    "format_summary",
    "resample",
    "restamp",
    "restamp_file",
    "validate",
]

lazy_exports(__name__, _EXPORTS)
