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
    // Every point gouges that part, refused as the input's own (exit 3):
    // written with --force, the report with it.
    args.extend(["--report".into(), os(&reorder), "--force".into()]);
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
    assert_eq!(millplan(&args), Some(3));
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

/// What a page measures of itself once laid out (run inside Chromium):
/// the viewport's width and the page's, the elements whose box leaves the
/// viewport, the legend entries whose boxes meet a plot's area, per plot
/// its axis labels and tick labels, the cells that read as raw data (JSON
/// braces or keys, numbers to seven or more decimals), the names of the
/// inputs box's rows, and the verdict's level, colour, first line and
/// whether a warnings box is shown.
const PROBE: &str = r#"<script>
(() => {
  const W = window.innerWidth;
  const r = { width: W, page: document.documentElement.scrollWidth, off: [], over: [], plots: [], verdict: null };
  for (const e of document.querySelectorAll('td,th,p,li,h1,h2,pre,figcaption,svg,table')) {
    const b = e.getBoundingClientRect();
    if (b.width > 0 && (b.right > W + 0.5 || b.left < -0.5))
      r.off.push(e.tagName + ': ' + (e.textContent || '').slice(0, 80));
  }
  for (const svg of document.querySelectorAll('svg')) {
    const areas = [...svg.querySelectorAll('.plot-area')].map(a => a.getBoundingClientRect());
    if (areas.length === 0) continue;
    for (const l of svg.querySelectorAll('.legend > *')) {
      const b = l.getBoundingClientRect();
      for (const a of areas)
        if (b.left < a.right - 0.5 && b.right > a.left + 0.5 && b.top < a.bottom - 0.5 && b.bottom > a.top + 0.5)
          r.over.push((svg.querySelector('text') || {}).textContent + ': ' + (l.textContent || l.tagName));
    }
    const ticks = [...svg.querySelectorAll('text')].filter(t => /^[−-]?[0-9.]+$/.test(t.textContent.trim())).length;
    r.plots.push({ title: (svg.querySelector('text') || {}).textContent, map: !!svg.querySelector('.map-area'),
      labels: svg.querySelectorAll('.axis-label').length, ticks });
  }
  r.raw = [...document.querySelectorAll('td,pre')]
    .filter(e => /[{}]|"\w+"\s*:|\d\.\d{7,}/.test(e.textContent))
    .map(e => e.tagName + ': ' + e.textContent.slice(0, 80));
  r.inputs = [...document.querySelectorAll('#inputs th')].map(e => e.textContent);
  const v = document.getElementById('verdict');
  if (v) r.verdict = { level: v.dataset.level, colour: getComputedStyle(v).borderLeftColor,
    first: (v.querySelector('p') || {}).textContent || '', warnings: !!document.getElementById('warnings') };
  const p = document.createElement('pre'); p.id = 'layout-probe'; p.textContent = JSON.stringify(r);
  document.body.appendChild(p);
})();
</script>"#;

/// The page laid out by headless Chromium 1,400 px wide, measured by
/// [`PROBE`].
fn measure(profile: &Path, page: &Path) -> serde_json::Value {
    let probed = page.with_extension("probe.html");
    let html = std::fs::read_to_string(page).expect("page");
    let html = match html.rfind("</body>") {
        Some(i) => format!("{}{PROBE}{}", &html[..i], &html[i..]),
        None => format!("{html}{PROBE}"),
    };
    std::fs::write(&probed, html).expect("write");
    let out = Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
        ])
        .args(["--disable-background-networking", "--window-size=1400,3000"])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("--dump-dom")
        .arg(format!("file://{}", probed.display()))
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&out.stdout);
    let json = dom
        .split("<pre id=\"layout-probe\">")
        .nth(1)
        .and_then(|r| r.split("</pre>").next())
        .unwrap_or_else(|| panic!("{}: the probe did not run", page.display()));
    let json = json
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&json).expect("probe json")
}

/// The colour of each level's verdict box, as Chromium computes it.
fn level_colour(level: &str) -> &'static str {
    match level {
        "green" => "rgb(46, 125, 50)",
        "amber" => "rgb(239, 143, 0)",
        "red" => "rgb(198, 40, 40)",
        _ => "no level",
    }
}

