//! Issue 17, "Hostile inputs and arguments", through the real binary: each
//! case of the issue is its smallest repro, run with the exit code and the
//! message it must give, and leaves no file behind (not even a temporary
//! one) unless it is meant to write one.
//!
//! Special files: the device cases use a FIFO and symbolic links made here,
//! never the machine's own `/dev/null` (a regression would replace it when
//! the tests run as root); `/dev/null` itself is tried only by other users,
//! whom the system stops anyway.

use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_geom::stl::write_binary_stl;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The names in `dir`, hidden ones too.
fn names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .expect("read dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect()
}

/// A folder with the inputs the cases share.
struct Bench {
    dir: tempfile::TempDir,
}

impl Bench {
    fn new() -> Bench {
        let b = Bench {
            dir: tempfile::tempdir().expect("tmp"),
        };
        let mesh = tessellate(&DemoSurface::default(), 2.0);
        let mut stl = Vec::new();
        write_binary_stl(&mesh, "part", &mut stl);
        b.write("part.stl", &stl);
        b.write(
            "lf.nc",
            b"G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z0 F100\nG1 X10\nG1 Y10\nM30\n",
        );
        b.write(
            "ball.apt",
            b"UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nGOTO/10,10,50\nGOTO/10,10,20\nGOTO/50,50,20\nFINI\n",
        );
        b.write(
            "plunge.apt",
            b"UNITS/MM\nCUTTER/10\nFEDRAT/500\nGOTO/10,10,50\nGOTO/10,10,-20\nGOTO/50,50,-20\nGOTO/50,50,50\nFINI\n",
        );
        b.write(
            "machine.toml",
            b"[spindle]\nmin = 500\nmax = 18000\naccel = 6000\n[feed]\nmax = 20000\n",
        );
        b
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.path(name);
        std::fs::write(&p, bytes).expect("write");
        p
    }

    /// Runs millplan in the folder with `args` (`{name}` words are paths).
    fn run(&self, args: &[&str]) -> Output {
        bin()
            .current_dir(self.dir.path())
            .args(args)
            .stdin(Stdio::null())
            .output()
            .expect("millplan runs")
    }

