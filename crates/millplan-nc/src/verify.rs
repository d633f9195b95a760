//! The IR verifier: checks the invariants every front end, pass and generator must
//! keep. The pass pipeline runs it after every pass in debug builds and tests.

use crate::ir::*;

/// Allowed difference (mm) between an arc's start and end radius, plus 1e-4·r.
pub const ARC_TOL: f64 = 0.01;

/// The invariant a [`Violation`] breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// An operation's frame is finite and orthonormal.
    Frame,
    /// Tool axes are finite unit vectors; rotary angles are finite.
    Orientation,
    /// A tool is set before the first cutting move.
    ToolBeforeCut,
    /// Tool geometry has d > 0, r ≥ 0 and finite offsets.
    ToolGeometry,
    /// Coordinates are finite or NaN (unknown); feeds and speeds are finite.
    Finite,
    /// Spindle speeds are not negative.
    Spindle,
    /// Cutting moves have a positive feed.
    Feed,
    /// Side-table ids (arc, cycle, orientation) name an existing entry.
    Index,
    /// Arcs start and end at known points on their circle, with a unit axis and
    /// 0 < sweep ≤ 2π.
    Arc,
    /// Cycle points are known positions; cycle parameters are finite with a
    /// positive feed.
    Cycle,
    /// An axis known before a move becomes unknown only after an event that
    /// moves the machine out of the program's view or changes the work offset.
    Unknown,
    /// Events are sorted by the move they precede and anchored inside the operation.
    Events,
}

/// One broken invariant, located by operation and move index.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    pub op: usize,
    pub mv: Option<usize>,
    pub rule: Rule,
    pub message: String,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.mv {
            Some(m) => write!(f, "operation {} move {}: {}", self.op, m, self.message),
            None => write!(f, "operation {}: {}", self.op, self.message),
        }
    }
}

/// Checks every [`Rule`] on a program.
pub fn verify(p: &Program) -> Result<(), Vec<Violation>> {
    let mut v = Vec::new();
    for (oi, op) in p.operations.iter().enumerate() {
        verify_op(oi, op, &mut v);
    }
    if v.is_empty() {
        Ok(())
    } else {
        Err(v)
    }
}

fn finite_or_unknown(p: millplan_geom::DVec3) -> bool {
    (0..3).all(|k| p[k].is_finite() || p[k].is_nan())
}

