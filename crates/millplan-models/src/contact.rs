//! Where a ball-end mill touches the part at each tool position, and the local
//! quantities the working-diameter model needs there: contact point and normal,
//! inclination, feed direction, uncut side and actual stepover (spec
//! `working-diameter.md` §1.1, §1.4 and §5).

use crate::wd::{self, Case, Neighbour, Side};
use millplan_geom::bvh::{vertex_normals, Bvh};
use millplan_geom::{DVec3, TriMesh};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// Which point of the tool the CL points are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Convention {
    /// The tool tip (ISO CLDATA; nearly every CAM system by default).
    Tip,
    /// The ball centre.
    Centre,
}

/// Which normal is used at the contact point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum NormalMode {
    /// Angle-weighted vertex normals interpolated at the contact point (default:
    /// a tessellated free-form surface should not step from facet to facet).
    Smooth,
    /// The normal of the facet that holds the contact point (true creases).
    Facet,
    /// The direction from the contact point to the ball centre.
    Ball,
}

/// The part surface prepared for contact queries.
pub struct Surface<'a> {
    pub mesh: &'a TriMesh,
    pub bvh: Bvh,
    pub vertex_normals: Vec<DVec3>,
}

impl<'a> Surface<'a> {
    pub fn new(mesh: &'a TriMesh) -> Surface<'a> {
        let (bvh, vertex_normals) = rayon::join(|| Bvh::build(mesh), || vertex_normals(mesh));
        Surface {
            mesh,
            bvh,
            vertex_normals,
        }
    }
}

/// One tool position to analyse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoint {
    /// CL point as read.
    pub cl: DVec3,
    /// Unit tool axis (from the tip up the spindle).
    pub axis: DVec3,
    /// Pass number: points of one pass are cut one after another without a link.
    pub pass: u32,
}

/// Settings of the analysis.
#[derive(Clone, Copy, Debug)]
pub struct Params {
    /// Ball diameter, mm.
    pub d: f64,
    /// Stock thickness along the normal, mm.
    pub ap: f64,
    pub convention: Convention,
    pub normals: NormalMode,
    /// |centre-to-mesh distance − R| beyond this flags the point, mm.
    pub gap_tol: f64,
    /// How far to look sideways for neighbouring passes, mm.
    pub neighbour_search: f64,
    /// Turns sharper than this (radians) are corners: both directions are evaluated
    /// and the larger working diameter kept.
    pub corner_angle: f64,
    /// Use the paper's nearest-in-centre facet instead of the exact contact
    /// (for comparison only).
    pub nearest_incentre: bool,
}

impl Params {
    pub fn new(d: f64, ap: f64) -> Params {
        Params {
            d,
            ap,
            convention: Convention::Tip,
            normals: NormalMode::Smooth,
            gap_tol: 0.02,
            neighbour_search: 0.6 * d,
            corner_angle: 45f64.to_radians(),
            nearest_incentre: false,
        }
    }
}

/// Everything known about one tool position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointResult {
    /// Contact point on the mesh.
    pub contact: DVec3,
    /// Unit surface normal at the contact point.
    pub normal: DVec3,
    /// Centre-to-mesh distance minus R (negative: the ball is inside the part).
    pub gap: f64,
    /// No surface within reach of the ball.
    pub no_contact: bool,
    /// Inclination α, radians.
    pub inclination: f64,
    /// Feed direction relative to uphill, radians.
    pub feed_angle: f64,
    pub side: Side,
    pub neighbour: Neighbour,
    pub corner: bool,
    /// Working diameter, mm.
    pub dw: f64,
}

impl PointResult {
    pub fn ae(&self) -> Option<f64> {
        match self.neighbour {
            Neighbour::None => None,
            Neighbour::One(a) | Neighbour::Both(a) => Some(a),
        }
    }
}

/// Ball centre of a CL point.
pub fn centre(p: &PathPoint, conv: Convention, r: f64) -> DVec3 {
    match conv {
        Convention::Tip => p.cl + p.axis * r,
        Convention::Centre => p.cl,
    }
}

/// The ball centres of points under a convention, computed where asked
/// (the same bits as [`centre`] each time).
#[derive(Clone, Copy)]
struct Centres<'a> {
    pts: &'a [PathPoint],
    conv: Convention,
    r: f64,
}

