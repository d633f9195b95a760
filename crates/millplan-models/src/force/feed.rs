//! Feed-per-tooth iteration of Tunc & Budak (spec `process-models.md` §2.3):
//! scale the feed by the tightest ratio limit/value until the binding
//! constraint is met.

use super::deflect::Cantilever;
use super::Summary;

/// The quantities a feed is limited by, at one feed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Loads {
    /// F_xy,max \[N\].
    pub fxy_max: f64,
    /// T_max and T_mean [N·mm].
    pub torque_max: f64,
    pub torque_mean: f64,
    /// Mean power \[W\].
    pub power_w: f64,
    /// Bending stress \[MPa\] and tip deflection \[mm\].
    pub stress_mpa: f64,
    pub deflection_mm: f64,
}

impl Loads {
    /// From a revolution summary and the tool as a cantilever under F_xy,max.
    pub fn new(s: &Summary, tool: &Cantilever) -> Loads {
        let b = tool.bend(s.fxy_max);
        Loads {
            fxy_max: s.fxy_max,
            torque_max: s.torque_max,
            torque_mean: s.torque_mean,
            power_w: s.power_w,
            stress_mpa: b.stress,
            deflection_mm: b.deflection,
        }
    }
}

/// Which limit binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Constraint {
    Fxy,
    Torque,
    Power,
    Stress,
    Deflection,
    /// The feed sits on fz_min or fz_max.
    FeedRange,
}

impl Constraint {
    pub fn name(self) -> &'static str {
        match self {
            Constraint::Fxy => "fxy",
            Constraint::Torque => "torque",
            Constraint::Power => "power",
            Constraint::Stress => "stress",
            Constraint::Deflection => "deflection",
            Constraint::FeedRange => "feed-range",
        }
    }
}

/// Limits of the iteration; `None` leaves a quantity free. Power, torque and
/// stress are divided by `fos` (§2.3), force and deflection are not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub fxy: Option<f64>,
    /// Against T_max (the conservative default of §2.1).
    pub torque: Option<f64>,
    /// Against the mean power.
    pub power: Option<f64>,
    pub stress: Option<f64>,
    pub deflection: Option<f64>,
    pub fos: f64,
    pub fz_min: f64,
    pub fz_max: f64,
}

impl Limits {
    /// The tightest ratio limit/value and its constraint; None when no
    /// limited quantity is positive.
    pub fn ratio(&self, l: &Loads) -> Option<(f64, Constraint)> {
        let fos = if self.fos > 0.0 { self.fos } else { 1.0 };
        [
            (self.fxy, l.fxy_max, 1.0, Constraint::Fxy),
            (self.torque, l.torque_max, fos, Constraint::Torque),
            (self.power, l.power_w, fos, Constraint::Power),
            (self.stress, l.stress_mpa, fos, Constraint::Stress),
            (
                self.deflection,
                l.deflection_mm,
                1.0,
                Constraint::Deflection,
            ),
        ]
        .into_iter()
        .filter_map(|(lim, v, fos, c)| match lim {
            Some(lim) if v > 0.0 => Some((lim / (fos * v), c)),
            _ => None,
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}

/// Result of the iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct FeedSchedule {
    /// The feed per tooth reached \[mm\].
    pub fz: f64,
    /// Every feed tried, starting with the start value.
    pub sequence: Vec<f64>,
    /// The constraint that binds at the end (None: nothing limited).
    pub binding: Option<Constraint>,
    /// |r − 1| < tolerance, or the feed sits on a bound it cannot leave.
    pub converged: bool,
    /// Loads at the final feed.
    pub loads: Option<Loads>,
}

/// §2.3: fz ← clamp(fz·r, fz_min, fz_max) with r the tightest ratio, repeated
/// until |r − 1| < `tol` (0.01 in the spec) or `max_iter` (20) evaluations.
/// `eval` gives the loads at a feed per tooth.
pub fn iterate_feed(
    start: f64,
    limits: &Limits,
    tol: f64,
    max_iter: usize,
    mut eval: impl FnMut(f64) -> Loads,
) -> FeedSchedule {
    let clamp = |f: f64| f.clamp(limits.fz_min, limits.fz_max);
    let mut fz = clamp(start);
    let mut sequence = vec![fz];
    let mut binding = None;
    let mut loads = None;
    let mut converged = false;
    for _ in 0..max_iter.max(1) {
        let l = eval(fz);
        loads = Some(l);
        let Some((r, c)) = limits.ratio(&l) else {
            // Nothing limited: the largest feed allowed.
            binding = None;
            converged = fz == limits.fz_max;
            if !converged {
                fz = limits.fz_max;
                sequence.push(fz);
                continue;
            }
            break;
        };
        let next = clamp(fz * r);
        binding = Some(if next != fz * r {
            Constraint::FeedRange
        } else {
            c
        });
        if (r - 1.0).abs() < tol || next == fz {
            converged = true;
            if (r - 1.0).abs() < tol {
                binding = Some(c);
            }
            break;
        }
        fz = next;
        sequence.push(fz);
    }
    FeedSchedule {
        fz,
        sequence,
        binding,
        converged,
        loads,
    }
}
