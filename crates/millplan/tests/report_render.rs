//! Opt-in: the HTML report renders in headless Chromium (Debian's `chromium`).
//! Run with `cargo test -p millplan --test report_render -- --ignored`; `.ci/run`
//! does when it could install Chromium.

use std::path::Path;
use std::process::Command;

/// Headless Chromium on a page: `--screenshot=PNG` or `--dump-dom`.
fn chromium(profile: &Path, page: &Path, what: &str) -> std::process::Output {
    Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--window-size=1200,2600",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(what)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs")
}

#[test]
#[ignore = "needs /usr/bin/chromium"]
fn speed_report_renders_in_headless_chromium() {
    let dir = tempfile::tempdir().expect("tmp");
    let demo = dir.path().join("demo");
    let st = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["demo", "-o", demo.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(st.status.success());
    let png = dir.path().join("report.png");
    let out = chromium(
        &dir.path().join("profile"),
        &demo.join("report.html"),
        &format!("--screenshot={}", png.display()),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).expect("screenshot written");
    assert_eq!(&bytes[1..4], b"PNG");
    // A blank page compresses to a few kB; the plots make it far larger.
    assert!(
        bytes.len() > 100_000,
        "screenshot only {} bytes",
        bytes.len()
    );
}

/// The speed report opens with its inputs, the warnings in a box and the
/// verdict in words, above the summary table: as Chromium lays the page out,
/// for a part that matches its program and for one that does not.
#[test]
#[ignore = "needs /usr/bin/chromium"]
fn speed_report_shows_inputs_warnings_and_verdict() {
    let dir = tempfile::tempdir().expect("tmp");
    let demo = dir.path().join("demo");
    let st = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .arg("demo")
        .arg("-o")
        .arg(&demo)
        .output()
        .expect("runs");
    assert!(st.status.success());
    // The part read in the wrong unit: most points miss it.
    let report = dir.path().join("mismatch.html");
    let st = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args([
            "speed",
            "--vc",
            "63",
            "--fz",
            "0.125",
            "--ap",
            "0.3",
            "--stl-units",
            "inch",
            "--stl",
        ])
        .arg(demo.join("part.stl"))
        .arg(demo.join("finish.apt"))
        .arg("-o")
        .arg(dir.path().join("vc.nc"))
        .arg("--report")
        .arg(&report)
        .output()
        .expect("runs");
    assert_eq!(
        st.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    for (page, warning) in [
        (demo.join("report.html"), "open edges"),
        (report, "do not touch the part"),
    ] {
        let (dom, [warnings, verdict, summary]) =
            rendered_sections(&dir.path().join("profile"), &page);
        let box_text = &dom[warnings..verdict];
        assert!(box_text.contains(warning), "{}: {box_text}", page.display());
        let verdict_text = &dom[verdict..summary];
        for said in [
            "Spindle control keeps the cutting speed",
            "Cycle time",
            "spindle's acceleration",
        ] {
            assert!(
                verdict_text.contains(said),
                "{}: {verdict_text}",
                page.display()
            );
        }
        assert!(
            dom.contains("spindle 500–18000 1/min"),
            "the machine limits in the header"
        );
        assert!(
            dom.contains("spindle maximum"),
            "the limit drawn on the speed plot"
        );
    }
}

/// The page as headless Chromium renders it, with where its warnings box,
/// verdict and summary start; fails unless the inputs come first and the
/// four follow in that order.
fn rendered_sections(profile: &Path, page: &Path) -> (String, [usize; 3]) {
    let out = chromium(profile, page, "--dump-dom");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dom = String::from_utf8_lossy(&out.stdout).to_string();
    let at = |needle: &str| {
        dom.find(needle)
            .unwrap_or_else(|| panic!("{}: no `{needle}`", page.display()))
    };
    let (inputs, warnings, verdict, summary) = (
        at("id=\"inputs\""),
        at("id=\"warnings\""),
        at("id=\"verdict\""),
        at("<h2>Summary</h2>"),
    );
    assert!(
        inputs < warnings && warnings < verdict && verdict < summary,
        "{}",
        page.display()
    );
    (dom, [warnings, verdict, summary])
}

/// Runs `millplan` with `args`; returns its exit code.
fn millplan(args: &[&std::ffi::OsStr]) -> Option<i32> {
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(args)
        .output()
        .expect("runs");
    o.status.code()
}

/// The reorder and setup reports open with their inputs, the warnings in a
/// box and the verdict in words, above the summary table, as Chromium lays
/// the pages out; the machine's limits are drawn on their plots.
#[test]
#[ignore = "needs /usr/bin/chromium"]
fn reorder_and_setup_reports_show_inputs_warnings_and_verdict() {
    let dir = tempfile::tempdir().expect("tmp");
    let demo = dir.path().join("demo");
    let os = |p: &Path| p.as_os_str().to_owned();
    assert_eq!(
        millplan(&["demo".as_ref(), "-o".as_ref(), demo.as_os_str()]),
        Some(0)
    );
    let (part, apt) = (demo.join("part.stl"), demo.join("finish.apt"));
    // The part read in the wrong unit: its points do not touch it.
    let reorder = dir.path().join("reorder.html");
    let mut args: Vec<std::ffi::OsString> = ["reorder", "-q", "--stl-units", "inch", "--stl"]
        .iter()
        .map(|s| s.into())
        .collect();
    args.extend([
        os(&part),
        os(&apt),
        "-o".into(),
        os(&dir.path().join("r.apt")),
    ]);
    args.extend(["--report".into(), os(&reorder)]);
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
    assert_eq!(millplan(&args), Some(0));
    let setup = dir.path().join("setup.html");
    let mut args: Vec<std::ffi::OsString> = [
        "setup", "-q", "--type", "ab", "--range1", "-20,20", "--range2", "-20,20", "--stl",
    ]
    .iter()
    .map(|s| s.into())
    .collect();
    args.extend([os(&part), "--report".into(), os(&setup)]);
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
    assert_eq!(millplan(&args), Some(0), "a relief is seen from above");
    for (k, (page, warning, verdict, limit)) in [
        (
            &reorder,
            "do not touch the part within tolerance",
            "candidate orders measured",
            "spindle maximum",
        ),
        (
            &setup,
            "open edges",
            "Feasible in one setup",
            "class=\"limit\"",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let (dom, [warnings, said, summary]) =
            rendered_sections(&dir.path().join(format!("profile{k}")), page);
        assert!(
            dom[warnings..said].contains(warning),
            "{}",
            &dom[warnings..said]
        );
        assert!(
            dom[said..summary].contains(verdict),
            "{}",
            &dom[said..summary]
        );
        assert!(dom.contains(limit), "{}: the limits drawn", page.display());
    }
}

/// The simulate report's 3-D view of the stock draws in headless Chromium
/// with software WebGL (SwiftShader): the canvas says it rendered with WebGL 2
/// and read back a fifth or so of its pixels covered by the stock, and the
/// page logs no script error. Without WebGL (`--disable-gpu`, no SwiftShader)
/// the view steps aside and says the 2-D map stands in for it.
#[test]
#[ignore = "needs /usr/bin/chromium"]
fn simulate_report_draws_the_stock_in_3d_or_says_it_cannot() {
    let dir = tempfile::tempdir().expect("tmp");
    let demo = dir.path().join("demo");
    let bin = env!("CARGO_BIN_EXE_millplan");
    let st = Command::new(bin)
        .args(["demo", "-o", demo.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(st.status.success());
    let st = Command::new(bin)
        .current_dir(&demo)
        .args([
            "simulate",
            "finish.apt",
            "--stock",
            "offset:0.5",
            "--stl",
            "part.stl",
        ])
        .args(["--report", "sim.html"])
        .output()
        .expect("runs");
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let page = demo.join("sim.html");
    let run = |gl: &[&str]| {
        Command::new("chromium")
            .args(["--headless", "--no-sandbox", "--no-first-run"])
            .args([
                "--disable-background-networking",
                "--enable-logging=stderr",
                "--v=0",
            ])
            .args(gl)
            .arg(format!(
                "--user-data-dir={}",
                dir.path().join("profile").display()
            ))
            .arg("--dump-dom")
            .arg(format!("file://{}", page.display()))
            .output()
            .expect("chromium runs")
    };
    let out = run(&["--use-angle=swiftshader", "--enable-unsafe-swiftshader"]);
    let dom = String::from_utf8_lossy(&out.stdout);
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(dom.contains("data-rendered=\"webgl2\""), "{log}");
    let painted: f64 = dom
        .split("data-painted=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .and_then(|v| v.parse().ok())
        .expect("the view reports what it painted");
    assert!(painted > 0.05 && painted < 0.95, "painted {painted}");
    assert!(!log.contains("Uncaught"), "{log}");
    let out = run(&["--disable-gpu", "--disable-software-rasterizer"]);
    let dom = String::from_utf8_lossy(&out.stdout);
    assert!(
        dom.contains("data-rendered=\"none\"") || dom.contains("data-rendered=\"webgl2\""),
        "the view neither drew nor stepped aside"
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("Uncaught"));
}
