//! `millplan post` end to end: the five-axis CL samples of `../shared/data`
//! posted for a table-table A/C and a head-table B/C machine and re-read
//! with `millplan inspect`, an unreachable orientation (exit 3, nothing
//! written), and the posted five-axis G-code samples read back to tool tips
//! and axes through the kinematics.

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

fn bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_millplan"))
}
use millplan_models::kinematics::{KinKind, Kinematics};
use millplan_nc::{parse_program, MoveKind, Operation, Orient, Program, ReadOptions};
use millplan_plan::machine::Machine;
use millplan_plan::orient::ResolveOrientation;
use millplan_plan::pipeline::{self, Context};
use millplan_plan::post::{post, PostOptions};
use serde_json::Value;
use std::path::Path;

const TABLE_AC: &str = r#"name = "table A/C"
[control]
dialect = "fanuc"
[spindle]
min = 500.0
max = 18000.0
accel = 6000.0
[feed]
max = 20000.0
rapid = 30000.0
[kinematics]
kind = "table-ac"
rot_point = [0.0, 0.0, -100.0]
offset = [0.0, 5.0, 20.0]
[kinematics.first]
min = -120.0
max = 120.0
[axes.a]
velocity = 9000.0
[axes.c]
velocity = 18000.0
"#;

const HEAD_B_TABLE_C: &str = r#"name = "head B, table C"
[control]
dialect = "sinumerik"
[spindle]
min = 500.0
max = 18000.0
accel = 6000.0
[feed]
max = 20000.0
[kinematics]
kind = "head-b-table-c"
pivot = 250.0
[kinematics.first]
min = -110.0
max = 110.0
[kinematics.second]
min = -720.0
max = 720.0
"#;

fn json(o: &std::process::Output) -> Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "not JSON ({e}): {}\n{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    })
}

fn run_post(input: &Path, machine: &Path, out: &Path, extra: &[&str]) -> Value {
    let o = bin()
        .arg("post")
        .arg(input)
        .arg("--machine")
        .arg(machine)
        .arg("-o")
        .arg(out)
        .args(["--json", "-q"])
        .args(extra)
        .output()
        .expect("runs");
    assert!(
        o.status.success(),
        "{}: {}",
        input.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    json(&o)
}

/// The five-axis CL samples post for both machines, in G94 and G93, with and
/// without TCP (Heidenhain M128: the fragments have no tool number for
/// G43.4); `millplan inspect` re-reads each output and reports the rotary
/// motion the post commanded (the machine's two letters, moved).
#[test]
fn cl_samples_post_for_table_ac_and_head_table_bc_and_reinspect() {
    let samples = [
        "nx-clsf-5axis-varcontour/ust_a.cls",
        "impeller-5axis-goto-fragments/yelun.txt",
        "impeller-5axis-goto-fragments/pathdata2.txt",
        "impeller-5axis-goto-fragments/toolpathdata3.txt",
    ];
    let tmp = tempfile::tempdir().expect("tmp");
    let machines = [
        ("ac", TABLE_AC, ["A", "C"]),
        ("bc", HEAD_B_TABLE_C, ["B", "C"]),
    ];
    for (name, text, letters) in machines {
        let m = tmp.path().join(format!("{name}.toml"));
        std::fs::write(&m, text).expect("write");
        for s in samples {
            let Some(input) = shared_data::file(s) else {
                continue;
            };
            for (k, extra) in [
                &[][..],
                &["--g93"],
                &["--tcp", "--g93", "--to", "heidenhain"],
            ]
            .iter()
            .enumerate()
            {
                let out = tmp.path().join(format!("{name}-{k}.nc"));
                let j = run_post(&input, &m, &out, extra);
                for key in [
                    "blocks",
                    "flips",
                    "pole_blocks",
                    "max_orientation_deviation_deg",
                    "inserted_points",
                    "time_s",
                    "time_g94_s",
                    "time_g93_s",
                ] {
                    assert!(
                        j.get(key).is_some_and(|v| !v.is_null()),
                        "{s}: no {key} in {j}"
                    );
                }
                assert!(
                    j["max_tip_error_mm"].as_f64().expect("number") < 1e-6,
                    "{s}: {j}"
                );
                let o = bin()
                    .args(["inspect", "--json", "-q"])
                    .arg(&out)
                    .output()
                    .expect("runs");
                assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
                let i = json(&o);
                assert_eq!(i["moves"]["total"], j["blocks"], "{s} {name} {extra:?}");
                for (l, used) in letters.iter().zip(j["rotary"].as_array().expect("rotary")) {
                    let r = &i["rotary"][l];
                    assert!(r.is_object(), "{s} {name}: inspect reports no {l}: {i}");
                    // What inspect reads back is what the post reports using.
                    for (a, b) in [("min_deg", "min"), ("max_deg", "max")] {
                        let (x, y) = (r[a].as_f64().expect("n"), used[b].as_f64().expect("n"));
                        assert!((x - y).abs() < 1e-3, "{s} {name} {l}: {x} vs {y}");
                    }
                }
                assert!(
                    letters
                        .iter()
                        .any(|l| i["rotary"][l]["travel_deg"].as_f64() > Some(1.0)),
                    "{s} {name}: the rotaries move: {i}"
                );
            }
        }
    }
}

/// An orientation beyond the rotary travel: exit 3, no output, and the
/// message names the CL file, its line and the axis (JSON too).
#[test]
fn unreachable_orientation_exits_3_and_writes_nothing() {
    let Some(input) = shared_data::file("impeller-5axis-goto-fragments/yelun.txt") else {
        return;
    };
    // A short path, so that the message names it whole.
    let input = std::fs::canonicalize(input).expect("path");
    let tmp = tempfile::tempdir().expect("tmp");
    let m = tmp.path().join("m.toml");
    // yelun tilts the tool up to about 90°: A stops at ±45°.
    std::fs::write(
        &m,
        TABLE_AC.replace("min = -120.0\nmax = 120.0", "min = -45.0\nmax = 45.0"),
    )
    .expect("write");
    let out = tmp.path().join("out.nc");
    let o = bin()
        .arg("post")
        .arg(&input)
        .arg("--machine")
        .arg(&m)
        .arg("-o")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("yelun.txt:") && err.contains("axis A runs out of range"),
        "{err}"
    );
    let o = bin()
        .arg("post")
        .arg(&input)
        .arg("--machine")
        .arg(&m)
        .arg("-o")
        .arg(&out)
        .arg("--json")
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(3));
    let e: Value = serde_json::from_slice(&o.stderr).expect("JSON error");
    assert_eq!(e["error"]["exit"], 3, "{e}");
    assert!(e["error"]["line"].as_u64().is_some_and(|l| l > 1), "{e}");
    assert!(
        e["error"]["file"]
            .as_str()
            .is_some_and(|f| f.ends_with("yelun.txt")),
        "{e}"
    );
    assert!(!out.exists());
}

