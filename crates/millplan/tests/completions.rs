//! `millplan completions SHELL` and `millplan man`: generated from the command
//! tree, so they name every command and option `--help` does.

use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

#[test]
fn completions_for_bash_zsh_and_fish_name_the_commands_and_options() {
    for shell in ["bash", "zsh", "fish"] {
        let o = bin().args(["completions", shell]).output().expect("runs");
        assert!(
            o.status.success(),
            "{shell}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let script = String::from_utf8_lossy(&o.stdout);
        for word in [
            "millplan",
            "reorder",
            "wd-sweep",
            "completions",
            "stl-units",
        ] {
            assert!(script.contains(word), "{shell}: no `{word}` in the script");
        }
        // `--stl`, as fish spells a long option too.
        assert!(
            script.contains("--stl") || script.contains("-l stl"),
            "{shell}: no --stl in the script"
        );
    }
    // bash reads its script without complaint.
    let o = bin().args(["completions", "bash"]).output().expect("runs");
    let check = Command::new("bash")
        .arg("-n")
        .arg("-c")
        .arg(String::from_utf8_lossy(&o.stdout).to_string())
        .output();
    if let Ok(c) = check {
        assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    }
    let o = bin()
        .args(["completions", "powershell"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn man_writes_a_page_per_command() {
    let tmp = tempfile::tempdir().expect("tmp");
    let dir = tmp.path().join("man1");
    let o = bin().args(["man", "-o"]).arg(&dir).output().expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for page in [
        "millplan.1",
        "millplan-speed.1",
        "millplan-tool-add.1",
        "millplan-thread-check.1",
    ] {
        let roff = std::fs::read_to_string(dir.join(page)).unwrap_or_default();
        assert!(
            roff.starts_with(".ie") || roff.contains(".TH"),
            "{page}: {roff:.200}"
        );
        assert!(
            roff.contains(".SH OPTIONS") || page == "millplan.1",
            "{page}"
        );
    }
    let speed = std::fs::read_to_string(dir.join("millplan-speed.1")).expect("page");
    assert!(
        speed.contains("constant") && speed.contains("stl"),
        "{speed:.400}"
    );
    // Without -o the page of millplan itself.
    let o = bin().arg("man").output().expect("runs");
    let roff = String::from_utf8_lossy(&o.stdout);
    assert!(roff.contains(".TH millplan"), "{roff:.200}");
}
