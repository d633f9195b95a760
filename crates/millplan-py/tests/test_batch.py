"""millplan.batch: three programs and a broken one on a LocalCluster of two
workers, the table against single-process runs of the same programs."""

import shutil

import pandas as pd
import pytest

import millplan
from millplan import batch

# G-code says nothing of the cutter's shape: the demo's ball:10 for all.
OPTIONS = dict(stock="offset:0.5", material="al7075", tools="ball:10", passes="speed,feed", resolution=0.5)


@pytest.fixture(scope="module")
def folder(demo, tmp_path_factory):
    """Three programs (the demo's raster as APT and Heidenhain, and its
    constant-speed version in G-code) and one that cannot be read: each
    runs the whole job twice, so more would test the cluster no further."""
    d = tmp_path_factory.mktemp("batch")
    for name in ["finish.apt", "finish_heidenhain.h", "finish_constant_vc_fanuc.nc"]:
        shutil.copy(demo / name, d / name)
    (d / "broken.nc").write_text("G21\nG1 X1 Q@@\n")
    return d


def test_the_batch_on_two_workers_agrees_with_one_process(demo, folder, tmp_path):
    opts = dict(OPTIONS, part=str(demo / "part.stl"), machine=str(demo / "machine.toml"))
    csv = tmp_path / "summary.csv"
    out = tmp_path / "optimised"
    df = batch.optimise_folder(str(folder), workers=2, threads_per_worker=1, csv=str(csv),
                               output=str(out), **opts)
    assert list(df.columns) == batch.COLUMNS
    assert len(df) == 4
    assert list(df["file"]) == sorted(df["file"])
    broken = df[df["file"] == "broken.nc"].iloc[0]
    assert broken["verdict"] == "error" and "broken.nc:2:8" in broken["error"]
    good = df[df["file"] != "broken.nc"]
    # Each program is improved with every check passed (the constant-vc
    # program too: a block still over its power at the smallest chip runs at
    # a lower spindle speed).
    assert (good["verdict"] == "improved").all(), good
    improved = good
    assert (improved["time_after_s"] < improved["time_before_s"]).all()
    assert (improved["failed_checks"] == "").all()
    # Written in the machine's dialect (Fanuc), under their own names.
    stems = sorted(f.rsplit(".", 1)[0] + ".nc" for f in improved["file"])
    assert sorted(p.name for p in out.iterdir()) == stems
    # The same table, computed in this process one program after another.
    one = batch.table([batch.optimise_one(str(folder / f), dict(opts)) for f in df["file"]])
    pd.testing.assert_frame_equal(df, one)
    again = pd.read_csv(csv, keep_default_na=False)
    assert list(again["file"]) == list(df["file"])
    assert list(again["verdict"]) == list(df["verdict"])
