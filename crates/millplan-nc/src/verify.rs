//! The IR verifier: checks the invariants every front end, pass and generator must
//! keep. Tests run it after every transformation.

use crate::ir::*;

/// Allowed difference (mm) between an arc's start and end radius, plus 1e-4·r.
pub const ARC_TOL: f64 = 0.01;

/// One broken invariant, located by operation and move index.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    pub op: usize,
    pub mv: Option<usize>,
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

/// Checks: finite numbers; unit tool axes; feed > 0 on cutting moves; arcs whose
/// start and end lie on their circle and whose side-table indices exist; a tool
/// before the first cut; events sorted and anchored inside the operation.
pub fn verify(p: &Program) -> Result<(), Vec<Violation>> {
    let mut v = Vec::new();
    for (oi, op) in p.operations.iter().enumerate() {
        let mut bad = |mv: Option<usize>, message: String| {
            v.push(Violation {
                op: oi,
                mv,
                message,
            })
        };
        if let Some(f) = &op.frame {
            if !f.is_orthonormal(1e-6) || !f.origin.is_finite() {
                bad(None, "frame is not a finite orthonormal frame".into());
            }
        }
        for (k, o) in op.orients.iter().enumerate() {
            match o {
                Orient::Vector(a) => {
                    if !a.is_finite() || (a.length() - 1.0).abs() > millplan_geom::tol::UNIT {
                        bad(None, format!("orientation {k} is not a unit vector: {a:?}"));
                    }
                }
                Orient::Rotary(r) => {
                    if r.iter().flatten().any(|x| !x.is_finite()) {
                        bad(None, format!("orientation {k} has a non-finite angle"));
                    }
                }
            }
        }
        let first_cut = op.moves.iter().position(Move::is_cutting);
        if first_cut.is_some() && op.tool.is_none() {
            bad(first_cut, "cutting move without a tool".into());
        }
        if let Some(Tool {
            cutter: Some(c), ..
        }) = &op.tool
        {
            if !(c.d > 0.0) || c.r < 0.0 || !c.e.is_finite() || !c.f.is_finite() {
                bad(None, format!("tool geometry is invalid: {c:?}"));
            }
        }
        for (i, m) in op.moves.iter().enumerate() {
            if !m.end.is_finite() || !m.feed.is_finite() || !m.spindle.is_finite() {
                bad(Some(i), "non-finite number".into());
                continue;
            }
            if m.spindle < 0.0 {
                bad(Some(i), format!("negative spindle speed {}", m.spindle));
            }
            if m.is_cutting() && !(m.feed > 0.0) {
                bad(Some(i), format!("cutting move with feed {}", m.feed));
            }
            if m.orient != NO_ORIENT && m.orient as usize >= op.orients.len() {
                bad(Some(i), "orientation index out of range".into());
            }
            match m.kind {
                MoveKind::Arc => {
                    let Some(a) = op.arcs.get(m.aux as usize) else {
                        bad(Some(i), "arc index out of range".into());
                        continue;
                    };
                    let Some(s) = op.move_start(i) else {
                        bad(Some(i), "arc without a known start point".into());
                        continue;
                    };
                    let sweep_ok = a.sweep > 0.0 && a.sweep <= std::f64::consts::TAU + 1e-9;
                    if !(a.radius > 0.0 && sweep_ok) {
                        bad(
                            Some(i),
                            format!("arc radius {} sweep {}", a.radius, a.sweep),
                        );
                    }
                    if (a.normal.length() - 1.0).abs() > 1e-9 {
                        bad(Some(i), "arc axis is not a unit vector".into());
                    }
                    // Files written to 4 decimals in inch round each coordinate by up to
                    // 1.3 µm; controls accept radius mismatches of about 0.01 mm.
                    let tol = ARC_TOL + 1e-4 * a.radius;
                    for (what, q) in [("start", s), ("end", m.end)] {
                        let d = q - a.centre;
                        let r = (d - a.normal * d.dot(a.normal)).length();
                        if (r - a.radius).abs() > tol {
                            bad(
                                Some(i),
                                format!(
                                    "arc {what} is {r:.5} from the centre, radius {:.5}",
                                    a.radius
                                ),
                            );
                        }
                    }
                    let e = a.point_at(s, m.end, 1.0);
                    if (e - m.end).length() > tol {
                        bad(Some(i), "arc sweep does not reach its end point".into());
                    }
                }
                MoveKind::Cycle if op.cycles.get(m.aux as usize).is_none() => {
                    bad(Some(i), "cycle index out of range".into());
                }
                _ => {}
            }
        }
        let n = op.moves.len() as u32;
        if op.events.windows(2).any(|w| w[0].at > w[1].at) {
            bad(None, "events are not in move order".into());
        }
        if op.events.iter().any(|e| e.at > n) {
            bad(None, "event anchored after the end of the operation".into());
        }
    }
    if v.is_empty() {
        Ok(())
    } else {
        Err(v)
    }
}
