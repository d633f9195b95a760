"""Programs and parts through the package, compared with the command line
on the demo's files."""

import numpy as np
import pytest

import millplan
from conftest import assert_like_cli, cli_json, run_cli

PROGRAMS = ["finish.apt", "finish_fanuc.nc", "finish_sinumerik.mpf", "finish_heidenhain.h", "finish_linuxcnc.ngc"]


@pytest.mark.parametrize("name", PROGRAMS + ["part.stl"])
def test_inspect_gives_what_the_command_line_prints(cli, demo, name):
    assert_like_cli(millplan.inspect(demo / name), cli_json(cli, "inspect", demo / name))


def test_inspect_on_a_machine(cli, demo):
    m = demo / "machine.toml"
    got = millplan.inspect(demo / "finish.apt", machine=m)
    assert_like_cli(got, cli_json(cli, "inspect", demo / "finish.apt", "--machine", m))
    assert got["time_s"] > 0


def test_moves_as_arrays(cli, demo):
    p = millplan.read_program(demo / "finish.apt")
    s = millplan.inspect(demo / "finish.apt")
    n = s["moves"]["total"]
    assert len(p) == n
    assert p.xyz.shape == (n, 3) and p.axis.shape == (n, 3)
    for a in (p.feed, p.spindle, p.kind, p.line, p.operation):
        assert a.shape == (n,)
    counts = np.bincount(p.kind, minlength=4)
    assert list(counts) == [s["moves"][k] for k in p.KINDS]
    known = ~np.isnan(p.xyz).any(axis=1)
    lo, hi = p.xyz[known].min(axis=0), p.xyz[known].max(axis=0)
    np.testing.assert_allclose(lo, s["bounds"]["min"], atol=1e-9)
    np.testing.assert_allclose(hi, s["bounds"]["max"], atol=1e-9)
    assert (np.diff(p.line[p.line > 0].astype(np.int64)) > 0).all(), "source lines in order"
    assert p.summary() == s
    assert len(p.operations) == s["operations"]
    assert p.tools == s["tools"]


@pytest.mark.parametrize("dialect", ["fanuc", "sinumerik", "heidenhain", "linuxcnc", "apt"])
def test_write_program_writes_what_convert_writes(cli, demo, tmp_path, dialect):
    p = millplan.read_program(demo / "finish.apt")
    ours, theirs = tmp_path / f"py.{dialect}", tmp_path / f"cli.{dialect}"
    assert millplan.write_program(p, ours, dialect) == dialect
    run_cli(cli, "convert", demo / "finish.apt", "--to", dialect, "-o", theirs, "-q")
    assert ours.read_bytes() == theirs.read_bytes()
    back = millplan.read_program(ours)
    np.testing.assert_allclose(back.xyz, p.xyz, atol=1e-3)


def test_errors_carry_file_line_and_column(cli, tmp_path):
    bad = tmp_path / "bad.nc"
    bad.write_text("G21\nG1 X1 Q@@\n")
    with pytest.raises(millplan.MillplanError) as e:
        millplan.read_program(bad)
    assert (e.value.file, e.value.line, e.value.col) == (str(bad), 2, 8)
    r = run_cli(cli, "inspect", bad, check=False)
    assert r.returncode == 2
    assert f"{bad}:2:8:" in r.stderr and str(e.value).startswith(f"{bad}:2:8:")
    with pytest.raises(millplan.MillplanError) as e:
        millplan.read_program(tmp_path / "missing.nc")
    assert e.value.line is None and "cannot read" in e.value.message
    stl = tmp_path / "bad.stl"
    stl.write_text("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 zz\n")
    with pytest.raises(millplan.MillplanError) as e:
        millplan.read_stl(stl)
    assert e.value.line == 4
    good = tmp_path / "good.nc"
    good.write_text("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n")
    with pytest.raises(millplan.MillplanError, match="dialect"):
        millplan.write_program(millplan.read_program(good), tmp_path / "o.nc", "klingon")


def test_mesh_arrays_match_inspect(demo):
    m = millplan.read_stl(demo / "part.stl")
    s = millplan.inspect(demo / "part.stl")
    assert m.vertices.shape == (s["vertices"], 3)
    assert m.faces.shape == (s["triangles"], 3) and len(m) == s["triangles"]
    np.testing.assert_allclose(m.vertices.min(axis=0), s["bounds"]["min"])
    assert m.faces.max() < len(m.vertices)


def _brute_closest(v, f, p):
    """Closest point on each triangle by projection and edge clamping (numpy, slow)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    # Sample each triangle densely enough for a 1e-3 check on a smooth part.
    n = 12
    us, ws = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    keep = us + ws <= 1 + 1e-12
    us, ws = us[keep], ws[keep]
    pts = a[:, None, :] + us[None, :, None] * (b - a)[:, None, :] + ws[None, :, None] * (c - a)[:, None, :]
    d = np.linalg.norm(pts - p, axis=2)
    return d.min()


def test_closest_points_against_sampled_triangles(demo):
    m = millplan.read_stl(demo / "part.stl")
    v, f = m.vertices, m.faces
    rng = np.random.default_rng(3)
    lo, hi = v.min(axis=0), v.max(axis=0)
    q = rng.uniform(lo, hi + [0, 0, 5], size=(40, 3))
    pts, dist, tri = m.closest_points(q)
    assert pts.shape == (40, 3) and dist.shape == (40,) and tri.shape == (40,)
    np.testing.assert_allclose(np.linalg.norm(pts - q, axis=1), dist, atol=1e-9)
    assert (tri >= 0).all()
    for i in range(0, 40, 4):
        sampled = _brute_closest(v, f, q[i])
        assert dist[i] <= sampled + 1e-9
        assert dist[i] >= sampled - 0.05, "the samples lie within 0.05 mm of the exact closest point"
    # Bounded: nothing beyond max_distance.
    _, d2, t2 = m.closest_points(q, max_distance=0.5)
    assert ((t2 == -1) == (dist > 0.5)).all()
    assert np.isinf(d2[t2 == -1]).all()
    # Lists and float32 are converted.
    np.testing.assert_array_equal(m.closest_points(q.astype(np.float32).tolist())[2].shape, (40,))
    with pytest.raises(millplan.MillplanError, match="shape"):
        m.closest_points(np.zeros((3, 2)))


def test_drop_cutter_touches_the_surface(demo):
    """A ball dropped at (x, y) stands with its centre one radius from the surface."""
    m = millplan.read_stl(demo / "part.stl")
    lo, hi = m.vertices.min(axis=0), m.vertices.max(axis=0)
    rng = np.random.default_rng(5)
    xy = rng.uniform(lo[:2] + 6, hi[:2] - 6, size=(500, 2))
    z = m.drop_cutter("ball:10", xy)
    assert z.shape == (500,) and np.isfinite(z).all()
    centres = np.column_stack([xy, z + 5.0])
    _, d, _ = m.closest_points(centres)
    np.testing.assert_allclose(d, 5.0, atol=1e-6)
    far = m.drop_cutter("flat:6", [[lo[0] - 100, lo[1] - 100]])
    assert np.isnan(far).all()
    with pytest.raises(millplan.MillplanError):
        m.drop_cutter("spoon:3", xy)
