//! The machine-file reader under fuzzing (issue 17: "machine files with
//! `spindle_max = inf` are accepted"): the example file with any of its
//! numbers replaced by a hostile one never panics, and is either refused at
//! a line and column or read into a machine whose every number is finite.

use millplan_plan::machine::Machine;
use proptest::prelude::*;

fn example() -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/machine.toml");
    std::fs::read_to_string(p).expect("examples/machine.toml")
}

const HOSTILE: &[&str] = &[
    "inf",
    "-inf",
    "nan",
    "+nan",
    "1e308",
    "-1e308",
    "1e-320",
    "0",
    "-0.0",
    "-1",
    "1e400",
    "99999999999999999999999",
    "\"text\"",
    "[]",
    "[1e308, inf]",
    "true",
];

/// Every number of a machine as it writes itself back is finite.
fn finite_everywhere(m: &Machine) {
    let text = m.to_toml().expect("a machine that reads writes back");
    for w in text.split(|c: char| c.is_whitespace() || matches!(c, '=' | ',' | '[' | ']')) {
        let w = w.trim_matches('"');
        assert!(
            !matches!(w, "inf" | "-inf" | "+inf" | "nan" | "-nan" | "+nan"),
            "{w} in\n{text}"
        );
    }
}

/// The example with number `k` (counted over the file) replaced by `v`.
fn replace_number(src: &str, k: usize, v: &str) -> String {
    let mut out = String::new();
    let mut seen = 0;
    for line in src.lines() {
        let (code, comment) = line.split_once('#').map_or((line, ""), |(a, b)| (a, b));
        match code.split_once('=') {
            Some((key, val))
                if val.trim().parse::<f64>().is_ok() || val.trim().starts_with('[') =>
            {
                seen += 1;
                if seen == k {
                    out += &format!("{key}= {v}");
                } else {
                    out += code;
                }
            }
            _ => out += code,
        }
        if !comment.is_empty() {
            out += " #";
            out += comment;
        }
        out.push('\n');
    }
    out
}

#[test]
fn the_issue_files_are_refused_where_they_are_wrong() {
    for (src, at) in [
        (
            "[spindle]\nmin = 0\nmax = inf\naccel = 6000\n[feed]\nmax = 10000\n",
            (3, 7),
        ),
        (
            "spindle_min = 0\nspindle_max = inf\nspindle_accel = 6000\nfeed_max = 10000\n",
            (2, 15),
        ),
    ] {
        let e = Machine::from_toml(src).expect_err("refused");
        assert_eq!(e.at, Some(at), "{e}");
    }
    finite_everywhere(&Machine::from_toml(&example()).expect("the example reads"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn any_number_replaced_is_read_or_located(k in 1usize..80, v in prop::sample::select(HOSTILE)) {
        let src = replace_number(&example(), k, v);
        match Machine::from_toml(&src) {
            Ok(m) => finite_everywhere(&m),
            Err(e) => {
                let lines = src.lines().count();
                if let Some((l, c)) = e.at {
                    prop_assert!(l >= 1 && l <= lines + 1 && c >= 1, "{e}");
                }
            }
        }
    }

    #[test]
    fn arbitrary_text_never_panics(lines in prop::collection::vec(
        "(\\[[a-z.]{1,12}\\]|[a-z_]{1,14} = (inf|nan|-?[0-9.e+-]{1,12}|\"[a-z-]{0,10}\"|\\[[0-9., inf]{0,20}\\]))", 0..25)) {
        let _ = Machine::from_toml(&lines.join("\n"));
    }
}
