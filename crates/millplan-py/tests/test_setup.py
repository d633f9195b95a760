"""millplan.setup against `millplan setup` on the demo's part."""

import json

import numpy as np
import pytest

import millplan
from conftest import assert_like_cli, run_cli


@pytest.mark.parametrize("args", [
    dict(kind="ca", range1="0,95"),
    dict(kind="ab", range1="-30,30", range2="-30,30", tool="6,40", clearance=5.0, cells=320),
    dict(kind="ca", range1="-10,60", grid="icosphere", cells=320, ignore_bottom=True),
])
def test_setup_is_the_commands(cli, demo, tmp_path, args):
    flags = []
    for k, v in args.items():
        flag = "--type" if k == "kind" else "--" + k.replace("_", "-")
        flags += [flag] if v is True else [flag, v]
    r = run_cli(cli, "setup", "--stl", demo / "part.stl", *flags, "-o", tmp_path / "cli.stl",
                "--json", "-q", check=False)
    assert r.returncode in (0, 3), r.stderr
    theirs = json.loads(r.stdout)
    report, rotated = millplan.setup(demo / "part.stl", **args)
    assert report.pop("seconds") > 0
    theirs.pop("seconds")
    assert_like_cli(report, theirs)
    assert report["feasible"] == (r.returncode == 0)
    cli_mesh = millplan.read_stl(tmp_path / "cli.stl")
    np.testing.assert_allclose(rotated.vertices, cli_mesh.vertices, atol=1e-4)


def test_setup_with_a_machine_file_without_kinematics_is_refused(demo):
    with pytest.raises(millplan.MillplanError, match="kinematics") as e:
        millplan.setup(demo / "part.stl", machine=demo / "machine.toml")
    assert e.value.file == str(demo / "machine.toml")


def test_setup_refuses_bad_ranges_and_kinds(demo):
    with pytest.raises(millplan.MillplanError, match="range1") as e:
        millplan.setup(demo / "part.stl", kind="ca", range1="60,0")
    assert e.value.file == "range1"
    with pytest.raises(millplan.MillplanError, match="ca or ab"):
        millplan.setup(demo / "part.stl", kind="xy")
