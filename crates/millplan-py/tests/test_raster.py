"""millplan.raster against `millplan raster` on the demo's part."""

import json

import pytest

import millplan
from conftest import assert_like_cli, run_cli


@pytest.mark.parametrize("dialect,opts", [
    ("apt", dict(stepover=2.0, step=1.0)),
    ("fanuc", dict(stepover=1.5, step=0.8, angle=30.0, oneway=True)),
])
def test_raster_writes_what_the_command_writes(cli, demo, tmp_path, dialect, opts):
    flags = ["--tool", "ball:10", "--stepover", opts["stepover"], "--step", opts["step"]]
    if "angle" in opts:
        flags += ["--angle", opts["angle"]]
    if opts.get("oneway"):
        flags += ["--oneway"]
    if "tol" in opts:
        flags += ["--tol", opts["tol"]]
    theirs = tmp_path / f"cli.{millplan.dialect_extension(dialect)}"
    r = run_cli(cli, "raster", "--stl", demo / "part.stl", *flags, "--to", dialect, "-o", theirs, "--json", "-q")
    prog, report = millplan.raster(demo / "part.stl", "ball:10", dialect=dialect, **opts)
    ours = tmp_path / f"py.{millplan.dialect_extension(dialect)}"
    millplan.write_program(prog, ours, dialect)
    assert ours.read_bytes() == theirs.read_bytes()
    cli_report = json.loads(r.stdout)
    cli_report.pop("output")
    assert_like_cli(report, cli_report)
    assert report["gouge_check"]["gouges"] == 0 and all(c["ok"] for c in report["checks"])


def test_raster_refuses_a_stepover_under_a_thousandth_of_the_tool(demo):
    with pytest.raises(millplan.MillplanError) as e:
        millplan.raster(demo / "part.stl", "ball:10", stepover=0.001, step=1)
    assert e.value.file == "stepover"


def test_raster_refuses_what_the_command_refuses_unless_forced(cli, demo, tmp_path):
    """Without refinement (tol 0) the chords between drop points cut into
    the part: the gouge check refuses the program, as the command does."""
    opts = dict(stepover=1.5, step=0.8, tol=0.0)
    r = run_cli(cli, "raster", "--stl", demo / "part.stl", "--tool", "ball:10", "--stepover", 1.5,
                "--step", 0.8, "--tol", 0, "-o", tmp_path / "cli.apt", "-q", check=False)
    assert r.returncode == 3 and not (tmp_path / "cli.apt").exists()
    with pytest.raises(millplan.MillplanError, match="gouge"):
        millplan.raster(demo / "part.stl", "ball:10", **opts)
    prog, report = millplan.raster(demo / "part.stl", "ball:10", force=True, **opts)
    assert len(prog) > 0 and report["gouge_check"]["gouges"] > 0
    assert [c["name"] for c in report["checks"] if not c["ok"]] == ["gouge"]
