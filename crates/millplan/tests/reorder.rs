//! `millplan reorder`: every cutting point kept exactly once, no gouging link,
//! the default method never worse than the original as it will run, the
//! optimised method never worse than the original on its documented cost.

mod common;
use common::bin;
use millplan_nc::{parse_program, MoveKind, ReadOptions};
use std::collections::BTreeMap;
use std::path::Path;

fn cutting_points(path: &Path) -> BTreeMap<[i64; 3], usize> {
    let p = parse_program(
        &std::fs::read_to_string(path).expect("read"),
        ReadOptions::default(),
    )
    .expect("reads")
    .program;
    millplan_nc::verify::verify(&p).expect("verifies");
    let mut m = BTreeMap::new();
    for op in &p.operations {
        for mv in &op.moves {
            if mv.kind == MoveKind::Linear {
                *m.entry(mv.end.to_array().map(|v| (v * 1e4).round() as i64))
                    .or_insert(0) += 1;
            }
        }
    }
    m
}

#[test]
fn reordered_paths_keep_every_point_and_never_gouge() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, path) = common::demo_raster(
        dir.path(),
        &[
            "--stepover",
            "1",
            "--step",
            "0.5",
            "--boundary",
            "18",
            "--tol",
            "0",
        ],
    );
    let original = cutting_points(&path);
    for method in ["as-run", "paper", "optimised"] {
        let out = dir.path().join(format!("{method}.apt"));
        let o = bin()
            .args([
                "reorder",
                path.to_str().expect("utf8"),
                "--stl",
                stl.to_str().expect("utf8"),
                "--method",
                method,
                "--no-speed",
                "--json",
            ])
            .args(["-o", out.to_str().expect("utf8")])
            .output()
            .expect("runs");
        assert!(
            o.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        // A permutation: every cutting point of the original, once (plunges end
        // on a cutting point too, so the set of end points is compared).
        let got = cutting_points(&out);
        assert_eq!(
            got.keys().collect::<Vec<_>>(),
            original.keys().collect::<Vec<_>>(),
            "{method}: points lost or added"
        );
        assert_eq!(j["reordered"]["points"], j["original"]["points"]);
        // No link gouges the part.
        let g = bin()
            .args([
                "gouge",
                "--json",
                "-q",
                "--stl",
                stl.to_str().expect("utf8"),
                out.to_str().expect("utf8"),
            ])
            .output()
            .expect("runs");
        assert_eq!(
            g.status.code(),
            Some(0),
            "{method}: {}",
            String::from_utf8_lossy(&g.stdout)
        );
        if method == "as-run" {
            // The default: worse than the original on none of the measures as
            // it will run, and it says whether it found better.
            let m = |k: &str, f: &str| j[k]["as_run"][f].as_f64().expect("measure");
            assert!(
                j["verdict"] == "improved" || j["verdict"] == "kept",
                "{}",
                j["verdict"]
            );
            assert_eq!(
                j["original"]["vc_deviation_share"],
                j["original"]["as_run"]["vc_deviation_share"]
            );
            assert!(
                j["reordered"]["vc_deviation_share"]
                    .as_f64()
                    .expect("share")
                    <= j["original"]["vc_deviation_share"].as_f64().expect("share")
            );
            assert!(m("reordered", "total_variation_n") <= m("original", "total_variation_n"));
            assert!(m("reordered", "time_s") <= 1.03 * m("original", "time_s"));
        }
        if method == "optimised" {
            let w = [1.0, 10.0, 100.0];
            let cost = |k: &str| -> f64 {
                (0..3)
                    .map(|i| w[i] * j["stats"][k][i].as_f64().expect("term"))
                    .sum()
            };
            assert!(
                cost("cost_reordered") <= cost("cost_original") + 1e-6,
                "{}",
                j["stats"]
            );
        }
    }
}

/// The reorder summary of `path` with `extra` options.
fn summary(stl: &Path, path: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let o = bin()
        .args(["reorder", path.to_str().expect("utf8"), "--stl"])
        .arg(stl)
        .args(["--ap", "0.3", "--vc", "63", "--fz", "0.125", "--json", "-o"])
        .arg(out)
        .args(extra)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("json")
}

#[test]
fn paper_search_lowers_the_largest_working_diameter_step() {
    // Paper 000, thesis 5, test conditions: D10 ball, ap 0.3, ae 0.25, vc 63
    // m/min, fz 0.125 mm; the free-form demo part, a zig-zag raster (its
    // turnarounds switch between uphill and downhill cutting: the largest
    // successive D_w changes of the original order, above 2 mm).
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, path) = common::demo_raster(
        dir.path(),
        &[
            "--stepover",
            "0.25",
            "--step",
            "0.25",
            "--boundary",
            "24",
            "--tol",
            "0",
        ],
    );
    let out = dir.path().join("paper.apt");
    let max = |j: &serde_json::Value, k: &str| j[k]["delta_d_w"]["max"].as_f64().expect("max");
    // The search with its step guard (the default, 0.5 mm) keeps every step
    // between points cut one after the other within the guard here, where the
    // original order has steps above 2 mm.
    let report = dir.path().join("reorder.html");
    let j = summary(
        &stl,
        &path,
        &out,
        &[
            "--method",
            "paper",
            "--report",
            report.to_str().expect("utf8"),
        ],
    );
    assert!(max(&j, "original") > 2.0, "{j}");
    // The report shows both orders: the summary as original → reordered, the
    // plots with both series, both tours.
    let html = std::fs::read_to_string(&report).expect("report written");
    assert!(html.matches("<svg").count() >= 5, "five figures");
    assert!(html.contains("Original order") && html.contains("Reordered"));
    assert!(html.contains(&format!(
        "{:.3} → {:.3}",
        max(&j, "original"),
        max(&j, "reordered")
    )));
    assert!(max(&j, "reordered") <= 0.5 + 1e-9, "{j}");
    assert!(max(&j, "reordered") < max(&j, "original"));
    assert_eq!(j["reordered"]["points"], j["original"]["points"]);
    // The published search alone still runs and keeps every point; it is
    // greedy, so at dead ends it takes large steps (reported, not asserted).
    let j0 = summary(&stl, &path, &out, &["--method", "paper", "--max-step", "0"]);
    assert_eq!(j0["reordered"]["points"], j0["original"]["points"]);
    assert!(max(&j0, "reordered") > 0.0);
}

