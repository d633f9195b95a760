//! Mechanistic cutting-force model of helical end mills (spec
//! `process-models.md` §0–§2): ball, flat and bull end mills in 3- and 5-axis
//! work, with the linear edge-force model of Altintas (constant or oblique
//! coefficients) or the flute-segment model of Schnoes & Zaeh.
//!
//! Conventions (§0): lengths mm, forces N, torque N·mm, angles rad. Tool frame
//! (TCS) with the origin at the tip and +z toward the shank; an edge point at
//! immersion φ sits at (R sin φ, R cos φ, z) and φ grows with time; the feed is
//! +x of the feed frame (FCN), whose z is the surface normal. R_wt = Rx(tilt)·
//! Ry(lead) maps TCS vectors into FCN. Forces are those acting on the tool.
//!
//! How it is evaluated: the edge is cut into axial slices once per tool
//! ([`ForceModel::new`]). For one engagement, every (slice, absolute angle θ)
//! cell on a grid of M angles per revolution is tested once for chip thickness
//! and material, and its force is accumulated into a per-angle table; flute j
//! at spindle angle φ_m sits at θ = φ_m + 2πj/N − ψ(z), which is a fixed
//! index shift, so the total over flutes at every spindle angle is a sum of N
//! table entries. The force is periodic with the tooth period, so one period
//! of M/N spindle angles is kept.
//!
//! - [`case`]: one planar-raster engagement with its loads (`millplan cut`).
//! - [`edge`]: tool description and edge discretisation (§1.1).
//! - [`coeffs`]: coefficients, oblique transformation, calibration (§1.5).
//! - [`converge`]: the steps chosen from the engagement, refined until the
//!   peaks converge (the user's grid the coarsest).
//! - [`engage`]: the engagement interface and the analytic planar raster (§1.4a).
//! - [`flat`]: closed-form mean forces of a flat end mill (T1, T2).
//! - [`deflect`]: bending stress and deflection of the tool (§2.2).
//! - [`feed`]: the feed-per-tooth iteration of §2.3.
//! - [`materials`]: named coefficient sets from a small TOML file.
//! - [`mean`]: the mean force over the poses of a move (the static load).

pub mod case;
pub mod coeffs;
pub mod converge;
pub mod deflect;
pub mod edge;
pub mod engage;
pub mod feed;
pub mod flat;
pub mod materials;
pub mod mean;
pub mod quadrature;

use coeffs::{ChipRule, Law};
use converge::error_estimates;
use edge::{Slice, Tool};
use engage::Engagement;
use quadrature::{accumulate, Cell, COLUMNS};
use std::f64::consts::PI;

/// 3×3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// R_wt = Rx(tilt)·Ry(lead) (§0): maps tool-frame vectors into the feed frame.
pub fn r_wt(lead: f64, tilt: f64) -> Mat3 {
    let (sl, cl) = lead.sin_cos();
    let (st, ct) = tilt.sin_cos();
    // Rx(T) = [[1,0,0],[0,cT,−sT],[0,sT,cT]], Ry(L) = [[cL,0,sL],[0,1,0],[−sL,0,cL]].
    [
        [cl, 0.0, sl],
        [st * sl, ct, -st * cl],
        [-ct * sl, st, ct * cl],
    ]
}

/// m·v.
#[inline]
pub fn mul(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// mᵀ·v.
#[inline]
pub fn mul_t(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// Cutting conditions of one engagement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cut {
    /// Feed per tooth \[mm\].
    pub fz: f64,
    /// Spindle speed [1/min] (for power only).
    pub rpm: f64,
    /// Lead and tilt \[rad\] (§0).
    pub lead: f64,
    pub tilt: f64,
}

impl Cut {
    /// The feed-per-tooth vector in the tool frame, fz·R_wtᵀ·x̂ (§1.2).
    pub fn feed_vector(&self) -> [f64; 3] {
        let m = r_wt(self.lead, self.tilt);
        let v = mul_t(&m, [1.0, 0.0, 0.0]);
        [self.fz * v[0], self.fz * v[1], self.fz * v[2]]
    }
}

/// Discretisation: axial slice height and rotation step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Slice height \[mm\].
    pub dz: f64,
    /// Rotation step \[rad\]; rounded down so that a tooth period holds a whole
    /// number of steps.
    pub dphi: f64,
}

