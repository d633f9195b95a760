//! The tool as a body: the cutter (flat, ball, bull or cone) up to its flute
//! length, the shank above it and the holder from the stick-out up; and where
//! such a body, or its sweep along a move, meets the vertical line of a cell.

use millplan_geom::{DVec2, DVec3};
use millplan_models::cutter::Shape;

/// Flute length of a tool whose flutes nobody gives: the whole tool cuts.
pub const UNKNOWN_FLUTE: f64 = 1e6;

/// Flute length, in tool diameters, of a tool whose flutes nobody gives
/// (neither the options nor the program's cutter) when its shank or holder
/// is simulated: a standard end mill's length of cut. Without it the shank
/// would start a metre up and the holder never meet material.
pub const DEFAULT_FLUTE_DIAMETERS: f64 = 3.0;

impl BodyOptions {
    /// The flute length `op`'s tool takes by [`DEFAULT_FLUTE_DIAMETERS`],
    /// mm, when it takes it (a holder or shank given, no flute length known);
    /// commands state it in their output.
    pub fn default_flute(&self, op: &millplan_nc::Operation) -> Option<f64> {
        let cutter = op.tool.as_ref().and_then(|t| t.cutter);
        let known = self
            .flute
            .or_else(|| cutter.map(|c| c.h).filter(|h| *h > 0.0));
        if known.is_some() || (self.holder.is_none() && self.shank_r.is_none()) {
            return None;
        }
        let shape = self
            .shape
            .or_else(|| cutter.and_then(|c| crate::shape_of(&c)))?;
        Some(DEFAULT_FLUTE_DIAMETERS * 2.0 * shape.radius())
    }
}

/// What a command says of its tools beyond the program (see
/// [`ToolBody::for_operation`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyOptions {
    /// Cutter for operations whose tool has no geometry, or to override it.
    pub shape: Option<Shape>,
    /// Cutting length from the tip, mm.
    pub flute: Option<f64>,
    /// Shank radius above the flutes, mm.
    pub shank_r: Option<f64>,
    /// Holder radius and stick-out from the tip to its face, mm.
    pub holder: Option<(f64, f64)>,
    /// Leave out cone cutters (the force model has none).
    pub no_cone: bool,
}

/// A tool body, coaxial parts from the tip up. Lengths from the tip, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolBody {
    pub shape: Shape,
    /// Cutting length (flutes) from the tip; above it the shank does not cut.
    pub flute: f64,
    /// Shank radius above the flutes.
    pub shank_r: f64,
    /// From the tip to the holder's face (∞: no holder modelled).
    pub stickout: f64,
    /// Holder radius (0: none).
    pub holder_r: f64,
}

impl ToolBody {
    /// The cutter alone with a shank of its own diameter, flutes of three
    /// diameters, no holder.
    pub fn new(shape: Shape) -> ToolBody {
        let r = shape.radius();
        ToolBody {
            shape,
            flute: 6.0 * r,
            shank_r: r,
            stickout: f64::INFINITY,
            holder_r: 0.0,
        }
    }

    pub fn radius(&self) -> f64 {
        self.shape.radius()
    }

    /// The body of an operation's tool, the one rule every command uses: the
    /// cutter from `o.shape` or the program's CUTTER record (`None` when
    /// neither gives a shape, or a cone where `o.no_cone`); the flutes up to
    /// `o.flute`, else the tool's height when it gives one, else the whole
    /// tool cuts (no shank collision); the shank of `o.shank_r`, else the
    /// cutter's radius; the holder of `o.holder` (radius, stick-out from the
    /// tip, never below the flutes), else none.
    pub fn for_operation(op: &millplan_nc::Operation, o: &BodyOptions) -> Option<ToolBody> {
        let cutter = op.tool.as_ref().and_then(|t| t.cutter);
        let shape = o
            .shape
            .or_else(|| cutter.and_then(|c| crate::shape_of(&c)))?;
        if o.no_cone && matches!(shape, Shape::Cone { .. }) {
            return None;
        }
        let mut b = ToolBody::new(shape);
        b.flute = o
            .flute
            .or_else(|| cutter.map(|c| c.h).filter(|h| *h > 0.0))
            .or_else(|| o.default_flute(op))
            .unwrap_or(UNKNOWN_FLUTE);
        b.shank_r = o.shank_r.unwrap_or(shape.radius());
        if let Some((r, l)) = o.holder {
            b.holder_r = r;
            b.stickout = l.max(b.flute.min(1e5));
        }
        Some(b)
    }

