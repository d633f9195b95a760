//! Tool-direction accessibility on a spherical map (paper 004, spec
//! `kinematics-access-tools.md` §3): sphere grids, each facet's point visibility
//! cone (PVC) as a bitset of grid cells, the directions a five-axis machine can
//! reach (its FTM) and whether every facet keeps one of them.
//!
//! Line-of-sight mode: a direction is visible from a facet when it leaves the
//! facet's outer side (optionally by a minimum clearance angle) and the ray from
//! the facet's centroid along it meets no other triangle.

use millplan_geom::bvh::{Bvh, CapsuleHit};
use millplan_geom::{DMat3, DVec3, TriMesh};
use millplan_models::kinematics::Kinematics;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// A partition of the unit sphere into cells, each with a centre direction.
pub trait SphereGrid: Sync {
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Unit centre direction of a cell.
    fn direction(&self, cell: usize) -> DVec3;
    /// Solid angle of a cell, steradians.
    fn area(&self, cell: usize) -> f64;
    /// The cell that contains a unit direction.
    fn cell_of(&self, d: DVec3) -> usize;
    fn name(&self) -> String;
}

fn sph(theta: f64, phi: f64) -> DVec3 {
    DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Latitude-longitude grid: `bands` polar bands × `sectors` azimuth sectors, each
/// (θ, φ) rectangle split into two triangles along its diagonal in the (θ, φ)
/// plane. 20 × 30 × 2 = 1200 cells is the paper's map.
#[derive(Clone, Copy, Debug)]
pub struct LatLon {
    pub bands: usize,
    pub sectors: usize,
}

impl LatLon {
    pub const PAPER: LatLon = LatLon {
        bands: 20,
        sectors: 30,
    };

    fn steps(&self) -> (f64, f64) {
        (PI / self.bands as f64, TAU / self.sectors as f64)
    }
}

impl SphereGrid for LatLon {
    fn len(&self) -> usize {
        2 * self.bands * self.sectors
    }

    fn direction(&self, cell: usize) -> DVec3 {
        let (dt, dp) = self.steps();
        let (q, t) = (cell / 2, cell % 2);
        let (i, j) = (q / self.sectors, q % self.sectors);
        // Centroid in the (θ, φ) plane: (1/3, 1/3) of the lower, (2/3, 2/3) of the upper triangle.
        let f = if t == 0 { 1.0 / 3.0 } else { 2.0 / 3.0 };
        sph((i as f64 + f) * dt, (j as f64 + f) * dp)
    }

    fn area(&self, cell: usize) -> f64 {
        let (dt, dp) = self.steps();
        let (q, t) = (cell / 2, cell % 2);
        let a = (q / self.sectors) as f64 * dt;
        // ∫∫ sin θ dθ dφ over the triangle u + v ≤ 1 (or ≥ 1) of the rectangle.
        let i0 = (a.cos() - (a + dt).cos()) / dt;
        let i1 = -(a + dt).cos() / dt + ((a + dt).sin() - a.sin()) / (dt * dt);
        dt * dp * if t == 0 { i0 - i1 } else { i1 }
    }

    fn cell_of(&self, d: DVec3) -> usize {
        let (dt, dp) = self.steps();
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let phi = d.y.atan2(d.x).rem_euclid(TAU);
        let i = ((theta / dt) as usize).min(self.bands - 1);
        let j = ((phi / dp) as usize).min(self.sectors - 1);
        let u = theta / dt - i as f64;
        let v = phi / dp - j as f64;
        2 * (i * self.sectors + j) + usize::from(u + v > 1.0)
    }

    fn name(&self) -> String {
        format!("latlon {}x{}x2", self.bands, self.sectors)
    }
}

/// Geodesic icosphere: the icosahedron's faces split `level` times into four,
/// projected onto the sphere; 20·4^level near-uniform triangular cells (1280 at level 3).
#[derive(Clone, Debug)]
pub struct Icosphere {
    tris: Vec<[DVec3; 3]>,
    centres: Vec<DVec3>,
}

impl Icosphere {
    pub fn new(level: u32) -> Icosphere {
        let g = (1.0 + 5f64.sqrt()) / 2.0;
        let v = [
            [-1.0, g, 0.0],
            [1.0, g, 0.0],
            [-1.0, -g, 0.0],
            [1.0, -g, 0.0],
            [0.0, -1.0, g],
            [0.0, 1.0, g],
            [0.0, -1.0, -g],
            [0.0, 1.0, -g],
            [g, 0.0, -1.0],
            [g, 0.0, 1.0],
            [-g, 0.0, -1.0],
            [-g, 0.0, 1.0],
        ]
        .map(|p| DVec3::from_array(p).normalize());
        const F: [[usize; 3]; 20] = [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        let mut tris: Vec<[DVec3; 3]> = F.iter().map(|f| f.map(|i| v[i])).collect();
        for _ in 0..level {
            tris = tris
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (
                        (a + b).normalize(),
                        (b + c).normalize(),
                        (c + a).normalize(),
                    );
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        let centres = tris
            .iter()
            .map(|[a, b, c]| (*a + *b + *c).normalize())
            .collect();
        Icosphere { tris, centres }
    }
}

impl SphereGrid for Icosphere {
    fn len(&self) -> usize {
        self.tris.len()
    }

    fn direction(&self, cell: usize) -> DVec3 {
        self.centres[cell]
    }

    fn area(&self, cell: usize) -> f64 {
        // Van Oosterom–Strackee solid angle of a spherical triangle.
        let [a, b, c] = self.tris[cell];
        let num = a.dot(b.cross(c)).abs();
        let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
        2.0 * num.atan2(den)
    }

    fn cell_of(&self, d: DVec3) -> usize {
        // The cell whose three great-circle edges all have d on their inner side;
        // the nearest centre when rounding leaves d on no cell.
        let inside = |&[a, b, c]: &[DVec3; 3]| {
            let e = -1e-12;
            a.cross(b).dot(d) >= e
                && b.cross(c).dot(d) >= e
                && c.cross(a).dot(d) >= e
                && (a + b + c).dot(d) > 0.0
        };
        self.tris.iter().position(inside).unwrap_or_else(|| {
            (0..self.centres.len())
                .max_by(|&i, &j| self.centres[i].dot(d).total_cmp(&self.centres[j].dot(d)))
                .unwrap_or(0)
        })
    }

    fn name(&self) -> String {
        format!("icosphere {}", self.tris.len())
    }
}

/// HEALPix (Górski et al. 2005), ring ordering: 12·N² equal-area cells on 4N − 1
/// rings of constant latitude. N = 10 gives 1200 cells of about 5.9°.
#[derive(Clone, Copy, Debug)]
pub struct Healpix {
    pub nside: usize,
}

impl SphereGrid for Healpix {
    fn len(&self) -> usize {
        12 * self.nside * self.nside
    }

    fn direction(&self, cell: usize) -> DVec3 {
        let n = self.nside as f64;
        let ns = self.nside;
        let npix = self.len();
        let cap = 2 * ns * (ns - 1);
        let (z, phi) = if cell < cap {
            // North polar cap: ring i has 4i cells and starts at 2i(i − 1).
            let i = ((1.0 + (1.0 + 2.0 * cell as f64).sqrt()) / 2.0).floor() as usize;
            let i = if 2 * i * (i - 1) > cell { i - 1 } else { i };
            let j = cell - 2 * i * (i - 1);
            let i_f = i as f64;
            (
                1.0 - i_f * i_f / (3.0 * n * n),
                (j as f64 + 0.5) * PI / (2.0 * i_f),
            )
        } else if cell < npix - cap {
            let k = cell - cap;
            let i = k / (4 * ns) + ns;
            let j = k % (4 * ns);
            // Rings alternate between cells starting at φ = 0 and half a cell off.
            let s = ((i - ns + 1) % 2) as f64;
            (
                4.0 / 3.0 - 2.0 * i as f64 / (3.0 * n),
                (j as f64 + 1.0 - s / 2.0) * PI / (2.0 * n),
            )
        } else {
            // South polar cap, mirrored: ring i' from the south pole.
            let k = npix - 1 - cell;
            let i = ((1.0 + (1.0 + 2.0 * k as f64).sqrt()) / 2.0).floor() as usize;
            let i = if 2 * i * (i - 1) > k { i - 1 } else { i };
            let j = 4 * i - 1 - (k - 2 * i * (i - 1));
            let i_f = i as f64;
            (
                -(1.0 - i_f * i_f / (3.0 * n * n)),
                (j as f64 + 0.5) * PI / (2.0 * i_f),
            )
        };
        let st = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(st * phi.cos(), st * phi.sin(), z)
    }

    fn area(&self, _cell: usize) -> f64 {
        4.0 * PI / self.len() as f64
    }

    fn cell_of(&self, d: DVec3) -> usize {
        let ns = self.nside;
        let n = ns as f64;
        let z = d.z.clamp(-1.0, 1.0);
        let za = z.abs();
        let tt = (d.y.atan2(d.x).rem_euclid(TAU) / (PI / 2.0)).min(4.0 - 1e-15);
        if za <= 2.0 / 3.0 {
            let t1 = n * (0.5 + tt);
            let t2 = n * z * 0.75;
            let jp = (t1 - t2).floor() as i64;
            let jm = (t1 + t2).floor() as i64;
            let ir = ns as i64 + 1 + jp - jm; // 1 ..= 2N + 1, from z = 2/3 down
            let kshift = 1 - (ir & 1);
            let ip = ((jp + jm - ns as i64 + kshift + 1) / 2).rem_euclid(4 * ns as i64);
            (2 * ns * (ns - 1)) + (ir as usize - 1) * 4 * ns + ip as usize
        } else {
            let tp = tt - tt.floor();
            let tmp = n * (3.0 * (1.0 - za)).sqrt();
            let jp = (tp * tmp).floor() as usize;
            let jm = ((1.0 - tp) * tmp).floor() as usize;
            let ir = (jp + jm + 1).min(ns); // ring from the nearer pole
            let ip = ((tt * ir as f64).floor() as usize).min(4 * ir - 1);
            if z > 0.0 {
                2 * ir * (ir - 1) + ip
            } else {
                self.len() - 2 * ir * (ir + 1) + ip
            }
        }
    }

    fn name(&self) -> String {
        format!("healpix N={} ({} cells)", self.nside, self.len())
    }
}

/// One bitset of grid cells per facet.
#[derive(Clone, Debug, PartialEq)]
pub struct CellSets {
    pub cells: usize,
    words: usize,
    bits: Vec<u64>,
}

impl CellSets {
    pub fn new(sets: usize, cells: usize) -> CellSets {
        let words = cells.div_ceil(64);
        CellSets {
            cells,
            words,
            bits: vec![0; sets * words],
        }
    }

    pub fn len(&self) -> usize {
        self.bits.len().checked_div(self.words).unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn set(&self, i: usize) -> &[u64] {
        &self.bits[i * self.words..(i + 1) * self.words]
    }

    /// Copies set `j` of `from` (over the same grid) into set `i`.
    pub fn copy_from(&mut self, i: usize, from: &CellSets, j: usize) {
        let w = self.words;
        self.bits[i * w..(i + 1) * w].copy_from_slice(from.set(j));
    }

    pub fn contains(&self, i: usize, cell: usize) -> bool {
        self.set(i)[cell / 64] >> (cell % 64) & 1 == 1
    }

    pub fn count(&self, i: usize) -> usize {
        self.set(i).iter().map(|w| w.count_ones() as usize).sum()
    }

    pub fn cells_of(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.set(i).iter().enumerate().flat_map(|(k, &w)| {
            let mut b = w;
            std::iter::from_fn(move || {
                (b != 0).then(|| {
                    let c = k * 64 + b.trailing_zeros() as usize;
                    b &= b - 1;
                    c
                })
            })
        })
    }
}

/// One cell bitset over a grid (for example a machine's reachable directions).
pub fn cell_mask(grid: &dyn SphereGrid, keep: impl Fn(DVec3) -> bool) -> Vec<u64> {
    let mut m = vec![0u64; grid.len().div_ceil(64)];
    for c in 0..grid.len() {
        if keep(grid.direction(c)) {
            m[c / 64] |= 1 << (c % 64);
        }
    }
    m
}

/// Line-of-sight point visibility cones of all facets. A direction d is in
/// facet t's cone when d·n_t > sin(clearance) and the ray from t's centroid
/// (lifted by a hair along n_t) along d meets no other triangle. Zero-area
/// facets get an empty cone.
pub fn visibility(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
) -> CellSets {
    visibility_with_progress(mesh, bvh, grid, clearance_deg, &|_, _| {})
}

/// A progress callback: `(done, total)` steps of the work, called from any
/// thread.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// [`visibility`], calling `progress(done, total)` as facets are decided.
pub fn visibility_with_progress(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    progress: Progress,
) -> CellSets {
    let test = DirectionTest::sight(mesh, bvh, clearance_deg);
    cones(
        mesh,
        grid,
        clearance_deg,
        |_, _, _| true,
        |t, p, n, d| test.clear(t, p, n, d),
        progress,
    )
}

/// Counts finished steps and reports them every 1/256 of `total` and at the end.
struct Counter<'a> {
    done: std::sync::atomic::AtomicUsize,
    total: usize,
    every: usize,
    progress: Progress<'a>,
}

impl<'a> Counter<'a> {
    fn new(total: usize, progress: Progress<'a>) -> Counter<'a> {
        Counter {
            done: std::sync::atomic::AtomicUsize::new(0),
            total,
            every: (total / 256).max(1),
            progress,
        }
    }

    fn step(&self) {
        let k = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if k.is_multiple_of(self.every) || k == self.total {
            (self.progress)(k, self.total);
        }
    }
}

/// The cones of all facets: cell d is in facet t's cone when d·n_t >
/// sin(clearance) and `free(t, centroid, n_t, d)`; a facet for which
/// `usable(t, centroid, n_t)` is false, or with zero area, gets an empty cone.
fn cones(
    mesh: &TriMesh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    usable: impl Fn(usize, DVec3, DVec3) -> bool + Sync,
    free: impl Fn(usize, DVec3, DVec3, DVec3) -> bool + Sync,
    progress: Progress,
) -> CellSets {
    let counter = Counter::new(mesh.len(), progress);
    let cells = grid.len();
    let dirs: Vec<DVec3> = (0..cells).map(|c| grid.direction(c)).collect();
    let min_dot = clearance_deg.to_radians().sin();
    let mut out = CellSets::new(mesh.len(), cells);
    let words = out.words;
    out.bits
        .par_chunks_mut(words.max(1))
        .enumerate()
        .for_each(|(t, set)| {
            counter.step();
            let n = mesh.facet_normal(t);
            let [a, b, c] = mesh.corners(t);
            let p = (a + b + c) / 3.0;
            if n == DVec3::ZERO || !usable(t, p, n) {
                return;
            }
            for (k, d) in dirs.iter().enumerate() {
                if d.dot(n) > min_dot && free(t, p, n, *d) {
                    set[k / 64] |= 1 << (k % 64);
                }
            }
        });
    out
}

/// A ball-end mill with its shank and holder as two coaxial cylinders (capsules)
/// for accessibility in tool mode. Lengths are measured from the ball centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolModel {
    /// Ball (and shank) radius, mm.
    pub radius: f64,
    /// From the ball centre to the holder's face, mm.
    pub reach: f64,
    /// Holder radius, mm (0: no holder).
    pub holder_radius: f64,
    /// Holder length beyond `reach`, mm.
    pub holder_length: f64,
}

/// Tool-mode accessibility of all facets: direction d is in facet t's set when
/// d·n_t > sin(clearance) and the tool with its ball touching t's centroid
/// (ball centre on the facet normal) and its axis along d touches no part of
/// the mesh except where the ball already touches (a tolerance of 0.1 % of the
/// radius absorbs the tessellation).
///
/// Decided per direction over the whole part at once: the mesh seen along d
/// is rasterised twice (cells of 1/6 of the shank's and of the holder's
/// radius), each cell holding the greatest depth along d of any point of the
/// mesh over it and of any vertex in it. Where no point within a capsule's
/// radius of the axis lies above the capsule's base, the capsule is proven
/// free (the ball itself was tested free beforehand); where a vertex lies
/// inside a capsule's cylinder, it is proven blocked; the exact capsule tests
/// decide the rest. So the answer is the exact test's, every one
/// ([`accessibility_exact`] is the reference), in a fraction of the time.
pub fn accessibility(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    tool: &ToolModel,
) -> CellSets {
    accessibility_with_progress(mesh, bvh, grid, clearance_deg, tool, &|_, _| {})
}

/// [`accessibility`], calling `progress(done, total)` as facets (few
/// triangles) or groups of 64 directions (depth maps) are decided.
pub fn accessibility_with_progress(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    tool: &ToolModel,
    progress: Progress,
) -> CellSets {
    // On few triangles the capsule tests are cheap and the maps not.
    if mesh.len() < MAPS_FROM {
        exact(mesh, bvh, grid, clearance_deg, tool, progress)
    } else {
        accessibility_mapped(mesh, bvh, grid, clearance_deg, tool, progress)
    }
}

/// Meshes of at least this many triangles are decided by depth maps first.
const MAPS_FROM: usize = 4096;

/// [`accessibility`] by depth maps first, whatever the size of the mesh.
fn accessibility_mapped(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    tool: &ToolModel,
    progress: Progress,
) -> CellSets {
    let test = DirectionTest::tool(mesh, bvh, clearance_deg, tool);
    let cells = grid.len();
    let mut out = CellSets::new(mesh.len(), cells);
    let words = out.words;
    let counter = Counter::new(words, progress);
    // Per facet: centroid, normal, ball centre; `None` when it cannot be served.
    let facets: Vec<Option<(DVec3, DVec3)>> = (0..mesh.len())
        .into_par_iter()
        .map(|t| {
            let (p, n) = test.facet(t)?;
            test.usable_at(t, p, n).then_some((p, n))
        })
        .collect();
    let mut used = vec![false; mesh.vertices.len()];
    for tri in &mesh.triangles {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    let verts: Vec<DVec3> = mesh
        .vertices
        .iter()
        .zip(&used)
        .filter(|(_, u)| **u)
        .map(|(v, _)| *v)
        .collect();
    let dirs: Vec<DVec3> = (0..cells).map(|c| grid.direction(c)).collect();
    // One word of 64 directions at a time: their views side by side, then
    // the facets in chunks, so that both cores stay busy to the end (the
    // cost of a facet varies tenfold with its slope and neighbourhood).
    for (w, word) in dirs.chunks(64).enumerate() {
        let views: Vec<ToolView> = word
            .par_iter()
            .map(|&d| ToolView::new(mesh, &verts, d, tool, test.tol()))
            .collect();
        let col: Vec<u64> = facets
            .par_iter()
            .with_min_len(256)
            .map(|f| {
                let Some((p, n)) = *f else { return 0 };
                let mut bits = 0u64;
                let mut hints = Hints::default();
                for (k, view) in views.iter().enumerate() {
                    if view.d.dot(n) > test.min_dot && view.free(&test, p, n, &mut hints) {
                        bits |= 1 << k;
                    }
                }
                bits
            })
            .collect();
        for (t, bits) in col.into_iter().enumerate() {
            out.bits[t * words + w] = bits;
        }
        counter.step();
    }
    out
}

/// The plain tool-mode accessibility, every direction of every facet by the
/// exact capsule tests: the reference for [`accessibility`].
pub fn accessibility_exact(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    tool: &ToolModel,
) -> CellSets {
    exact(mesh, bvh, grid, clearance_deg, tool, &|_, _| {})
}

fn exact(
    mesh: &TriMesh,
    bvh: &Bvh,
    grid: &dyn SphereGrid,
    clearance_deg: f64,
    tool: &ToolModel,
    progress: Progress,
) -> CellSets {
    let test = DirectionTest::tool(mesh, bvh, clearance_deg, tool);
    cones(
        mesh,
        grid,
        clearance_deg,
        |t, p, n| test.usable_at(t, p, n),
        |t, p, n, d| test.clear(t, p, n, d),
        progress,
    )
}

/// The mesh seen along one tool direction, rasterised on the plane across
/// it: what proves a tool position free or blocked without the capsule tests.
struct ToolView {
    d: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// The ball's radius (its centre stands this far off the facet), mm.
    radius: f64,
    /// The radius of the shank's capsule (the ball's, less the tolerance), mm.
    shank_radius: f64,
    reach: f64,
    /// The holder's radius and length, when there is one.
    holder: Option<(f64, f64)>,
    shank: DepthMap,
    holder_map: Option<DepthMap>,
    /// Margin of the depth comparisons (rounding), mm.
    eps: f64,
}

/// Cells of a depth map across a capsule's radius.
const CELLS_PER_RADIUS: f64 = 8.0;

/// Cells of a depth map across the part, at most (about).
const MAP_CELLS: f64 = 256.0;

/// Depths along the view direction over square cells of the plane across it.
struct DepthMap {
    h: f64,
    u0: f64,
    v0: f64,
    nu: usize,
    nv: usize,
    /// Greatest depth of any mesh point within `radius` (across the axis) of
    /// any point of the cell.
    near: Vec<f64>,
    /// Greatest depth of a mesh vertex lying, wherever in the cell the axis
    /// passes, within `radius` of it.
    inside: Vec<f64>,
}

impl DepthMap {
    /// The map for capsules of `radius` about axes along the view: triangles
    /// `tris` over points projected to `proj` = (u, v, depth), the vertices
    /// of the mesh (those of its triangles only) projected to `verts`, all of
    /// them within `lo`..`hi` across the view.
    fn new(
        tris: &[[u32; 3]],
        proj: &[(f64, f64, f64)],
        verts: &[(f64, f64, f64)],
        (lo, hi): ((f64, f64), (f64, f64)),
        radius: f64,
    ) -> DepthMap {
        // Proving free takes a window a hair wider than the radius, proving
        // blocked one a hair narrower: rounding never decides.
        let (outer, inner) = (radius * (1.0 + 1e-9), radius * (1.0 - 1e-9));
        // At most about MAP_CELLS cells across the part.
        let h = (radius / CELLS_PER_RADIUS).max((hi.0 - lo.0).max(hi.1 - lo.1) / MAP_CELLS);
        let u0 = lo.0 - outer - h;
        let v0 = lo.1 - outer - h;
        let nu = (((hi.0 + outer + h - u0) / h).ceil() as usize).max(1);
        let nv = (((hi.1 + outer + h - v0) / h).ceil() as usize).max(1);
        let mut all = vec![f64::NEG_INFINITY; nu * nv];
        let mut vert = vec![f64::NEG_INFINITY; nu * nv];
        // The cast truncates, which is the floor for the non-negative values
        // it gets (a call to floor is a library call on the baseline target).
        let cell = |u: f64, v: f64| {
            (
                (((u - u0) / h).max(0.0) as usize).min(nu - 1),
                (((v - v0) / h).max(0.0) as usize).min(nv - 1),
            )
        };
        for &(u, v, z) in verts {
            let (i, j) = cell(u, v);
            let x = &mut vert[j * nu + i];
            *x = x.max(z);
        }
        // Every point of a triangle projects into its box and lies no deeper
        // than its deepest corner.
        for tri in tris {
            let [a, b, c] = tri.map(|k| proj[k as usize]);
            let (i0, j0) = cell(a.0.min(b.0).min(c.0), a.1.min(b.1).min(c.1));
            let (i1, j1) = cell(a.0.max(b.0).max(c.0), a.1.max(b.1).max(c.1));
            let z = a.2.max(b.2).max(c.2);
            for j in j0..=j1 {
                for x in &mut all[j * nu + i0..=j * nu + i1] {
                    *x = x.max(z);
                }
            }
        }
        // For an axis anywhere in cell (i, j): the cells (i + di, j + dj)
        // that come within `outer` of some point of it, and those all of
        // whose points lie within `inner` of every point of it.
        let (ro, ri) = (outer / h, inner / h);
        let k = ro.ceil() as i64 + 1;
        let reach = |dj: i64, near: bool| -> Option<usize> {
            (0..=k)
                .rev()
                .find(|&di| {
                    if near {
                        let (a, b) = ((di - 1).max(0) as f64, (dj.abs() - 1).max(0) as f64);
                        a * a + b * b <= ro * ro
                    } else {
                        let (a, b) = ((di + 1) as f64, (dj.abs() + 1) as f64);
                        a * a + b * b < ri * ri
                    }
                })
                .map(|di| di as usize)
        };
        let near_w: Vec<(i64, usize)> = (-k..=k)
            .filter_map(|dj| reach(dj, true).map(|w| (dj, w)))
            .collect();
        let inside_w: Vec<(i64, usize)> = (-k..=k)
            .filter_map(|dj| reach(dj, false).map(|w| (dj, w)))
            .collect();
        DepthMap {
            h,
            u0,
            v0,
            nu,
            nv,
            near: disc_max(&all, nu, nv, &near_w),
            inside: disc_max(&vert, nu, nv, &inside_w),
        }
    }

    fn at(&self, u: f64, v: f64) -> Option<usize> {
        // Non-negative, so the truncating cast is the floor.
        let i = (u - self.u0) / self.h;
        let j = (v - self.v0) / self.h;
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.nu && (j as usize) < self.nv)
            .then(|| j as usize * self.nu + i as usize)
    }
}

/// The greatest value over a window given by rows: `rows` holds (dj, w),
/// the cells (i + di, j + dj) with |di| ≤ w; an empty window gives −∞.
fn disc_max(src: &[f64], nu: usize, nv: usize, rows: &[(i64, usize)]) -> Vec<f64> {
    let mut out = vec![f64::NEG_INFINITY; src.len()];
    let mut widths: Vec<usize> = rows.iter().map(|r| r.1).collect();
    widths.sort_unstable();
    widths.dedup();
    // One buffer for the running maxima and one for the suffix maxima,
    // reused for every width and row (no allocation per row).
    let mut run = vec![f64::NEG_INFINITY; src.len()];
    let mut suffix = vec![f64::NEG_INFINITY; nu];
    for w in widths {
        // Each row's running maximum over 2w + 1 cells, then into every
        // output row that takes this width at its offset.
        for (s, r) in src.chunks_exact(nu).zip(run.chunks_exact_mut(nu)) {
            window_max(s, r, w, &mut suffix);
        }
        for &(dj, _) in rows.iter().filter(|r| r.1 == w) {
            // Output row j takes run row j + dj where that exists.
            let (j0, j1) = (
                (-dj).clamp(0, nv as i64) as usize,
                (nv as i64 - dj).clamp(0, nv as i64) as usize,
            );
            for j in j0..j1 {
                let f = (j as i64 + dj) as usize;
                for (o, r) in out[j * nu..(j + 1) * nu]
                    .iter_mut()
                    .zip(&run[f * nu..(f + 1) * nu])
                {
                    *o = o.max(*r);
                }
            }
        }
    }
    out
}

/// dst[i] = max of src[i − k ..= i + k] (van Herk / Gil–Werman: blocks of
/// 2k + 1, prefix and suffix maxima). `suffix` is scratch space (resized to
/// the row); the prefix maxima are built in `dst` itself, each read at or
/// after the position being written.
fn window_max(src: &[f64], dst: &mut [f64], k: usize, suffix: &mut Vec<f64>) {
    let n = src.len();
    if k == 0 || n == 0 {
        dst.copy_from_slice(src);
        return;
    }
    let b = 2 * k + 1;
    suffix.resize(n, f64::NEG_INFINITY);
    let suf = &mut suffix[..n];
    // Prefix maxima within each block of b cells, in dst.
    for (pre, s) in dst.chunks_mut(b).zip(src.chunks(b)) {
        let mut m = f64::NEG_INFINITY;
        for (p, x) in pre.iter_mut().zip(s) {
            m = m.max(*x);
            *p = m;
        }
    }
    // Suffix maxima within each block.
    for (su, s) in suf.chunks_mut(b).zip(src.chunks(b)) {
        let mut m = f64::NEG_INFINITY;
        for (p, x) in su.iter_mut().zip(s).rev() {
            m = m.max(*x);
            *p = m;
        }
    }
    for i in 0..n {
        let lo = i.saturating_sub(k);
        let hi = (i + k).min(n - 1);
        // A window within one block starts it (at the first cell) or ends it
        // (at the last); otherwise it spans one block boundary. dst[hi]
        // (hi ≥ i) still holds its prefix maximum.
        dst[i] = if lo / b != hi / b {
            suf[lo].max(dst[hi])
        } else if lo % b == 0 {
            dst[hi]
        } else {
            suf[lo]
        };
    }
}

impl ToolView {
    fn new(mesh: &TriMesh, verts: &[DVec3], d: DVec3, tool: &ToolModel, tol: f64) -> ToolView {
        let (e1, e2) = d.any_orthonormal_pair();
        let proj_of = |x: &DVec3| (x.dot(e1), x.dot(e2), x.dot(d));
        let all: Vec<(f64, f64, f64)> = mesh.vertices.iter().map(proj_of).collect();
        let vproj: Vec<(f64, f64, f64)> = verts.iter().map(proj_of).collect();
        let mut span = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for &(u, v, _) in &vproj {
            span.0 = (span.0 .0.min(u), span.0 .1.min(v));
            span.1 = (span.1 .0.max(u), span.1 .1.max(v));
        }
        let b = mesh.bounds();
        let scale = b.diagonal().max(1.0) + b.min.abs().max(b.max.abs()).max_element();
        let holder = (tool.holder_radius > 0.0 && tool.holder_length > 0.0)
            .then_some((tool.holder_radius, tool.holder_length));
        let map = |radius: f64| DepthMap::new(&mesh.triangles, &all, &vproj, span, radius);
        ToolView {
            d,
            e1,
            e2,
            radius: tool.radius,
            shank_radius: tool.radius - tol,
            reach: tool.reach,
            holder,
            shank: map(tool.radius - tol),
            holder_map: holder.map(|(hr, _)| map(hr)),
            eps: 1e-9 * scale,
        }
    }

    /// Whether the tool touching a facet at centroid p (normal n) along this
    /// direction is free: by the maps where they prove it either way, else by
    /// the capsule tests of what they leave open. The ball must have been
    /// tested free.
    ///
    /// `hints` carry the triangles that last blocked the holder and the
    /// shank for this facet: neighbouring directions are often blocked by
    /// the same one, which is then tried first (the answer is the same).
    fn free(&self, test: &DirectionTest, p: DVec3, n: DVec3, hints: &mut Hints) -> bool {
        let centre = p + n * self.radius;
        let (u, v) = (centre.dot(self.e1), centre.dot(self.e2));
        let base = centre.dot(self.d);
        let top = base + self.reach;
        let eps = self.eps;
        let shank_at = self.shank.at(u, v);
        // A vertex inside the shank's cylinder.
        if shank_at.is_some_and(|s| {
            let x = self.shank.inside[s];
            x > base + eps && x < top - eps
        }) {
            return false;
        }
        let holder_free = match (&self.holder_map, self.holder) {
            (Some(m), Some((hr, hl))) => {
                let c = m.at(u, v);
                // A vertex inside the holder's cylinder.
                if c.is_some_and(|c| {
                    let x = m.inside[c];
                    x > top + eps && x < top + hl - eps
                }) {
                    return false;
                }
                // Nothing within its radius above its lowest point.
                c.is_some_and(|c| m.near[c] < top - hr - eps)
            }
            _ => true,
        };
        // Nothing within the shank's radius above the ball's centre.
        let near = shank_at.map(|s| self.shank.near[s]);
        let shank_free = near.is_some_and(|z| z < base - eps);
        // The holder's test first: it is the quicker, and often blocked.
        if !(holder_free || test.holder_clear_from(p, n, self.d, &mut hints.holder)) {
            return false;
        }
        if shank_free {
            return true;
        }
        // The shank's capsule is the union of the capsules over two pieces
        // of its axis, split at `s` from the ball's centre. Every point of
        // the upper one lies within the shank's radius of the axis and
        // deeper than base + s − radius: above the deepest mesh point within
        // that radius when s is chosen so, and the map then proves it free.
        // Only the lower, short piece needs the capsule test; it meets the
        // mesh only where the whole shank does.
        if let Some(z) = near {
            let s = z - base + self.shank_radius + 4.0 * eps;
            if s < 0.75 * self.reach {
                return test.shank_piece_clear(p, n, self.d, s, &mut hints.shank);
            }
        }
        test.shank_clear_from(p, n, self.d, &mut hints.shank)
    }
}

/// The triangles that last blocked the holder and the shank of one facet's
/// tool ([`Bvh::capsule_hits_above_from`]).
#[derive(Default)]
struct Hints {
    holder: Option<CapsuleHit>,
    shank: Option<CapsuleHit>,
}

/// The test the cones are made of, for any direction: whether a direction
/// leaves a facet by more than the clearance angle and is free (line of
/// sight, or the tool in tool mode). The setup search refines directions
/// between the grid's cells with it: a direction counts only once this test
/// has passed it.
pub struct DirectionTest<'a> {
    mesh: &'a TriMesh,
    bvh: &'a Bvh,
    min_dot: f64,
    mode: TestMode,
}

enum TestMode {
    /// The ray from the centroid, lifted by `lift` along the normal.
    Sight { lift: f64 },
    /// The ball, shank and holder; capsules shrunk by `tol`.
    Tool { tool: ToolModel, tol: f64 },
}

impl<'a> DirectionTest<'a> {
    /// Line of sight.
    pub fn sight(mesh: &'a TriMesh, bvh: &'a Bvh, clearance_deg: f64) -> DirectionTest<'a> {
        DirectionTest {
            mesh,
            bvh,
            min_dot: clearance_deg.to_radians().sin(),
            mode: TestMode::Sight {
                lift: 1e-7 * mesh.bounds().diagonal().max(1e-9),
            },
        }
    }

    /// Tool mode.
    pub fn tool(
        mesh: &'a TriMesh,
        bvh: &'a Bvh,
        clearance_deg: f64,
        tool: &ToolModel,
    ) -> DirectionTest<'a> {
        DirectionTest {
            mesh,
            bvh,
            min_dot: clearance_deg.to_radians().sin(),
            mode: TestMode::Tool {
                tool: *tool,
                tol: 1e-3 * tool.radius + 1e-7 * mesh.bounds().diagonal(),
            },
        }
    }

    /// The tolerance the tool's capsules are shrunk by (0 in line of sight), mm.
    fn tol(&self) -> f64 {
        match &self.mode {
            TestMode::Sight { .. } => 0.0,
            TestMode::Tool { tol, .. } => *tol,
        }
    }

    /// sin(clearance): a direction must leave a facet by more than this (d·n).
    pub fn min_dot(&self) -> f64 {
        self.min_dot
    }

    /// Centroid and unit normal of facet t (`None` for a zero-area facet).
    pub fn facet(&self, t: usize) -> Option<(DVec3, DVec3)> {
        let n = self.mesh.facet_normal(t);
        let [a, b, c] = self.mesh.corners(t);
        (n != DVec3::ZERO).then(|| ((a + b + c) / 3.0, n))
    }

    /// Whether unit direction `d` is in facet t's cone.
    pub fn free(&self, t: usize, d: DVec3) -> bool {
        let Some((p, n)) = self.facet(t) else {
            return false;
        };
        d.dot(n) > self.min_dot && self.usable_at(t, p, n) && self.clear(t, p, n, d)
    }

    /// Whether facet t can be served at all: in tool mode, whether the ball
    /// touching its centroid is free whatever the direction.
    fn usable_at(&self, _t: usize, p: DVec3, n: DVec3) -> bool {
        match &self.mode {
            TestMode::Sight { .. } => true,
            TestMode::Tool { tool, tol, .. } => {
                let c = p + n * tool.radius;
                !self.bvh.capsule_hits(c, c, tool.radius - tol, None)
            }
        }
    }

    /// Whether direction d from facet t (centroid p, normal n) meets nothing.
    fn clear(&self, t: usize, p: DVec3, n: DVec3, d: DVec3) -> bool {
        match &self.mode {
            TestMode::Sight { lift } => {
                !self
                    .bvh
                    .occluded(p + n * *lift, d, f64::INFINITY, Some(t as u32))
            }
            TestMode::Tool { .. } => self.shank_clear(p, n, d) && self.holder_clear(p, n, d),
        }
    }

    /// Tool mode: whether the shank along d, the ball touching centroid p
    /// (normal n), meets nothing. Behind the plane through the ball's centre
    /// across the axis the shank reaches no farther than the ball, checked
    /// free on its own.
    fn shank_clear(&self, p: DVec3, n: DVec3, d: DVec3) -> bool {
        self.shank_clear_from(p, n, d, &mut None)
    }

    /// [`shank_clear`](Self::shank_clear), `hint` as in
    /// [`Bvh::capsule_hits_above_from`].
    fn shank_clear_from(
        &self,
        p: DVec3,
        n: DVec3,
        d: DVec3,
        hint: &mut Option<CapsuleHit>,
    ) -> bool {
        let TestMode::Tool { tool, tol, .. } = &self.mode else {
            return true;
        };
        let centre = p + n * tool.radius;
        let top = centre + d * tool.reach;
        !self.bvh.capsule_hits_above_from(
            centre,
            top,
            tool.radius - tol,
            None,
            Some((d, d.dot(centre))),
            hint,
        )
    }

    /// Tool mode: whether the shank's axis from the ball's centre up to
    /// `s` (< the reach) along d, with the shank's radius about it, meets
    /// nothing: the lower piece of [`shank_clear`](Self::shank_clear).
    /// `hint` as in [`Bvh::capsule_hits_above_from`].
    fn shank_piece_clear(
        &self,
        p: DVec3,
        n: DVec3,
        d: DVec3,
        s: f64,
        hint: &mut Option<CapsuleHit>,
    ) -> bool {
        let TestMode::Tool { tool, tol, .. } = &self.mode else {
            return true;
        };
        let centre = p + n * tool.radius;
        !self.bvh.capsule_hits_above_from(
            centre,
            centre + d * s.clamp(0.0, tool.reach),
            tool.radius - tol,
            None,
            Some((d, d.dot(centre))),
            hint,
        )
    }

    /// Tool mode: whether the holder meets nothing (nothing below its lowest
    /// point can touch it).
    fn holder_clear(&self, p: DVec3, n: DVec3, d: DVec3) -> bool {
        self.holder_clear_from(p, n, d, &mut None)
    }

    /// [`holder_clear`](Self::holder_clear), `hint` as in
    /// [`Bvh::capsule_hits_above_from`].
    fn holder_clear_from(
        &self,
        p: DVec3,
        n: DVec3,
        d: DVec3,
        hint: &mut Option<CapsuleHit>,
    ) -> bool {
        let TestMode::Tool { tool, .. } = &self.mode else {
            return true;
        };
        let (hr, hl) = (tool.holder_radius, tool.holder_length);
        if hr <= 0.0 || hl <= 0.0 {
            return true;
        }
        let top = p + n * tool.radius + d * tool.reach;
        !self.bvh.capsule_hits_above_from(
            top,
            top + d * hl,
            hr,
            None,
            Some((d, d.dot(top) - hr)),
            hint,
        )
    }
}

