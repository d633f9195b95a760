//! Golden tests: every input under `tests/golden/` is read and its IR printed; the
//! print must equal the `.ir` file beside it and read back to the same program. `UPDATE_GOLDEN=1 cargo test` rewrites
//! them after a deliberate change (review the diff).

use millplan_nc::{parse_program, text, verify::verify, ReadOptions};
use std::path::Path;

#[test]
fn golden_inputs_print_their_expected_ir() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let mut seen = 0;
    let mut failures = Vec::new();
    let mut entries: Vec<_> = std::fs::read_dir(&dir)
        .expect("golden dir")
        .flatten()
        .map(|e| e.path())
        .collect();
    entries.sort();
    for path in entries {
        if path.extension().map(|e| e == "ir").unwrap_or(true) {
            continue;
        }
        seen += 1;
        let src = std::fs::read_to_string(&path).expect("read");
        let parsed = parse_program(&src, ReadOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        verify(&parsed.program).unwrap_or_else(|v| panic!("{}: {v:?}", path.display()));
        let mut got = text::print(&parsed.program);
        // The text form reads back to the same program.
        let back = text::parse(&got).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(back, parsed.program, "{}: text round trip", path.display());
        for d in &parsed.diagnostics {
            got.push_str(&format!("diagnostic {d}\n"));
        }
        let want_path = path.with_extension(format!(
            "{}.ir",
            path.extension().and_then(|e| e.to_str()).unwrap_or("")
        ));
        if std::env::var_os("UPDATE_GOLDEN").is_some() {
            std::fs::write(&want_path, &got).expect("write golden");
            continue;
        }
        let want = std::fs::read_to_string(&want_path).unwrap_or_default();
        if want != got {
            failures.push(format!(
                "{}\n--- want\n{want}\n--- got\n{got}",
                path.display()
            ));
        }
    }
    assert!(seen >= 8, "golden inputs missing");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_move_count_hint_never_changes_what_is_read() {
    // Every golden input (APT, G-code dialects, Heidenhain), read with no
    // hint, a hint far too small, about right, and one too large to reserve:
    // the same program each time.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let mut seen = 0;
    for path in std::fs::read_dir(&dir)
        .expect("golden dir")
        .flatten()
        .map(|e| e.path())
    {
        if path.extension().map(|e| e == "ir").unwrap_or(true) {
            continue;
        }
        let src = std::fs::read_to_string(&path).expect("read");
        let read = |expect_moves: usize| {
            let opts = ReadOptions {
                expect_moves,
                ..ReadOptions::default()
            };
            parse_program(&src, opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        };
        let plain = read(0);
        for hint in [1, src.len() / 20, usize::MAX / 2] {
            let hinted = read(hint);
            assert_eq!(
                hinted.program,
                plain.program,
                "{} with hint {hint}",
                path.display()
            );
            assert_eq!(
                format!("{:?}", hinted.diagnostics),
                format!("{:?}", plain.diagnostics)
            );
        }
        seen += 1;
    }
    assert!(seen >= 8, "only {seen} golden inputs");
}
