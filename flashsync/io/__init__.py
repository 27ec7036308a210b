"""Every file format flashsync reads or writes, one module each, with ``load_*`` / ``save_*``.

===================  ======================================  =========================================
module               file                                    functions
===================  ======================================  =========================================
``model_file``       ``sync.json``, the model                :func:`load_model`, :func:`save_model`
``events``           the events table (``detect``)           :func:`load_events`, :func:`save_events`,
                                                             :func:`events_to_frame`
``detections``       tracker detections: CSV, Parquet, MOT   :func:`load_detections`,
                                                             :func:`save_detections`, :func:`load_mot`
``timestamps``       a camera's frame times as CSV           :func:`load_timestamps`
``homographies``     image -> plane homographies, JSON       :func:`load_homographies`,
                     (and the plane's outline)               :func:`load_plane_outline`
``validation``       ``validate --json``                     :func:`load_validation`,
                                                             :func:`save_validation`
``scenario``         simulator scenario, YAML or JSON        :func:`load_scenario`
``truth``            ``truth.json``, a simulation's truth    :func:`load_ground_truth`,
                                                             :func:`save_ground_truth`
``tables``           any table as CSV or Parquet, atomically :func:`write_table`
===================  ======================================  =========================================

Each reader is the single entry point of its format: whatever reads that file calls it.
Writers are atomic (:mod:`flashsync.atomic`).
"""

from flashsync.lazy import lazy_exports

#: Each exported name and the module that defines it, imported on first use
#: (:mod:`flashsync.lazy`): a command loads only the modules it needs.
_EXPORTS = {
    "events_from_frame": "flashsync.io.events",
    "events_to_frame": "flashsync.io.events",
    "load_detections": "flashsync.io.detections",
    "load_events": "flashsync.io.events",
    "load_ground_truth": "flashsync.io.truth",
    "load_homographies": "flashsync.io.homographies",
    "load_model": "flashsync.io.model_file",
    "load_mot": "flashsync.io.detections",
    "load_plane_outline": "flashsync.io.homographies",
    "load_scenario": "flashsync.io.scenario",
    "load_timestamps": "flashsync.io.timestamps",
    "load_validation": "flashsync.io.validation",
    "save_detections": "flashsync.io.detections",
    "save_events": "flashsync.io.events",
    "save_ground_truth": "flashsync.io.truth",
    "save_model": "flashsync.io.model_file",
    "save_validation": "flashsync.io.validation",
    "write_table": "flashsync.io.tables",
}

__all__ = [
    "events_from_frame",
    "events_to_frame",
    "load_detections",
    "load_events",
    "load_ground_truth",
    "load_homographies",
    "load_model",
    "load_mot",
    "load_plane_outline",
    "load_scenario",
    "load_timestamps",
    "load_validation",
    "save_detections",
    "save_events",
    "save_ground_truth",
    "save_model",
    "save_validation",
    "write_table",
]

lazy_exports(__name__, _EXPORTS)
