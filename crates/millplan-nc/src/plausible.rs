//! The plausibility limit on the numbers a program gives (issue 34): an axis
//! word, feed or spindle speed that is finite but absurd (`X1e308`,
//! `FU1e308`, `A+1e308`) is refused at its source line when the reader
//! finishes, so that no model downstream turns it into an infinite length,
//! a zero feed or `Ainf` in a written program. The limits are
//! [`millplan_geom::limits::NC_EXTENT`] (coordinates and arc radii, mm;
//! rotary positions, degrees) and [`millplan_geom::limits::NC_RATE`] (feeds
//! and spindle speeds), documented in the limits table of docs/usage.md.

use crate::diag::{Code, Diagnostic, ParseError, Severity};
use crate::ir::{EventKind, MoveKind, Operation, Program, SpindleDir};
use millplan_geom::limits::{NC_DWELL, NC_EXTENT, NC_RATE};

/// The smallest feed a feed move may ask for, mm/min or mm/rev (a block
/// time of a million minutes under inverse time, 1e-6 1/min): a positive
/// feed below it (`FEDRAT/1e-300`) is absurd, and a writer's three
/// decimals would turn it into `F0.`.
pub const MIN_FEED: f64 = 1e-3;
const MIN_INVERSE_TIME: f64 = 1e-6;

/// The smallest spindle speed a move may be given, 1/min: a positive speed
/// below one revolution a minute (`SPINDL/1e-300`) is absurd, and the force
/// models would turn its feed per tooth into an infinite force. `S0` is a
/// stopped spindle, not refused here (see [`warnings`]).
pub const MIN_SPINDLE: f64 = 1.0;

/// Positive and below the smallest plausible feed of its mode.
fn too_slow(feed: f64, mode: crate::ir::FeedMode) -> bool {
    let min = match mode {
        crate::ir::FeedMode::InverseTime => MIN_INVERSE_TIME,
        _ => MIN_FEED,
    };
    feed > 0.0 && feed < min
}

fn refuse_slow(line: u32, what: &str, v: f64) -> ParseError {
    ParseError::new(
        line,
        1,
        format!("{what} {v:e} is below the smallest plausible feed ({MIN_FEED} mm/min or mm/rev, {MIN_INVERSE_TIME} 1/min under inverse time): no machine cuts that slowly"),
    )
}

/// Finite and beyond `limit` (a number that is not finite is refused by
/// [`crate::write::preflight::finite`] with its own message).
fn over(v: f64, limit: f64) -> bool {
    v.is_finite() && v.abs() > limit
}

fn refuse(line: u32, what: &str, v: f64, limit: f64, unit: &str) -> ParseError {
    ParseError::new(
        line,
        1,
        format!(
            "{what} {v:e} is beyond the plausibility limit of {limit:e} {unit}: no machine moves there"
        ),
    )
}

/// Refuses the first number of `p` beyond its plausibility limit, at its
/// source line. Unknown (NaN) coordinates pass: they are never used.
pub fn check(p: &Program) -> Result<(), ParseError> {
    p.operations.iter().try_for_each(check_op)
}

/// Refuses a dwell (an event's, or a cycle's at the bottom) beyond
/// [`NC_DWELL`] at `line`.
fn dwell(line: u32, what: &str, t: f64) -> Result<(), ParseError> {
    if over(t, NC_DWELL) {
        return Err(ParseError::new(
            line,
            1,
            format!("{what} {t:e} s, is beyond the plausibility limit of {NC_DWELL} s (a day): a unit slip, or a runaway number"),
        ));
    }
    Ok(())
}