impl Centres<'_> {
    #[inline]
    fn at(&self, i: usize) -> DVec3 {
        centre(&self.pts[i], self.conv, self.r)
    }
}

/// What the convention check found: the median |distance − R| under each reading.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ConventionCheck {
    pub chosen: Convention,
    pub median_gap_tip: f64,
    pub median_gap_centre: f64,
    pub sampled: usize,
}

/// Decides tip or centre from the data: with the right reading the centre-to-mesh
/// distance is about R at nearly every point (formats.md §2.4).
pub fn detect_convention(s: &Surface, points: &[PathPoint], r: f64) -> ConventionCheck {
    let step = (points.len() / 400).max(1);
    let sample: Vec<&PathPoint> = points.iter().step_by(step).collect();
    let median = |conv: Convention| {
        let mut g: Vec<f64> = sample
            .par_iter()
            .map(|p| {
                let c = centre(p, conv, r);
                s.bvh
                    .closest(s.mesh, c, 4.0 * r)
                    .map(|h| (h.distance - r).abs())
                    .unwrap_or(f64::INFINITY)
            })
            .collect();
        g.sort_by(f64::total_cmp);
        g.get(g.len() / 2).copied().unwrap_or(f64::INFINITY)
    };
    let (tip, cen) = (median(Convention::Tip), median(Convention::Centre));
    ConventionCheck {
        chosen: if cen < tip {
            Convention::Centre
        } else {
            Convention::Tip
        },
        median_gap_tip: tip,
        median_gap_centre: cen,
        sampled: sample.len(),
    }
}

/// Triangle in-centres in a k-d tree, for the paper's nearest-in-centre mapping.
struct Incentres {
    tree: kiddo::ImmutableKdTree<f64, 3>,
}

impl Incentres {
    fn new(mesh: &TriMesh) -> Incentres {
        let pts: Vec<[f64; 3]> = (0..mesh.len())
            .into_par_iter()
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
                ((a * la + b * lb + c * lc) / (la + lb + lc)).to_array()
            })
            .collect();
        Incentres {
            tree: kiddo::ImmutableKdTree::new_from_slice(&pts),
        }
    }

    /// The facet whose in-centre is nearest to `p` (none on an empty mesh).
    fn nearest(&self, p: DVec3) -> Option<u32> {
        (self.tree.size() > 0).then(|| {
            self.tree
                .nearest_one::<kiddo::SquaredEuclidean>(&p.to_array())
                .item as u32
        })
    }
}

fn key(p: DVec3, cell: f64) -> (i64, i64, i64) {
    (
        (p.x / cell).floor() as i64,
        (p.y / cell).floor() as i64,
        (p.z / cell).floor() as i64,
    )
}

/// Analyses every point of a path. Points are in cutting order; neighbouring passes
/// count as machined when they come earlier in that order.
/// Shortest run of consecutive points a thread analyses (each run's first
/// contact search starts without a hint).
const RUN_MIN: usize = 1024;
/// Longest run: short enough that no thread is left with a long run at the end
/// while the others wait.
const RUN_MAX: usize = 8192;

/// Contact point, unit normal, gap (centre-to-mesh distance − R), no contact.
pub type Located = (DVec3, DVec3, f64, bool);

/// Ball centres and contacts of every point: (centre, contact, unit normal, gap,
/// no contact). The first half of [`analyse`], reused by passes that evaluate the
/// working diameter for other orders of the same points.
pub fn locate(s: &Surface, points: &[PathPoint], p: &Params) -> (Vec<DVec3>, Vec<Located>) {
    let centres: Vec<DVec3> = points
        .par_iter()
        .map(|q| centre(q, p.convention, p.d / 2.0))
        .collect();
    let loc = Locator::new(s, p);
    // Consecutive points in parallel runs, each point starting its search from
    // the previous point's contact triangle.
    let contacts = (0..points.len())
        .into_par_iter()
        .with_min_len(RUN_MIN)
        .with_max_len(RUN_MAX)
        .map_init(
            || None,
            |hint, i| loc.contact(&centres[i], &points[i], hint),
        )
        .collect();
    (centres, contacts)
}

/// Finds the contact point and normal of one ball centre.
struct Locator<'a> {
    s: &'a Surface<'a>,
    p: &'a Params,
    incentres: Option<Incentres>,
}

