//! The per-point table of the spindle-speed pass.

use millplan_plan::speed::{side_name, PointRow};
use std::fmt::Write;

pub const HEADER: &str = "index,line,x,y,z,cx,cy,cz,nx,ny,nz,inclination_deg,feed_angle_deg,uncut_side,ae,d_w,n,feed,n_target,gap,clamped,rate_limited,held,gap_flag,corner";

/// One row per cutting point; `ae` is empty when there is no neighbouring pass.
pub fn points_csv(rows: &[PointRow]) -> String {
    let mut s = String::with_capacity(rows.len() * 200 + 256);
    s.push_str(HEADER);
    s.push('\n');
    for (i, r) in rows.iter().enumerate() {
        let p = &r.r;
        // Lengths to the micrometre, angles to 0.001°, speeds to 0.1 1/min.
        let ae = p.ae().map(|a| format!("{a:.3}")).unwrap_or_default();
        let b = |x: bool| if x { 1 } else { 0 };
        let _ = writeln!(
            s,
            "{i},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.6},{:.6},{:.6},{:.3},{:.3},{},{ae},{:.3},{:.1},{:.1},{:.1},{:.3},{},{},{},{},{}",
            r.line,
            r.cl.x,
            r.cl.y,
            r.cl.z,
            p.contact.x,
            p.contact.y,
            p.contact.z,
            p.normal.x,
            p.normal.y,
            p.normal.z,
            p.inclination.to_degrees(),
            p.feed_angle.to_degrees(),
            side_name(p),
            p.dw,
            r.n,
            r.feed,
            r.n_target,
            if p.gap.is_finite() { p.gap } else { f64::NAN },
            b(r.clamped),
            b(r.rate_limited),
            b(r.held),
            b(r.gap_flag),
            b(p.corner),
        );
    }
    s
}