    /// Largest radius of any part that can meet material.
    pub fn reach(&self) -> f64 {
        let h = if self.stickout.is_finite() {
            self.holder_r
        } else {
            0.0
        };
        self.radius().max(self.shank_r).max(h)
    }

    /// Radius of the cutter at height `h` above the tip (the cutting part).
    pub fn cutter_radius_at(&self, h: f64) -> f64 {
        if h < 0.0 {
            return 0.0;
        }
        match self.shape {
            Shape::Flat { radius } => radius,
            Shape::Ball { radius } => {
                if h >= radius {
                    radius
                } else {
                    (radius * radius - (radius - h) * (radius - h))
                        .max(0.0)
                        .sqrt()
                }
            }
            Shape::Bull { radius, corner } => {
                if h >= corner {
                    radius
                } else {
                    radius - corner
                        + (corner * corner - (corner - h) * (corner - h))
                            .max(0.0)
                            .sqrt()
                }
            }
            Shape::Cone { radius, alpha } => (h / alpha.tan().max(1e-12)).min(radius),
        }
    }

    /// Lower boundary of the non-cutting parts at radius `r` from the axis, as
    /// a height above the tip (∞ where none reaches).
    #[inline]
    pub fn noncut_height(&self, r: f64) -> f64 {
        if r <= self.shank_r {
            self.flute
        } else if r <= self.holder_r {
            self.stickout
        } else {
            f64::INFINITY
        }
    }
}

/// What a vertical tool's sweep leaves in one cell: everything above `cut`
/// goes; material above `noncut` was met by the shank or holder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColumnCut {
    pub cut: f64,
    pub noncut: f64,
}

/// A vertical tool (axis +Z) moving in a straight line from `p0` to `p1`
/// (tool tips): the lowest point of its swept body over each cell.
#[derive(Clone, Copy, Debug)]
pub struct VerticalSweep {
    pub tool: ToolBody,
    pub p0: DVec3,
    pub p1: DVec3,
    /// XY direction (unit; X when the move is vertical) and XY length.
    pub u: DVec2,
    pub len: f64,
}

impl VerticalSweep {
    pub fn new(tool: ToolBody, p0: DVec3, p1: DVec3) -> VerticalSweep {
        let d = (p1 - p0).truncate();
        let len = d.length();
        VerticalSweep {
            tool,
            p0,
            p1,
            u: if len > 1e-12 { d / len } else { DVec2::X },
            len,
        }
    }

    /// The parameter range t ∈ [0, 1] over which the axis passes within `r`
    /// of (x, y).
    #[inline]
    fn within(&self, c: DVec2, r: f64) -> Option<(f64, f64)> {
        let w = c - self.p0.truncate();
        if self.len <= 1e-12 {
            return (w.length_squared() <= r * r).then_some((0.0, 1.0));
        }
        let along = w.dot(self.u);
        let perp2 = w.length_squared() - along * along;
        let h2 = r * r - perp2;
        if h2 < 0.0 {
            return None;
        }
        let h = h2.sqrt();
        let a = ((along - h) / self.len).max(0.0);
        let b = ((along + h) / self.len).min(1.0);
        (a <= b).then_some((a, b))
    }

    #[inline]
    fn z(&self, t: f64) -> f64 {
        self.p0.z + (self.p1.z - self.p0.z) * t
    }

    /// Lowest height over t ∈ [a, b] of the axis's tip plus `h`.
    #[inline]
    fn lowest(&self, (a, b): (f64, f64), h: f64) -> f64 {
        self.z(a).min(self.z(b)) + h
    }

    /// The sweep's lowest points over the cell centred at `c`.
    pub fn column(&self, c: DVec2) -> ColumnCut {
        let t = &self.tool;
        let mut noncut = f64::INFINITY;
        if let Some(r) = self.within(c, t.shank_r) {
            noncut = self.lowest(r, t.flute);
        }
        if t.stickout.is_finite() && t.holder_r > 0.0 {
            if let Some(r) = self.within(c, t.holder_r) {
                noncut = noncut.min(self.lowest(r, t.stickout));
            }
        }
        let cut = match self.within(c, t.radius()) {
            None => f64::INFINITY,
            Some(range) => self.cutter_lowest(c, range),
        };
        ColumnCut {
            cut: cut.min(noncut),
            noncut,
        }
    }

