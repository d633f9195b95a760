//! Issue 37, "each dialect's modes read, kept through `convert`, and shown
//! by `inspect`": per dialect, a program with an exact stop and a blend
//! within a tolerance is converted to its own dialect (the modes' words
//! kept), and `inspect` of it with the LinuxCNC 2.9 planner names the
//! planner and the time under each mode. The amounts the estimate changes
//! by are checked against closed forms in millplan-plan's
//! `tests/path_modes.rs`.

fn bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_millplan"))
}

const MACHINE: &str = "[control]\nplanner = \"linuxcnc-2.9\"\n[spindle]\nmin = 0\nmax = 24000\naccel = 10000\n[feed]\nmax = 12000\nrapid = 12000\n";

/// (file name, source, the words `convert` must keep, the modes `inspect`
/// must list with their blocks)
type Case = (
    &'static str,
    &'static str,
    &'static [&'static str],
    &'static [(&'static str, usize)],
);

const CASES: &[Case] = &[
    (
        "lc.ngc",
        "G21 G90 G17\nG0 X0 Y0 Z0\nG61\nG1 X50 F3000\nG1 Y50\nG64 P0.01\nG1 X0\nG1 Y0\nM2\n",
        &["G61", "G64 P0.01"],
        &[("exact stop", 2), ("blend 0.01 mm", 2)],
    ),
    (
        "fanuc.nc",
        "%\nO0001\nG21 G90 G17\nG0 X0 Y0 Z0\nG61\nG1 X50 F3000\nG1 Y50\nG64\nG1 X0\nG1 Y0\nM30\n%\n",
        &["G61", "G64"],
        &[("exact stop", 2), ("blend", 2)],
    ),
    (
        "sin.mpf",
        "G71 G90 G17\nG0 X0 Y0 Z0\nG60\nG1 X50 F3000\nG1 Y50\nCTOL=0.01 G642\nG1 X0\nG1 Y0\nM30\n",
        &["G60", "G642 CTOL=0.01"],
        &[("exact stop", 2), ("blend 0.01 mm", 2)],
    ),
    (
        "tnc.h",
        "0 BEGIN PGM T MM\n1 L X+0 Y+0 Z+0 FMAX\n2 L X+50 F3000\n3 CYCL DEF 32.0 TOLERANCE\n4 CYCL DEF 32.1 T0.01\n5 L Y+50\n6 L X+0\n7 END PGM T MM\n",
        &["CYCL DEF 32.1 T0.01"],
        &[("blend", 1), ("blend 0.01 mm", 2)],
    ),
];

#[test]
fn each_dialect_keeps_its_modes_through_convert_and_inspect_shows_them() {
    let dir = tempfile::tempdir().expect("tmp");
    std::fs::write(dir.path().join("m.toml"), MACHINE).expect("machine");
    for (name, src, words, modes) in CASES {
        std::fs::write(dir.path().join(name), src).expect("write");
        let out = format!("out-{name}");
        let o = bin()
            .current_dir(dir.path())
            .args(["convert", name, "-o", &out, "-q"])
            .output()
            .expect("runs");
        assert_eq!(
            o.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let text = std::fs::read_to_string(dir.path().join(&out)).expect("written");
        for w in *words {
            assert!(text.contains(w), "{name}: `{w}` not kept:\n{text}");
        }
        let o = bin()
            .current_dir(dir.path())
            .args(["inspect", &out, "--machine", "m.toml"])
            .output()
            .expect("runs");
        let shown = String::from_utf8_lossy(&o.stdout);
        assert_eq!(o.status.code(), Some(0), "{name}: {shown}");
        assert!(
            shown.contains("planner     linuxcnc-2.9"),
            "{name}: {shown}"
        );
        // `    MODE (18 wide)   TIME s  N blocks`
        for (m, n) in *modes {
            let line = shown
                .lines()
                .find(|l| l.get(4..22).is_some_and(|x| x.trim() == *m) && l.contains(" s  "))
                .unwrap_or_else(|| panic!("{name}: no time under `{m}`:\n{shown}"));
            assert!(line.ends_with(&format!(" {n} blocks")), "{name}: {line}");
        }
    }
}
