"""millplan.speed against `millplan speed` on the demo's raster and part:
the written program byte for byte, the per-point table against the
command's --table CSV, the report against --json."""

import csv
import json

import numpy as np
import pytest

import millplan
from conftest import assert_like_cli, run_cli

CUT = dict(vc=63.0, fz=0.125, flutes=2, ap=0.3)


@pytest.fixture(scope="module")
def by_cli(cli, demo, tmp_path_factory):
    d = tmp_path_factory.mktemp("speed")
    out, table = d / "cli.nc", d / "cli.csv"
    r = run_cli(cli, "speed", demo / "finish.apt", "--stl", demo / "part.stl", "--vc", CUT["vc"],
                "--fz", CUT["fz"], "--flutes", CUT["flutes"], "--ap", CUT["ap"],
                "--machine", demo / "machine.toml", "-o", out, "--table", table, "--json", "-q")
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    return out.read_bytes(), rows, json.loads(r.stdout)


@pytest.fixture(scope="module")
def by_py(demo):
    return millplan.speed(demo / "finish.apt", millplan.read_stl(demo / "part.stl"),
                          machine=demo / "machine.toml", pandas=False, **CUT)


def test_speed_writes_the_program_the_command_writes(demo, by_cli, by_py, tmp_path):
    new, _, _ = by_py
    # Written as the command writes it: in the machine file's dialect.
    assert millplan.write_program(new, tmp_path / "py.nc", machine=demo / "machine.toml") == "fanuc"
    assert (tmp_path / "py.nc").read_bytes() == by_cli[0]


def test_speed_table_is_the_commands_table(by_cli, by_py):
    _, t, _ = by_py
    rows = by_cli[1]
    assert len(rows) > 100 and all(len(a) == len(rows) for a in t.values())
    # The CSV rounds lengths to 1 µm, normals to 1e-6, angles to 0.001°,
    # speeds and feeds to 0.1.
    for name, tol in [("x", 5e-4), ("cz", 5e-4), ("nz", 5e-7), ("inclination_deg", 5e-4),
                      ("feed_angle_deg", 5e-4), ("d_w", 5e-4), ("n", 0.05), ("feed", 0.05),
                      ("n_target", 0.05)]:
        theirs = np.array([float(r[name]) for r in rows])
        np.testing.assert_allclose(t[name], theirs, atol=tol * 1.001, err_msg=name)
    ae = np.array([float(r["ae"]) if r["ae"] else np.nan for r in rows])
    np.testing.assert_allclose(t["ae"], ae, atol=5.01e-4, equal_nan=True)
    assert list(t["uncut_side"]) == [r["uncut_side"] for r in rows]
    assert list(t["line"]) == [int(r["line"]) for r in rows]
    for name in ["clamped", "rate_limited", "held", "gap_flag", "corner"]:
        assert list(t[name]) == [r[name] == "1" for r in rows], name


def test_speed_report_is_what_json_prints(by_cli, by_py):
    theirs = dict(by_cli[2])
    theirs.pop("output")
    theirs.pop("dialect")
    assert_like_cli(by_py[2], theirs)


def test_speed_table_is_a_dataframe_with_pandas(demo):
    pd = pytest.importorskip("pandas")
    _, df, _ = millplan.speed(demo / "finish.apt", demo / "part.stl", **CUT)
    assert isinstance(df, pd.DataFrame) and "d_w" in df.columns


def test_speed_refuses_a_stock_thicker_than_the_ball_radius(demo):
    with pytest.raises(millplan.MillplanError, match="ap"):
        millplan.speed(demo / "finish.apt", demo / "part.stl", vc=63, fz=0.1, flutes=2, ap=50)
