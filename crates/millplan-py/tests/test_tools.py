"""millplan.ToolLibrary against `millplan tool`, and optimise with a tool
library against `millplan optimise --tools`."""

import json

import pytest

import millplan
from conftest import assert_like_cli, cli_json, run_cli


@pytest.fixture()
def library(cli, demo, tmp_path):
    """A library with the tool the demo's Fanuc program calls (a 10 mm ball
    with three flutes and 25 mm of flutes) and a flat end mill."""
    number = millplan.read_program(demo / "finish_fanuc.nc").operations[0]["tool"]
    db = tmp_path / "tools.db"
    run_cli(cli, "tool", "--db", db, "add", number, "--name", "ball 10", "--kind", "ball",
            "--l", 100, "--r", 5, "--iso", "APMX=25", "--iso", "ZEFP=3")
    run_cli(cli, "tool", "--db", db, "add", 40, "--name", "flat 8", "--l", 80, "--r", 4)
    # Its first measurement far from the registered length: the library
    # decides setup-mismatch and locks it.
    run_cli(cli, "tool", "--db", db, "measure", 40, "--first", "--l", 79.9, "--r", 3.99, "--json", check=False)
    return db, number


def test_the_library_lists_what_tool_show_lists(cli, library):
    db, number = library
    lib = millplan.ToolLibrary(db)
    assert len(lib) == 2 and number in lib and 41 not in lib
    assert lib.numbers == sorted([number, 40])
    assert_like_cli(lib.tools, cli_json(cli, "tool", "--db", db, "show"))
    assert_like_cli(lib[40], cli_json(cli, "tool", "--db", db, "show", 40)[0])
    assert_like_cli(lib.log(), cli_json(cli, "tool", "--db", db, "log"))
    assert lib.decision(40) == lib.log(40)[-1]["decision"] == "setup-mismatch"
    assert lib[40]["locked"]
    assert lib.decision(number) is None
    assert lib.cutter(number) == {"d": 10.0, "r": 5.0, "flute_length": 25.0}
    with pytest.raises(KeyError):
        lib[41]


def test_a_missing_library_is_an_error_not_an_empty_one(tmp_path):
    with pytest.raises(millplan.MillplanError) as e:
        millplan.ToolLibrary(tmp_path / "none.db")
    assert e.value.file == str(tmp_path / "none.db")


def test_optimise_with_the_library_is_the_commands(cli, demo, library, tmp_path):
    db, _ = library
    opts = dict(stock="offset:0.5", material="al7075", passes="speed,feed", resolution=0.5)
    theirs = tmp_path / "cli.nc"
    r = run_cli(cli, "optimise", demo / "finish_fanuc.nc", "--stl", demo / "part.stl", "--stock",
                opts["stock"], "--material", opts["material"], "--passes", opts["passes"],
                "--resolution", opts["resolution"], "--machine", demo / "machine.toml",
                "--tools", db, "-o", theirs, "--json", check=False)
    _, o = millplan.optimise(demo / "finish_fanuc.nc", part=demo / "part.stl",
                             machine=demo / "machine.toml", library=millplan.ToolLibrary(db), **opts)
    summary = json.loads(r.stdout)
    strip = lambda s: {**s, "passes": [{**p, "seconds": 0} for p in s["passes"]]}
    summary.pop("output", None)
    ours = dict(o.summary)
    ours.pop("output", None)
    assert_like_cli(strip(ours), strip(summary))
    if not o.refused:
        assert o.text.encode() == theirs.read_bytes()


def test_a_tool_the_library_lacks_is_an_error_at_its_call(cli, demo, tmp_path):
    db = tmp_path / "other.db"
    run_cli(cli, "tool", "--db", db, "add", 99, "--name", "x", "--l", 50, "--r", 3)
    with pytest.raises(millplan.MillplanError) as e:
        millplan.optimise(demo / "finish_fanuc.nc", library=db)
    assert e.value.file == str(demo / "finish_fanuc.nc") and e.value.line > 0
