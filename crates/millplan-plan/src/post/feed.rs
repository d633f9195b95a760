//! The tool tip's path relative to the workpiece while the joints move
//! linearly (spec kinematics-access-tools §1.10), the block times and F words
//! of G93 and G94 (§1.10, process-models §2.5), and the tip deviation that
//! linearisation bounds (§1.7.5).

use millplan_geom::DVec3;
use millplan_models::kinematics::{Joints, Kinematics};

/// The joints at fraction `s` of a block from `a` to `b`: every axis moves
/// linearly (the rotaries by their programmed degrees, already unwound).
#[inline]
pub fn lerp(a: &Joints, b: &Joints, s: f64) -> Joints {
    Joints {
        xyz: a.xyz + (b.xyz - a.xyz) * s,
        first: a.first + (b.first - a.first) * s,
        second: a.second + (b.second - a.second) * s,
    }
}

/// Length of the tool tip's path relative to the workpiece while the joints
/// go linearly from `a` to `b` (a non-TCP control): the chord sums over n and
/// 2n steps extrapolated (Richardson: the chord error falls as 1/n², so
/// (4·L₂ₙ − Lₙ)/3 cancels its leading term), n growing with the rotary
/// travel, one step per 2° and at least 2. Without rotary motion the path is
/// the straight chord.
pub fn tip_path_length(kin: &Kinematics, a: &Joints, b: &Joints) -> f64 {
    tip_path_length_from(kin, a, b, None)
}

/// [`tip_path_length`], the tips inside the block taken from `samples`
/// ([`tip_samples`] of the same block) where its steps fall on them (2 and
/// 4 steps, or 4 and 8): the same bits, three or seven tips fewer.
pub fn tip_path_length_from(
    kin: &Kinematics,
    a: &Joints,
    b: &Joints,
    samples: Option<&Samples>,
) -> f64 {
    let turn = (b.first - a.first).abs().max((b.second - a.second).abs());
    if turn < 1e-12 {
        return (kin.tip(b) - kin.tip(a)).length();
    }
    let n = ((turn / 2.0).ceil() as usize).clamp(2, 512);
    let m = 2 * n;
    // Step i of m is sample i·(S/m) of S when m divides S: the same
    // fraction, so the same joints and tip to the bit (both quotients are
    // the one correctly rounded value).
    let tip_at = |i: usize| match samples {
        Some(s) if DEVIATION_SAMPLES.is_multiple_of(m) && i < m => {
            s[i * (DEVIATION_SAMPLES / m) - 1]
        }
        _ => kin.tip(&lerp(a, b, i as f64 / m as f64)),
    };
    // The 2n steps; every other point gives the n steps.
    let mut l2n = 0.0;
    let mut ln = 0.0;
    let mut prev = kin.tip(a);
    let mut prev2 = prev;
    for i in 1..=m {
        let p = tip_at(i);
        l2n += (p - prev).length();
        prev = p;
        if i % 2 == 0 {
            ln += (p - prev2).length();
            prev2 = p;
        }
    }
    (4.0 * l2n - ln) / 3.0
}

/// Distance from `p` to the segment `a`–`b`.
#[inline]
pub fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).length()
}

/// Samples per block of the deviation estimate.
pub const DEVIATION_SAMPLES: usize = 8;

/// The tips at the inner sample points of a block (joints moving linearly
/// from `a` to `b`), at fractions i / [`DEVIATION_SAMPLES`].
pub type Samples = [DVec3; DEVIATION_SAMPLES - 1];

/// [`Samples`] of the block from `a` to `b`; `None` when the rotaries do not
/// turn (the joints move in a straight line with the table still: so does
/// the tip).
pub fn tip_samples(kin: &Kinematics, a: &Joints, b: &Joints) -> Option<Samples> {
    let turn = (b.first - a.first).abs().max((b.second - a.second).abs());
    if turn < 1e-12 {
        return None;
    }
    Some(std::array::from_fn(|k| {
        let s = (k + 1) as f64 / DEVIATION_SAMPLES as f64;
        kin.tip(&lerp(a, b, s))
    }))
}

/// The largest distance of the sampled tips from the straight CL segment
/// `p0`–`p1` (0 without samples).
pub fn sampled_deviation(samples: Option<&Samples>, p0: DVec3, p1: DVec3) -> f64 {
    samples.map_or(0.0, |s| {
        s.iter()
            .map(|&p| segment_distance(p, p0, p1))
            .fold(0.0, f64::max)
    })
}

/// The largest distance of the tip path (joints moving linearly from `a` to
/// `b`) from the straight CL segment `p0`–`p1`, sampled at
/// [`DEVIATION_SAMPLES`] − 1 inner points.
pub fn tip_deviation(kin: &Kinematics, a: &Joints, b: &Joints, p0: DVec3, p1: DVec3) -> f64 {
    sampled_deviation(tip_samples(kin, a, b).as_ref(), p0, p1)
}

/// The F word of G93 for a block of tip path length `len` (mm) at the tool
/// tip feed `v` (mm/min): F = v / L, 1/min (§1.10 step 3).
pub fn inverse_time_f(len: f64, v: f64) -> f64 {
    v / len
}

/// The F word a G94 control must be given so that a block whose tip moves
/// `len` mm relative to the part takes `minutes`: the control applies F to
/// the XYZ distance of the joints when X, Y or Z moves, else to the rotary
/// distance in degrees (RS274/NGC, §1.10), so F = that distance / minutes.
pub fn g94_machine_f(a: &Joints, b: &Joints, minutes: f64) -> f64 {
    let d = (b.xyz - a.xyz).length();
    if d > 1e-9 {
        d / minutes
    } else {
        (b.first - a.first).hypot(b.second - a.second) / minutes
    }
}

/// The minutes a G94 control takes for a block whose F word is `f`: the XYZ
/// distance of the joints at F, or without linear motion the rotary distance
/// at F degrees/min (what an uncompensated post's tool-tip F becomes).
pub fn g94_minutes(a: &Joints, b: &Joints, f: f64) -> f64 {
    let d = (b.xyz - a.xyz).length();
    if d > 1e-9 {
        d / f
    } else {
        (b.first - a.first).hypot(b.second - a.second) / f
    }
}
