//! The fuzzing of issue 17, kept as properties that run with the tests (a
//! fixed number of cases each, a few seconds in all): every reader, fed the
//! hostile inputs of the issue and random mutations of them, never panics,
//! stays within its limits and gives either a program whose every number is
//! finite or an error located in the input; every writer, given what the
//! readers accept, writes or refuses without panicking and never writes a
//! number that is not finite.

use millplan_geom::stl::read_stl_limited;
use millplan_nc::write::{preflight, write_program, Target, WriteOptions};
use millplan_nc::{parse_program, Limits, ReadOptions};
use proptest::prelude::*;

/// Limits small enough that no case can take long.
fn limits() -> Limits {
    Limits {
        moves: 200_000,
        expansion: 2_000,
        line_bytes: 4_096,
        expression_depth: 32,
        stl_triangles: 5_000,
        stl_extent: 1e5,
        memory: 100_000_000,
    }
}

fn opts() -> ReadOptions {
    ReadOptions {
        limits: limits(),
        ..ReadOptions::default()
    }
}

/// The issue's inputs, one per reader and hostile case.
const SEEDS: &[&str] = &[
    // NURBS with control points at 1e12.
    "CUTTER/10\nFEDRAT/100\nGOTO/0,0,0\nNURBS/\nKNOT/0.5,1\nCNTRL/1e12,0,0\nCNTRL/0,1e12,0\nCNTRL/1e12,1e12,0\nCNTRL/0,0,1e12\nFINI\n",
    // Inch APT whose coordinate overflows in mm.
    "UNITS/INCHES\nCUTTER/0.5\nFEDRAT/10\nGOTO/0,0,1\nGOTO/1e308,1,1\nFINI\n",
    // APT CYCLE/DEEP with a tiny peck.
    "UNITS/MM\nCUTTER/10\nFEDRAT/100\nGOTO/0,0,10\nCYCLE/DEEP,FEDTO,20,STEP,0.000001,RAPTO,2,MMPM,100\nGOTO/10,10,0\nCYCLE/OFF\nFINI\n",
    // A circle of radius 1e6 off the principal planes.
    "UNITS/MM\nCUTTER/10\nFEDRAT/100\nGOTO/1000000,0,0\nCIRCLE/0,0,0,0,0.6,0.8,1000000,0.06,0.5,25.0,0.0\nGOTO/0,800000,-600000\nFINI\n",
    // G83 with a tiny peck.
    "G21 G17 G90 G94\nT2 M6\nG43 H2 S1500 M3\nG0 X10. Y10. Z5.\nG98 G83 X10. Y10. Z-20. R2. Q0.000001 F100.\nX30.\nG80\nM30\n",
    // Heidenhain cycle 200 with a tiny plunging depth.
    "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 200 DRILLING ~\n  Q200=2 ;SET-UP CLEARANCE ~\n  Q201=-20 ;DEPTH ~\n  Q206=150 ;FEED RATE ~\n  Q202=0.000001 ;PLUNGING DEPTH ~\n  Q210=0 ;DWELL TIME AT TOP ~\n  Q203=+0 ;SURFACE COORDINATE ~\n  Q204=50 ;2ND SET-UP CLEARANCE ~\n  Q211=0 ;DWELL TIME AT BOTTOM\n4 L X+10 Y+10 R0 FMAX M99\n5 END PGM P MM\n",
    // Heidenhain cycle 1.
    "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 1.0 PECKING\n4 CYCL DEF 1.1 SET UP 2\n5 CYCL DEF 1.2 DEPTH -20\n6 CYCL DEF 1.3 PECKG 0.000001\n7 CYCL DEF 1.4 DWELL 0\n8 CYCL DEF 1.5 F150\n9 L X+10 Y+10 R0 FMAX M99\n10 END PGM P MM\n",
    // Sinumerik with a deep expression.
    "N10 G710 G90\nN20 TRAORI\nN30 DEF REAL _Z\nN40 T=\"BALL\" D1\nN50 G1 X1 Y1 Z=-------------------------------------------------5 F100\nN60 M30\n",
    // LinuxCNC with parameters and an arc.
    "G21 G90\nT1 M6\n#<r>=5\nG0 X0 Y0 Z5\nG1 Z0 F100\nG2 X10 Y0 I5 J0\nG1 X#<r>\nM30\n",
    // CR-only Fanuc.
    "G21 G90\rT1 M6\rG0 X0 Y0 Z5\rG1 Z0 F100\rG1 X10\rG1 Y10\rM30\r",
];

