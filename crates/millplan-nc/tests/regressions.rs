//! Regression tests for the faults of issue 16 (and those found while
//! writing these tests), each named after its fault and citing the source
//! file and line it was seen at. Programs written out are read back and
//! checked against their source, never against numbers copied from a run.
//!
//! Tests on the real samples of `../shared/data/` print a `SKIPPED:` line
//! and pass when the samples are not there; the synthetic ones always run.

mod common;

use common::{read, read_sample, sample, write, written, Out, GCODE};
use millplan_nc::detect::detect;
use millplan_nc::equiv::{compare, Tolerance};
use millplan_nc::stats::summarize;
use millplan_nc::write::Target;
use millplan_nc::{
    Dialect, EventKind, FeedMode, MoveKind, Operation, Orient, Program, ReadOptions,
};

const MORI: &str = "nx-posted-gcode-samples/moriseiki_nmv5000_fanuc_g43-4_mm.ptp";
const DMU: &str = "nx-posted-gcode-samples/dmu70evo_sinumerik840d_traori_inch.ptp";
const ACHSKREUZ: &str = "sinumerik-840d-spinner-u5/Achskreuz.mpf";
const BOTTLE: &str = "sinumerik-840d-spinner-u5/Bottle_opener.mpf";
const BEAR: &str = "camotics-ballnose-relief-gcode/bear.nc";
const BOSS: &str = "swcam-apt-stl-pairs/boss.apt";
const DMC100: &str = "nx-posted-gcode-samples/dmc100_heidenhain_m128_inch.ptp";

fn parse(text: &str, what: &str) -> Program {
    read(text, ReadOptions::default(), what)
}

/// The text a target writes, refused words as comments (`lossy`), and the
/// program read back from it.
fn through(p: &Program, t: Target, lossy: bool, what: &str) -> (String, Program) {
    let text = match write(p, t, lossy) {
        Out::Text(s, _) => s,
        Out::Refused(e) => panic!("{what} -> {}: refused: {e}", t.name()),
    };
    let q = parse(&text, &format!("{what} -> {} re-read", t.name()));
    (text, q)
}

/// The words of a written block, without its block number (`12 L X+1` →
/// `L`, `X+1`; `N20 G1 X1` → `G1`, `X1`).
fn words(line: &str) -> Vec<&str> {
    let mut w: Vec<&str> = line.split_whitespace().collect();
    let numbered = |s: &str| {
        let d = s.strip_prefix('N').unwrap_or(s);
        !d.is_empty() && d.bytes().all(|c| c.is_ascii_digit())
    };
    if w.first().is_some_and(|s| numbered(s)) {
        w.remove(0);
    }
    w
}

/// Whether a block has a word of `letter` with a value (`X1`, `X=1`, `X+1`, `X.5`).
fn has_axis(line: &str, letter: char) -> bool {
    words(line).iter().any(|w| {
        let mut c = w.chars();
        c.next() == Some(letter)
            && c.next()
                .is_some_and(|d| d.is_ascii_digit() || matches!(d, '-' | '+' | '.' | '='))
    })
}

fn has_xyz(line: &str) -> bool {
    ['X', 'Y', 'Z'].iter().any(|&c| has_axis(line, c))
}

fn has_rotary(line: &str) -> bool {
    ['A', 'B', 'C'].iter().any(|&c| has_axis(line, c))
}

/// Source lines that move rotary axes only: a G0/G1 block (comments
/// stripped) with an A, B or C word and no X, Y or Z word.
fn rotary_only_lines(src: &str) -> Vec<u32> {
    src.lines()
        .enumerate()
        .filter_map(|(i, l)| {
            let code = l.split(';').next().unwrap_or("");
            let code = code.split('(').next().unwrap_or("");
            let moves = words(code)
                .iter()
                .any(|w| matches!(*w, "G0" | "G00" | "G1" | "G01"));
            (moves && has_rotary(code) && !has_xyz(code) && !code.contains("SUPA"))
                .then_some(i as u32 + 1)
        })
        .collect()
}

/// A move to where the previous move already ended, in the same orientation.
fn idle(a: &[(&Operation, &millplan_nc::Move)], i: usize) -> bool {
    let angles = |(o, m): (&Operation, &millplan_nc::Move)| o.orient(m).map(|o| o.angles);
    i > 0
        && matches!(a[i].1.kind, MoveKind::Rapid | MoveKind::Linear)
        && millplan_nc::same_position(a[i - 1].1.end, a[i].1.end)
        && angles(a[i - 1]) == angles(a[i])
        && a[i - 1].0.axis(a[i - 1].1) == a[i].0.axis(a[i].1)
}

/// For each move of `a`, the index of the move of `b` that ends where it
/// ends (on every axis `a` knows, with the same rotary angles and the same
/// kind), searched forward from the last match within a few moves; `None`
/// for a move to where the tool already stands, which a writer may leave
/// out. (With `lossy` a target may know positions its source did not: a
/// machine-coordinate block written as a comment.)
fn align(a: &Program, b: &Program) -> Vec<Option<usize>> {
    let (a, b) = (moves(a), moves(b));
    let same = |(ao, am): &(&Operation, &millplan_nc::Move),
                (bo, bm): &(&Operation, &millplan_nc::Move)| {
        let pos = (0..3).all(|k| am.end[k].is_nan() || (am.end[k] - bm.end[k]).abs() < 1e-3);
        let angles = |o: &Operation, m: &millplan_nc::Move| {
            o.orient(m).map(|o| o.angles).unwrap_or([None; 3])
        };
        let (x, y) = (angles(ao, am), angles(bo, bm));
        let rot = (0..3).all(|k| match (x[k], y[k]) {
            (Some(p), Some(q)) => (p - q).abs() < 1e-6,
            (None, _) => true,
            (Some(_), None) => false,
        });
        pos && rot && am.kind.name() == bm.kind.name()
    };
    let mut j = 0;
    (0..a.len())
        .map(|i| {
            if idle(&a, i) {
                return None;
            }
            let k = (j..(j + 4).min(b.len())).find(|&k| same(&a[i], &b[k]))?;
            j = k + 1;
            Some(k)
        })
        .collect()
}

/// Line `n` (1-based) of a text.
fn line_of(text: &str, n: u32) -> &str {
    text.lines().nth(n as usize - 1).unwrap_or("")
}

/// The moves of a program in order, with their operation.
fn moves(p: &Program) -> Vec<(&Operation, &millplan_nc::Move)> {
    p.operations
        .iter()
        .flat_map(|op| op.moves.iter().map(move |m| (op, m)))
        .collect()
}

// ---------------------------------------------------------------------------
// Positions the source never commanded.

/// Issue 16: "The CAMotics relief's `G0Z20` then `G0X0Y0` — a Z-first
/// retract from wherever the tool is — becomes one diagonal `G0 X0. Y0. Z20.`"
/// bear.nc:4 `G0Z20.000`, bear.nc:5 `G0X0.000Y0.000S15000M3`: two blocks in
/// every G-code target, the first with Z alone, the second with X and Y and
/// no Z; read back, X and Y are unknown until the second.
#[test]
fn bear_z_first_retract_stays_z_first() {
    let Some(p) = read_sample(BEAR) else { return };
    let first = &p.operations[0].moves[..2];
    assert_eq!((first[0].line, first[1].line), (4, 5), "bear.nc:4-5");
    for t in GCODE {
        let (text, q) = through(&p, t, false, BEAR);
        let m = &q.operations[0].moves;
        let (z, xy) = (line_of(&text, m[0].line), line_of(&text, m[1].line));
        assert!(
            has_axis(z, 'Z') && !has_axis(z, 'X') && !has_axis(z, 'Y'),
            "{}: `{z}`",
            t.name()
        );
        assert!(
            has_axis(xy, 'X') && has_axis(xy, 'Y') && !has_axis(xy, 'Z'),
            "{}: `{xy}`",
            t.name()
        );
        assert!(m[0].end.x.is_nan() && m[0].end.y.is_nan(), "{}", t.name());
        assert_eq!(m[0].end.z, first[0].end.z, "{}", t.name());
        assert_eq!(m[1].end, first[1].end, "{}", t.name());
    }
}

/// The same on a program of our own, into every G-code target: a move from
/// an unknown position names only the axes its source named, and a block in
/// machine coordinates (`G53`) forgets X, Y and Z again.
#[test]
fn moves_from_unknown_positions_name_only_their_source_axes() {
    let src = "G21 G17 G90 G94\nT1 M6\nG0 Z20\nG0 X0 Y0 S10000 M3\nG1 Z-1 F500\n\
               G53 G0 Z0\nG0 X5\nG0 Y5 Z2\n";
    let p = parse(src, "unknown start");
    for t in GCODE {
        let Out::Text(text, warnings) = write(&p, t, true) else {
            panic!("{}: lossy refused", t.name())
        };
        let q = parse(&text, t.name());
        if warnings.is_empty() {
            compare(&p, &q, &Tolerance::default()).unwrap_or_else(|e| panic!("{}: {e}", t.name()));
        }
        let written: Vec<(&str, bool, bool, bool)> = moves(&q)
            .iter()
            .map(|(_, m)| {
                let l = line_of(&text, m.line);
                (l, has_axis(l, 'X'), has_axis(l, 'Y'), has_axis(l, 'Z'))
            })
            .collect();
        let axes: Vec<_> = written.iter().map(|w| (w.1, w.2, w.3)).collect();
        assert_eq!(axes.len(), 5, "{}: {written:?}", t.name());
        // Z alone, then X and Y without Z, then Z.
        assert_eq!(
            axes[..3],
            [
                (false, false, true),
                (true, true, false),
                (false, false, true)
            ],
            "{}: {written:?}",
            t.name()
        );
        // After the machine-coordinate block Z is unknown: `G0 X5` names X
        // (Y, still known, may be stated again), never Z.
        assert!(axes[3].0 && !axes[3].2, "{}: {written:?}", t.name());
        assert!(axes[4].1 && axes[4].2, "{}: {written:?}", t.name());
    }
}

// ---------------------------------------------------------------------------
// Words dropped or changed.

/// Issue 16: "`G05.1 Q1` and `G05.1 Q0` (AI contour control on/off) both
/// become `G5.1`." moriseiki…ptp:12 `G05.1 Q1`, :292 `G05.1 Q0`: into Fanuc
/// every one keeps its Q word, as many of each as the source has.
#[test]
fn ai_contour_control_keeps_its_q_word() {
    let Some(src) = sample(MORI) else { return };
    let p = read(&src, common::options_for(MORI), MORI);
    let text = written(&p, Target::Fanuc, MORI);
    for (q, spelled) in [("Q1", "G5.1 Q1"), ("Q0", "G5.1 Q0")] {
        let want = src
            .lines()
            .filter(|l| l.trim() == format!("G05.1 {q}"))
            .count();
        assert!(want > 0, "{MORI}: no `G05.1 {q}`");
        let got = text.lines().filter(|l| l.trim() == spelled).count();
        assert_eq!(got, want, "`{spelled}` blocks in the Fanuc output");
    }
    assert!(
        !text.lines().any(|l| l.trim() == "G5.1"),
        "a G5.1 without its Q"
    );
}

