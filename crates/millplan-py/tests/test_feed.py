"""millplan.feed against `millplan feed` on the demo's finishing program."""

import csv
import json

import numpy as np
import pytest

import millplan
from conftest import assert_like_cli, run_cli


@pytest.fixture(scope="module")
def fed(cli, demo, tmp_path_factory):
    d = tmp_path_factory.mktemp("feed")
    r = run_cli(cli, "feed", demo / "finish.apt", "--stock", "offset:0.5", "--stl", demo / "part.stl",
                "--material", "al7075", "--resolution", 0.5, "--machine", demo / "machine.toml",
                "--limit", "fxy=150", "--fos", 1.5, "-o", d / "cli.nc", "--table", d / "moves.csv",
                "--json", "-q", check=False)
    assert r.returncode in (0, 3), r.stderr
    with open(d / "moves.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    ours = millplan.feed(demo / "finish.apt", "offset:0.5", "al7075", part=demo / "part.stl",
                         machine=demo / "machine.toml", resolution=0.5, limits={"fxy": 150.0},
                         fos=1.5, output=d / "py.nc", pandas=False)
    return json.loads(r.stdout), rows, (d / "cli.nc").read_text(), d / "py.nc", ours


def test_feed_summary_is_the_commands(fed):
    theirs, _, _, py_out, (_, _, summary, _) = fed
    assert summary.pop("output") == str(py_out)
    theirs.pop("output")
    assert_like_cli(summary, theirs)
    assert summary["limits"]["fxy"] == 150.0 and summary["max_after"]["fxy"] > 0


def test_feed_writes_the_commands_program(fed):
    _, _, cli_text, py_out, (prog, text, summary, _) = fed
    assert text == cli_text and py_out.read_text() == cli_text
    assert summary["dialect"] == "fanuc"
    feeds = prog.feed[prog.kind == 1]
    assert len(feeds) > 100 and feeds.min() > 0


def test_feed_table_is_the_commands(fed):
    _, rows, _, _, (_, _, _, moves) = fed
    assert len(rows) > 100 and all(len(a) == len(rows) for a in moves.values())
    assert list(moves["line"]) == [int(r["line"]) for r in rows]
    for name, tol in [("fxy_max", 5e-4), ("torque_max", 5e-4), ("fz", 5e-6)]:
        theirs = np.array([float(r[name]) for r in rows])
        np.testing.assert_allclose(moves[name], theirs, atol=tol * 1.001, err_msg=name)
    allowed = np.array([float(r["fz_allowed"]) if r["fz_allowed"] else np.nan for r in rows])
    np.testing.assert_allclose(moves["fz_allowed"], allowed, atol=5e-6 * 1.001, equal_nan=True)


def test_feed_refuses_a_bad_limit_and_option(demo):
    with pytest.raises(millplan.MillplanError, match="fxy") as e:
        millplan.feed(demo / "finish.apt", "offset:0.5", "al7075", part=demo / "part.stl",
                      limits={"fxy": -1.0})
    assert e.value.file == "limit"
    with pytest.raises(millplan.MillplanError, match="fos") as e:
        millplan.feed(demo / "finish.apt", "offset:0.5", "al7075", part=demo / "part.stl", fos=0.5)
    assert e.value.file == "fos"


def test_feed_locates_a_bad_program(tmp_path):
    bad = tmp_path / "bad.nc"
    bad.write_text("G21\nG1 X1 Q@@\n")
    with pytest.raises(millplan.MillplanError) as e:
        millplan.feed(bad, "box:auto", "al7075")
    assert (e.value.file, e.value.line, e.value.col) == (str(bad), 2, 8)
