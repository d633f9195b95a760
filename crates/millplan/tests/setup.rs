//! `millplan setup` end to end: parts with known answers.

use millplan_geom::{DMat3, DVec3, TriMesh};
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

/// A 40 mm cube (closed, or without its bottom face), rotated by `r`, written as binary STL.
fn cube(dir: &Path, name: &str, r: DMat3, bottom: bool) -> PathBuf {
    let s = 40.0;
    let faces: [(DVec3, [[f64; 3]; 4]); 6] = [
        (
            DVec3::Z,
            [[0.0, 0.0, s], [s, 0.0, s], [s, s, s], [0.0, s, s]],
        ),
        (
            -DVec3::Z,
            [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, s, 0.0], [0.0, s, 0.0]],
        ),
        (
            DVec3::X,
            [[s, 0.0, 0.0], [s, s, 0.0], [s, s, s], [s, 0.0, s]],
        ),
        (
            -DVec3::X,
            [[0.0, 0.0, 0.0], [0.0, s, 0.0], [0.0, s, s], [0.0, 0.0, s]],
        ),
        (
            DVec3::Y,
            [[0.0, s, 0.0], [s, s, 0.0], [s, s, s], [0.0, s, s]],
        ),
        (
            -DVec3::Y,
            [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, 0.0, s], [0.0, 0.0, s]],
        ),
    ];
    let mut soup = Vec::new();
    for (n, q) in faces {
        if n == -DVec3::Z && !bottom {
            continue;
        }
        let [a, b, c, d] = q.map(|p| r * DVec3::from_array(p));
        let n = r * n;
        if (b - a).cross(c - a).dot(n) > 0.0 {
            soup.extend([[a, b, c], [a, c, d]]);
        } else {
            soup.extend([[a, c, b], [a, d, c]]);
        }
    }
    let mut bytes = Vec::new();
    millplan_geom::stl::write_binary_stl(&TriMesh::from_soup(&soup).0, "cube", &mut bytes);
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write");
    p
}

fn setup(stl: &Path, args: &[&str]) -> (Option<i32>, serde_json::Value) {
    let o = bin()
        .args([
            "setup",
            "--json",
            "-q",
            "--stl",
            stl.to_str().expect("utf8"),
        ])
        .args(args)
        .output()
        .expect("runs");
    (
        o.status.code(),
        serde_json::from_slice(&o.stdout).unwrap_or_default(),
    )
}

/// `setup` with the case's arguments followed by the test's common ones.
fn setup2(stl: &Path, args: &[&str], common: &[&str]) -> (Option<i32>, serde_json::Value) {
    setup(stl, &[args, common].concat())
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().expect("number")
}

#[test]
fn cube_on_a_ca_table_needs_a_tilt_near_ninety_degrees() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = cube(dir.path(), "cube.stl", DMat3::IDENTITY, true);
    // An 80° clearance: each face is cut within 10° of its normal.
    let common = ["--clearance", "80", "--ignore-bottom"];
    let (code, j) = setup2(
        &p,
        &["--type", "ca", "--range1", "0,95", "--range2", "free"],
        &common,
    );
    assert_eq!(code, Some(0), "{j}");
    assert_eq!(j["feasible"], true);
    assert_eq!(j["ignored"], 2);
    assert!(
        (f(&j["setup"][2][2]) - 1.0).abs() < 1e-9,
        "kept upright: {}",
        j["setup"]
    );
    let a = &j["required"]["a"];
    assert!(f(&a[0]) == 0.0 && (80.0..90.0).contains(&f(&a[1])), "{a}");
    // Up to 60° of tilt the four walls are out of reach.
    let (code, j) = setup2(&p, &["--type", "ca", "--range1", "0,60"], &common);
    assert_eq!(code, Some(3));
    assert_eq!(j["feasible"], false);
    assert_eq!(j["out_of_reach"].as_array().expect("list").len(), 8);
    // Every face is seen from somewhere: no range is out of the question.
    assert!(j["unreachable"].as_array().expect("list").is_empty());
    // ... and the ranges that would do are reported: A up to the walls' 80-90°.
    let w = &j["would_do"]["a"];
    assert!(
        f(&w[0]) == 0.0 && (80.0..90.0).contains(&f(&w[1])),
        "{}",
        j["would_do"]
    );
    // Two tilting axes of ±95° reach everything; ±30° does not.
    let (code, _) = setup2(
        &p,
        &["--type", "ab", "--range1", "-95,95", "--range2", "-95,95"],
        &common,
    );
    assert_eq!(code, Some(0));
    let (code, _) = setup2(
        &p,
        &["--type", "ab", "--range1", "-30,30", "--range2", "-30,30"],
        &common,
    );
    assert_eq!(code, Some(3));
    // Tool mode: nothing of a convex cube is in the way of a D10 ball-end mill.
    let (code, j) = setup2(
        &p,
        &["--type", "ca", "--range1", "0,95", "--tool", "10,50"],
        &common,
    );
    assert_eq!((code, j["mode"].as_str()), (Some(0), Some("tool")), "{j}");
    // Without --ignore-bottom the bottom face needs the tool from below.
    let (code, j) = setup(
        &p,
        &["--type", "ca", "--range1", "0,95", "--clearance", "80"],
    );
    assert_eq!(
        (code, j["feasible"].clone()),
        (Some(3), serde_json::json!(false))
    );
}

