//! How much of a machine's rotary ranges a setup needs, and the continuous
//! search for the setup that needs least (spec `kinematics-access-tools.md`
//! §3.2, §3.6).
//!
//! A tool direction uses each rotary axis as far as its angle goes towards
//! the axis's limit: the usage is angle / limit on the side the angle lies
//! (so 1 at the limit), 0 on an unlimited rotary C axis, angle / 90° on an
//! unlimited tilting axis. A direction's usage is the larger of its two axes
//! on the better of its two inverse-kinematics branches; a facet's is the
//! least over the directions of its cone; a setup's, the largest over the
//! facets. The machine reaches every facet in a setup exactly when the
//! setup's usage is at most 1, and the setup of least usage needs the
//! smallest ranges: with an unlimited C the least tilt, on an A,B table the
//! smallest box scaled like the machine's.
//!
//! The grid's cells give each facet an upper bound of its usage (their
//! directions are tested); the cap of directions that leave the facet by the
//! clearance angle gives a lower bound and, where the exact test passes it,
//! the facet's least usage itself. A pattern search over rotations of the
//! setup then moves it to its optimum between the grid's directions.

use millplan_geom::{DMat3, DVec3};
use millplan_models::kinematics::{KinKind, Kinematics, RotaryAxis};
use millplan_sim::access::{CellSets, DirectionTest, SphereGrid};

/// Reference of an unlimited tilting axis, degrees.
const FREE_TILT: f64 = 90.0;

/// Usage of an angle beyond a side with no room at all.
const NO_ROOM: f64 = 1e6;

/// The machine's axes as the usage sees them.
#[derive(Clone, Debug)]
pub struct Fit {
    machine: Kinematics,
    /// The second axis is a rotary C axis (its angle wraps).
    wraps: bool,
}

impl Fit {
    pub fn new(machine: &Kinematics) -> Fit {
        Fit {
            machine: machine.clone(),
            wraps: super::has_c_axis(machine.kind),
        }
    }

    /// The same kind of machine with unlimited rotary axes.
    pub fn free(machine: &Kinematics) -> Fit {
        let mut m = machine.clone();
        for ax in [&mut m.first, &mut m.second] {
            *ax = RotaryAxis {
                min: None,
                max: None,
                sign: ax.sign,
            };
        }
        Fit::new(&m)
    }

    /// Whether the usage depends on the tilt from the table's Z alone (a C
    /// axis without limits).
    fn tilt_only(&self) -> bool {
        self.wraps && self.machine.second.min.is_none() && self.machine.second.max.is_none()
    }

    /// Usage of angle `v` (degrees) on a non-wrapping axis.
    fn linear(axis: &RotaryAxis, v: f64) -> f64 {
        let lo = axis.min.unwrap_or(-FREE_TILT);
        let hi = axis.max.unwrap_or(FREE_TILT);
        // Measured from home (0) when the range holds it, else from its middle.
        let m = if lo <= 0.0 && 0.0 <= hi {
            0.0
        } else {
            0.5 * (lo + hi)
        };
        let ratio = |x: f64, w: f64| {
            if x <= 1e-12 {
                0.0
            } else if w > 0.0 {
                x / w
            } else {
                NO_ROOM + x
            }
        };
        if v >= m {
            ratio(v - m, hi - m)
        } else {
            ratio(m - v, m - lo)
        }
    }

    fn usage(&self, axis: &RotaryAxis, v: f64, wraps: bool) -> f64 {
        if !wraps {
            return Self::linear(axis, v);
        }
        if axis.min.is_none() && axis.max.is_none() {
            return 0.0;
        }
        (-2..=2)
            .map(|w| Self::linear(axis, v + 360.0 * w as f64))
            .fold(f64::INFINITY, f64::min)
    }

