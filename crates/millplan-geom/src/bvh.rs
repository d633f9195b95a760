//! A bounding-volume hierarchy over a [`TriMesh`] for exact closest-point queries,
//! and the per-triangle geometry the queries return.

use crate::{Aabb, TriMesh};
use glam::{DVec3, Vec3A, Vec4};
use rayon::prelude::*;
use std::sync::OnceLock;

const LEAF: usize = 8;

#[derive(Clone, Copy, Debug)]
struct Node {
    bbox: Aabb,
    /// Leaf: first index into `order`; inner: index of the left child.
    first: u32,
    /// Inner: index of the right child.
    right: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
    /// The positions in `order` of the triangles below (the collapse asks
    /// for them at every node).
    span: [u32; 2],
}

impl Node {
    const EMPTY: Node = Node {
        bbox: Aabb::EMPTY,
        first: 0,
        right: 0,
        count: 0,
        span: [0; 2],
    };
}

/// A node of the closest-point tree: up to four children side by side in single
/// precision, so one SIMD step bounds the distance to all four. Each child is an
/// oriented box: for patches of up to `OBB_MAX` triangles its first axis is
/// their mean normal, so the box is thin for a nearly flat patch and bounds the
/// distance far better than an axis-aligned box when a large ball hovers over
/// a finely tessellated slope; larger children keep their axis-aligned box.
/// Coordinates are relative to the node's own `centre`, so single-precision
/// rounding stays at the scale of the node. Leaves are children too (`count` >
/// 0): their triangles are tested exactly.
#[derive(Clone, Copy, Debug)]
struct NearNode {
    centre: DVec3,
    /// Bounds |x − centre| over the node's children (the scale of rounding).
    scale: f32,
    /// `axes[k][c]`: component c of axis k, one lane per child.
    axes: [[Vec4; 3]; 3],
    lo: [Vec4; 3],
    hi: [Vec4; 3],
    /// Per child: a leaf's first position in `order`, or an inner node's index.
    child: [u32; 4],
    /// Per child: a leaf's triangle count (> 0), or 0 for an inner node.
    count: [u32; 4],
    /// Bit k set when child k exists.
    valid: u32,
}

/// The triangles' corners in tree order. In single precision when every
/// vertex is a single-precision number, as in binary STL: half the memory of
/// the tree's largest array, and every value read back exactly.
#[derive(Clone, Debug)]
enum Tris {
    F32(Vec<[[f32; 3]; 3]>),
    F64(Vec<[DVec3; 3]>),
}

impl Tris {
    fn new(mesh: &TriMesh, order: &[u32]) -> Tris {
        let exact = |v: &DVec3| v.to_array().iter().all(|&x| (x as f32) as f64 == x);
        if mesh.vertices.par_iter().all(exact) {
            Tris::F32(
                order
                    .par_iter()
                    .map(|&t| mesh.corners(t as usize).map(|c| c.as_vec3().to_array()))
                    .collect(),
            )
        } else {
            Tris::F64(
                order
                    .par_iter()
                    .map(|&t| mesh.corners(t as usize))
                    .collect(),
            )
        }
    }

    /// The least and greatest of `axes`·(x − `centre`) over the corners x of
    /// the triangles at positions `range`. In single precision, four lanes at
    /// a time: relative to `centre` rounded to f32 (the difference of two f32
    /// numbers, rounded once), with the projection of that rounding added
    /// back in f64. The rounding, a few units in the last place of the
    /// distance from the centre, is within the padding the boxes get.
    fn extents(
        &self,
        range: std::ops::Range<usize>,
        centre: DVec3,
        axes: [glam::Vec3; 3],
    ) -> ([f64; 3], [f64; 3]) {
        // Columns such that m · x = (axes[0]·x, axes[1]·x, axes[2]·x).
        let m = glam::Mat3A::from_cols(axes[0].into(), axes[1].into(), axes[2].into()).transpose();
        let c32 = centre.as_vec3();
        let mut lo = Vec3A::splat(f32::INFINITY);
        let mut hi = Vec3A::splat(f32::NEG_INFINITY);
        match self {
            Tris::F32(t) => {
                let c = Vec3A::from(c32);
                for tri in &t[range] {
                    for p in tri {
                        let y = m * (Vec3A::from_array(*p) - c);
                        lo = lo.min(y);
                        hi = hi.max(y);
                    }
                }
            }
            Tris::F64(t) => {
                let c = c32.as_dvec3();
                for tri in &t[range] {
                    for p in tri {
                        let y = m * Vec3A::from((*p - c).as_vec3());
                        lo = lo.min(y);
                        hi = hi.max(y);
                    }
                }
            }
        }
        let shift = axes.map(|a| a.as_dvec3().dot(c32.as_dvec3() - centre));
        (
            [0, 1, 2].map(|k| lo[k] as f64 + shift[k]),
            [0, 1, 2].map(|k| hi[k] as f64 + shift[k]),
        )
    }

    /// The corners of the triangle at position `k` of the order.
    #[inline(always)]
    fn get(&self, k: usize) -> [DVec3; 3] {
        match self {
            Tris::F32(t) => t[k].map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
            Tris::F64(t) => t[k],
        }
    }
}

/// Closest point of a mesh to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    pub point: DVec3,
    pub distance: f64,
    pub triangle: u32,
    /// Barycentric coordinates of `point` in its triangle.
    pub bary: [f64; 3],
}

/// A BVH over the triangles of one mesh, built by median splits on the longest
/// axis of the centroid bounds (leaves of up to eight triangles), with boxes
/// merged from the leaves up. Closest-point and capsule queries walk a
/// four-wide tree of oriented boxes collapsed from it (the binary tree is
/// then dropped); rays a four-wide tree of axis-aligned boxes of the same
/// shape, built on first use.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// The box of the whole mesh.
    bounds: Aabb,
    order: Vec<u32>,
    /// Triangle corners in `order`, contiguous: the queries read them leaf by leaf.
    tris: Tris,
    /// Per triangle in `order`, what the capsule query's cheap tests read,
    /// computed once on the first capsule query.
    shapes: OnceLock<Vec<TriShape>>,
    /// The closest-point tree, root first.
    near: Vec<NearNode>,
    wide: OnceLock<Vec<WideNode>>,
}

/// A node of the ray tree: the boxes of up to four children (x, y and z of
/// `min` and `max`, one lane per child), widened so that each still holds
/// everything the double-precision box holds.
#[derive(Clone, Copy, Debug)]
struct WideNode {
    min: [Vec4; 3],
    max: [Vec4; 3],
    /// Per child: a leaf's first position in `order`, or an inner node's index.
    child: [u32; 4],
    /// Per child: a leaf's triangle count (> 0), or 0 for an inner node.
    count: [u32; 4],
    /// Bit k set when child k exists.
    valid: u32,
}

impl WideNode {
    const EMPTY: WideNode = WideNode {
        min: [Vec4::ZERO; 3],
        max: [Vec4::ZERO; 3],
        child: [0; 4],
        count: [0; 4],
        valid: 0,
    };

    /// Puts the box `b` in `lane`: a leaf of `count` triangles from position
    /// `child` of `order`, or (`count` = 0) the wide node `child`.
    fn set(&mut self, lane: usize, b: &Aabb, pad: f64, child: u32, count: u32) {
        let (lo, hi) = ((b.min - pad).as_vec3(), (b.max + pad).as_vec3());
        for axis in 0..3 {
            self.min[axis][lane] = lo[axis];
            self.max[axis][lane] = hi[axis];
        }
        (self.child[lane], self.count[lane]) = (child, count);
        self.valid |= 1 << lane;
    }

    /// The ray tree below closest-point node `at` (the same four-wide shape),
    /// appended to `out`: its index and the box of its triangles. A leaf of
    /// several triangles gets a wide node of its own with a box per triangle
    /// (per pair above four): one SIMD box test then spares most exact
    /// triangle tests.
    fn from_near(
        near: &[NearNode],
        tris: &Tris,
        at: usize,
        pad: f64,
        out: &mut Vec<WideNode>,
    ) -> (u32, Aabb) {
        let me = out.len();
        out.push(WideNode::EMPTY);
        let node = &near[at];
        let mut all = Aabb::EMPTY;
        for lane in (0..4).filter(|l| node.valid & (1 << l) != 0) {
            let (child, count) = (node.child[lane], node.count[lane] as usize);
            let (child, b, count) = if count == 0 {
                let (w, b) = Self::from_near(near, tris, child as usize, pad, out);
                (w, b, 0)
            } else if count == 1 {
                (
                    child,
                    Self::bounds(tris, child as usize..child as usize + 1),
                    1,
                )
            } else {
                let (w, b) = Self::leaf(tris, child as usize, count, pad, out);
                (w, b, 0)
            };
            out[me].set(lane, &b, pad, child, count as u32);
            all = all.union(&b);
        }
        (me as u32, all)
    }

    /// A wide node over the `count` triangles from position `first` of the
    /// order, a box per triangle (per pair above four); its index and box.
    fn leaf(
        tris: &Tris,
        first: usize,
        count: usize,
        pad: f64,
        out: &mut Vec<WideNode>,
    ) -> (u32, Aabb) {
        let me = out.len();
        out.push(WideNode::EMPTY);
        let per = count.div_ceil(4);
        let mut all = Aabb::EMPTY;
        for (lane, start) in (first..first + count).step_by(per).enumerate() {
            let end = (start + per).min(first + count);
            let b = Self::bounds(tris, start..end);
            out[me].set(lane, &b, pad, start as u32, (end - start) as u32);
            all = all.union(&b);
        }
        (me as u32, all)
    }

    /// The box of the triangles at positions `range` of the order.
    fn bounds(tris: &Tris, range: std::ops::Range<usize>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for t in range {
            tris.get(t).iter().for_each(|&c| b.extend(c));
        }
        b
    }
}

