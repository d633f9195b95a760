//! The plausibility limit on the numbers a program gives (issue 34): an axis
//! word, feed or spindle speed that is finite but absurd (`X1e308`,
//! `FU1e308`, `A+1e308`) is refused at its source line when the reader
//! finishes, so that no model downstream turns it into an infinite length,
//! a zero feed or `Ainf` in a written program. The limits are
//! [`millplan_geom::limits::NC_EXTENT`] (coordinates and arc radii, mm;
//! rotary positions, degrees) and [`millplan_geom::limits::NC_RATE`] (feeds
//! and spindle speeds), documented in the limits table of docs/usage.md.

use crate::diag::ParseError;
use crate::ir::{MoveKind, Operation, Program};
use millplan_geom::limits::{NC_EXTENT, NC_RATE};

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

fn check_op(op: &Operation) -> Result<(), ParseError> {
    for c in &op.cycles {
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