impl Default for Grid {
    /// 0.05 mm slices and 1° steps.
    fn default() -> Grid {
        Grid {
            dz: 0.05,
            dphi: 1f64.to_radians(),
        }
    }
}

/// Per-slice constants of the kernel, at θ = 0.
#[derive(Clone, Copy, Debug)]
struct SliceK {
    z: f64,
    /// Meridian length of the centre, and the height of the slice's top.
    u: f64,
    z_top: f64,
    r: f64,
    kappa: f64,
    psi: f64,
    sin_psi: f64,
    cos_psi: f64,
    /// Outward normal (y, z components; x is 0 at θ = 0).
    ny: f64,
    nz: f64,
    /// Force directions of the three coefficient channels.
    dirs: [[f64; 3]; 3],
    /// Width multiplying the cutting term (h·w_cut) and the edge term.
    w_cut: f64,
    w_edge: f64,
    /// Per-slice coefficients (for h-independent laws).
    kc: [f64; 3],
    ke: [f64; 3],
    /// Local inclination i(z) [rad] for the per-element oblique law.
    incl: f64,
}

/// A tool, force law and grid, prepared for many evaluations.
#[derive(Clone, Debug)]
pub struct ForceModel {
    pub tool: Tool,
    pub law: Law,
    pub grid: Grid,
    slices: Vec<SliceK>,
    dz: f64,
    /// Angles per revolution (a multiple of the flute count).
    m: usize,
    sin_t: Vec<f64>,
    cos_t: Vec<f64>,
}

/// Forces over one tooth period and what follows from them.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Rotation step actually used \[rad\].
    pub dphi: f64,
    /// Slice height actually used \[mm\].
    pub dz: f64,
    /// Estimated relative discretisation error of F_xy,max and T_max (the
    /// larger of the two) from the slice height and from the rotation step
    /// (see [`converge`]).
    pub error_dz: f64,
    pub error_dphi: f64,
    pub flutes: usize,
    pub rpm: f64,
    /// R_wt of the engagement.
    pub r_wt: Mat3,
    /// [Fx, Fy, Fz, T] in the tool frame at spindle angles m·dphi over one
    /// tooth period (the force repeats every 2π/N).
    pub period: Vec<[f64; 4]>,
    /// Engaged (slice, angle) cells, counted once per revolution of one flute.
    pub cells: usize,
    /// Smallest axial immersion angle κ of an engaged cell \[rad\].
    pub kappa_min: Option<f64>,
    /// Highest engaged point above the tip \[mm\].
    pub z_max: Option<f64>,
}

/// Minimum and maximum of a quantity over one revolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MinMax {
    pub min: f64,
    pub max: f64,
}

impl MinMax {
    fn of(v: impl Iterator<Item = f64>) -> MinMax {
        let mut r = MinMax {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        };
        for x in v {
            r.min = r.min.min(x);
            r.max = r.max.max(x);
        }
        if r.min > r.max {
            r = MinMax { min: 0.0, max: 0.0 };
        }
        r
    }
}

/// Revolution statistics of an [`Evaluation`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Fx, Fy, Fz ranges in the tool frame.
    pub tool: [MinMax; 3],
    /// The same in the feed (workpiece) frame, F_w = R_wt·F_t.
    pub work: [MinMax; 3],
    /// Mean force over a revolution, tool frame.
    pub mean: [f64; 3],
    /// Maximum transversal resultant sqrt(Fx² + Fy²) in the tool frame.
    pub fxy_max: f64,
    pub torque_max: f64,
    pub torque_mean: f64,
    /// Mean power P = T_mean·ω/1000 \[W\], and the peak from T_max.
    pub power_w: f64,
    pub power_peak_w: f64,
}

/// One sample of the force curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Spindle angle \[rad\].
    pub phi: f64,
    pub tool: [f64; 3],
    pub work: [f64; 3],
    pub torque: f64,
}

/// Angular velocity [rad/s] at n [1/min].
pub fn omega(rpm: f64) -> f64 {
    2.0 * PI * rpm / 60.0
}

