"""millplan.force against `millplan force PATH` on the demo's raster, and
millplan.cut against `millplan cut`."""

import csv
import json

import numpy as np
import pytest

import millplan
from conftest import assert_like_cli, run_cli


@pytest.fixture(scope="module")
def forces(cli, demo, tmp_path_factory):
    d = tmp_path_factory.mktemp("force")
    r = run_cli(cli, "force", demo / "finish.apt", "--stock", "offset:0.5", "--stl", demo / "part.stl",
                "--material", "al7075", "--resolution", 0.5, "--machine", demo / "machine.toml",
                "--table", d / "moves.csv", "--json", "-q", check=False)
    assert r.returncode in (0, 3), r.stderr
    with open(d / "moves.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    ours = millplan.force(demo / "finish.apt", "offset:0.5", "al7075", part=demo / "part.stl",
                          machine=demo / "machine.toml", resolution=0.5, pandas=False)
    return json.loads(r.stdout), rows, ours


def test_force_summary_is_the_commands(forces):
    theirs, _, (_, summary) = forces
    assert_like_cli(summary, {k: theirs[k] for k in summary})
    assert summary["max"]["fxy"] > 0


def test_force_per_move_is_the_commands_table(forces):
    _, rows, (moves, summary) = forces
    assert len(rows) > 100 and all(len(a) == len(rows) for a in moves.values())
    assert list(moves["line"]) == [int(r["line"]) for r in rows]
    for name, tol in [("t_s", 5e-5), ("rpm", 0.05), ("feed", 5e-3), ("fz", 5e-6),
                      ("removed_mm3", 5e-6), ("fxy_max", 5e-4), ("fx_min", 5e-4), ("fz_max", 5e-4),
                      ("torque_max", 5e-4), ("power_w", 5e-4), ("deflection_mm", 5e-7)]:
        theirs = np.array([float(r[name]) for r in rows])
        np.testing.assert_allclose(moves[name], theirs, atol=tol * 1.001, err_msg=name)
    assert list(moves["air"]) == [r["air"] == "true" for r in rows]
    assert moves["fxy_max"].max() == pytest.approx(summary["max"]["fxy"], rel=1e-12)


def test_force_needs_a_known_material(demo):
    with pytest.raises(millplan.MillplanError, match="unobtainium"):
        millplan.force(demo / "finish.apt", "offset:0.5", "unobtainium", part=demo / "part.stl")


@pytest.mark.parametrize("args", [
    dict(tool="ball:10", fz=0.1, ap=0.5, ae=0.5, n=10000, material="al7075"),
    dict(tool="ball:10", fz=0.05, ap=0.4, ae=0.6, n=8000, material="al7075", lead=10.0, tilt=-5.0),
    dict(tool="flat:8", fz=0.05, ap=4.0, ae=None, n=8000, material="al7075"),
    dict(tool="bull:10:2", fz=0.08, ap=1.0, ae=3.0, n=9000, coeffs="800,300,150,20,25,3"),
])
def test_cut_gives_what_the_command_prints(cli, tmp_path, args):
    flags = ["--tool", args["tool"], "--fz", args["fz"], "--ap", args["ap"], "--n", args["n"]]
    flags += ["--slot"] if args["ae"] is None else ["--ae", args["ae"]]
    for k in ("material", "coeffs", "lead", "tilt"):
        if k in args:
            flags += [f"--{k}", args[k]]
    r = run_cli(cli, "cut", *flags, "--csv", tmp_path / "c.csv", "--json")
    figures, curves = millplan.cut(**args, pandas=False)
    assert_like_cli(figures, json.loads(r.stdout))
    with open(tmp_path / "c.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for name, tol in [("phi_deg", 5e-4), ("fx", 5e-5), ("fy", 5e-5), ("fz", 5e-5), ("torque", 5e-5)]:
        np.testing.assert_allclose(curves[name], [float(x[name]) for x in rows], atol=tol * 1.001)
    assert np.hypot(curves["fx"], curves["fy"]).max() == pytest.approx(figures["fxy_max"], rel=1e-9)


def test_cut_without_a_material_is_refused():
    with pytest.raises(millplan.MillplanError, match="material"):
        millplan.cut("ball:10", 0.1, 0.5, 10000, ae=0.5)