/// The text of the report's inputs, warnings box and verdict, in the order
/// they stand before the summary table (a section missing is an empty string).
fn report_sections(html: &str) -> [String; 3] {
    let at = |needle: &str| html.find(needle);
    let summary = at("<h2>Summary</h2>").expect("a summary table");
    let ids = ["id=\"inputs\"", "id=\"warnings\"", "id=\"verdict\""].map(at);
    let mut prev = 0;
    for i in ids.iter().flatten() {
        assert!(prev <= *i && *i < summary, "out of order: {ids:?}");
        prev = *i;
    }
    let mut out: [String; 3] = Default::default();
    for k in 0..3 {
        if let Some(a) = ids[k] {
            let b = ids[k + 1..]
                .iter()
                .flatten()
                .next()
                .copied()
                .unwrap_or(summary);
            out[k] = html[a..b].to_string();
        }
    }
    out
}

/// Issue 18, item 7: the reorder report opens with its inputs (files, tool,
/// machine limits, cutting data), a warnings box and a verdict in words with
/// the measures as the JSON gives them; the spindle's range is drawn on the
/// speed plot. A part read in the wrong unit puts its off-surface points in
/// the box.
#[test]
fn reorder_report_has_inputs_warnings_and_verdict() {
    let dir = tempfile::tempdir().expect("tmp");
    let demo = dir.path().join("demo");
    assert!(bin()
        .arg("demo")
        .arg("-o")
        .arg(&demo)
        .output()
        .expect("runs")
        .status
        .success());
    for (units, off_part) in [("mm", false), ("inch", true)] {
        let report = dir.path().join(format!("reorder_{units}.html"));
        let o = bin()
            .args(["reorder", "--json", "--ap", "0.3", "--stl-units", units])
            // The machine file's control is fanuc: an APT output says so.
            .args(["--to", "apt"])
            .arg("--stl")
            .arg(demo.join("part.stl"))
            .arg(demo.join("finish.apt"))
            .arg("--machine")
            .arg(demo.join("machine.toml"))
            .arg("-o")
            .arg(dir.path().join("r.apt"))
            .arg("--report")
            .arg(&report)
            // The part read in inches stands 25 times over the path: every
            // point gouges it, refused as the input's own (exit 3) and
            // written only with --force.
            .args(off_part.then_some("--force"))
            .output()
            .expect("runs");
        let code = if off_part { 3 } else { 0 };
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{err}");
        assert_eq!(err.contains("(the input's own fault)"), off_part, "{err}");
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        let html = std::fs::read_to_string(&report).expect("report");
        let [inputs, warnings, verdict] = report_sections(&html);
        for said in [
            "finish.apt",
            "part.stl",
            "T1",
            "spindle 500–18000 1/min, acceleration 6000 1/min/s",
            "vc 63 m/min, fz 0.125 mm, 2 flutes, ap 0.3 mm",
            "as-run",
        ] {
            assert!(inputs.contains(said), "{units}: {said} in {inputs}");
        }
        // The demo part is an open relief: its border is a mesh defect.
        assert!(warnings.contains("open edges"), "{units}: {warnings}");
        assert_eq!(
            warnings.contains("do not touch the part within tolerance"),
            off_part,
            "{units}: {warnings}"
        );
        let share = |k: &str| {
            100.0
                * j[k]["as_run"]["vc_deviation_share"]
                    .as_f64()
                    .expect("share")
        };
        let word = match j["verdict"].as_str() {
            Some("improved") => "Improved:",
            Some("kept") => "Kept:",
            v => panic!("verdict {v:?}"),
        };
        assert!(verdict.contains(word), "{units}: {verdict}");
        if word == "Improved:" {
            let shares = format!("{:.1} % → {:.1} %", share("original"), share("reordered"));
            assert!(verdict.contains(&shares), "{units}: {shares} in {verdict}");
            let time = |k: &str| j[k]["as_run"]["time_s"].as_f64().expect("time");
            let times = format!("time {:.1} → {:.1} s", time("original"), time("reordered"));
            assert!(verdict.contains(&times), "{units}: {times} in {verdict}");
        }
        assert!(verdict.contains("Look at the warnings above"), "{verdict}");
        assert!(
            html.contains("spindle maximum") && html.contains("spindle minimum"),
            "the spindle's range drawn"
        );
    }
}