    /// Runs `args`, which must exit 2 with `needle` in its message and leave
    /// the folder as it was.
    fn refused(&self, args: &[&str], needle: &str) -> String {
        let before = names(self.dir.path());
        let o = self.run(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(names(self.dir.path()), before, "{args:?} left files");
        err
    }
}

const RASTER: [&str; 9] = [
    "raster",
    "--stl",
    "part.stl",
    "--tool",
    "ball:10",
    "--stepover",
    "1",
    "--step",
    "0.5",
];

/// The raster of [`RASTER`] with `extra` options, an option given there
/// (`--step 1e-9` or `--step=1e-9`) in place of its value in [`RASTER`].
fn raster_with(extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = RASTER.iter().map(|a| a.to_string()).collect();
    let mut k = 0;
    while k < extra.len() {
        let (flag, value, used) = match extra[k].split_once('=') {
            Some((f, v)) => (f, Some(v), 1),
            None if k + 1 < extra.len() && !extra[k + 1].starts_with("--") => {
                (extra[k], Some(extra[k + 1]), 2)
            }
            None => (extra[k], None, 1),
        };
        match (args.iter().position(|a| a == flag), value) {
            (Some(i), Some(v)) => args[i + 1] = v.to_string(),
            _ => args.extend(extra[k..k + used].iter().map(|a| a.to_string())),
        }
        k += used;
    }
    args.extend(["-o".to_string(), "r.apt".to_string()]);
    args
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

// ---------------------------------------------------------------------------
// Numbers validated at the boundary.

/// Issue 17: "`raster --clearance nan` writes `ZNaN`; `--angle inf` `XNaN
/// YNaN ZNaN`; `--tool ball:inf` `Z-inf`; `--feed inf` `Finf`;
/// `--clearance=-100` rapids 92 mm into the part", "`raster --stepover 1e-9`
/// (>30 s), `--step 1e-9` (17 GB), `--boundary 1e308` (endless)", "`raster
/// --step 1e-300` (capacity overflow, exit 101)", "`raster --spindle=-100`
/// blames stepover". Each is refused naming its option and range.
#[test]
fn raster_arguments_are_checked_by_name() {
    let b = Bench::new();
    for (extra, needle) in [
        (
            vec!["--clearance", "nan"],
            "--clearance NaN: must be a number above 0",
        ),
        (
            vec!["--clearance=-100"],
            "--clearance -100: must be a number above 0",
        ),
        (
            vec!["--angle", "inf"],
            "--angle inf: must be a number from -360 to 360 degrees",
        ),
        (
            vec!["--feed", "inf"],
            "--feed inf: must be a number from 0.1 to 1000000 mm/min",
        ),
        (
            vec!["--stepover", "1e-9"],
            "--stepover 1e-9: must be a number from 0.01 to 1000 mm",
        ),
        (
            vec!["--step", "1e-9"],
            "--step 1e-9: must be a number from 0.001",
        ),
        (
            vec!["--step", "1e-300"],
            "--step 1e-300: must be a number from 0.001",
        ),
        (
            vec!["--boundary", "1e308"],
            "--boundary 1e308: must be a number from -1000000",
        ),
        (vec!["--boundary", "40"], "--boundary 40: must be from"),
        (vec!["--boundary=-1000"], "--boundary -1000: must be from"),
        (
            vec!["--spindle=-100"],
            "--spindle -100: must be a number from 1 to",
        ),
        (
            vec!["--tol", "1e-9"],
            "--tol 1e-9: must be a number from 0.00001",
        ),
    ] {
        // The later option wins with clap: the hostile value replaces the
        // default.
        let args = raster_with(&extra);
        b.refused(&strs(&args), needle);
    }
    let mut args = raster_with(&[]);
    args[4] = "ball:inf".into();
    b.refused(
        &strs(&args),
        "--tool `ball:inf`: the diameter must be a positive number",
    );
    args[4] = "ball:5000".into();
    b.refused(
        &strs(&args),
        "--tool ball:5000: the diameter must be at most 1000 mm",
    );
}

/// Issue 17: "`convert --feed nan` `FNaN`, `--feed=-100` `F-100.`"; "`wd --af
/// nan` gives `D_w 0, n inf`, `--vc=-63` a negative speed, `--ap 10.5` with
/// D 10 is accepted; `speed --vc inf`"; "`speed --ball-d 0` blames 'vc, fz,
/// flutes and ap'"; "`gouge --step 1e-9` (OOM at 24 GB)".
#[test]
fn other_arguments_are_checked_by_name() {
    let b = Bench::new();
    let cases: [(&[&str], &str); 10] = [
        (
            &["convert", "lf.nc", "-o", "c.nc", "--feed", "nan"],
            "--feed NaN: must be a number from 0.1 to",
        ),
        (
            &["convert", "lf.nc", "-o", "c.nc", "--feed=-100"],
            "--feed -100: must be a number from 0.1 to",
        ),
        (
            &[
                "wd", "--d", "10", "--ap", "0.3", "--alpha", "10", "--af", "nan",
            ],
            "--af NaN: must be a number from -360 to 360",
        ),
        (
            &[
                "wd", "--d", "10", "--ap", "0.3", "--alpha", "10", "--af", "0", "--vc=-63",
            ],
            "--vc -63: must be a number above 0",
        ),
        (
            &[
                "wd", "--d", "10", "--ap", "10.5", "--alpha", "10", "--af", "0",
            ],
            "--ap 10.5: must be a number above 0 and at most 5 mm (at most D/2)",
        ),
        (
            &[
                "speed", "ball.apt", "--stl", "part.stl", "--vc", "inf", "--fz", "0.1", "--ap",
                "0.3", "-o", "s.nc",
            ],
            "--vc inf: must be a number above 0 and at most 10000 m/min",
        ),
        (
            &[
                "speed", "ball.apt", "--stl", "part.stl", "--vc", "63", "--fz", "0.1", "--ap",
                "0.3", "--ball-d", "0", "-o", "s.nc",
            ],
            "--ball-d 0: must be a number above 0",
        ),
        (
            &[
                "speed", "ball.apt", "--stl", "part.stl", "--vc", "63", "--fz", "0.1", "--ap",
                "0.3", "--flutes", "0", "-o", "s.nc",
            ],
            "--flutes 0: must be a number from 1 to 1000",
        ),
        (
            &["gouge", "ball.apt", "--stl", "part.stl", "--step", "1e-9"],
            "--step 1e-9: must be a number from 0.001 to 1000 mm",
        ),
        (
            &[
                "reorder", "ball.apt", "--stl", "part.stl", "--vc", "inf", "-o", "r.apt",
            ],
            "--vc inf: must be a number above 0",
        ),
    ];
    for (args, needle) in cases {
        b.refused(args, needle);
    }
}

/// Issue 17: "machine files with `spindle_max = inf` are accepted" — refused
/// at the value's line and column, in both layouts.
#[test]
fn machine_file_numbers_are_located() {
    let b = Bench::new();
    b.write(
        "inf.toml",
        b"[spindle]\nmin = 0\nmax = inf\naccel = 6000\n[feed]\nmax = 10000\n",
    );
    b.write(
        "flat.toml",
        b"spindle_min = 0\nspindle_max = inf\nspindle_accel = 6000\nfeed_max = 10000\n",
    );
    for (file, at) in [
        ("inf.toml", "inf.toml:3:7: spindle.max"),
        ("flat.toml", "flat.toml:2:15: spindle_max"),
    ] {
        b.refused(
            &[
                "speed",
                "ball.apt",
                "--stl",
                "part.stl",
                "--vc",
                "63",
                "--fz",
                "0.1",
                "--ap",
                "0.3",
                "--machine",
                file,
                "-o",
                "s.nc",
            ],
            at,
        );
        b.refused(&["convert", "lf.nc", "-o", "c.nc", "--machine", file], at);
    }
}

/// Issue 17: "an inch APT with `GOTO/1e308,1,1` becomes `Xinf`" — a
/// located error on reading, whatever the command.
#[test]
fn a_coordinate_out_of_range_in_mm_is_located() {
    let b = Bench::new();
    b.write(
        "inch.apt",
        b"UNITS/INCHES\nCUTTER/0.5\nFEDRAT/10\nGOTO/0,0,1\nGOTO/1e308,1,1\nFINI\n",
    );
    b.refused(
        &["inspect", "inch.apt"],
        "inch.apt:5:1: a coordinate of this move is not a finite number",
    );
    b.refused(
        &["convert", "inch.apt", "--to", "fanuc", "-o", "i.nc"],
        "inch.apt:5:1:",
    );
}

// ---------------------------------------------------------------------------
// Resource limits.

/// Issue 17: "A 133-byte NURBS with 1e12 control points subdivides to 16.8
/// M moves (2 GB, 13 s)". Refused at the NURBS record; `--limit` raises it.
#[test]
fn a_nurbs_of_far_control_points_is_refused() {
    let b = Bench::new();
    b.write("nurbs.apt", b"CUTTER/10\nFEDRAT/100\nGOTO/0,0,0\nNURBS/\nKNOT/0.5,1\nCNTRL/1e12,0,0\nCNTRL/0,1e12,0\nCNTRL/1e12,1e12,0\nCNTRL/0,0,1e12\nFINI\n");
    let t = std::time::Instant::now();
    b.refused(
        &["inspect", "nurbs.apt"],
        "nurbs.apt:4:1: NURBS: span 1 needs more than 10000 moves",
    );
    b.refused(
        &["convert", "nurbs.apt", "--to", "fanuc", "-o", "n.nc"],
        "--limit expansion=N",
    );
    assert!(t.elapsed().as_secs() < 20, "{:?}", t.elapsed());
    // A small spline reads; a lower limit refuses it too.
    b.write("small.apt", b"CUTTER/10\nFEDRAT/100\nGOTO/0,0,0\nNURBS/\nKNOT/0.5,1\nCNTRL/10,0,0\nCNTRL/0,10,0\nCNTRL/10,10,0\nCNTRL/0,0,10\nFINI\n");
    assert!(b.run(&["inspect", "small.apt"]).status.success());
    b.refused(
        &["inspect", "small.apt", "--limit", "expansion=5"],
        "expansion limit of 5",
    );
    let o = bin()
        .current_dir(b.dir.path())
        .env("MILLPLAN_LIMITS", "expansion=5")
        .args(["inspect", "small.apt"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    b.refused(
        &["inspect", "small.apt", "--limit", "movez=5"],
        "--limit movez=5: `movez` is not a limit",
    );
    b.refused(
        &["inspect", "small.apt", "--limit", "moves"],
        "write NAME=VALUE",
    );
}

/// Issue 17: "pecks of `Q0.000001` (G83, APT `CYCLE/DEEP`, Heidenhain
/// 200/1.3) expand to gigabytes". Refused at the cycle's line.
#[test]
fn tiny_pecks_are_refused() {
    let b = Bench::new();
    b.write("peck.nc", b"G21 G17 G90 G94\nT2 M6\nG43 H2 S1500 M3\nG0 X10. Y10. Z5.\nG98 G83 X10. Y10. Z-20. R2. Q0.000001 F100.\nX30.\nG80\nM30\n");
    b.write("peck.apt", b"UNITS/MM\nCUTTER/10\nFEDRAT/100\nGOTO/0,0,10\nCYCLE/DEEP,FEDTO,20,STEP,0.000001,RAPTO,2,MMPM,100\nGOTO/10,10,0\nCYCLE/OFF\nFINI\n");
    b.write("peck200.h", b"0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 200 DRILLING ~\n  Q200=2 ;SET-UP CLEARANCE ~\n  Q201=-20 ;DEPTH ~\n  Q206=150 ;FEED RATE ~\n  Q202=0.000001 ;PLUNGING DEPTH ~\n  Q210=0 ;DWELL TIME AT TOP ~\n  Q203=+0 ;SURFACE COORDINATE ~\n  Q204=50 ;2ND SET-UP CLEARANCE ~\n  Q211=0 ;DWELL TIME AT BOTTOM\n4 L X+10 Y+10 R0 FMAX M99\n5 END PGM P MM\n");
    b.write("peck1.h", b"0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 1.0 PECKING\n4 CYCL DEF 1.1 SET UP 2\n5 CYCL DEF 1.2 DEPTH -20\n6 CYCL DEF 1.3 PECKG 0.000001\n7 CYCL DEF 1.4 DWELL 0\n8 CYCL DEF 1.5 F150\n9 L X+10 Y+10 R0 FMAX M99\n10 END PGM P MM\n");
    for (file, at) in [
        ("peck.nc", "peck.nc:5:1:"),
        ("peck.apt", "peck.apt:5:1:"),
        ("peck200.h", "peck200.h:4:1:"),
        ("peck1.h", "peck1.h:4:1:"),
    ] {
        let e = b.refused(&["convert", file, "--to", "fanuc", "-o", "p.nc"], at);
        assert!(e.contains("at most 1000 are accepted"), "{e}");
    }
}

/// Issue 17: "30 non-planar CIRCLEs of R 1e6 write 527k lines". Refused at
/// the first such circle, before a byte is written.
#[test]
fn far_circles_written_as_lines_are_refused() {
    let b = Bench::new();
    let r = 1e6_f64;
    let pt = |t: f64| (r * t.cos(), 0.8 * r * t.sin(), -0.6 * r * t.sin());
    let mut src = String::from("UNITS/MM\nCUTTER/10\nFEDRAT/100\n");
    let (x, y, z) = pt(0.0);
    src += &format!("GOTO/{x:.4},{y:.4},{z:.4}\n");
    for k in 1..=30 {
        src += &format!("CIRCLE/0,0,0,0,0.6,0.8,{r},0.06,0.5,25.0,0.0\n");
        // Quarter circles, as in the issue (17,500 lines each).
        let (x, y, z) = pt(std::f64::consts::FRAC_PI_2 * k as f64);
        src += &format!("GOTO/{x:.4},{y:.4},{z:.4}\n");
    }
    src += "FINI\n";
    b.write("circles.apt", src.as_bytes());
    let e = b.refused(
        &["convert", "circles.apt", "--to", "fanuc", "-o", "c.nc"],
        "circles.apt:6:1: an arc of radius 1000000 mm",
    );
    assert!(e.contains("expansion limit of 10000"), "{e}");
    // APT says CIRCLE as it is.
    assert!(b
        .run(&["convert", "circles.apt", "--to", "apt", "-o", "c.apt"])
        .status
        .success());
}

/// Issue 17: "a 123-byte STL facet at ±1e30 makes `raster` take 8–24 GB".
/// Refused on reading, at the facet's byte; and a facet count over the
/// limit before anything is allocated.
#[test]
fn an_stl_beyond_its_limits_is_refused_on_reading() {
    let b = Bench::new();
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&1u32.to_le_bytes());
    for v in [
        [0.0f32, 0.0, 1.0],
        [-1e30, -1e30, 0.0],
        [1e30, -1e30, 0.0],
        [0.0, 1e30, 1.0],
    ] {
        for c in v {
            stl.extend_from_slice(&c.to_le_bytes());
        }
    }
    stl.extend_from_slice(&[0, 0]);
    b.write("far.stl", &stl);
    let e = b.refused(
        &raster_with(&[])
            .iter()
            .map(|a| {
                if a == "part.stl" {
                    "far.stl"
                } else {
                    a.as_str()
                }
            })
            .collect::<Vec<_>>(),
        "far.stl:byte 84: facet 1 has a vertex at -1.000e30 mm",
    );
    assert!(e.contains("--limit stl-extent=N"), "{e}");
    b.refused(&["inspect", "far.stl"], "stl-extent limit of 1000000");
    b.refused(
        &["inspect", "part.stl", "--limit", "stl-triangles=10"],
        "part.stl:byte 80: the binary STL header declares",
    );
}

/// Issue 17: "200k identical triangles make `raster`/`gouge` run over 60 s".
/// Repeated facets are one facet: both finish in seconds.
#[test]
fn repeated_facets_cost_nothing() {
    let b = Bench::new();
    let mut stl = vec![0u8; 80];
    let n = 200_000u32;
    stl.extend_from_slice(&n.to_le_bytes());
    let mut rec = Vec::new();
    for v in [
        [0.0f32, 0.0, 1.0],
        [0.0, 0.0, 0.0],
        [60.0, 0.0, 0.0],
        [0.0, 60.0, 5.0],
    ] {
        for c in v {
            rec.extend_from_slice(&c.to_le_bytes());
        }
    }
    rec.extend_from_slice(&[0, 0]);
    for _ in 0..n {
        stl.extend_from_slice(&rec);
    }
    b.write("same.stl", &stl);
    let t = std::time::Instant::now();
    let args: Vec<String> = raster_with(&["-q"])
        .into_iter()
        .map(|a| {
            if a == "part.stl" {
                "same.stl".into()
            } else {
                a
            }
        })
        .collect();
    let o = b.run(&strs(&args));
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    let o = b.run(&["gouge", "ball.apt", "--stl", "same.stl", "-q"]);
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
}

/// The raster's grid and a gouge check's samples are counted against the
/// moves and memory limits before any work.
#[test]
fn work_over_the_limits_is_refused_up_front() {
    let b = Bench::new();
    let args = raster_with(&["--stepover", "0.01", "--step", "0.001"]);
    b.refused(&strs(&args), "make 3");
    let e = b.refused(&strs(&args), "over the moves limit of 50000000");
    assert!(e.contains("--limit moves=N"), "{e}");
    let args = raster_with(&["--limit", "memory=1"]);
    b.refused(
        &strs(&args),
        "over the memory limit of 1 (raise it with --limit memory=N)",
    );
    b.refused(
        &[
            "gouge", "ball.apt", "--stl", "part.stl", "--step", "0.001", "--limit", "memory=1",
        ],
        "--step 0.001 over this program samples",
    );
}

/// Issue 17: "a 12 KB Sinumerik expression of nested unary minus overflows
/// the reader thread's stack (exit 134)". `speed` reads on a thread of its
/// own: a located error there as in `inspect`.
#[test]
fn a_deep_expression_is_located_on_any_thread() {
    let b = Bench::new();
    let src = format!("N10 G710 G90\nN20 TRAORI\nN30 DEF REAL _Z\nN40 T=\"BALL\" D1\nN50 G1 X1 Y1 Z={}5 F100\nN60 M30\n", "-".repeat(12_000));
    b.write("deep.mpf", src.as_bytes());
    let e = b.refused(&["inspect", "deep.mpf"], "deep.mpf:5:14:");
    assert!(e.contains("expression-depth limit of 64"), "{e}");
    assert!(
        e.len() < 1000,
        "the 12 KB expression is echoed: {} bytes",
        e.len()
    );
    b.refused(
        &[
            "speed", "deep.mpf", "--stl", "part.stl", "--vc", "63", "--fz", "0.1", "--ap", "0.3",
            "--ball-d", "10", "-o", "s.nc",
        ],
        "expression-depth limit of 64",
    );
}

/// Issue 17: "error messages echo a whole 1 MB token". The message keeps
/// the token's start and says how long it was; a line over the line-bytes
/// limit is refused where the limit ends.
#[test]
fn a_huge_token_is_not_echoed() {
    let b = Bench::new();
    let src = format!("G21\nT1 M6\nG1 X{} F10\nM30\n", "9".repeat(1_000_000));
    b.write("tok.nc", src.as_bytes());
    let e = b.refused(
        &["inspect", "tok.nc", "--limit", "line-bytes=2M"],
        "tok.nc:3:4:",
    );
    assert!(e.contains("…[1000002 bytes]"), "{}", &e[..e.len().min(300)]);
    assert!(e.len() < 500, "{} bytes", e.len());
    b.refused(
        &["inspect", "tok.nc"],
        "tok.nc:3:65537: a line of 65537 bytes or more, over the line-bytes limit of 65536",
    );
}

// ---------------------------------------------------------------------------
// Line endings.

/// Issue 17: "CR-only line endings read silently as one line: a five-block
/// program becomes one move; `convert` writes an empty program, exit 0".
/// Every dialect's golden input reads alike from a file with LF, CRLF and CR
/// endings (the streaming reader, whose reads may split a CRLF).
#[test]
fn every_line_ending_reads_alike_from_a_file() {
    let b = Bench::new();
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../millplan-nc/tests/golden");
    for name in [
        "fanuc.nc",
        "linuxcnc.ngc",
        "sinumerik.mpf",
        "heidenhain.h",
        "catia.apt",
        "nx.cls",
        "solidworks.apt",
        "inch_iso.apt",
    ] {
        let src = std::fs::read_to_string(golden.join(name)).expect("golden");
        let lines: Vec<&str> = src.lines().collect();
        let mut seen = Vec::new();
        for (k, nl) in ["\n", "\r\n", "\r"].iter().enumerate() {
            let f = format!("{k}_{name}");
            b.write(&f, (lines.join(nl) + nl).as_bytes());
            let o = b.run(&["inspect", "--json", "-q", &f]);
            assert!(o.status.success(), "{name} {nl:?}: {}", stderr(&o));
            let mut j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
            j["name"] = serde_json::Value::Null;
            seen.push(j);
        }
        assert_eq!(seen[0], seen[1], "{name}: CRLF");
        assert_eq!(seen[0], seen[2], "{name}: CR");
    }
    b.write(
        "cr.nc",
        b"G21 G90\rT1 M6\rG0 X0 Y0 Z5\rG1 Z0 F100\rG1 X10\rG1 Y10\rG1 X0\rM30\r",
    );
    let o = b.run(&["convert", "cr.nc", "-o", "out.ngc"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = b.run(&["inspect", "--json", "out.ngc"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(j["moves"]["total"], 5);
}

// ---------------------------------------------------------------------------
// Outputs.

/// Issue 17: "`-o` onto a device node, FIFO or a symlink to
/// `/proc/self/fd/1` swaps it for a regular file". Refused, the special file
/// left as it was (the FIFO is never opened: nothing blocks).
#[test]
fn special_files_are_never_replaced() {
    let b = Bench::new();
    let fifo = b.path("fifo.nc");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo")
        .success());
    std::os::unix::fs::symlink(&fifo, b.path("to_fifo.nc")).expect("link");
    std::os::unix::fs::symlink("/dev/null", b.path("to_null.nc")).expect("link");
    std::os::unix::fs::symlink("/proc/self/fd/1", b.path("to_stdout.nc")).expect("link");
    std::os::unix::fs::symlink(b.path("nowhere"), b.path("dangling.nc")).expect("link");
    for out in ["fifo.nc", "to_fifo.nc", "to_null.nc"] {
        b.refused(
            &["convert", "lf.nc", "-o", out],
            "not a regular file (a device, a FIFO or a socket)",
        );
    }
    // Standard output a pipe: the link names no file.
    b.refused(
        &["convert", "lf.nc", "-o", "to_stdout.nc"],
        "not a regular file",
    );
    b.refused(
        &["convert", "lf.nc", "-o", "dangling.nc"],
        "a symbolic link to nothing",
    );
    let meta = std::fs::symlink_metadata(&fifo).expect("fifo");
    assert!(std::os::unix::fs::FileTypeExt::is_fifo(&meta.file_type()));
    for l in ["to_fifo.nc", "to_null.nc", "to_stdout.nc"] {
        assert!(std::fs::symlink_metadata(b.path(l))
            .expect("link")
            .file_type()
            .is_symlink());
    }
    // Other commands and outputs go through the same check.
    b.refused(
        &strs(&raster_with(&[]))
            .iter()
            .map(|a| if *a == "r.apt" { "fifo.nc" } else { a })
            .collect::<Vec<_>>(),
        "not a regular file",
    );
    b.refused(
        &[
            "speed",
            "ball.apt",
            "--stl",
            "part.stl",
            "--vc",
            "63",
            "--fz",
            "0.1",
            "--ap",
            "0.3",
            "-o",
            "s.nc",
            "--report",
            "to_null.nc",
        ],
        "--report to_null.nc: not a regular file",
    );
    // `/dev/null` itself only where the system would stop a regression.
    if !is_root() {
        b.refused(
            &["convert", "lf.nc", "-o", "/dev/null"],
            "not a regular file",
        );
    }
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(true)
}

/// A symbolic link to a regular file is written through: the link stays, the
/// file it names gets the output.
#[test]
fn a_link_to_a_file_is_written_through() {
    let b = Bench::new();
    b.write("real.nc", b"old");
    std::os::unix::fs::symlink(b.path("real.nc"), b.path("link.nc")).expect("link");
    let o = b.run(&["convert", "lf.nc", "-o", "link.nc"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(b.path("link.nc"))
        .expect("link")
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(b.path("real.nc"))
        .expect("real")
        .contains("G1"));
}

/// Issue 17: "`-o <directory>` exit 1 (bad input is 2)"; a folder that does
/// not exist; two outputs on one path ("the CSV replaced the program");
/// "`-o m.toml` overwrote" the `--machine` file; an input under another
/// name (a hard link); the library of `tool` as an output.
#[test]
fn outputs_are_checked_before_any_work() {
    let b = Bench::new();
    std::fs::create_dir(b.path("folder")).expect("dir");
    b.refused(
        &["convert", "lf.nc", "-o", "folder"],
        "-o folder: is a folder; name a file",
    );
    b.refused(&["convert", "lf.nc", "-o", "folder/"], "is a folder");
    b.refused(
        &["convert", "lf.nc", "-o", "missing/x.nc"],
        "the folder missing does not exist",
    );
    let speed = [
        "speed", "ball.apt", "--stl", "part.stl", "--vc", "63", "--fz", "0.1", "--ap", "0.3",
    ];
    b.refused(
        &[&speed[..], &["-o", "same.nc", "--table", "same.nc"]].concat(),
        "--table same.nc: same.nc is already an output of this run",
    );
    b.refused(
        &[&speed[..], &["-o", "a.nc", "--report", "./a.nc"]].concat(),
        "already an output",
    );
    b.refused(
        &[
            &speed[..],
            &["-o", "s.nc", "--table", "t.csv", "--report", "folder"],
        ]
        .concat(),
        "--report folder: is a folder",
    );
    let machine = std::fs::read(b.path("machine.toml")).expect("machine");
    b.refused(
        &[
            "convert",
            "lf.nc",
            "--machine",
            "machine.toml",
            "-o",
            "machine.toml",
        ],
        "refusing to overwrite an input file",
    );
    b.refused(
        &[
            &speed[..],
            &[
                "--machine",
                "machine.toml",
                "-o",
                "s.nc",
                "--report",
                "machine.toml",
            ],
        ]
        .concat(),
        "refusing to overwrite an input file",
    );
    assert_eq!(
        std::fs::read(b.path("machine.toml")).expect("machine"),
        machine
    );
    std::fs::hard_link(b.path("lf.nc"), b.path("hard.nc")).expect("hard link");
    b.refused(
        &["convert", "lf.nc", "-o", "hard.nc"],
        "refusing to overwrite an input file",
    );
    b.refused(
        &[
            "raster",
            "--stl",
            "part.stl",
            "--tool",
            "ball:10",
            "--stepover",
            "1",
            "--step",
            "0.5",
            "-o",
            "part.stl",
        ],
        "refusing to overwrite an input file",
    );
    let o = b.run(&["tool", "--db", "lib.db", "add", "1", "--name", "x"]);
    assert!(o.status.success(), "{}", stderr(&o));
    b.refused(
        &["tool", "--db", "lib.db", "export", "-o", "lib.db"],
        "refusing to overwrite an input file",
    );
    b.refused(
        &[
            "raster",
            "--stl",
            "part.stl",
            "--tool",
            "ball:10",
            "--stepover",
            "1",
            "--step",
            "0.5",
            "-o",
            "-",
        ],
        "-o -: standard output carries this command's summary",
    );
}

/// `-o -` writes the program to standard output where a command allows it.
#[test]
fn dash_is_standard_output() {
    let b = Bench::new();
    let before = names(b.dir.path());
    let o = b.run(&["convert", "lf.nc", "--to", "fanuc", "-o", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("G1 Z0. F100."));
    assert_eq!(names(b.dir.path()), before);
    let o = b.run(&["tool", "--db", "lib.db", "add", "1", "--name", "x"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = b.run(&[
        "tool", "--db", "lib.db", "export", "--format", "csv", "-o", "-",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).starts_with("number"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}

/// Issue 17: "an interrupt while writing a 1 M-point program leaves a
/// hidden `.millplan-XXXXXX` of 30–75 MB". SIGINT while the outputs are
/// staged removes them (exit 130); a temporary file of a process that is
/// gone is removed by the next run in its folder.
#[test]
fn an_interrupt_leaves_nothing() {
    let b = Bench::new();
    // A raster of some 40,000 points: its table and report take a while
    // after the program is staged.
    let o = b.run(&[
        "raster",
        "--stl",
        "part.stl",
        "--tool",
        "ball:10",
        "--stepover",
        "0.5",
        "--step",
        "0.2",
        "--tol",
        "0",
        "-o",
        "big.apt",
        "-q",
    ]);
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    std::fs::create_dir(b.path("out")).expect("dir");
    let out = b.path("out");
    let mut caught = false;
    for _ in 0..5 {
        let mut child = bin()
            .current_dir(b.dir.path())
            .args([
                "speed",
                "big.apt",
                "--stl",
                "part.stl",
                "--vc",
                "63",
                "--fz",
                "0.1",
                "--ap",
                "0.3",
                "-q",
                "-o",
                "out/p.nc",
                "--table",
                "out/t.csv",
                "--report",
                "out/r.html",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        let t = std::time::Instant::now();
        while t.elapsed().as_secs() < 60 {
            if names(&out).iter().any(|n| n.starts_with(".millplan-")) {
                let _ = Command::new("kill")
                    .args(["-INT", &child.id().to_string()])
                    .status();
                caught = true;
                break;
            }
            if child.try_wait().expect("wait").is_some() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        let o = child.wait_with_output().expect("wait");
        if caught {
            assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
            assert!(
                stderr(&o).contains("stopped by signal 2; no output written"),
                "{}",
                stderr(&o)
            );
            assert!(names(&out).is_empty(), "left {:?}", names(&out));
            break;
        }
        for f in names(&out) {
            std::fs::remove_file(out.join(f)).expect("remove");
        }
    }
    assert!(caught, "the staged outputs were never seen");
    // Left by a process that is gone (pid over any pid_max): removed; one of
    // a process alive (this test's) is left alone.
    b.write("out/.millplan-4194999-AbCdEf.tmp", b"stale");
    let mine = format!("out/.millplan-{}-AbCdEf.tmp", std::process::id());
    b.write(&mine, b"live");
    let o = b.run(&["convert", "lf.nc", "-o", "out/c.nc"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let left = names(&out);
    assert!(!left.contains(".millplan-4194999-AbCdEf.tmp"), "{left:?}");
    assert!(left.contains(mine.trim_start_matches("out/")), "{left:?}");
}

/// Issue 17: "writing to a closed pipe or `/dev/full` (exit 101)": a message
/// and exit 1; a check that found problems keeps its 3.
#[test]
fn a_closed_or_full_standard_output_is_reported() {
    let b = Bench::new();
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
    if let Ok(full) = full {
        let o = bin()
            .current_dir(b.dir.path())
            .arg("explain")
            .stdout(full)
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("error: standard output: No space left on device"),
            "{}",
            stderr(&o)
        );
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("full");
        let o = bin()
            .current_dir(b.dir.path())
            .args(["gouge", "plunge.apt", "--stl", "part.stl"])
            .stdout(full)
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("error: standard output"),
            "{}",
            stderr(&o)
        );
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("full");
        let o = bin().arg("--help").stdout(full).output().expect("runs");
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    } else {
        eprintln!("SKIPPED: no /dev/full here");
    }
    // A closed pipe: the IR of a long program to a reader that left.
    let mut long = String::from("G21 G90\nT1 M6\n");
    for k in 0..100_000 {
        long += &format!("G1 X{} Y{} F100\n", k % 100, k / 100);
    }
    b.write("long.nc", long.as_bytes());
    let mut child = bin()
        .current_dir(b.dir.path())
        .args(["inspect", "--ir", "-q", "long.nc"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let o = child.wait_with_output().expect("wait");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("error: standard output: Broken pipe"),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    let mut child = bin()
        .current_dir(b.dir.path())
        .args(["gouge", "plunge.apt", "--stl", "part.stl"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let o = child.wait_with_output().expect("wait");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
}

/// Issue 17: "binary-STL detection of a truncated file depends on its
/// name". The same bytes give the same error under any name.
#[test]
fn a_truncated_binary_stl_is_judged_by_content() {
    let b = Bench::new();
    let whole = std::fs::read(b.path("part.stl")).expect("stl");
    let cut = &whole[..whole.len() / 2];
    let mut errs = Vec::new();
    for name in ["cut.stl", "cut.nc", "cut"] {
        b.write(name, cut);
        let e = b.refused(
            &["inspect", name],
            &format!("{name}:byte 80: binary STL header declares"),
        );
        errs.push(e.replacen(name, "F", 1));
    }
    assert_eq!(errs[0], errs[1]);
    assert_eq!(errs[0], errs[2]);
}

/// Issue 17: "A non-SQLite `--db` … exit 1", "`tool --db /dev/null` creates
/// `/dev/null-journal`". Both exit 2; nothing is created beside a special
/// file.
#[test]
fn a_library_that_is_no_library_is_refused() {
    let b = Bench::new();
    b.write(
        "text.db",
        b"not a database at all, just some text that is long enough",
    );
    b.refused(
        &["tool", "--db", "text.db", "show"],
        "text.db: file is not a database",
    );
    let fifo = b.path("lib.fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo")
        .success());
    b.refused(
        &["tool", "--db", "lib.fifo", "show"],
        "lib.fifo: not a regular file",
    );
    let extra: Vec<PathBuf> = ["-journal", "-wal", "-shm"]
        .iter()
        .map(|s| PathBuf::from(format!("/dev/null{s}")))
        .collect();
    let existed: Vec<bool> = extra.iter().map(|p| p.exists()).collect();
    let o = b.run(&["tool", "--db", "/dev/null", "show"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("/dev/null: not a regular file"),
        "{}",
        stderr(&o)
    );
    for (p, was) in extra.iter().zip(existed) {
        assert!(was || !p.exists(), "{} was created", p.display());
    }
}

// ---------------------------------------------------------------------------
// The tool library under concurrent writers.

/// Issue 17: "two loops of `tool measure` fail 184 of 600 times with
/// 'database is locked'". Eight processes at a time, 2,400 measurements:
/// none fails, the library stays sound, every measurement is logged once.
#[test]
fn eight_concurrent_writers_all_succeed() {
    const WRITERS: usize = 8;
    const EACH: usize = 300;
    let b = Bench::new();
    let db = b.path("tools.db");
    for args in [
        vec![
            "add", "5", "--name", "mill", "--l", "100", "--r", "5", "--ltol", "0.5", "--rtol",
            "0.5", "--lbreak", "1", "--rbreak", "1",
        ],
        vec!["preset", "5", "--l", "100", "--r", "5"],
        vec!["measure", "5", "--first", "--l", "100", "--r", "5"],
    ] {
        let o = bin()
            .args(["tool", "--db", s(&db)])
            .args(&args)
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let count = |sql: &str| -> i64 {
        let c = rusqlite::Connection::open(&db).expect("open");
        c.query_row(sql, [], |r| r.get(0)).expect("count")
    };
    let (m0, e0) = (
        count("SELECT count(*) FROM measurements"),
        count("SELECT count(*) FROM events"),
    );
    let t = std::time::Instant::now();
    let failures: Vec<String> = std::thread::scope(|sc| {
        let hs: Vec<_> = (0..WRITERS)
            .map(|w| {
                let db = db.clone();
                sc.spawn(move || {
                    let mut failed = Vec::new();
                    for i in 0..EACH {
                        let l = format!("{:.4}", 100.0 + 0.0001 * ((w * EACH + i) % 50) as f64);
                        let o = bin()
                            .args([
                                "tool",
                                "--db",
                                s(&db),
                                "measure",
                                "5",
                                "--l",
                                &l,
                                "--r",
                                "5",
                            ])
                            .output()
                            .expect("runs");
                        if o.status.code() != Some(0) {
                            failed.push(format!(
                                "writer {w} #{i}: {:?} {}",
                                o.status.code(),
                                stderr(&o)
                            ));
                        }
                    }
                    failed
                })
            })
            .collect();
        hs.into_iter()
            .flat_map(|h| h.join().expect("writer"))
            .collect()
    });
    let secs = t.elapsed().as_secs_f64();
    assert!(
        failures.is_empty(),
        "{} of {} failed: {:?}",
        failures.len(),
        WRITERS * EACH,
        &failures[..failures.len().min(5)]
    );
    let c = rusqlite::Connection::open(&db).expect("open");
    let ok: String = c
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .expect("check");
    assert_eq!(ok, "ok");
    let (m, e) = (
        count("SELECT count(*) FROM measurements") - m0,
        count("SELECT count(*) FROM events") - e0,
    );
    assert_eq!(m, (WRITERS * EACH) as i64);
    assert_eq!(e, m, "every measurement logged once");
    eprintln!("{} measurements by {WRITERS} processes in {secs:.1} s: 0 failed, integrity ok, {m} measurements = {e} events", WRITERS * EACH);
}

/// Found fuzzing the tool-room commands: `tool cycle --clearance nan` wrote
/// `Q260=+NaN`, `tool measure --dset inf` accepted any first measurement,
/// `wd-sweep --af-step 1e-300` never ended.
#[test]
fn tool_room_and_sweep_numbers_are_checked() {
    let b = Bench::new();
    for args in [
        &[
            "tool", "--db", "lib.db", "add", "1", "--l", "100", "--r", "5",
        ][..],
        &[
            "tool", "--db", "lib.db", "preset", "1", "--l", "100", "--r", "5",
        ][..],
    ] {
        let o = b.run(args);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    b.refused(
        &[
            "tool",
            "--db",
            "lib.db",
            "cycle",
            "1",
            "--clearance",
            "nan",
            "-o",
            "c.h",
        ],
        "--clearance NaN: must be a number above 0",
    );
    b.refused(
        &[
            "tool", "--db", "lib.db", "measure", "1", "--first", "--l", "100", "--r", "5",
            "--dset", "inf",
        ],
        "--dset inf: must be a number from 0 to 10 mm",
    );
    b.refused(
        &[
            "tool", "--db", "lib.db", "measure", "1", "--l", "nan", "--r", "5",
        ],
        "measured L must be a non-negative number",
    );
    b.refused(
        &["thread", "check", "M20x1", "--class", "6H", "--d2", "inf"],
        "D2 must be a positive number",
    );
    b.refused(
        &["wd-sweep", "--af-step", "1e-300", "-o", "sweep"],
        "--af-step 1e-300: must be a number from 0.1 to 180 degrees",
    );
    b.refused(
        &["wd-sweep", "--d", "10,inf", "-o", "sweep"],
        "--d inf: must be a number above 0",
    );
}

/// The hostile inputs stay in bounds under a cap on the process's memory
/// (`ulimit -v`): refused with exit 2, never killed by the allocator.
#[test]
fn limits_hold_under_a_memory_cap() {
    let b = Bench::new();
    b.write("nurbs.apt", b"CUTTER/10\nFEDRAT/100\nGOTO/0,0,0\nNURBS/\nKNOT/0.5,1\nCNTRL/1e12,0,0\nCNTRL/0,1e12,0\nCNTRL/1e12,1e12,0\nCNTRL/0,0,1e12\nFINI\n");
    b.write("peck.nc", b"G21 G17 G90 G94\nT2 M6\nG0 X10. Y10. Z5.\nG98 G83 X10. Y10. Z-20. R2. Q0.000001 F100.\nG80\nM30\n");
    let bin = env!("CARGO_BIN_EXE_millplan");
    for (cmd, needle) in [
        (format!("{bin} inspect nurbs.apt"), "expansion limit"),
        (
            format!("{bin} convert peck.nc --to linuxcnc -o p.ngc"),
            "at most 1000 are accepted",
        ),
        (
            format!(
                "{bin} raster --stl part.stl --tool ball:10 --stepover 0.01 --step 0.001 -o r.apt"
            ),
            "moves limit",
        ),
        (
            format!("{bin} gouge ball.apt --stl part.stl --step 0.001 --limit memory=1"),
            "memory limit",
        ),
    ] {
        let o = Command::new("sh")
            .current_dir(b.dir.path())
            .arg("-c")
            .arg(format!("ulimit -v 2000000 && exec {cmd}"))
            .output()
            .expect("sh");
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{cmd}: {}", stderr(&o));
    }
}

// ---------------------------------------------------------------------------
// Issue 34, "Hostile inputs, round two".

/// Issue 34: "`simulate finish.apt --stock box:auto:1e18` (also
/// `offset:1e308`, `cylinder:0,0,0,1,1e19`): capacity overflow in
/// `Stock::empty`" and "`--stock box:0,0,0,429496729.6,429496729.6,1`: the
/// memory estimate wraps". Each is refused under the memory limit, named,
/// before anything is allocated.
#[test]
fn a_huge_stock_is_refused_under_the_memory_limit() {
    let b = Bench::new();
    for stock in [
        "box:auto:1e18",
        "cylinder:0,0,0,1,1e19",
        "box:0,0,0,429496729.6,429496729.6,1",
        "box:0,0,0,1e12,1e12,1",
    ] {
        let e = b.refused(
            &["simulate", "ball.apt", "--stock", stock],
            "over the memory limit",
        );
        assert!(e.contains("dexels"), "{stock}: {e}");
    }
    b.refused(
        &[
            "simulate",
            "ball.apt",
            "--stl",
            "part.stl",
            "--stock",
            "offset:1e308",
        ],
        "over the memory limit",
    );
}

/// Issue 34: "`tool pz --insl 14 --tp 1e-4` and `tool add` with `--tp` below
/// 5e-4: attempt to divide by zero (thread.rs:33)". A pitch below the finest
/// ISO metric pitch, 0.2 mm, is refused at the option.
#[test]
fn an_implausible_thread_pitch_is_refused() {
    let b = Bench::new();
    let o = b.run(&["tool", "add", "--db", "t.db", "1", "--name", "E"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for tp in ["1e-4", "4e-4", "0.1"] {
        b.refused(
            &["tool", "pz", "--insl", "14", "--tp", tp],
            "at least 0.2 mm",
        );
        b.refused(
            &[
                "tool",
                "add",
                "--db",
                "t.db",
                "7",
                "--name",
                "TM",
                "--kind",
                "thread-mill",
                "--insl",
                "14",
                "--tp",
                tp,
            ],
            "at least 0.2 mm",
        );
    }
    let o = b.run(&["tool", "pz", "--insl", "14", "--tp", "0.2"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// Issue 34: "`inspect` of 30,000 nested functions with `--limit
/// expression-depth=100000`: stack overflow". The limit is capped at 1,000
/// (documented in the limits table); at the cap the parser holds on the
/// reading thread of `speed` and on `inspect`'s.
#[test]
fn the_expression_depth_limit_is_capped() {
    let b = Bench::new();
    let deep = |n: usize| {
        format!(
            "N10 G710 G90\nN20 TRAORI\nN30 DEF REAL _Z\nN40 T=\"BALL\" D1\nN50 G1 X1 Y1 Z={}5{} F100\nN60 M30\n",
            "(-".repeat(n),
            ")".repeat(n)
        )
    };
    b.write("deep.mpf", deep(30_000).as_bytes());
    let e = b.refused(
        &[
            "inspect",
            "deep.mpf",
            "--limit",
            "expression-depth=100000",
            "--limit",
            "line-bytes=1M",
        ],
        "expression-depth",
    );
    assert!(e.contains("1000"), "{e}");
    b.write("cap.mpf", deep(499).as_bytes());
    for args in [
        &["inspect", "cap.mpf", "--limit", "expression-depth=1000"][..],
        &[
            "speed",
            "cap.mpf",
            "--stl",
            "part.stl",
            "--vc",
            "63",
            "--fz",
            "0.1",
            "--ap",
            "0.3",
            "--ball-d",
            "10",
            "-o",
            "s.nc",
            "--limit",
            "expression-depth=1000",
        ][..],
    ] {
        let o = b.run(args);
        let err = stderr(&o);
        assert!(
            matches!(o.status.code(), Some(0 | 2 | 3)),
            "{args:?}: {err}"
        );
        assert!(!err.contains("expression-depth"), "{args:?}: {err}");
        assert!(!err.contains("overflow"), "{args:?}: {err}");
    }
}

/// Issue 34: "Negative tangential and radial cutting coefficients (K_tc,
/// K_rc, K_te, K_re) are accepted (negative power and torque); axial ones may
/// legitimately be negative". Refused at the file's line, exit 2.
#[test]
fn negative_tangential_or_radial_coefficients_are_refused_at_their_line() {
    let b = Bench::new();
    for (kc, ke, line) in [
        ("[-2100, 800, 500]", "[30, 40, 0]", 4),
        ("[2100, -800, 500]", "[30, 40, 0]", 4),
        ("[2100, 800, 500]", "[-30, 40, 0]", 5),
        ("[2100, 800, 500]", "[30, -40, 0]", 5),
    ] {
        b.write(
            "m.toml",
            format!("[c45]\nmodel = \"linear\"\nnote = \"shop\"\nkc = {kc}\nke = {ke}\n")
                .as_bytes(),
        );
        let e = b.refused(
            &["force", "materials", "--materials", "m.toml"],
            &format!("m.toml:{line}: material `c45`"),
        );
        assert!(e.contains("must not be negative"), "{e}");
    }
    b.write(
        "m.toml",
        b"[ob]\nmodel = \"oblique\"\ntau_s = 300.0\nbeta_a = [20.0, 0.3]\nrc_c0 = [0.3, 0.01]\nrc_a = [0.2, 0.0]\nke = [-24.0, 43.0, 0.0]\n",
    );
    b.refused(
        &["force", "materials", "--materials", "m.toml"],
        "m.toml:7: material `ob`",
    );
    // A negative axial coefficient is a real case and stays accepted.
    b.write(
        "m.toml",
        b"[c45]\nmodel = \"linear\"\nkc = [2100, 800, -50]\nke = [30, 40, -2]\n",
    );
    let o = b.run(&["force", "materials", "--materials", "m.toml"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// Issue 34: "`--tool ball:10:3` silently ignores its extra field".
#[test]
fn a_tool_spec_with_an_extra_field_is_refused() {
    let b = Bench::new();
    for tool in ["ball:10:3", "flat:10:1", "bull:10:2:1", "cone:6:118:4"] {
        b.refused(
            &[
                "cut",
                "--tool",
                tool,
                "--fz",
                "0.1",
                "--ap",
                "2",
                "--ae",
                "5",
                "--n",
                "3000",
                "--material",
                "c45",
            ],
            "one too many",
        );
    }
}
