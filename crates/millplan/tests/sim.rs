//! `millplan raster` and `millplan gouge` end to end.

mod common;
use common::bin;
use std::path::Path;

fn gouge(stl: &Path, path: &Path) -> (Option<i32>, serde_json::Value) {
    let o = bin()
        .args([
            "gouge",
            "--json",
            "-q",
            "--stl",
            stl.to_str().expect("utf8"),
            path.to_str().expect("utf8"),
        ])
        .output()
        .expect("runs");
    (
        o.status.code(),
        serde_json::from_slice(&o.stdout).unwrap_or_default(),
    )
}

#[test]
fn raster_is_clean_and_a_planted_gouge_is_found() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt) = common::demo_raster(
        dir.path(),
        &["--angle", "30", "--stepover", "1.5", "--step", "0.5"],
    );
    let (code, j) = gouge(&stl, &apt);
    assert_eq!(code, Some(0), "{j}");
    assert_eq!(j["clean"], true);
    assert!(j["points_checked"].as_u64().expect("points") > 10_000);
    // Plant a gouge 0.05 mm deep in the middle of the path.
    let text = std::fs::read_to_string(&apt).expect("read");
    let lines: Vec<&str> = text.lines().collect();
    let gotos: Vec<usize> = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.starts_with("GOTO/"))
        .map(|(i, _)| i)
        .collect();
    let k = gotos[gotos.len() / 2];
    let v: Vec<f64> = lines[k][5..]
        .split(',')
        .map(|x| x.parse().expect("number"))
        .collect();
    let planted = format!("GOTO/{},{},{}", v[0], v[1], v[2] - 0.05);
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    out[k] = planted;
    let bad = dir.path().join("gouged.apt");
    std::fs::write(&bad, out.join("\n")).expect("write");
    let (code, j) = gouge(&stl, &bad);
    assert_eq!(code, Some(3), "{j}");
    let g = j["gouges"].as_array().expect("gouges");
    assert!(!g.is_empty());
    // The move into the planted point (its source line) and the move out of it
    // gouge, 0.05 mm deep at that point.
    let into = g
        .iter()
        .find(|x| x["line"].as_u64() == Some(k as u64 + 1))
        .expect("the planted line is reported");
    assert!(
        (into["depth"].as_f64().expect("depth") - 0.05).abs() < 1e-3,
        "{into}"
    );
    assert!(
        g.iter()
            .all(|x| (x["line"].as_u64().expect("line") as usize).abs_diff(k + 1) <= 1),
        "only the two moves at the point: {g:?}"
    );
}