/// Words that hurt: overflowing, tiny, not numbers, deep, long.
const HOSTILE: &[&str] = &[
    "1e308",
    "-1e308",
    "1e-300",
    "0.000001",
    "nan",
    "inf",
    "-inf",
    "1e12",
    "-0",
    "0",
    "((((((((((((((((((((((((((((((((((1",
    "----------------------------------------1",
    "999999999999999999999999999999999999999999",
    "$",
    "$$",
    "~",
    ";",
    "(",
    ")",
    "=",
    "CIRCLE/0,0,0,0,0.6,0.8,1e6",
    "NURBS/",
    "KNOT/0.5,1",
    "CNTRL/1e12,0,0",
    "G83 Q0.000001",
    "CYCL DEF 1.3 PECKG 0.000001",
    "UNITS/INCHES",
    "G20",
    "G2 X1 R1e300",
    "CC X+1e300",
];

/// Every number a program holds is finite, and reading stayed in limits.
fn check_program(src: &str) {
    match parse_program(src, opts()) {
        Ok(p) => {
            if let Err(e) = preflight::finite(&p.program) {
                // Readers may keep what overflows; the binary refuses it
                // where it reads. Never a panic, and located.
                assert!(e.line as usize <= src.len() + 1, "{e}");
            }
            let lines = millplan_nc::lines::split(src).count() as u64;
            assert!(
                (p.program.move_count() as u64) <= lines * (limits().expansion + 8) + 8,
                "{} moves from {lines} lines",
                p.program.move_count()
            );
            write_every_target(&p.program, src);
        }
        Err(e) => {
            let lines = millplan_nc::lines::split(src).count() as u32;
            assert!(e.line <= lines + 1 && e.col >= 1, "{e} ({lines} lines)");
        }
    }
}

/// Every target writes or refuses; no number it writes is not finite (a
/// word kept verbatim from the source, `-inf` for all a reader knows, is the
/// source's own).
fn write_every_target(p: &millplan_nc::Program, src: &str) {
    // A line without its block number (`12 L X+1`, `N20 G1`): a verbatim
    // block is renumbered by the writer.
    // (and without a `;` comment, which a writer may leave out).
    let body = |l: &str| -> String {
        let l = l.split(';').next().unwrap_or("").trim();
        let l = l.strip_prefix('N').unwrap_or(l);
        l.trim_start_matches(|c: char| c.is_ascii_digit())
            .trim()
            .to_string()
    };
    let verbatim: Vec<String> = millplan_nc::lines::split(src)
        .map(body)
        .filter(|l| !l.is_empty())
        .collect();
    for t in Target::ALL {
        let o = WriteOptions {
            limits: limits(),
            ..WriteOptions::new(t)
        };
        let Ok((out, _)) = write_program(p, o) else {
            continue;
        };
        let text = String::from_utf8_lossy(&out);
        for line in text.lines() {
            let b = body(line);
            if verbatim.iter().any(|v| b.contains(v.as_str())) {
                continue;
            }
            // Comments carry the source's words (APT's as PPRINT text).
            if line.trim_start().starts_with("PPRINT") {
                continue;
            }
            let code = line.split([';', '(']).next().unwrap_or("");
            let code = code.split("$$").next().unwrap_or("");
            for w in code.split(|c: char| !c.is_ascii_alphanumeric() && c != '.' && c != '-') {
                let body = w.trim_start_matches(|c: char| c.is_ascii_alphabetic());
                assert!(
                    !matches!(body, "NaN" | "inf" | "-inf"),
                    "{} wrote `{w}` in `{line}`",
                    t.name()
                );
            }
        }
    }
}

#[test]
fn the_issue_inputs_are_read_or_refused_in_bounds() {
    for s in SEEDS {
        check_program(s);
        for nl in ["\r\n", "\r"] {
            check_program(&millplan_nc::lines::split(s).collect::<Vec<_>>().join(nl));
        }
    }
}

