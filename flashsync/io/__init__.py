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

from flashsync.io.detections import load_detections, load_mot, save_detections
from flashsync.io.events import events_from_frame, events_to_frame, load_events, save_events
from flashsync.io.homographies import load_homographies, load_plane_outline
from flashsync.io.model_file import load_model, save_model
from flashsync.io.scenario import load_scenario
from flashsync.io.tables import write_table
from flashsync.io.timestamps import load_timestamps
from flashsync.io.truth import load_ground_truth, save_ground_truth
from flashsync.io.validation import load_validation, save_validation

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
