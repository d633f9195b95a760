"""working_diameter: the spec's oracle, broadcasting, the vectorised call
against the scalar one and the command line, errors per element."""

import numpy as np
import pytest

import millplan
from conftest import cli_json


def test_oracle_of_the_spec():
    # working-diameter.md §2.3: D 10, ap 0.3, ae 0.25, α 20°, A_f 45°, left → 4.1301 mm.
    dw = millplan.working_diameter(10, 0.3, 0.25, 20, 45, "left")
    assert isinstance(dw, float)
    assert dw == pytest.approx(4.1301, abs=1e-4)


def test_vectorised_equals_scalar_calls_element_by_element():
    rng = np.random.default_rng(7)
    n = 2000
    d = rng.choice([6.0, 8.0, 10.0, 12.0], n)
    ap = rng.uniform(0.05, 0.5, n) * d / 2
    ae = rng.uniform(0.05, 2.0, n)
    alpha = rng.uniform(0, 89.9, n)
    af = rng.uniform(-360, 360, n)
    side = rng.choice(["left", "right"], n)
    v = millplan.working_diameter(d, ap, ae, alpha, af, side)
    assert v.shape == (n,)
    s = [millplan.working_diameter(*args) for args in zip(d, ap, ae, alpha, af, side)]
    np.testing.assert_array_equal(v, np.array(s))
    # Without a neighbour: ae None, or inf per element.
    v0 = millplan.working_diameter(d, ap, None, alpha, af, side)
    vi = millplan.working_diameter(d, ap, np.full(n, np.inf), alpha, af, side)
    np.testing.assert_array_equal(v0, vi)
    assert (v0 >= v - 1e-12).all(), "a machined neighbour never raises D_w"


def test_broadcasting_over_any_argument():
    alpha = np.linspace(0, 80, 9)[:, None]
    af = np.linspace(-180, 180, 13)[None, :]
    v = millplan.working_diameter(10, 0.3, None, alpha, af, "right")
    assert v.shape == (9, 13)
    for i in (0, 4, 8):
        for j in (0, 6, 12):
            assert v[i, j] == millplan.working_diameter(
                10, 0.3, None, float(alpha[i, 0]), float(af[0, j]), "right"
            )
    sides = np.array(["left", "right"])[:, None, None]
    w = millplan.working_diameter(10, 0.3, 0.5, alpha, af, sides)
    assert w.shape == (2, 9, 13)
    # Flat surface: left and right are mirror images.
    np.testing.assert_allclose(w[0, 0], w[1, 0])


def test_agrees_with_the_command_line(cli):
    cases = [(10, 0.3, 0.25, 20, 45, "left"), (8, 0.2, None, 35, -120, "right"), (12, 0.5, 1.0, 60, 170, "right")]
    for d, ap, ae, alpha, af, side in cases:
        args = ["wd", "--d", d, "--ap", ap, "--alpha", alpha, "--af", af, "--side", side]
        if ae is not None:
            args += ["--ae", ae]
        j = cli_json(cli, *args)
        assert millplan.working_diameter(d, ap, ae, alpha, af, side) == pytest.approx(j["d_w"], abs=5e-4)  # JSON rounds to 3 decimals


def test_an_element_outside_the_domain_is_named():
    with pytest.raises(millplan.MillplanError) as e:
        millplan.working_diameter(10, [0.3, 0.3, 6.0], None, 10, 0, "left")
    assert "element 2" in str(e.value) and "ap" in str(e.value)
    assert isinstance(e.value, ValueError)
    with pytest.raises(millplan.MillplanError, match="alpha"):
        millplan.working_diameter(10, 0.3, None, 95, 0, "left")
    with pytest.raises(millplan.MillplanError, match="side"):
        millplan.working_diameter(10, 0.3, None, 10, 0, "up")
    with pytest.raises(ValueError):
        millplan.working_diameter(np.ones(3) * 10, 0.3, None, np.ones(4), 0)