impl<'a> Locator<'a> {
    fn new(s: &'a Surface<'a>, p: &'a Params) -> Locator<'a> {
        Locator {
            s,
            p,
            incentres: p.nearest_incentre.then(|| Incentres::new(s.mesh)),
        }
    }

    /// The contact of centre `c` of point `q`; `hint` is the previous point's
    /// contact triangle and becomes this one's.
    #[inline]
    fn contact(&self, c: &DVec3, q: &PathPoint, hint: &mut Option<u32>) -> Located {
        let (s, p, r) = (self.s, self.p, self.p.d / 2.0);
        if let Some(ic) = &self.incentres {
            // The paper: the facet whose in-centre is nearest to the tool position.
            let t = ic.nearest(q.cl).unwrap_or(0) as usize;
            let n = orient_up(s.mesh.facet_normal(t), q.axis);
            let [a, b, cc] = s.mesh.corners(t);
            let (pt, _) = millplan_geom::bvh::closest_on_triangle(*c, a, b, cc);
            return (pt, n, (pt - *c).length() - r, false);
        }
        match s.bvh.closest_near(s.mesh, *c, 3.0 * r + p.ap + 1.0, *hint) {
            Some(h) => {
                *hint = Some(h.triangle);
                let n = match p.normals {
                    NormalMode::Facet => s.mesh.facet_normal(h.triangle as usize),
                    NormalMode::Ball => (*c - h.point).normalize_or_zero(),
                    NormalMode::Smooth => {
                        let t = s.mesh.triangles[h.triangle as usize];
                        let vn = &s.vertex_normals;
                        (vn[t[0] as usize] * h.bary[0]
                            + vn[t[1] as usize] * h.bary[1]
                            + vn[t[2] as usize] * h.bary[2])
                            .normalize_or_zero()
                    }
                };
                let n = if n == DVec3::ZERO {
                    (*c - h.point).normalize_or_zero()
                } else {
                    n
                };
                (h.point, orient_up(n, q.axis), h.distance - r, false)
            }
            None => (*c - q.axis * r, q.axis, f64::INFINITY, true),
        }
    }
}

pub fn analyse(s: &Surface, points: &[PathPoint], p: &Params) -> Vec<PointResult> {
    analyse_with(s, points, p, |r| r)
}

/// [`analyse`], each result passed through `wrap` as it is made (so a caller
/// building larger rows fills them in one pass, without a second vector).
pub fn analyse_with<T: Send>(
    s: &Surface,
    points: &[PathPoint],
    p: &Params,
    wrap: impl Fn(PointResult) -> T + Sync,
) -> Vec<T> {
    // Computed where asked rather than stored: a million points' centres
    // are 24 MB more at the analysis's peak, for a few additions each.
    let centres = Centres {
        pts: points,
        conv: p.convention,
        r: p.d / 2.0,
    };
    let search = stepover_search_radius(|i| centres.at(i), points, p.neighbour_search);
    let grid = NeighbourGrid::new(centres, search);
    let loc = Locator::new(s, p);
    // The turn between unit directions exceeds the corner angle when the
    // cosine falls below its cosine.
    let cos_corner = p.corner_angle.cos();
    // Contact and working diameter in one pass over consecutive runs of points
    // (each contact search starts from the previous point's triangle).
    (0..points.len())
        .into_par_iter()
        .with_min_len(RUN_MIN)
        .with_max_len(RUN_MAX)
        .map_init(
            || None,
            |hint, i| {
                let (contact, n, gap, no_contact) = loc.contact(&centres.at(i), &points[i], hint);
                let k = points[i].axis;
                let inclination = n.dot(k).clamp(-1.0, 1.0).acos();
                let (t_in, t_out) = feed_directions(centres, i);
                let project = |t: DVec3| (t - n * t.dot(n)).normalize_or_zero();
                let (t_in, t_out) = (project(t_in), project(t_out));
                let central = (t_in + t_out).normalize_or_zero();
                let t = if central == DVec3::ZERO {
                    if t_out != DVec3::ZERO {
                        t_out
                    } else {
                        t_in
                    }
                } else {
                    central
                };
                let corner =
                    t_in != DVec3::ZERO && t_out != DVec3::ZERO && t_in.dot(t_out) < cos_corner;
                let eval = |t: DVec3| {
                    let (af, side, neighbour) = local_case(&grid, centres, i, n, k, t, search);
                    let c = Case {
                        d: p.d,
                        ap: p.ap,
                        neighbour,
                        alpha: inclination,
                        af,
                        side,
                    };
                    (wd::working_diameter(&c), af, side, neighbour)
                };
                let mut best = eval(t);
                if corner {
                    for dir in [t_in, t_out] {
                        let e = eval(dir);
                        if e.0 > best.0 {
                            best = e;
                        }
                    }
                }
                let (dw, feed_angle, side, neighbour) = best;
                wrap(PointResult {
                    contact,
                    normal: n,
                    gap,
                    no_contact,
                    inclination,
                    feed_angle,
                    side,
                    neighbour,
                    corner,
                    dw,
                })
            },
        )
        .collect()
}

/// The sideways search radius: 1.6 × the median distance from a sample of points
/// to the nearest point of the passes cut just before and after theirs (the
/// stepover the CAM system used), at most `max`. Keeps the neighbour search cheap
/// on fine rasters.
pub fn stepover_search_radius(c: impl Fn(usize) -> DVec3, pts: &[PathPoint], max: f64) -> f64 {
    if pts.len() < 3 {
        return max;
    }
    // Index ranges of the passes (points of a pass are consecutive).
    let mut ranges: Vec<(usize, usize)> = Vec::new();
    let mut start = 0;
    for i in 1..=pts.len() {
        if i == pts.len() || pts[i].pass != pts[start].pass {
            ranges.push((start, i));
            start = i;
        }
    }
    let pass_of = |i: usize| ranges.partition_point(|r| r.1 <= i);
    // The nearest point of the passes cut just before and after: the stepover.
    let step = (pts.len() / 300).max(1);
    let mut d: Vec<f64> = (0..pts.len())
        .step_by(step)
        .filter_map(|i| {
            let k = pass_of(i);
            let mut best = f64::INFINITY;
            // Skip link moves between passes (passes of one or two points).
            for dir in [-1i64, 1] {
                let mut kk = k as i64 + dir;
                for _ in 0..4 {
                    let Some(&(a, b)) = usize::try_from(kk).ok().and_then(|x| ranges.get(x)) else {
                        break;
                    };
                    if b - a >= 3 {
                        for j in a..b {
                            best = best.min((c(j) - c(i)).length());
                        }
                        break;
                    }
                    kk += dir;
                }
            }
            best.is_finite().then_some(best)
        })
        .collect();
    if d.is_empty() {
        // A single pass: there is no neighbour to find.
        return 1e-3;
    }
    d.sort_by(f64::total_cmp);
    (1.6 * d[d.len() / 2]).clamp(1e-3, max)
}

fn orient_up(n: DVec3, k: DVec3) -> DVec3 {
    if n.dot(k) < 0.0 {
        -n
    } else {
        n
    }
}

/// Incoming and outgoing directions at point i, skipping zero-length steps and
/// staying inside the pass.
fn feed_directions(c: Centres<'_>, i: usize) -> (DVec3, DVec3) {
    let pts = c.pts;
    let pass = pts[i].pass;
    let mut t_in = DVec3::ZERO;
    let mut j = i;
    while j > 0 && pts[j - 1].pass == pass {
        j -= 1;
        let v = c.at(i) - c.at(j);
        if v.length() > 1e-6 {
            t_in = v.normalize();
            break;
        }
    }
    let mut t_out = DVec3::ZERO;
    let mut j = i;
    while j + 1 < pts.len() && pts[j + 1].pass == pass {
        j += 1;
        let v = c.at(j) - c.at(i);
        if v.length() > 1e-6 {
            t_out = v.normalize();
            break;
        }
    }
    (t_in, t_out)
}

/// Feed angle, uncut side and neighbour for feed direction t at point i.
#[allow(clippy::too_many_arguments)]
fn local_case(
    grid: &NeighbourGrid<'_>,
    c: Centres<'_>,
    i: usize,
    n: DVec3,
    k: DVec3,
    t: DVec3,
    search: f64,
) -> (f64, Side, Neighbour) {
    let at = c.at(i);
    let mut side = SideFinder::new(at, n, t, search);
    let pass = c.pts[i].pass;
    // Only points machined before this one, of other passes, count.
    grid.for_each_near(at, i as u32, |centre, e| {
        if e.pass != pass {
            side.machined(centre);
        }
    });
    (feed_angle(n, k, t), side.result().0, side.result().1)
}

/// Feed direction t relative to uphill at a point with normal n, tool axis k
/// (radians; 0 when the surface is flat or the point does not move).
pub fn feed_angle(n: DVec3, k: DVec3, t: DVec3) -> f64 {
    let up = k - n * n.dot(k);
    if up.length() < 1e-9 || t == DVec3::ZERO {
        0.0
    } else {
        let u = up.normalize();
        t.dot(n.cross(u)).atan2(t.dot(u))
    }
}

/// Finds the uncut side and the stepover at a ball centre from the machined
/// centres around it: a machined centre within `search` of it (in space, so
/// what counts never depends on how a search grid happens to fall) and beside
/// the feed direction in the tangent plane (more sideways than along) marks
/// that side as cut.
pub struct SideFinder {
    at: DVec3,
    n: DVec3,
    t: DVec3,
    left: DVec3,
    search: f64,
    l_best: f64,
    r_best: f64,
}

impl SideFinder {
    pub fn new(at: DVec3, n: DVec3, t: DVec3, search: f64) -> SideFinder {
        SideFinder {
            at,
            n,
            t,
            left: n.cross(t),
            search,
            l_best: f64::INFINITY,
            r_best: f64::INFINITY,
        }
    }