/// A machine file without kinematics is bad input (exit 2).
#[test]
fn a_machine_without_kinematics_is_refused() {
    let Some(input) = shared_data::file("impeller-5axis-goto-fragments/yelun.txt") else {
        return;
    };
    let tmp = tempfile::tempdir().expect("tmp");
    let m = tmp.path().join("m.toml");
    std::fs::write(
        &m,
        "[spindle]\nmin = 1.0\nmax = 2.0\naccel = 1.0\n[feed]\nmax = 100.0\n",
    )
    .expect("write");
    let o = bin()
        .arg("post")
        .arg(&input)
        .arg("--machine")
        .arg(&m)
        .args(["-o"])
        .arg(tmp.path().join("o.nc"))
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("[kinematics]"));
}

/// The tool tips and axes of a TCP program's known linear moves, as a CL
/// program (one operation per run between moves it cannot take: arcs,
/// cycles, unknown positions).
fn cl_from(p: &Program) -> Program {
    let mut out = Program::new(p.source);
    out.units = p.units;
    for op in &p.operations {
        let mut cur = Operation::default();
        for m in &op.moves {
            let take = matches!(m.kind, MoveKind::Rapid | MoveKind::Linear)
                && millplan_nc::known(m.end).is_some()
                && op.axis(m).is_some();
            if !take {
                if !cur.moves.is_empty() {
                    out.operations.push(std::mem::take(&mut cur));
                }
                continue;
            }
            let mut n = *m;
            n.orient = Some(cur.intern_orient(Orient::vector(op.axis(m).expect("axis"))));
            cur.moves.push(n);
        }
        if !cur.moves.is_empty() {
            out.operations.push(cur);
        }
    }
    out
}