/// A report read at 1,400 px: nothing off-screen, no legend over a plot's
/// data, no raw data dump (JSON, full double precision), an inputs box,
/// axes (two labels, ticks) on every map and plot, and a verdict whose
/// colour is its level's and whose level follows from what the page says:
/// red with a failed check, amber with a warning, a kept input or a worse
/// measure, green otherwise. Returns the level.
fn readable(profile: &Path, page: &Path) -> String {
    let v = measure(profile, page);
    let name = page.display();
    assert!(v["page"].as_f64() <= v["width"].as_f64(), "{name}: {v}");
    assert_eq!(v["off"], serde_json::json!([]), "{name}: off-screen");
    assert_eq!(v["over"], serde_json::json!([]), "{name}: legend over data");
    assert_eq!(
        v["raw"],
        serde_json::json!([]),
        "{name}: raw data in a table"
    );
    assert!(
        v["inputs"].as_array().is_some_and(|i| !i.is_empty()),
        "{name}: no inputs box"
    );
    let plots = v["plots"].as_array().expect("plots");
    assert!(!plots.is_empty(), "{name}: no plot");
    for p in plots {
        assert!(p["labels"].as_u64() >= Some(2), "{name}: axes of {p}");
        assert!(p["ticks"].as_u64() >= Some(4), "{name}: ticks of {p}");
    }
    let verdict = &v["verdict"];
    let level = verdict["level"].as_str().expect("a verdict with a level");
    assert_eq!(verdict["colour"], level_colour(level), "{name}: {verdict}");
    let first = verdict["first"].as_str().unwrap_or("");
    let failed = first.contains("failed:");
    let amber =
        verdict["warnings"] == true || first.contains("worse:") || first.contains("kept as it was");
    let want = if failed {
        "red"
    } else if amber {
        "amber"
    } else {
        "green"
    };
    assert_eq!(level, want, "{name}: {verdict}");
    let mut cap = level.chars();
    let cap: String = cap
        .next()
        .map(|c| c.to_ascii_uppercase())
        .into_iter()
        .chain(cap)
        .collect();
    assert!(first.starts_with(&format!("{cap}:")), "{name}: {first}");
    level.to_string()
}

/// The demo's folder, made once for the tests of this file that share it.
fn demo() -> &'static Path {
    static DEMO: std::sync::OnceLock<tempfile::TempDir> = std::sync::OnceLock::new();
    DEMO.get_or_init(|| {
        let dir = tempfile::tempdir().expect("tmp");
        let st = Command::new(env!("CARGO_BIN_EXE_millplan"))
            .args(["demo", "-q", "-o"])
            .arg(dir.path())
            .output()
            .expect("runs");
        assert!(st.status.success());
        dir
    })
    .path()
}

