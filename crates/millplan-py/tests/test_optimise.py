"""optimise: the same job as `millplan optimise`, the same bytes and summary."""

import json

import pytest

import millplan
from conftest import assert_like_cli, run_cli

# A quicker job than the tour's (no reorder search, a coarser stock) with
# every kind of input: part, stock, machine, material.
PASSES = "speed,feed"
RESOLUTION = 0.5


def test_optimise_writes_what_the_command_line_writes(cli, demo, tmp_path):
    ours, theirs = tmp_path / "py.nc", tmp_path / "cli.nc"
    part = millplan.read_stl(demo / "part.stl")
    prog, o = millplan.optimise(
        millplan.read_program(demo / "finish.apt"),
        part=part,
        stock="offset:0.5",
        machine=demo / "machine.toml",
        material="al7075",
        passes=PASSES,
        resolution=RESOLUTION,
        output=ours,
    )
    r = run_cli(
        cli, "optimise", demo / "finish.apt", "--stl", demo / "part.stl", "--stock", "offset:0.5",
        "--machine", demo / "machine.toml", "--material", "al7075", "--passes", PASSES,
        "--resolution", RESOLUTION, "-o", theirs, "--json",
    )
    cli_summary = json.loads(r.stdout)
    assert ours.read_bytes() == theirs.read_bytes()
    assert o.text.encode() == theirs.read_bytes()
    assert o.written == str(ours)
    assert o.verdict == cli_summary["verdict"] == "improved"
    assert o.time_after_s < o.time_before_s and o.max_after["fxy"] > 0
    assert [c["name"] for c in o.checks] == [c["name"] for c in cli_summary["checks"]]
    assert all(c["ok"] for c in o.checks) and o.failed_checks == []
    # Seconds per pass differ run to run; the rest of the summary does not.
    strip = lambda s: {**s, "passes": [{**p, "seconds": 0} for p in s["passes"]]}
    assert_like_cli(strip(o.summary), strip(cli_summary))
    assert len(prog) == cli_summary["moves"]
    assert prog.summary(machine=str(demo / "machine.toml"))["time_s"] == pytest.approx(o.time_after_s, rel=1e-9)


def test_optimise_takes_file_names_and_reports_skipped_passes(demo):
    # Passes the three-axis program has nothing for are skipped, saying why.
    prog, o = millplan.optimise(
        str(demo / "finish_fanuc.nc"), tools="ball:10", passes="orient,post"
    )
    assert o.verdict in ("improved", "kept")
    ran = {p["name"]: p["ran"] for p in o.passes}
    assert ran == {"orient": False, "post": False}, o.passes
    assert o.max_before is None and o.written is None
    assert o.dialect == "fanuc" and o.text.startswith("%")
    assert len(prog) > 0
    # A named pass whose input is missing is refused, as --passes is.
    with pytest.raises(millplan.MillplanError, match="names speed, which cannot run: no part"):
        millplan.optimise(str(demo / "finish_fanuc.nc"), tools="ball:10", passes="speed,orient")


def test_optimise_errors_are_located(demo, tmp_path):
    bad = tmp_path / "bad.nc"
    bad.write_text("G21\nG1 X1 Q@@\n")
    with pytest.raises(millplan.MillplanError) as e:
        millplan.optimise(bad)
    assert (e.value.line, e.value.col) == (2, 8)
    with pytest.raises(millplan.MillplanError, match="stock"):
        millplan.optimise(demo / "finish.apt", stock="pyramid:3")
    with pytest.raises(millplan.MillplanError, match="resolution"):
        millplan.optimise(demo / "finish.apt", resolution=-1)
    with pytest.raises(millplan.MillplanError, match="passes"):
        millplan.optimise(demo / "finish.apt", passes="speed,polish")
    with pytest.raises(millplan.MillplanError, match="fxy") as e:
        millplan.optimise(demo / "finish.apt", limits={"fxy": -3})
    assert e.value.file == "limit"
    # The names and ranges of --limit, one set for the command line, feed
    # and optimise: an unknown name is refused, never taken as another.
    for call in (lambda l: millplan.optimise(demo / "finish.apt", limits=l),
                 lambda l: millplan.feed(demo / "finish.apt", "offset:0.5", "al7075",
                                         part=demo / "part.stl", limits=l)):
        with pytest.raises(millplan.MillplanError, match="flexion: not a load limit") as e:
            call({"flexion": 0.01})
        assert e.value.file == "limit"
        with pytest.raises(millplan.MillplanError, match="fxy"):
            call({"fxy": 2e9})
