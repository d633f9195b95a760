//! The complete stability envelope a_lim(n) over a spindle-speed range.
//!
//! A table of both eigenvalue roots over chatter frequencies 0…f_hi (fine
//! near each natural frequency, geometric away from it, and halved where a
//! root's a_lim or ε changes fast) is built once. At a
//! spindle speed n the tooth period is T = 60/(N·n), and the phase condition
//! ω·T = ε(ω) + 2kπ of §3 holds wherever m(ω) = (ω·T − ε)/2π passes an
//! integer k ≥ 0; every such crossing in every interval of the table is a
//! point of lobe k, and the envelope is the smallest a_lim among them. Lobes
//! are thus never counted beforehand. Above f_hi every root's a_lim is at
//! least [`Setup::bound_above`]; the band doubles until that bound lies above
//! the whole envelope of the range, so nothing beyond the band can lower it.

use super::{Setup, C};
use millplan_geom::optimize::golden_max;
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::fmt;

/// Frequency steps per ζ·fn near a natural frequency.
const PER_BANDWIDTH: f64 = 40.0;
/// Relative frequency step away from the natural frequencies (the step is
/// this fraction of the distance to the nearest one).
const FAR_STEP: f64 = 0.005;
/// Speed samples per lobe at 1.25 times the highest natural frequency.
const PER_LOBE: f64 = 32.0;
/// Largest relative change of a root's a_lim between two table rows.
const MAX_DA: f64 = 0.01;
/// Largest change of a root's ε between two table rows \[rad\].
const MAX_DEPS: f64 = 0.02;
/// Most halvings of one step of the table.
const MAX_SPLITS: u32 = 24;
/// Fewest speed samples of an envelope.
const MIN_SPEEDS: usize = 1000;
/// Most lobes a speed range may span: the envelope is resolved with
/// `PER_LOBE` speeds per lobe, so this bounds it to 16,000 speeds.
pub const MAX_LOBES: f64 = 500.0;
/// The band stops growing once nothing above it can come below this depth
/// \[mm\]: envelope values above it are reported as this bound.
pub const CEILING_MM: f64 = 1e4;
/// Most doublings of the band (each adds about 140 table rows).
const MAX_DOUBLINGS: usize = 64;
/// Most rows of the frequency table (never reached within the validated
/// ranges of [`super::Mode`]; a guard against an endless loop).
const MAX_ROWS: usize = 1_000_000;

/// Why an envelope cannot be computed.
#[derive(Clone, Debug, PartialEq)]
pub enum LobesError {
    /// The setup or the speed range is not valid.
    Invalid(String),
    /// The speed range spans more than [`MAX_LOBES`] lobes; `n_min` is the
    /// lowest start \[1/min\] that keeps it within.
    TooManyLobes { lobes: f64, n_min: f64 },
}

impl fmt::Display for LobesError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LobesError::Invalid(m) => f.write_str(m),
            LobesError::TooManyLobes { lobes, n_min } => write!(
                f,
                "the speed range spans about {lobes:.0} lobes, more than the {MAX_LOBES:.0} \
                 resolved; start it at {n_min:.1} 1/min or above"
            ),
        }
    }
}

/// The smallest depth limit over all chatter frequencies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobePoint {
    /// Chatter frequency \[Hz\].
    pub fc_hz: f64,
    /// Limiting axial depth \[mm\].
    pub a_lim_mm: f64,
    /// Phase ε \[rad\] of the root there.
    pub eps: f64,
}

/// Where the envelope is set: the chatter frequency and the lobe.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Chatter {
    pub fc_hz: f64,
    pub lobe: u64,
}

/// One point of the envelope.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EnvPoint {
    /// Spindle speed \[1/min\].
    pub rpm: f64,
    /// The smallest a_lim over every lobe at this speed \[mm\].
    pub a_lim_mm: f64,
    /// The lobe that sets it; None where no lobe below the band's bound
    /// reaches this speed (a_lim_mm is then that bound, a lower limit).
    pub chatter: Option<Chatter>,
}

