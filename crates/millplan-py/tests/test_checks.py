"""millplan.gouge and millplan.simulate against `millplan gouge` and
`millplan simulate` on the demo's raster and part."""

import csv
import json

import numpy as np
import pytest

import millplan
from conftest import assert_like_cli, run_cli


def test_gouge_reports_what_the_command_prints(cli, demo):
    r = run_cli(cli, "gouge", demo / "finish.apt", "--stl", demo / "part.stl", "--step", 0.5,
                "--json", "-q", check=False)
    assert r.returncode in (0, 3), r.stderr
    ours = millplan.gouge(demo / "finish.apt", millplan.read_stl(demo / "part.stl"), step=0.5)
    assert_like_cli(ours, json.loads(r.stdout))
    assert ours["moves_checked"] > 0 and ours["points_checked"] > ours["moves_checked"]


def test_gouge_finds_a_move_pushed_into_the_part(cli, demo, tmp_path):
    """The raster's first cutting move 1 mm lower: a gouge there, by both."""
    lines = (demo / "finish.apt").read_text().splitlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("GOTO") and k > 0 and "FEDRAT" in lines[k - 1])
    x, y, z = (float(v) for v in lines[i].split("/")[1].split(",")[:3])
    lines[i] = f"GOTO/{x:.4f},{y:.4f},{z - 1:.4f}"
    bad = tmp_path / "gouged.apt"
    bad.write_text("\n".join(lines) + "\n")
    r = run_cli(cli, "gouge", bad, "--stl", demo / "part.stl", "--json", "-q", check=False)
    ours = millplan.gouge(bad, demo / "part.stl")
    assert_like_cli(ours, json.loads(r.stdout))
    assert not ours["clean"] and ours["max_depth"] > 0.5
    assert any(g["line"] == i + 1 for g in ours["gouges"])


def test_gouge_option_errors_name_the_argument(demo):
    with pytest.raises(millplan.MillplanError) as e:
        millplan.gouge(demo / "finish.apt", demo / "part.stl", step=0)
    assert e.value.file == "step" and "step" in str(e.value)


@pytest.fixture(scope="module")
def simulated(cli, demo, tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    args = ["--stock", "offset:0.5", "--resolution", 0.5]
    r = run_cli(cli, "simulate", demo / "finish.apt", "--stl", demo / "part.stl", *args,
                "--table", d / "moves.csv", "-o", d / "cli.stl", "--json", "-q", check=False)
    assert r.returncode in (0, 3), r.stderr
    with open(d / "moves.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    ours = millplan.simulate(demo / "finish.apt", "offset:0.5", part=demo / "part.stl",
                             resolution=0.5, output=d / "py.stl", pandas=False)
    return json.loads(r.stdout), rows, ours, d


def test_simulate_reports_what_the_command_prints(simulated):
    theirs, _, (_, report), d = simulated
    assert_like_cli(report, theirs)
    assert report["removed_mm3"] > 0
    assert (d / "py.stl").read_bytes() == (d / "cli.stl").read_bytes()


def test_simulate_moves_are_the_commands_table(simulated):
    _, rows, (moves, report), _ = simulated
    assert len(rows) > 100 and all(len(a) == len(rows) for a in moves.values())
    assert list(moves["index"]) == [int(r["index"]) for r in rows]
    assert list(moves["line"]) == [int(r["line"]) for r in rows]
    for name, tol in [("removed_mm3", 5e-4), ("mrr", 0.05), ("ap", 5e-4), ("ae", 5e-4),
                      ("holder_depth", 5e-4), ("minutes", 5e-7)]:
        theirs = np.array([float(r[name]) for r in rows])
        np.testing.assert_allclose(moves[name], theirs, atol=tol * 1.001, err_msg=name)
    assert list(moves["air"]) == [r["air"] == "1" for r in rows]
    # The per-move volumes add up to the whole removal.
    assert moves["removed_mm3"].sum() == pytest.approx(report["removed_mm3"], rel=1e-9)
