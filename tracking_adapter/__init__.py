"""Detections in and out: re-stamping with global times, cross-camera validation, formats.

Examples
--------
>>> from flashsync.model_file import load_model                                # doctest: +SKIP
>>> model = load_model("sync.json")                                             # doctest: +SKIP
>>> print(format_summary(restamp_file("dets.csv", "dets_t.csv", model)))        # doctest: +SKIP
>>> report = validate(read_detections("puck.csv"), model,
...                   load_homographies("H.json"))                              # doctest: +SKIP
>>> print(format_report(report))                                                # doctest: +SKIP
"""

from tracking_adapter.formats import load_homographies, read_detections, read_mot, write_detections
from tracking_adapter.restamp import RestampSummary, format_summary, restamp, restamp_file
from tracking_adapter.validate import ValidationReport, format_report, validate

__all__ = [
    "RestampSummary",
    "ValidationReport",
    "format_report",
    "format_summary",
    "load_homographies",
    "read_detections",
    "read_mot",
    "restamp",
    "restamp_file",
    "validate",
    "write_detections",
]