impl Bvh {
    pub fn build(mesh: &TriMesh) -> Bvh {
        let n = mesh.len();
        let mut items: Vec<Item> = (0..n)
            .into_par_iter()
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                Item {
                    cen: (a + b + c) / 3.0,
                    tri: t as u32,
                }
            })
            .collect();
        let sizes = subtree_sizes(n);
        let mut nodes = vec![Node::EMPTY; sizes[&n]];
        if n > 0 {
            let ctx = Ctx {
                mesh,
                sizes: &sizes,
            };
            ctx.split(&mut nodes, 0, &mut items, 0, 0);
        }
        let order: Vec<u32> = items.par_iter().map(|i| i.tri).collect();
        drop(items);
        let tris = Tris::new(mesh, &order);
        let near = if n > 0 {
            NearBuild {
                nodes: &nodes,
                tris: &tris,
            }
            .tree()
        } else {
            Vec::new()
        };
        Bvh {
            bounds: nodes[0].bbox,
            order,
            tris,
            near,
            shapes: OnceLock::new(),
            wide: OnceLock::new(),
        }
    }

    /// The ray tree, built on the first ray query (closest-point and capsule
    /// work never needs it).
    fn wide(&self) -> &[WideNode] {
        self.wide.get_or_init(|| {
            // The f32 boxes are widened by 1e-5 of the part's size (far more
            // than the single-precision rounding of coordinates of that size).
            let pad = 1e-5 * self.bounds.diagonal().max(1e-9);
            // A node per closest-point node, and one per leaf of several
            // triangles (leaves hold four to eight).
            let mut wide = Vec::with_capacity(self.near.len() + self.order.len() / 4 + 1);
            if !self.order.is_empty() {
                WideNode::from_near(&self.near, &self.tris, 0, pad, &mut wide);
            }
            wide
        })
    }

    /// The triangles' [`TriShape`]s in tree order, computed on first use.
    fn shapes(&self) -> &[TriShape] {
        self.shapes.get_or_init(|| {
            (0..self.order.len())
                .into_par_iter()
                .map(|k| TriShape::new(&self.tris.get(k)))
                .collect()
        })
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The closest point of the mesh to `p` within `max_dist`, if any.
    pub fn closest(&self, mesh: &TriMesh, p: DVec3, max_dist: f64) -> Option<Closest> {
        self.closest_near(mesh, p, max_dist, None)
    }

    /// The closest points of the mesh to many points within `max_dist`, in
    /// parallel runs of consecutive points, each point starting from the
    /// previous one's triangle (points along a path lie near each other; the
    /// results are those of [`Bvh::closest`] either way).
    pub fn closest_many(
        &self,
        mesh: &TriMesh,
        pts: &[DVec3],
        max_dist: f64,
    ) -> Vec<Option<Closest>> {
        pts.par_iter()
            .with_min_len(256)
            .with_max_len(8192)
            .map_init(
                || None,
                |hint: &mut Option<u32>, p| {
                    let c = self.closest_near(mesh, *p, max_dist, *hint);
                    if let Some(c) = &c {
                        *hint = Some(c.triangle);
                    }
                    c
                },
            )
            .collect()
    }

    /// As [`Bvh::closest`], starting from the distance to triangle `hint` (for
    /// example the previous point's contact along a path): a tight first bound
    /// prunes almost the whole tree. The result is the same with or without it.
    pub fn closest_near(
        &self,
        mesh: &TriMesh,
        p: DVec3,
        max_dist: f64,
        hint: Option<u32>,
    ) -> Option<Closest> {
        if self.order.is_empty() {
            return None;
        }
        let mut best: Option<Closest> = None;
        let mut best_d2 = max_dist * max_dist;
        if let Some(t) = hint.filter(|t| (*t as usize) < mesh.len()) {
            let [a, b, c] = mesh.corners(t as usize);
            let (q, bary) = closest_on_triangle(p, a, b, c);
            let d2 = (q - p).length_squared();
            if d2 <= best_d2 {
                best_d2 = d2;
                best = Some(Closest {
                    point: q,
                    distance: d2.sqrt(),
                    triangle: t,
                    bary,
                });
            }
        }
        // Each entry keeps the lower bound computed when it was pushed, so a node's
        // bound is evaluated once.
        let above = |d2: f64| (d2 * (1.0 + 1e-6)) as f32;
        let mut best32 = above(best_d2);
        // Each entry keeps the lower bound computed when it was pushed.
        let mut stack: [(u32, f32); 128] = [(0, 0.0); 128];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (at, lower) = stack[sp];
            if lower > best32 {
                continue;
            }
            let node = &self.near[at as usize];
            let lower = node.lower_bounds(p);
            let mask = lower.cmple(Vec4::splat(best32)).bitmask() & node.valid;
            let (lanes, m) = nearest_first(lower, mask);
            let lower = lower.to_array();
            // Leaves at once, nearest first (each may lower the bound) ...
            for &l in &lanes[..m] {
                let count = node.count[l] as usize;
                if count == 0 || lower[l] > best32 {
                    continue;
                }
                let start = node.child[l] as usize;
                for k in start..start + count {
                    let [a, b, c] = self.tris.get(k);
                    // Cheap bound first: the distance to the triangle's plane.
                    let nrm = (b - a).cross(c - a);
                    let h = nrm.dot(p - a);
                    if h * h > best_d2 * nrm.length_squared() {
                        continue;
                    }
                    let (pt, bary) = closest_on_triangle(p, a, b, c);
                    let d2 = (pt - p).length_squared();
                    if d2 <= best_d2 {
                        best_d2 = d2;
                        best32 = above(d2);
                        best = Some(Closest {
                            point: pt,
                            distance: d2.sqrt(),
                            triangle: self.order[k],
                            bary,
                        });
                    }
                }
            }
            // ... inner children on the stack, the nearest on top.
            for &l in lanes[..m].iter().rev() {
                if node.count[l] == 0 && lower[l] <= best32 && sp < stack.len() {
                    stack[sp] = (node.child[l], lower[l]);
                    sp += 1;
                }
            }
        }
        best
    }
}

/// The lanes set in `mask`, ordered by their `lower` bound, least first,
/// and how many there are.
#[inline(always)]
fn nearest_first(lower: Vec4, mut mask: u32) -> ([usize; 4], usize) {
    let lower = lower.to_array();
    let (mut lanes, mut m) = ([0usize; 4], 0);
    while mask != 0 {
        let l = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let mut j = m;
        while j > 0 && lower[lanes[j - 1]] > lower[l] {
            lanes[j] = lanes[j - 1];
            j -= 1;
        }
        lanes[j] = l;
        m += 1;
    }
    (lanes, m)
}

/// What the capsule query's cheap tests read of one triangle pqr: its
/// plane's normal m = (q − p) × (r − p) (not normalised) with |m|, how far
/// rounding may have turned m (`noise`, per unit of distance from p), and
/// its centroid with the greatest distance of a corner from it. Computed
/// once, on the first capsule query.
#[derive(Clone, Copy, Debug)]
struct TriShape {
    m: DVec3,
    m_len: f64,
    /// Bounds, with room to spare, how far the computed m·x may be from
    /// the true one, per unit of |x|: each component of m is rounded by a
    /// few ε·|q − p|·|r − p|, which on a sliver or a needle is all there
    /// is of m.
    noise: f64,
    centre: DVec3,
    rho: f64,
}

impl TriShape {
    fn new([p, q, r]: &[DVec3; 3]) -> TriShape {
        let (e1, e2) = (*q - *p, *r - *p);
        let m = e1.cross(e2);
        let c = (*p + *q + *r) * (1.0 / 3.0);
        let rho2 = (*p - c)
            .length_squared()
            .max((*q - c).length_squared())
            .max((*r - c).length_squared());
        TriShape {
            m,
            m_len: m.length(),
            noise: 16.0 * f64::EPSILON * e1.length() * e2.length(),
            centre: c,
            rho: rho2.sqrt(),
        }
    }
}

/// A triangle a capsule query hit, to try first in the next one
/// ([`Bvh::capsule_hits_above_from`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapsuleHit(usize);

impl Bvh {
    /// Whether the ray `origin + s·dir`, `0 < s < max_s`, hits any triangle other
    /// than `skip` (an any-hit occlusion query: it stops at the first hit).
    /// Triangles are hit from both sides; `dir` need not be unit.
    pub fn occluded(&self, origin: DVec3, dir: DVec3, max_s: f64, skip: Option<u32>) -> bool {
        self.any_near_ray(origin, dir, max_s, |k, [a, b, c]| {
            // The skipped triangle is looked up only on a hit.
            ray_triangle(origin, dir, *a, *b, *c).is_some_and(|s| s > 0.0 && s < max_s)
                && skip != Some(self.order[k])
        })
    }

    /// Whether any triangle other than `skip` comes closer than `radius` to the
    /// segment ab (a capsule-versus-mesh collision test).
    pub fn capsule_hits(&self, a: DVec3, b: DVec3, radius: f64, skip: Option<u32>) -> bool {
        self.capsule_hits_above(a, b, radius, skip, None)
    }

    /// [`capsule_hits`](Self::capsule_hits) among the triangles that reach
    /// above `above` = (n, h), n a unit vector: those lying wholly in the
    /// half-space n·x ≤ h are left out. A tool's shank capsule starting at
    /// the ball centre c, with (d, d·c) for its axis d, leaves out exactly
    /// what only the ball could touch.
    pub fn capsule_hits_above(
        &self,
        a: DVec3,
        b: DVec3,
        radius: f64,
        skip: Option<u32>,
        above: Option<(DVec3, f64)>,
    ) -> bool {
        self.capsule_hits_above_from(a, b, radius, skip, above, &mut None)
    }