    /// Usage of the unit direction `q` (table frame) and the rotary angles
    /// (degrees) of the branch that needs least.
    pub fn cost(&self, q: DVec3) -> (f64, (f64, f64)) {
        let m = &self.machine;
        m.orientation_ik(q, 0.0)
            .into_iter()
            .map(|(f, s)| {
                let u = self
                    .usage(&m.first, f, false)
                    .max(self.usage(&m.second, s, self.wraps));
                (u, (f, s))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or((f64::INFINITY, (0.0, 0.0)))
    }

    pub fn kind(&self) -> KinKind {
        self.machine.kind
    }
}

/// A facet's direction in a setup: part frame, usage, rotary angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choice {
    pub dir: DVec3,
    pub usage: f64,
    pub angles: (f64, f64),
}

/// What the search works with.
pub struct Search<'a> {
    pub fit: &'a Fit,
    pub grid: &'a dyn SphereGrid,
    pub vis: &'a CellSets,
    pub test: &'a DirectionTest<'a>,
    /// Facets a setup must serve.
    pub live: &'a [usize],
    /// Cell directions (part frame).
    pub dirs: Vec<DVec3>,
}

/// A rotation by the rotation vector `w` (radians).
fn rot(w: DVec3) -> DMat3 {
    let a = w.length();
    if a < 1e-15 {
        DMat3::IDENTITY
    } else {
        DMat3::from_axis_angle(w / a, a)
    }
}

