"""restamp of a folder of tables (a partitioned dataset), partition by partition, here and
on a Dask cluster: each output file is what restamp_file makes of its input."""

import pandas as pd
import pytest
from cli_run import one_error_line, run
from test_restamp import model  # noqa: F401 - the fixture

from flashsync.io import save_model
from tracking_adapter.restamp import restamp_file, restamp_folder


@pytest.fixture
def dataset(tmp_path):
    """``camera=cam1/part-0.parquet``, ``camera=cam2/part-0.parquet`` and ``extra.csv``, one with
    a row of an unknown camera and one with a frame out of range."""
    folder = tmp_path / "dets"
    tables = {
        "camera=cam1/part-0.parquet": pd.DataFrame(
            {"camera": ["cam1"] * 3, "frame": [0, 5, 49], "y": [1.0, 50.0, 99.0]}
        ),
        "camera=cam2/part-0.parquet": pd.DataFrame({"camera": ["cam2", "cam2"], "frame": [3, 99], "y": [0.0, 4.0]}),
    }
    for name, table in tables.items():
        (folder / name).parent.mkdir(parents=True)
        table.assign(object=range(len(table))).to_parquet(folder / name)
    (folder / "extra.csv").write_text("camera,frame,y,x\ncam1,1,2.5,3\ncamX,1,2,3\n")
    return folder


def test_each_partition_as_restamp_file_makes_it(dataset, tmp_path, model):  # noqa: F811
    summary = restamp_folder(dataset, tmp_path / "out", model, with_std=True)
    assert (summary.rows, summary.stamped) == (7, 5)
    assert summary.failed == {"unknown camera": 1, "frame past the end of the video": 1}
    assert summary.unknown_cameras == {"camX"}
    names = sorted(str(p.relative_to(dataset)) for p in dataset.rglob("*.*"))
    assert sorted(str(p.relative_to(tmp_path / "out")) for p in (tmp_path / "out").rglob("*.*")) == names
    for name in names:
        restamp_file(dataset / name, tmp_path / "one" / name, model, with_std=True)
        assert (tmp_path / "out" / name).read_bytes() == (tmp_path / "one" / name).read_bytes(), name
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no scratch left


def test_command_here_and_on_a_cluster(dataset, tmp_path, model, capsys, local_cluster):  # noqa: F811
    save_model(model, tmp_path / "sync.json")
    code, _, err = run(capsys, "restamp", dataset, "--model", tmp_path / "sync.json")
    assert code == 1 and "sync.json: camX (it holds cam1, cam2);" in err
    here = tmp_path / "dets.restamped"
    code, _, err = run(
        capsys,
        "restamp",
        dataset,
        "--model",
        tmp_path / "sync.json",
        "-o",
        tmp_path / "c",
        "--scheduler",
        local_cluster,
    )
    assert code == 1 and "7 rows, 5 stamped" in err
    for path in here.rglob("*.*"):
        assert (tmp_path / "c" / path.relative_to(here)).read_bytes() == path.read_bytes()


@pytest.mark.parametrize(
    "case, words",
    [
        ("output exists", ["out", "not an empty folder"]),
        ("no tables", ["holds no .parquet"]),
        ("bad partition", ["bad.csv", "y"]),
        ("scheduler with a file", ["--scheduler local:1", "is a file"]),
    ],
)
def test_bad_folders(dataset, tmp_path, model, capsys, case, words):  # noqa: F811
    save_model(model, tmp_path / "sync.json")
    source, out = dataset, tmp_path / "out"
    options = []
    if case == "output exists":
        out.mkdir()
        (out / "keep.txt").write_text("mine")
    elif case == "no tables":
        source = tmp_path / "empty"
        source.mkdir()
    elif case == "bad partition":
        (dataset / "bad.csv").write_text("camera,frame\ncam1,1\n")
    else:
        source, options = dataset / "extra.csv", ["--scheduler", "local:1"]
    code, _, err = run(capsys, "restamp", source, "--model", tmp_path / "sync.json", "-o", out, *options)
    assert code == 1
    one_error_line(err, *words)
    assert (out / "keep.txt").exists() if case == "output exists" else not out.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