    /// min over t in `range` of z(t) + height(distance from the axis at t).
    fn cutter_lowest(&self, c: DVec2, range: (f64, f64)) -> f64 {
        match self.tool.shape {
            Shape::Flat { .. } => self.lowest(range, 0.0),
            Shape::Ball { radius } => self.capsule_lowest(c, radius),
            shape => {
                // Convex in t (a convex, increasing profile of a convex
                // distance plus a linear height): golden-section search.
                let g = |t: f64| {
                    let q = self.p0.truncate() + self.u * (self.len * t);
                    self.z(t) + shape.height((c - q).length().min(shape.radius()))
                };
                let (mut a, mut b) = range;
                if self.len <= 1e-12 || (self.p1.z - self.p0.z).abs() < 1e-12 && b - a < 1e-12 {
                    return g(a).min(g(b));
                }
                const INV_PHI: f64 = 0.618_033_988_749_894_9;
                let mut x1 = b - INV_PHI * (b - a);
                let mut x2 = a + INV_PHI * (b - a);
                let (mut f1, mut f2) = (g(x1), g(x2));
                // 1e-9 of the move: far below any cell.
                for _ in 0..48 {
                    if f1 < f2 {
                        b = x2;
                        x2 = x1;
                        f2 = f1;
                        x1 = b - INV_PHI * (b - a);
                        f1 = g(x1);
                    } else {
                        a = x1;
                        x1 = x2;
                        f1 = f2;
                        x2 = a + INV_PHI * (b - a);
                        f2 = g(x2);
                    }
                }
                f1.min(f2).min(g(range.0)).min(g(range.1))
            }
        }
    }

    /// Lowest point over (x, y) of the capsule swept by the ball's centre.
    fn capsule_lowest(&self, c: DVec2, r: f64) -> f64 {
        let c0 = self.p0 + DVec3::Z * r;
        let c1 = self.p1 + DVec3::Z * r;
        let mut best = f64::INFINITY;
        for e in [c0, c1] {
            let d2 = (c - e.truncate()).length_squared();
            if d2 <= r * r {
                best = best.min(e.z - (r * r - d2).sqrt());
            }
        }
        let s = c1 - c0;
        let l2 = s.length_squared();
        if l2 > 1e-24 {
            let l = l2.sqrt();
            let v = s / l;
            // Points q = (c, z) at distance r from the line c0 + v·s:
            // (1 − vz²) z'² − 2 (w0·v) vz z' + (|w0|² − (w0·v)² − r²) = 0,
            // z' = z − c0.z, w0 = (c − c0.xy, 0).
            let w0 = DVec3::new(c.x - c0.x, c.y - c0.y, 0.0);
            let wv = w0.dot(v);
            let a = 1.0 - v.z * v.z;
            let b = -2.0 * wv * v.z;
            let cc = w0.length_squared() - wv * wv - r * r;
            if a > 1e-12 {
                let disc = b * b - 4.0 * a * cc;
                if disc >= 0.0 {
                    let zp = (-b - disc.sqrt()) / (2.0 * a);
                    let along = wv + zp * v.z;
                    if (0.0..=l).contains(&along) {
                        best = best.min(c0.z + zp);
                    }
                }
            }
        }
        best
    }
}

/// A tool body standing still at `tip` with unit axis `axis`, met by the
/// vertical line through (x, y): the z-intervals inside its cutting part and
/// inside its non-cutting parts (each part is convex, so one interval each).
#[derive(Clone, Copy, Debug)]
pub struct Pose {
    pub tool: ToolBody,
    pub tip: DVec3,
    pub axis: DVec3,
}

/// A convex part of a tool body in its own frame (heights from the tip).
#[derive(Clone, Copy, Debug)]
enum Part {
    /// Ball of radius r centred at height c.
    Sphere { c: f64, r: f64 },
    /// Cylinder of radius r between heights h0 and h1.
    Cylinder { h0: f64, h1: f64, r: f64 },
    /// Cone from the tip: radius = h·k for h in [0, h1].
    Cone { k: f64, h1: f64 },
    /// The bull nose's lower part: points within `corner` of the disc of
    /// radius `e` at height `corner`, below that height.
    Torus { e: f64, corner: f64 },
}