    /// [`capsule_hits_above`](Self::capsule_hits_above), trying first the
    /// triangle `hint` names (a previous query's hit, as this returns it in
    /// `hint`): queries in a row that the same triangle blocks, like a tool
    /// turned through neighbouring directions, then cost one triangle test.
    /// The answer is the same whatever `hint` holds: the hinted triangle is
    /// put to the very test every other triangle gets.
    pub fn capsule_hits_above_from(
        &self,
        a: DVec3,
        b: DVec3,
        radius: f64,
        skip: Option<u32>,
        above: Option<(DVec3, f64)>,
        hint: &mut Option<CapsuleHit>,
    ) -> bool {
        if radius <= 0.0 {
            return false;
        }
        let r2 = radius * radius;
        let reaches = |t: &[DVec3; 3]| above.is_none_or(|(n, h)| t.iter().any(|v| n.dot(*v) > h));
        let (ab, ab2) = (b - a, (b - a).length_squared());
        let inv_ab2 = if ab2 > 0.0 { 1.0 / ab2 } else { 0.0 };
        let shapes = self.shapes();
        let scale = a.abs().max(b.abs()).max_element() + radius;
        // The radius with margins for the rounding of differences of
        // coordinates of this size (absolute) and of lengths (relative).
        let slack = radius * (1.0 + 1e-9) + 16.0 * f64::EPSILON * scale;
        // Cheap first: the triangle's bounding sphere about its centroid.
        let sphere_near = |sh: &TriShape| {
            let c = sh.centre;
            let s = ((c - a).dot(ab) * inv_ab2).clamp(0.0, 1.0);
            let reach = slack + sh.rho;
            (a + ab * s - c).length_squared() < reach * reach * (1.0 + 1e-9)
        };
        // Also cheap: both ends of the segment on one side of the triangle's
        // plane and at least `radius` from it keep the whole segment that far
        // from the triangle. Near a tool's contact point the surface is nearly
        // tangent to the ball, and this is what rules most of it out. The
        // margin covers the rounding of the ends' offsets from p and of the
        // normal itself, which on a sliver or needle triangle (whose normal is
        // mostly rounding) rules nothing out.
        let plane_near = |p: DVec3, sh: &TriShape| {
            let (da, db) = (a - p, b - p);
            let (sa, sb) = (da.dot(sh.m), db.dot(sh.m));
            // |x|₂ ≤ √3·|x|∞ for the offsets.
            let far = da.abs().max(db.abs()).max_element() * 1.7321;
            let lim = sh.m_len * slack + sh.noise * far;
            sa * sb <= 0.0 || sa.abs().min(sb.abs()) < lim
        };
        // When what lies wholly below the plane through a across the axis is
        // left out (a shank standing on its ball), what is left touches the
        // capsule through its side or its top, beside the axis: there the
        // distance across the axis, to the triangle seen along it, is cheaper
        // than the distance to the segment and never more, and rules out most
        // of what the tests above leave. Its margin is far above the rounding
        // of either distance, so it never decides what the exact one would not.
        let axis = (ab2 > 0.0).then(|| ab * inv_ab2.sqrt()).filter(|u| {
            above.is_some_and(|(n, h)| n.dot(*u) > 1.0 - 1e-12 && h >= n.dot(a) - 1e-9 * radius)
        });
        let beside = r2 * (1.0 + 1e-9) + 1e-13 * scale * scale;
        let apart = |[p, q, r]: &[DVec3; 3]| {
            axis.is_some_and(|u| {
                let across = |x: DVec3| {
                    let w = x - a;
                    w - u * w.dot(u)
                };
                lateral_dist2(across(*p), across(*q), across(*r)) >= beside
            })
        };
        // The test of triangle t at position k, written out at both places
        // it runs so that the traversal's copy is inlined.
        macro_rules! hits {
            ($k:expr, $t:expr) => {{
                let (k, t): (usize, &[DVec3; 3]) = ($k, $t);
                let [p, q, r] = t;
                let sh = &shapes[k];
                skip != Some(self.order[k])
                    && plane_near(*p, sh)
                    && sphere_near(sh)
                    && reaches(t)
                    && !apart(t)
                    && segment_triangle_dist2(a, b, *p, *q, *r) < r2
            }};
        }
        if let Some(CapsuleHit(k)) = *hint {
            if k < self.order.len() && hits!(k, &self.tris.get(k)) {
                return true;
            }
        }
        let mut found = None;
        let test = |k: usize, t: &[DVec3; 3]| {
            let yes = hits!(k, t);
            if yes {
                found = Some(CapsuleHit(k));
            }
            yes
        };
        // The closest-point tree's oriented boxes bound the distance far
        // tighter than axis-aligned boxes where a ball stands on a finely
        // tessellated surface or a shank leans along it; each triangle gets
        // the very same test.
        let hit = self.any_within(a, b, r2, above, test);
        if hit {
            *hint = found;
        }
        hit
    }

    /// Any-hit traversal of the closest-point tree: calls `hit(position in
    /// order, corners)` for the triangles of every leaf whose box may come
    /// within squared distance `r2` of the segment ab (the boxes' bounds never
    /// exceed the true distance, and a relative margin covers single
    /// precision) and, with `above` = (n, h), reaches above n·x = h, until
    /// `hit` says yes. The nearest children are opened first: where the
    /// answer is yes, they are the likeliest to hold a hit.
    fn any_within(
        &self,
        a: DVec3,
        b: DVec3,
        r2: f64,
        above: Option<(DVec3, f64)>,
        mut hit: impl FnMut(usize, &[DVec3; 3]) -> bool,
    ) -> bool {
        if self.order.is_empty() {
            return false;
        }
        let bound = (r2 * (1.0 + 1e-6)) as f32;
        let reach = r2.sqrt() as f32;
        // Up to three entries per level stay behind on the stack; the median
        // splits keep the depth under 42 for any mesh that fits in memory.
        let mut stack: [u32; 128] = [0; 128];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = &self.near[stack[sp] as usize];
            let lower = node.segment_lower_bounds(a, b, reach);
            let mut mask = lower.cmple(Vec4::splat(bound)).bitmask() & node.valid;
            if mask == 0 {
                continue;
            }
            if let Some((n, h)) = above {
                mask &= node.reaches_above(n, h);
            }
            let (lanes, m) = nearest_first(lower, mask);
            for &l in &lanes[..m] {
                let count = node.count[l] as usize;
                if count > 0 {
                    let start = node.child[l] as usize;
                    for k in start..start + count {
                        if hit(k, &self.tris.get(k)) {
                            return true;
                        }
                    }
                }
            }
            for &l in lanes[..m].iter().rev() {
                if node.count[l] == 0 {
                    debug_assert!(sp < stack.len(), "the tree is deeper than 42 levels");
                    if sp < stack.len() {
                        stack[sp] = node.child[l];
                        sp += 1;
                    }
                }
            }
        }
        false
    }

    /// Any-hit traversal: calls `hit(position in order, corners)` for the
    /// triangles of every leaf whose box the ray `origin + s·dir`
    /// (0 ≤ s ≤ max_s) meets, until `hit` says yes.
    fn any_near_ray(
        &self,
        origin: DVec3,
        dir: DVec3,
        max_s: f64,
        mut hit: impl FnMut(usize, &[DVec3; 3]) -> bool,
    ) -> bool {
        if self.order.is_empty() {
            return false;
        }
        // A zero component becomes a tiny one: its slab is then [-huge, huge] from
        // inside and empty from outside, with no 0·∞ = NaN on the slab faces;
        // clamped so that a zero slab width times the inverse stays 0.
        let nz = |x: f64| if x == 0.0 { 1e-300 } else { x };
        let inv = DVec3::new(nz(dir.x), nz(dir.y), nz(dir.z)).recip();
        let inv32 = Vec3A::from(inv.clamp(DVec3::splat(-1e30), DVec3::splat(1e30)).as_vec3());
        let o32 = Vec3A::from(origin.as_vec3());
        let [o, inv] = [o32, inv32].map(|v| [v.x, v.y, v.z].map(Vec4::splat));
        let far = Vec4::splat(max_s as f32);
        let wide = self.wide();
        let mut stack: [u32; 128] = [0; 128];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = &wide[stack[sp] as usize];
            // The slab test of the four child boxes at once.
            let (mut lo, mut hi) = (Vec4::ZERO, far);
            for a in 0..3 {
                let t1 = (node.min[a] - o[a]) * inv[a];
                let t2 = (node.max[a] - o[a]) * inv[a];
                lo = lo.max(t1.min(t2));
                hi = hi.min(t1.max(t2));
            }
            let mut mask = lo.cmple(hi).bitmask() & node.valid;
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let count = node.count[lane] as usize;
                if count > 0 {
                    let start = node.child[lane] as usize;
                    for k in start..start + count {
                        if hit(k, &self.tris.get(k)) {
                            return true;
                        }
                    }
                } else if sp < stack.len() {
                    stack[sp] = node.child[lane];
                    sp += 1;
                }
            }
        }
        false
    }
}

