//! Issue 34, "Hostile inputs, round two", the findings left after the first
//! round: each is its smallest repro through the real binary, with the exit
//! code and the message it must give, and the inputs left as they were.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A slot 1 mm deep in a 20 mm box, a ball of 10 mm at 6000 1/min.
const SLOT: &str = "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nSPINDL/6000,CLW\nGOTO/0,0,50\nGOTO/0,0,19\nGOTO/60,0,19\nGOTO/60,20,19\nGOTO/0,20,19\nGOTO/0,20,50\nFINI\n";
const BOX: &str = "box:-10,-10,0,70,30,20";
const MATERIAL: &str = "[c45]\nmodel = \"linear\"\nkc = [2100, 800, 500]\nke = [30, 40, 0]\n";
const MACHINE: &str = "[spindle]\nmin = 500\nmax = 18000\naccel = 6000\n[feed]\nmax = 20000\n";

struct Bench {
    dir: tempfile::TempDir,
}

impl Bench {
    fn new() -> Bench {
        let b = Bench {
            dir: tempfile::tempdir().expect("tmp"),
        };
        b.write("slot.apt", SLOT);
        b.write("m.toml", MATERIAL);
        b.write("machine.toml", MACHINE);
        b
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.path(name);
        std::fs::write(&p, text).expect("write");
        p
    }

    fn run(&self, args: &[&str]) -> Output {
        bin()
            .current_dir(self.dir.path())
            .args(args)
            .stdin(Stdio::null())
            .output()
            .expect("millplan runs")
    }

    /// A shell line in the folder, `$M` the binary.
    fn sh(&self, line: &str) -> Output {
        Command::new("sh")
            .current_dir(self.dir.path())
            .env("M", env!("CARGO_BIN_EXE_millplan"))
            .args(["-c", line])
            .stdin(Stdio::null())
            .output()
            .expect("sh runs")
    }

    /// `args` must exit 2 with `needle` in its message, no panic.
    fn refused(&self, args: &[&str], needle: &str) -> String {
        let o = self.run(args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains(needle), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
        e
    }
}

/// Issue 34: "`--resolution 0.005` on a 100 mm stock (3,400 MB estimated)
/// passes the default memory limit (half the RAM) and aborts under a 4 GB
/// address-space limit". The default limit is half of the address space.
#[test]
fn a_stock_over_the_address_space_is_refused_not_aborted() {
    let b = Bench::new();
    let o = b.sh("ulimit -v 4000000 && exec \"$M\" simulate slot.apt --stock box:0,0,0,100,100,20 --resolution 0.005 -q");
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("over the memory limit of 2048"), "{e}");
}

/// Issue 34's fuzz campaign of 27 Nov 2026: `feed` with a 2 m cutter in an
/// auto cylinder held 13.2 GB where its stock's estimate said 7.1 GB, since
/// a force run keeps the stock before the program beside the copy it cuts.
/// The estimate counts both, so the refusal comes before the allocation;
/// `simulate`, which cuts its only copy, is not refused for them.
#[test]
fn a_stock_held_twice_is_estimated_twice() {
    let b = Bench::new();
    let res = ["--resolution", "0.1", "--limit", "memory=4"];
    let sim = [&["simulate", "slot.apt", "--stock", BOX, "-q"][..], &res].concat();
    let o = b.run(&sim);
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    let model = ["--stock", BOX, "--material", "c45", "--materials", "m.toml"];
    let feed = [
        &["feed", "slot.apt", "-o", "out.apt", "-q"][..],
        &model,
        &res,
    ]
    .concat();
    b.refused(
        &feed,
        "held twice (the stock before the program and the copy a run cuts)",
    );
    let force = [&["force", "slot.apt", "-q"][..], &model, &res].concat();
    b.refused(&force, "held twice");
}