impl Pose {
    /// The cutting and non-cutting parts, heights from the tip.
    fn parts(&self) -> ([Option<Part>; 2], [Option<Part>; 2]) {
        let t = &self.tool;
        let r = t.radius();
        let cut = match t.shape {
            Shape::Flat { .. } => [
                Some(Part::Cylinder {
                    h0: 0.0,
                    h1: t.flute,
                    r,
                }),
                None,
            ],
            Shape::Ball { radius } => [
                Some(Part::Sphere {
                    c: radius,
                    r: radius,
                }),
                (t.flute > radius).then_some(Part::Cylinder {
                    h0: radius,
                    h1: t.flute,
                    r: radius,
                }),
            ],
            Shape::Bull { radius, corner } => [
                Some(Part::Torus {
                    e: radius - corner,
                    corner,
                }),
                (t.flute > corner).then_some(Part::Cylinder {
                    h0: corner,
                    h1: t.flute,
                    r: radius,
                }),
            ],
            Shape::Cone { radius, alpha } => {
                let h = radius * alpha.tan();
                [
                    Some(Part::Cone {
                        k: 1.0 / alpha.tan().max(1e-12),
                        h1: h.min(t.flute),
                    }),
                    (t.flute > h).then_some(Part::Cylinder {
                        h0: h,
                        h1: t.flute,
                        r: radius,
                    }),
                ]
            }
        };
        let top = if t.stickout.is_finite() {
            t.stickout
        } else {
            t.flute + 1e6
        };
        let noncut = [
            (t.shank_r > 0.0 && top > t.flute).then_some(Part::Cylinder {
                h0: t.flute,
                h1: top,
                r: t.shank_r,
            }),
            (t.stickout.is_finite() && t.holder_r > 0.0).then_some(Part::Cylinder {
                h0: t.stickout,
                h1: t.stickout + 1e6,
                r: t.holder_r,
            }),
        ];
        (cut, noncut)
    }

    /// Lowest z of the body (tip region) and the XY box of its parts up to
    /// `height` above the tip.
    pub fn xy_box(&self, height: f64) -> (DVec2, DVec2) {
        let a = self.axis;
        let r = self.tool.reach();
        let e = DVec2::new(
            r * (1.0 - a.x * a.x).max(0.0).sqrt(),
            r * (1.0 - a.y * a.y).max(0.0).sqrt(),
        );
        let p0 = self.tip.truncate();
        let p1 = (self.tip + a * height).truncate();
        (p0.min(p1) - e, p0.max(p1) + e)
    }

    /// The z-intervals where the vertical line through `c` is inside the
    /// cutting parts and inside the non-cutting parts.
    pub fn column(&self, c: DVec2) -> (Option<[f64; 2]>, Option<[f64; 2]>) {
        self.column_parts(c, true)
    }

    /// As [`Pose::column`]; the non-cutting parts only when `noncut`.
    pub fn column_parts(&self, c: DVec2, noncut: bool) -> (Option<[f64; 2]>, Option<[f64; 2]>) {
        let (cut, upper) = self.parts();
        let upper = if noncut { upper } else { [None, None] };
        let hull = |parts: [Option<Part>; 2]| {
            let mut out: Option<[f64; 2]> = None;
            for p in parts.into_iter().flatten() {
                if let Some([a, b]) = self.part_interval(p, c) {
                    out = Some(match out {
                        // The parts of one group touch end to end along the
                        // axis, so their intervals on one line overlap or
                        // touch: the union is the hull.
                        Some([x, y]) => [x.min(a), y.max(b)],
                        None => [a, b],
                    });
                }
            }
            out
        };
        (hull(cut), hull(upper))
    }

    /// The lowest z any non-cutting part (shank, holder) reaches.
    pub fn noncut_lowest(&self) -> f64 {
        let t = &self.tool;
        let sin = (1.0 - self.axis.z * self.axis.z).max(0.0).sqrt();
        let shank = self.tip.z + self.axis.z * t.flute - t.shank_r * sin;
        let holder = if t.stickout.is_finite() && t.holder_r > 0.0 {
            self.tip.z + self.axis.z * t.stickout - t.holder_r * sin
        } else {
            f64::INFINITY
        };
        shank.min(holder)
    }

    /// The z-interval of the vertical line through `c` inside one part.
    fn part_interval(&self, p: Part, c: DVec2) -> Option<[f64; 2]> {
        let a = self.axis;
        // Line q(z) = (c, z); relative to the tip: w(z) = w0 + z·ez.
        let w0 = DVec3::new(c.x - self.tip.x, c.y - self.tip.y, -self.tip.z);
        // Height along the axis: h(z) = w0·a + z·az; squared distance from
        // the axis: |w0 + z ez|² − h(z)², quadratic in z.
        let h0 = w0.dot(a);
        let az = a.z;
        // r²(z) = A z² + B z + C
        let ra = 1.0 - az * az;
        let rb = 2.0 * (w0.z - h0 * az);
        let rc = w0.length_squared() - h0 * h0;
        // The heights [lo, hi] as a z-range (h(z) = h0 + z·az).
        let h_range = |lo: f64, hi: f64| -> Option<[f64; 2]> {
            if az.abs() < 1e-12 {
                return (h0 >= lo && h0 <= hi).then_some([f64::NEG_INFINITY, f64::INFINITY]);
            }
            let (z1, z2) = ((lo - h0) / az, (hi - h0) / az);
            Some([z1.min(z2), z1.max(z2)])
        };
        let out = match p {
            Part::Sphere { c: hc, r } => {
                // |w(z) − hc·a|² ≤ r²
                let m = w0 - a * hc;
                quad_le(1.0, 2.0 * m.z, m.length_squared() - r * r, None)
            }
            Part::Cylinder { h0: lo, h1: hi, r } => {
                quad_le(ra, rb, rc - r * r, Some(h_range(lo, hi)?))
            }
            Part::Cone { k, h1 } => {
                // r² ≤ k² h² with h in [0, h1] (the nappe above the tip)
                let qa = ra - k * k * az * az;
                let qb = rb - 2.0 * k * k * h0 * az;
                let qc = rc - k * k * h0 * h0;
                quad_le(qa, qb, qc, Some(h_range(0.0, h1)?))
            }
            Part::Torus { e, corner } => self.torus_interval(c, e, corner),
        };
        out.filter(|[lo, hi]| hi > lo)
    }