/// The directions, in part coordinates, that a machine reaches with the part
/// clamped in setup `setup` (part frame → table frame): cell d is reachable when
/// `setup·d` has an inverse-kinematics solution inside the rotary limits.
pub fn reachable(grid: &dyn SphereGrid, machine: &Kinematics, setup: DMat3) -> Vec<u64> {
    cell_mask(grid, |d| machine.reaches(setup * d))
}

/// Facets whose cone has no cell in `mask` (unreachable; facets with empty cones included).
pub fn unreachable(vis: &CellSets, mask: &[u64]) -> Vec<usize> {
    (0..vis.len())
        .filter(|&i| vis.set(i).iter().zip(mask).all(|(a, b)| a & b == 0))
        .collect()
}

/// Per facet, the smallest angle (degrees) between `pole` and a direction of
/// its cone: the tilt a C,A or B,C machine with unlimited C needs there (either
/// tilt sign). `None` for an empty cone.
pub fn required_tilt(vis: &CellSets, grid: &dyn SphereGrid, pole: DVec3) -> Vec<Option<f64>> {
    let cos: Vec<f64> = (0..grid.len())
        .map(|c| grid.direction(c).dot(pole))
        .collect();
    (0..vis.len())
        .into_par_iter()
        .map(|i| {
            vis.cells_of(i)
                .map(|c| cos[c])
                .max_by(f64::total_cmp)
                .map(|m| m.clamp(-1.0, 1.0).acos().to_degrees())
        })
        .collect()
}