impl ForceModel {
    /// Prepares the edge of `tool` over its whole flute length.
    pub fn new(tool: Tool, law: Law, grid: Grid) -> Result<ForceModel, String> {
        tool.validate()?;
        if !(grid.dz > 0.0 && grid.dz <= 1.0) {
            return Err(format!("slice height {} mm: must be in (0, 1]", grid.dz));
        }
        if !(grid.dphi > 0.0 && grid.dphi <= 10f64.to_radians()) {
            return Err("rotation step: must be above 0 and at most 10 degrees".into());
        }
        if tool.flute_length / grid.dz > 1e6 {
            return Err("too many slices: the flute is too long for the slice height".into());
        }
        let n = tool.flutes;
        let per_tooth = (2.0 * PI / (n as f64 * grid.dphi) - 1e-9).ceil().max(1.0) as usize;
        let m = per_tooth * n;
        let step = 2.0 * PI / m as f64;
        let (sin_t, cos_t) = (0..m).map(|k| (k as f64 * step).sin_cos()).unzip();
        let raw = edge::slices(&tool, 0.0, tool.flute_length, grid.dz);
        let dz = raw.first().map_or(grid.dz, |s| s.dz);
        let slices = raw.iter().map(|s| slice_k(s, &law, &tool.shape)).collect();
        Ok(ForceModel {
            tool,
            law,
            grid,
            slices,
            dz,
            m,
            sin_t,
            cos_t,
        })
    }

    /// Slice height actually used \[mm\] (the grid's, shortened so that
    /// whole slices fill the flute).
    pub fn dz(&self) -> f64 {
        self.dz
    }

    /// Rotation step actually used \[rad\].
    pub fn dphi(&self) -> f64 {
        2.0 * PI / self.m as f64
    }

    /// Forces of one engagement.
    pub fn evaluate<E: Engagement + ?Sized>(&self, cut: &Cut, eng: &E) -> Evaluation {
        self.evaluate_engaged(cut, &self.engaged(cut, eng))
    }

    /// The cells of one engagement where the chip is positive and the edge
    /// is in material. They depend on the direction of the feed (lead and
    /// tilt), not on the feed per tooth, so one set serves every feed of the
    /// §2.3 iteration without asking the engagement again.
    pub fn engaged<E: Engagement + ?Sized>(&self, cut: &Cut, eng: &E) -> Engaged {
        self.engaged_in(cut, eng, (f64::NEG_INFINITY, f64::INFINITY))
    }

    /// [`ForceModel::engaged`] on the slices whose centres lie in `band`
    /// (heights above the tip, mm) and in the engagement's own range.
    pub fn engaged_in<E: Engagement + ?Sized>(
        &self,
        cut: &Cut,
        eng: &E,
        band: (f64, f64),
    ) -> Engaged {
        self.engaged_where(cut, eng, band, None)
    }

    /// [`ForceModel::engaged_in`], at the angle indices `angles` only where
    /// given (each a whole column of the edge at one spindle angle; a few,
    /// so each slice looks at those instead of its whole chip window).
    pub(crate) fn engaged_where<E: Engagement + ?Sized>(
        &self,
        cut: &Cut,
        eng: &E,
        band: (f64, f64),
        angles: Option<&[usize]>,
    ) -> Engaged {
        self.engaged_listing(cut, eng, band, angles, None)
    }

    /// [`ForceModel::engaged`], and its cells as runs
    /// ([`quadrature::Run`], from which [`ForceModel::cells_of_runs`]
    /// rebuilds them); `None` for the runs where this model's grid does not
    /// fit them ([`ForceModel::runs_fit`]).
    pub fn engaged_runs<E: Engagement + ?Sized>(
        &self,
        cut: &Cut,
        eng: &E,
    ) -> (Engaged, Option<Vec<quadrature::Run>>) {
        if !self.runs_fit() {
            return (self.engaged(cut, eng), None);
        }
        let mut runs = Vec::new();
        let all = (f64::NEG_INFINITY, f64::INFINITY);
        let e = self.engaged_listing(cut, eng, all, None, Some(&mut runs));
        (e, Some(runs))
    }