/// Squared distance from the origin to triangle pqr, whose corners lie in a
/// plane through the origin (a triangle seen along an axis, possibly edge-on):
/// the least over its three edges, or 0 when the origin lies inside it. NaN
/// never comes out as a distance the caller could trust: a degenerate input
/// gives at most the true value.
fn lateral_dist2(p: DVec3, q: DVec3, r: DVec3) -> f64 {
    // Inside: the origin on the same side of all three edges (within the
    // plane the corners span; a flat triangle spans none and is its edges).
    // Near an edge's line rounding may flip a side: within a relative 1e-9 of
    // it counts as either side, so a doubt answers 0, never too much.
    let m = (q - p).cross(r - p);
    let side = |u: DVec3, v: DVec3| {
        let s = (v - u).cross(-u).dot(m);
        let tol = 1e-9 * (v - u).length() * u.length() * m.length();
        (s >= -tol, s <= tol)
    };
    let (s1, s2, s3) = (side(p, q), side(q, r), side(r, p));
    if m.length_squared() > 0.0 && ((s1.0 && s2.0 && s3.0) || (s1.1 && s2.1 && s3.1)) {
        return 0.0;
    }
    let edge = |u: DVec3, v: DVec3| {
        let e = v - u;
        let e2 = e.length_squared();
        let t = if e2 > 0.0 {
            (-u.dot(e) / e2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (u + e * t).length_squared()
    };
    edge(p, q).min(edge(q, r)).min(edge(r, p))
}

/// Squared distance between segment ab and triangle pqr.
pub fn segment_triangle_dist2(a: DVec3, b: DVec3, p: DVec3, q: DVec3, r: DVec3) -> f64 {
    if ray_triangle(a, b - a, p, q, r).is_some_and(|s| (0.0..=1.0).contains(&s)) {
        return 0.0;
    }
    // Otherwise the minimum is at an end of the segment or on an edge.
    let ends = [a, b].map(|x| (closest_on_triangle(x, p, q, r).0 - x).length_squared());
    let edges = [(p, q), (q, r), (r, p)].map(|(u, v)| segment_segment_dist2(a, b, u, v));
    ends.into_iter().chain(edges).fold(f64::INFINITY, f64::min)
}

/// Squared distance between segments ab and cd.
pub fn segment_segment_dist2(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (u, v, w) = (b - a, d - c, a - c);
    let (aa, bb, cc, dd, ee) = (u.dot(u), u.dot(v), v.dot(v), u.dot(w), v.dot(w));
    let den = aa * cc - bb * bb;
    // Closest points of the infinite lines, then clamped (and the other re-solved).
    let mut s = if den > 1e-14 * aa * cc {
        ((bb * ee - cc * dd) / den).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = if cc > 0.0 { (bb * s + ee) / cc } else { 0.0 };
    if t < 0.0 {
        t = 0.0;
        s = if aa > 0.0 {
            (-dd / aa).clamp(0.0, 1.0)
        } else {
            0.0
        };
    } else if t > 1.0 {
        t = 1.0;
        s = if aa > 0.0 {
            ((bb - dd) / aa).clamp(0.0, 1.0)
        } else {
            0.0
        };
    }
    (w + u * s - v * t).length_squared()
}

/// Möller–Trumbore: the ray parameter s of the hit with triangle abc, if any.
#[inline]
pub fn ray_triangle(o: DVec3, d: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    // Barycentric tests scaled by |det|: the one division waits for a hit.
    let (sign, adet) = if det < 0.0 { (-1.0, -det) } else { (1.0, det) };
    let t = o - a;
    let u = t.dot(p) * sign;
    if !(0.0..=adet).contains(&u) {
        return None;
    }
    let q = t.cross(e1);
    let v = d.dot(q) * sign;
    if !(v >= 0.0 && u + v <= adet) {
        return None;
    }
    Some(e2.dot(q) / det)
}

/// A triangle as the build splits it: its centroid beside its index, so the
/// splits read and move one contiguous array (not an index into the centroids).
#[derive(Clone, Copy)]
struct Item {
    cen: DVec3,
    tri: u32,
}

/// Per-triangle data the build reads.
struct Ctx<'a> {
    mesh: &'a TriMesh,
    /// Subtree sizes by triangle count.
    sizes: &'a rustc_hash::FxHashMap<usize, usize>,
}

/// Halves at least this large are built in parallel.
const PAR_MIN: usize = 1 << 16;

/// Nodes of the binary tree over `m` triangles, for `m` and every size its
/// median splits lead to (sizes at one depth differ by at most one, so there
/// are few).
fn subtree_sizes(m: usize) -> rustc_hash::FxHashMap<usize, usize> {
    fn go(m: usize, memo: &mut rustc_hash::FxHashMap<usize, usize>) -> usize {
        if let Some(&c) = memo.get(&m) {
            return c;
        }
        let c = if m <= LEAF {
            1
        } else {
            1 + go(m / 2, memo) + go(m - m / 2, memo)
        };
        memo.insert(m, c);
        c
    }
    let mut memo = Default::default();
    go(m, &mut memo);
    memo
}

impl Ctx<'_> {
    /// The axis along which the centroids of `items` spread most.
    fn longest_axis(&self, items: &[Item]) -> usize {
        let mut cb = Aabb::EMPTY;
        for i in items {
            cb.extend(i.cen);
        }
        let size = cb.size();
        if size.x >= size.y && size.x >= size.z {
            0
        } else if size.y >= size.z {
            1
        } else {
            2
        }
    }

    /// Fills `nodes` (exactly the subtree over `items`, its root first, at
    /// global index `base`; the triangles at positions `base`.. of the final
    /// order) depth first: the left subtree follows its parent. Boxes are
    /// merged from the leaves up; large halves are built in parallel into
    /// their own parts of the one vector.
    fn split(
        &self,
        nodes: &mut [Node],
        base: usize,
        items: &mut [Item],
        offset: usize,
        depth: u32,
    ) {
        if items.len() <= LEAF {
            let mut bbox = Aabb::EMPTY;
            for t in items.iter() {
                self.mesh
                    .corners(t.tri as usize)
                    .iter()
                    .for_each(|c| bbox.extend(*c));
            }
            nodes[0] = Node {
                bbox,
                first: offset as u32,
                right: 0,
                count: items.len() as u32,
                span: [offset as u32, (offset + items.len()) as u32],
            };
            return;
        }
        let axis = self.longest_axis(items);
        let mid = items.len() / 2;
        // The same comparisons as on indices into the centroids: the
        // selection's moves, and so the order, are those it made there.
        items.select_nth_unstable_by(mid, |a, b| a.cen[axis].total_cmp(&b.cen[axis]));
        let end = offset + items.len();
        let (l, r) = items.split_at_mut(mid);
        let (me, rest) = nodes.split_at_mut(1);
        let (ln, rn) = rest.split_at_mut(self.sizes[&mid]);
        let (left, right) = (base + 1, base + 1 + ln.len());
        if mid >= PAR_MIN && depth < 8 {
            rayon::join(
                || self.split(ln, left, l, offset, depth + 1),
                || self.split(rn, right, r, offset + mid, depth + 1),
            );
        } else {
            self.split(ln, left, l, offset, depth + 1);
            self.split(rn, right, r, offset + mid, depth + 1);
        }
        me[0] = Node {
            bbox: ln[0].bbox.union(&rn[0].bbox),
            first: left as u32,
            right: right as u32,
            count: 0,
            span: [offset as u32, end as u32],
        };
    }
}

/// Children of at most this many triangles get an oriented box; larger ones
/// keep their axis-aligned box (a mean normal means little over so large a patch).
const OBB_MAX: usize = 1 << 15;

/// Collapses the binary tree into the closest-point tree.
struct NearBuild<'a> {
    nodes: &'a [Node],
    tris: &'a Tris,
}

impl NearNode {
    const EMPTY: NearNode = NearNode {
        centre: DVec3::ZERO,
        scale: 0.0,
        axes: [[Vec4::ZERO; 3]; 3],
        lo: [Vec4::ZERO; 3],
        hi: [Vec4::ZERO; 3],
        child: [0; 4],
        count: [0; 4],
        valid: 0,
    };
}

impl NearNode {
    /// Lower bounds of the squared distance from the segment ab to each
    /// child, where it may come within `reach` (elsewhere +∞). In each
    /// box's own axes: the part of the segment inside the box grown by
    /// `reach` along every axis (a slab test), then per axis the gap between
    /// that part's extent and the box's, squared and summed: at every point
    /// of the part each axis's share of the distance is at least its gap.
    /// For a = b this is the point's bound. Relative to the node's centre in
    /// single precision; `err` and a relative margin on `reach` cover the
    /// rounding, so no bound exceeds the true value.
    #[inline]
    fn segment_lower_bounds(&self, a: DVec3, b: DVec3, reach: f32) -> Vec4 {
        let (qa, qb) = (a - self.centre, b - self.centre);
        let err = Vec4::splat(
            16.0 * f32::EPSILON * (qa.abs().max(qb.abs()).max_element() as f32 + self.scale),
        );
        let pad = Vec4::splat(reach * 1.0001) + err;
        let (qa, qd) = (qa.as_vec3(), (qb - qa).as_vec3());
        let qa = [qa.x, qa.y, qa.z].map(Vec4::splat);
        let qd = [qd.x, qd.y, qd.z].map(Vec4::splat);
        let (mut x0, mut dx) = ([Vec4::ZERO; 3], [Vec4::ZERO; 3]);
        let (mut t0, mut t1) = (Vec4::ZERO, Vec4::ONE);
        for k in 0..3 {
            let ax = &self.axes[k];
            x0[k] = ax[0] * qa[0] + ax[1] * qa[1] + ax[2] * qa[2];
            dx[k] = ax[0] * qd[0] + ax[1] * qd[1] + ax[2] * qd[2];
            let (lo, hi) = (self.lo[k] - pad, self.hi[k] + pad);
            let inv = Vec4::ONE / dx[k];
            // Along an axis across the segment (a step too small to divide
            // by, which 0·∞ would turn into NaN) the slab holds all of the
            // segment or none of it.
            let flat = inv.abs().cmpeq(Vec4::INFINITY);
            let inside = x0[k].cmpge(lo) & x0[k].cmple(hi);
            let (enter, leave) = (
                Vec4::select(inside, Vec4::NEG_INFINITY, Vec4::INFINITY),
                Vec4::select(inside, Vec4::INFINITY, Vec4::NEG_INFINITY),
            );
            let (u, v) = ((lo - x0[k]) * inv, (hi - x0[k]) * inv);
            t0 = t0.max(Vec4::select(flat, enter, u.min(v)));
            t1 = t1.min(Vec4::select(flat, leave, u.max(v)));
        }
        let mut lower = Vec4::ZERO;
        for k in 0..3 {
            let (xl, xh) = (x0[k] + dx[k] * t0, x0[k] + dx[k] * t1);
            let d = ((self.lo[k] - xl.max(xh)).max(xl.min(xh) - self.hi[k]) - err).max(Vec4::ZERO);
            lower += d * d;
        }
        Vec4::select(t0.cmple(t1), lower, Vec4::INFINITY)
    }

    /// Per child (bit k for child k), whether some point of its box may lie
    /// above the plane n·x = h: a doubt within the rounding answers yes.
    #[inline]
    fn reaches_above(&self, n: DVec3, h: f64) -> u32 {
        let rel = h - n.dot(self.centre);
        let err = 16.0 * f32::EPSILON * (rel.abs() as f32 + 2.0 * self.scale);
        let n32 = n.as_vec3();
        let mut top = Vec4::ZERO;
        for k in 0..3 {
            let ax = &self.axes[k];
            let c = ax[0] * n32.x + ax[1] * n32.y + ax[2] * n32.z;
            top += (c * self.lo[k]).max(c * self.hi[k]);
        }
        top.cmpgt(Vec4::splat(rel as f32 - err)).bitmask()
    }

    /// Lower bounds of the squared distance from `p` to each child. Relative to
    /// the node's centre in single precision; `err` covers the rounding of the
    /// query point and of the projections, so no bound exceeds the true value.
    #[inline]
    fn lower_bounds(&self, p: DVec3) -> Vec4 {
        let q = p - self.centre;
        let err = Vec4::splat(16.0 * f32::EPSILON * (q.abs().max_element() as f32 + self.scale));
        let q = q.as_vec3();
        let q = [q.x, q.y, q.z].map(Vec4::splat);
        let mut lower = Vec4::ZERO;
        for k in 0..3 {
            let ax = &self.axes[k];
            let x = ax[0] * q[0] + ax[1] * q[1] + ax[2] * q[2];
            let d = ((self.lo[k] - x).max(x - self.hi[k]) - err).max(Vec4::ZERO);
            lower += d * d;
        }
        lower
    }
}