fn check_op(op: &Operation) -> Result<(), ParseError> {
    for e in &op.events {
        if let EventKind::Dwell(t) = e.kind {
            dwell(e.line, "this dwell,", t)?;
        }
    }
    for c in &op.cycles {
        if let Some(t) = c.dwell {
            dwell(c.line, "the dwell of this cycle,", t)?;
        }
        // More pecks a hole than any target writes: every model would take
        // the hole as one stroke, where the control pecks on for hours.
        crate::write::check_pecks(c).map_err(|e| ParseError::new(e.line, 1, e.message))?;
        for v in [c.bottom, c.clearance, c.retract] {
            if over(v, NC_EXTENT) {
                return Err(refuse(
                    c.line,
                    "a height of this cycle,",
                    v,
                    NC_EXTENT,
                    "mm",
                ));
            }
        }
        if too_slow(c.feed, crate::ir::FeedMode::PerMinute) {
            return Err(refuse_slow(c.line, "the feed of this cycle,", c.feed));
        }
        if over(c.feed, NC_RATE) {
            return Err(refuse(
                c.line,
                "the feed of this cycle,",
                c.feed,
                NC_RATE,
                "per minute",
            ));
        }
    }
    for m in &op.moves {
        if let Some(v) = m.end.to_array().into_iter().find(|v| over(*v, NC_EXTENT)) {
            return Err(refuse(
                m.line,
                "a coordinate of this move,",
                v,
                NC_EXTENT,
                "mm",
            ));
        }
        if !matches!(m.kind, MoveKind::Rapid) && too_slow(m.feed, m.feed_mode) {
            return Err(refuse_slow(m.line, "the feed of this move,", m.feed));
        }
        if over(m.feed, NC_RATE) {
            return Err(refuse(
                m.line,
                "the feed of this move,",
                m.feed,
                NC_RATE,
                "per minute or per revolution",
            ));
        }
        if m.spindle < 0.0 {
            // `TOOL CALL 1 Z S-1`: the G-code readers refuse `S-1` as they
            // read it; a reader that takes the sign is refused here.
            return Err(ParseError::new(
                m.line,
                1,
                format!(
                    "the spindle speed of this move, {}, is negative: give the speed and the direction (M3/M4) apart",
                    m.spindle
                ),
            ));
        }
        if !matches!(m.kind, MoveKind::Rapid) && m.spindle > 0.0 && m.spindle < MIN_SPINDLE {
            return Err(ParseError::new(
                m.line,
                1,
                format!(
                    "the spindle speed of this move, {:e}, is below the smallest plausible speed ({MIN_SPINDLE} 1/min): no spindle cuts that slowly",
                    m.spindle
                ),
            ));
        }
        if over(m.spindle, NC_RATE) {
            return Err(refuse(
                m.line,
                "the spindle speed of this move,",
                m.spindle,
                NC_RATE,
                "1/min",
            ));
        }
        if let Some(a) = m.orient.and_then(|id| op.orients.get(id.index())) {
            let deg = a.angles.iter().flatten().map(|r| r.to_degrees());
            if let Some(v) = deg.into_iter().find(|v| over(*v, NC_EXTENT)) {
                return Err(refuse(
                    m.line,
                    "a rotary axis position of this move,",
                    v,
                    NC_EXTENT,
                    "degrees",
                ));
            }
        }
        if let MoveKind::Arc(id) = m.kind {
            if let Some(a) = op.arcs.get(id.index()) {
                let far = a.centre.to_array().into_iter().chain([a.radius]);
                if let Some(v) = far.into_iter().find(|v| over(*v, NC_EXTENT)) {
                    return Err(refuse(
                        m.line,
                        "the centre or radius of this arc,",
                        v,
                        NC_EXTENT,
                        "mm",
                    ));
                }
            }
        }
    }
    Ok(())
}