/// The best pole among the grid's cell directions for a machine whose C axis is
/// unlimited: the one minimising the largest required tilt over the facets with
/// a non-empty cone, refined by a local search on the sphere. Returns the pole
/// and that tilt in degrees.
pub fn best_pole(vis: &CellSets, grid: &dyn SphereGrid) -> Option<(DVec3, f64)> {
    let live: Vec<usize> = (0..vis.len()).filter(|&i| vis.count(i) > 0).collect();
    if live.is_empty() {
        return None;
    }
    // Facets with the same cone need the same tilt: evaluate each cone once.
    let mut cones: Vec<&[u64]> = live.iter().map(|&i| vis.set(i)).collect();
    cones.sort_unstable();
    cones.dedup();
    let dirs: Vec<DVec3> = (0..grid.len()).map(|c| grid.direction(c)).collect();
    // Hard cones first, so that a pole worse than the best so far is found out
    // after a few cones: order them by their angle to the mean direction.
    let angle_to = |pole: DVec3, cone: &[u64]| {
        let mut best = -1.0f64;
        for (k, word) in cone.iter().enumerate() {
            let mut b = *word;
            while b != 0 {
                best = best.max(dirs[k * 64 + b.trailing_zeros() as usize].dot(pole));
                b &= b - 1;
            }
        }
        best
    };
    let mean = cones
        .iter()
        .map(|c| {
            (0..dirs.len())
                .filter(|&k| c[k / 64] >> (k % 64) & 1 == 1)
                .map(|k| dirs[k])
                .sum::<DVec3>()
        })
        .sum::<DVec3>()
        .normalize_or(DVec3::Z);
    cones.sort_by_cached_key(|c| (angle_to(mean, c) * 1e9) as i64);
    let worst = |pole: DVec3, bound: f64| -> f64 {
        // Largest over cones of the smallest angle to the pole; stops once above
        // `bound`. Cells are visited nearest the pole first, so a cone usually
        // answers at its first few cells.
        let mut by_angle: Vec<(f64, usize)> = dirs
            .iter()
            .enumerate()
            .map(|(c, d)| (d.dot(pole).clamp(-1.0, 1.0).acos(), c))
            .collect();
        by_angle.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut w: f64 = 0.0;
        for cone in &cones {
            let first = by_angle
                .iter()
                .find(|&&(ang, c)| ang > bound || cone[c / 64] >> (c % 64) & 1 == 1);
            let ang = first.map_or(f64::INFINITY, |f| f.0);
            w = w.max(ang);
            if w > bound {
                return w;
            }
        }
        w
    };
    // Ties (common: many poles see every facet) go to the pole nearest +Z, the
    // orientation the part was programmed in.
    let better = |a: (DVec3, f64), b: (DVec3, f64)| {
        if (a.1 - b.1).abs() > 1e-12 {
            a.1 < b.1
        } else {
            a.0.z > b.0.z
        }
    };
    let bound = std::sync::Mutex::new(f64::INFINITY);
    let (mut pole, mut tilt) = dirs
        .par_iter()
        .map(|&d| {
            let b = *bound.lock().unwrap_or_else(|e| e.into_inner());
            let w = worst(d, b + 1e-9);
            let mut g = bound.lock().unwrap_or_else(|e| e.into_inner());
            *g = g.min(w);
            (d, w)
        })
        .reduce_with(|a, b| if better(a, b) { a } else { b })?;
    // Pattern search around the best grid pole with a shrinking step.
    let mut step = (4.0 * PI / grid.len() as f64).sqrt();
    while step > 1e-4 {
        let (u, v) = (pole.any_orthonormal_pair().0, pole.any_orthonormal_pair().1);
        let mut moved = false;
        for k in 0..8 {
            let a = k as f64 * TAU / 8.0;
            let cand = (pole + (u * a.cos() + v * a.sin()) * step.tan()).normalize();
            let w = worst(cand, tilt + 1e-9);
            if better((cand, w), (pole, tilt)) && w <= tilt {
                (pole, tilt, moved) = (cand, w, true);
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    Some((pole, tilt.to_degrees()))
}

/// A rotation taking `pole` to +Z (the setup that puts the pole on the C axis).
pub fn setup_for_pole(pole: DVec3) -> DMat3 {
    let w = pole.normalize();
    let (u, mut v) = w.any_orthonormal_pair();
    if u.cross(v).dot(w) < 0.0 {
        v = -v;
    }
    DMat3::from_cols(u, v, w).transpose()
}

/// Required rotary ranges of a tilt + rotary (C,A) machine: the tilt interval
/// (degrees, holding 0) and the C window (start, length in degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaRanges {
    pub tilt: (f64, f64),
    pub c_start: f64,
    pub c_len: f64,
}

impl CaRanges {
    /// The spec's objective (tilt span + ε)(C span + ε), ε = 1°: never zero.
    pub fn cost(&self) -> f64 {
        (self.tilt.1 - self.tilt.0 + 1.0) * (self.c_len + 1.0)
    }

    /// Whether the direction (tilt, c) lies in these ranges.
    pub fn holds(&self, tilt: f64, c: f64) -> bool {
        tilt >= self.tilt.0 - 1e-9
            && tilt <= self.tilt.1 + 1e-9
            && (c - self.c_start).rem_euclid(360.0) <= self.c_len + 1e-9
    }
}

/// The fast method ("minimally distanced points"): each facet is served by its
/// candidate of least |tilt|; the ranges are then the span of those tilts (with
/// 0) and the smallest arc of their C angles. Each facet's candidates are its
/// (tilt, C) pairs in degrees. `None` when a facet has none.
pub fn ca_ranges_fast(pairs: &[Vec<(f64, f64)>]) -> Option<CaRanges> {
    let mut tilt = (0.0f64, 0.0f64);
    let mut cs = Vec::with_capacity(pairs.len());
    for p in pairs {
        let &(a, c) = p.iter().min_by(|x, y| x.0.abs().total_cmp(&y.0.abs()))?;
        tilt = (tilt.0.min(a), tilt.1.max(a));
        cs.push(c);
    }
    let (c_start, c_len) = min_arc(&cs).unwrap_or((0.0, 0.0));
    Some(CaRanges {
        tilt,
        c_start,
        c_len,
    })
}

/// The exact algorithm on the discretised data (spec §3.2): every tilt interval
/// holding 0 between candidate tilts, and for each the smallest circular C
/// window holding a candidate of every facet inside it; the least cost wins.
/// O(K²·M log M) for K distinct tilts and M pairs: the reference for the fast method.
pub fn ca_ranges_exact(pairs: &[Vec<(f64, f64)>]) -> Option<CaRanges> {
    if pairs.iter().any(|p| p.is_empty()) {
        return None;
    }
    let mut tilts: Vec<f64> = pairs.iter().flatten().map(|p| p.0).chain([0.0]).collect();
    tilts.sort_by(f64::total_cmp);
    tilts.dedup();
    let los: Vec<f64> = tilts.iter().copied().filter(|&a| a <= 0.0).collect();
    let his: Vec<f64> = tilts.iter().copied().filter(|&a| a >= 0.0).collect();
    let mut best: Option<CaRanges> = None;
    for &lo in los.iter().rev() {
        for &hi in &his {
            // A wider tilt span only pays when it narrows C; skip what cannot win.
            if let Some(b) = best {
                if (hi - lo + 1.0) * 1.0 >= b.cost() {
                    break;
                }
            }
            let sets: Vec<Vec<f64>> = pairs
                .iter()
                .map(|p| {
                    p.iter()
                        .filter(|q| q.0 >= lo && q.0 <= hi)
                        .map(|q| q.1)
                        .collect()
                })
                .collect();
            if sets.iter().any(|s| s.is_empty()) {
                continue;
            }
            let Some((c_start, c_len)) = min_window_at(&sets) else {
                continue;
            };
            let cand = CaRanges {
                tilt: (lo, hi),
                c_start,
                c_len,
            };
            if best.is_none_or(|b| cand.cost() < b.cost()) {
                best = Some(cand);
            }
        }
    }
    best
}

/// As [`min_window`], with the window's start angle.
fn min_window_at(sets: &[Vec<f64>]) -> Option<(f64, f64)> {
    if sets.iter().any(|s| s.is_empty()) {
        return None;
    }
    let mut ev: Vec<(f64, usize)> = sets
        .iter()
        .enumerate()
        .flat_map(|(k, s)| s.iter().map(move |&a| (a.rem_euclid(360.0), k)))
        .collect();
    ev.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = ev.len();
    let all: Vec<(f64, usize)> = ev
        .iter()
        .copied()
        .chain(ev.iter().map(|&(a, k)| (a + 360.0, k)))
        .collect();
    let mut have = vec![0usize; sets.len()];
    let (mut covered, mut lo) = (0, 0);
    let mut best: Option<(f64, f64)> = None;
    for hi in 0..all.len() {
        let k = all[hi].1;
        if have[k] == 0 {
            covered += 1;
        }
        have[k] += 1;
        while covered == sets.len() {
            if lo < n && best.is_none_or(|b| all[hi].0 - all[lo].0 < b.1) {
                best = Some((all[lo].0, all[hi].0 - all[lo].0));
            }
            let k = all[lo].1;
            have[k] -= 1;
            if have[k] == 0 {
                covered -= 1;
            }
            lo += 1;
        }
    }
    best
}

/// The smallest arc (start, length in degrees) of the circle that covers all
/// angles; `None` for no angles.
pub fn min_arc(angles: &[f64]) -> Option<(f64, f64)> {
    let mut a: Vec<f64> = angles.iter().map(|x| x.rem_euclid(360.0)).collect();
    a.sort_by(f64::total_cmp);
    let n = a.len();
    if n == 0 {
        return None;
    }
    // The arc leaves out the largest gap between neighbours.
    let (gap, start) = (0..n)
        .map(|i| {
            let next = if i + 1 < n { a[i + 1] } else { a[0] + 360.0 };
            (next - a[i], a[(i + 1) % n])
        })
        .max_by(|x, y| x.0.total_cmp(&y.0))?;
    Some((start, 360.0 - gap))
}

/// The length (degrees) of the smallest circular window that holds at least one
/// angle of every set (spec §3.2 step 3): a sliding window over the merged sorted
/// angles, unrolled once around the circle. `None` when a set is empty.
pub fn min_window(sets: &[Vec<f64>]) -> Option<f64> {
    if sets.is_empty() {
        return Some(0.0);
    }
    min_window_at(sets).map(|w| w.1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_models::kinematics::{KinKind, RotaryAxis};

    /// Two triangles of the planar quad abcd, wound so that they face `n`.
    fn quad(soup: &mut Vec<[DVec3; 3]>, q: [[f64; 3]; 4], n: DVec3) {
        let [a, b, c, d] = q.map(DVec3::from_array);
        if (b - a).cross(c - a).dot(n) > 0.0 {
            soup.extend([[a, b, c], [a, c, d]]);
        } else {
            soup.extend([[a, c, b], [a, d, c]]);
        }
    }

    fn mesh(soup: &[[DVec3; 3]]) -> (TriMesh, Bvh) {
        let m = TriMesh::from_soup(soup).0;
        let b = Bvh::build(&m);
        (m, b)
    }

    /// A 40 mm cube standing on the table: five faces, no bottom.
    fn cube() -> Vec<[DVec3; 3]> {
        let s = 40.0;
        let mut t = Vec::new();
        quad(
            &mut t,
            [[0.0, 0.0, s], [s, 0.0, s], [s, s, s], [0.0, s, s]],
            DVec3::Z,
        );
        quad(
            &mut t,
            [[s, 0.0, 0.0], [s, s, 0.0], [s, s, s], [s, 0.0, s]],
            DVec3::X,
        );
        quad(
            &mut t,
            [[0.0, 0.0, 0.0], [0.0, s, 0.0], [0.0, s, s], [0.0, 0.0, s]],
            -DVec3::X,
        );
        quad(
            &mut t,
            [[0.0, s, 0.0], [s, s, 0.0], [s, s, s], [0.0, s, s]],
            DVec3::Y,
        );
        quad(
            &mut t,
            [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, 0.0, s], [0.0, 0.0, s]],
            -DVec3::Y,
        );
        t
    }

    /// A 100 × 80 mm plate facing +Z (two triangles).
    fn plate() -> Vec<[DVec3; 3]> {
        let mut t = Vec::new();
        quad(
            &mut t,
            [
                [0.0, 0.0, 0.0],
                [100.0, 0.0, 0.0],
                [100.0, 80.0, 0.0],
                [0.0, 80.0, 0.0],
            ],
            DVec3::Z,
        );
        t
    }

    /// The inner faces of a closed pocket 2l long (x), 2w wide (y), h deep, open at the top.
    fn pocket(l: f64, w: f64, h: f64) -> Vec<[DVec3; 3]> {
        let mut t = Vec::new();
        quad(
            &mut t,
            [[-l, -w, 0.0], [l, -w, 0.0], [l, w, 0.0], [-l, w, 0.0]],
            DVec3::Z,
        );
        quad(
            &mut t,
            [[-l, w, 0.0], [l, w, 0.0], [l, w, h], [-l, w, h]],
            -DVec3::Y,
        );
        quad(
            &mut t,
            [[-l, -w, 0.0], [l, -w, 0.0], [l, -w, h], [-l, -w, h]],
            DVec3::Y,
        );
        quad(
            &mut t,
            [[l, -w, 0.0], [l, w, 0.0], [l, w, h], [l, -w, h]],
            -DVec3::X,
        );
        quad(
            &mut t,
            [[-l, -w, 0.0], [-l, w, 0.0], [-l, w, h], [-l, -w, h]],
            DVec3::X,
        );
        t
    }

    fn table_ac(a: (f64, f64)) -> Kinematics {
        let mut k = Kinematics::new(KinKind::TableAc);
        k.first = RotaryAxis {
            min: Some(a.0),
            max: Some(a.1),
            sign: 1.0,
        };
        k
    }

    #[test]
    fn grids_tile_the_sphere() {
        // Spec §5 counts: UV 20×30×2 = 1200, icosphere level 3 = 1280.
        let grids: [Box<dyn SphereGrid>; 3] = [
            Box::new(LatLon::PAPER),
            Box::new(Icosphere::new(3)),
            Box::new(Icosphere::new(1)),
        ];
        assert_eq!(
            (grids[0].len(), grids[1].len(), grids[2].len()),
            (1200, 1280, 80)
        );
        for g in &grids {
            let total: f64 = (0..g.len()).map(|c| g.area(c)).sum();
            assert!((total - 4.0 * PI).abs() < 1e-9, "{}: {total}", g.name());
            for c in 0..g.len() {
                assert!((g.direction(c).length() - 1.0).abs() < 1e-12);
                assert_eq!(g.cell_of(g.direction(c)), c, "{} cell {c}", g.name());
            }
        }
        // A brute-force solid angle of one lat-long cell: count fine samples in it.
        let g = LatLon::PAPER;
        let n = 400;
        let mut hits = 0.0;
        for i in 0..n {
            for j in 0..n {
                let th = (i as f64 + 0.5) / n as f64 * PI / 20.0 * 2.0;
                let ph = (j as f64 + 0.5) / n as f64 * TAU / 30.0 * 2.0;
                if g.cell_of(sph(th, ph)) == 2 * (30 + 1) + 1 {
                    hits += th.sin() * (PI / 20.0 * 2.0 / n as f64) * (TAU / 30.0 * 2.0 / n as f64);
                }
            }
        }
        assert!(
            (hits - g.area(63)).abs() < 1e-3 * g.area(63),
            "{hits} vs {}",
            g.area(63)
        );
    }

    #[test]
    fn healpix_cells_have_equal_areas() {
        // Spec §3.3: N_side = 10 gives 1200 equal cells of about 5.86°.
        let g = Healpix { nside: 10 };
        assert!((g.area(0).sqrt().to_degrees() - 5.86).abs() < 0.01);
        // Uniform directions (a Fibonacci lattice) fall evenly into the cells.
        let n = 600_000;
        let mut count = vec![0usize; g.len()];
        for i in 0..n {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let phi = i as f64 * PI * (3.0 - 5f64.sqrt());
            let r = (1.0 - z * z).sqrt();
            count[g.cell_of(DVec3::new(r * phi.cos(), r * phi.sin(), z))] += 1;
        }
        let mean = n as f64 / g.len() as f64;
        for (c, k) in count.iter().enumerate() {
            assert!(
                (*k as f64 - mean).abs() < 0.05 * mean,
                "cell {c}: {k} vs {mean}"
            );
        }
        // The four cells round each pole come first and last.
        assert!(g.cell_of(DVec3::new(1e-3, 1e-3, 1.0).normalize()) < 4);
        assert!(g.cell_of(DVec3::new(1e-3, 1e-3, -1.0).normalize()) >= g.len() - 4);
    }

    #[test]
    fn circle_window_oracles() {
        // Spec §5 "Sphere algorithms".
        let (start, len) = min_arc(&[10.0, 350.0, 20.0, 340.0]).expect("arc");
        assert!((start - 340.0).abs() < 1e-12 && (len - 40.0).abs() < 1e-12);
        let w =
            min_window(&[vec![0.0, 90.0], vec![45.0, 180.0], vec![350.0, 100.0]]).expect("window");
        assert!((w - 55.0).abs() < 1e-12, "{w}");
        let w = min_window(&[
            vec![10.0, 200.0],
            vec![190.0, 20.0],
            vec![100.0, 280.0],
            vec![5.0],
        ])
        .expect("window");
        assert!((w - 95.0).abs() < 1e-12, "{w}");
        assert_eq!(min_window(&[vec![1.0], vec![]]), None);
        // Brute force over window starts at every angle and all lengths.
        let sets: Vec<Vec<f64>> = vec![
            vec![33.0, 250.0],
            vec![300.0],
            vec![12.0, 170.0, 359.0],
            vec![80.0, 90.0],
        ];
        let mut best = f64::INFINITY;
        for s in sets.iter().flatten() {
            let len = sets
                .iter()
                .map(|set| {
                    set.iter()
                        .map(|a| (a - s).rem_euclid(360.0))
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0, f64::max);
            best = best.min(len);
        }
        assert!((min_window(&sets).expect("w") - best).abs() < 1e-12);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

        /// The fast method never calls a machine sufficient that the exact test
        /// (some candidate of every facet inside the ranges) rejects, and the
        /// exact ranges never cost more than the fast ones.
        #[test]
        fn fast_ranges_are_never_optimistic(
            seed in proptest::collection::vec(proptest::collection::vec((-9i32..=12, 0i32..36), 1..6), 1..8),
            box_lo in -90.0..0.0f64, box_hi in 0.0..110.0f64, c0 in 0.0..360.0f64, clen in 0.0..360.0f64,
        ) {
            let pairs: Vec<Vec<(f64, f64)>> = seed.iter().map(|f| f.iter().map(|&(a, c)| (a as f64 * 10.0, c as f64 * 10.0)).collect()).collect();
            let fast = ca_ranges_fast(&pairs).expect("fast");
            let exact = ca_ranges_exact(&pairs).expect("exact");
            proptest::prop_assert!(exact.cost() <= fast.cost() + 1e-9, "{:?} vs {:?}", exact, fast);
            // Both answers serve every facet.
            for r in [fast, exact] {
                proptest::prop_assert!(pairs.iter().all(|p| p.iter().any(|&(a, c)| r.holds(a, c))), "{:?}", r);
            }
            // A machine box: the fast method's "fits" implies the exact test's.
            let machine = CaRanges { tilt: (box_lo, box_hi), c_start: c0, c_len: clen };
            let inside = |r: &CaRanges| machine.tilt.0 <= r.tilt.0 && r.tilt.1 <= machine.tilt.1
                && (r.c_len <= 1e-9 && machine.holds(0.0, r.c_start) || (r.c_start - machine.c_start).rem_euclid(360.0) + r.c_len <= machine.c_len + 1e-9);
            let exact_ok = pairs.iter().all(|p| p.iter().any(|&(a, c)| machine.holds(a, c)));
            if inside(&fast) {
                proptest::prop_assert!(exact_ok);
            }
            // Brute force on the cost: no (tilt interval, C window) from the data does better.
            let mut best = f64::INFINITY;
            let tilts: Vec<f64> = pairs.iter().flatten().map(|p| p.0).chain([0.0]).collect();
            let cs: Vec<f64> = pairs.iter().flatten().map(|p| p.1).collect();
            for &lo in tilts.iter().filter(|&&a| a <= 0.0) {
                for &hi in tilts.iter().filter(|&&a| a >= 0.0) {
                    for &s in &cs {
                        for &e in &cs {
                            let r = CaRanges { tilt: (lo, hi), c_start: s, c_len: (e - s).rem_euclid(360.0) };
                            if pairs.iter().all(|p| p.iter().any(|&(a, c)| r.holds(a, c))) {
                                best = best.min(r.cost());
                            }
                        }
                    }
                }
            }
            proptest::prop_assert!((exact.cost() - best).abs() < 1e-9, "{} vs brute {}", exact.cost(), best);
        }
    }

    #[test]
    fn flat_plate_needs_only_the_cap_above_it() {
        let (m, b) = mesh(&plate());
        for g in [&LatLon::PAPER as &dyn SphereGrid, &Icosphere::new(3)] {
            let vis = visibility(&m, &b, g, 0.0);
            for f in 0..m.len() {
                for c in 0..g.len() {
                    assert_eq!(
                        vis.contains(f, c),
                        g.direction(c).z > 0.0,
                        "{} cell {c}",
                        g.name()
                    );
                }
            }
            let (pole, tilt) = best_pole(&vis, g).expect("pole");
            assert!(pole.z > 0.0 && tilt < 1e-3, "{pole} {tilt}");
            assert!(
                unreachable(&vis, &reachable(g, &table_ac((0.0, 10.0)), DMat3::IDENTITY))
                    .is_empty(),
                "one cell of tilt"
            );
        }
    }

    #[test]
    fn cube_needs_a_tilt_near_ninety_degrees() {
        let (m, b) = mesh(&cube());
        // An 80° clearance keeps each face's cone within 10° of its normal.
        let g = Icosphere::new(3);
        let vis = visibility(&m, &b, &g, 80.0);
        for f in 0..m.len() {
            assert!(vis.count(f) > 0);
            for c in vis.cells_of(f) {
                assert!(g.direction(c).dot(m.facet_normal(f)) > 80f64.to_radians().sin());
            }
        }
        let tilt = required_tilt(&vis, &g, DVec3::Z);
        for (f, t) in tilt.iter().enumerate() {
            let t = t.expect("cone");
            if m.facet_normal(f).z > 0.5 {
                assert!(t < 10.0, "top {t}");
            } else {
                assert!((80.0..90.0).contains(&t), "side {t}");
            }
        }
        let reach = |k: &Kinematics| unreachable(&vis, &reachable(&g, k, DMat3::IDENTITY));
        assert!(
            reach(&table_ac((0.0, 95.0))).is_empty(),
            "C,A with A up to 95° reaches all five faces"
        );
        assert_eq!(
            reach(&table_ac((0.0, 60.0))).len(),
            8,
            "A up to 60°: the four walls are out of reach"
        );
        assert_eq!(reach(&table_ac((-60.0, 95.0))).len(), 0);
        let mut ab = Kinematics::new(KinKind::TableAb);
        ab.first = RotaryAxis {
            min: Some(-95.0),
            max: Some(95.0),
            sign: 1.0,
        };
        ab.second = RotaryAxis {
            min: Some(-95.0),
            max: Some(95.0),
            sign: 1.0,
        };
        assert!(reach(&ab).is_empty());
        ab.second = RotaryAxis {
            min: Some(-30.0),
            max: Some(30.0),
            sign: 1.0,
        };
        // B ±30° leaves the ±X walls (K_x = sin B) out.
        let out = reach(&ab);
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|&f| m.facet_normal(f).x.abs() > 0.99));
    }

    #[test]
    fn pocket_bottom_sees_out_through_its_opening_only() {
        // A closed pocket 200 long (x), 10 wide (y), 20 deep, open at the top.
        let (l, w, h) = (100.0, 5.0, 20.0);
        let t = pocket(l, w, h);
        let (m, b) = mesh(&t);
        for g in [
            &LatLon::PAPER as &dyn SphereGrid,
            &Icosphere::new(3),
            &Healpix { nside: 10 },
        ] {
            let vis = visibility(&m, &b, g, 0.0);
            let mut seen = 0;
            for f in (0..m.len()).filter(|&f| m.facet_normal(f).z > 0.5) {
                let [a, bb, c] = m.corners(f);
                let p = (a + bb + c) / 3.0;
                for cell in 0..g.len() {
                    let d = g.direction(cell);
                    if d.z <= 0.0 {
                        assert!(!vis.contains(f, cell));
                        continue;
                    }
                    let e = p + d * (h / d.z);
                    let (mx, my) = (l - e.x.abs(), w - e.y.abs());
                    if mx.abs() < 1e-6 || my.abs() < 1e-6 {
                        continue;
                    }
                    assert_eq!(
                        vis.contains(f, cell),
                        mx > 0.0 && my > 0.0,
                        "{} facet {f} cell {cell} {d}",
                        g.name()
                    );
                    seen += vis.contains(f, cell) as usize;
                }
            }
            assert!(seen > 0, "{}", g.name());
        }
    }

    /// Steep bumps: tools at grazing angles touch them, nearly touch them and
    /// pass them, so every proof of the depth maps and every capsule test is
    /// met.
    struct Bumps;
    impl millplan_geom::analytic::HeightField for Bumps {
        fn z(&self, x: f64, y: f64) -> f64 {
            6.0 * (0.35 * x).sin() * (0.3 * y).cos() + 0.05 * x
        }
        fn grad(&self, x: f64, y: f64) -> millplan_geom::DVec2 {
            millplan_geom::DVec2::new(
                2.1 * (0.35 * x).cos() * (0.3 * y).cos() + 0.05,
                -1.8 * (0.35 * x).sin() * (0.3 * y).sin(),
            )
        }
        fn domain(&self) -> (millplan_geom::DVec2, millplan_geom::DVec2) {
            (
                millplan_geom::DVec2::ZERO,
                millplan_geom::DVec2::splat(40.0),
            )
        }
    }

    #[test]
    fn tool_mode_pruning_changes_no_answer() {
        // The plain formulation (whole capsules, nothing left out) against
        // `accessibility` by depth maps first, which proves directions free or
        // blocked where it can and leaves out what only the ball could touch:
        // on free-form surfaces and in the pocket, with and without a holder.
        let surf = millplan_geom::analytic::tessellate(
            &millplan_geom::analytic::DemoSurface::default(),
            4.0,
        );
        let bumps = millplan_geom::analytic::tessellate(&Bumps, 1.6);
        let pocket_mesh = mesh(&pocket(30.0, 6.0, 12.0)).0;
        let g = Icosphere::new(2);
        for m in [surf, bumps, pocket_mesh] {
            let b = Bvh::build(&m);
            for tool in [
                ToolModel {
                    radius: 2.0,
                    reach: 25.0,
                    holder_radius: 0.0,
                    holder_length: 0.0,
                },
                ToolModel {
                    radius: 5.0,
                    reach: 15.0,
                    holder_radius: 9.0,
                    holder_length: 30.0,
                },
            ] {
                let r = tool.radius;
                let tol = 1e-3 * r + 1e-7 * m.bounds().diagonal();
                let plain = cones(
                    &m,
                    &g,
                    0.0,
                    |_, p, n| !b.capsule_hits(p + n * r, p + n * r, r - tol, None),
                    |_, p, n, d| {
                        let (c, top) = (p + n * r, p + n * r + d * tool.reach);
                        !b.capsule_hits(c, top, r - tol, None)
                            && (tool.holder_radius <= 0.0
                                || !b.capsule_hits(
                                    top,
                                    top + d * tool.holder_length,
                                    tool.holder_radius,
                                    None,
                                ))
                    },
                    &|_, _| {},
                );
                let seen = std::sync::Mutex::new(Vec::new());
                let fast = accessibility_mapped(&m, &b, &g, 0.0, &tool, &|d, t| {
                    seen.lock().expect("lock").push((d, t))
                });
                // Progress counts the words of 64 directions up to their total.
                let words = g.len().div_ceil(64);
                let seen = seen.into_inner().expect("lock");
                assert_eq!(seen.iter().map(|s| s.0).max(), Some(words));
                assert!(seen
                    .iter()
                    .all(|&(d, t)| t == words && d >= 1 && d <= words));
                // Line of sight counts facets, and decides what it would without.
                let seen = std::sync::Mutex::new(Vec::new());
                let vis = visibility_with_progress(&m, &b, &g, 0.0, &|d, t| {
                    seen.lock().expect("lock").push((d, t))
                });
                let seen = seen.into_inner().expect("lock");
                assert_eq!(seen.iter().map(|s| s.0).max(), Some(m.len()));
                assert!(seen.iter().all(|&(_, t)| t == m.len()));
                let plain_vis = visibility(&m, &b, &g, 0.0);
                assert!((0..m.len()).all(|f| vis.set(f) == plain_vis.set(f)));
                let total: usize = (0..m.len()).map(|f| plain.count(f)).sum();
                assert!(total > 0);
                for f in 0..m.len() {
                    assert_eq!(fast.set(f), plain.set(f), "facet {f}, {tool:?}");
                }
            }
        }
    }

    #[test]
    fn tool_mode_agrees_with_the_exact_reference_on_random_tools() {
        // Random tools (ball, reach, holder) on the bumps and in the pocket:
        // the depth maps with the split shank test and the chunked facets
        // answer like `accessibility_exact`, cell for cell.
        let bumps = millplan_geom::analytic::tessellate(&Bumps, 2.2);
        let pocket_mesh = mesh(&pocket(20.0, 7.0, 10.0)).0;
        let g = Icosphere::new(2);
        let mut seed = 20_261_123u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for (i, m) in [&bumps, &pocket_mesh, &bumps, &pocket_mesh]
            .into_iter()
            .enumerate()
        {
            let b = Bvh::build(m);
            let radius = 0.5 + 4.0 * next();
            let tool = ToolModel {
                radius,
                reach: radius + 30.0 * next(),
                holder_radius: if i < 2 { radius + 12.0 * next() } else { 0.0 },
                holder_length: 10.0 + 40.0 * next(),
            };
            let clearance = [0.0, 5.0][i % 2];
            let fast = accessibility_mapped(m, &b, &g, clearance, &tool, &|_, _| {});
            let exact = accessibility_exact(m, &b, &g, clearance, &tool);
            let total: usize = (0..m.len()).map(|f| exact.count(f)).sum();
            assert!(total > 0, "{tool:?}");
            for f in 0..m.len() {
                assert_eq!(fast.set(f), exact.set(f), "facet {f}, {tool:?}");
            }
        }
    }

    #[test]
    fn tool_mode_agrees_with_brute_force_where_the_capsule_tests_decide() {
        // Spec §3.4, tool model: the distance from each triangle to each of
        // the tool's axis segments must be at least its radius (the ball's
        // own contact region left out). Brute force over every triangle, no
        // tree, no maps, against the depth maps with their capsule tests and
        // against `accessibility_exact`, on the bumps with a holder, where the
        // maps leave a good share of the free directions to the capsules.
        let m = millplan_geom::analytic::tessellate(&Bumps, 3.2);
        let b = Bvh::build(&m);
        let g = Icosphere::new(1);
        let tool = ToolModel {
            radius: 3.0,
            reach: 12.0,
            holder_radius: 8.0,
            holder_length: 20.0,
        };
        let fast = accessibility_mapped(&m, &b, &g, 0.0, &tool, &|_, _| {});
        let exact = accessibility_exact(&m, &b, &g, 0.0, &tool);
        let tol = 1e-3 * tool.radius + 1e-7 * m.bounds().diagonal();
        let rs = tool.radius - tol;
        let hits = |a: DVec3, z: DVec3, r: f64, above: Option<(DVec3, f64)>| {
            (0..m.len()).any(|k| {
                let [p, q, s] = m.corners(k);
                above.is_none_or(|(n, h)| [p, q, s].iter().any(|v| n.dot(*v) > h))
                    && millplan_geom::bvh::segment_triangle_dist2(a, z, p, q, s) < r * r
            })
        };
        let test = DirectionTest::tool(&m, &b, 0.0, &tool);
        let views: Vec<ToolView> = (0..g.len())
            .map(|c| ToolView::new(&m, &m.vertices, g.direction(c), &tool, tol))
            .collect();
        let (mut free, mut by_capsules) = (0, 0);
        for t in (0..m.len()).step_by(2) {
            let (p, n) = test.facet(t).expect("no degenerate facets");
            let c = p + n * tool.radius;
            let usable = !hits(c, c, rs, None);
            for (k, view) in views.iter().enumerate() {
                let d = view.d;
                let top = c + d * tool.reach;
                let want = d.dot(n) > 0.0
                    && usable
                    && !hits(c, top, rs, Some((d, d.dot(c))))
                    && !hits(
                        top,
                        top + d * tool.holder_length,
                        tool.holder_radius,
                        Some((d, d.dot(top) - tool.holder_radius)),
                    );
                assert_eq!(fast.contains(t, k), want, "facet {t}, cell {k}");
                assert_eq!(exact.contains(t, k), want, "facet {t}, cell {k}");
                if want {
                    free += 1;
                    // Whether the shank's map alone proved it.
                    let (u, v) = (c.dot(view.e1), c.dot(view.e2));
                    let proved = view
                        .shank
                        .at(u, v)
                        .is_some_and(|s| view.shank.near[s] < c.dot(d) - view.eps);
                    by_capsules += !proved as usize;
                }
            }
        }
        // 338 triangles, half of them tested: 1,239 free pairs, 920 of them
        // left by the shank's map to the capsule tests.
        assert!(
            free > 500 && by_capsules * 2 > free,
            "{free} free, {by_capsules} by the capsule tests"
        );
    }

    #[test]
    fn a_tool_sees_less_of_a_pocket_bottom_than_a_ray() {
        // The pocket of the line-of-sight test; a ball of radius 2 with a long
        // shank: its axis must cross the top of the walls 2 mm inside them.
        let (l, w, h, r) = (100.0, 5.0, 20.0, 2.0);
        let t = pocket(l, w, h);
        let (m, b) = mesh(&t);
        let g = LatLon {
            bands: 40,
            sectors: 60,
        };
        let tool = ToolModel {
            radius: r,
            reach: 60.0,
            holder_radius: 0.0,
            holder_length: 0.0,
        };
        let acc = accessibility(&m, &b, &g, 0.0, &tool);
        let vis = visibility(&m, &b, &g, 0.0);
        let (mut yes, mut no) = (0, 0);
        for f in (0..m.len()).filter(|&f| m.facet_normal(f).z > 0.5) {
            let [a, bb, c] = m.corners(f);
            let centre = (a + bb + c) / 3.0 + DVec3::Z * r;
            for cell in 0..g.len() {
                let d = g.direction(cell);
                // Within its reach the tool's body holds the ray from the contact
                // point, so it never sees more than that ray.
                if d.z > 0.5 {
                    assert!(
                        !acc.contains(f, cell) || vis.contains(f, cell),
                        "facet {f} cell {cell}"
                    );
                }
                if (h - r) / d.z.max(1e-9) > tool.reach - 5.0 {
                    continue; // the shank ends below the wall tops
                }
                // Where the axis crosses the wall tops, and how far inside it stays.
                let e = centre + d * ((h - r) / d.z);
                let inside_y = (w - r) - e.y.abs();
                let inside_x = (l - r) - e.x.abs();
                if inside_y > 0.5 && inside_x > 0.5 {
                    assert!(acc.contains(f, cell), "facet {f} cell {cell} {d}");
                    yes += 1;
                } else if inside_y < -0.5 {
                    assert!(!acc.contains(f, cell), "facet {f} cell {cell} {d}");
                    no += 1;
                }
            }
        }
        assert!(yes > 10 && no > 100, "{yes} {no}");
        // A holder wider than the pocket keeps out of it: a short reach then blocks everything.
        let stub = ToolModel {
            radius: r,
            reach: 10.0,
            holder_radius: 8.0,
            holder_length: 40.0,
        };
        let acc = accessibility(&m, &b, &g, 0.0, &stub);
        for f in (0..m.len()).filter(|&f| m.facet_normal(f).z > 0.5) {
            assert_eq!(acc.count(f), 0);
        }
        // On an open plate every upward direction is free for a slim holder; a
        // fat one (radius 10 at 30 mm) needs the axis 3 + 30·d_z ≥ 10 above it.
        let (m, b) = mesh(&plate());
        let acc = accessibility(
            &m,
            &b,
            &g,
            0.0,
            &ToolModel {
                radius: 3.0,
                reach: 30.0,
                holder_radius: 2.5,
                holder_length: 50.0,
            },
        );
        for f in 0..m.len() {
            assert_eq!(
                acc.count(f),
                (0..g.len()).filter(|&c| g.direction(c).z > 0.0).count()
            );
        }
        let acc = accessibility(
            &m,
            &b,
            &g,
            0.0,
            &ToolModel {
                radius: 3.0,
                reach: 30.0,
                holder_radius: 10.0,
                holder_length: 5.0,
            },
        );
        for f in 0..m.len() {
            let [a, bb, c] = m.corners(f);
            let centre = (a + bb + c) / 3.0 + DVec3::Z * 3.0;
            for cell in 0..g.len() {
                let d = g.direction(cell);
                let top = centre + d * 30.0;
                let over = (0.0..100.0).contains(&top.x) && (0.0..80.0).contains(&top.y);
                if d.z > 0.0 && over && (top.z - 10.0).abs() > 0.2 {
                    assert_eq!(
                        acc.contains(f, cell),
                        top.z > 10.0,
                        "facet {f} cell {cell} {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn results_agree_across_grids_within_a_cell() {
        let (m, b) = mesh(&cube());
        let mut tilts = Vec::new();
        for g in [
            &LatLon::PAPER as &dyn SphereGrid,
            &Icosphere::new(3),
            &LatLon {
                bands: 40,
                sectors: 60,
            },
        ] {
            let vis = visibility(&m, &b, g, 45.0);
            let (pole, tilt) = best_pole(&vis, g).expect("pole");
            assert!(pole.z > 0.0, "{}: {pole}", g.name());
            tilts.push(tilt);
        }
        // The exact answer: the cone axes are +Z and the four wall normals, each
        // cone a 45° cap, so the best pole is +Z with a tilt of 45°.
        for t in &tilts {
            assert!((t - 45.0).abs() < 9.0, "{tilts:?}");
        }
    }

    #[test]
    fn setup_rotation_puts_the_pole_on_z() {
        for d in [
            DVec3::X,
            -DVec3::Z,
            DVec3::new(0.3, -0.4, 0.5).normalize(),
            DVec3::Z,
        ] {
            let r = setup_for_pole(d);
            assert!((r * d - DVec3::Z).length() < 1e-12);
            assert!((r.determinant() - 1.0).abs() < 1e-12);
        }
    }
}

#[cfg(test)]
mod window_tests {
    use super::*;

    #[test]
    fn window_maxima_agree_with_brute_force() {
        let mut seed = 3u64;
        for n in 1..40 {
            let v: Vec<f64> = (0..n)
                .map(|_| {
                    seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
                    (seed >> 40) as f64
                })
                .collect();
            for k in 0..12 {
                let mut got = vec![0.0; n];
                // A scratch buffer left longer by an earlier call.
                let mut scratch = vec![7.0; 50];
                window_max(&v, &mut got, k, &mut scratch);
                for i in 0..n {
                    let want = v[i.saturating_sub(k)..=(i + k).min(n - 1)]
                        .iter()
                        .copied()
                        .fold(f64::NEG_INFINITY, f64::max);
                    assert_eq!(got[i], want, "n {n} k {k} i {i}");
                }
            }
        }
    }
}

#[cfg(test)]
mod slow_tests {
    use super::*;

    /// The depth maps against the plain capsule tests on the demo surface at
    /// 24,642 triangles with the benchmark's tool (D10 ball, 40 mm reach,
    /// D40 × 60 mm holder): the same answer for every facet and direction.
    /// Seconds in a release build: `cargo test --release -p
    /// millplan-sim -- --ignored`.
    #[test]
    #[ignore]
    fn depth_maps_answer_like_the_capsule_tests_on_the_demo_surface() {
        let m = millplan_geom::analytic::tessellate(
            &millplan_geom::analytic::DemoSurface::default(),
            0.54,
        );
        let b = Bvh::build(&m);
        let g = Icosphere::new(2);
        let tool = ToolModel {
            radius: 5.0,
            reach: 40.0,
            holder_radius: 20.0,
            holder_length: 60.0,
        };
        assert!(m.len() >= MAPS_FROM);
        assert_eq!(
            accessibility(&m, &b, &g, 0.0, &tool),
            accessibility_exact(&m, &b, &g, 0.0, &tool)
        );
    }
}
