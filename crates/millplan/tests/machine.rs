//! `--machine FILE` end to end: the complete example machine file, and both
//! older layouts, drive `speed`; a bad file is refused with its place
//! (`file:line:col: field: message`) and exit code 2 before any input is read.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

/// The paper's test conditions for `speed`.
const CUT: [&str; 6] = ["--vc", "63", "--fz", "0.125", "--ap", "0.3"];

fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/machine.toml")
}

/// `speed` on the demo's finishing program with `machine`, written as APT.
fn speed(dir: &Path, machine: &Path) -> Output {
    let d = dir.join("demo");
    if !d.exists() {
        let o = bin()
            .args(["demo", "-o", d.to_str().expect("utf8")])
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    bin()
        .args(["speed", d.join("finish.apt").to_str().expect("utf8")])
        .args(["--stl", d.join("part.stl").to_str().expect("utf8")])
        .args(CUT)
        .args(["--json", "-q", "--to", "apt"])
        .args(["--machine", machine.to_str().expect("utf8")])
        .args(["-o", dir.join("out.apt").to_str().expect("utf8")])
        .output()
        .expect("runs")
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("json")
}

#[test]
fn every_layout_drives_speed() {
    let dir = tempfile::tempdir().expect("tmp");
    // The full example: its spindle range is the one applied.
    let j = json(&speed(dir.path(), &example()));
    assert_eq!(j["machine"]["spindle_max"], 18000.0);
    assert_eq!(j["machine"]["kinematics"]["kind"], "table-ac");
    let old_speed = dir.path().join("speed.toml");
    std::fs::write(
        &old_speed,
        "spindle_min = 1000\nspindle_max = 9000\nspindle_accel = 4000\nfeed_max = 8000\n",
    )
    .expect("write");
    let j = json(&speed(dir.path(), &old_speed));
    assert_eq!(j["machine"]["spindle_max"], 9000.0);
    // The kinematics-only file of `setup`: the default spindle and feeds.
    let old_kin = dir.path().join("kin.toml");
    std::fs::write(
        &old_kin,
        "kind = \"table-ac\"\n[first]\nmin = -30\nmax = 110\n",
    )
    .expect("write");
    let j = json(&speed(dir.path(), &old_kin));
    assert_eq!(j["machine"]["spindle_max"], 18000.0);
    assert_eq!(j["machine"]["kinematics"]["first"]["max"], 110.0);
}

#[test]
fn a_bad_machine_file_is_located() {
    let dir = tempfile::tempdir().expect("tmp");
    let bad = dir.path().join("m.toml");
    std::fs::write(
        &bad,
        "[spindle]\nmin = 500\nmax = nan\naccel = 6000\n[feed]\nmax = 20000\n",
    )
    .expect("write");
    // No program is read: the machine file is checked first.
    let o = bin()
        .args(["speed", "missing.apt", "--stl", "missing.stl"])
        .args(CUT)
        .args(["--machine", bad.to_str().expect("utf8"), "-o"])
        .arg(dir.path().join("out.apt"))
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!(
            "{}:3:7: spindle.max: must be from 1 to 1000000 1/min, got NaN",
            bad.display()
        )),
        "{err}"
    );
}

/// `inspect` times a program with the machine's axis limits: the example
/// machine (5 m/s², jerk-limited) is quicker than the built-in one with its
/// conservative 1 m/s², both are at least the time at programmed feeds, and
/// the text says the time is an estimate with acceleration.
#[test]
fn inspect_estimates_the_time_with_the_machines_acceleration() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path().join("demo");
    let o = bin()
        .args(["demo", "-o", d.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let apt = d.join("finish.apt");
    let inspect = |machine: Option<&Path>, json_out: bool| {
        let mut c = bin();
        c.args(["inspect", apt.to_str().expect("utf8"), "-q"]);
        if json_out {
            c.arg("--json");
        }
        if let Some(m) = machine {
            c.args(["--machine", m.to_str().expect("utf8")]);
        }
        c.output().expect("runs")
    };
    let default = json(&inspect(None, true));
    let hsc = json(&inspect(Some(&example()), true));
    let t = |j: &serde_json::Value, k: &str| j[k].as_f64().expect(k);
    // The example's rapid rate differs, so the nominal times differ too;
    // each estimate is above its own nominal.
    assert!(t(&default, "time_s") > t(&default, "time_nominal_s"));
    assert!(t(&hsc, "time_s") >= t(&hsc, "time_nominal_s"));
    assert!(
        t(&hsc, "time_s") - t(&hsc, "time_nominal_s")
            < t(&default, "time_s") - t(&default, "time_nominal_s"),
        "{hsc}\n{default}"
    );
    let o = inspect(None, false);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("estimated with acceleration"), "{text}");
}

/// The dialect written by `speed` and `feed`, which both read a machine
/// file: the demo machine's Fanuc control where the file name does not
/// contradict it, refused with exit 2 and nothing written where it does
/// (`.mpf` is Sinumerik), and `--to` deciding over both.
#[test]
fn speed_and_feed_refuse_a_file_name_that_contradicts_the_machine() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path().join("demo");
    let o = bin()
        .args(["demo", "-q", "-o", d.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = |f: &str| d.join(f).to_str().expect("utf8").to_string();
    let (apt, stl) = (p("finish.apt"), p("part.stl"));
    let speed = [&["speed", &apt, "--stl", &stl][..], &CUT].concat();
    let feed = [
        "feed",
        &apt,
        "--stl",
        &stl,
        "--stock",
        "offset:0.3",
        "--resolution",
        "0.5",
        "--material",
        "al7075",
    ];
    for cmd in [&speed[..], &feed[..]] {
        let run = |out: &str, to: Option<&str>| {
            let mut c = bin();
            c.args(cmd)
                .args(["--machine", &p("machine.toml"), "-q", "-o"])
                .arg(dir.path().join(out));
            if let Some(t) = to {
                c.args(["--to", t]);
            }
            c.output().expect("runs")
        };
        let name = cmd[0];
        let bad = run(&format!("{name}.mpf"), None);
        assert_eq!(bad.status.code(), Some(2), "{name}");
        let msg = String::from_utf8_lossy(&bad.stderr);
        assert!(msg.contains("the machine file says"), "{name}: {msg}");
        assert!(!dir.path().join(format!("{name}.mpf")).exists(), "{name}");
        let forced = run(&format!("{name}_to.mpf"), Some("sinumerik"));
        assert!(
            forced.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&forced.stderr)
        );
        let fanuc = run(&format!("{name}.nc"), None);
        assert!(
            fanuc.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&fanuc.stderr)
        );
        let text = std::fs::read_to_string(dir.path().join(format!("{name}.nc"))).expect("written");
        assert!(
            text.starts_with('%'),
            "{name}: a Fanuc program opens with %"
        );
    }
}