impl NearBuild<'_> {
    fn tree(&self) -> Vec<NearNode> {
        let mut big = Vec::new();
        let mut out = vec![NearNode::EMPTY; self.count(0, &mut big)];
        let counts: rustc_hash::FxHashMap<usize, usize> = big.into_iter().collect();
        self.fill(0, &mut out, 0, &counts);
        out
    }

    /// Nodes of the closest-point tree over binary node `at` (large subtrees
    /// counted in parallel). The counts of subtrees of at least `PAR_MIN` / 8
    /// triangles are noted in `big`: `fill` splits its vector by them, and
    /// counting them again would walk the tree once per parallel level.
    fn count(&self, at: usize, big: &mut Vec<(usize, usize)>) -> usize {
        let (kids, n) = self.kids(at);
        let inner = kids[..n].iter().filter(|&&k| self.nodes[k].count == 0);
        let len = self.range(at).len();
        let c = if len >= PAR_MIN {
            let parts: Vec<(usize, Vec<(usize, usize)>)> = inner
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|&k| {
                    let mut b = Vec::new();
                    (self.count(k, &mut b), b)
                })
                .collect();
            1 + parts
                .into_iter()
                .map(|(c, b)| {
                    big.extend(b);
                    c
                })
                .sum::<usize>()
        } else {
            1 + inner.map(|&k| self.count(k, big)).sum::<usize>()
        };
        if len >= PAR_MIN / 8 {
            big.push((at, c));
        }
        c
    }

    /// Fills `out` (exactly the tree over binary node `at`, its root first, at
    /// global index `base`) depth first; large subtrees in parallel, each into
    /// its own part of the one vector. Returns the sum of the triangles'
    /// area-weighted normals below `at`.
    fn fill(
        &self,
        at: usize,
        out: &mut [NearNode],
        base: usize,
        counts: &rustc_hash::FxHashMap<usize, usize>,
    ) -> DVec3 {
        if self.range(at).len() < PAR_MIN {
            return self.collapse(at, out, base, &mut 0).1;
        }
        let nodes = self.nodes;
        let (mut w, pad) = self.start(at);
        let (kids, n) = self.kids(at);
        let (me, mut rest) = out.split_at_mut(1);
        let mut next = base + 1;
        let mut jobs = Vec::new();
        let mut sums = [DVec3::ZERO; 4];
        for (lane, &k) in kids[..n].iter().enumerate() {
            if nodes[k].count > 0 {
                sums[lane] = self.leaf_sum(k);
            } else {
                let count = match counts.get(&k) {
                    Some(&c) => c,
                    None => self.count(k, &mut Vec::new()),
                };
                let (part, tail) = std::mem::take(&mut rest).split_at_mut(count);
                rest = tail;
                next += part.len();
                jobs.push((lane, k, next - part.len(), part));
            }
        }
        let inner: Vec<(usize, u32, DVec3)> = jobs
            .into_par_iter()
            .map(|(lane, k, b, part)| (lane, b as u32, self.fill(k, part, b, counts)))
            .collect();
        for (lane, child, sum) in inner {
            sums[lane] = sum;
            self.set(&mut w, lane, kids[lane], pad, sum, child, 0);
        }
        for (lane, &k) in kids[..n].iter().enumerate() {
            if nodes[k].count > 0 {
                self.set(
                    &mut w,
                    lane,
                    k,
                    pad,
                    sums[lane],
                    nodes[k].first,
                    nodes[k].count,
                );
            }
        }
        me[0] = w;
        sums.iter().sum()
    }

    /// The sum of the area-weighted normals of leaf `k`'s triangles.
    fn leaf_sum(&self, k: usize) -> DVec3 {
        self.range(k)
            .map(|t| {
                let [a, b, c] = self.tris.get(t);
                (b - a).cross(c - a)
            })
            .sum()
    }

    /// A node over binary node `at` with its centre and scale set, and the
    /// padding of its children's bounds: far more than the rounding of
    /// coordinates of this size to f32 and of the projections onto the axes.
    fn start(&self, at: usize) -> (NearNode, f64) {
        let b = &self.nodes[at].bbox;
        let w = NearNode {
            centre: b.center(),
            scale: (0.5 * b.diagonal()) as f32,
            ..NearNode::EMPTY
        };
        (
            w,
            8.0 * f32::EPSILON as f64 * (0.5 * b.diagonal()).max(1e-9),
        )
    }

    /// Up to four binary nodes below binary node `at`: two levels become one,
    /// opening the largest inner child first (none below a leaf).
    fn kids(&self, at: usize) -> ([usize; 4], usize) {
        let nodes = self.nodes;
        let mut kids = [0usize; 4];
        if nodes[at].count > 0 {
            return (kids, 0);
        }
        kids[0] = nodes[at].first as usize;
        kids[1] = nodes[at].right as usize;
        let mut n = 2;
        while n < 4 {
            let size = |k: usize| nodes[k].bbox.size().element_sum();
            let open = (0..n)
                .filter(|&i| nodes[kids[i]].count == 0)
                .max_by(|&a, &b| size(kids[a]).total_cmp(&size(kids[b])));
            let Some(i) = open else { break };
            let k = kids[i];
            kids[i] = kids[n - 1];
            kids[n - 1] = nodes[k].first as usize;
            kids[n] = nodes[k].right as usize;
            n += 1;
        }
        (kids, n)
    }

    /// Positions in `order` of the triangles below binary node `k`.
    fn range(&self, k: usize) -> std::ops::Range<usize> {
        let [a, b] = self.nodes[k].span;
        a as usize..b as usize
    }

    /// Puts binary node `k` in `lane` of `w` (whose centre and scale are set):
    /// its oriented box (about the mean normal of `sum`, the sum of its
    /// triangles' area-weighted normals) or axis-aligned box, widened by
    /// `pad`, and what it points to.
    #[allow(clippy::too_many_arguments)]
    fn set(
        &self,
        w: &mut NearNode,
        lane: usize,
        k: usize,
        pad: f64,
        sum: DVec3,
        child: u32,
        count: u32,
    ) {
        let range = self.range(k);
        let obb = range.len() <= OBB_MAX;
        let axes = if obb {
            let n = sum.try_normalize().unwrap_or(DVec3::Z);
            let u = n.any_orthonormal_vector();
            [n, u, n.cross(u)]
        } else {
            [DVec3::X, DVec3::Y, DVec3::Z]
        };
        // The axes as stored are the axes used: the query projects on them.
        let axes = axes.map(|a| a.as_vec3());
        let (lo, hi) = if obb {
            self.tris.extents(range, w.centre, axes)
        } else {
            let b = &self.nodes[k].bbox;
            ((b.min - w.centre).to_array(), (b.max - w.centre).to_array())
        };
        for a in 0..3 {
            for (slot, v) in w.axes[a].iter_mut().zip(axes[a].to_array()) {
                slot[lane] = v;
            }
            w.lo[a][lane] = (lo[a] - pad) as f32;
            w.hi[a][lane] = (hi[a] + pad) as f32;
        }
        (w.child[lane], w.count[lane]) = (child, count);
        w.valid |= 1 << lane;
    }

    /// The node over binary node `at` and its subtree, depth first from
    /// `out[*next]` (`out[0]` is global index `base`); returns its global index
    /// and the sum of the area-weighted normals of its triangles.
    fn collapse(
        &self,
        at: usize,
        out: &mut [NearNode],
        base: usize,
        next: &mut usize,
    ) -> (u32, DVec3) {
        let me = *next;
        *next += 1;
        let nodes = self.nodes;
        let (mut w, pad) = self.start(at);
        let mut total = DVec3::ZERO;
        if nodes[at].count > 0 {
            // A mesh of one leaf.
            total = self.leaf_sum(at);
            self.set(&mut w, 0, at, pad, total, nodes[at].first, nodes[at].count);
        }
        let (kids, n) = self.kids(at);
        for (lane, &k) in kids[..n].iter().enumerate() {
            let (child, count, sum) = if nodes[k].count > 0 {
                (nodes[k].first, nodes[k].count, self.leaf_sum(k))
            } else {
                let (child, sum) = self.collapse(k, out, base, next);
                (child, 0, sum)
            };
            self.set(&mut w, lane, k, pad, sum, child, count);
            total += sum;
        }
        out[me] = w;
        ((base + me) as u32, total)
    }
}