/// A seed with lines replaced, inserted or dropped, numbers swapped for
/// hostile ones and line endings mixed.
fn mutated() -> impl Strategy<Value = String> {
    (
        prop::sample::select(SEEDS),
        prop::collection::vec(
            (
                any::<prop::sample::Index>(),
                0..4u8,
                prop::sample::select(HOSTILE),
            ),
            0..6,
        ),
        prop::sample::select(&["\n", "\r\n", "\r"][..]),
    )
        .prop_map(|(seed, edits, nl)| {
            let mut lines: Vec<String> = millplan_nc::lines::split(seed)
                .map(str::to_string)
                .collect();
            for (at, how, word) in edits {
                let i = at.index(lines.len().max(1));
                match how {
                    0 => lines.insert(i, word.to_string()),
                    1 if i < lines.len() => lines[i] = format!("{}{word}", lines[i]),
                    2 if i < lines.len() => {
                        // Replace the last number of the line.
                        let l = &lines[i];
                        let cut = l
                            .rfind(|c: char| !(c.is_ascii_digit() || c == '.'))
                            .map_or(0, |k| k + 1);
                        lines[i] = format!("{}{word}", &l[..cut]);
                    }
                    _ if i < lines.len() => {
                        lines.remove(i);
                    }
                    _ => {}
                }
            }
            lines.join(nl)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn readers_and_writers_stay_in_bounds_on_mutated_seeds(src in mutated()) {
        check_program(&src);
    }

    #[test]
    fn expressions_of_any_nesting_are_bounded(depth in 0usize..5000, sign in prop::sample::select(&["-", "+", "(", "(-"][..])) {
        let e = format!("{}1{}", sign.repeat(depth), ")".repeat(if sign.contains('(') { depth } else { 0 }));
        let src = format!("N10 G710\nN20 DEF REAL _Z\nN30 G1 X1 Z={e} F100\nN40 M30\n");
        check_program(&src);
        let ngc = format!("G21\nT1 M6\n#<a>={e}\nG1 X#<a> F100\nM30\n");
        check_program(&ngc);
    }

    #[test]
    fn nurbs_of_any_control_points_are_bounded(
        pts in prop::collection::vec(prop::array::uniform3(prop::sample::select(&[0.0, 1.0, -7.5, 1e3, 1e6, 1e12, -1e12, 1e300][..])), 4..9),
    ) {
        let mut src = String::from("UNITS/MM\nCUTTER/10\nFEDRAT/100\nGOTO/0,0,0\nNURBS/\n");
        let n = pts.len() + 1;
        let knots: Vec<String> = (1..=n - 3).map(|k| format!("{:.4}", k as f64 / (n - 3) as f64)).collect();
        src += &format!("KNOT/{}\n", knots.join(","));
        for p in &pts {
            src += &format!("CNTRL/{},{},{}\n", p[0], p[1], p[2]);
        }
        src += "FINI\n";
        check_program(&src);
    }

    #[test]
    fn stl_bytes_are_read_in_bounds(
        facets in prop::collection::vec(prop::array::uniform9(prop::sample::select(&[0.0f32, 1.0, -3.0, 1e5, 1e30, -1e30, f32::NAN, f32::INFINITY, 2.5][..])), 0..40),
        count in prop::option::of(any::<u32>()),
        cut in any::<prop::sample::Index>(),
        ascii in any::<bool>(),
        nl in prop::sample::select(&["\n", "\r\n", "\r"][..]),
    ) {
        let bytes = if ascii {
            let mut s = format!("solid fuzz{nl}");
            for f in &facets {
                s += &format!("facet normal 0 0 1{nl}outer loop{nl}");
                for v in f.chunks(3) {
                    s += &format!("vertex {} {} {}{nl}", v[0], v[1], v[2]);
                }
                s += &format!("endloop{nl}endfacet{nl}");
            }
            s += "endsolid";
            s.into_bytes()
        } else {
            let mut b = vec![0u8; 80];
            b.extend_from_slice(&count.unwrap_or(facets.len() as u32).to_le_bytes());
            for f in &facets {
                b.extend_from_slice(&[0u8; 12]);
                for c in f {
                    b.extend_from_slice(&c.to_le_bytes());
                }
                b.extend_from_slice(&[0, 0]);
            }
            b
        };
        let bytes = if count.is_some() { &bytes[..cut.index(bytes.len() + 1)] } else { &bytes[..] };
        if let Ok((mesh, _)) = read_stl_limited(bytes, &limits()) {
            prop_assert!(mesh.len() as u64 <= limits().stl_triangles);
            for v in &mesh.vertices {
                prop_assert!(v.is_finite() && v.abs().max_element() <= limits().stl_extent);
            }
        }
    }
}