#[test]
fn a_tilted_part_is_turned_back_upright() {
    let dir = tempfile::tempdir().expect("tmp");
    // An open box (five faces) lying in the file tilted 30° about X: as given,
    // one wall needs 120° of tilt, more than the machine has.
    let tilt = DMat3::from_rotation_x(30f64.to_radians());
    let p = cube(dir.path(), "tilted.stl", tilt, false);
    let out = dir.path().join("upright.stl");
    let html = dir.path().join("setup.html");
    let o = bin()
        .args([
            "setup",
            "--json",
            "-q",
            "--stl",
            p.to_str().expect("utf8"),
            "--type",
            "ca",
            "--range1",
            "-100,100",
        ])
        .args(["--clearance", "80", "-o", out.to_str().expect("utf8")])
        .args(["--report", html.to_str().expect("utf8")])
        .output()
        .expect("runs");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    // Every face keeps a direction within 10° of its normal; the best setup puts
    // the cube's own axes along the table's, up or down.
    assert_eq!(o.status.code(), Some(0), "{j}");
    let s = DMat3::from_cols_array_2d(&[0, 1, 2].map(|i| [0, 1, 2].map(|k| f(&j["setup"][i][k]))))
        .transpose();
    let up = s * (tilt * DVec3::Z);
    assert!(
        up.z.abs() > 0.95 || up.x.abs() > 0.95 || up.y.abs() > 0.95,
        "{up}"
    );
    assert!(f(&j["max_tilt_deg"]) < 100.0);
    let page = std::fs::read_to_string(&html).expect("report");
    assert_eq!(page.matches("<svg").count(), 2);
    assert!(page.contains("feasible in one setup</td><td>yes"));
    // The rotated part is written and reads back with all its facets.
    let o = bin()
        .args(["inspect", "--json", out.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(o.status.success());
    // It never overwrites its input.
    let o = bin()
        .args([
            "setup",
            "-q",
            "--stl",
            p.to_str().expect("utf8"),
            "--type",
            "ca",
            "-o",
            p.to_str().expect("utf8"),
        ])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn bad_ranges_are_rejected_with_exit_2() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = cube(dir.path(), "cube.stl", DMat3::IDENTITY, true);
    let bad = [
        ("--tool", "0,30"),
        ("--tool", "10"),
        ("--tool", "10,30,40"),
        ("--tool", "-6,30"),
    ];
    let bad = bad.into_iter().chain([
        ("--range1", "95,0"),
        ("--range1", "abc"),
        ("--range1", "1,2,3"),
    ]);
    for (flag, v) in bad {
        let o = bin()
            .args([
                "setup",
                "--stl",
                p.to_str().expect("utf8"),
                "--type",
                "ca",
                flag,
                v,
            ])
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(2), "{flag} {v}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(flag),
            "{flag} {v}"
        );
    }
    let o = bin()
        .args(["setup", "--stl", p.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn an_inside_out_part_is_turned_outward() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = cube(dir.path(), "cube.stl", DMat3::IDENTITY, true);
    // The same cube with every facet wound the other way.
    let mesh = millplan_geom::stl::read_stl(&std::fs::read(&p).expect("read"))
        .expect("stl")
        .0;
    let mut inv = mesh.clone();
    for t in &mut inv.triangles {
        t.swap(1, 2);
    }
    let mut bytes = Vec::new();
    millplan_geom::stl::write_binary_stl(&inv, "inside out", &mut bytes);
    let q = dir.path().join("inside_out.stl");
    std::fs::write(&q, bytes).expect("write");
    let args = [
        "--type",
        "ca",
        "--range1",
        "0,95",
        "--clearance",
        "80",
        "--ignore-bottom",
    ];
    let (c1, j1) = setup(&p, &args);
    let (c2, j2) = setup(&q, &args);
    assert_eq!((c1, c2), (Some(0), Some(0)));
    assert_eq!(
        (j1["flipped"].clone(), j2["flipped"].clone()),
        (serde_json::json!(false), serde_json::json!(true))
    );
    assert_eq!(j1["max_tilt_deg"], j2["max_tilt_deg"]);
}

#[test]
fn moulds_from_the_shared_data_run_for_both_machine_types() {
    let Some(p) = shared_data::file("stl-pitfalls-opencamlib/ktoolcor.stl") else {
        return;
    };
    for args in [
        ["--type", "ca", "--range1", "-30,110"],
        ["--type", "ab", "--range1", "-120,120"],
    ] {
        let (code, j) = setup(
            &p,
            &[
                &args[..],
                &["--ignore-bottom", "--grid", "icosphere", "--cells", "320"],
            ]
            .concat(),
        );
        assert!(matches!(code, Some(0) | Some(3)), "{code:?}");
        assert_eq!(j["cells"], 320);
        assert_eq!(j["feasible"], code == Some(0));
        let s = &j["setup"];
        let m = DMat3::from_cols_array_2d(&[0, 1, 2].map(|i| [0, 1, 2].map(|k| f(&s[i][k]))));
        assert!((m.determinant() - 1.0).abs() < 1e-9, "a rotation: {s}");
    }
}

#[test]
fn the_bezier_vase_runs_end_to_end_for_both_machine_types() {
    let dir = tempfile::tempdir().expect("tmp");
    let mesh = millplan_geom::bezier::tessellate_patches(&millplan_geom::bezier::vase(), 16);
    let mut bytes = Vec::new();
    millplan_geom::stl::write_binary_stl(&mesh, "vase", &mut bytes);
    let p = dir.path().join("vase.stl");
    std::fs::write(&p, bytes).expect("write");
    let html = dir.path().join("vase.html");
    let common = ["--ignore-bottom", "--report", html.to_str().expect("utf8")];
    // The lowest row of belly facets rises 26.3° (profile (40,0)→(62,8), first
    // 1/16): its normal is 153.7° from +Z, so no direction under 63.7° sees it.
    let (code, j) = setup2(&p, &["--type", "ca", "--range1", "-30,110"], &common);
    assert_eq!(code, Some(0), "{j}");
    let t = f(&j["max_tilt_deg"]);
    assert!((63.7..75.0).contains(&t), "{t}");
    assert!(f(&j["setup"][2][2]) > 0.99, "stays upright: {}", j["setup"]);
    assert!(std::fs::read_to_string(&html)
        .expect("report")
        .contains("<svg"));
    let (code, j) = setup2(&p, &["--type", "ca", "--range1", "0,60"], &common);
    assert_eq!(code, Some(3));
    assert!(!j["out_of_reach"].as_array().expect("list").is_empty());
    let (code, j) = setup2(
        &p,
        &[
            "--type", "ab", "--range1", "-120,120", "--range2", "-120,120",
        ],
        &common,
    );
    assert_eq!(code, Some(0), "{j}");
    let (code, _) = setup2(
        &p,
        &["--type", "ab", "--range1", "-45,45", "--range2", "-45,45"],
        &common,
    );
    assert_eq!(code, Some(3));
}

#[test]
fn cube_on_its_corner_needs_a_tilt_of_35_26_degrees_on_every_grid() {
    // Every face of a closed cube sees its open half-space; standing on a
    // corner, the faces turned away begin atan(1/√2) = 35.26° from the C axis.
    let dir = tempfile::tempdir().expect("tmp");
    let p = cube(dir.path(), "cube.stl", DMat3::IDENTITY, true);
    let exact = (1.0f64 / 2f64.sqrt()).atan().to_degrees();
    for grid in ["latlon", "icosphere", "healpix"] {
        let run = |range: &str| setup(&p, &["--type", "ca", "--range1", range, "--grid", grid]);
        let (code, j) = run("-36,36");
        assert_eq!(
            (code, &j["feasible"]),
            (Some(0), &serde_json::json!(true)),
            "{grid}: {j}"
        );
        assert!((f(&j["max_tilt_deg"]) - exact).abs() < 0.5, "{grid}: {j}");
        // Out of reach at ±34.5°, and the JSON says what would do: the least
        // tilt of any setup, in that setup; nothing is out of every range.
        let (code, j) = run("-34.5,34.5");
        assert_eq!(
            (code, &j["feasible"]),
            (Some(3), &serde_json::json!(false)),
            "{grid}: {j}"
        );
        let a = &j["required"]["a"];
        assert!(
            f(&a[0]) == 0.0 && (f(&a[1]) - exact).abs() < 0.5,
            "{grid}: {a}"
        );
        assert!(f(&j["usage"]) > 1.0);
        assert!(j["unreachable"].as_array().expect("list").is_empty());
        assert!(!j["out_of_reach"].as_array().expect("list").is_empty());
    }
}

/// Issue 18, item 7: the setup report opens with its inputs (the part, the
/// machine's rotary ranges, the mode, the sphere grid), a warnings box
/// (facets out of reach, a mesh's open edges) and a verdict in words (feasible
/// or not, the ranges the part needs, the setup chosen); the machine's limits
/// are drawn on the direction map.
#[test]
fn setup_report_has_inputs_warnings_and_verdict() {
    let dir = tempfile::tempdir().expect("tmp");
    // A cube without its bottom face: an open mesh.
    let p = cube(dir.path(), "open.stl", DMat3::IDENTITY, false);
    let html = dir.path().join("setup.html");
    let report = [
        "--clearance",
        "80",
        "--report",
        html.to_str().expect("utf8"),
    ];
    // Two tilting axes of ±30° do not reach the walls.
    let (code, j) = setup2(
        &p,
        &["--type", "ab", "--range1", "-30,30", "--range2", "-30,30"],
        &report,
    );
    assert_eq!(code, Some(3), "{j}");
    let page = std::fs::read_to_string(&html).expect("report");
    let at = |needle: &str| page.find(needle).unwrap_or_else(|| panic!("no {needle}"));
    let (inputs, warnings, verdict, summary) = (
        at("id=\"inputs\""),
        at("id=\"warnings\""),
        at("id=\"verdict\""),
        at("<h2>Summary</h2>"),
    );
    assert!(inputs < warnings && warnings < verdict && verdict < summary);
    let head = &page[inputs..warnings];
    for said in [
        "open.stl",
        "TableAb: A -30° … 30°, B -30° … 30°",
        "line of sight",
        "clearance 80°",
    ] {
        assert!(head.contains(said), "{said} in {head}");
    }
    let boxed = &page[warnings..verdict];
    let out = j["out_of_reach"].as_array().expect("list").len();
    assert!(out > 0, "{j}");
    assert!(
        boxed.contains(&format!("{out} facets (")) && boxed.contains("out of the machine's reach"),
        "{boxed}"
    );
    assert!(boxed.contains("open edges"), "{boxed}");
    let said = &page[verdict..summary];
    assert!(said.contains("Not feasible in one setup"), "{said}");
    let r = &j["required"];
    let needs = format!(
        "The part needs A {:.3}° … {:.3}° and B {:.3}° … {:.3}°",
        f(&r["a"][0]),
        f(&r["a"][1]),
        f(&r["b"][0]),
        f(&r["b"][1])
    )
    .replace("-0.000", "0.000");
    assert!(said.contains(&needs), "{needs} in {said}");
    assert!(said.contains("a second setup"), "{said}");
    // The limits of both axes bound the reachable directions.
    assert!(page.contains("class=\"limit\""), "the limits drawn");
    // Feasible on ±95°: the verdict says so, and the box holds only the mesh.
    let (code, j) = setup2(
        &p,
        &["--type", "ab", "--range1", "-95,95", "--range2", "-95,95"],
        &report,
    );
    assert_eq!(code, Some(0), "{j}");
    let page = std::fs::read_to_string(&html).expect("report");
    assert!(page.contains("Feasible in one setup"));
    assert!(!page.contains("out of the machine's reach"));
}