    /// The bull nose's lower part: {q : dist(q, disc) ≤ corner, h ≤ corner},
    /// convex, so its trace on a line is an interval: F(z) = max(dist − corner,
    /// height above the disc) is convex and ≤ 0 exactly inside; minimise it,
    /// then bisect both ends.
    fn torus_interval(&self, c: DVec2, e: f64, corner: f64) -> Option<[f64; 2]> {
        let a = self.axis;
        let centre = self.tip + a * corner;
        let f = |z: f64| -> f64 {
            let w = DVec3::new(c.x, c.y, z) - centre;
            let h = w.dot(a);
            let radial = (w - a * h).length();
            let out = (radial - e).max(0.0);
            ((out * out + h * h).sqrt() - corner).max(h)
        };
        let span = 2.0 * (e + corner) + 1.0;
        let (lo, hi) = (centre.z - span, centre.z + span);
        const INV_PHI: f64 = 0.618_033_988_749_894_9;
        let (mut a1, mut b1) = (lo, hi);
        // 40 steps shrink the bracket (a few tens of mm) below 1e-6 mm.
        for _ in 0..40 {
            let x1 = b1 - INV_PHI * (b1 - a1);
            let x2 = a1 + INV_PHI * (b1 - a1);
            if f(x1) < f(x2) {
                b1 = x2;
            } else {
                a1 = x1;
            }
        }
        let seed = 0.5 * (a1 + b1);
        if f(seed) > 0.0 {
            return None;
        }
        let bis = |mut inn: f64, mut out: f64| -> f64 {
            for _ in 0..40 {
                let m = 0.5 * (inn + out);
                if f(m) <= 0.0 {
                    inn = m;
                } else {
                    out = m;
                }
            }
            inn
        };
        Some([bis(seed, lo), bis(seed, hi)])
    }
}

/// {z : qa z² + qb z + qc ≤ 0} ∩ `range` as one interval. When qa < 0 the
/// solution is two half-lines; `range` (a cone's heights) keeps one of them.
fn quad_le(qa: f64, qb: f64, qc: f64, range: Option<[f64; 2]>) -> Option<[f64; 2]> {
    const ALL: [f64; 2] = [f64::NEG_INFINITY, f64::INFINITY];
    let range = match range {
        Some(r) => r,
        None if qa > 0.0 => ALL,
        None => return None,
    };
    let meet = |x: [f64; 2]| -> Option<[f64; 2]> {
        let (lo, hi) = (x[0].max(range[0]), x[1].min(range[1]));
        (lo < hi).then_some([lo, hi])
    };
    if qa.abs() < 1e-12 {
        if qb.abs() < 1e-12 {
            return if qc <= 0.0 { meet(ALL) } else { None };
        }
        let z = -qc / qb;
        return meet(if qb > 0.0 {
            [f64::NEG_INFINITY, z]
        } else {
            [z, f64::INFINITY]
        });
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return if qa > 0.0 { None } else { meet(ALL) };
    }
    let s = disc.sqrt();
    let (x1, x2) = ((-qb - s) / (2.0 * qa), (-qb + s) / (2.0 * qa));
    let (x1, x2) = (x1.min(x2), x1.max(x2));
    if qa > 0.0 {
        return meet([x1, x2]);
    }
    // Outside the roots: two half-lines, of which the height range keeps
    // the one on the cone's side (the nappe above the tip is convex).
    match (meet([f64::NEG_INFINITY, x1]), meet([x2, f64::INFINITY])) {
        (Some(a), None) | (None, Some(a)) => Some(a),
        (Some(a), Some(b)) => Some([a[0].min(b[0]), a[1].max(b[1])]),
        (None, None) => None,
    }
}
