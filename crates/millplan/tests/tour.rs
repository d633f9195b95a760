//! README's five-minute tour runs as written: the block under "Five-minute
//! tour" is taken from README.md itself and run by bash, line by line, with
//! `B` the binary under test, from a fresh folder standing in for the
//! repository root. Every command must exit 0 (`set -e`) and write what it
//! says it writes.

use std::path::Path;
use std::process::Command;

/// The shell block of README.md's "Five-minute tour" section.
fn tour_block() -> String {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"))
            .expect("README.md");
    let section = readme
        .split("## Five-minute tour")
        .nth(1)
        .expect("README has a five-minute tour");
    let body = section
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("\n```").next())
        .expect("the tour is a ```sh block");
    body.to_string()
}

/// The tour as a script for the binary under test: the build step and the
/// line that names the binary are replaced by `B` set beforehand.
fn script(block: &str) -> String {
    let mut s = String::from("set -eu\n");
    for line in block.lines() {
        if line.starts_with("cargo build") || line.starts_with("B=") {
            continue;
        }
        s.push_str(line);
        s.push('\n');
    }
    s
}

#[test]
fn readme_tour_runs_as_written() {
    let block = tour_block();
    assert!(block.contains("B=$PWD/target/release/millplan"), "{block}");
    let commands = block.lines().filter(|l| l.starts_with("$B ")).count();
    assert!(commands >= 12, "{commands} commands in the tour");
    let root = tempfile::tempdir().expect("tmp");
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!("{}\necho TOUR-DONE", script(&block)))
        .env("B", env!("CARGO_BIN_EXE_millplan"))
        .current_dir(root.path())
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stdout.contains("TOUR-DONE"),
        "the tour stopped ({:?}):\n{stdout}\n{stderr}",
        out.status
    );
    let demo = root.path().join("millplan-demo");
    for f in [
        "part.stl",
        "finish.apt",
        "machine.toml",
        "raster_0.apt",
        "raster_45.apt",
        "raster_90.apt",
        "finish.ir",
        "finish.h",
        "finish_vc.nc",
        "vc_points.csv",
        "vc_report.html",
        "sweep/wd_sweep.csv",
        "r45.apt",
        "reordered.apt",
        "reorder.html",
    ] {
        let p = demo.join(f);
        let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        assert!(len > 0, "{} was not written", p.display());
    }
    for said in [
        "wrote finish.h",
        "wrote      finish_vc.nc (fanuc)",
        "wrote sweep/wd_sweep.csv",
        "wrote r45.apt",
        "wrote reordered.apt",
        "moves checked",
        "M8x1.25-6g: D2 7.100 mm",
    ] {
        assert!(
            stdout.contains(said) || stderr.contains(said),
            "the tour did not say `{said}`:\n{stdout}\n{stderr}"
        );
    }
}