    fn engaged_listing<E: Engagement + ?Sized>(
        &self,
        cut: &Cut,
        eng: &E,
        band: (f64, f64),
        angles: Option<&[usize]>,
        runs: Option<&mut Vec<quadrature::Run>>,
    ) -> Engaged {
        let m = self.m;
        let dir = Cut { fz: 1.0, ..*cut };
        let f = dir.feed_vector();
        let (z_lo, z_hi) = eng.z_range(&self.tool);
        let (z_lo, z_hi) = (z_lo.max(band.0), z_hi.min(band.1));
        let u = |z: f64| edge::meridian(&self.tool.shape, z.max(0.0)) / self.dz;
        let first = (u(z_lo).floor() as usize).min(self.slices.len());
        let last = (u(z_hi).ceil() as usize).min(self.slices.len());
        let mut raw = Vec::new();
        // Sector of angle index k: θ = kδ − ψ in units of 2π/SECTORS.
        let per_k = engage::SECTORS as f64 / m as f64;
        for (si, s) in self.slices[first..last.max(first)].iter().enumerate() {
            let mask = eng.sectors(s.z, s.r);
            if mask == 0 {
                continue;
            }
            let psi = s.psi * engage::SECTORS as f64 / (2.0 * PI);
            let (lo, count) = self.chip_window(s, f);
            let mut test = |k: usize| {
                if mask != u64::MAX {
                    let sec = engage::floor_i64(k as f64 * per_k - psi);
                    if mask & (1u64 << sec.rem_euclid(engage::SECTORS as i64)) == 0 {
                        return;
                    }
                }
                let (st, ct) = self.rotated(s, k);
                // h = f·n(θ), n(θ) = (ny sθ, ny cθ, nz)
                let h = f[0] * s.ny * st + f[1] * s.ny * ct + f[2] * s.nz;
                if h > 0.0 && eng.contains([s.r * st, s.r * ct, s.z]) {
                    raw.push(((first + si) as u32, k as u32));
                }
            };
            match angles {
                None => {
                    (0..count).for_each(|i| test(if lo + i >= m { lo + i - m } else { lo + i }))
                }
                Some(ks) => ks
                    .iter()
                    .filter(|&&k| (k + m - lo) % m < count)
                    .for_each(|&k| test(k)),
            }
        }
        Engaged {
            lead: cut.lead,
            tilt: cut.tilt,
            cells: self.weigh(&raw, eng, f, runs),
        }
    }

    /// Forces of an engagement from its engaged cells, at the feed per tooth
    /// and spindle speed of `cut` (its lead and tilt must be those the cells
    /// were found with).
    pub fn evaluate_engaged(&self, cut: &Cut, e: &Engaged) -> Evaluation {
        let (rows, stats) = self.rows(cut, e);
        self.finish(cut, &rows, stats, e.cells.len())
    }

    /// The per-angle table of an engagement over one tooth period
    /// ([`quadrature::COLUMNS`]), and the smallest κ and the highest slice
    /// top of its cells.
    pub(crate) fn rows(&self, cut: &Cut, e: &Engaged) -> (Vec<[f64; COLUMNS]>, (f64, f64)) {
        debug_assert!(e.lead == cut.lead && e.tilt == cut.tilt);
        let m = self.m;
        let f = cut.feed_vector();
        let mut table = vec![[0.0f64; COLUMNS]; m];
        let mut kappa_min = f64::INFINITY;
        let mut z_max = f64::NEG_INFINITY;
        let oblique = match self.law {
            Law::Oblique(o) => match o.chip {
                ChipRule::PerElement { h_min } => Some((o, h_min)),
                ChipRule::Fixed(_) => None,
            },
            _ => None,
        };
        for c in &e.cells {
            let s = &self.slices[c.slice as usize];
            let k = c.k as usize;
            kappa_min = kappa_min.min(s.kappa);
            z_max = z_max.max(s.z_top);
            let (st, ct) = self.rotated(s, k);
            let h = (f[0] * s.ny * st + f[1] * s.ny * ct + f[2] * s.nz).max(0.0);
            let kc = match oblique {
                Some((o, h_min)) => o.coefficients(h.max(h_min), s.incl),
                None => s.kc,
            };
            let wc = h * s.w_cut;
            let mut f0 = [0.0; 3];
            for ((ke, kc), d) in s.ke.iter().zip(kc).zip(&s.dirs) {
                let mag = ke * s.w_edge + kc * wc;
                f0[0] += mag * d[0];
                f0[1] += mag * d[1];
                f0[2] += mag * d[2];
            }
            // Rotate from θ = 0 to θ: (a, b, c) → (a cθ + b sθ, −a sθ + b cθ, c).
            let q = [
                f0[0] * ct + f0[1] * st,
                -f0[0] * st + f0[1] * ct,
                f0[2],
                -s.r * f0[0],
            ];
            accumulate(&mut table[k], c, q);
        }
        let n = self.tool.flutes;
        let p = m / n;
        let sums: Vec<[f64; COLUMNS]> = (0..p)
            .map(|i| {
                let mut acc = [0.0; COLUMNS];
                for j in 0..n {
                    let t = &table[(i + j * p) % m];
                    for c in 0..COLUMNS {
                        acc[c] += t[c];
                    }
                }
                acc
            })
            .collect();
        (sums, (kappa_min, z_max))
    }