/// Issue 34: "`--materials FILE` is not treated as an input: `-o`, `--csv`,
/// `--svg`, `--report`, `--table` of `cut`, `force`, `feed`, `orient`
/// replace it" and "`simulate --machine M --report M` (also `--table M`,
/// `-o M`) replaces the machine file". A stock's STL is an input too.
#[test]
fn every_file_read_is_an_input_no_output_replaces() {
    let b = Bench::new();
    let cut = [
        "cut",
        "--tool",
        "ball:10",
        "--fz",
        ".1",
        "--ap",
        "1",
        "--ae",
        "2",
        "--n",
        "6000",
        "--material",
        "c45",
        "--materials",
        "m.toml",
    ];
    let model = ["--stock", BOX, "--material", "c45", "--materials", "m.toml"];
    let cases: Vec<Vec<&str>> = vec![
        [&cut[..], &["--csv", "m.toml"]].concat(),
        [&cut[..], &["--svg", "m.toml"]].concat(),
        [&["force", "slot.apt"][..], &model, &["--table", "m.toml"]].concat(),
        [&["force", "slot.apt"][..], &model, &["--report", "m.toml"]].concat(),
        [&["feed", "slot.apt"][..], &model, &["-o", "m.toml"]].concat(),
        [
            &["feed", "slot.apt"][..],
            &model,
            &["-o", "f.apt", "--table", "m.toml"],
        ]
        .concat(),
        vec![
            "simulate",
            "slot.apt",
            "--stock",
            BOX,
            "--machine",
            "machine.toml",
            "--report",
            "machine.toml",
        ],
        vec![
            "simulate",
            "slot.apt",
            "--stock",
            BOX,
            "--machine",
            "machine.toml",
            "--table",
            "machine.toml",
        ],
        vec![
            "simulate",
            "slot.apt",
            "--stock",
            BOX,
            "--machine",
            "machine.toml",
            "-o",
            "machine.toml",
        ],
    ];
    for args in &cases {
        b.refused(args, "refusing to overwrite an input file");
    }
    assert_eq!(
        std::fs::read_to_string(b.path("m.toml")).expect("m"),
        MATERIAL
    );
    assert_eq!(
        std::fs::read_to_string(b.path("machine.toml")).expect("m"),
        MACHINE
    );
    // A stock written by `simulate -o` is read back as a stock, and is an
    // input of the run that reads it.
    let o = b.run(&[
        "simulate",
        "slot.apt",
        "--stock",
        BOX,
        "-o",
        "stock.stl",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let stl = std::fs::read(b.path("stock.stl")).expect("stock");
    let o = b.run(&["simulate", "slot.apt", "--stock", "stl:stock.stl", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    b.refused(
        &[
            "force",
            "slot.apt",
            "--stock",
            "stl:stock.stl",
            "--material",
            "al7075",
            "--table",
            "stock.stl",
        ],
        "refusing to overwrite an input file",
    );
    assert_eq!(std::fs::read(b.path("stock.stl")).expect("stock"), stl);
}

/// Issue 34: "an oblique material with `rc_c0=[0,0]` gives 'NaN N·mm',
/// 'NaN W'" and "`cut --modulus 1e-308` prints 'deflection inf µm'".
/// Refused where they are given: the materials file's line, the option.
#[test]
fn values_that_make_nan_or_inf_are_refused_where_given() {
    let b = Bench::new();
    b.write(
        "ob.toml",
        "[ob]\nmodel = \"oblique\"\ntau_s = 300.0\nbeta_a = [20.0, 0.3]\nrc_c0 = [0, 0]\nrc_a = [0.2, 0.0]\nke = [24.0, 43.0, 0.0]\n",
    );
    let cut = [
        "cut", "--tool", "ball:10", "--fz", ".1", "--ap", "1", "--ae", "2", "--n", "6000",
    ];
    let e = b.refused(
        &[&cut[..], &["--material", "ob", "--materials", "ob.toml"]].concat(),
        "ob.toml:5: material `ob`: `rc_c0`",
    );
    assert!(!e.to_lowercase().contains("nan"), "{e}");
    b.refused(
        &[&cut[..], &["--material", "al7075", "--modulus", "1e-308"]].concat(),
        "--modulus 1e-308: must be a number from 10000 to 2000000",
    );
    // The built-in oblique material still reads and gives finite numbers.
    let o = b.run(&[&cut[..], &["--material", "ti6al4v"]].concat());
    let out = String::from_utf8_lossy(&o.stdout).to_lowercase();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!out.contains("nan") && !out.contains("inf"), "{out}");
}

/// Issue 34: "`post` with an axis velocity 1e-300, feed min 5e-324,
/// `rot_point` ≥ 1e20 (also accepted by the machine-file reader, which should
/// refuse them at their line); `inspect --machine` with `feed.rapid = 1e308`
/// blames `--rapid-rate`, an option not given".
#[test]
fn implausible_machine_files_are_refused_at_their_line() {
    let b = Bench::new();
    b.write(
        "five.apt",
        "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nGOTO/0,0,50,0,0,1\nGOTO/10,0,19,0,0.5,0.866\nGOTO/20,0,19,0,0,1\nFINI\n",
    );
    let kin = "[kinematics]\nkind = \"table-ac\"\n";
    for (extra, at) in [
        (
            format!("{MACHINE}{kin}[axes.a]\nvelocity = 1e-300\n"),
            "machine.toml:10:12: axes.a.velocity",
        ),
        (
            MACHINE.replace("max = 20000", "min = 5e-324\nmax = 20000") + kin,
            "machine.toml:6:7: feed.min",
        ),
        (
            format!("{MACHINE}{kin}rot_point = [1e20, 0, 0]\n"),
            "machine.toml:9:14: kinematics.rot_point[0]",
        ),
    ] {
        b.write("machine.toml", &extra);
        let e = b.refused(
            &[
                "post",
                "five.apt",
                "--machine",
                "machine.toml",
                "-o",
                "o.nc",
            ],
            at,
        );
        assert!(!e.contains("read back"), "{e}");
        assert!(!b.path("o.nc").exists());
    }
    b.write("machine.toml", &format!("{MACHINE}rapid = 1e308\n"));
    let e = b.refused(
        &["inspect", "slot.apt", "--machine", "machine.toml"],
        "machine.toml:7:9: feed.rapid",
    );
    assert!(!e.contains("--rapid-rate"), "{e}");
}

/// Issue 34: "`convert` of … `TOOL CALL … S-1`" exits 1 (the read-back
/// refuses what the reader took); refused at its line on reading.
#[test]
fn a_negative_spindle_speed_is_refused_at_its_line() {
    let b = Bench::new();
    b.write(
        "s.h",
        "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S-1\n2 L X+0 Y+0 Z+5 FMAX M3\n3 L X+10 F100\n4 END PGM T MM\n",
    );
    b.refused(
        &["convert", "s.h", "--to", "fanuc", "-o", "c.nc"],
        "s.h:3:1: the spindle speed",
    );
    assert!(!b.path("c.nc").exists());
}

/// Issue 34: "a pass that needs the spindle speed refuses such a block
/// [S0] at its line": `feed` and `force` used to keep the slot's feed and
/// report it as unloaded (0 N), exit 0.
#[test]
fn a_cut_with_the_spindle_at_zero_is_refused_by_the_force_passes() {
    let b = Bench::new();
    b.write(
        "s0.nc",
        "G21 G90\nT1 M6\nS0 M3\nG0 X-20 Y0 Z5\nG1 Z15 F100\nG1 X60\nG0 Z50\nM30\n",
    );
    let model = ["--stock", BOX, "--material", "al7075", "--tool", "ball:10"];
    b.refused(
        &[&["feed", "s0.nc", "-o", "f.nc"][..], &model].concat(),
        "s0.nc:6:1: this move removes material with the spindle at 0",
    );
    assert!(!b.path("f.nc").exists());
    b.refused(&[&["force", "s0.nc"][..], &model].concat(), "s0.nc:6:1:");
}

/// Issue 34: "An `S0` in a source (real NX posts carry `S0 M03`) is copied
/// with a warning": `convert` keeps it, says so at the line of the spindle
/// start on standard error and in `--json`'s warnings, and `speed` (which
/// sets the spindle speeds itself) runs; `feed` refuses the cut at its line
/// (the test above).
#[test]
fn an_s0_is_copied_with_a_warning() {
    let b = Bench::new();
    b.write(
        "s0.nc",
        "G21 G90\nT1 M6\nS0 M3\nG0 X-20 Y0 Z5\nG1 Z15 F100\nG1 X60\nG0 Z50\nM30\n",
    );
    let o = b.run(&["convert", "s0.nc", "--to", "fanuc", "-o", "c.nc"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{e}");
    assert!(
        e.contains("s0.nc:3:1: warning[spindle-stopped]") && e.contains("line 5"),
        "{e}"
    );
    let out = std::fs::read_to_string(b.path("c.nc")).expect("written");
    assert!(out.contains("S0"), "{out}");
    let o = b.run(&["convert", "s0.nc", "--to", "fanuc", "-o", "j.nc", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let w = j["warnings"].as_array().expect("warnings");
    assert!(
        w.iter().any(|w| w
            .as_str()
            .is_some_and(|w| w.contains("s0.nc:3:1: warning[spindle-stopped]"))),
        "{j}"
    );
    // Without S0 there is nothing to say.
    b.write(
        "s6.nc",
        "G21 G90\nT1 M6\nS6000 M3\nG0 X-20 Y0 Z5\nG1 Z15 F100\nM30\n",
    );
    let o = b.run(&[
        "convert", "s6.nc", "--to", "fanuc", "-o", "s6o.nc", "--json",
    ]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(j["warnings"].as_array().map(Vec::len), Some(0), "{j}");
}

/// Issue 34: "`orient … --objective time --ap 0.01` (any `--ap` ≤ 0.02)
/// writes `FEDRAT/0,MMPM`; the program's own reader then refuses it".
/// Whatever `orient` decides for so thin a cut, it writes no feed of 0.
#[test]
fn orient_for_time_on_a_thin_cut_writes_no_zero_feed() {
    use millplan_geom::analytic::{tessellate, DemoSurface};
    let b = Bench::new();
    let mut stl = Vec::new();
    millplan_geom::stl::write_binary_stl(
        &tessellate(&DemoSurface::default(), 4.0),
        "part",
        &mut stl,
    );
    std::fs::write(b.path("part.stl"), &stl).expect("stl");
    for ap in ["0.01", "0.02"] {
        let o = b.run(&[
            "orient",
            "slot.apt",
            "--stl",
            "part.stl",
            "--material",
            "c45",
            "--materials",
            "m.toml",
            "--machine",
            "machine.toml",
            "--fz",
            "0.1",
            "--ap",
            ap,
            "--ae",
            "1",
            "--objective",
            "time",
            "-o",
            "o.apt",
            "-q",
        ]);
        let e = stderr(&o);
        assert!(matches!(o.status.code(), Some(0 | 2 | 3)), "--ap {ap}: {e}");
        if let Ok(out) = std::fs::read_to_string(b.path("o.apt")) {
            let zero = out.lines().find(|l| {
                l.strip_prefix("FEDRAT/")
                    .and_then(|f| f.split(',').next())
                    .and_then(|f| f.parse::<f64>().ok())
                    .is_some_and(|f| f <= 0.0)
            });
            assert!(zero.is_none(), "--ap {ap}: {zero:?}\n{out}");
            // The program's own reader takes it back.
            let back = b.run(&["inspect", "o.apt"]);
            assert_eq!(back.status.code(), Some(0), "{}", stderr(&back));
        }
        let _ = std::fs::remove_file(b.path("o.apt"));
    }
}

/// Issue 34: "`convert` of `SPINDL/0` … exit 1": an APT spindle start at 0
/// is copied with the warning of an `S0`, exit 0.
#[test]
fn an_apt_spindle_at_zero_is_copied_with_a_warning() {
    let b = Bench::new();
    b.write("s0.apt", &SLOT.replace("SPINDL/6000,CLW", "SPINDL/0,CLW"));
    let o = b.run(&["convert", "s0.apt", "--to", "apt", "-o", "c.apt"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{e}");
    assert!(e.contains("s0.apt:4:1: warning[spindle-stopped]"), "{e}");
}

/// Issue 34's 20,000-case campaign (docs/usage.md): `feed` on an APT with
/// `FEDRAT/1e-300` wrote `FEDRAT/0`. Every reader refuses a positive feed
/// below the smallest plausible one at its line.
#[test]
fn an_absurdly_slow_feed_is_refused_at_its_line() {
    let b = Bench::new();
    b.write("slow.apt", &SLOT.replace("FEDRAT/500", "FEDRAT/1e-300"));
    let model = ["--stock", BOX, "--material", "al7075"];
    let e = b.refused(
        &[&["feed", "slow.apt", "-o", "f.apt"][..], &model].concat(),
        "smallest plausible feed",
    );
    assert!(e.contains("slow.apt:"), "{e}");
    assert!(!b.path("f.apt").exists());
    b.refused(
        &["convert", "slow.apt", "--to", "fanuc", "-o", "c.nc"],
        "smallest plausible feed",
    );
}

/// Issue 34: "`simulate --holder 59:30` is ignored unless `--flute-length`
/// is given: 'no collisions' where 6,087 exist". The flutes default to
/// 3·D, said in the output, and the holder meets the stock.
#[test]
fn the_holder_is_simulated_without_a_flute_length() {
    let b = Bench::new();
    b.write("deep.apt", &SLOT.replace(",19\n", ",-15\n"));
    let o = b.run(&["simulate", "deep.apt", "--stock", BOX, "--holder", "59:30"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(
        e.contains("simulated above 30.000 mm of flutes (3·D)"),
        "{e}"
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("shank or holder in material") || e.contains("shank or holder in material"),
        "{out}\n{e}"
    );
}

/// Issue 34: "With standard output closed (`>&-`), `convert -o -` exits 0
/// and prints 'wrote - (6386 moves)'"; "`inspect /dev/zero` reads until
/// allocation fails"; "File names with ESC are echoed raw to the terminal".
#[test]
fn closed_output_endless_input_and_control_characters() {
    let b = Bench::new();
    let o = b.sh("exec \"$M\" convert slot.apt --to fanuc -o - >&-");
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("standard output is closed"), "{e}");
    assert!(!e.contains("wrote"), "{e}");
    // `> /dev/null` is a reader that wants nothing, not a closed output.
    let o = b.sh("exec \"$M\" convert slot.apt --to fanuc -o - > /dev/null");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    if Path::new("/dev/zero").exists() {
        b.refused(&["inspect", "/dev/zero"], "a device or socket");
    }
    let name = "odd\u{1b}[31m.apt";
    let e = b.refused(&["inspect", name], "cannot open");
    assert!(!e.contains('\u{1b}'), "{e:?}");
    assert!(e.contains("odd\\u{1b}[31m.apt"), "{e:?}");
}

/// Issue 34: "`tool add --db /nonexistent/dir/t.db` creates the folders".
#[test]
fn a_library_in_a_missing_folder_is_refused() {
    let b = Bench::new();
    let db = b.path("no/such/t.db");
    b.refused(
        &[
            "tool",
            "add",
            "--db",
            db.to_str().expect("utf-8"),
            "1",
            "--name",
            "E",
        ],
        "does not exist",
    );
    assert!(!b.path("no").exists());
}

/// Issue 34: "A read-only library cannot even be shown." Shown by a user
/// who may not write it (as root, through `setpriv` when it is there).
#[test]
fn a_read_only_library_can_be_shown() {
    use std::os::unix::fs::PermissionsExt;
    let b = Bench::new();
    let o = b.run(&["tool", "add", "--db", "t.db", "1", "--name", "E"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let root = b.sh("id -u").stdout == b"0\n";
    let setpriv = b.sh("command -v setpriv").status.success();
    if root && !setpriv {
        eprintln!("skipped: running as root without setpriv");
        return;
    }
    let set = |p: &Path, mode| std::fs::set_permissions(p, std::fs::Permissions::from_mode(mode));
    set(b.dir.path(), 0o555).expect("chmod");
    set(&b.path("t.db"), 0o444).expect("chmod");
    let prefix = if root {
        "setpriv --reuid=65534 --regid=65534 --clear-groups "
    } else {
        ""
    };
    let o = b.sh(&format!("{prefix}\"$M\" tool show --db t.db"));
    set(b.dir.path(), 0o755).expect("chmod");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains('E'));
}
