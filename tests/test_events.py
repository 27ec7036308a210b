"""Typed events: the events table file round trip and the pairing of edges into bands."""

import numpy as np
import pandas as pd
import pytest

from flashsync.errors import InputError
from flashsync.events import Band, Edge, Events, Flag
from flashsync.io import load_events, save_events


def events() -> Events:
    """Three events of one camera: a split pulse, a pulse whose leading edge is hidden, a light
    switched on (a step: leading edge only)."""
    return Events.from_columns(
        camera=["cam1"] * 4,
        event=[0, 0, 1, 2],
        frame=[3, 4, 9, 20],
        t_frame_ms=[100.0, 133.4, 300.2, 667.0],
        row=[170.25, 12.5, 40.75, 0.5],
        edge=[Edge.LEADING, Edge.TRAILING, Edge.TRAILING, Edge.LEADING],
        band=[Band.PULSE, Band.PULSE, Band.PULSE, Band.ON],
        rise_rows=[4.1, 4.3, 3.9, np.nan],
        strength=[0.4, 0.4, 0.5, 0.6],
        quality=[400.0, 400.0, 500.0, 600.0],
        flags=[frozenset({Flag.SPLIT, Flag.SATURATED})] * 2 + [frozenset({Flag.LEADING_HIDDEN}), frozenset()],
    )


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_events_table_round_trip(tmp_path, suffix):
    save_events(events(), tmp_path / f"events{suffix}")
    again = load_events(tmp_path / f"events{suffix}")
    for name in ("camera", "event", "frame", "t_frame_ms", "row", "edge", "band", "strength", "quality", "flags"):
        assert list(getattr(again, name)) == list(getattr(events(), name)), name
    np.testing.assert_array_equal(again.rise_rows, events().rise_rows)
    assert again.edge[0] is Edge.LEADING and again.flags[0] == {Flag.SPLIT, Flag.SATURATED}


def test_flags_are_joined_text_in_the_csv(tmp_path):
    save_events(events(), tmp_path / "events.csv")
    table = pd.read_csv(tmp_path / "events.csv", keep_default_na=False)
    assert list(table["flags"]) == ["saturated|split", "saturated|split", "leading_hidden", ""]
    assert list(table["edge"]) == ["leading", "trailing", "trailing", "leading"]


def test_edges_pair_into_bands():
    bands = events().bands()
    assert list(bands.event) == [0, 1, 2]
    assert list(bands.leading) == [0, -1, 3] and list(bands.trailing) == [1, 2, -1]
    assert list(bands.complete) == [True, False, False]
    assert list(bands.first_edges()) == [0, 2, 3]


def test_an_unknown_edge_kind_is_an_input_error(tmp_path):
    save_events(events(), tmp_path / "events.csv")
    table = pd.read_csv(tmp_path / "events.csv")
    table.loc[1, "edge"] = "middle"
    table.to_csv(tmp_path / "bad.csv", index=False)
    with pytest.raises(InputError, match="bad.csv: row 2, column edge is .middle., expected one of leading, trailing"):
        load_events(tmp_path / "bad.csv")