/// The posted Heidenhain (M128), Sinumerik (TRAORI) and Fanuc (G43.4)
/// five-axis samples read back to tool tips and axes through the machine's
/// kinematics (the orient pass), and posting those tips and axes again under
/// TCP reproduces every one of them.
#[test]
fn posted_samples_read_back_to_tips_and_axes() {
    let samples = [
        (
            "nx-posted-gcode-samples/dmc100_heidenhain_m128_inch.ptp",
            KinKind::HeadBTableC,
        ),
        (
            "nx-posted-gcode-samples/dmu70evo_sinumerik840d_traori_inch.ptp",
            KinKind::TableBc,
        ),
        (
            "nx-posted-gcode-samples/moriseiki_nmv5000_fanuc_g43-4_mm.ptp",
            KinKind::TableBc,
        ),
        ("sinumerik-840d-spinner-u5/Achskreuz.mpf", KinKind::TableBc),
    ];
    for (s, kind) in samples {
        let Some(path) = shared_data::file(s) else {
            continue;
        };
        let text = String::from_utf8_lossy(&std::fs::read(&path).expect("read")).to_string();
        let mut p = parse_program(&text, ReadOptions::default())
            .expect("reads")
            .program;
        let kin = Kinematics {
            pivot: 250.0,
            ..Kinematics::new(kind)
        };
        let machine = Machine {
            kinematics: Some(kin.clone()),
            ..Machine::default()
        };
        let cx = Context::new(machine.clone());
        let mut pass = ResolveOrientation::new(kin.clone());
        pipeline::run(&mut [&mut pass], &mut p, &cx).expect("orient pass");
        assert!(pass.resolved > 0, "{s}: no angles resolved");
        let cl = cl_from(&p);
        let points: usize = cl.operations.iter().map(|o| o.moves.len()).sum();
        assert!(points > 20, "{s}: {points} tool tips with axes");
        let o = PostOptions {
            tcp: true,
            ..PostOptions::default()
        };
        let posted = post(&cl, &machine, &o).unwrap_or_else(|e| panic!("{s}: {e}"));
        assert!(posted.report.flips.is_empty() || posted.report.flip_moves > 0);
        // Every CL tip and axis, in order, among the posted blocks.
        for (a, b) in cl.operations.iter().zip(&posted.program.operations) {
            let mut k = 0;
            for m in &b.moves {
                let o = b.orient(m).expect("angles");
                let ang = |i: usize| o.angles[i].map(f64::to_degrees);
                let (f, sec) = match kind {
                    KinKind::TableAc => (ang(0), ang(2)),
                    _ => (ang(1), ang(2)),
                };
                let axis = kin.tool_axis(f.expect("first"), sec.expect("second"));
                if k >= a.moves.len() {
                    break;
                }
                let want = a.axis(&a.moves[k]).expect("axis");
                // Inside the pole cone (1°) the turning axis is held: the
                // axis may deviate by up to the cone.
                let tol = if want.z.abs() >= 1f64.to_radians().cos() {
                    0.0175
                } else {
                    1e-9
                };
                if (m.end - a.moves[k].end).length() < 1e-9 && (axis - want).length() < tol {
                    k += 1;
                }
            }
            assert_eq!(k, a.moves.len(), "{s}: CL point {k} is not posted");
        }
    }
}

/// A user trial: `post -o -` printed its summary on standard output after
/// the program, so the program piped to a file was not the one `-o FILE`
/// writes. The summary now goes to standard error there; the two are the
/// same bytes.
#[test]
fn a_program_on_standard_output_is_the_file_byte_for_byte() {
    let Some(input) = shared_data::file("impeller-5axis-goto-fragments/yelun.txt") else {
        return;
    };
    let tmp = tempfile::tempdir().expect("tmp");
    let m = tmp.path().join("ac.toml");
    std::fs::write(&m, TABLE_AC).expect("write");
    let file = tmp.path().join("y.nc");
    let post = |out: &Path| {
        let mut c = bin();
        c.arg("post").arg(&input).arg("--machine").arg(&m);
        let o = c.arg("-o").arg(out).args(["--to", "fanuc"]).output();
        let o = o.expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    post(&file);
    let piped = post(Path::new("-"));
    let written = std::fs::read(&file).expect("written");
    assert_eq!(
        piped.stdout,
        written,
        "{}",
        String::from_utf8_lossy(&piped.stderr)
    );
    assert!(String::from_utf8_lossy(&piped.stderr).contains("verdict"));
}