    /// A machined ball centre nearby.
    #[inline]
    pub fn machined(&mut self, c: DVec3) {
        if self.t == DVec3::ZERO {
            return;
        }
        let v = c - self.at;
        if v.length_squared() > self.search * self.search {
            return;
        }
        let v = v - self.n * v.dot(self.n);
        let lat = v.dot(self.left);
        let along = v.dot(self.t);
        if along.abs() > lat.abs().max(1e-9) {
            return;
        }
        if lat > 1e-6 {
            self.l_best = self.l_best.min(lat);
        } else if lat < -1e-6 {
            self.r_best = self.r_best.min(-lat);
        }
    }

    /// Uncut side and neighbour.
    pub fn result(&self) -> (Side, Neighbour) {
        match (self.l_best.is_finite(), self.r_best.is_finite()) {
            (false, false) => (Side::Left, Neighbour::None),
            // Machined on the left: the uncut material is on the right.
            (true, false) => (Side::Right, Neighbour::One(self.l_best)),
            (false, true) => (Side::Left, Neighbour::One(self.r_best)),
            (true, true) => (Side::Left, Neighbour::Both(self.l_best.min(self.r_best))),
        }
    }
}

/// Uniform grid over ball centres for the sideways neighbour search.
struct NeighbourGrid<'a> {
    /// The ball centres, by point index.
    c: Centres<'a>,
    /// Cell edge: twice the search radius, so the 2×2×2 cells on the point's side
    /// of its own cell cover the whole search sphere.
    cell: f64,
    /// The lowest cell; keys count cells from it.
    origin: (i64, i64, i64),
    /// Whether cells might share a key (a grid over 2^21 cells along an axis);
    /// candidates are then checked to be in the cells asked for.
    aliased: bool,
    /// The points sorted by cell and, within a cell, by index, each with its
    /// pass (the centre is read from `c`: a third of the memory);
    /// `cells` maps a cell's key to its run.
    entries: Vec<GridEntry>,
    cells: FxHashMap<u64, (u32, u32)>,
}