/// The stability envelope over a speed range.
#[derive(Clone, Debug, PartialEq)]
pub struct Stability {
    /// Ascending speeds, uniform in the tooth period (so every lobe gets
    /// the same number of points), and the refined top of every pocket.
    pub envelope: Vec<EnvPoint>,
    /// The deepest stable cut: the maximum of the envelope over the range.
    pub deepest: EnvPoint,
    /// The chatter band searched \[Hz\]: from 0 to this.
    pub band_hz: f64,
    /// Every value at or below this depth \[mm\] is exact; a value above it
    /// is this lower bound.
    pub exact_below_mm: f64,
}

impl Stability {
    /// The lowest and highest lobe numbers that set the envelope.
    pub fn lobes(&self) -> Option<(u64, u64)> {
        let ks = self
            .envelope
            .iter()
            .filter_map(|p| p.chatter.map(|c| c.lobe));
        let lo = ks.clone().min()?;
        Some((lo, ks.max()?))
    }
}

/// One eigenvalue root at one frequency; `a_mm` is NaN where a_lim is not
/// positive.
#[derive(Clone, Copy, Debug)]
struct Root {
    lam: C,
    a_mm: f64,
    eps: f64,
}

#[derive(Clone, Copy, Debug)]
struct Row {
    w: f64,
    roots: [Option<Root>; 2],
}

/// The limit found at one speed (a_mm infinite: none yet).
#[derive(Clone, Copy, Debug)]
struct Hit {
    a_mm: f64,
    w: f64,
    lobe: u64,
}

const NO_HIT: Hit = Hit {
    a_mm: f64::INFINITY,
    w: 0.0,
    lobe: 0,
};

/// The roots over chatter frequencies 0…f_hi, each root's row continuing
/// the nearest root of the row before (so a branch stays one branch).
struct Table {
    rows: Vec<Row>,
}

impl Table {
    fn new(s: &Setup) -> Table {
        let mut t = Table { rows: Vec::new() };
        t.push(s, 0.0);
        t
    }

    fn push(&mut self, s: &Setup, f: f64) {
        let row = self.row(s, f);
        self.rows.push(row);
    }

    /// The roots at f \[Hz\], in the order that continues the last row.
    fn row(&self, s: &Setup, f: f64) -> Row {
        let mut r: Vec<Root> = s
            .eigen(TAU * f)
            .into_iter()
            .map(|lam| {
                let (a_mm, eps) = s.limit(lam).unwrap_or((f64::NAN, f64::NAN));
                Root { lam, a_mm, eps }
            })
            .collect();
        if let (2, Some([Some(p0), Some(p1)])) = (r.len(), self.rows.last().map(|p| p.roots)) {
            let d = |a: C, b: C| a.sub(b).norm();
            if d(p0.lam, r[1].lam) + d(p1.lam, r[0].lam) < d(p0.lam, r[0].lam) + d(p1.lam, r[1].lam)
            {
                r.swap(0, 1);
            }
        }
        Row {
            w: TAU * f,
            roots: [r.first().copied(), r.get(1).copied()],
        }
    }

    /// Extends the table to f_hi \[Hz\].
    fn extend_to(&mut self, s: &Setup, f_hi: f64) -> Result<(), LobesError> {
        let mut f = self.rows.last().map_or(0.0, |r| r.w / TAU);
        while f < f_hi {
            if self.rows.len() >= MAX_ROWS {
                return Err(LobesError::Invalid(format!(
                    "the chatter-frequency table would exceed {MAX_ROWS} rows"
                )));
            }
            f = (f + s.freq_step(f)).min(f_hi);
            self.advance(s, f, 0);
        }
        Ok(())
    }

