"""Shared fixtures: the millplan command line (the reference the package is
compared with) and the demo's inputs it generates."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


def _target_dir() -> pathlib.Path:
    return pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))


@pytest.fixture(scope="session")
def cli() -> str:
    """The millplan binary: $MILLPLAN_BIN, else target/debug/millplan, built
    with cargo when missing."""
    given = os.environ.get("MILLPLAN_BIN")
    if given:
        return given
    exe = _target_dir() / "debug" / "millplan"
    if not exe.exists():
        subprocess.run(["cargo", "build", "-p", "millplan"], cwd=ROOT, check=True)
    return str(exe)


def run_cli(cli: str, *args, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(
        [cli, *map(str, args)], capture_output=True, text=True, check=check
    )


def cli_json(cli: str, *args):
    return json.loads(run_cli(cli, *args, "--json").stdout)


@pytest.fixture(scope="session")
def demo(cli, tmp_path_factory) -> pathlib.Path:
    """The folder `millplan demo` writes: part.stl, finish.apt, the raster in
    each dialect, machine.toml."""
    d = tmp_path_factory.mktemp("demo")
    run_cli(cli, "demo", "-o", d, "-q")
    return d


def assert_like_cli(ours, cli, path="$"):
    """`ours` (full precision) equals the command line's JSON, which rounds
    lengths to 3 decimals, spindle speeds to 0.1 1/min and other numbers to
    6 significant digits: the
    same keys and values, each number within that rounding."""
    if isinstance(cli, dict):
        assert isinstance(ours, dict) and set(ours) == set(cli), (path, set(ours) ^ set(cli))
        for k in cli:
            assert_like_cli(ours[k], cli[k], f"{path}.{k}")
    elif isinstance(cli, list):
        assert isinstance(ours, list) and len(ours) == len(cli), path
        for i, (a, b) in enumerate(zip(ours, cli)):
            assert_like_cli(a, b, f"{path}[{i}]")
    elif isinstance(cli, float) or (isinstance(ours, float) and isinstance(cli, int)):
        # Spindle speeds are printed to 0.1 1/min.
        speed = "spindle" in path or "delta_n" in path or path.endswith("_n")
        tol = 0.05 if speed else 5e-4
        assert abs(ours - cli) <= tol + 5e-6 * abs(cli), (path, ours, cli)
    else:
        assert ours == cli, (path, ours, cli)