#[derive(Clone, Copy, Debug)]
struct GridEntry {
    i: u32,
    pass: u32,
}

const GRID_BITS: u32 = 21;

impl<'a> NeighbourGrid<'a> {
    fn new(c: Centres<'a>, radius: f64) -> NeighbourGrid<'a> {
        let pts = c.pts;
        let cell = 2.0 * radius.max(1e-3);
        let empty = || {
            (
                (i64::MAX, i64::MAX, i64::MAX),
                (i64::MIN, i64::MIN, i64::MIN),
            )
        };
        type Span = ((i64, i64, i64), (i64, i64, i64));
        let join = |(lo, hi): Span, (l, h): Span| {
            (
                (lo.0.min(l.0), lo.1.min(l.1), lo.2.min(l.2)),
                (hi.0.max(h.0), hi.1.max(h.1), hi.2.max(h.2)),
            )
        };
        let (lo, hi) = (0..pts.len())
            .into_par_iter()
            .map(|i| {
                let k = key(c.at(i), cell);
                (k, k)
            })
            .reduce(empty, join);
        let span = (hi.0.saturating_sub(lo.0))
            .max(hi.1.saturating_sub(lo.1))
            .max(hi.2.saturating_sub(lo.2));
        let mut grid = NeighbourGrid {
            c,
            cell,
            origin: lo,
            aliased: span >= (1 << GRID_BITS) - 2,
            entries: Vec::new(),
            cells: FxHashMap::default(),
        };
        let mut keyed: Vec<(u64, u32)> = (0..pts.len())
            .into_par_iter()
            .map(|i| (grid.packed(key(c.at(i), cell)), i as u32))
            .collect();
        keyed.par_sort_unstable();
        // Where each cell's run starts, found in parallel; then the map.
        let starts: Vec<u32> = (0..keyed.len())
            .into_par_iter()
            .filter(|&i| i == 0 || keyed[i].0 != keyed[i - 1].0)
            .map(|i| i as u32)
            .collect();
        grid.cells.reserve(starts.len());
        for (k, &i) in starts.iter().enumerate() {
            let end = starts.get(k + 1).map_or(keyed.len(), |&e| e as usize);
            grid.cells
                .insert(keyed[i as usize].0, (i, (end - i as usize) as u32));
        }
        grid.entries = keyed
            .par_iter()
            .map(|&(_, i)| GridEntry {
                i,
                pass: pts[i as usize].pass,
            })
            .collect();
        grid
    }

    #[inline]
    fn packed(&self, k: (i64, i64, i64)) -> u64 {
        let m = (1u64 << GRID_BITS) - 1;
        let f = |v: i64, o: i64| (v.wrapping_sub(o) as u64) & m;
        f(k.0, self.origin.0) << (2 * GRID_BITS)
            | f(k.1, self.origin.1) << GRID_BITS
            | f(k.2, self.origin.2)
    }

    /// Calls `f` with the centre and entry of every point before index `before`
    /// within the search radius of `p` (and some more).
    fn for_each_near(&self, p: DVec3, before: u32, mut f: impl FnMut(DVec3, &GridEntry)) {
        let k = key(p, self.cell);
        let side = |v: f64, k: i64| {
            if v / self.cell - k as f64 >= 0.5 {
                1
            } else {
                -1
            }
        };
        let (sx, sy, sz) = (side(p.x, k.0), side(p.y, k.1), side(p.z, k.2));
        for dx in [0, sx] {
            for dy in [0, sy] {
                for dz in [0, sz] {
                    let want = (k.0 + dx, k.1 + dy, k.2 + dz);
                    if let Some(&(start, len)) = self.cells.get(&self.packed(want)) {
                        // A cell's points are in path order: stop at the first
                        // one not before.
                        for e in &self.entries[start as usize..(start + len) as usize] {
                            if e.i >= before {
                                break;
                            }
                            let c = self.c.at(e.i as usize);
                            if !self.aliased || key(c, self.cell) == want {
                                f(c, e);
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_geom::analytic::{tessellate, DemoSurface};

    #[test]
    fn nearest_incentre_agrees_with_brute_force() {
        let m = tessellate(&DemoSurface::default(), 2.0);
        let ic = Incentres::new(&m);
        let incentre = |t: usize| {
            let [a, b, c] = m.corners(t);
            let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
            (a * la + b * lb + c * lc) / (la + lb + lc)
        };
        let mut seed = 11u64;
        for _ in 0..300 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let f = |k: u32| ((seed >> k) & 0xffff) as f64 / 65535.0;
            let p = DVec3::new(
                -20.0 + 100.0 * f(0),
                -20.0 + 100.0 * f(16),
                -10.0 + 40.0 * f(32),
            );
            let want = (0..m.len())
                .map(|t| (incentre(t) - p).length_squared())
                .fold(f64::INFINITY, f64::min);
            let got = ic.nearest(p).expect("a facet") as usize;
            assert!((incentre(got) - p).length_squared() <= want * (1.0 + 1e-12));
        }
        assert_eq!(
            Incentres::new(&TriMesh::default()).nearest(DVec3::ZERO),
            None
        );
    }
}
