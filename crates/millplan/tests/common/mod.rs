//! Helpers shared by the end-to-end tests.

use std::path::{Path, PathBuf};
use std::process::Command;

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

/// Runs `millplan demo` into `dir/demo`, then `millplan raster` over its part
/// with a D10 ball and the given options into `dir/raster.apt`; returns the
/// part and the raster.
pub fn demo_raster(dir: &Path, options: &[&str]) -> (PathBuf, PathBuf) {
    let d = dir.join("demo");
    assert!(bin()
        .args(["demo", "-o", d.to_str().expect("utf8")])
        .output()
        .expect("runs")
        .status
        .success());
    let stl = d.join("part.stl");
    let apt = dir.join("raster.apt");
    let o = bin()
        .args([
            "raster",
            "--stl",
            stl.to_str().expect("utf8"),
            "--tool",
            "ball:10",
        ])
        .args(options)
        .args(["-o", apt.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (stl, apt)
}