    /// Adds the row at f, first halving the step (up to `MAX_SPLITS` times)
    /// while a root's a_lim changes by more than `MAX_DA` or its ε by more
    /// than `MAX_DEPS` from the last row, or a root stops or starts being a
    /// limit: a_lim and ε are interpolated linearly between rows, and near
    /// the edge of a root's valid range a_lim grows like 1/(r² − 1).
    fn advance(&mut self, s: &Setup, f: f64, depth: u32) {
        let row = self.row(s, f);
        let Some(last) = self.rows.last().copied() else {
            self.rows.push(row);
            return;
        };
        if depth < MAX_SPLITS && coarse(&last, &row) {
            self.advance(s, 0.5 * (last.w / TAU + f), depth + 1);
            self.advance(s, f, depth + 1);
        } else {
            self.rows.push(row);
        }
    }

    /// The smallest a_lim of any crossing at tooth period `t` in the
    /// intervals from row `from` on, merged into `best`.
    fn scan(&self, t: f64, from: usize, best: &mut Hit) {
        for pair in self.rows[from.min(self.rows.len())..].windows(2) {
            for b in 0..2 {
                if let (Some(p), Some(q)) = (pair[0].roots[b], pair[1].roots[b]) {
                    if let Some(h) = crossing((pair[0].w, p), (pair[1].w, q), t) {
                        if h.a_mm < best.a_mm {
                            *best = h;
                        }
                    }
                }
            }
        }
    }

    /// The smallest a_lim in the table: the row's index and its root.
    fn lowest(&self) -> Option<(usize, Root)> {
        self.rows
            .iter()
            .enumerate()
            .flat_map(|(i, r)| r.roots.iter().flatten().map(move |x| (i, *x)))
            .filter(|(_, x)| x.a_mm.is_finite())
            .min_by(|a, b| a.1.a_mm.total_cmp(&b.1.a_mm))
    }
}

/// Whether the step from row p to q is too coarse to interpolate across.
fn coarse(p: &Row, q: &Row) -> bool {
    p.roots.iter().zip(&q.roots).any(|(a, b)| match (a, b) {
        (Some(a), Some(b)) => {
            let (fa, fb) = (a.a_mm.is_finite(), b.a_mm.is_finite());
            if fa && fb {
                (a.a_mm - b.a_mm).abs() > MAX_DA * a.a_mm.min(b.a_mm)
                    || (a.eps - b.eps).abs() > MAX_DEPS
            } else {
                fa != fb
            }
        }
        (a, b) => a.is_some() != b.is_some(),
    })
}

/// The crossing of the phase condition between two rows of one branch with
/// the smallest a_lim (a_lim and ε linear between the rows; a_lim is linear
/// along the interval, so the smallest is at the first or the last integer
/// crossed). None where a root is not a limit, where ε wraps (Λ_R passes
/// 0, a_lim → ∞), or where no integer k ≥ 0 is crossed.
fn crossing((wp, p): (f64, Root), (wq, q): (f64, Root), t: f64) -> Option<Hit> {
    if !(p.a_mm.is_finite() && q.a_mm.is_finite()) || (p.eps - q.eps).abs() > std::f64::consts::PI {
        return None;
    }
    let m0 = (wp * t - p.eps) / TAU;
    let m1 = (wq * t - q.eps) / TAU;
    let (j0, j1) = (m0.min(m1).ceil().max(0.0), m0.max(m1).floor());
    if j0 > j1 {
        return None;
    }
    let at = |j: f64| {
        let u = if m1 != m0 { (j - m0) / (m1 - m0) } else { 0.0 };
        Hit {
            a_mm: p.a_mm + u * (q.a_mm - p.a_mm),
            w: wp + u * (wq - wp),
            lobe: j as u64,
        }
    };
    let (h0, h1) = (at(j0), at(j1));
    Some(if h0.a_mm <= h1.a_mm { h0 } else { h1 })
}

impl Setup {
    /// Step of the frequency table at f \[Hz\]: ζ·fn/40 near a natural
    /// frequency, 0.5 % of the distance to it farther away.
    fn freq_step(&self, f: f64) -> f64 {
        self.modes()
            .map(|m| (m.zeta * m.fn_hz / PER_BANDWIDTH).max(FAR_STEP * (f - m.fn_hz).abs()))
            .fold(f64::INFINITY, f64::min)
            .max(f * 1e-12)
    }