fn verify_op(oi: usize, op: &Operation, v: &mut Vec<Violation>) {
    let mut bad = |mv: Option<usize>, rule: Rule, message: String| {
        v.push(Violation {
            op: oi,
            mv,
            rule,
            message,
        })
    };
    if let Some(f) = &op.frame {
        if !f.is_orthonormal(1e-6) || !f.origin.is_finite() {
            bad(
                None,
                Rule::Frame,
                "frame is not a finite orthonormal frame".into(),
            );
        }
    }
    for (k, o) in op.orients.iter().enumerate() {
        if let Some(a) = o.axis {
            if !a.is_finite() || (a.length() - 1.0).abs() > millplan_geom::tol::UNIT {
                bad(
                    None,
                    Rule::Orientation,
                    format!("orientation {k} is not a unit vector: {a:?}"),
                );
            }
        }
        if o.angles.iter().flatten().any(|x| !x.is_finite()) {
            bad(
                None,
                Rule::Orientation,
                format!("orientation {k} has a non-finite angle"),
            );
        }
    }
    let first_cut = op.moves.iter().position(Move::is_cutting);
    if first_cut.is_some() && op.tool.is_none() {
        bad(
            first_cut,
            Rule::ToolBeforeCut,
            "cutting move without a tool".into(),
        );
    }
    if let Some(Tool {
        cutter: Some(c), ..
    }) = &op.tool
    {
        let valid = c.d > 0.0 && c.d.is_finite() && c.r >= 0.0 && c.r.is_finite();
        if !valid || !c.e.is_finite() || !c.f.is_finite() {
            bad(
                None,
                Rule::ToolGeometry,
                format!("tool geometry is invalid: {c:?}"),
            );
        }
    }
    if !finite_or_unknown(op.start) {
        bad(None, Rule::Finite, "start position is infinite".into());
    }
    for (k, c) in op.cycles.iter().enumerate() {
        let nums = [c.bottom, c.clearance, c.retract, c.feed];
        if nums.iter().any(|x| !x.is_finite())
            || c.peck.is_some_and(|q| !q.is_finite())
            || c.peck_next.is_some_and(|q| !q.is_finite())
            || c.dwell.is_some_and(|t| !t.is_finite())
            || !(c.feed > 0.0)
        {
            bad(
                None,
                Rule::Cycle,
                format!("cycle {k} has a non-finite value or a feed that is not positive"),
            );
        }
    }
    // Moves before which the machine may have moved out of the program's view,
    // or the program changed the frame positions are given in (work offset,
    // tool length, TCP).
    let moved: Vec<u32> = op
        .events
        .iter()
        .filter(|e| {
            matches!(&e.kind, EventKind::Passthrough(p) if p.moves)
                || matches!(
                    e.kind,
                    EventKind::WorkOffset(_) | EventKind::ToolLength(_) | EventKind::Tcp(_)
                )
        })
        .map(|e| e.at)
        .collect();
    for (i, m) in op.moves.iter().enumerate() {
        if !finite_or_unknown(m.end) || !m.feed.is_finite() || !m.spindle.is_finite() {
            bad(Some(i), Rule::Finite, "non-finite number".into());
            continue;
        }
        let before = op.move_start(i);
        if (0..3).any(|k| !before[k].is_nan() && m.end[k].is_nan())
            && moved.binary_search(&(i as u32)).is_err()
        {
            bad(
                Some(i),
                Rule::Unknown,
                "a known axis becomes unknown without a machine move before it".into(),
            );
        }
        if m.spindle < 0.0 {
            bad(
                Some(i),
                Rule::Spindle,
                format!("negative spindle speed {}", m.spindle),
            );
        }
        if m.is_cutting() && !(m.feed > 0.0) {
            bad(
                Some(i),
                Rule::Feed,
                format!("cutting move with feed {}", m.feed),
            );
        }
        if let Some(o) = m.orient {
            if o.index() >= op.orients.len() {
                bad(Some(i), Rule::Index, "orientation id out of range".into());
            }
        }
        match m.kind {
            MoveKind::Arc(id) => {
                let Some(a) = op.arcs.get(id.index()) else {
                    bad(Some(i), Rule::Index, "arc id out of range".into());
                    continue;
                };
                let (Some(s), Some(e)) = (op.known_start(i), known(m.end)) else {
                    bad(
                        Some(i),
                        Rule::Arc,
                        "arc without a known start and end point".into(),
                    );
                    continue;
                };
                let sweep_ok = a.sweep > 0.0 && a.sweep <= std::f64::consts::TAU + 1e-9;
                if !(a.radius > 0.0 && sweep_ok && a.centre.is_finite()) {
                    bad(
                        Some(i),
                        Rule::Arc,
                        format!("arc radius {} sweep {}", a.radius, a.sweep),
                    );
                    continue;
                }
                if !((a.normal.length() - 1.0).abs() <= 1e-9) {
                    bad(Some(i), Rule::Arc, "arc axis is not a unit vector".into());
                    continue;
                }
                // Files written to 4 decimals in inch round each coordinate by up to
                // 1.3 µm; controls accept radius mismatches of about 0.01 mm.
                let tol = ARC_TOL + 1e-4 * a.radius;
                for (what, q) in [("start", s), ("end", e)] {
                    let d = q - a.centre;
                    let r = (d - a.normal * d.dot(a.normal)).length();
                    if (r - a.radius).abs() > tol {
                        bad(
                            Some(i),
                            Rule::Arc,
                            format!(
                                "arc {what} is {r:.5} from the centre, radius {:.5}",
                                a.radius
                            ),
                        );
                    }
                }
                if (a.point_at(s, e, 1.0) - e).length() > tol {
                    bad(
                        Some(i),
                        Rule::Arc,
                        "arc sweep does not reach its end point".into(),
                    );
                }
            }
            MoveKind::Cycle(id) => {
                if op.cycles.get(id.index()).is_none() {
                    bad(Some(i), Rule::Index, "cycle id out of range".into());
                } else if known(m.end).is_none() {
                    bad(
                        Some(i),
                        Rule::Cycle,
                        "cycle point with an unknown coordinate".into(),
                    );
                }
            }
            _ => {}
        }
    }
    let n = op.moves.len() as u32;
    if op.events.windows(2).any(|w| w[0].at > w[1].at) {
        bad(None, Rule::Events, "events are not in move order".into());
    }
    if op.events.iter().any(|e| e.at > n) {
        bad(
            None,
            Rule::Events,
            "event anchored after the end of the operation".into(),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_geom::{DVec3, Frame};

    /// A valid program of every move kind: a rapid, a line, an arc, a cycle
    /// point, with tool, orientation and events.
    fn good() -> Program {
        let mut op = Operation {
            tool: Some(Tool {
                number: Some(1),
                name: None,
                cutter: Some(Cutter::ball(10.0)),
                line: 1,
            }),
            start: DVec3::new(0.0, 0.0, 50.0),
            ..Operation::default()
        };
        op.push_event(1, EventKind::Spindle(SpindleDir::Cw));
        op.moves.push(Move::rapid(DVec3::new(10.0, 0.0, 5.0)));
        let mut l = Move::linear(DVec3::new(10.0, 0.0, 0.0), 500.0);
        l.orient = Some(op.intern_orient(Orient::vector(DVec3::Z)));
        op.moves.push(l);
        let arc = Arc::from_points(
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(0.0, 10.0, 0.0),
            DVec3::ZERO,
            DVec3::Z,
            false,
        )
        .expect("arc");
        let mut a = Move::linear(DVec3::new(0.0, 10.0, 0.0), 500.0);
        a.kind = MoveKind::Arc(op.push_arc(arc));
        op.moves.push(a);
        let cy = op.push_cycle(Cycle {
            name: "G81".into(),
            bottom: -5.0,
            clearance: 0.0,
            retract: 2.0,
            feed: 100.0,
            peck: None,
            peck_next: None,
            dwell: None,
            line: 4,
        });
        let mut c = Move::rapid(DVec3::new(20.0, 20.0, 2.0));
        c.kind = MoveKind::Cycle(cy);
        op.moves.push(c);
        op.push_event(5, EventKind::Coolant(Coolant::Off));
        let mut p = Program::new(Dialect::Generated);
        p.operations.push(op);
        p
    }

    /// Breaks `good()` with `f` and checks that the verifier reports `rule`.
    fn rejects(rule: Rule, f: impl FnOnce(&mut Operation)) {
        let mut p = good();
        f(&mut p.operations[0]);
        let v = verify(&p).expect_err("the broken program must be rejected");
        assert!(
            v.iter().any(|x| x.rule == rule),
            "expected {rule:?}, got {v:?}"
        );
    }

    #[test]
    fn the_valid_program_passes() {
        verify(&good()).expect("valid");
    }

    #[test]
    fn rejects_a_broken_frame() {
        rejects(Rule::Frame, |op| {
            let mut f = Frame::IDENTITY;
            f.rot.x_axis = DVec3::new(2.0, 0.0, 0.0);
            op.frame = Some(f);
        });
    }

    #[test]
    fn rejects_a_tool_axis_that_is_not_unit() {
        rejects(Rule::Orientation, |op| {
            op.orients[0].axis = Some(DVec3::new(0.0, 0.0, 2.0))
        });
        rejects(Rule::Orientation, |op| {
            op.orients[0].angles[1] = Some(f64::INFINITY)
        });
    }

    #[test]
    fn rejects_a_cut_without_a_tool() {
        rejects(Rule::ToolBeforeCut, |op| op.tool = None);
    }

    #[test]
    fn rejects_invalid_tool_geometry() {
        rejects(Rule::ToolGeometry, |op| {
            if let Some(t) = &mut op.tool {
                t.cutter = Some(Cutter::ball(-1.0));
            }
        });
    }

    #[test]
    fn rejects_infinite_numbers_but_not_unknown_ones() {
        rejects(Rule::Finite, |op| op.moves[0].end.x = f64::INFINITY);
        rejects(Rule::Finite, |op| op.moves[1].feed = f64::NAN);
        rejects(Rule::Finite, |op| op.start.y = f64::NEG_INFINITY);
        let mut p = good();
        p.operations[0].start = UNKNOWN;
        verify(&p).expect("an unknown start is valid");
    }

    #[test]
    fn rejects_a_negative_spindle_speed() {
        rejects(Rule::Spindle, |op| op.moves[1].spindle = -1.0);
    }

    #[test]
    fn rejects_a_cut_without_feed() {
        rejects(Rule::Feed, |op| op.moves[1].feed = 0.0);
    }

    #[test]
    fn rejects_ids_out_of_range() {
        rejects(Rule::Index, |op| {
            op.moves[1].orient = Some(OrientId::new(5))
        });
        rejects(Rule::Index, |op| {
            op.moves[2].kind = MoveKind::Arc(ArcId::new(3))
        });
        rejects(Rule::Index, |op| {
            op.moves[3].kind = MoveKind::Cycle(CycleId::new(3))
        });
    }

    #[test]
    fn rejects_arcs_off_their_circle_or_from_an_unknown_start() {
        rejects(Rule::Arc, |op| op.moves[2].end = DVec3::new(0.0, 11.0, 0.0));
        rejects(Rule::Arc, |op| op.arcs[0].sweep = 7.0);
        rejects(Rule::Arc, |op| {
            op.arcs[0].normal = DVec3::new(0.0, 0.0, 0.5)
        });
        rejects(Rule::Arc, |op| {
            op.moves[1].end.x = f64::NAN;
            op.push_event(0, EventKind::Comment("x".into()));
        });
    }

    #[test]
    fn rejects_bad_cycles() {
        rejects(Rule::Cycle, |op| op.cycles[0].feed = 0.0);
        rejects(Rule::Cycle, |op| op.cycles[0].peck = Some(f64::INFINITY));
        rejects(Rule::Cycle, |op| op.moves[3].end.y = f64::NAN);
    }

    #[test]
    fn rejects_an_axis_forgotten_without_a_machine_move() {
        rejects(Rule::Unknown, |op| op.moves[0].end.z = f64::NAN);
        // After a reference return the same program is valid.
        let mut p = good();
        let op = &mut p.operations[0];
        op.moves[0].end.z = f64::NAN;
        op.events.insert(
            0,
            Event {
                at: 0,
                line: 1,
                kind: EventKind::Passthrough(Passthrough {
                    word: "G28".into(),
                    text: "G91 G28 Z0".into(),
                    class: PassClass::Machine,
                    modal: true,
                    moves: true,
                }),
            },
        );
        verify(&p).expect("valid after a reference return");
    }

    #[test]
    fn rejects_events_out_of_order() {
        rejects(Rule::Events, |op| op.events.reverse());
        rejects(Rule::Events, |op| op.events[1].at = 99);
    }
}
