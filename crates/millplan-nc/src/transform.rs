//! Whole-program transformations that every front and back end needs.

use crate::ir::*;

/// Multiplies every length in the program by `k` (inch → mm on reading, mm → inch
/// on writing). Feeds per minute and per revolution scale too; inverse-time feeds,
/// spindle speeds and angles do not.
pub fn scale_lengths(p: &mut Program, k: f64) {
    for op in &mut p.operations {
        if let Some(t) = &mut op.tool {
            t.cutter = t.cutter.map(|c| c.scaled(k));
        }
        if let Some(f) = &mut op.frame {
            f.origin *= k;
        }
        op.start = op.start.map(|s| s * k);
        for m in &mut op.moves {
            m.end *= k;
            if m.feed_mode != FeedMode::InverseTime {
                m.feed *= k;
            }
        }
        for a in &mut op.arcs {
            a.centre *= k;
            a.radius *= k;
        }
        for c in &mut op.cycles {
            c.bottom *= k;
            c.clearance *= k;
            c.retract *= k;
            c.feed *= k;
            c.peck = c.peck.map(|q| q * k);
            c.peck_next = c.peck_next.map(|q| q * k);
        }
    }
}