    /// The evaluation from the per-angle table `rows` of one tooth period
    /// ([`ForceModel::rows`]), with the smallest κ and highest slice top of
    /// its `cells` cells.
    pub(crate) fn finish(
        &self,
        cut: &Cut,
        rows: &[[f64; COLUMNS]],
        (kappa_min, z_max): (f64, f64),
        cells: usize,
    ) -> Evaluation {
        let (error_dz, error_dphi) = error_estimates(rows);
        Evaluation {
            dphi: self.dphi(),
            dz: self.dz,
            error_dz,
            error_dphi,
            flutes: self.tool.flutes,
            rpm: cut.rpm,
            r_wt: r_wt(cut.lead, cut.tilt),
            period: rows.iter().map(|r| [r[0], r[1], r[2], r[3]]).collect(),
            cells,
            kappa_min: kappa_min.is_finite().then_some(kappa_min),
            z_max: z_max.is_finite().then_some(z_max),
        }
    }

    /// Angles per tooth period.
    pub(crate) fn per_tooth(&self) -> usize {
        self.m / self.tool.flutes
    }

    /// sin θ and cos θ of slice `s` at angle index `k`: θ = kδ − ψ.
    #[inline]
    fn rotated(&self, s: &SliceK, k: usize) -> (f64, f64) {
        let (sk, ck) = (self.sin_t[k], self.cos_t[k]);
        (
            sk * s.cos_psi - ck * s.sin_psi,
            ck * s.cos_psi + sk * s.sin_psi,
        )
    }
}

/// The engaged cells of one engagement ([`ForceModel::engaged`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Engaged {
    lead: f64,
    tilt: f64,
    /// Column by column (angle index ascending), each column's slices
    /// ascending ([`quadrature`]).
    cells: Vec<Cell>,
}

impl Engaged {
    /// Engaged cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The engaged cells, column by column.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// An engagement of `cut`'s lead and tilt from cells that
    /// [`ForceModel::engaged`] of the same model gave at that lead and tilt
    /// (kept from an earlier run over the same stock and path: the cells
    /// depend on the feed direction, not on the feed per tooth or the
    /// spindle speed).
    pub fn from_cells(cut: &Cut, cells: Vec<Cell>) -> Engaged {
        Engaged {
            lead: cut.lead,
            tilt: cut.tilt,
            cells,
        }
    }
}

impl ForceModel {
    /// The angle indices of one revolution where the chip thickness of slice
    /// `s` can be positive, as (first index, count): h(θ) = A·sin θ +
    /// B·cos θ + C is positive on one arc, widened by a step on each side
    /// (every index is still checked).
    fn chip_window(&self, s: &SliceK, f: [f64; 3]) -> (usize, usize) {
        let m = self.m;
        let (a, b, c) = (f[0] * s.ny, f[1] * s.ny, f[2] * s.nz);
        let rho = a.hypot(b);
        if rho <= c.abs() {
            return if c > 0.0 { (0, m) } else { (0, 0) };
        }
        // ρ sin(θ + α) > −C on θ + α ∈ (u, π − u), u = asin(−C/ρ).
        let alpha = b.atan2(a);
        let u = (-c / rho).asin();
        let step = 2.0 * PI / m as f64;
        let start = u - alpha + s.psi;
        let span = PI - 2.0 * u;
        let first = (start / step).floor() as i64 - 1;
        let count = ((span / step).ceil() as usize + 3).min(m);
        (first.rem_euclid(m as i64) as usize, count)
    }
}

