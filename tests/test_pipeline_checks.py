"""synchronize's checks of its arguments and of what it announces: datasheet times per row
of unknown cameras or no number, anchors naming two events of one camera, cameras left out."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flashsync import detect_videos, synchronize
from flashsync.detect import CameraDetection
from flashsync.errors import InputError
from flashsync.events import Band, Edge, Events
from flashsync.pipeline import check_anchors, check_row_times


@pytest.mark.parametrize(
    "row_times, words",
    [({"cam9": 0.03}, "cam9: no such camera among cam1, cam2"), ({"cam1": math.inf}, "cam1=inf"),
     ({"cam1": math.nan}, "cam1=nan"), ({"cam1": -0.1}, "cam1=-0.1"), ({"cam1": True}, "cam1=True")],
)  # fmt: skip
def test_datasheet_times_per_row_of_no_camera_or_no_number_are_errors(row_times, words):
    with pytest.raises(InputError) as error:
        check_row_times(row_times, ["cam1", "cam2"])
    assert error.value.parameter == "row_times" and words in str(error.value)


def test_anchors_naming_two_events_of_one_camera_are_an_error():
    check_anchors(["cam1:0", "cam2:3", "cam1:0"])  # the same anchor twice is one
    with pytest.raises(InputError) as error:
        check_anchors(["cam1:0", "cam2:3", "cam1:4"])
    assert error.value.parameter == "anchors" and "cam1:0 and cam1:4" in str(error.value)


def test_a_camera_left_out_is_not_announced_upside_down(tiny_scenario):
    """A third camera read both ways up whose bottom-up reading has two leading edges fewer:
    the search reads it bottom-up (two events fewer unexplained raise the likelihood by more
    than a choice needs), but it
    is left out (too few events) and must not be reported as mounted upside down."""
    detections = detect_videos([tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv"], estimate_readout=False)

    def one_edge(count: int) -> Events:
        return Events.from_columns(
            ["cam3"] * count, range(count), [5] * count, [200.0] * count, [10.0] * count, [Edge.LEADING] * count,
            [Band.PULSE] * count, [1.0] * count, [0.5] * count, [50.0] * count, [frozenset()] * count,
        )  # fmt: skip

    lonely = CameraDetection("cam3", tiny_scenario / "cam3.mp4", 160, 120, np.arange(50) * 40.0, one_edge(2),
                             one_edge(0))  # fmt: skip
    model, report = synchronize([*detections, lonely])
    assert "cam3" not in model.cameras and any("cam3.mp4: 0 usable flash events" in w for w in report.warnings)
    assert report.flipped_found == []
