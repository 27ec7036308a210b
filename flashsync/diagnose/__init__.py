"""The discrepancy workflow (``flashsync diagnose``): compare the time model's predictions
with what the videos measured, name the effect the model misses, add it, repeat.

Examples
--------
>>> from flashsync.pipeline import detect_videos
>>> from flashsync.diagnose import diagnose, format_diagnosis
>>> d = diagnose(detect_videos(["cam1.mp4", "cam2.mkv"]))      # doctest: +SKIP
>>> print(format_diagnosis(d))                                  # doctest: +SKIP
>>> d.to_dict()["steps"][0]["effect"]                           # doctest: +SKIP
'drift'
"""

from flashsync.diagnose.effects import CATALOGUE, CameraEstimate, Effect
from flashsync.diagnose.report import format_diagnosis
from flashsync.diagnose.workflow import Diagnosis, Step, diagnose

__all__ = ["CATALOGUE", "CameraEstimate", "Diagnosis", "Effect", "Step", "diagnose", "format_diagnosis"]