/// Issue 16: "G-code → APT drops the rotary axes of five-axis moves (a
/// PPRINT instead; 177 five-axis moves become 0 on re-read)." APT has no
/// machine angles: a rotary program refuses at the line of its first move
/// with angles; `lossy` writes each as a comment with a warning at its line.
#[test]
fn gcode_rotary_moves_into_apt_refuse_at_their_line() {
    let src = "%\nO0003\nG21 G90 G17 G94\nT1 M6\nG43 H1 S2000 M3\nG0 X0. Y0. Z50.\n\
               G1 Z5. F500.\nX10. B-30. C45.\nX20. B-35.\nG0 Z50.\nM30\n%\n";
    let p = parse(src, "rotary");
    let angled: Vec<u32> = moves(&p)
        .iter()
        .filter(|(op, m)| op.orient(m).is_some_and(Orient::has_angles))
        .map(|(_, m)| m.line)
        .collect();
    assert_eq!(angled.first(), Some(&8), "the first move with B and C");
    match write(&p, Target::Apt, false) {
        Out::Refused(e) => {
            assert_eq!(e.line, 8, "{e}");
            assert!(e.message.contains("rotary"), "{e}");
        }
        Out::Text(t, _) => panic!("written:\n{t}"),
    }
    let Out::Text(text, warnings) = write(&p, Target::Apt, true) else {
        panic!("lossy refused")
    };
    for l in &angled {
        assert!(
            warnings
                .iter()
                .any(|w| w.starts_with(&format!("{l}:1:")) && w.contains("rotary")),
            "no warning at line {l}: {warnings:?}"
        );
    }
    assert!(text.contains("PPRINT"), "{text}");
    // The Mori Seiki sample: its first problem for APT is the reference
    // return at :5; with lossy every move with angles is a warning at its line.
    if let Some(src) = sample(MORI) {
        let p = read(&src, common::options_for(MORI), MORI);
        let Out::Refused(e) = write(&p, Target::Apt, false) else {
            panic!("{MORI} written into APT without lossy")
        };
        assert!(e.line > 0, "{e}");
        let Out::Text(_, warnings) = write(&p, Target::Apt, true) else {
            panic!("{MORI}: lossy refused")
        };
        let angled: std::collections::BTreeSet<u32> = moves(&p)
            .iter()
            .filter(|(op, m)| op.orient(m).is_some_and(Orient::has_angles))
            .map(|(_, m)| m.line)
            .collect();
        assert!(angled.len() > 100, "{}", angled.len());
        for l in angled {
            assert!(
                warnings.iter().any(|w| w.starts_with(&format!("{l}:1:"))),
                "{MORI}:{l}: a move with angles went into APT without a warning"
            );
        }
    }
}

