//! A bounding-volume hierarchy over a [`TriMesh`] for exact closest-point queries,
//! and the per-triangle geometry the queries return.

use crate::{Aabb, TriMesh};
use glam::DVec3;

const LEAF: usize = 8;

#[derive(Clone, Copy, Debug)]
struct Node {
    bbox: Aabb,
    /// Leaf: first index into `order`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
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

/// A BVH over the triangles of one mesh (built by median splits on the longest
/// axis of the centroid bounds; leaves of up to four triangles).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// Triangle corners in `order`, contiguous: the queries read them leaf by leaf.
    tris: Vec<[DVec3; 3]>,
}

impl Bvh {
    pub fn build(mesh: &TriMesh) -> Bvh {
        let n = mesh.len();
        let centroids: Vec<DVec3> = (0..n)
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                (a + b + c) / 3.0
            })
            .collect();
        let boxes: Vec<Aabb> = (0..n)
            .map(|t| Aabb::from_points(mesh.corners(t).iter()))
            .collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF + 2);
        nodes.push(Node {
            bbox: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        if n > 0 {
            Self::split(&mut nodes, 0, &mut order, 0, &centroids, &boxes);
        }
        let tris = order.iter().map(|&t| mesh.corners(t as usize)).collect();
        Bvh { nodes, order, tris }
    }

    fn split(
        nodes: &mut Vec<Node>,
        at: usize,
        order: &mut [u32],
        offset: usize,
        cen: &[DVec3],
        boxes: &[Aabb],
    ) {
        let mut bbox = Aabb::EMPTY;
        let mut cb = Aabb::EMPTY;
        for &t in order.iter() {
            bbox = bbox.union(&boxes[t as usize]);
            cb.extend(cen[t as usize]);
        }
        if order.len() <= LEAF {
            nodes[at] = Node {
                bbox,
                first: offset as u32,
                count: order.len() as u32,
            };
            return;
        }
        let size = cb.size();
        let axis = if size.x >= size.y && size.x >= size.z {
            0
        } else if size.y >= size.z {
            1
        } else {
            2
        };
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |a, b| {
            cen[*a as usize][axis].total_cmp(&cen[*b as usize][axis])
        });
        let left = nodes.len();
        nodes.push(Node {
            bbox: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes.push(Node {
            bbox: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes[at] = Node {
            bbox,
            first: left as u32,
            count: 0,
        };
        let (lo, hi) = order.split_at_mut(mid);
        Self::split(nodes, left, lo, offset, cen, boxes);
        Self::split(nodes, left + 1, hi, offset + mid, cen, boxes);
    }

    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bbox
    }

    /// The closest point of the mesh to `p` within `max_dist`, if any.
    pub fn closest(&self, mesh: &TriMesh, p: DVec3, max_dist: f64) -> Option<Closest> {
        self.closest_near(mesh, p, max_dist, None)
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
        let mut stack: [u32; 64] = [0; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = self.nodes[stack[sp] as usize];
            if box_dist2(&node.bbox, p) > best_d2 {
                continue;
            }
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for (k, [a, b, c]) in self.tris[range.clone()].iter().enumerate() {
                    // Cheap bound first: the distance to the triangle's plane.
                    let nrm = (*b - *a).cross(*c - *a);
                    let h = nrm.dot(p - *a);
                    if h * h > best_d2 * nrm.length_squared() {
                        continue;
                    }
                    let (q, bary) = closest_on_triangle(p, *a, *b, *c);
                    let d2 = (q - p).length_squared();
                    if d2 <= best_d2 {
                        best_d2 = d2;
                        let triangle = self.order[range.start + k];
                        best = Some(Closest {
                            point: q,
                            distance: d2.sqrt(),
                            triangle,
                            bary,
                        });
                    }
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let dl = box_dist2(&self.nodes[l as usize].bbox, p);
                let dr = box_dist2(&self.nodes[r as usize].bbox, p);
                // Nearer child last so it is popped first.
                let (far, near) = if dl <= dr { (r, l) } else { (l, r) };
                if sp + 2 <= stack.len() {
                    stack[sp] = far;
                    stack[sp + 1] = near;
                    sp += 2;
                }
            }
        }
        best
    }
}

#[inline]
fn box_dist2(b: &Aabb, p: DVec3) -> f64 {
    let d = (b.min - p).max(p - b.max).max(DVec3::ZERO);
    d.length_squared()
}

/// Closest point on triangle (a, b, c) to p, with its barycentric coordinates
/// (Ericson, Real-Time Collision Detection §5.1.5).
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
