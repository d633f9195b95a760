//! Argument combinations of `raster`, `speed` and `convert` under fuzzing
//! (issue 17: some 220 bad arguments): every numeric option drawn from the
//! hostile values of the issue and ordinary ones. Whatever the mix, the run
//! ends in time with 0, 2 or 3 (never 1, 101 or a signal), never panics,
//! leaves no temporary file, and what it writes holds no number that is not
//! finite. A fixed, small number of cases keeps it to seconds.

use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_geom::stl::write_binary_stl;
use proptest::prelude::*;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const VALUES: &[&str] = &[
    "nan", "inf", "-inf", "-100", "0", "1e-300", "1e-9", "1e308", "-1e308", "0.3", "1", "2", "10",
    "63", "2000",
];

fn setup() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tmp");
    let mesh = tessellate(&DemoSurface::default(), 3.0);
    let mut stl = Vec::new();
    write_binary_stl(&mesh, "part", &mut stl);
    std::fs::write(dir.path().join("part.stl"), stl).expect("stl");
    std::fs::write(
        dir.path().join("ball.apt"),
        "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nGOTO/10,10,50\nGOTO/10,10,20\nGOTO/50,50,20\nFINI\n",
    )
    .expect("apt");
    std::fs::write(
        dir.path().join("in.nc"),
        "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z0 F100\nG2 X10 Y0 R5\nM30\n",
    )
    .expect("nc");
    dir
}

/// Runs millplan in `dir` and checks the properties of the module.
fn run_checked(dir: &Path, args: &[String]) -> Result<(), TestCaseError> {
    for f in ["out.apt", "out.nc"] {
        let _ = std::fs::remove_file(dir.join(f));
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let t = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break Some(s);
        }
        if t.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let o = child.wait_with_output().expect("output");
    let err = String::from_utf8_lossy(&o.stderr);
    let Some(status) = status else {
        return Err(TestCaseError::fail(format!("{args:?} ran over 60 s")));
    };
    prop_assert!(
        matches!(status.code(), Some(0 | 2 | 3)),
        "{args:?}: {status:?} {err}"
    );
    prop_assert!(!err.contains("panicked"), "{args:?}: {err}");
    for e in std::fs::read_dir(dir).expect("dir").flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        prop_assert!(!n.starts_with(".millplan-"), "{args:?} left {n}");
    }
    for f in ["out.apt", "out.nc"] {
        if let Ok(text) = std::fs::read_to_string(dir.join(f)) {
            prop_assert!(status.code() != Some(2), "{args:?} wrote {f} and failed");
            for line in text.lines() {
                let code = line.split([';', '(']).next().unwrap_or("");
                let code = code.split("$$").next().unwrap_or("");
                for w in code.split(|c: char| !c.is_ascii_alphanumeric() && c != '.' && c != '-') {
                    let body = w.trim_start_matches(|c: char| c.is_ascii_alphabetic());
                    prop_assert!(
                        !matches!(body, "NaN" | "inf" | "-inf"),
                        "{args:?} wrote `{line}`"
                    );
                }
            }
        }
    }
    Ok(())
}

fn v() -> impl Strategy<Value = &'static str> {
    prop::sample::select(VALUES)
}

/// An option with a value, or left out.
fn opt(flag: &'static str) -> impl Strategy<Value = Vec<String>> {
    prop::option::of(v()).prop_map(move |x| match x {
        Some(x) => vec![format!("{flag}={x}")],
        None => vec![],
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn raster_arguments(
        d in v(), stepover in v(), step in v(),
        rest in (opt("--angle"), opt("--clearance"), opt("--feed"), opt("--spindle"), opt("--boundary"), opt("--tol")),
    ) {
        let dir = setup();
        let mut args: Vec<String> = ["raster", "--stl", "part.stl", "-q", "-o", "out.apt"].map(String::from).to_vec();
        args.push(format!("--tool=ball:{d}"));
        args.push(format!("--stepover={stepover}"));
        args.push(format!("--step={step}"));
        for r in [rest.0, rest.1, rest.2, rest.3, rest.4, rest.5] {
            args.extend(r);
        }
        run_checked(dir.path(), &args)?;
    }

    #[test]
    fn speed_arguments(
        vc in v(), fz in v(), ap in v(),
        rest in (opt("--ball-d"), opt("--s-threshold"), prop::option::of(prop::sample::select(&["0", "1", "2", "7", "100000"][..]))),
    ) {
        let dir = setup();
        let mut args: Vec<String> = ["speed", "ball.apt", "--stl", "part.stl", "-q", "-o", "out.nc"].map(String::from).to_vec();
        args.push(format!("--vc={vc}"));
        args.push(format!("--fz={fz}"));
        args.push(format!("--ap={ap}"));
        args.extend(rest.0);
        args.extend(rest.1);
        if let Some(f) = rest.2 {
            args.push(format!("--flutes={f}"));
        }
        run_checked(dir.path(), &args)?;
    }

    #[test]
    fn convert_arguments(
        feed in opt("--feed"),
        to in prop::sample::select(&["fanuc", "sinumerik", "heidenhain", "linuxcnc", "apt"][..]),
        limit in prop::option::of(prop::sample::select(&["moves=1", "expansion=1", "line-bytes=5", "expression-depth=1", "memory=1", "moves=0", "bogus=1"][..])),
    ) {
        let dir = setup();
        let mut args: Vec<String> = ["convert", "in.nc", "-q", "-o", "out.nc"].map(String::from).to_vec();
        args.push(format!("--to={to}"));
        args.extend(feed);
        if let Some(l) = limit {
            args.push(format!("--limit={l}"));
        }
        run_checked(dir.path(), &args)?;
    }
}

/// The issue's own bad arguments, each once.
#[test]
fn the_issue_arguments() {
    let dir = setup();
    let cases: &[&[&str]] = &[
        &[
            "raster",
            "--stl",
            "part.stl",
            "--tool",
            "ball:10",
            "--stepover",
            "1",
            "--step",
            "1e-300",
            "-o",
            "out.apt",
        ],
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
            "--boundary",
            "1e308",
            "-o",
            "out.apt",
        ],
        &[
            "raster",
            "--stl",
            "part.stl",
            "--tool",
            "ball:10",
            "--stepover",
            "1e-9",
            "--step",
            "0.5",
            "-o",
            "out.apt",
        ],
        &[
            "speed", "ball.apt", "--stl", "part.stl", "--vc", "inf", "--fz", "0.1", "--ap", "0.3",
            "-o", "out.nc",
        ],
        &["convert", "in.nc", "--feed", "nan", "-o", "out.nc"],
    ];
    for c in cases {
        let args: Vec<String> = c.iter().map(|s| s.to_string()).collect();
        run_checked(dir.path(), &args).expect("in bounds");
    }
}
