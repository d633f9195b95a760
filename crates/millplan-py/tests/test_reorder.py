"""millplan.reorder against `millplan reorder` on the demo's raster."""

import json

import pytest

import millplan
from conftest import assert_like_cli, run_cli


@pytest.mark.parametrize("method,speed", [("paper", False), ("as-run", True)])
def test_reorder_writes_what_the_command_writes(cli, demo, tmp_path, method, speed):
    theirs = tmp_path / "cli.apt"
    flags = ["--method", method] + ([] if speed else ["--no-speed"])
    r = run_cli(cli, "reorder", demo / "finish.apt", "--stl", demo / "part.stl", *flags,
                "-o", theirs, "--json", "-q", check=False)
    assert r.returncode in (0, 3), r.stderr
    prog, summary = millplan.reorder(demo / "finish.apt", millplan.read_stl(demo / "part.stl"),
                                     method, speed=speed)
    ours = tmp_path / "py.apt"
    millplan.write_program(prog, ours)
    assert ours.read_bytes() == theirs.read_bytes()
    cli_summary = json.loads(r.stdout)
    cli_summary.pop("output")
    assert_like_cli(summary, cli_summary)
    assert summary["method"] == method


def test_reorder_names_a_bad_method(demo):
    with pytest.raises(millplan.MillplanError) as e:
        millplan.reorder(demo / "finish.apt", demo / "part.stl", "fastest")
    assert e.value.file == "method"