    /// The table up to a band whose bound lies above `limit(table)` (or
    /// above [`CEILING_MM`]); the band \[Hz\] and its bound \[mm\].
    fn grow(
        &self,
        table: &mut Table,
        mut limit: impl FnMut(&Table, usize) -> f64,
    ) -> Result<(f64, f64), LobesError> {
        let mut f_hi = 4.0 * self.max_fn();
        for _ in 0..MAX_DOUBLINGS {
            let from = table.rows.len() - 1;
            table.extend_to(self, f_hi)?;
            let bound = self.bound_above(f_hi);
            if limit(table, from) <= bound || bound >= CEILING_MM {
                return Ok((f_hi, bound));
            }
            f_hi *= 2.0;
        }
        Err(LobesError::Invalid(
            "the chatter band did not close after 64 doublings".into(),
        ))
    }

    /// The smallest a_lim over all chatter frequencies and both roots (T10e,
    /// T10f), refined between the table's rows by golden section.
    pub fn minimum(&self) -> Result<LobePoint, LobesError> {
        self.validate().map_err(LobesError::Invalid)?;
        let mut table = Table::new(self);
        self.grow(&mut table, |t, _| {
            t.lowest().map_or(f64::INFINITY, |x| x.1.a_mm)
        })?;
        let none =
            || LobesError::Invalid("no chatter frequency gives a positive depth limit".into());
        let (i, _) = table.lowest().ok_or_else(none)?;
        let rows = &table.rows;
        let (lo, hi) = (
            rows[i.saturating_sub(1)].w,
            rows[(i + 1).min(rows.len() - 1)].w,
        );
        let lowest_at = |w: f64| {
            self.limits_at(w)
                .into_iter()
                .flatten()
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        let (w, _) = golden_max(
            &|w| lowest_at(w).map_or(f64::NEG_INFINITY, |x| -x.0),
            lo,
            hi,
            1e-12 * hi,
            200,
        );
        let (a_lim_mm, eps) = lowest_at(w).ok_or_else(none)?;
        Ok(LobePoint {
            fc_hz: w / TAU,
            a_lim_mm,
            eps,
        })
    }

    /// The complete envelope over n_lo…n_hi \[1/min\]: at each speed the
    /// smallest a_lim over every lobe and both roots, and its maximum over
    /// the range.
    pub fn stability(&self, n_lo: f64, n_hi: f64) -> Result<Stability, LobesError> {
        self.validate().map_err(LobesError::Invalid)?;
        let speeds = self.speeds(n_lo, n_hi)?;
        let periods: Vec<f64> = speeds.iter().map(|&n| self.period(n)).collect();
        let mut table = Table::new(self);
        let mut hits = vec![NO_HIT; speeds.len()];
        let (band_hz, bound) = self.grow(&mut table, |t, from| {
            hits.par_iter_mut()
                .zip(&periods)
                .for_each(|(h, &p)| t.scan(p, from, h));
            hits.iter().map(|h| h.a_mm).fold(0.0, f64::max)
        })?;
        let mut envelope: Vec<EnvPoint> = speeds
            .iter()
            .zip(&hits)
            .map(|(&n, &h)| point(n, h, bound))
            .collect();
        let peaks = self.peaks(&table, &envelope, bound);
        envelope.extend(peaks);
        envelope.sort_by(|p, q| p.rpm.total_cmp(&q.rpm));
        let deepest = envelope
            .iter()
            .copied()
            .max_by(|p, q| p.a_lim_mm.total_cmp(&q.a_lim_mm))
            .unwrap_or(point(n_lo, NO_HIT, bound));
        if !deepest.a_lim_mm.is_finite() {
            return Err(LobesError::Invalid(
                "no chatter frequency gives a finite depth limit in this speed range".into(),
            ));
        }
        Ok(Stability {
            envelope,
            deepest,
            band_hz,
            exact_below_mm: bound,
        })
    }

    /// Tooth period \[s\] at n \[1/min\].
    fn period(&self, n: f64) -> f64 {
        60.0 / (self.flutes as f64 * n)
    }

    /// Ascending speeds from n_lo to n_hi, uniform in 1/n (lobes are evenly
    /// spaced in the tooth period), `PER_LOBE` per lobe and at least
    /// `MIN_SPEEDS`; refused when the range spans more than [`MAX_LOBES`].
    fn speeds(&self, n_lo: f64, n_hi: f64) -> Result<Vec<f64>, LobesError> {
        if !(n_lo > 0.0 && n_hi > n_lo && n_hi.is_finite()) {
            return Err(LobesError::Invalid(format!(
                "speed range {n_lo}…{n_hi} 1/min: must be positive and rising"
            )));
        }
        let f_ref = 1.25 * self.max_fn();
        let lobes = f_ref * (self.period(n_lo) - self.period(n_hi));
        if lobes > MAX_LOBES {
            let n_min = 1.0 / (MAX_LOBES / (60.0 / self.flutes as f64 * f_ref) + 1.0 / n_hi);
            return Err(LobesError::TooManyLobes { lobes, n_min });
        }
        let count = ((lobes * PER_LOBE).ceil() as usize).max(MIN_SPEEDS);
        let (u0, u1) = (1.0 / n_lo, 1.0 / n_hi);
        Ok((0..count)
            .map(|i| match i {
                0 => n_lo,
                i if i == count - 1 => n_hi,
                i => 1.0 / (u0 + (u1 - u0) * i as f64 / (count - 1) as f64),
            })
            .collect())
    }

    /// The envelope's value at one speed, from the whole table.
    fn at_speed(&self, table: &Table, n: f64, bound: f64) -> EnvPoint {
        let mut h = NO_HIT;
        table.scan(self.period(n), 0, &mut h);
        point(n, h, bound)
    }

    /// The tops of the envelope's pockets: each local maximum of the grid,
    /// refined between its neighbours by golden section (one cusp or one
    /// lobe flank at most lies there, so the envelope is unimodal on it),
    /// where that finds more than the grid.
    fn peaks(&self, table: &Table, env: &[EnvPoint], bound: f64) -> Vec<EnvPoint> {
        let a = |i: usize| env[i].a_lim_mm;
        let last = env.len().saturating_sub(1);
        let tops: Vec<usize> = (0..env.len())
            .filter(|&i| (i == 0 || a(i) >= a(i - 1)) && (i == last || a(i) > a(i + 1)))
            .collect();
        tops.par_iter()
            .filter_map(|&i| {
                let (lo, hi) = (env[i.saturating_sub(1)].rpm, env[(i + 1).min(last)].rpm);
                let f = |n: f64| self.at_speed(table, n, bound).a_lim_mm;
                let (n, v) = golden_max(&f, lo, hi, 1e-7 * hi, 100);
                (v > a(i)).then(|| self.at_speed(table, n, bound))
            })
            .collect()
    }

    /// Speed \[1/min\] of lobe k at a point: n_k = 60·ω/(N·(ε + 2kπ)).
    pub fn lobe_speed(&self, p: &LobePoint, k: u64) -> f64 {
        60.0 * TAU * p.fc_hz / (self.flutes as f64 * (p.eps + TAU * k as f64))
    }

    /// The default speed range: from 0.9 times the speed of the bottom of
    /// lobe 9 to 1.3 times that of lobe 0, so ten lobes show; the envelope
    /// in it still takes every lobe there.
    pub fn default_range(&self, p: &LobePoint) -> (f64, f64) {
        (0.9 * self.lobe_speed(p, 9), 1.3 * self.lobe_speed(p, 0))
    }
}

/// The envelope point at speed n from the best hit, within the band's bound.
fn point(rpm: f64, h: Hit, bound: f64) -> EnvPoint {
    if h.a_mm <= bound {
        EnvPoint {
            rpm,
            a_lim_mm: h.a_mm,
            chatter: Some(Chatter {
                fc_hz: h.w / TAU,
                lobe: h.lobe,
            }),
        }
    } else {
        EnvPoint {
            rpm,
            a_lim_mm: bound,
            chatter: None,
        }
    }
}