/// Runs millplan in the demo's folder; the report it wrote.
fn report_of(args: &[&str], report: &str, codes: &[i32]) -> std::path::PathBuf {
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .current_dir(demo())
        .args(args)
        .args(["-q", "--report", report])
        .output()
        .expect("runs");
    assert!(
        o.status.code().is_some_and(|c| codes.contains(&c)),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    demo().join(report)
}

fn profile(name: &str) -> std::path::PathBuf {
    demo().join(format!("profile-{name}"))
}

/// The tour's speed reports (the demo's and `speed`'s), read at 1,400 px.
#[test]
#[ignore = "needs /usr/bin/chromium"]
fn tour_speed_reports_are_readable() {
    readable(&profile("demo"), &demo().join("report.html"));
    let page = report_of(
        &[
            "speed",
            "--stl",
            "part.stl",
            "finish.apt",
            "--vc",
            "63",
            "--fz",
            "0.125",
            "--flutes",
            "2",
            "--ap",
            "0.3",
            "-o",
            "finish_vc.nc",
        ],
        "vc_report.html",
        &[0, 3],
    );
    // The demo's part is open by design: its note is a warning, so amber.
    assert_eq!(readable(&profile("speed"), &page), "amber");
}

#[test]
#[ignore = "needs /usr/bin/chromium"]
fn tour_reorder_report_is_readable() {
    let page = report_of(
        &[
            "reorder",
            "--stl",
            "part.stl",
            "finish.apt",
            "--ap",
            "0.3",
            "--machine",
            "machine.toml",
            "--to",
            "apt",
            "-o",
            "reordered.apt",
        ],
        "reorder.html",
        &[0],
    );
    readable(&profile("reorder"), &page);
}

#[test]
#[ignore = "needs /usr/bin/chromium"]
fn tour_simulate_report_is_readable() {
    let page = report_of(
        &[
            "simulate",
            "finish.apt",
            "--stock",
            "offset:0.5",
            "--stl",
            "part.stl",
        ],
        "sim.html",
        &[0, 3],
    );
    readable(&profile("sim"), &page);
    // A plunge into the part: a cut into it is a failed check, so red.
    std::fs::write(
        demo().join("plunge.apt"),
        "UNITS/MM\nCUTTER/10,5\nFEDRAT/100,MMPM\nGOTO/30,30,50\nGOTO/30,30,-5\n",
    )
    .expect("write");
    let page = report_of(
        &[
            "simulate",
            "plunge.apt",
            "--stock",
            "box:auto",
            "--stl",
            "part.stl",
        ],
        "plunge.html",
        &[0, 3],
    );
    assert_eq!(readable(&profile("plunge"), &page), "red");
}

#[test]
#[ignore = "needs /usr/bin/chromium"]
fn tour_optimise_report_is_readable() {
    let page = report_of(
        &[
            "optimise",
            "finish.apt",
            "--stl",
            "part.stl",
            "--stock",
            "offset:0.5",
            "--machine",
            "machine.toml",
            "--material",
            "al7075",
            "-o",
            "optimised.nc",
        ],
        "optimise.html",
        &[0, 3],
    );
    readable(&profile("optimise"), &page);
}

#[test]
#[ignore = "needs /usr/bin/chromium"]
fn force_and_feed_reports_are_readable() {
    let model = [
        "--stock",
        "offset:0.5",
        "--stl",
        "part.stl",
        "--material",
        "al7075",
    ];
    let force = report_of(
        &[&["force", "finish.apt"][..], &model].concat(),
        "force.html",
        &[0, 3],
    );
    readable(&profile("force"), &force);
    let feed = report_of(
        &[&["feed", "finish.apt"][..], &model, &["-o", "fed.nc"]].concat(),
        "feed.html",
        &[0, 3],
    );
    readable(&profile("feed"), &feed);
    // The header of the other reports: what was run on what.
    let want = [
        "program",
        "part",
        "stock",
        "tools",
        "material",
        "machine",
        "options",
        "load limits",
    ];
    for (name, page) in [("force", &force), ("feed", &feed)] {
        let v = measure(&profile(&format!("{name}-inputs")), page);
        assert_eq!(v["inputs"], serde_json::json!(want), "{name}");
    }
}

#[test]
#[ignore = "needs /usr/bin/chromium"]
fn setup_report_is_readable() {
    let page = report_of(
        &[
            "setup", "--type", "ab", "--range1", "-20,20", "--range2", "-20,20", "--stl",
            "part.stl",
        ],
        "setup.html",
        &[0],
    );
    readable(&profile("setup"), &page);
}

/// SOLIDWORKS CAM's multi-tool program (a drill, a flat and a ball end mill)
/// with its part: the speed report names the ball, the tool its ball-end
/// operation uses, and reads at 1,400 px.
#[test]
#[ignore = "needs /usr/bin/chromium"]
fn shared_sample_speed_report_is_readable_and_names_the_ball() {
    #[path = "../../millplan-nc/tests/shared_data/mod.rs"]
    mod shared_data;
    let (Some(apt), Some(stl)) = (
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.apt"),
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.STL"),
    ) else {
        return;
    };
    let out = demo().join("glue_vc.apt");
    let page = demo().join("glue.html");
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args([
            "speed", "-q", "--vc", "200", "--fz", "0.05", "--ap", "0.3", "--to", "apt",
        ])
        .arg("--stl")
        .arg(&stl)
        .arg(&apt)
        .arg("-o")
        .arg(&out)
        .arg("--report")
        .arg(&page)
        .arg("--force")
        .output()
        .expect("runs");
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let html = std::fs::read_to_string(&page).expect("report");
    let tool = html
        .split("<th>tool</th><td>")
        .nth(1)
        .and_then(|r| r.split("</td>").next())
        .expect("the tool in the header");
    assert!(
        tool.contains("D14") && tool.to_lowercase().contains("ball"),
        "{tool}"
    );
    // The path runs inside this revision of the part: warnings, so amber.
    assert_eq!(readable(&profile("glue"), &page), "amber");
}
