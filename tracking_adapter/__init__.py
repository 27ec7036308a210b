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

from tracking_adapter.resample import Resampled, format_resampled, resample
from tracking_adapter.restamp import RestampSummary, format_summary, restamp, restamp_file
from tracking_adapter.validate import ErrorStats, PairValidation, ValidationReport, format_report, validate

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
