//! Candidate rotary positions per CL point (spec kinematics-access-tools
//! §1.7), the pole rule (§1.8) and what makes a transition a branch flip.

use millplan_geom::DVec3;
use millplan_models::kinematics::{KinKind, Kinematics, RotaryAxis};

/// One rotary solution of a CL point, programmed degrees, with the angle
/// (degrees) between the tool axis it gives and the CL axis (non-zero only
/// where the pole rule held an axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cand {
    pub first: f64,
    pub second: f64,
    pub dev: f64,
}

/// Which of the machine's two rotary axes tilts the tool away from the pole
/// and which turns about it (undefined at the pole). Table-table A/B turns
/// the roles round: its pole is the A axis (K = ±X), where A is undefined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roles {
    /// The held (turning) axis is `second` (true) or `first` (false, A/B).
    pub held_is_second: bool,
    /// The pole direction in the workpiece frame.
    pub pole: [f64; 3],
}

pub fn roles(kind: KinKind) -> Roles {
    match kind {
        KinKind::TableAb => Roles {
            held_is_second: false,
            pole: [1.0, 0.0, 0.0],
        },
        _ => Roles {
            held_is_second: true,
            pole: [0.0, 0.0, 1.0],
        },
    }
}

/// (tilt, held) of a solution.
#[inline]
pub fn split(r: Roles, first: f64, second: f64) -> (f64, f64) {
    if r.held_is_second {
        (first, second)
    } else {
        (second, first)
    }
}

/// (first, second) from (tilt, held).
#[inline]
pub fn join(r: Roles, tilt: f64, held: f64) -> (f64, f64) {
    if r.held_is_second {
        (tilt, held)
    } else {
        (held, tilt)
    }
}

/// Whether an axis has no travel limits (it is then "wrapped": only its
/// angle modulo 360° matters, and the path unwraps it).
pub fn wrapped(a: &RotaryAxis) -> bool {
    a.min.is_none() && a.max.is_none()
}

/// `x` in (−180, 180].
#[inline]
pub fn wrap180(x: f64) -> f64 {
    let y = x - 360.0 * (x / 360.0).round();
    if y <= -180.0 {
        y + 360.0
    } else {
        y
    }
}

/// The angle between two unit vectors, degrees.
pub fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b)).to_degrees()
}

/// Whether `k` lies inside the cone of half-angle `cone_deg` about the pole
/// (either end).
pub fn in_pole(r: Roles, k: DVec3, cone_deg: f64) -> bool {
    let p = DVec3::from_array(r.pole);
    k.dot(p).abs() >= cone_deg.to_radians().cos()
}

/// The tilt that brings the tool axis closest to `k` with the held axis at
/// `held` (degrees), and the angle left between them. For every kind the
/// axis traces a great circle in the tilt: K(t) = cos t·K(0) + sin t·K(90°),
/// because the tilt turns a vector perpendicular to its rotation axis.
pub fn solve_tilt(kin: &Kinematics, r: Roles, k: DVec3, held: f64) -> Cand {
    let at = |t: f64| {
        let (f, s) = join(r, t, held);
        kin.tool_axis(f, s)
    };
    let k0 = at(0.0);
    let k90 = at(90.0);
    let t = k.dot(k90).atan2(k.dot(k0)).to_degrees();
    let (f, s) = join(r, t, held);
    Cand {
        first: f,
        second: s,
        dev: angle_deg(kin.tool_axis(f, s), k),
    }
}

/// The angles of one axis that stand for `deg` within the axis's travel:
/// `deg` itself for a wrapped axis, else every whole-turn winding of it
/// within ±720° that the limits allow.
fn windings(a: &RotaryAxis, deg: f64, out: &mut Vec<f64>) {
    if wrapped(a) {
        out.push(deg);
        return;
    }
    let lo = a.min.unwrap_or(f64::NEG_INFINITY) - 1e-9;
    let hi = a.max.unwrap_or(f64::INFINITY) + 1e-9;
    let base = deg - 360.0 * (deg / 360.0).round();
    for w in -2..=2 {
        let v = base + 360.0 * w as f64;
        if v >= lo && v <= hi {
            out.push(v);
        }
    }
}

/// Why a CL point has no candidate: the first rotary axis that cannot take
/// the orientation, as (axis letter, angle wanted, min, max).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutOfRange {
    pub axis: char,
    pub wanted: f64,
    pub min: Option<f64>,
    pub max: Option<f64>,
}