/// Issue 16: "the Heidenhain writer drops the tool axis of 455 tilted arcs."
/// boss.apt (3+2, tool axis 1,0,0; its first such arc at :5614): into
/// Heidenhain every arc reads back with the tool axis it had. dmc100…ptp
/// (M128, B/C): every arc keeps its angles.
#[test]
fn heidenhain_keeps_the_tool_axis_of_tilted_arcs() {
    for rel in [BOSS, DMC100] {
        let Some(p) = read_sample(rel) else { continue };
        let (_, q) = through(&p, Target::Heidenhain, false, rel);
        let arcs = |p: &Program| -> Vec<(u32, Option<Orient>)> {
            moves(p)
                .iter()
                .filter(|(_, m)| m.arc().is_some())
                .map(|(op, m)| (m.line, op.orient(m).copied()))
                .collect()
        };
        let (a, b) = (arcs(&p), arcs(&q));
        assert_eq!(a.len(), b.len(), "{rel}: arcs");
        let tilted = a
            .iter()
            .filter(|(_, o)| o.is_some_and(|o| o.is_tilted()))
            .count();
        assert!(tilted > 100, "{rel}: {tilted} tilted arcs");
        for ((line, o), (_, r)) in a.iter().zip(&b) {
            let (o, r) = match (o, r) {
                (Some(o), Some(r)) => (o, r),
                (None, r) => {
                    assert!(!r.is_some_and(|r| r.is_tilted()), "{rel}:{line}: {r:?}");
                    continue;
                }
                (Some(o), None) => panic!("{rel}:{line}: {o:?} read back without"),
            };
            match (o.axis, r.axis) {
                (Some(u), Some(v)) => assert!((u - v).length() < 1e-6, "{rel}:{line}"),
                _ => {
                    for k in 0..3 {
                        let d = match (o.angles[k], r.angles[k]) {
                            (Some(x), Some(y)) => (x - y).abs(),
                            (None, None) => 0.0,
                            _ => f64::INFINITY,
                        };
                        assert!(d < 1e-6, "{rel}:{line}: {o:?} read back as {r:?}");
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Feed modes.

/// Issue 15/16: "`G93 … F50` is written under G94 as 50 mm/min; `G95 F0.1`
/// becomes 0.1 mm/min." Blocks in inverse time and per revolution, from a
/// G-code and from an APT source, keep their mode and value in every target
/// (G93/G95 in Fanuc, Sinumerik and LinuxCNC; FT/FU in Heidenhain;
/// FEDRAT/…,INVERS and MMPR in APT), read back move by move.
#[test]
fn inverse_time_and_per_revolution_feeds_survive_every_target() {
    let gcode = "%\nO0010\nG21 G17 G90 G94\nT1 M6\nG43 H1\nS2000 M3\nG0 X0. Y0. Z5.\nG1 Z0. F300.\n\
                 G93 G1 X10. Y5. F50.\nX20. F25.\nG95 G1 X30. F0.1\nY10. F0.25\nG94 G1 X40. F400.\nM30\n%\n";
    let apt = "PARTNO FEEDS\nUNITS/MM\nLOADTL/1\nSPINDL/2000,RPM,CLW\nRAPID\nGOTO/0,0,5\n\
               FEDRAT/300,MMPM\nGOTO/0,0,0\nFEDRAT/50,INVERS\nGOTO/10,5,0\nFEDRAT/25,INVERS\n\
               GOTO/20,5,0\nFEDRAT/0.1,MMPR\nGOTO/30,5,0\nFEDRAT/0.25,MMPR\nGOTO/30,10,0\n\
               FEDRAT/400,MMPM\nGOTO/40,10,0\nFINI\n";
    for (what, src) in [("G-code", gcode), ("APT", apt)] {
        let p = parse(src, what);
        let feeds = |p: &Program| -> Vec<(FeedMode, f64)> {
            moves(p)
                .iter()
                .filter(|(_, m)| m.is_cutting())
                .map(|(_, m)| (m.feed_mode, m.feed))
                .collect()
        };
        let want = feeds(&p);
        assert!(
            want.contains(&(FeedMode::InverseTime, 50.0)),
            "{what}: {want:?}"
        );
        assert!(want.contains(&(FeedMode::PerRev, 0.1)), "{what}: {want:?}");
        for t in Target::ALL {
            let (text, q) = through(&p, t, false, what);
            let got = feeds(&q);
            assert_eq!(got.len(), want.len(), "{what} -> {}", t.name());
            for ((wm, wf), (gm, gf)) in want.iter().zip(&got) {
                assert_eq!(wm, gm, "{what} -> {}:\n{text}", t.name());
                assert!(
                    (wf - gf).abs() <= 1e-9 * wf.abs().max(1.0),
                    "{what} -> {}: F{wf} read back as F{gf}",
                    t.name()
                );
            }
            let words: &[&str] = match t {
                Target::Heidenhain => &[" FT", " FU"],
                Target::Apt => &[",INVERS", ",MMPR"],
                _ => &["G93", "G95"],
            };
            for w in words {
                assert!(text.contains(w), "{what} -> {}: no {w}\n{text}", t.name());
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Bounded cycles.

// ---------------------------------------------------------------------------
// Spindle words.

/// Issue 16: "Fanuc output carries decimal S words (`S4200.6`) that most
/// Fanuc controls reject." Every S word of every Fanuc output of the real
/// samples and of a program with fractional speeds is a whole number, within
/// half a revolution per minute of the source.
#[test]
fn fanuc_spindle_speeds_are_whole_numbers() {
    let src =
        "%\nO0040\nG20 G17 G90 G94\nT3 M6\nG43 H3 S4200.6 M3\nG0 X0. Y0. Z1.\nG1 Z-.05 F20.\n\
               G1 X1. S5100.4\nY.5 S5099.5\nM30\n%\n";
    let mut programs = vec![("fractional speeds".to_string(), parse(src, "speeds"))];
    if let Some(root) = common::data() {
        for f in common::programs(&root) {
            let name = f
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("?")
                .to_string();
            let text = std::fs::read_to_string(&f).expect("sample");
            programs.push((name.clone(), read(&text, common::options_for(&name), &name)));
        }
    }
    let mut s_words = 0;
    for (name, p) in &programs {
        let Out::Text(text, _) = write(p, Target::Fanuc, true) else {
            continue;
        };
        for l in text.lines() {
            for w in words(l) {
                if let Some(v) = w.strip_prefix('S') {
                    if v.parse::<f64>().is_ok() {
                        assert!(
                            v.bytes().all(|c| c.is_ascii_digit()),
                            "{name}: `{w}` in `{l}`"
                        );
                        s_words += 1;
                    }
                }
            }
        }
        let q = parse(&text, name);
        let speeds = |p: &Program| -> Vec<f64> { p.moves().map(|m| m.spindle).collect() };
        if p.move_count() == q.move_count() {
            for (a, b) in speeds(p).iter().zip(speeds(&q)) {
                assert!((a - b).abs() <= 0.5, "{name}: S{a} written as S{b}");
            }
        }
    }
    // The synthetic program alone writes S4201, S5100 (S5099.5 rounds to the
    // speed already running and is not repeated).
    assert!(s_words >= 3, "{s_words} S words");
}

// ---------------------------------------------------------------------------
// Detection.

/// Issue 16: "dialect detection looks inside comments." Words of other
/// dialects in comments do not change what a program is read as.
#[test]
fn detection_ignores_words_in_comments() {
    let fanuc = "%\nO0001 (TRAORI CYCLE800 G710 SUPA DEF REAL MSG( T=\"X\")\n\
                 (SETUP: G70 G71 COMPCAD SOFT FNORM #<_X> O100 SUB ENDSUB G64 P0.01)\n\
                 G21 G17 G90\nT1 M6 (CYCLE832 TRAFOOF)\nG0 X0. Y0. Z5. (G642 G61.1)\nG1 Z-1. F100.\nM30\n%\n";
    assert_eq!(detect(fanuc), Dialect::Fanuc);
    let sinumerik = "; program: #<depth> ENDSUB O100 SUB G64 P0.01 G61.1\n\
                     N10 G17 G710 G90\nN20 T=\"MILL\"\nN30 M6\nN40 D1\n\
                     N50 G0 X0 Y0 Z5 ; (MSG, not a LinuxCNC message) G61.1\nN60 G1 Z-1 F100\nN70 M30\n";
    assert_eq!(detect(sinumerik), Dialect::Sinumerik);
    let linuxcnc = "G21 G17 G90 G64 P0.01\n(TRAORI G710 SUPA CYCLE800 T=\"X\" DEF REAL)\n\
                    ; TRAORI G710 SUPA CYCLE832 COMPCAD\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\nM2\n";
    assert_eq!(detect(linuxcnc), Dialect::LinuxCnc);
    // And the real samples read as what they are, whatever their comments say.
    for (rel, d) in [
        (MORI, Dialect::Fanuc),
        (DMU, Dialect::Sinumerik),
        (ACHSKREUZ, Dialect::Sinumerik),
        (BEAR, Dialect::Fanuc),
        (DMC100, Dialect::Heidenhain),
    ] {
        if let Some(src) = sample(rel) {
            assert_eq!(detect(&src), d, "{rel}");
        }
    }
}

// ---------------------------------------------------------------------------
// Bounds and lengths.

/// A small interpreter of plain absolute G0/G1 programs (bear.nc is one):
/// the box of every known coordinate, and rapid and feed lengths of the
/// moves whose start and end are both fully known.
fn plain_gcode_figures(src: &str) -> ([f64; 3], [f64; 3], f64, f64, usize) {
    let mut pos = [f64::NAN; 3];
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let (mut rapid, mut feed, mut unknown) = (0.0, 0.0, 0);
    let mut motion = 0;
    for l in src.lines() {
        let code = l
            .split(['(', ';'])
            .next()
            .unwrap_or("")
            .to_ascii_uppercase();
        let mut toks = Vec::new();
        let b = code.as_bytes();
        let mut i = 0;
        while i < b.len() {
            if b[i].is_ascii_alphabetic() {
                let s = i + 1;
                let mut e = s;
                while e < b.len() && (b[e].is_ascii_digit() || matches!(b[e], b'.' | b'-' | b'+')) {
                    e += 1;
                }
                toks.push((b[i] as char, code[s..e].parse::<f64>().unwrap_or(f64::NAN)));
                i = e;
            } else {
                i += 1;
            }
        }
        let mut end = pos;
        let mut moved = false;
        for &(c, v) in &toks {
            match c {
                'G' if v == 0.0 => motion = 0,
                'G' if v == 1.0 => motion = 1,
                'G' => assert!(!matches!(v as i64, 2 | 3 | 91), "not a plain program: G{v}"),
                'X' | 'Y' | 'Z' => {
                    end[(c as u8 - b'X') as usize] = v;
                    moved = true;
                }
                _ => {}
            }
        }
        if !moved {
            continue;
        }
        for k in 0..3 {
            if !end[k].is_nan() {
                lo[k] = lo[k].min(end[k]);
                hi[k] = hi[k].max(end[k]);
            }
        }
        if pos.iter().chain(&end).any(|v| v.is_nan()) {
            unknown += 1;
        } else {
            let d = (0..3)
                .map(|k| (end[k] - pos[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            if motion == 0 {
                rapid += d;
            } else {
                feed += d;
            }
        }
        pos = end;
    }
    (lo, hi, rapid, feed, unknown)
}

/// Issue 16: "Bounds and lengths count a phantom first move from 0,0,0 and
/// leave out canned-cycle depths." bear.nc:4 `G0Z20.000` starts from an
/// unknown position: `summarize` agrees with a separate interpreter of the
/// text on the box and the lengths, and counts the moves from the unknown.
#[test]
fn bounds_and_lengths_have_no_phantom_start() {
    let src = "G21 G17 G90 G94\nT1 M6\nG0 Z20\nG0 X5 Y5\nG1 Z0 F100\nG1 X15\nM30\n";
    let p = parse(src, "phantom");
    let s = summarize(&p, 10_000.0);
    let (lo, hi, rapid, feed, unknown) = plain_gcode_figures(src);
    assert_eq!(s.unknown_moves, unknown);
    assert_eq!(
        unknown, 2,
        "the first two moves start where X, Y or Z is unknown"
    );
    assert!(
        (s.rapid_mm - rapid).abs() < 1e-9 && (s.cutting_mm - feed).abs() < 1e-9,
        "{s:?}"
    );
    assert_eq!((s.bounds.min.to_array(), s.bounds.max.to_array()), (lo, hi));
    let Some(src) = sample(BEAR) else { return };
    let p = read(&src, ReadOptions::default(), BEAR);
    let s = summarize(&p, 10_000.0);
    let (lo, hi, rapid, feed, unknown) = plain_gcode_figures(&src);
    assert_eq!(s.unknown_moves, unknown, "{BEAR}");
    assert!(unknown >= 1);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * b.abs().max(1.0);
    assert!(
        close(s.rapid_mm, rapid) && close(s.cutting_mm, feed),
        "{s:?} against {rapid} {feed}"
    );
    for k in 0..3 {
        assert!(
            close(s.bounds.min[k], lo[k]) && close(s.bounds.max[k], hi[k]),
            "{:?} against {lo:?} {hi:?}",
            s.bounds
        );
    }
}

/// Canned-cycle depths are in the bounds and the feed length: two G81
/// holes from R to Z feed `2 (R - Z)` and the box reaches Z.
#[test]
fn bounds_and_lengths_include_canned_cycle_depths() {
    let (r, z, clear) = (2.0, -15.5, 25.0);
    let src = format!(
        "%\nO0001\nG21 G17 G90 G94\nT1 M6\nG43 H1 S1000 M3\nG0 X0. Y0. Z{clear}\n\
         G98 G81 X10. Y10. Z{z} R{r} F100.\nX20.\nG80\nM30\n%\n"
    );
    let p = parse(&src, "G81");
    assert!(p.moves().any(|m| matches!(m.kind, MoveKind::Cycle(_))));
    let s = summarize(&p, 10_000.0);
    assert_eq!(s.bounds.min.z, z);
    assert_eq!(s.bounds.max.z, clear);
    assert!((s.cutting_mm - 2.0 * (r - z)).abs() < 1e-9, "{s:?}");
    assert_eq!(
        s.unknown_moves, 1,
        "the first rapid, from an unknown position"
    );
}

/// A user trial: a G81 whose hole bottom Z lies above its R plane was read,
/// and `convert` then stopped with exit 1 (its own read-back disagreed).
/// LinuxCNC refuses such a cycle ("R less than Z"); so does the reader, at
/// the cycle's line and its Z word, in mm and in inch programs. Z level with
/// R is a hole of no depth, still read, with a `cycle-depth` note. Back
/// boring (G87) is read with Z on either side of R.
#[test]
fn a_cycle_bottom_above_its_r_plane_is_a_located_error() {
    for (units, z, r) in [("G21", "5.", "2."), ("G20", "0.2", "0.1")] {
        let src = format!(
            "%\nO0001\n{units} G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z10.\n\
             G98 G81 X10. Y10. Z{z} R{r} F100.\nX20.\nG80\nM30\n%\n"
        );
        let e = millplan_nc::parse_program(&src, ReadOptions::default()).expect_err(units);
        assert_eq!(e.line, 7, "{units}: {e}");
        assert_eq!(e.col, 19, "{units}: the Z word: {e}");
        assert!(
            e.message.contains(&format!("Z{}", z.trim_end_matches('.'))),
            "{units}: {e}"
        );
        assert!(e.message.contains("above its R plane"), "{units}: {e}");
    }
    let level = "%\nO0001\nG21 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z10.\n\
                 G98 G81 X10. Y10. Z2. R2. F100.\nX20.\nG80\nM30\n%\n";
    let parsed = millplan_nc::parse_program(level, ReadOptions::default()).expect("Z = R");
    assert!(parsed
        .program
        .moves()
        .any(|m| matches!(m.kind, MoveKind::Cycle(_))));
    let notes: Vec<_> = parsed
        .diagnostics
        .iter()
        .filter(|d| d.code == millplan_nc::diag::Code::CycleDepth)
        .collect();
    assert_eq!(notes.len(), 1, "one note for the definition: {notes:?}");
    assert_eq!((notes[0].line, notes[0].col), (7, 19), "{notes:?}");
    let back = level.replace("G81 X10. Y10. Z2. R2.", "G87 X10. Y10. Z5. R-10. Q0.5");
    let p = parse(&back, "G87 Z above R");
    assert!(p.moves().any(|m| matches!(m.kind, MoveKind::Cycle(_))));
    // Back boring with R above Z is read too: an NX post writes it so for
    // a tool turned upside down (haas_vf2tr_5axis_inch.ptp, line 1044).
    let down = back.replace("Z5. R-10.", "Z-10. R5.");
    let p = parse(&down, "G87 R above Z");
    assert!(p.moves().any(|m| matches!(m.kind, MoveKind::Cycle(_))));
}

/// A user trial: G-code converted to APT wrote `CYCLE/G81`, a record no APT
/// post knows. The G-code drilling, tapping and boring cycles are written
/// under their APT names (G81/G82 `DRILL`, G83 `DEEP`, G73 `BRKCHP`, G84
/// `TAP`, G85/G89 `BORE`, the dwell and peck as words). Back in G-code an
/// APT cycle is spelled out as lines (its name says less than a G-code
/// cycle needs), and means what the source meant.
#[test]
fn gcode_cycles_take_their_apt_names() {
    let src = "%\nO0001\nG21 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z25.\n\
               G98 G81 X10. Y10. Z-5. R2. F120.\nG80\n\
               G99 G82 X20. Y10. Z-4. R2. P500 F120.\nG80\n\
               G99 G83 X30. Y10. Z-20. R2. Q5. F100.\nG80\n\
               G99 G73 X40. Y10. Z-20. R2. Q4. F100.\nG80\n\
               G99 G85 X50. Y10. Z-8. R1. F80.\nG80\nG0 Z25.\nM30\n%\n";
    let p = parse(src, "cycles");
    let (apt, back) = through(&p, Target::Apt, false, "cycles");
    for name in ["DRILL", "DRILL", "DEEP", "BRKCHP", "BORE"] {
        assert!(apt.contains(&format!("CYCLE/{name},")), "{name}: {apt}");
    }
    assert!(!apt.contains("CYCLE/G"), "{apt}");
    assert!(apt.contains(",DWELL,0.5"), "{apt}");
    let (fanuc, _) = through(&back, Target::Fanuc, false, "cycles -> apt");
    assert_eq!(fanuc.matches("written as lines").count(), 5, "{fanuc}");
    compare(
        &p,
        &parse(&fanuc, "cycles -> apt -> fanuc"),
        &Tolerance::default(),
    )
    .expect("means what the source meant");
}

/// A user trial: `G83 … Q-2` is read as one stroke to depth (with a
/// `peck-depth` warning) and was written as lines that drill the whole
/// depth at once. Spelled out, and into LinuxCNC (whose `rs274` refuses a
/// peck of zero or below), it is refused; the Fanuc cycle keeps its Q.
#[test]
fn a_pecking_cycle_without_a_positive_peck_is_not_drilled_in_one_stroke() {
    let src = "%\nO0005\nG21 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z10.\n\
               G98 G83 X10. Y10. Z-10. R2. Q-2. F100.\nG80\nM30\n%\n";
    let p = read(src, ReadOptions::default(), "Q-2");
    for t in [Target::Sinumerik, Target::Heidenhain, Target::LinuxCnc] {
        let Out::Refused(e) = write(&p, t, false) else {
            panic!("{} wrote it", t.name());
        };
        assert_eq!(e.line, 7, "{}: {e}", t.name());
        assert!(e.message.contains("without a peck depth above 0"), "{e}");
    }
    let fanuc = written(&p, Target::Fanuc, "Q-2");
    assert!(
        fanuc.contains("G98 G83 X10. Y10. Z-10. R2. Q-2. F100."),
        "{fanuc}"
    );
}

/// A user trial: the Heidenhain dwell millplan writes (`CYCL DEF 9.0
/// DWELL TIME` / `9.1 DWELL 2.000`) was read back as words kept verbatim:
/// its time lost, and the program not convertible onwards. Cycle 9 reads
/// as the dwell it is.
#[test]
fn the_heidenhain_dwell_reads_back() {
    let src = "%\nO0006\nG21 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z5.\nG1 Z-1. F100.\nG4 X2.\nG0 Z5.\nM30\n%\n";
    let p = parse(src, "G4");
    let (text, back) = through(&p, Target::Heidenhain, false, "G4");
    assert!(text.contains("CYCL DEF 9.1 DWELL 2.000"), "{text}");
    let dwell: Vec<f64> = (back.operations.iter().flat_map(|o| o.events.iter()))
        .filter_map(|e| match e.kind {
            EventKind::Dwell(t) => Some(t),
            _ => None,
        })
        .collect();
    assert_eq!(dwell, [2.0], "{text}");
    compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    let (fanuc, _) = through(&back, Target::Fanuc, false, "G4 -> heidenhain");
    assert!(fanuc.contains("G4 P2000"), "{fanuc}");
    // A dwell given by a Q parameter is known only at the control: both
    // lines kept as written (the review found it refused).
    let q = "0 BEGIN PGM P MM\n1 FN 0: Q5 = +1.5\n2 TOOL CALL 1 Z S1000\n3 L Z+5 R0 FMAX\n\
             4 CYCL DEF 9.0 DWELL TIME\n5 CYCL DEF 9.1 DWELL Q5\n6 L Z+10 FMAX\n7 END PGM P MM\n";
    let p = read(q, ReadOptions::default(), "cycle 9 Q");
    let text = written(&p, Target::Heidenhain, "cycle 9 Q");
    assert!(
        text.contains("CYCL DEF 9.0 DWELL TIME") && text.contains("CYCL DEF 9.1 DWELL Q5"),
        "{text}"
    );
}

/// A user trial: G73 spelled out as lines went back to R after every peck,
/// as G83 does. A chip-breaking cycle backs off 0.254 mm and feeds on, the
/// canonical moves of LinuxCNC's own G73 (its `rs274`: Z0, 0.254, −2,
/// −1.746, −4, −3.746, −6).
#[test]
fn a_spelled_out_g73_breaks_the_chip_without_leaving_the_hole() {
    let src = "%\nO0007\nG21 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z10.\n\
               G98 G73 X10. Y10. Z-6. R2. Q2. F100.\nG80\nM30\n%\n";
    let p = parse(src, "G73");
    let (text, back) = through(&p, Target::Sinumerik, false, "G73");
    let zs: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.contains("cycle G73"))
        .filter_map(|l| l.split_whitespace().find(|w| w.starts_with('Z')))
        .collect();
    assert_eq!(
        zs,
        ["Z2", "Z0", "Z0.254", "Z-2", "Z-1.746", "Z-4", "Z-3.746", "Z-6", "Z10"],
        "{text}"
    );
    compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
}

/// A user trial: a bare `F` (`G2 X20 I5 J0 F`) was kept verbatim with a
/// warning and written into the Fanuc output as `F G2 X20. …`, which no
/// control reads. It is refused at its column.
#[test]
fn an_address_letter_without_its_number_is_refused_at_its_column() {
    let src = "G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F100\nG2 X20 I5 J0 F\nM30\n";
    let e = millplan_nc::parse_program(src, ReadOptions::default()).expect_err("refused");
    assert_eq!((e.line, e.col), (4, 14), "{e}");
    assert!(e.message.contains("`F` without a number"), "{e}");
}

/// A user trial: Sinumerik's `G4 S10` (a dwell of ten spindle revolutions)
/// set the spindle to 10 1/min for the cuts that followed. It dwells 0.6 s
/// at 1000 1/min, and the speed stays; without a speed it is refused at
/// the S word.
#[test]
fn a_sinumerik_dwell_in_revolutions_keeps_the_speed() {
    let src = "G71 G90 G17 G642\nT1 M6\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG4 S10\nG1 X10\nM30\n";
    let p = read(src, ReadOptions::default(), "G4 S");
    assert_eq!(p.source, Dialect::Sinumerik);
    let op = &p.operations[0];
    let dwell: Vec<f64> = (op.events.iter())
        .filter_map(|e| match e.kind {
            EventKind::Dwell(t) => Some(t),
            _ => None,
        })
        .collect();
    assert_eq!(dwell.len(), 1);
    assert!((dwell[0] - 0.6).abs() < 1e-12, "{dwell:?}");
    assert!(
        op.moves.iter().all(|m| m.spindle == 1000.0),
        "{:?}",
        op.moves
    );
    let none = "G71 G90 G17 G642\nT1 M6\nG0 X0 Y0 Z5\nG4 S10\nM30\n";
    let e = millplan_nc::parse_program(none, ReadOptions::default()).expect_err("refused");
    assert_eq!((e.line, e.col), (4, 4), "{e}");
    // Nor with the spindle stopped (M5): the control would wait for turns
    // that never come (the review saw 0.15 s from the last speed).
    let stopped = src.replace("G4 S10", "M5\nG4 S10");
    let e = millplan_nc::parse_program(&stopped, ReadOptions::default()).expect_err("refused");
    assert_eq!((e.line, e.col), (7, 4), "{e}");
}

/// The review: the peck limit took the Q of a fine-boring G76 (the bar's
/// shift) for a peck depth and refused the program on reading. Only G73
/// and G83 peck among the G-code cycles.
#[test]
fn the_q_of_a_cycle_that_does_not_peck_is_no_peck() {
    let src = "%\nO0009\nG21 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z10.\n\
               G98 G76 X10. Y10. Z-60. R2. Q0.05 F80.\nG80\nM30\n%\n";
    let p = parse(src, "G76 Q");
    assert_eq!(p.operations[0].cycles[0].pecks(), 1);
    let g81 = src.replace("G76", "G81");
    assert_eq!(parse(&g81, "G81 Q").operations[0].cycles[0].pecks(), 1);
}

/// The review: Sinumerik's `G4 S=10` (the assignment form) still set the
/// spindle speed.
#[test]
fn a_sinumerik_dwell_in_revolutions_by_assignment_keeps_the_speed() {
    let src = "G71 G90 G17 G642\nT1 M6\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG4 S=10\nG1 X10\nM30\n";
    let p = read(src, ReadOptions::default(), "G4 S=");
    let op = &p.operations[0];
    assert!(
        op.moves.iter().all(|m| m.spindle == 1000.0),
        "{:?}",
        op.moves
    );
    assert!(op
        .events
        .iter()
        .any(|e| matches!(e.kind, EventKind::Dwell(t) if (t - 0.6).abs() < 1e-12)));
}

/// A user trial: in a series of cycles without G80 between, a G98 hole
/// after a G99 one returned to R (where the tool stood) rather than to the
/// level the series began at, and LinuxCNC's `rs274` showed the output
/// traversing 18 mm lower than the source. The initial level holds for the
/// whole series, and G98/G99 alone switch it for the holes that follow.
#[test]
fn a_cycle_series_keeps_its_initial_level() {
    let src = "%\nO0004\nG21 G17 G90 G94\nT1 M6\nS2000 M3\nG0 X0. Y0. Z20.\n\
               G98 G81 X10. Y10. Z-5. R2. F100.\nG99 G82 X20. Z-5. R2. P500\n\
               G98 G83 X30. Z-10. R2. Q3.\nG99 X40.\nG98 X50.\nG80\nG0 Z50.\nM30\n%\n";
    let p = parse(src, "series");
    let op = &p.operations[0];
    let retract: Vec<f64> = op
        .moves
        .iter()
        .filter_map(|m| op.cycle(m))
        .map(|c| c.retract)
        .collect();
    // Holes at X10 … X50: back to Z20 (18 above R), to R, 18, to R, 18.
    assert_eq!(retract, [18.0, 0.0, 18.0, 0.0, 18.0], "{retract:?}");
    for t in [Target::Fanuc, Target::LinuxCnc, Target::Sinumerik] {
        let (text, back) = through(&p, t, false, "series");
        compare(&p, &back, &Tolerance::default())
            .unwrap_or_else(|e| panic!("{}: {e}\n{text}", t.name()));
    }
}

/// A user trial: `G0 Z20` then `G43 H1 Z20` was written `G43 H1`, the Z
/// left out as already there; but under the new length the same Z is
/// another machine position, and LinuxCNC's `rs274` showed the XY moves
/// that followed a tool length lower than the source's. A change of length
/// compensation (or of TCP) states the next Z again.
#[test]
fn a_z_on_the_length_compensation_block_is_kept() {
    let src = "%\nO0003\nG21 G17 G90 G94\nT1 M6\nS2000 M3\nG0 X0. Y0. Z20.\nG43 H1 Z20.\n\
               G0 X10. Y10.\nG1 Z-1. F100.\nG0 Z20.\nG49\nM30\n%\n";
    let p = parse(src, "G43 Z");
    for (t, block) in [
        (Target::Fanuc, "G43 H1 Z20."),
        (Target::LinuxCnc, "G43 H1 Z20"),
        (Target::Sinumerik, "D1 Z20"),
    ] {
        let (text, back) = through(&p, t, false, "G43 Z");
        assert!(
            text.lines().any(|l| l.ends_with(block)),
            "{}: {text}",
            t.name()
        );
        compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    }
    // The review: a compensation block without Z moves nothing, and the
    // next move without Z keeps the machine's height; writing the program's
    // old Z there dropped the tool a length during a rapid (rs274).
    let src = "%\nO0008\nG21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0. Y0. Z20.\nG1 Z-5. F100.\n\
               G0 Z20.\nG49\nG0 X100. Y0.\nM30\n%\n";
    let p = parse(src, "G49 alone");
    for t in [Target::Fanuc, Target::LinuxCnc] {
        let text = written(&p, t, "G49 alone");
        let after: Vec<&str> = text.lines().skip_while(|l| !l.starts_with("G49")).collect();
        assert!(
            after.iter().skip(1).all(|l| !l.contains('Z')),
            "{}: {text}",
            t.name()
        );
    }
}

/// A change of length compensation without a Z leaves the tool where it
/// stands, which is another program Z: the reader held the old Z as known,
/// so the checks saw the moves after it a tool length off, and the writer
/// restated that Z on the next compensation block (NX's Mori Seiki post:
/// `G49` after `Z50.2`, then `G43 G00 Y19.92` was written with
/// `Z50.2`, a move the source never made). Z is unknown until commanded.
#[test]
fn a_length_change_without_z_leaves_z_unknown() {
    let src = "%\nO0009\nG21 G17 G90 G94\nT1 M6\nG43 H1 Z50.\nG0 X0. Y0.\nG1 Z-1. F100.\n\
               G0 Z50.2\nG49\nG43 H2 G0 X10. Y10.\nG0 Z5.\nG43 H2\nG0 X20.\nM30\n%\n";
    let p = parse(src, "G43 without Z");
    let moves: Vec<_> = p.moves().collect();
    let at = |line: u32| moves.iter().find(|m| m.line == line).expect("a move").end;
    assert_eq!(at(8).z, 50.2);
    // After G49 and G43 H2 without Z: X and Y as commanded, Z unknown.
    let e = at(10);
    assert_eq!((e.x, e.y), (10.0, 10.0));
    assert!(e.z.is_nan(), "{e:?}");
    // A compensation already in force changes nothing.
    assert_eq!(at(13).z, 5.0);
    for t in [Target::Fanuc, Target::LinuxCnc] {
        let (text, back) = through(&p, t, false, "G43 without Z");
        let line = text
            .lines()
            .find(|l| l.contains("X10"))
            .expect("the move to X10");
        assert!(!line.contains('Z'), "{}: {text}", t.name());
        compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    }
}

/// The review of the rule above: the length changes it missed. `G49` kept
/// in a machine block, `G43` without H after a tool change (the new tool's
/// length), a G98 cycle on the block that changes the length (its initial
/// level is then unknown: kept verbatim, not refused), and TCP switched on
/// a Heidenhain positioning block with B turned.
#[test]
fn every_length_change_leaves_z_unknown() {
    let z_at = |src: &str, x: f64| -> f64 {
        let p = parse(src, "length change");
        let z = p
            .moves()
            .find(|m| m.end.x == x)
            .unwrap_or_else(|| panic!("a move to X{x}: {src}"))
            .end
            .z;
        z
    };
    let g49_machine = "%\nO0010\nG21 G17 G90\nT1 M6\nG43 H1 G0 Z50.\nG0 X0. Y0.\nG1 Z-1. F100.\n\
                       G49 G53 G0 Z0.\nG0 Z100.\nG43 H1 G0 X10. Y10.\nG1 X20.\nM30\n%\n";
    assert!(z_at(g49_machine, 10.0).is_nan());
    let new_tool = "%\nO0011\nG21 G17 G90\nT1 M6\nG43 G0 Z50.\nG0 X0. Y0.\nT2 M6\n\
                    G0 X0. Y0. Z100.\nG43 G0 X10. Y10.\nM30\n%\n";
    assert!(z_at(new_tool, 10.0).is_nan());
    let cycle = "%\nO0012\nG21 G17 G90\nT1 M6\nG43 H1 G0 Z50.\nG0 X0. Y0.\n\
                 G43 H2 G98 G81 X10. Y10. Z-5. R2. F100.\nG80\nM30\n%\n";
    let p = parse(cycle, "G98 cycle with G43");
    assert!(p.moves().all(|m| m.cycle().is_none()), "kept verbatim");
    let tcp = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+50 B+30 C+0 R0 FMAX M3\n\
               3 L X+10 R0 FMAX M128\n4 END PGM T MM\n";
    let p = parse(tcp, "M128 on a move");
    let e = p.moves().find(|m| m.end.x == 10.0).expect("the move").end;
    assert!(e.y.is_nan() && e.z.is_nan(), "{e:?}");
}

/// A user trial: a Heidenhain program converted to Fanuc, LinuxCNC or
/// Sinumerik ran without tool-length compensation (`G49` in the header, no
/// `G43`): TOOL CALL applies the tool's length on the Heidenhain, so every Z
/// was a tool length off. Each tool change now selects its length.
#[test]
fn a_heidenhain_tool_call_keeps_its_length() {
    let src = "0 BEGIN PGM H1 MM\n1 TOOL CALL 1 Z S8000\n2 L X+0 Y+0 Z+50 R0 FMAX M3\n\
               3 L Z-1 R0 F500\n4 TOOL CALL 2 Z S6000\n5 L Z+50 R0 FMAX\n6 L Z-2 F300\n\
               7 END PGM H1 MM\n";
    let p = parse(src, "TOOL CALL");
    for (t, after) in [
        (Target::Fanuc, ["G43 H1", "G43 H2"]),
        (Target::LinuxCnc, ["G43 H1", "G43 H2"]),
        (Target::Sinumerik, ["D1", "D1"]),
    ] {
        let (text, back) = through(&p, t, false, "TOOL CALL");
        let lines: Vec<&str> = text.lines().collect();
        let changes: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i].contains("M6"))
            .collect();
        assert_eq!(changes.len(), 2, "{}: {text}", t.name());
        for (i, want) in changes.iter().zip(after) {
            assert!(
                lines[i + 1..].iter().take(2).any(|l| l.contains(want)),
                "{}: {want} after line {i}: {text}",
                t.name()
            );
        }
        compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    }
}

/// A user trial: Sinumerik's `D1` (edge 1 of the tool in the spindle)
/// became `G43 H1` for every tool, and Fanuc's `H12` on tool 2 became
/// Sinumerik's `D12` (edge 12 of tool 2): lengths of other tools. A
/// register is translated only where its meaning is known, else refused.
#[test]
fn length_registers_keep_their_meaning_across_dialects() {
    let sin =
        "; S\nG71 G90 G17\nT=\"BALL_D10\"\nM6\nD1\nS8000 M3\nG0 X0 Y0 Z50\nG1 Z-1 F500\nM30\n";
    let p = parse(sin, "named tool D1");
    for t in [Target::Fanuc, Target::LinuxCnc] {
        match write(&p, t, false) {
            Out::Refused(e) => assert!(e.message.contains("D1"), "{}: {e}", t.name()),
            Out::Text(s, _) => panic!("{}: written: {s}", t.name()),
        }
    }
    let sin = "; S\nG71 G90 G17\nT5\nM6\nD1\nS8000 M3\nG0 X0 Y0 Z50\nG1 Z-1 F500\nM30\n";
    let p = parse(sin, "T5 D1");
    let (text, _) = through(&p, Target::Fanuc, false, "T5 D1");
    assert!(text.contains("G43 H5"), "{text}");
    let p = parse(&sin.replace("D1", "D2"), "T5 D2");
    for t in [Target::Fanuc, Target::LinuxCnc, Target::Heidenhain] {
        match write(&p, t, false) {
            Out::Refused(e) => assert!(e.message.contains("D2"), "{}: {e}", t.name()),
            Out::Text(s, _) => panic!("{}: written: {s}", t.name()),
        }
    }
    let fanuc = |h: u32| {
        format!("%\nO0013\nG21 G17 G90\nT2 M6\nG43 H{h} G0 X0. Y0. Z40.\nG1 Z-1. F100.\nM30\n%\n")
    };
    let p = parse(&fanuc(2), "H2 on T2");
    let (text, _) = through(&p, Target::Sinumerik, false, "H2 on T2");
    assert!(text.lines().any(|l| l.starts_with("D1")), "{text}");
    let p = parse(&fanuc(12), "H12 on T2");
    for t in [Target::Sinumerik, Target::Heidenhain] {
        match write(&p, t, false) {
            Out::Refused(e) => assert!(e.message.contains("H12"), "{}: {e}", t.name()),
            Out::Text(s, _) => panic!("{}: written: {s}", t.name()),
        }
    }
}

/// A user trial: after `CYCL DEF 2.0 TAPPING` (no model covers it) the
/// `M99` calls ran the pecking cycle defined before it: the tap fed and
/// pecked like a drill at the drill's depth. A call of a cycle no model
/// covers is kept as the control's own, not simulated; another dialect
/// refuses it.
#[test]
fn a_call_of_an_unmodelled_cycle_does_not_run_the_previous_one() {
    let src = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX M3\n\
               3 CYCL DEF 1.0 PECKING\n4 CYCL DEF 1.1 SET UP 2\n5 CYCL DEF 1.2 DEPTH -10\n\
               6 CYCL DEF 1.3 PECKG 3\n7 CYCL DEF 1.4 DWELL 0\n8 CYCL DEF 1.5 F100\n\
               9 L X+10 Y+10 R0 FMAX M99\n10 CYCL DEF 2.0 TAPPING\n11 CYCL DEF 2.1 SET UP 2\n\
               12 CYCL DEF 2.2 DEPTH -8\n13 CYCL DEF 2.3 DWELL 0\n14 CYCL DEF 2.4 F125\n\
               15 L X+20 Y+10 R0 FMAX M99\n16 END PGM T MM\n";
    let p = parse(src, "tapping");
    let cycles = p.moves().filter(|m| m.cycle().is_some()).count();
    assert_eq!(cycles, 1, "only the pecking hole is a cycle of the IR");
    let (_, back) = through(&p, Target::Heidenhain, false, "tapping");
    compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    match write(&p, Target::LinuxCnc, false) {
        Out::Refused(e) => assert!(e.message.contains("CYCL"), "{e}"),
        Out::Text(s, _) => panic!("written: {s}"),
    }
}

/// A user trial: a Fanuc tapping cycle could not be converted to LinuxCNC,
/// which has G84 and G74 (its `rs274` runs them: feed in, spindle reversed,
/// feed out). They stay the control's own when the spindle turns the tap's
/// way, as LinuxCNC insists (it refuses G84 with M4); otherwise a tap is
/// refused, as before (it cannot be spelled out as moves).
#[test]
fn fanuc_taps_stay_taps_in_linuxcnc() {
    let tap = |dir: &str, g: &str| {
        format!(
            "%\nO0002\nG21 G17 G90 G94\nT1 M6\nS500 {dir}\nG0 X0. Y0. Z5.\n\
             G98 {g} X10. Y10. Z-10. R2. P300 F625.\nX20.\nG80\nM30\n%\n"
        )
    };
    for (dir, g) in [("M3", "G84"), ("M4", "G74")] {
        let p = parse(&tap(dir, g), g);
        let (text, back) = through(&p, Target::LinuxCnc, false, g);
        assert!(
            text.contains(&format!("G98 {g} X10 Y10 Z-10 R2 P0.3 F625")),
            "{text}"
        );
        compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    }
    // The review: LinuxCNC refuses a tap with Q (peck tapping), and a tap
    // after an M6 (which stops its spindle) before the spindle is started.
    let pecked = tap("M3", "G84").replace("P300", "Q3. P300");
    let after_m6 = tap("M3", "G84").replace("T1 M6\nS500 M3\n", "S500 M3\nT1 M6\n");
    for src in [pecked, after_m6] {
        let p = parse(&src, "G84");
        let Out::Refused(e) = write(&p, Target::LinuxCnc, false) else {
            panic!("written: {src}");
        };
        assert!(e.message.contains("tapping"), "{e}");
    }
    for (dir, g) in [("M4", "G84"), ("M3", "G74")] {
        let p = parse(&tap(dir, g), g);
        let Out::Refused(e) = write(&p, Target::LinuxCnc, false) else {
            panic!("{g} with {dir} was written");
        };
        assert_eq!(e.line, 7, "{e}");
        assert!(e.message.contains("tapping"), "{e}");
    }
}

/// An APT cycle named by its G code (as millplan wrote APT before the APT
/// names) whose holes lie at two heights: its depth and levels are offsets
/// from each point, so the second hole states the cycle again with its own
/// Z, R and return level (the control's G81 kept them modal from the first).
#[test]
fn a_gcode_named_cycle_at_a_new_height_states_itself_again() {
    let src = "PARTNO VZ\nUNITS/MM\nCUTTER/6,0,0,0,0,0,50\nLOADTL/1\nSPINDL/2000,RPM,CLW\n\
               RAPID\nGOTO/0,0,50\nCYCLE/G81,FEDTO,10,RAPTO,2,RTRCTO,5,MMPM,150\n\
               GOTO/10,10,0\nGOTO/20,10,-5\nCYCLE/OFF\nRAPID\nGOTO/20,10,50\nFINI\n";
    let p = parse(src, "two heights");
    for t in [Target::Fanuc, Target::LinuxCnc] {
        let (text, back) = through(&p, t, false, "two heights");
        assert_eq!(text.matches(" G81 ").count(), 2, "{text}");
        assert!(text.contains("Z-15") && text.contains("R-3"), "{text}");
        compare(&p, &back, &Tolerance::default()).expect("means what the source meant");
    }
}

// ---------------------------------------------------------------------------
// Found with the writer snapshots.

/// Issue 15: "a 7-line `G83 … Q0.00001` became 3.6 M lines, 89 MB." The
/// reader refuses it at the cycle's line (7), and so does every target,
/// `lossy` or not, for such a cycle made otherwise: spelled out it is
/// millions of pecks, and in the control's own cycle the peck is below
/// what the target's decimals can say (it was written `Q0.`).
#[test]
fn absurd_peck_is_a_located_error_in_every_target() {
    let src = "%\nO0020\nG21 G17 G90 G94\nT2 M6\nG43 H2 S1500 M3\nG0 X10. Y10. Z5.\n\
               G98 G83 X10. Y10. Z-20. R2. Q0.00001 F100.\nX30.\nG80\nM30\n%\n";
    let e = millplan_nc::parse_program(src, ReadOptions::default()).expect_err("refused");
    assert_eq!(e.line, 7, "{e}");
    let mut p = parse(&src.replace("Q0.00001", "Q2.5"), "G83");
    let c = &mut p.operations[0].cycles[0];
    c.peck = Some(0.00001);
    assert_eq!(c.line, 7);
    assert!(c.pecks() > millplan_nc::MAX_PECKS);
    for t in Target::ALL {
        for lossy in [false, true] {
            match write(&p, t, lossy) {
                Out::Refused(e) => {
                    assert_eq!(e.line, 7, "{}: {e}", t.name());
                    assert!(e.message.contains("peck"), "{}: {e}", t.name());
                }
                Out::Text(text, _) => panic!("{} (lossy {lossy}) wrote:\n{text}", t.name()),
            }
        }
    }
    // A sane peck is written and reads back with its value.
    let ok = src.replace("Q0.00001", "Q2.5");
    let p = parse(&ok, "G83 Q2.5");
    for t in Target::ALL {
        let (text, q) = through(&p, t, false, "G83 Q2.5");
        compare(&p, &q, &Tolerance::default())
            .unwrap_or_else(|e| panic!("{}: {e}\n{text}", t.name()));
    }
}

/// Found with the writer snapshots: Fanuc's G82 dwell `P` is milliseconds
/// and takes no decimal point; `G82 … P500` was written `P500.`.
#[test]
fn fanuc_cycle_dwell_is_whole_milliseconds() {
    let src = "%\nO0021\nG21 G90 G17\nT2 M6\nG43 H2 S1500 M3\nG0 X0. Y0. Z10.\n\
               G99 G82 X30. Y10. Z-4. R2. P500 F120.\nG80\nM30\n%\n";
    let p = parse(src, "G82");
    let text = written(&p, Target::Fanuc, "G82");
    let line = text
        .lines()
        .find(|l| l.contains("G82"))
        .expect("a G82 block");
    let p_word = words(line)
        .into_iter()
        .find(|w| w.starts_with('P'))
        .expect("a P word");
    assert_eq!(p_word, "P500", "`{line}`");
    let q = parse(&text, "G82 re-read");
    assert_eq!(q.operations[0].cycles[0].dwell, Some(0.5));
}

/// Found with the Mori Seiki test: moriseiki…ptp:347 `G00 B-37.576 C45. S0
/// M03` in G91 (from :341) is kept verbatim and was written `G91 G0
/// B-37.576 C45`; on a Fanuc without decimal-point input `C45` is 0.045°.
/// Every axis word the Fanuc writer copies keeps its decimal point.
#[test]
fn verbatim_axis_words_keep_their_decimal_point_in_fanuc() {
    let src = "%\nO0001\nG21 G90 G17\nT1 M6\nG91 G28 Z0.0 M05\nG00 B-90. C270. S0 M03\n\
               G90 G53 G0 Z-10.\nG28 G91 X0.0 Y0.0\nG90 G0 X10. Y10. Z50.\nM30\n%\n";
    let p = parse(src, "verbatim words");
    let text = written(&p, Target::Fanuc, "verbatim words");
    let mut copied = 0;
    for l in text
        .lines()
        .filter(|l| l.contains("G91") || l.contains("G53"))
    {
        for w in words(l) {
            let (letter, num) = w.split_at(1);
            if matches!(letter, "X" | "Y" | "Z" | "A" | "B" | "C") {
                assert!(num.contains('.'), "`{w}` in `{l}` has no decimal point");
                copied += 1;
            }
        }
    }
    assert!(copied >= 5, "{text}");
    if let Some(src) = sample(MORI) {
        let p = read(&src, common::options_for(MORI), MORI);
        let text = written(&p, Target::Fanuc, MORI);
        for l in text.lines() {
            for w in words(l) {
                let (letter, num) = w.split_at(1);
                let axis = matches!(letter, "X" | "Y" | "Z" | "A" | "B" | "C");
                let number = num.parse::<f64>().is_ok();
                assert!(
                    !(axis && number) || num.contains('.'),
                    "`{w}` in `{l}` has no decimal point"
                );
            }
        }
    }
}

/// Found with the Mori Seiki test: moriseiki…ptp:370 `G49` after
/// `G43.4 … H09` (:350) was written `G49 G43 H9 G49`: TCP off (`G49 G43
/// H9`) and length compensation off in one block. It is one `G49`.
#[test]
fn g49_under_tcp_is_one_g49() {
    let src =
        "%\nO0002\nG21 G90 G17\nT9 M6\nG43.4 X10. Y10. Z50. B0. C0. H09\nG1 X20. B-30. F500.\n\
               G49\nG0 Z100.\nG43.4 X10. Y10. Z50. H09\nG1 X20. B-20.\nG49\nM30\n%\n";
    let p = parse(src, "G49 under TCP");
    let text = written(&p, Target::Fanuc, "G49 under TCP");
    let g49: Vec<&str> = text.lines().filter(|l| l.contains("G49")).collect();
    // The header's own G49 and one for each source G49.
    assert_eq!(g49.len(), 3, "{text}");
    for l in &g49[1..] {
        assert_eq!(l.trim(), "G49", "{text}");
    }
    if let Some(src) = sample(MORI) {
        let p = read(&src, common::options_for(MORI), MORI);
        let text = written(&p, Target::Fanuc, MORI);
        for l in text.lines().filter(|l| l.contains("G49")) {
            let groups = words(l)
                .iter()
                .filter(|w| w.starts_with("G43") || **w == "G49")
                .count();
            assert_eq!(groups, 1, "`{l}`: two tool-length words in one block");
        }
    }
}

/// LinuxCNC has no tool-centre-point control: with `lossy`, a `G43.4`
/// source said so in a comment and then wrote `G43.4 H9` anyway, a block
/// LinuxCNC rejects. It writes plain `G43 H9`.
#[test]
fn linuxcnc_never_writes_tcp_words() {
    let src =
        "%\nO0030\nG21 G17 G90 G94\nT9 M6\nG43.4 G90 G0 X10. Y10. Z50. B0. C0. H09 S3000 M3\n\
               G1 Z5. F500.\nX20. B-30. C45.\nG49\nM30\n%\n";
    let p = parse(src, "TCP");
    let Out::Text(text, warnings) = write(&p, Target::LinuxCnc, true) else {
        panic!("lossy refused")
    };
    assert!(
        warnings.iter().any(|w| w.contains("tool-centre-point")),
        "{warnings:?}"
    );
    for l in text.lines().filter(|l| !l.starts_with('(')) {
        assert!(
            !l.contains("G43.4") && !l.contains("G43.5"),
            "`{l}`\n{text}"
        );
    }
    assert!(text.lines().any(|l| words(l).contains(&"G43")), "{text}");
}

/// Issue 16: "A rotary-only `G00 B0.0 C0.0` becomes `G0 X0. Y0. Z0. B0. C0.`
/// in every G-code output of the Sinumerik, Mori Seiki and DMU samples."
/// Achskreuz.mpf:29 `N280 G0 B0.0 C0.0` (and 19 more), Bottle_opener.mpf,
/// dmu70evo…ptp:15-16 `N15 G00 B0.0` / `N16 G00 C0.0`: each such block is
/// written as a block with rotary words and no X, Y or Z word, in every
/// G-code target (words a target refuses are written as comments).
#[test]
fn rotary_only_rapids_stay_rotary_only_in_every_gcode_target() {
    // A rotary block to where the axes already stand (Achskreuz.mpf:933
    // `N9320 G0 B0.0 C0.0`) is left out, or written as it is: Heidenhain
    // wrote it `L X-59 Y+3.92 Z+8.2 FMAX`, naming the axes its source did not.
    let src = "%\nO0001\nG21 G90 G17\nT1 M6\nG43 H1\nG0 X1. Y2. Z3. B0. C0.\nG0 B0. C0.\n\
               G0 B10.\nM30\n%\n";
    let p = parse(src, "idle rotary");
    for t in GCODE {
        let (text, _) = through(&p, t, false, "idle rotary");
        let xyz = text.lines().filter(|l| has_xyz(l)).count();
        assert_eq!(
            xyz,
            1,
            "{}: only the first move names X, Y, Z\n{text}",
            t.name()
        );
    }
    let mut checked = 0;
    for rel in [ACHSKREUZ, BOTTLE, DMU] {
        let Some(src) = sample(rel) else { continue };
        let lines = rotary_only_lines(&src);
        assert!(!lines.is_empty(), "{rel}: no rotary-only block found");
        let p = read(&src, common::options_for(rel), rel);
        for t in GCODE {
            let (text, q) = through(&p, t, true, rel);
            let (a, b) = (moves(&p), moves(&q));
            for (i, ((_, m), k)) in a.iter().zip(align(&p, &q)).enumerate() {
                if !lines.contains(&m.line) {
                    continue;
                }
                let Some(k) = k else {
                    // Only a block to where the axes already stand may be left out.
                    assert!(
                        idle(&a, i),
                        "{rel}:{} -> {}: not in the output",
                        m.line,
                        t.name()
                    );
                    continue;
                };
                let n = b[k].1;
                let out = line_of(&text, n.line);
                assert!(
                    has_rotary(out) && !has_xyz(out),
                    "{rel}:{} `{}` -> {} line {}: `{out}`",
                    m.line,
                    line_of(&src, m.line).trim(),
                    t.name(),
                    n.line
                );
                checked += 1;
            }
        }
    }
    if checked > 0 {
        eprintln!("{checked} rotary-only blocks checked");
    }
}

/// Issue 16: "a Heidenhain program written by `speed` re-reads as 6,310
/// operations because each `TOOL CALL S…` reads as a tool change." A
/// `TOOL CALL S…` (or `TOOL CALL Z S…`) without a tool number changes the
/// speed of the same operation.
#[test]
fn heidenhain_tool_call_without_a_number_changes_the_speed() {
    let src = "0 BEGIN PGM SPIN MM\n1 TOOL CALL 3 Z S4200.6\n2 L X+0 Y+0 Z+5 R0 FMAX M3\n\
               3 L Z-1 F200\n4 TOOL CALL S5100\n5 L X+10 F200\n6 TOOL CALL Z S6100.4\n7 L X+20\n\
               8 L Z+5 FMAX M5\n9 END PGM SPIN MM\n";
    let p = parse(src, "TOOL CALL S");
    assert_eq!(p.operations.len(), 1);
    let speeds: Vec<f64> = p.moves().map(|m| m.spindle).collect();
    // The TNC stops the spindle (M5) at the end of its block: the retract
    // still turns.
    assert_eq!(speeds, [4200.6, 4200.6, 5100.0, 6100.4, 6100.4]);
    let op = &p.operations[0];
    assert!(matches!(
        op.events.last().map(|e| (e.at, &e.kind)),
        Some((
            5,
            millplan_nc::EventKind::Spindle(millplan_nc::SpindleDir::Off)
        ))
    ));
    // A real program whose speed changes at every cutting move (as `speed`
    // writes them), into Heidenhain and back: as many operations as before.
    let Some(mut p) = read_sample("swcam-apt-stl-pairs/Interface-glue.apt") else {
        return;
    };
    let mut k = 0.0;
    for op in &mut p.operations {
        for m in &mut op.moves {
            if m.is_cutting() && m.spindle > 0.0 {
                k += 1.0;
                m.spindle = 5000.0 + (k % 97.0) * 10.0;
            }
        }
    }
    let (text, q) = through(&p, Target::Heidenhain, false, "Interface-glue");
    let calls = text.lines().filter(|l| l.contains("TOOL CALL S")).count();
    assert!(calls > 1000, "{calls} speed changes");
    assert_eq!(q.operations.len(), p.operations.len());
    compare(&p, &q, &Tolerance::default()).unwrap_or_else(|e| panic!("{e}"));
}

/// Found when Heidenhain stopped writing moves to where the tool stands:
/// after a `CYCL CALL` the writer took the tool to be where it was before
/// the cycle, and left out the retract after the last hole (dmc100…ptp:4094
/// `L Z+1.9685 FMAX` after cycle 240 with Q204=+.1181). The cycle leaves
/// the tool at its own clearance; the next block states Z.
#[test]
fn heidenhain_states_z_after_a_cycle_call() {
    let src = "0 BEGIN PGM HOLES MM\n1 TOOL CALL 5 Z S4000\n2 L Z+50 R0 FMAX M3\n\
               3 CYCL DEF 200 DRILLING ~\n  Q200=2 ;SET-UP CLEARANCE ~\n  Q201=-10 ;DEPTH ~\n\
               \x20 Q206=150 ;FEED RATE ~\n  Q203=+0 ;SURFACE COORDINATE ~\n  Q204=5 ;2ND SET-UP CLEARANCE\n\
               4 L X+10 Y+0 FMAX M99\n5 L X+20 Y+0 FMAX M99\n6 L Z+50 FMAX\n7 END PGM HOLES MM\n";
    let p = parse(src, "holes");
    let (text, q) = through(&p, Target::Heidenhain, false, "holes");
    compare(&p, &q, &Tolerance::default()).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let last = q.moves().last().expect("moves");
    assert_eq!((last.end.x, last.end.z), (20.0, 50.0), "{text}");
    assert!(last.is_rapid(), "{text}");
}

/// Found with the tilted-arc test: an arc whose own tool orientation
/// differs from the move before it (`CIRCLE/` then a six-value `GOTO` with a
/// new axis; `G2 … B-30.`) lost it in every G-code target: the arc read back
/// with the old one. Targets that can state it in the arc block do
/// (Sinumerik vectors and angles, Fanuc and LinuxCNC angles); the others
/// refuse at the arc's line (with `lossy`: a warning there).
#[test]
fn an_arc_that_turns_the_tool_keeps_its_orientation_or_refuses() {
    let vectors =
        "PARTNO ARCAXIS\nUNITS/MM\nCUTTER/10,0,5,0,0,0,50\nLOADTL/1\nSPINDL/3000,RPM,CLW\n\
                   FEDRAT/200,MMPM\nGOTO/0,0,10,0,0,1\nGOTO/0,0,0,0,0,1\nCIRCLE/0,10,0,1,0,0,10\n\
                   GOTO/0,10,10,1,0,0\nGOTO/0,20,10,1,0,0\nFINI\n";
    let angles = "%\nO0005\nG21 G90 G17 G94\nT1 M6\nG43 H1 S3000 M3\nG0 X0. Y0. Z10. B0. C0.\n\
                  G1 Z0. F200.\nG2 X10. Y0. I5. J0. B-30.\nG1 X20.\nG0 Z50.\nG49\nM30\n%\n";
    // (source, the arc's line, targets that must write it, the line where
    // a target that cannot take the program's orientations at all refuses)
    let cases = [
        (
            vectors,
            10,
            vec![Target::Sinumerik, Target::Apt],
            Some((Target::LinuxCnc, 7)),
        ),
        (
            angles,
            8,
            vec![Target::Sinumerik, Target::Fanuc, Target::LinuxCnc],
            Some((Target::Apt, 6)),
        ),
    ];
    for (src, arc_line, writes, other) in cases {
        let p = parse(src, "arc");
        let arc = moves(&p)
            .into_iter()
            .find(|(_, m)| m.arc().is_some())
            .expect("arc");
        assert_eq!(arc.1.line, arc_line);
        let want = *arc.0.orient(arc.1).expect("orientation");
        for t in Target::ALL {
            match write(&p, t, false) {
                Out::Refused(e) => {
                    assert!(!writes.contains(&t), "{}: {e}", t.name());
                    let line = match other {
                        Some((o, l)) if o == t => l,
                        _ => arc_line,
                    };
                    assert_eq!(e.line, line, "{}: {e}", t.name());
                    if line == arc_line {
                        let Out::Text(_, w) = write(&p, t, true) else {
                            panic!("{}: lossy refused", t.name())
                        };
                        assert!(
                            w.iter().any(|w| w.starts_with(&format!("{arc_line}:1:"))),
                            "{}: {w:?}",
                            t.name()
                        );
                    }
                }
                Out::Text(text, _) => {
                    assert!(writes.contains(&t), "{} wrote it:\n{text}", t.name());
                    let q = parse(&text, t.name());
                    compare(&p, &q, &Tolerance::default())
                        .unwrap_or_else(|e| panic!("{}: {e}\n{text}", t.name()));
                    let (op, m) = moves(&q)
                        .into_iter()
                        .find(|(_, m)| m.arc().is_some())
                        .expect("the arc");
                    let got = *op.orient(m).expect("an orientation");
                    match (want.axis, got.axis) {
                        (Some(u), Some(v)) => {
                            assert!((u - v).length() < 1e-9, "{}: {v}\n{text}", t.name())
                        }
                        _ => {
                            for k in 0..3 {
                                let close = match (want.angles[k], got.angles[k]) {
                                    (Some(a), Some(b)) => (a - b).abs() < 1e-6,
                                    (a, b) => a.is_none() && b.is_none(),
                                };
                                assert!(close, "{}: {got:?} for {want:?}\n{text}", t.name());
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Found with the writer snapshots: Sinumerik `G4 F1.5` is a dwell of 1.5 s
/// for that block only; it was read as no dwell and a feed of 1.5 for the
/// moves after it. LinuxCNC's `G4 P` is in seconds, Fanuc's in milliseconds.
#[test]
fn dwell_words_are_read_in_each_dialects_unit() {
    let cases = [
        (
            "; dwell\nG17 G710 G90 G94\nT1\nM6\nD1\nG0 X0 Y0 Z5 S1000 M3\nG1 Z0 F300\nG4 F1.5\nG1 X10\nM30\n",
            Dialect::Sinumerik,
        ),
        (
            "G21 G17 G90 G94 G64 P0.01\nT1 M6\nG0 X0 Y0 Z5 S1000 M3\nG1 Z0 F300\nG4 P1.5\nG1 X10\nM30\n",
            Dialect::LinuxCnc,
        ),
        (
            "%\nO0001\nG21 G17 G90 G94\nT1 M6\nG0 X0 Y0 Z5 S1000 M3\nG1 Z0 F300.\nG4 P1500\nG1 X10.\nM30\n%\n",
            Dialect::Fanuc,
        ),
    ];
    for (src, dialect) in cases {
        assert_eq!(detect(src), dialect);
        let p = parse(src, dialect.name());
        let dwells: Vec<f64> = p.operations[0]
            .events
            .iter()
            .filter_map(|e| match e.kind {
                EventKind::Dwell(t) => Some(t),
                _ => None,
            })
            .collect();
        assert_eq!(dwells, [1.5], "{}", dialect.name());
        let last = p.operations[0].moves.last().expect("moves");
        assert_eq!(
            last.feed,
            300.0,
            "{}: the feed after the dwell",
            dialect.name()
        );
    }
}

/// Found with the feed-mode tests: the F of a block was read before the
/// block's G93/G95, so an inch `G93 G1 X1. F50.` read as 50 × 25.4 = 1270
/// moves a minute, and `G95 G1 … F.004` as 0.004 in/rev taken for a
/// per-minute feed first. F is read after the block's feed mode.
#[test]
fn feed_mode_and_f_in_one_block() {
    let src = "%\nO0001\nG20 G17 G90 G94\nT1 M6\nS1000 M3\nG0 X0. Y0. Z1.\nG1 Z0. F10.\n\
               G93 G1 X1. F50.\nG95 G1 X2. F.004\nG94 G1 X3. F20.\nM30\n%\n";
    let p = parse(src, "inch feeds");
    let feeds: Vec<(FeedMode, f64)> = p
        .moves()
        .filter(|m| m.is_cutting())
        .map(|m| (m.feed_mode, m.feed))
        .collect();
    let inch = 25.4;
    let want = [
        (FeedMode::PerMinute, 10.0 * inch),
        (FeedMode::InverseTime, 50.0),
        (FeedMode::PerRev, 0.004 * inch),
        (FeedMode::PerMinute, 20.0 * inch),
    ];
    assert_eq!(feeds.len(), want.len());
    for ((gm, gf), (wm, wf)) in feeds.iter().zip(want) {
        assert_eq!(*gm, wm);
        assert!((gf - wf).abs() < 1e-9, "{gm:?} F{gf}, want F{wf}");
    }
}

/// Found with the writer snapshots: LinuxCNC output read back as Fanuc (it
/// said nothing only LinuxCNC says), so its dwell `G4 P1.000` and `G82 … P1`
/// (seconds) came back as 1 ms. The LinuxCNC header now states `G91.1`
/// (arc centres relative to the start, as the writer writes them), which
/// marks it; the reader knows G91.1 and G90.1 (absolute arc centres).
#[test]
fn linuxcnc_output_reads_back_as_linuxcnc_with_its_dwells() {
    let src = "%\nO0006\nG21 G17 G90 G94\nT1 M6\nG43 H1 S1000 M3\nG0 X0. Y0. Z10.\nG1 Z0. F100.\n\
               G4 P1000\nG0 Z10.\nG99 G82 X30. Y10. Z-4. R2. P1000 F120.\nG80\nM30\n%\n";
    let p = parse(src, "dwells");
    let dwells = |p: &Program| -> (Vec<f64>, Vec<Option<f64>>) {
        let op = &p.operations[0];
        let events = op
            .events
            .iter()
            .filter_map(|e| match e.kind {
                EventKind::Dwell(t) => Some(t),
                _ => None,
            })
            .collect();
        (events, op.cycles.iter().map(|c| c.dwell).collect())
    };
    assert_eq!(dwells(&p), (vec![1.0], vec![Some(1.0)]));
    let (text, q) = through(&p, Target::LinuxCnc, false, "dwells");
    assert_eq!(q.source, Dialect::LinuxCnc, "{text}");
    assert_eq!(dwells(&q), dwells(&p), "{text}");
    // Absolute arc centres.
    let arcs = "G21 G17 G90 G94 G90.1\nT1 M6\nG0 X0 Y0 Z5\nG1 Z0 F100\nG2 X10 Y0 I5 J0\nG91.1\n\
                G3 X0 Y0 I-5 J0\nM2\n";
    let p = parse(arcs, "G90.1");
    let centres: Vec<_> = p.operations[0].arcs.iter().map(|a| a.centre).collect();
    assert_eq!(centres.len(), 2);
    for c in centres {
        assert!(
            (c - millplan_geom::DVec3::new(5.0, 0.0, 0.0)).length() < 1e-9,
            "{c}"
        );
    }
}

/// A machine whose control reads a G93 F as the block's time in seconds
/// (`g93_f = "seconds"`, Beckhoff/ISG): what the writer writes so, the
/// reader told so reads back as the same inverse time (per minute in the
/// IR); read as RS274/NGC's inverse minutes it would not be. `post --g93`
/// on such a machine failed its own read-back on every run.
#[test]
fn g93_feeds_in_seconds_read_back_as_written() {
    let src = "%\nO0001\nG21 G17 G90 G94\nT1 M6\nS2000 M3\nG0 X0. Y0. Z5.\nG1 Z0. F300.\n\
               G93 G1 X10. Y5. F50.\nX20. F25.\nG94 G1 X40. F400.\nM30\n%\n";
    let p = parse(src, "G93");
    let wo = millplan_nc::write::WriteOptions {
        g93_seconds: true,
        ..millplan_nc::write::WriteOptions::new(Target::Fanuc)
    };
    let (bytes, _) = millplan_nc::write::write_program(&p, wo).expect("writes");
    let text = String::from_utf8_lossy(&bytes);
    // 50 blocks a minute: 1.2 s each.
    assert!(text.contains("F1.2"), "{text}");
    let tol = Tolerance::default();
    let back = millplan_nc::readback::read_back_with(&bytes, Target::Fanuc, &p, &tol, true)
        .expect("reads");
    assert!(back.equiv.is_ok(), "{:?}", back.equiv);
    let inverse = back
        .program
        .moves()
        .filter(|m| m.feed_mode == FeedMode::InverseTime)
        .map(|m| m.feed)
        .collect::<Vec<_>>();
    assert_eq!(inverse.len(), 2);
    assert!((inverse[0] - 50.0).abs() < 1e-9 && (inverse[1] - 25.0).abs() < 1e-9);
    let plain = millplan_nc::readback::read_back(&bytes, Target::Fanuc, &p, &tol).expect("reads");
    assert!(plain.equiv.is_err());
}

/// The classic APT form `CYCLE/DRILL, depth, MMPM, feed, clearance` gives
/// its depth and clearance by position: they were dropped, and the holes
/// written to Z0 at the feed (found by trying `convert` on it). A number
/// that neither a word nor the form names is refused at its column.
#[test]
fn positional_cycle_numbers_are_the_depth_and_the_clearance() {
    let src =
        "PARTNO D\nUNITS/MM\nCUTTER/10\nLOADTL/1\nSPINDL/3000,RPM,CLW\nRAPID\nGOTO/20,20,20\n\
               CYCLE/DRILL,5,MMPM,150,3\nGOTO/20,20,0\nCYCLE/OFF\nFINI\n";
    let p = parse(src, "positional cycle");
    let op = &p.operations[0];
    let hole = op
        .moves
        .iter()
        .find(|m| op.cycle(m).is_some())
        .expect("a hole");
    let c = op.cycle(hole).expect("its cycle");
    assert_eq!((c.bottom, c.clearance, c.feed), (-5.0, 3.0, 150.0));
    let bad = src.replace("CYCLE/DRILL,5,MMPM,150,3", "CYCLE/DRILL,5,7,MMPM,150,3");
    let e = millplan_nc::parse_program(&bad, ReadOptions::default()).expect_err("refused");
    assert_eq!((e.line, e.col), (8, 15), "{e}");
    assert!(
        e.message.contains("the number 7 has no word before it"),
        "{e}"
    );
}

/// A ball end written in inches to six decimals (`convert --out-units
/// inch` of the demo) is still a ball when read back, and so is a corner
/// radius a hundred-thousandth of the diameter short of half of it; a
/// corner radius a thousandth short is a bull-nose.
#[test]
fn a_ball_end_written_in_inches_reads_back_as_a_ball() {
    use millplan_nc::ir::CutterKind;
    let kind = |units: &str, cutter: &str| {
        let p = parse(
            &format!(
                "PARTNO/T\nUNITS/{units}\nCUTTER/{cutter}\nLOAD/TOOL,1\nRAPID\nGOTO/0,0,1\nFINI\n"
            ),
            cutter,
        );
        let tool = p.operations[0].tool.as_ref().expect("a tool");
        tool.cutter.expect("a cutter").kind
    };
    assert_eq!(
        kind("INCHES", "0.393701,0.19685,0,0.19685,0,0,0"),
        CutterKind::Ball
    );
    assert_eq!(kind("MM", "10,4.99999"), CutterKind::Ball);
    assert_eq!(kind("MM", "10,4.99"), CutterKind::Bull);
}

/// The line of each `program-end` warning of `src`.
fn end_warnings(src: &str) -> Vec<u32> {
    let parsed = millplan_nc::parse_program(src, ReadOptions::default()).expect("reads");
    let code = millplan_nc::diag::Code::ProgramEnd;
    (parsed.diagnostics.iter())
        .filter(|d| d.code == code)
        .map(|d| d.line)
        .collect()
}

/// A user trial: a program cut short in its transfer (no M30, its last
/// line missing its Z) read without a word, and a move after M30 read as
/// if the control ran it, so that a conversion, whose writer ends the
/// program after everything it read, would have run it. A program without
/// an end is warned of at its last block; a block after the end is refused
/// at its line, in G-code, Heidenhain and APT alike.
#[test]
fn a_program_without_its_end_is_warned_of_and_a_block_after_it_refused() {
    let head = "%\nO1000\nG21 G90 G17\nT1 M6\nG43 H1 Z50\nS5000 M3\nG0 X0 Y0\nG1 Z-1 F500\nX10\n";
    // Cut short: no M30, no closing %, the last line without its Z.
    assert_eq!(end_warnings(&format!("{head}X53.9 Y8.7 ")), [10]);
    // Ended by M30, by M2, by a closing % alone, by a subprogram's M99 or
    // M17: no warning; comments after the end are let be.
    for end in [
        "M30\n%\n",
        "M2\n",
        "%\n",
        "M99\n",
        "M17\n",
        "M30\n(END)\n%\n",
    ] {
        assert_eq!(
            end_warnings(&format!("{head}{end}")),
            [] as [u32; 0],
            "{end}"
        );
    }
    // A block after M30 (or after the closing %) is never run: refused there.
    for (tail, line) in [("M30\nG1 X100 Y100\n%\n", 11), ("%\nG1 X100\n", 11)] {
        let e = millplan_nc::parse_program(&format!("{head}{tail}"), ReadOptions::default())
            .expect_err(tail);
        assert_eq!((e.line, e.col), (line, 1), "{tail}: {e}");
        assert!(e.message.contains("after the end of the program"), "{e}");
    }
    // Heidenhain: END PGM.
    let h = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S5000\n2 L X+0 Y+0 Z+50 R0 FMAX M3\n3 L Z-1 F500\n";
    assert_eq!(end_warnings(h), [4]);
    assert_eq!(
        end_warnings(&format!("{h}4 END PGM T MM\n")),
        [] as [u32; 0]
    );
    let e = millplan_nc::parse_program(
        &format!("{h}4 END PGM T MM\n5 L X+100 F500\n"),
        ReadOptions::default(),
    )
    .expect_err("after END PGM");
    assert_eq!(e.line, 6, "{e}");
    // APT: FINI, or NX's END-OF-PATH last.
    let a = "PARTNO T\nUNITS/MM\nCUTTER/10,5,0,5,0,0,0\nLOADTL/1\nFEDRAT/500,MMPM\nGOTO/0,0,1\nGOTO/10,0,1\n";
    assert_eq!(end_warnings(a), [7]);
    assert_eq!(end_warnings(&format!("{a}FINI\n")), [] as [u32; 0]);
    assert_eq!(
        end_warnings(&format!("{a}END-OF-PATH\nPPRINT DONE\n")),
        [] as [u32; 0]
    );
    let e = millplan_nc::parse_program(&format!("{a}FINI\nGOTO/20,0,1\n"), ReadOptions::default())
        .expect_err("after FINI");
    assert_eq!((e.line, e.col), (9, 1), "{e}");
}

/// The real samples that end as their CAM system wrote them read without
/// a `program-end` warning; the Roeders fragment (bare G-code, no end) and
/// the impeller's GOTO lists are warned of.
#[test]
fn the_samples_say_whether_they_end() {
    let cases = [
        (MORI, false),
        (DMU, false),
        (ACHSKREUZ, false),
        (BOTTLE, false),
        (BEAR, false),
        (BOSS, false),
        (DMC100, false),
        ("nx-clsf-ballend-nurbs/nurbs.clsf", false),
        (
            "nx-posted-gcode-samples/roeders_rfm600_finish_profile_mm.ptp",
            true,
        ),
        ("impeller-5axis-goto-fragments/yelun.txt", true),
    ];
    for (rel, warned) in cases {
        let Some(text) = sample(rel) else {
            continue;
        };
        let parsed = millplan_nc::parse_program(&text, common::options_for(rel)).expect(rel);
        let code = millplan_nc::diag::Code::ProgramEnd;
        let got = parsed.diagnostics.iter().any(|d| d.code == code);
        assert_eq!(got, warned, "{rel}");
    }
}

/// A trial finding: G43.1, G43.2 and an H without G43 change the tool
/// length in use, but were kept verbatim with Z read as before them; a move
/// after them then ran at a height the program never set. Z is now unknown
/// after them until the program commands it, and G43.1/G43.2 with axis
/// words (offsets, not a position) are refused at their word. G44 is
/// refused: under it a Z word names the tip only with negative lengths in
/// the tool table (a review: Z read as the tip after `G44 H2 Z40`).
#[test]
fn length_changes_not_modelled_leave_z_unknown() {
    let head = "%\nO1\nG21 G90 G17\nT1 M6\nG43 H1 Z50\nS5000 M3\nG0 X0 Y0\nG1 Z5 F500\n";
    for change in ["H3", "G43.1", "G43.2 H4"] {
        let src = format!("{head}{change}\nG1 X10\nZ4\nX20\nM30\n%\n");
        let p = parse(&src, change);
        let m = &p.operations[0].moves;
        let at = |x: f64| m.iter().find(|mv| mv.end.x == x).expect("the move");
        assert!(at(10.0).end.z.is_nan(), "{change}: {:?}", at(10.0).end);
        assert_eq!(at(20.0).end.z, 4.0, "{change}");
        let kept = p.operations[0].events.iter().any(|e| {
            matches!(&e.kind, EventKind::Passthrough(t) if t.moves && t.text.contains(change.split(' ').next().unwrap_or("")))
        });
        assert!(kept, "{change}: kept verbatim as a block that may move");
    }
    let e = millplan_nc::parse_program(&format!("{head}G43.1 Z1.5\nM30\n"), ReadOptions::default())
        .expect_err("G43.1 Z");
    assert_eq!((e.line, e.col), (9, 1), "{e}");
    let e = millplan_nc::parse_program(
        &format!("{head}G0 G44 H2 Z40\nM30\n"),
        ReadOptions::default(),
    )
    .expect_err("G44");
    assert_eq!((e.line, e.col), (9, 4), "{e}");
}

/// Trial findings on Heidenhain: `FUNCTION TCPM` with a rotary axis turned
/// makes X, Y and Z name another point (as M128 does), and a `TOOL CALL`
/// of the tool in use with a length delta moves its tip along the axis;
/// both were kept verbatim with the positions read as before them. Now
/// the positions are unknown until the program commands them.
#[test]
fn heidenhain_tcpm_and_a_length_delta_leave_the_positions_unknown() {
    let head = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S5000\n2 L X+0 Y+0 Z+50 R0 FMAX M3\n";
    let cases = [
        (
            "3 L B+30 FMAX\n4 FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\n",
            true,
        ),
        ("3 L B+30 FMAX\n4 FUNCTION RESET TCPM\n", true),
        // With the rotary axes at 0 the tip and the pivot are one point.
        (
            "3 L B+0 FMAX\n4 FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\n",
            false,
        ),
        ("3 L Z+40 FMAX\n4 TOOL CALL Z S6000 DL+0.5\n", true),
        ("3 L Z+40 FMAX\n4 TOOL CALL Z S6000\n", false),
    ];
    for (mid, unknown) in cases {
        let src = format!("{head}{mid}5 L X+10 F500\n6 L Z+30\n7 END PGM T MM\n");
        let p = parse(&src, mid);
        let m = &p.operations[0].moves;
        let at = |line: u32| m.iter().find(|mv| mv.line == line).expect("the move");
        // Blocks 5 and 6 are the file's lines 6 and 7.
        assert_eq!(at(6).end.z.is_nan(), unknown, "{mid}: {:?}", at(6).end);
        assert_eq!(at(7).end.z, 30.0, "{mid}");
    }
}

/// A review of the program end: a comment before the opening `%`, a
/// numbered comment or a lone block number after M30, a Sinumerik RET, a
/// PPRINT after FINI, a `*` block after END PGM and a trailing Ctrl-Z all
/// read as their controls take them; a file of comments only is not
/// warned of at a line 0.
#[test]
fn the_program_end_lets_comments_and_marks_be() {
    let body = "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F500\n";
    for src in [
        format!("(MAIN PROGRAM)\n%\nO1000\n{body}M30\n%\n"),
        format!("{body}N100 M30\nN110 (END)\n"),
        format!("{body}N80 M30\nN90 ;END OF PROGRAM\nN9999\n"),
        format!("{body}M30\n\u{1a}\n"),
        format!("{body}RET\n"),
    ] {
        assert_eq!(end_warnings(&src), [] as [u32; 0], "{src}");
    }
    let h = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S5000\n2 L Z+50 R0 FMAX\n3 END PGM T MM\n";
    assert_eq!(
        end_warnings(&format!("{h}4 * - NOTES\n\u{1a}\n")),
        [] as [u32; 0]
    );
    let a = "PARTNO T\nUNITS/MM\nCUTTER/10,5,0,5,0,0,0\nGOTO/0,0,1\nFINI\n";
    assert_eq!(
        end_warnings(&format!("{a}PPRINT DONE\n\u{1a}\n")),
        [] as [u32; 0]
    );
    // Comments only: nothing cut short, no warning at a line 0.
    let parsed = millplan_nc::parse_program("(NOTHING)\n(ELSE)\nG21\n", ReadOptions::default());
    if let Ok(p) = parsed {
        assert!(p
            .diagnostics
            .iter()
            .all(|d| d.line > 0 || d.code != millplan_nc::diag::Code::ProgramEnd));
    }
}

/// A program that began as a whole one (a tape's %, a program number, a
/// tool change; a header record in APT; BEGIN PGM) and has no end was cut
/// short: `Program::unterminated` names its last block, and the checks of
/// what a pass writes refuse it. Bare blocks or a bare list of GOTOs (the
/// impeller fragments, the Roeders profile) are fragments by nature:
/// warned of only.
#[test]
fn a_program_cut_short_is_told_from_a_fragment() {
    let read = |src: &str| {
        millplan_nc::parse_program(src, ReadOptions::default())
            .expect("reads")
            .program
            .unterminated
    };
    let body = "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F500\nX10\n";
    assert_eq!(read(&format!("%\nO1\n{body}")), Some(6));
    assert_eq!(read(&format!("T1 M6\n{body}")), Some(5));
    assert_eq!(read(body), None);
    assert_eq!(read(&format!("%\nO1\n{body}M30\n%\n")), None);
    let gotos = "GOTO/0,0,1\nGOTO/10,0,1\n";
    assert_eq!(read(&format!("PARTNO T\nUNITS/MM\n{gotos}")), Some(4));
    assert_eq!(read(gotos), None);
    let h = "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S5000\n2 L Z+50 R0 FMAX\n";
    assert_eq!(read(h), Some(3));
    for rel in [
        "impeller-5axis-goto-fragments/yelun.txt",
        "nx-posted-gcode-samples/roeders_rfm600_finish_profile_mm.ptp",
    ] {
        if let Some(p) = read_sample(rel) {
            assert_eq!(p.unterminated, None, "{rel}");
        }
    }
}