/// Closest point on triangle (a, b, c) to p, with its barycentric coordinates
/// (Ericson, Real-Time Collision Detection §5.1.5).
#[inline(always)]
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Angle-weighted vertex normals (each facet's normal weighted by its corner
/// angle), the smooth normals of a tessellated free-form surface.
pub fn vertex_normals(mesh: &TriMesh) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let fnrm = mesh.facet_normal(t);
        let p = mesh.corners(t);
        for k in 0..3 {
            let e1 = p[(k + 1) % 3] - p[k];
            let e2 = p[(k + 2) % 3] - p[k];
            let ang = e1.angle_between(e2);
            if ang.is_finite() {
                n[tri[k] as usize] += fnrm * ang;
            }
        }
    }
    for v in &mut n {
        *v = v.normalize_or_zero();
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analytic::{tessellate, DemoSurface};
    use proptest::prelude::*;

    fn brute(mesh: &TriMesh, p: DVec3) -> f64 {
        (0..mesh.len())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                (closest_on_triangle(p, a, b, c).0 - p).length()
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn closest_many_agrees_with_brute_force_point_by_point() {
        let mesh = tessellate(&DemoSurface::default(), 3.0);
        let bvh = Bvh::build(&mesh);
        // A wandering path (hints help) with jumps (hints mislead).
        let pts: Vec<DVec3> = (0..3000)
            .map(|i| {
                let f = i as f64;
                let jump = if i % 97 == 0 { 25.0 } else { 0.0 };
                DVec3::new(
                    (f * 0.02 + jump) % 60.0,
                    (f * 0.013) % 60.0,
                    2.0 + (f * 0.1).sin(),
                )
            })
            .collect();
        let got = bvh.closest_many(&mesh, &pts, f64::INFINITY);
        assert_eq!(got.len(), pts.len());
        for (p, c) in pts.iter().zip(&got) {
            let c = c.expect("an unbounded query always finds a triangle");
            assert!((c.distance - brute(&mesh, *p)).abs() < 1e-9, "{p}");
            assert!(((c.point - *p).length() - c.distance).abs() < 1e-9);
        }
        // Within a bound: none beyond it.
        let near = bvh.closest_many(&mesh, &pts, 0.5);
        for (p, c) in pts.iter().zip(&near) {
            assert_eq!(c.is_some(), brute(&mesh, *p) <= 0.5, "{p}");
        }
    }

    #[test]
    fn occlusion_of_small_meshes_agrees_with_brute_force() {
        // Trees of every shape near the top: a root leaf, partly filled wide
        // nodes, leaves of 5 to 8 triangles boxed in pairs; bounded rays too.
        let full = tessellate(&DemoSurface::default(), 6.0);
        let mut hits = 0;
        for k in [1, 2, 3, 4, 5, 7, 8, 9, 13, 17, 33, 64, 150] {
            let soup: Vec<[DVec3; 3]> = (0..k.min(full.len())).map(|t| full.corners(t)).collect();
            let mesh = TriMesh::from_soup(&soup).0;
            let bvh = Bvh::build(&mesh);
            for i in 0..300 {
                let f = i as f64;
                let o = DVec3::new((f * 7.3) % 30.0, (f * 3.1) % 30.0, -5.0 + (f * 1.7) % 20.0);
                let d = DVec3::new((f * 0.37).sin(), (f * 0.91).cos(), (f * 0.13).sin());
                let max_s = if i % 2 == 0 { 1e9 } else { 4.0 + f % 25.0 };
                let brute = (0..mesh.len()).any(|t| {
                    let [a, b, c] = mesh.corners(t);
                    ray_triangle(o, d, a, b, c).is_some_and(|s| s > 0.0 && s < max_s)
                });
                assert_eq!(
                    bvh.occluded(o, d, max_s, None),
                    brute,
                    "{k} triangles, ray {i}"
                );
                hits += brute as usize;
            }
        }
        assert!(hits > 200, "hits exercised: {hits}");
    }

    #[test]
    fn occlusion_agrees_with_brute_force() {
        let mesh = tessellate(&DemoSurface::default(), 1.0);
        let bvh = Bvh::build(&mesh);
        let mut n = 0;
        for i in 0..400 {
            let f = i as f64;
            let o = DVec3::new((f * 7.3) % 60.0, (f * 3.1) % 60.0, 2.0 + (f * 1.7) % 15.0);
            let d = DVec3::new(
                (f * 0.37).sin(),
                (f * 0.91).cos(),
                -0.2 - (f * 0.13).sin().abs(),
            );
            let brute = (0..mesh.len()).any(|t| {
                let [a, b, c] = mesh.corners(t);
                ray_triangle(o, d, a, b, c).is_some_and(|s| s > 0.0 && s < 1e9)
            });
            assert_eq!(bvh.occluded(o, d, 1e9, None), brute, "ray {i}");
            n += brute as usize;
        }
        assert!(n > 50 && n < 350, "both outcomes exercised: {n}");
    }

    #[test]
    fn capsule_test_above_a_plane_agrees_with_brute_force() {
        // Only triangles reaching above the plane count; planes through the
        // capsule, beside it and below the whole part.
        let mesh = tessellate(&DemoSurface::default(), 1.5);
        let bvh = Bvh::build(&mesh);
        let (mut hits, mut culled) = (0, 0);
        for i in 0..400 {
            let f = i as f64;
            let a = DVec3::new((f * 7.3) % 60.0, (f * 3.1) % 60.0, 2.0 + (f * 1.7) % 8.0);
            let d = DVec3::new(
                (f * 0.37).sin(),
                (f * 0.91).cos(),
                0.3 + (f * 0.13).sin().abs(),
            )
            .normalize();
            let b = a + d * 20.0;
            let r = 0.5 + (f * 0.7) % 4.0;
            let n = if i % 3 == 0 {
                d
            } else {
                DVec3::new(0.3, -0.2, 1.0).normalize()
            };
            let h = n.dot(a) - (f * 0.53) % 3.0;
            let brute = brute_capsule(&mesh, a, b, r, Some((n, h)));
            assert_eq!(
                bvh.capsule_hits_above(a, b, r, None, Some((n, h))),
                brute,
                "capsule {i}"
            );
            hits += brute as usize;
            culled += (bvh.capsule_hits(a, b, r, None) && !brute) as usize;
        }
        assert!(hits > 40 && culled > 10, "{hits} hits, {culled} only below");
    }

    #[test]
    fn capsule_test_near_tangency_agrees_with_brute_force() {
        // Capsules standing on the surface like a tool: the axis starting a
        // radius (a hair more or less) off a facet along its normal, tilted
        // from steep to grazing, so that the surface nearly touches them
        // over a long stretch: where the per-triangle plane test decides.
        let mesh = tessellate(&DemoSurface::default(), 0.8);
        let bvh = Bvh::build(&mesh);
        let (mut hits, mut free) = (0, 0);
        for i in 0..300 {
            let (a, axis, r, f) = near_facet_capsule(&mesh, i);
            let b = a + axis * (5.0 + (f * 1.3) % 30.0);
            let brute = brute_capsule(&mesh, a, b, r, None);
            assert_eq!(bvh.capsule_hits(a, b, r, None), brute, "capsule {i}");
            hits += brute as usize;
            free += !brute as usize;
        }
        assert!(hits > 30 && free > 30, "{hits} hits, {free} free");
    }

    /// Whether any triangle of `mesh` (reaching above `above`, when given)
    /// comes closer than r to the segment ab, every triangle tested.
    fn brute_capsule(
        mesh: &TriMesh,
        a: DVec3,
        b: DVec3,
        r: f64,
        above: Option<(DVec3, f64)>,
    ) -> bool {
        (0..mesh.len()).any(|k| {
            let [p, q, s] = mesh.corners(k);
            above.is_none_or(|(n, h)| [p, q, s].iter().any(|v| n.dot(*v) > h))
                && segment_triangle_dist2(a, b, p, q, s) < r * r
        })
    }

    /// Case `i` of the capsule tests: a start a radius (a hair more or
    /// less) off a facet along its normal, a unit axis tilted from the
    /// normal from steep to grazing, the radius, and `i` as a number.
    fn near_facet_capsule(mesh: &TriMesh, i: usize) -> (DVec3, DVec3, f64, f64) {
        let f = i as f64;
        let t = (i * 7919) % mesh.len();
        let [p, q, s] = mesh.corners(t);
        let n = mesh.facet_normal(t);
        let r = 0.5 + (f * 0.7) % 4.0;
        let lift = r * (1.0 + [-1e-3, 1e-3, 1e-6][i % 3]);
        let a = (p + q + s) / 3.0 + n * lift;
        let (u, _) = n.any_orthonormal_pair();
        let tilt = (f * 0.29) % 1.55;
        let spin = f * 2.4;
        let side = u * spin.cos() + n.cross(u) * spin.sin();
        (a, n * tilt.cos() + side * tilt.sin(), r, f)
    }

    #[test]
    fn balls_standing_on_a_fine_surface_agree_with_brute_force() {
        // A point capsule (a tool's ball) walks the closest-point tree: on a
        // finely tessellated surface, far from the origin in single
        // precision and near it in double, with the ball a hair off its
        // facet or a hair into it, and a convex and concave neighbourhood
        // either way: the same answer as every triangle tested.
        for mesh in [tessellate(&DemoSurface::default(), 0.4), far_mesh(0.4)] {
            let bvh = Bvh::build(&mesh);
            let (mut hits, mut free) = (0, 0);
            for i in 0..400 {
                let (a, _, r, _) = near_facet_capsule(&mesh, i);
                let brute = brute_capsule(&mesh, a, a, r, None);
                assert_eq!(bvh.capsule_hits(a, a, r, None), brute, "{i}");
                hits += brute as usize;
                free += !brute as usize;
            }
            assert!(hits > 50 && free > 50, "{hits} hits, {free} free");
        }
    }

    #[test]
    fn shank_capsules_standing_on_their_ball_agree_with_brute_force() {
        // Capsules like a tool's shank: starting a radius (a hair more or
        // less) off a facet, tilted from steep to grazing, with only what
        // reaches above the plane through the ball's centre across the axis:
        // where the distance across the axis rules triangles out. Every other
        // query carries the previous one's hit as its hint, which must not
        // change the answer, whether it hits or not.
        let mesh = tessellate(&DemoSurface::default(), 0.8);
        let bvh = Bvh::build(&mesh);
        let (mut hits, mut free, mut hinted) = (0, 0, 0);
        let mut hint = None;
        for i in 0..600 {
            let (a, axis, r, f) = near_facet_capsule(&mesh, i);
            let b = a + axis * (r + (f * 1.3) % 30.0);
            let h = axis.dot(a);
            let brute = brute_capsule(&mesh, a, b, r, Some((axis, h)));
            let above = Some((axis, h));
            assert_eq!(bvh.capsule_hits_above(a, b, r, None, above), brute, "{i}");
            if i % 2 == 1 {
                hinted += hint.is_some() as usize;
                let got = bvh.capsule_hits_above_from(a, b, r, None, above, &mut hint);
                assert_eq!(got, brute, "{i} with a hint");
            } else {
                hint = None;
                bvh.capsule_hits_above_from(a, b, r, None, above, &mut hint);
            }
            hits += brute as usize;
            free += !brute as usize;
        }
        assert!(
            hits > 30 && free > 30 && hinted > 10,
            "{hits} hits, {free} free, {hinted}"
        );
    }

    #[test]
    fn capsule_test_agrees_with_sampled_distance() {
        let mesh = tessellate(&DemoSurface::default(), 2.0);
        let bvh = Bvh::build(&mesh);
        let mut hits = 0;
        for i in 0..200 {
            let f = i as f64;
            let a = DVec3::new((f * 7.3) % 60.0, (f * 3.1) % 60.0, 3.0 + (f * 1.7) % 10.0);
            let b = a + DVec3::new((f * 0.37).sin(), (f * 0.91).cos(), (f * 0.13).sin()) * 15.0;
            let r = 0.5 + (f * 0.7) % 3.0;
            // Reference: the segment sampled finely, each sample's exact distance.
            let d = (0..=2000)
                .map(|k| {
                    bvh.closest(&mesh, a + (b - a) * (k as f64 / 2000.0), f64::INFINITY)
                        .expect("hit")
                        .distance
                })
                .fold(f64::INFINITY, f64::min);
            if (d - r).abs() < 0.02 {
                continue;
            }
            assert_eq!(
                bvh.capsule_hits(a, b, r, None),
                d < r,
                "segment {i}: distance {d}, radius {r}"
            );
            hits += (d < r) as usize;
        }
        assert!(hits > 20 && hits < 180, "{hits}");
        // Segment-segment distance: skew lines, parallel and touching cases.
        let d2 = segment_segment_dist2(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, -1.0, 2.0),
            DVec3::new(0.5, 1.0, 2.0),
        );
        assert!((d2 - 4.0).abs() < 1e-12);
        let d2 = segment_segment_dist2(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(3.0, 1.0, 0.0),
        );
        assert!((d2 - 2.0).abs() < 1e-12);
    }

    #[test]
    fn distance_across_an_axis_never_exceeds_the_distance_to_the_segment() {
        // The capsule query rules a triangle out by its distance across the
        // axis: that must be a lower bound of the exact distance to the
        // segment, and equal to it where the segment's nearest point is
        // inside its span. Random triangles, thin, edge-on ones among them.
        let mut seed = 19_005u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (mut inside, mut equal) = (0, 0);
        for i in 0..20_000 {
            let x: [f64; 18] = std::array::from_fn(|_| next());
            let v = |k: usize| DVec3::new(x[k], x[k + 1], x[k + 2]) * 8.0;
            let (a, dir) = (v(0), v(3).normalize_or(DVec3::Z));
            let b = a + dir * (1.0 + 20.0 * (x[15] + 0.5));
            let (p, q) = (v(6), v(9));
            let r = match i % 4 {
                // Edge-on: the third corner on the plane through p, q and the axis.
                0 => p + (q - p) * x[16] * 3.0 + dir * x[17] * 5.0,
                // Thin.
                1 => p + (q - p) * (0.5 + x[16]) + dir.cross(q - p) * 1e-7,
                _ => v(12),
            };
            let across = |x: DVec3| {
                let w = x - a;
                w - dir * w.dot(dir)
            };
            let lat = lateral_dist2(across(p), across(q), across(r));
            let exact = segment_triangle_dist2(a, b, p, q, r);
            assert!(lat <= exact * (1.0 + 1e-9) + 1e-12, "{i}: {lat} > {exact}");
            // The infinite line's distance, brute force: on a long segment
            // through the triangle's span the two agree.
            let long = segment_triangle_dist2(a - dir * 1e3, a + dir * 1e3, p, q, r);
            assert!(
                (lat - long).abs() <= 1e-7 * (1.0 + long),
                "{i}: {lat} vs {long}"
            );
            inside += (lat == 0.0) as usize;
            equal += ((lat - exact).abs() < 1e-9) as usize;
        }
        assert!(
            inside > 500 && equal > 2000,
            "{inside} inside, {equal} equal"
        );
    }

    #[test]
    fn triangle_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        crate::assert_near!(
            closest_on_triangle(DVec3::new(0.2, 0.2, 5.0), a, b, c).0,
            DVec3::new(0.2, 0.2, 0.0),
            1e-12
        );
        assert_eq!(
            closest_on_triangle(DVec3::new(-1.0, -1.0, 0.0), a, b, c).0,
            a
        );
        assert_eq!(
            closest_on_triangle(DVec3::new(0.5, -2.0, 1.0), a, b, c).0,
            DVec3::new(0.5, 0.0, 0.0)
        );
        let (q, w) = closest_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        crate::assert_near!(q, DVec3::new(0.5, 0.5, 0.0), 1e-12);
        crate::assert_near!(w[1] + w[2], 1.0, 1e-12);
    }

    #[test]
    fn smooth_normals_of_a_fine_tessellation_follow_the_surface() {
        let s = DemoSurface::default();
        let m = tessellate(&s, 0.5);
        let vn = vertex_normals(&m);
        use crate::analytic::HeightField;
        for (v, n) in m.vertices.iter().zip(&vn).step_by(97) {
            assert!(n.angle_between(s.normal(v.x, v.y)) < 0.01, "{v:?}");
        }
    }

    #[test]
    fn parallel_build_of_a_large_mesh_answers_like_brute_force() {
        // 320 000 triangles: two levels of subtrees are built in parallel.
        let m = tessellate(&DemoSurface::default(), 0.15);
        assert!(m.len() > 4 * PAR_MIN);
        let bvh = Bvh::build(&m);
        let mut seed = 1u64;
        for _ in 0..20 {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            let f = |k: u32| ((seed >> k) & 0xffff) as f64 / 65535.0;
            let p = DVec3::new(-5.0 + 70.0 * f(0), -5.0 + 70.0 * f(16), -5.0 + 25.0 * f(32));
            let c = bvh.closest(&m, p, f64::INFINITY).expect("hit");
            assert!((c.distance - brute(&m, p)).abs() < 1e-12);
        }
        // Every triangle is in exactly one leaf.
        let mut seen = vec![false; m.len()];
        for &t in &bvh.order {
            assert!(!std::mem::replace(&mut seen[t as usize], true));
        }
        assert!(seen.iter().all(|s| *s));
    }

    /// A mesh of single-precision vertices (as read from binary STL) keeps its
    /// triangles in single precision and answers exactly as the same mesh in
    /// double precision does, to the bit; a mesh with one vertex that is not
    /// a single-precision number keeps double precision.
    #[test]
    fn single_precision_storage_answers_exactly() {
        let mut m = far_mesh(0.5);
        m.vertices
            .iter_mut()
            .for_each(|v| *v = v.as_vec3().as_dvec3());
        let bvh = Bvh::build(&m);
        assert!(matches!(bvh.tris, Tris::F32(_)));
        let mut m64 = m.clone();
        m64.vertices[0].x += 1e-9;
        let bvh64 = Bvh::build(&m64);
        assert!(matches!(bvh64.tris, Tris::F64(_)));
        let mut seed = 5u64;
        let mut hint = None;
        for _ in 0..300 {
            let s = lcg(&mut seed);
            let f = |k: u32| ((s >> k) & 0xffff) as f64 / 65535.0;
            let p = DVec3::new(
                4817.25 + 60.0 * f(0),
                -2903.5 + 60.0 * f(16),
                915.0 + 5.0 * f(32),
            );
            let c = bvh.closest_near(&m, p, f64::INFINITY, hint).expect("hit");
            hint = Some(c.triangle);
            assert_eq!(c.distance, brute(&m, p));
            let [a, b, cc] = m.corners(c.triangle as usize);
            assert_eq!(c.point, closest_on_triangle(p, a, b, cc).0);
        }
    }

    /// Positions in `order` of the triangles below lane `lane` of near node `at`.
    fn lane_triangles(bvh: &Bvh, at: usize, lane: usize, out: &mut Vec<usize>) {
        let n = &bvh.near[at];
        if n.count[lane] > 0 {
            out.extend(n.child[lane] as usize..(n.child[lane] + n.count[lane]) as usize);
        } else {
            let c = n.child[lane] as usize;
            for l in 0..4 {
                if bvh.near[c].valid & (1 << l) != 0 {
                    lane_triangles(bvh, c, l, out);
                }
            }
        }
    }

    /// The demo surface tessellated at `step`, moved thousands of millimetres
    /// from the origin (where single-precision rounding is largest).
    fn far_mesh(step: f64) -> TriMesh {
        let mut m = tessellate(&DemoSurface::default(), step);
        let off = DVec3::new(4817.25, -2903.5, 911.125);
        m.vertices.iter_mut().for_each(|v| *v += off);
        m
    }

    /// The next value of a linear congruential sequence (deterministic tests).
    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed
    }

    #[test]
    fn single_precision_bounds_never_exceed_the_distance() {
        // Far from the origin, points exactly on the triangles (bound 0) and
        // just above and below them: every child's bound stays at or below the
        // true squared distance to its triangles.
        let bvh = Bvh::build(&far_mesh(0.5));
        let mut seed = 3u64;
        let mut checked = 0;
        for at in (0..bvh.near.len()).step_by(7) {
            for lane in 0..4 {
                if bvh.near[at].valid & (1 << lane) == 0 {
                    continue;
                }
                let mut tris = Vec::new();
                lane_triangles(&bvh, at, lane, &mut tris);
                for _ in 0..4 {
                    let seed = lcg(&mut seed);
                    let [a, b, c] = bvh.tris.get(tris[(seed >> 33) as usize % tris.len()]);
                    let f = |k: u32| ((seed >> k) & 0x3ff) as f64 / 1023.0;
                    let n = (b - a).cross(c - a).normalize();
                    for p in [
                        a,
                        b,
                        c,
                        a + (b - a) * f(0) * 0.5 + (c - a) * f(10) * 0.5,
                        a + n * 1e-4 * f(20),
                        a - n * 0.01 * f(20),
                    ] {
                        let d2 = tris
                            .iter()
                            .map(|&t| {
                                let [a, b, c] = bvh.tris.get(t);
                                (closest_on_triangle(p, a, b, c).0 - p).length_squared()
                            })
                            .fold(f64::INFINITY, f64::min);
                        let lb = bvh.near[at].lower_bounds(p)[lane] as f64;
                        assert!(lb <= d2, "node {at} lane {lane}: bound {lb:e} > {d2:e}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 1000);
    }

    #[test]
    fn segment_bounds_never_exceed_the_distance() {
        // Far from the origin, segments from points on, just above and just
        // below the triangles, along the axes exactly (a zero step across
        // two of an axis-aligned box's slabs), along the facet's normal and
        // across it, and of zero length: wherever a child's triangles come
        // within reach of the segment, its bound stays at or below the true
        // squared distance. Planes a hair below a corner of the child's
        // triangles always keep it.
        let bvh = Bvh::build(&far_mesh(0.5));
        let mut seed = 11u64;
        let (mut near, mut far, mut planes) = (0, 0, 0);
        for at in (0..bvh.near.len()).step_by(5) {
            for lane in 0..4 {
                if bvh.near[at].valid & (1 << lane) == 0 {
                    continue;
                }
                let mut tris = Vec::new();
                lane_triangles(&bvh, at, lane, &mut tris);
                let seed = lcg(&mut seed);
                let [a, b, c] = bvh.tris.get(tris[(seed >> 33) as usize % tris.len()]);
                let f = |k: u32| ((seed >> k) & 0x3ff) as f64 / 1023.0;
                let n = (b - a).cross(c - a).normalize();
                let reach = 0.2 + 6.0 * f(30);
                let starts = [
                    a,
                    a + n * (reach * f(0)),
                    a - n * 0.01 * f(10),
                    a + n * (reach * (1.0 + f(20))),
                ];
                let dirs = [
                    DVec3::X,
                    -DVec3::Y,
                    DVec3::Z,
                    n,
                    (b - a).normalize(),
                    DVec3::new(f(0) - 0.5, f(10) - 0.5, f(20) - 0.5).normalize(),
                    DVec3::ZERO,
                ];
                for p in starts {
                    for d in dirs {
                        let q = p + d * (1.0 + 20.0 * f(40));
                        let d2 = tris
                            .iter()
                            .map(|&t| {
                                let [a, b, c] = bvh.tris.get(t);
                                segment_triangle_dist2(p, q, a, b, c)
                            })
                            .fold(f64::INFINITY, f64::min);
                        let lb = bvh.near[at].segment_lower_bounds(p, q, reach as f32)[lane] as f64;
                        if d2 <= reach * reach {
                            assert!(lb <= d2, "node {at} lane {lane}: bound {lb:e} > {d2:e}");
                            near += 1;
                        } else {
                            far += (lb > reach * reach) as usize;
                        }
                    }
                }
                // The plane across a direction a hair below the child's
                // highest corner along it.
                for d in [DVec3::Z, -DVec3::X, n, dirs[5]] {
                    let top = tris
                        .iter()
                        .flat_map(|&t| bvh.tris.get(t))
                        .map(|v| d.dot(v))
                        .fold(f64::NEG_INFINITY, f64::max);
                    let h = top - 1e-9 * top.abs().max(1.0);
                    assert!(
                        bvh.near[at].reaches_above(d, h) & (1 << lane) != 0,
                        "node {at} lane {lane}: plane at {h} culls a corner at {top}"
                    );
                    planes += 1;
                }
            }
        }
        assert!(
            near > 2000 && far > 2000 && planes > 1000,
            "{near} {far} {planes}"
        );
    }

    #[test]
    fn axis_aligned_capsules_far_from_the_origin_agree_with_brute_force() {
        // Shank-like capsules thousands of millimetres from the origin with
        // axes exactly along the coordinate axes (two slabs of every
        // axis-aligned box see no step) and grazing ones, standing a radius
        // (a hair more or less) off a facet, with and without the plane
        // across the axis through the start.
        let mesh = far_mesh(0.8);
        let bvh = Bvh::build(&mesh);
        let (mut hits, mut free) = (0, 0);
        for i in 0..500 {
            let (a, grazing, r, f) = near_facet_capsule(&mesh, i);
            let axis = match i % 4 {
                0 => DVec3::Z,
                1 => DVec3::X,
                2 => -DVec3::Y,
                _ => grazing,
            };
            let b = a + axis * (r + (f * 1.3) % 30.0);
            let above = (i % 8 < 4).then(|| (axis, axis.dot(a)));
            let brute = brute_capsule(&mesh, a, b, r, above);
            assert_eq!(bvh.capsule_hits_above(a, b, r, None, above), brute, "{i}");
            hits += brute as usize;
            free += !brute as usize;
        }
        assert!(hits > 50 && free > 50, "{hits} hits, {free} free");
    }

    #[test]
    fn segment_bounds_keep_boxes_a_hair_within_reach() {
        // The tightest cases for the bound's rounding: a segment passing
        // within r·(1 − δ), δ down to 0, of the corner of a child's
        // triangles farthest along a direction made of the box's own axes
        // (a face, an edge or a corner of the box), across that direction,
        // from 1 µm to 100 m long, with radii from 1 µm to 1 m, thousands of
        // millimetres from the origin: the traversal's cut-off keeps the child.
        let bvh = Bvh::build(&far_mesh(0.7));
        let mut seed = 17u64;
        let mut checked = 0;
        for at in 0..bvh.near.len() {
            let node = &bvh.near[at];
            for lane in (0..4).filter(|l| node.valid & (1 << l) != 0) {
                let mut tris = Vec::new();
                lane_triangles(&bvh, at, lane, &mut tris);
                let axes = [0, 1, 2].map(|k| {
                    DVec3::new(
                        node.axes[k][0][lane] as f64,
                        node.axes[k][1][lane] as f64,
                        node.axes[k][2][lane] as f64,
                    )
                });
                for _ in 0..6 {
                    let s = lcg(&mut seed);
                    let pick = |k: u32, n: u64| ((s >> k) % n) as usize;
                    let sign = |k: u32| if (s >> k) & 1 == 0 { 1.0 } else { -1.0 };
                    let o = (0..=pick(3, 3))
                        .map(|j| axes[(pick(5, 3) + j) % 3] * sign(8 + j as u32))
                        .sum::<DVec3>()
                        .normalize();
                    let v = tris
                        .iter()
                        .flat_map(|&k| bvh.tris.get(k))
                        .max_by(|x, y| o.dot(*x).total_cmp(&o.dot(*y)))
                        .expect("a child has triangles");
                    let r = [1e-3, 0.05, 1.0, 5.0, 1e3][pick(12, 5)];
                    let delta = [1e-6, 1e-7, 3e-8, 0.0][pick(16, 4)];
                    let p = v + o * r * (1.0 - delta);
                    let (u1, u2) = o.any_orthonormal_pair();
                    let across = match pick(19, 3) {
                        0 => (axes[pick(21, 3)] - o * o.dot(axes[pick(21, 3)])).normalize_or(u1),
                        1 => u1,
                        _ => u2,
                    };
                    let len = [1e-3, 1.0, 1e3, 1e5][pick(24, 4)];
                    let back = [0.0, 0.5, 1.0][pick(27, 3)];
                    let a = p - across * len * back;
                    let b = a + across * len;
                    let lb = node.segment_lower_bounds(a, b, r as f32)[lane];
                    let cut = (r * r * (1.0 + 1e-6)) as f32;
                    assert!(
                        lb <= cut,
                        "node {at} lane {lane}: bound {lb:e} > {cut:e} (r {r}, δ {delta}, length {len})"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 20_000, "{checked}");
    }

    #[test]
    fn needles_and_slivers_agree_with_brute_force() {
        // Triangles whose corners lie on a line up to rounding (needles,
        // the normal then mostly rounding) or a hair off it (slivers), with
        // balls and capsules near them: the plane test must not rule out
        // what the exact test would find.
        let t = [
            DVec3::new(7.11031422329701, 0.5123065743763067, 1.4168378627283542),
            DVec3::new(7.688424909227498, 0.360989951006922, 0.5208957860423801),
            DVec3::new(7.502443296605347, 0.4096693999700236, 0.8091256290349935),
        ];
        let one = TriMesh {
            vertices: t.to_vec(),
            triangles: vec![[0, 1, 2]],
        };
        let p = DVec3::new(7.3, 0.45, 1.1);
        let d2 = segment_triangle_dist2(p, p, t[0], t[1], t[2]);
        let bvh = Bvh::build(&one);
        for k in [1.01, 1.5] {
            assert!(bvh.capsule_hits(p, p, d2.sqrt() * k, None), "{k}");
        }
        assert!(!bvh.capsule_hits(p, p, d2.sqrt() * 0.99, None));
        let mut seed = 5u64;
        let mut next = || (lcg(&mut seed) >> 11) as f64 / (1u64 << 53) as f64;
        let mut vertices = Vec::new();
        for _ in 0..300 {
            let a = DVec3::new(next(), next(), next()) * 40.0;
            let dir = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let b = a + dir * (0.5 + 5.0 * next());
            let off = [0.0, 1e-9, 1e-6, 1e-3][(next() * 4.0) as usize % 4];
            let c = a.lerp(b, next()) + dir.any_orthonormal_vector() * off;
            vertices.extend([a, b, c]);
        }
        let n = vertices.len() as u32 / 3;
        let soup = TriMesh {
            vertices,
            triangles: (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
        };
        let bvh = Bvh::build(&soup);
        let (mut hits, mut free) = (0, 0);
        for i in 0..600 {
            let [a0, b0, c0] = soup.corners(i % soup.len());
            let near = a0.lerp(b0, next()).lerp(c0, next() * 0.5);
            let r = [0.01, 0.1, 1.0][i % 3];
            let a = near + DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * (2.0 * r);
            let b = if i % 2 == 0 {
                a
            } else {
                a + DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 4.0
            };
            let brute = brute_capsule(&soup, a, b, r, None);
            assert_eq!(bvh.capsule_hits(a, b, r, None), brute, "{i}");
            hits += brute as usize;
            free += !brute as usize;
        }
        assert!(hits > 100 && free > 100, "{hits} hits, {free} free");
    }

    #[test]
    fn ball_centres_over_a_fine_mesh_far_from_the_origin_agree_with_brute_force() {
        // The case the single-precision bounds must not spoil: ball centres at
        // distance R along the normal of a finely tessellated surface, where
        // many triangles are nearly as close as the nearest, and coordinates in
        // the thousands of millimetres.
        let m = far_mesh(0.4);
        let bvh = Bvh::build(&m);
        let mut seed = 7u64;
        let mut hint = None;
        for _ in 0..150 {
            let seed = lcg(&mut seed);
            let f = |k: u32| ((seed >> k) & 0xffff) as f64 / 65535.0;
            let t = (seed >> 40) as usize % m.len();
            let [a, b, c] = m.corners(t);
            let (u, v) = (f(0), f(16));
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let r = 0.5 + 5.5 * f(32);
            let p = a + (b - a) * u + (c - a) * v + m.facet_normal(t) * r;
            let want = brute(&m, p);
            let got = bvh.closest_near(&m, p, 3.0 * r, hint).expect("hit");
            hint = Some(got.triangle);
            assert!(
                (got.distance - want).abs() <= 1e-12 * want.max(1.0),
                "{} vs {want}",
                got.distance
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn bvh_closest_equals_brute_force(x in -5.0..65.0f64, y in -5.0..65.0f64, z in -5.0..20.0f64) {
            let m = tessellate(&DemoSurface::default(), 3.0);
            let bvh = Bvh::build(&m);
            let p = DVec3::new(x, y, z);
            let c = bvh.closest(&m, p, f64::INFINITY).expect("hit");
            prop_assert!((c.distance - brute(&m, p)).abs() < 1e-12);
            let h = bvh.closest_near(&m, p, f64::INFINITY, Some(((x * 7.0).abs() as u32) % m.len() as u32)).expect("hit");
            prop_assert!((h.distance - c.distance).abs() < 1e-12);
            let [a, b, cc] = m.corners(c.triangle as usize);
            let q = a * c.bary[0] + b * c.bary[1] + cc * c.bary[2];
            prop_assert!((q - c.point).length() < 1e-9);
            // A search radius below the distance finds nothing.
            prop_assert!(bvh.closest(&m, p, c.distance * 0.999).is_none() || c.distance == 0.0);
        }
    }
}