/// Candidates of a unit tool axis, pushed onto `out` (every branch and
/// winding the rotary limits allow). With `hold`, the
/// axis lies inside the pole cone: each held angle given is kept and the
/// tilt solved alone (§1.8), the exact solutions kept beside them. Returns
/// the range problem when none fits.
pub fn candidates(
    kin: &Kinematics,
    r: Roles,
    k: DVec3,
    hold: Option<&[f64]>,
    out: &mut Vec<Cand>,
) -> Result<(), OutOfRange> {
    let start = out.len();
    let mut raw: [Cand; 16] = [Cand {
        first: 0.0,
        second: 0.0,
        dev: 0.0,
    }; 16];
    let mut n = 0;
    match hold {
        Some(held) => {
            for &h in held.iter().take(8) {
                raw[n] = solve_tilt(kin, r, k, h);
                n += 1;
            }
            // The exact solutions too: where the travel refuses the held
            // angle's tilt, the turning axis must swing (slowly, near the
            // pole, where its turn hardly moves the tool).
            for (f, s) in kin.orientation_ik(k, held.first().copied().unwrap_or(0.0)) {
                raw[n] = Cand {
                    first: f,
                    second: s,
                    dev: 0.0,
                };
                n += 1;
            }
        }
        None => {
            for (f, s) in kin.orientation_ik(k, 0.0) {
                raw[n] = Cand {
                    first: f,
                    second: s,
                    dev: 0.0,
                };
                n += 1;
            }
        }
    }
    let mut fs = Vec::with_capacity(5);
    let mut ss = Vec::with_capacity(5);
    for c in &raw[..n] {
        fs.clear();
        ss.clear();
        windings(&kin.first, c.first, &mut fs);
        windings(&kin.second, c.second, &mut ss);
        for &f in &fs {
            for &s in &ss {
                let dup = out[start..]
                    .iter()
                    .any(|o| (o.first - f).abs() < 1e-9 && (o.second - s).abs() < 1e-9);
                if !dup {
                    out.push(Cand {
                        first: f,
                        second: s,
                        dev: c.dev,
                    });
                }
            }
        }
    }
    if out.len() > start {
        return Ok(());
    }
    // Name the axis: the principal solution's first axis out of its range,
    // else its second.
    let c = raw[0];
    let names = kin.kind.rotary_names();
    fs.clear();
    windings(&kin.first, c.first, &mut fs);
    let (axis, a, wanted) = if fs.is_empty() {
        (names[0], kin.first, c.first)
    } else {
        (names[1], kin.second, c.second)
    };
    Err(OutOfRange {
        axis,
        wanted,
        min: a.min,
        max: a.max,
    })
}

/// Which side of the pole the tilt of `c` puts the tool: sin t for a tilt
/// from the pole at t = 0 (A/C, B/C, heads), cos t for the A/B table, whose
/// pole is at B = ±90°; near 0 at the pole.
#[inline]
pub fn side(r: Roles, c: &Cand) -> f64 {
    let (t, _) = split(r, c.first, c.second);
    let t = t.to_radians();
    if r.held_is_second {
        t.sin()
    } else {
        t.cos()
    }
}

/// Whether two [`side`]s are opposite (neither at the pole).
#[inline]
pub fn sides_differ(sa: f64, sb: f64) -> bool {
    !(sa.abs() < 1e-6 || sb.abs() < 1e-6 || (sa > 0.0) == (sb > 0.0))
}

/// Whether the tilt of `a` and of `b` put the tool on opposite sides of the
/// pole (neither at it).
#[inline]
pub fn changes_side(r: Roles, a: &Cand, b: &Cand) -> bool {
    sides_differ(side(r, a), side(r, b))
}

/// Whether the held (turning) axis turns by 90° or more from `a` to `b`.
#[inline]
pub fn held_turns(r: Roles, a: &Cand, b: &Cand) -> bool {
    let (_, ha) = split(r, a.first, a.second);
    let (_, hb) = split(r, b.first, b.second);
    wrap180(hb - ha).abs() >= 90.0
}

/// Whether the motion from `a` to `b` changes the IK branch: the two sides
/// of the tilt differ (neither at the pole, where the tilt passes through
/// zero continuously) while the held axis turns by 90° or more. Crossing the
/// pole with the held axis still is no flip: the tilt passes through zero.
/// (A change of side with a smaller turn is a change of branch too unless
/// the tool axis passes the pole between the two points: the post asks
/// [`closest_to_pole`] for that.)
#[inline]
pub fn is_flip(r: Roles, a: &Cand, b: &Cand) -> bool {
    changes_side(r, a, b) && held_turns(r, a, b)
}

/// The smallest angle, degrees, between the pole (either end) and the tool
/// axis as it turns on the great circle from unit `a` to unit `b` (the
/// path [`crate::post`]'s `axis_at` interpolates): whether a move passes
/// the pole, where the tilt may change side without a change of branch.
pub fn closest_to_pole(r: Roles, a: DVec3, b: DVec3) -> f64 {
    let p = DVec3::from_array(r.pole);
    // The cosine of the angle to the nearer end of the pole, largest over
    // the arc: at an end, or where the circle comes closest, if that lies
    // between the ends.
    let mut cos = a.dot(p).abs().max(b.dot(p).abs());
    let n = a.cross(b);
    if n.length() > 1e-12 {
        let n = n.normalize();
        for q in [p, -p] {
            let v = q - n * q.dot(n);
            if v.length() > 1e-12 {
                let v = v.normalize();
                if a.cross(v).dot(n) >= 0.0 && v.cross(b).dot(n) >= 0.0 {
                    cos = cos.max(v.dot(q));
                }
            }
        }
    }
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}
