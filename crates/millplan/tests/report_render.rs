//! Opt-in: the HTML report renders in headless Chromium (Debian's `chromium`).
//! Run with `cargo test -p millplan --test report_render -- --ignored`; `.ci/run`
//! does when it could install Chromium.

use std::process::Command;

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
    let out = Command::new("chromium")
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
        .arg(format!(
            "--user-data-dir={}",
            dir.path().join("profile").display()
        ))
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("file://{}", demo.join("report.html").display()))
        .output()
        .expect("chromium runs");
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
