"""millplan.post against `millplan post` on a five-axis CL program and the
example machine (a tilting A table carrying a C table)."""

import json
import math

import pytest

import millplan
from conftest import ROOT, assert_like_cli, run_cli

MACHINE = ROOT / "examples" / "machine.toml"


@pytest.fixture(scope="module")
def cl(tmp_path_factory):
    """A five-axis sweep: the tool axis turns about Y and Z along a wavy line."""
    p = tmp_path_factory.mktemp("post") / "sweep.apt"
    lines = ["PARTNO SWEEP", "UNITS/MM", "CUTTER/10,5,0,5,0,0,0", "LOADTL/1",
             "SPINDL/8000,RPM,CLW", "RAPID", "GOTO/0,0,-60,0,0,1", "FEDRAT/1200,MMPM"]
    for k in range(61):
        t = k / 60
        a, c = math.radians(-25 * t), math.radians(90 * t)
        i, j, kk = math.sin(a) * math.cos(c), math.sin(a) * math.sin(c), math.cos(a)
        lines.append(f"GOTO/{40 * t:.4f},{10 * math.sin(6 * t):.4f},{-100 + 2 * t:.4f},"
                     f"{i:.7f},{j:.7f},{kk:.7f}")
    lines += ["RAPID", "GOTO/40,0,-60,0,0,1", "FINI"]
    p.write_text("\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize("flags", [[], ["--g93"], ["--tcp", "--to", "heidenhain"]])
def test_post_is_the_commands(cli, cl, tmp_path, flags):
    out = tmp_path / "cli.nc"
    r = run_cli(cli, "post", cl, "--machine", MACHINE, *flags, "-o", out, "--json", "-q", check=False)
    assert r.returncode == 0, r.stderr
    kw = dict(tcp="--tcp" in flags, g93="--g93" in flags,
              dialect="heidenhain" if "--to" in flags else None)
    prog, text, summary = millplan.post(cl, MACHINE, output=out, **kw)
    assert text == out.read_text()
    assert_like_cli(summary, json.loads(r.stdout))
    assert summary["blocks"] > 60 and len(prog.xyz) >= 61


def test_post_without_kinematics_is_refused(cl, demo):
    with pytest.raises(millplan.MillplanError, match="kinematics") as e:
        millplan.post(cl, demo / "machine.toml", dialect="fanuc")
    assert e.value.file == str(demo / "machine.toml")


def test_post_writes_g_code_only(cl):
    with pytest.raises(millplan.MillplanError, match="G-code") as e:
        millplan.post(cl, MACHINE, dialect="apt")
    assert e.value.file == "dialect"


def test_post_beyond_the_tilt_stops_at_the_cl_line(cli, tmp_path):
    p = tmp_path / "steep.apt"
    p.write_text("UNITS/MM\nFEDRAT/1000,MMPM\nSPINDL/8000,RPM,CLW\nGOTO/0,0,-100,0,0,1\n"
                 "GOTO/10,0,-100,0.0,0.5,-0.8660254\nFINI\n")
    r = run_cli(cli, "post", p, "--machine", MACHINE, "-o", tmp_path / "o.nc", check=False)
    assert r.returncode == 3, r.stderr
    with pytest.raises(millplan.MillplanError) as e:
        millplan.post(p, MACHINE, output=tmp_path / "py.nc")
    assert e.value.file == str(p) and e.value.line == 5
    assert not (tmp_path / "py.nc").exists()