/// A warning at each spindle start (M3/M4, `SPINDL/…,CLW`) whose speed is 0
/// (`S0 M03`, as real NX posts write) and after which a feed move runs
/// before the speed is given: the program is copied as written, and a pass
/// that needs the spindle speed refuses that move at its line (issue 34).
pub fn warnings(p: &Program) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for op in &p.operations {
        for e in &op.events {
            if !matches!(e.kind, EventKind::Spindle(SpindleDir::Cw | SpindleDir::Ccw)) {
                continue;
            }
            let after = op.moves.iter().skip(e.at as usize);
            let first_cut = after
                .take_while(|m| m.spindle == 0.0)
                .find(|m| !matches!(m.kind, MoveKind::Rapid));
            if let Some(m) = first_cut {
                out.push(Diagnostic {
                    severity: Severity::Warning,
                    code: Code::SpindleStopped,
                    line: e.line,
                    col: 0,
                    message: format!(
                        "the spindle starts at speed 0 and the move at line {} cuts before a speed is given: copied as written; feed and force refuse that move",
                        m.line
                    ),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(src: &str) -> Vec<Diagnostic> {
        let parsed = crate::parse_program(src, crate::ReadOptions::default()).expect("reads");
        parsed
            .diagnostics
            .into_iter()
            .filter(|d| d.code == Code::SpindleStopped)
            .collect()
    }

    /// A user trial: `G82 … P` with 40 digits was read, and `inspect`
    /// printed a cycle time of 1e37 s. A dwell beyond a day is refused at
    /// its line, in a G4 block and in a cycle.
    #[test]
    fn an_absurd_dwell_is_refused_at_its_line() {
        let big = "1".repeat(40);
        let g4 = format!("G21 G90\nG0 X0 Y0 Z5\nG4 P{big}.\nM30\n");
        let cycle = format!("G21 G90\nG0 X0 Y0 Z5\nG98 G82 X1 Y1 Z-2 R2 P{big}. F100\nG80\nM30\n");
        for src in [g4, cycle] {
            let e = crate::parse_program(&src, crate::ReadOptions::default()).expect_err("refused");
            assert_eq!(e.line, 3, "{e}");
            assert!(
                e.to_string().contains("plausibility limit of 86400 s"),
                "{e}"
            );
        }
        let ok = "G21 G90\nG0 X0 Y0 Z5\nG4 P3600.\nM30\n";
        crate::parse_program(ok, crate::ReadOptions::default()).expect("an hour's dwell reads");
    }

    /// A user trial: an R of 30 digits in a cycle was refused at the
    /// line's first column. The G-code readers refuse it at the R word.
    #[test]
    fn an_absurd_r_word_is_refused_at_its_column() {
        let r = format!("R{}", "9".repeat(30));
        for (src, col) in [
            (
                format!("G21 G90\nG0 X0 Y0 Z5\nG98 G81 X1 Y1 Z-2 {r} F100\nG80\nM30\n"),
                19,
            ),
            (
                format!("G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F100\nG2 X1 {r}\nM30\n"),
                7,
            ),
        ] {
            let e = crate::parse_program(&src, crate::ReadOptions::default()).expect_err("refused");
            assert_eq!(
                (e.col, e.to_string().contains("plausibility limit")),
                (col, true),
                "{e}"
            );
        }
    }

    /// A user trial: a hole of more pecks than any writer writes was
    /// refused by `convert` but read by `inspect`, `simulate` and `gouge`,
    /// each taking it as one stroke. It is refused where it is read, at the
    /// cycle's line, in every reader; a thousand pecks still read.
    #[test]
    fn more_pecks_a_hole_than_any_target_writes_are_refused_at_the_cycle() {
        let g = "G21 G90\nG0 X0 Y0 Z5\nG98 G83 X1 Y1 Z-20 R2 Q0.0001 F100\nG80\nM30\n";
        let apt = "UNITS/MM\nCUTTER/10\nFEDRAT/100\nGOTO/0,0,10\nCYCLE/DEEP,FEDTO,20,STEP,0.0001,RAPTO,2,MMPM,100\nGOTO/10,10,0\nCYCLE/OFF\nFINI\n";
        let h = "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 1.0 PECKING\n4 CYCL DEF 1.1 SET UP 2\n5 CYCL DEF 1.2 DEPTH -20\n6 CYCL DEF 1.3 PECKG 0.0001\n7 CYCL DEF 1.4 DWELL 0\n8 CYCL DEF 1.5 F150\n9 L X+10 Y+10 R0 FMAX M99\n10 END PGM P MM\n";
        for (src, line) in [(g, 3), (apt, 5), (h, 4)] {
            let e = crate::parse_program(src, crate::ReadOptions::default()).expect_err("refused");
            assert_eq!(e.line, line, "{e}");
            assert!(e.to_string().contains("at most 1000 are accepted"), "{e}");
        }
        // 22 mm in pecks of 0.0221 mm: 996 pecks, within the limit.
        let ok = g.replace("Q0.0001", "Q0.0221");
        let p = crate::parse_program(&ok, crate::ReadOptions::default()).expect("reads");
        assert_eq!(p.program.operations[0].cycles[0].pecks(), 996);
    }

    /// Issue 34's fuzz campaign: `feed` on an APT with `FEDRAT/1e-300`
    /// wrote `FEDRAT/0`. The reader refuses the feed at its line.
    #[test]
    fn an_absurdly_slow_feed_is_refused_at_its_line() {
        let src = "UNITS/MM\nCUTTER/10,5\nFEDRAT/1e-300\nGOTO/0,0,50\nGOTO/0,0,19\nFINI\n";
        let e = crate::parse_program(src, crate::ReadOptions::default()).expect_err("refused");
        assert_eq!(e.line, 4, "{e}");
        assert!(e.to_string().contains("smallest plausible feed"), "{e}");
        let g = "G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F0.0001\nM30\n";
        let e = crate::parse_program(g, crate::ReadOptions::default()).expect_err("refused");
        assert_eq!(e.line, 3, "{e}");
        // A slow but real feed reads.
        let ok = "G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F0.5\nM30\n";
        assert!(crate::parse_program(ok, crate::ReadOptions::default()).is_ok());
    }

    /// Issue 34's fuzz campaign: `force` on an APT with `SPINDL/1e-300`
    /// printed a force of 5e299 N and an infinite power. The reader refuses
    /// the speed at the first feed move it applies to.
    #[test]
    fn an_absurdly_slow_spindle_is_refused_at_its_line() {
        let src = "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nSPINDL/1e-300,CLW\nRAPID\nGOTO/0,0,50\nGOTO/0,0,40\nFINI\n";
        let e = crate::parse_program(src, crate::ReadOptions::default()).expect_err("refused");
        assert_eq!(e.line, 7, "{e}");
        assert!(e.to_string().contains("smallest plausible speed"), "{e}");
        let g = "G21 G90\nS0.5 M3\nG0 X0 Y0 Z5\nG1 Z0 F100\nM30\n";
        let e = crate::parse_program(g, crate::ReadOptions::default()).expect_err("refused");
        assert_eq!(e.line, 4, "{e}");
        // A slow but real speed reads, and so does a stopped spindle; a
        // speed no feed move runs at is never used.
        for ok in [
            "G21 G90\nS1 M3\nG0 X0 Y0 Z5\nG1 Z0 F100\nM30\n",
            "G21 G90\nS0 M3\nG0 X0 Y0 Z5\nM30\n",
            "G21 G90\nS0.5 M3\nG0 X0 Y0 Z5\nM30\n",
        ] {
            assert!(
                crate::parse_program(ok, crate::ReadOptions::default()).is_ok(),
                "{ok}"
            );
        }
    }

    #[test]
    fn s0_before_a_cut_is_a_warning_at_its_line() {
        let w = read("G21 G90\nT1 M6\nS0 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nM30\n");
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].line, 3);
        assert!(w[0].message.contains("line 5"), "{}", w[0].message);
        // NX's `S0 M03` on the rotary move, the speed given before the cut.
        let given = read("G21 G90\nT1 M6\nG0 B-90. C270. S0 M03\nS6000\nG1 X1 F100\nM30\n");
        assert!(given.is_empty(), "{given:?}");
        // Only rapids before the spindle stops again: nothing cut at 0.
        let rapids = read("G21 G90\nT1 M6\nS0 M3\nG0 X1\nM5\nM30\n");
        assert!(rapids.is_empty(), "{rapids:?}");
    }
}