fn slice_k(s: &Slice, law: &Law, shape: &crate::cutter::Shape) -> SliceK {
    let (sk, ck) = (s.sin_k, s.cos_k);
    let nrm = s.normal;
    let t = s.tangent;
    // Directions at θ = 0: tangential (−1, 0, 0) against the cutting
    // velocity, radial −n, and axial along the meridian toward the shank,
    // (cos κ sin p, cos κ cos p, sin κ): on the cylinder a positive axial
    // force is +z, the textbook sign of T1a (F̄z = (Na/π)(Kac·c + Kae·π/2)).
    // Lee & Altintas' matrix of §1.3 takes the axial direction the other
    // way (dFz = −dFa on the cylinder, its caveat); its Kac is −Kac here.
    let rta = [[-1.0, 0.0, 0.0], [0.0, -sk, ck], [0.0, ck, sk]];
    let incl = s.edge.tan_i.atan();
    // The edge terms of the linear law act on the width of cut db = dz/sin κ
    // (the edge's length in the meridian plane): the textbook end-mill
    // model, with which every published coefficient set was calibrated,
    // gives Ke·dz on a flat end whatever the helix (T1a: "helix
    // irrelevant"); §1.3's dS would lengthen it by 1/cos i0 there. On a
    // ball the two differ by sqrt(1 + sin⁴κ·tan²i0): under 1 % up to κ = 40°
    // at i0 = 30°.
    let (dirs, w_cut, w_edge, kc, ke) = match *law {
        Law::Rta(c) => (rta, s.db, s.db, c.kc, c.ke),
        Law::Oblique(o) => {
            let kc = match o.chip {
                ChipRule::Fixed(h) => o.coefficients(h, incl),
                ChipRule::PerElement { .. } => [0.0; 3],
            };
            (rta, s.db, s.db, kc, o.db.ke)
        }
        Law::FluteSegment(c) => {
            // d = t × v / |…| = the outward normal; n = d × t (along v).
            let d = nrm;
            let nv = [
                d[1] * t[2] - d[2] * t[1],
                d[2] * t[0] - d[0] * t[2],
                d[0] * t[1] - d[1] * t[0],
            ];
            let l = (nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]).sqrt();
            let nv = [nv[0] / l, nv[1] / l, nv[2] / l];
            ([t, d, nv], s.ds, s.ds, c.kc, c.ke)
        }
    };
    SliceK {
        z: s.z,
        u: s.u,
        z_top: edge::height(shape, s.u + 0.5 * s.dz),
        r: s.edge.r,
        kappa: s.edge.kappa,
        psi: s.edge.psi,
        sin_psi: s.edge.psi.sin(),
        cos_psi: s.edge.psi.cos(),
        ny: nrm[1],
        nz: nrm[2],
        dirs,
        w_cut,
        w_edge,
        kc,
        ke,
        incl,
    }
}

impl Evaluation {
    /// Statistics over one revolution.
    pub fn summary(&self) -> Summary {
        let p = &self.period;
        let work: Vec<[f64; 3]> = p
            .iter()
            .map(|s| mul(&self.r_wt, [s[0], s[1], s[2]]))
            .collect();
        let len = p.len().max(1) as f64;
        let mean = |c: usize| p.iter().map(|s| s[c]).sum::<f64>() / len;
        let torque_mean = mean(3);
        let torque_max = MinMax::of(p.iter().map(|s| s[3])).max;
        let w = omega(self.rpm);
        Summary {
            tool: [0, 1, 2].map(|c| MinMax::of(p.iter().map(|s| s[c]))),
            work: [0, 1, 2].map(|c| MinMax::of(work.iter().map(|s| s[c]))),
            mean: [mean(0), mean(1), mean(2)],
            fxy_max: p.iter().map(|s| s[0].hypot(s[1])).fold(0.0, f64::max),
            torque_max,
            torque_mean,
            power_w: torque_mean * w / 1000.0,
            power_peak_w: torque_max * w / 1000.0,
        }
    }

    /// The force curve over one whole revolution.
    pub fn revolution(&self) -> Vec<Sample> {
        let p = self.period.len();
        (0..p * self.flutes)
            .map(|i| {
                let s = self.period[i % p.max(1)];
                Sample {
                    phi: i as f64 * self.dphi,
                    tool: [s[0], s[1], s[2]],
                    work: mul(&self.r_wt, [s[0], s[1], s[2]]),
                    torque: s[3],
                }
            })
            .collect()
    }
}