impl<'a> Search<'a> {
    pub fn new(
        fit: &'a Fit,
        grid: &'a dyn SphereGrid,
        vis: &'a CellSets,
        test: &'a DirectionTest<'a>,
        live: &'a [usize],
    ) -> Search<'a> {
        Search {
            fit,
            grid,
            vis,
            test,
            live,
            dirs: (0..grid.len()).map(|c| grid.direction(c)).collect(),
        }
    }

    /// Every cell's usage in setup `s`.
    fn cell_costs(&self, s: DMat3) -> Vec<(f64, (f64, f64))> {
        self.dirs.iter().map(|d| self.fit.cost(s * *d)).collect()
    }

    /// Per facet of `facets`, its cell of least usage in setup `s` (`None`:
    /// an empty cone), from the cells sorted by usage.
    fn cell_choices(
        &self,
        facets: &[usize],
        costs: &[(f64, (f64, f64))],
    ) -> Vec<Option<(usize, f64)>> {
        let mut order: Vec<usize> = (0..costs.len()).collect();
        order.sort_by(|&a, &b| costs[a].0.total_cmp(&costs[b].0));
        facets
            .iter()
            .map(|&t| {
                let set = self.vis.set(t);
                order
                    .iter()
                    .find(|&&c| set[c / 64] >> (c % 64) & 1 == 1)
                    .map(|&c| (c, costs[c].0))
            })
            .collect()
    }

    /// The setup's usage by the cells alone (an upper bound: every cell was
    /// tested), and per live facet its cell.
    pub fn by_cells(&self, s: DMat3) -> (f64, Vec<Option<(usize, f64)>>) {
        let costs = self.cell_costs(s);
        let ch = self.cell_choices(self.live, &costs);
        let worst = ch.iter().flatten().map(|c| c.1).fold(0.0, f64::max);
        (worst, ch)
    }

    /// The direction of least usage in setup `s` among those leaving facet
    /// normal `n` by more than the clearance angle (no occlusion considered:
    /// a lower bound of the facet's usage).
    fn cap_best(&self, s: DMat3, n: DVec3) -> DVec3 {
        let m = (self.test.min_dot() + 1e-9).min(1.0);
        let pole = s.transpose() * DVec3::Z;
        if pole.dot(n) > m {
            return pole;
        }
        let rim = (1.0 - m * m).max(0.0).sqrt();
        let toward = (pole - n * pole.dot(n)).normalize_or(n.any_orthonormal_vector());
        // Nearest the pole on the rim: the least tilt.
        let nearest = n * m + toward * rim;
        if self.fit.tilt_only() {
            return nearest;
        }
        let (e1, e2) = (toward, n.cross(toward));
        let at = |phi: f64| n * m + (e1 * phi.cos() + e2 * phi.sin()) * rim;
        let cost = |phi: f64| self.fit.cost(s * at(phi)).0;
        let (mut best, mut best_cost) = (0.0, cost(0.0));
        for k in 1..72 {
            let phi = k as f64 * std::f64::consts::TAU / 72.0;
            let c = cost(phi);
            if c < best_cost {
                (best, best_cost) = (phi, c);
            }
        }
        // Golden-section search about the best sample.
        let step = std::f64::consts::TAU / 72.0;
        let (mut lo, mut hi) = (best - step, best + step);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
        let (mut f1, mut f2) = (cost(x1), cost(x2));
        for _ in 0..40 {
            if f1 < f2 {
                hi = x2;
                (x2, f2) = (x1, f1);
                x1 = hi - g * (hi - lo);
                f1 = cost(x1);
            } else {
                lo = x1;
                (x1, f1) = (x2, f2);
                x2 = lo + g * (hi - lo);
                f2 = cost(x2);
            }
        }
        let x = if f1 < f2 { x1 } else { x2 };
        if cost(x) < best_cost {
            at(x)
        } else {
            at(best)
        }
    }

    /// Facet t's direction of least usage in setup `s`, given its best cell
    /// (`cell`, usage): the cap's best direction where the exact test passes
    /// it, else the last direction the test passes on the way from the cell
    /// towards it, else the cell.
    fn refine(&self, t: usize, s: DMat3, cell: (usize, f64)) -> Choice {
        let choice = |dir: DVec3| {
            let (usage, angles) = self.fit.cost(s * dir);
            Choice { dir, usage, angles }
        };
        let from_cell = choice(self.dirs[cell.0]);
        let Some((_, n)) = self.test.facet(t) else {
            return from_cell;
        };
        let target = self.cap_best(s, n);
        let best = choice(target);
        if best.usage >= from_cell.usage - 1e-12 {
            return from_cell;
        }
        if self.test.free(t, target) {
            return best;
        }
        // Bisection on the great circle from the cell (free) to the target.
        let a = self.dirs[cell.0];
        let angle = a.dot(target).clamp(-1.0, 1.0).acos();
        if angle < 1e-12 {
            return from_cell;
        }
        let axis = a.cross(target).normalize_or_zero();
        if axis == DVec3::ZERO {
            return from_cell;
        }
        let at = |u: f64| DMat3::from_axis_angle(axis, u * angle) * a;
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if self.test.free(t, at(mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let c = choice(at(lo));
        if lo > 0.0 && c.usage < from_cell.usage {
            c
        } else {
            from_cell
        }
    }

    /// Usage of setup `s` over `facets` (refined), stopping once it reaches
    /// `bound`; the per-facet choices when `keep`.
    fn worst(
        &self,
        s: DMat3,
        facets: &[usize],
        bound: f64,
        keep: bool,
    ) -> (f64, Vec<Option<Choice>>) {
        let costs = self.cell_costs(s);
        let cells = self.cell_choices(facets, &costs);
        // Facets by their cells' usage, highest first: a facet whose cell
        // needs no more than the worst so far cannot raise it.
        let mut order: Vec<usize> = (0..facets.len()).collect();
        order.sort_by(|&a, &b| {
            let u = |i: usize| cells[i].map_or(f64::INFINITY, |c| c.1);
            u(b).total_cmp(&u(a))
        });
        let mut out: Vec<Option<Choice>> = vec![None; if keep { facets.len() } else { 0 }];
        let mut w: f64 = 0.0;
        for &i in &order {
            let Some(cell) = cells[i] else { continue };
            if !keep && cell.1 <= w {
                break;
            }
            let c = self.refine(facets[i], s, cell);
            w = w.max(c.usage);
            if keep {
                out[i] = Some(c);
            } else if w >= bound {
                break;
            }
        }
        (w, out)
    }

    /// The setup near `s0` of least usage, by a pattern search over
    /// rotations (`dof`: which rotation vectors, in the table frame, it
    /// may take), in trust regions of two cells about the facets that can
    /// matter there. Returns the setup and its usage.
    pub fn optimise(&self, s0: DMat3, dof: Dof) -> (DMat3, f64) {
        let cell = (4.0 * std::f64::consts::PI / self.grid.len() as f64).sqrt();
        let trust = 2.0 * cell;
        let mut s = s0;
        let mut value = self.worst(s, self.live, f64::INFINITY, false).0;
        for _ in 0..6 {
            // The facets that can become the worst within the trust region:
            // a rotation by δ changes a usage by at most δ / (the smallest
            // limit), so by cells no farther than that below the worst.
            let (by_cells, ch) = self.by_cells(s);
            let lip = 1.0 / self.fit_min_limit().to_radians();
            let margin = (2.0 * trust + cell) * lip;
            let crit: Vec<usize> = self
                .live
                .iter()
                .zip(&ch)
                .filter(|(_, c)| c.is_some_and(|c| c.1 >= by_cells.min(value) - margin))
                .map(|(&t, _)| t)
                .collect();
            let (s1, v1, moved) = self.pattern(s, value, &crit, dof, cell, trust);
            s = s1;
            value = v1;
            if moved < 0.8 * trust {
                break;
            }
        }
        (s, self.worst(s, self.live, f64::INFINITY, false).0)
    }

    /// The smallest limit of the axes that count, degrees.
    fn fit_min_limit(&self) -> f64 {
        let m = &self.fit.machine;
        let side = |ax: &RotaryAxis| {
            let lo = ax.min.unwrap_or(-FREE_TILT).abs();
            let hi = ax.max.unwrap_or(FREE_TILT).abs();
            let v = lo.max(hi);
            if v > 1e-6 {
                v
            } else {
                FREE_TILT
            }
        };
        let mut l = side(&m.first);
        if !self.wraps_free() {
            l = l.min(side(&m.second));
        }
        l.max(1.0)
    }

    fn wraps_free(&self) -> bool {
        self.fit.wraps
            && self.fit.machine.second.min.is_none()
            && self.fit.machine.second.max.is_none()
    }

    /// Compass search from `s` within `trust` radians: polls rotations of
    /// step `h` in every direction of `dof` (turned a little each round so
    /// ridges of the maximum are followed), halving `h` when none helps.
    fn pattern(
        &self,
        s: DMat3,
        value: f64,
        crit: &[usize],
        dof: Dof,
        start: f64,
        trust: f64,
    ) -> (DMat3, f64, f64) {
        let (mut s, mut value) = (s, value);
        let mut offset = DVec3::ZERO;
        let mut h = start;
        let mut round = 0usize;
        while h > 2e-5 {
            round += 1;
            let polls = dof.polls(round);
            let mut improved = false;
            for v in polls {
                let w = v * h;
                if (offset + w).length() > trust {
                    continue;
                }
                let cand = rot(w) * s;
                let (u, _) = self.worst(cand, crit, value, false);
                if u < value - 1e-12 {
                    (s, value, improved) = (cand, u, true);
                    offset += w;
                    break;
                }
            }
            if !improved {
                h *= 0.5;
            }
        }
        (s, value, offset.length())
    }

    /// The choices of every live facet in setup `s`.
    pub fn choices(&self, s: DMat3) -> Vec<Option<Choice>> {
        self.worst(s, self.live, f64::INFINITY, true).1
    }
}

/// The rotations a setup may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dof {
    /// Spins about the table's Z only (the part stands on its bottom face).
    Spin,
    /// Tilts only (the spin does not matter: an unlimited C axis).
    Tilt,
    /// Any rotation.
    All,
}

impl Dof {
    /// Unit rotation vectors to poll in round `k`.
    fn polls(self, k: usize) -> Vec<DVec3> {
        let turn = k as f64 * 0.618_033_988_7 * std::f64::consts::TAU / 16.0;
        match self {
            Dof::Spin => vec![DVec3::Z, -DVec3::Z],
            Dof::Tilt => (0..16)
                .map(|i| {
                    let a = turn + i as f64 * std::f64::consts::TAU / 16.0;
                    DVec3::new(a.cos(), a.sin(), 0.0)
                })
                .collect(),
            Dof::All => {
                let r = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), turn);
                let mut v = Vec::with_capacity(26);
                for x in -1..=1 {
                    for y in -1..=1 {
                        for z in -1..=1 {
                            if (x, y, z) != (0, 0, 0) {
                                v.push(r * DVec3::new(x as f64, y as f64, z as f64).normalize());
                            }
                        }
                    }
                }
                v
            }
        }
    }
}
