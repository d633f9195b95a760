//! Machinability and setup orientation of a part on a five-axis machine
//! (paper 004, after Kang & Suh; spec `kinematics-access-tools.md` §3).
//!
//! Every facet gets its visibility cone: the grid directions that leave its
//! outer side by more than a clearance angle and see no other part of the part
//! (tool mode: along which the ball-end mill, its shank and holder touch
//! nothing but the facet). A setup is feasible when, with the part rotated by
//! it, every facet keeps a direction the machine reaches within its rotary
//! limits. A setup's usage is the largest share of the machine's ranges a
//! facet needs ([`fit`]); the search seeds from the part as it lies and the
//! orientation needing least tilt (the pole every facet sees most nearly), each
//! spun about the vertical in 15° steps, refines the best seeds (and the part
//! as it lies) between the grid's directions, and keeps the one of least
//! usage, ties to the smallest turn: the smallest ranges, scaled like the
//! machine's, of any setup, and feasible exactly when the machine has them.

use millplan_geom::bvh::Bvh;
use millplan_geom::{DMat3, DVec3, TriMesh};
use millplan_models::kinematics::{KinKind, Kinematics};
use millplan_sim::access::{
    self, CellSets, DirectionTest, Healpix, Icosphere, LatLon, SphereGrid, ToolModel,
};

pub mod fit;
use fit::{Dof, Fit, Search};

/// The sphere grid of tool directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridKind {
    /// Latitude-longitude bands and sectors, each split into two triangles.
    LatLon,
    /// Geodesic icosphere, near-uniform cells.
    Icosphere,
    /// HEALPix, equal-area cells on rings of constant latitude.
    Healpix,
}

/// A grid of about `cells` cells.
pub fn grid(kind: GridKind, cells: usize) -> Box<dyn SphereGrid> {
    match kind {
        GridKind::LatLon => {
            // cells = 2·b·s with s = 1.5·b.
            let b = ((cells as f64 / 3.0).sqrt().round() as usize).max(2);
            Box::new(LatLon {
                bands: b,
                sectors: (b * 3).div_ceil(2),
            })
        }
        GridKind::Healpix => Box::new(Healpix {
            nside: ((cells as f64 / 12.0).sqrt().round() as usize).max(1),
        }),
        GridKind::Icosphere => {
            let k = ((cells as f64 / 20.0).ln() / 4f64.ln()).round().max(0.0) as u32;
            Box::new(Icosphere::new(k))
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct SetupParams {
    pub grid: GridKind,
    /// About how many grid cells.
    pub cells: usize,
    /// Tool mode (ball, shank, holder); `None`: line of sight.
    pub tool: Option<ToolModel>,
    /// A direction must leave the facet's surface by more than this, degrees.
    pub clearance_deg: f64,
    /// The part stands on its bottom face: leave those facets out and keep
    /// that face on the table (spins only).
    pub ignore_bottom: bool,
    /// Required ranges of a machine with a C axis by the exact window
    /// algorithm instead of the nearest-direction method.
    pub exact: bool,
}

impl SetupParams {
    pub fn new() -> SetupParams {
        SetupParams {
            grid: GridKind::LatLon,
            cells: 1200,
            tool: None,
            clearance_deg: 0.0,
            ignore_bottom: false,
            exact: false,
        }
    }
}

impl Default for SetupParams {
    fn default() -> Self {
        SetupParams::new()
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SetupError {
    #[error("the part has no triangles")]
    NoTriangles,
    #[error("{0}")]
    Invalid(String),
}

/// One candidate setup and what it needs.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Rotation from part to table coordinates.
    pub setup: DMat3,
    /// Facets this machine does not reach in this setup.
    pub unreachable: Vec<usize>,
    pub unreachable_area: f64,
    /// Ranges (degrees) of the (first, second) axis the setup needs: the span
    /// of the facets' directions (tilts with 0, the C axis as its smallest
    /// arc), whether or not the machine has them.
    pub required: Option<[(f64, f64); 2]>,
    /// The largest angle between the table's Z (the C axis, or the A=B=0
    /// direction) and a facet's direction, degrees.
    pub tilt: f64,
    /// The largest share of the machine's ranges a facet needs (at most 1:
    /// the machine reaches every facet); see [`fit`].
    pub usage: f64,
    /// Per live facet, the direction it is cut from (part frame), tested
    /// free, of least usage.
    pub dirs: Vec<Option<DVec3>>,
    /// Per live facet, the grid cell of that direction.
    pub chosen: Vec<Option<usize>>,
    /// The machine's reachable cells.
    pub mask: Vec<u64>,
}

/// The answer: the best setup and what it leaves out.
pub struct SetupPlan {
    pub grid: Box<dyn SphereGrid>,
    /// Visibility cone of every facet.
    pub vis: CellSets,
    /// Facets a setup must serve (with a cone, not ignored, not degenerate).
    pub live: Vec<usize>,
    /// Facets no direction sees: no rotary range reaches them.
    pub inaccessible: Vec<usize>,
    /// Facets left out as the bottom face.
    pub ignored: usize,
    /// The mesh was wound inward and was turned outward.
    pub flipped: bool,
    /// The setup that needs least of this machine's ranges (so the smallest
    /// ranges, scaled like the machine's, over all setups), found on the grid
    /// and refined between its directions; its `required` holds them.
    pub best: Candidate,
    /// Out of reach: the ranges the part needs as it lies in the file, on the
    /// same kind of machine with unlimited rotary axes.
    pub would_do: Option<[(f64, f64); 2]>,
    pub feasible: bool,
}

/// Finds the best setup of `mesh` on `machine`. A mesh wound inward is
/// turned outward first (it would see only its own inside).
pub fn plan(
    mesh: &mut TriMesh,
    machine: &Kinematics,
    p: &SetupParams,
) -> Result<SetupPlan, SetupError> {
    plan_with_progress(mesh, machine, p, &|_, _| {})
}

/// [`plan`], calling `progress(done, total)` through the part's cones of
/// access, the bulk of the work (from any thread).
pub fn plan_with_progress(
    mesh: &mut TriMesh,
    machine: &Kinematics,
    p: &SetupParams,
    progress: access::Progress,
) -> Result<SetupPlan, SetupError> {
    if mesh.is_empty() {
        return Err(SetupError::NoTriangles);
    }
    if !(0.0..90.0).contains(&p.clearance_deg) {
        return Err(SetupError::Invalid(
            "the clearance must be in [0, 90) degrees".into(),
        ));
    }
    if !(20..=200_000).contains(&p.cells) {
        return Err(SetupError::Invalid(
            "the grid must have between 20 and 200000 cells".into(),
        ));
    }
    let flipped = wound_inward(mesh);
    if flipped {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    let mesh: &TriMesh = mesh;
    let grid = grid(p.grid, p.cells);
    let bvh = Bvh::build(mesh);
    let (vis, test) = match &p.tool {
        Some(t) => (
            access::accessibility_with_progress(
                mesh,
                &bvh,
                grid.as_ref(),
                p.clearance_deg,
                t,
                progress,
            ),
            DirectionTest::tool(mesh, &bvh, p.clearance_deg, t),
        ),
        None => (
            access::visibility_with_progress(mesh, &bvh, grid.as_ref(), p.clearance_deg, progress),
            DirectionTest::sight(mesh, &bvh, p.clearance_deg),
        ),
    };
    let areas: Vec<f64> = (0..mesh.len()).map(|t| facet_area(mesh, t)).collect();
    let ignored = if p.ignore_bottom {
        bottom_facets(mesh)
    } else {
        vec![false; mesh.len()]
    };
    let inaccessible: Vec<usize> = (0..mesh.len())
        .filter(|&t| !ignored[t] && areas[t] > 0.0 && vis.count(t) == 0)
        .collect();
    let live: Vec<usize> = (0..mesh.len())
        .filter(|&t| !ignored[t] && areas[t] > 0.0 && vis.count(t) > 0)
        .collect();
    let fit = Fit::new(machine);
    let search = Search::new(&fit, grid.as_ref(), &vis, &test, &live);
    let mut poles = vec![DVec3::Z];
    // A part standing on its bottom face keeps it on the table: spins only.
    if !p.ignore_bottom {
        if let Some((pole, _)) = access::best_pole(&restrict(&vis, &live), grid.as_ref()) {
            poles.push(pole);
        }
    }
    let dof = if p.ignore_bottom {
        Dof::Spin
    } else if has_c_axis(machine.kind)
        && machine.second.min.is_none()
        && machine.second.max.is_none()
    {
        Dof::Tilt
    } else {
        Dof::All
    };
    // The grid search: each pole spun in 15° steps, by the cells' usage; the
    // best few then refined between the grid's directions.
    let mut seeds: Vec<(f64, f64, DMat3)> = poles
        .iter()
        .flat_map(|&pole| {
            (0..24).map(move |k| {
                DMat3::from_rotation_z((k as f64 * 15.0).to_radians())
                    * access::setup_for_pole(pole)
            })
        })
        .map(|s| (search.by_cells(s).0, turn(s), s))
        .collect();
    seeds.sort_by(|a, b| {
        (a.0 * 1e9)
            .round()
            .total_cmp(&(b.0 * 1e9).round())
            .then(a.1.total_cmp(&b.1))
    });
    seeds.dedup_by(|a, b| (a.2 - b.2).abs_diff_eq(DMat3::ZERO, 1e-9));
    // The part as it lies in the file is always refined too: between the
    // grid's directions it may do as well as any.
    let as_is = seeds.iter().position(|q| q.1 < 1e-12);
    let refined: Vec<(f64, f64, DMat3)> = seeds
        .iter()
        .enumerate()
        .filter(|(i, _)| *i < if dof == Dof::Spin { 1 } else { 3 } || Some(*i) == as_is)
        .map(|(_, &(_, _, s))| {
            let (s, u) = search.optimise(s, dof);
            (u, turn(s), s)
        })
        .collect();
    let (_, _, setup) = refined
        .into_iter()
        .min_by(|a, b| {
            (a.0 * 1e9)
                .round()
                .total_cmp(&(b.0 * 1e9).round())
                .then(a.1.total_cmp(&b.1))
        })
        .ok_or_else(|| SetupError::Invalid("no setup candidates".into()))?;
    let mut best = candidate(setup, machine, &search, &areas);
    // Out of this machine's reach: the ranges the part needs as it lies in
    // the file (spun only, like the search, when it stands on its bottom).
    let would_do = if best.unreachable.is_empty() {
        None
    } else {
        let free = Fit::free(machine);
        let fs = Search::new(&free, grid.as_ref(), &vis, &test, &live);
        candidate(DMat3::IDENTITY, machine, &fs, &areas).required
    };
    if p.exact && has_c_axis(machine.kind) && best.unreachable.is_empty() {
        if let Some(r) = exact_ranges(machine, grid.as_ref(), &vis, &live, best.setup)? {
            best.required = Some(r);
        }
    }
    let feasible = best.unreachable.is_empty() && inaccessible.is_empty();
    Ok(SetupPlan {
        grid,
        vis,
        live,
        inaccessible,
        ignored: ignored.iter().filter(|&&x| x).count(),
        flipped,
        best,
        would_do,
        feasible,
    })
}

/// The angle of a rotation, radians.
fn turn(s: DMat3) -> f64 {
    ((s.x_axis.x + s.y_axis.y + s.z_axis.z - 1.0) / 2.0)
        .clamp(-1.0, 1.0)
        .acos()
}

pub(crate) fn has_c_axis(kind: KinKind) -> bool {
    matches!(
        kind,
        KinKind::TableAc | KinKind::TableBc | KinKind::HeadBc | KinKind::HeadBTableC
    )
}

/// Setup `setup` with every live facet's direction of least usage (by the
/// search's fit), the facets `machine` does not reach and the ranges needed.
fn candidate(setup: DMat3, machine: &Kinematics, search: &Search, areas: &[f64]) -> Candidate {
    let choices = search.choices(setup);
    let mut unreachable = Vec::new();
    let (mut first, mut second) = ((0.0f64, 0.0f64), Vec::new());
    let mut tilt: f64 = 0.0;
    let mut usage: f64 = 0.0;
    for (&t, c) in search.live.iter().zip(&choices) {
        let Some(c) = c else {
            unreachable.push(t);
            continue;
        };
        let q = setup * c.dir;
        if !machine.reaches(q) {
            unreachable.push(t);
        }
        usage = usage.max(c.usage);
        first = (first.0.min(c.angles.0), first.1.max(c.angles.0));
        second.push(c.angles.1);
        tilt = tilt.max(q.z.clamp(-1.0, 1.0).acos().to_degrees());
    }
    let s = if has_c_axis(machine.kind) {
        // A rotary C axis: the smallest arc of azimuths that serves every facet.
        let (start, len) = access::min_arc(&second).unwrap_or((0.0, 0.0));
        centred_window(start, len)
    } else {
        second
            .iter()
            .fold((0.0f64, 0.0f64), |r, &s| (r.0.min(s), r.1.max(s)))
    };
    // (+ 0.0: the empty float sum is −0.0.)
    let unreachable_area = unreachable.iter().map(|&t| areas[t]).sum::<f64>() + 0.0;
    let grid = search.grid;
    Candidate {
        setup,
        unreachable,
        unreachable_area,
        required: (!second.is_empty()).then_some([first, s]),
        tilt,
        usage,
        dirs: choices.iter().map(|c| c.map(|c| c.dir)).collect(),
        chosen: choices
            .iter()
            .map(|c| c.map(|c| grid.cell_of(c.dir)))
            .collect(),
        mask: access::reachable(grid, machine, setup),
    }
}

/// The exact window algorithm for a machine with a C axis: every tilt
/// interval, the smallest C window for each. Refuses work of hours.
fn exact_ranges(
    machine: &Kinematics,
    grid: &dyn SphereGrid,
    vis: &CellSets,
    live: &[usize],
    setup: DMat3,
) -> Result<Option<[(f64, f64); 2]>, SetupError> {
    let pairs: Vec<Vec<(f64, f64)>> = live
        .iter()
        .map(|&t| {
            vis.cells_of(t)
                .flat_map(|c| machine.inverse(DVec3::ZERO, setup * grid.direction(c), 0.0))
                .map(|j| (j.first, j.second))
                .collect()
        })
        .collect();
    let m: usize = pairs.iter().map(|p| p.len()).sum();
    let mut tilts: Vec<i64> = pairs
        .iter()
        .flatten()
        .map(|p| (p.0 * 1e6).round() as i64)
        .collect();
    tilts.sort_unstable();
    tilts.dedup();
    // K² interval scans over M pairs.
    let work = (tilts.len() as f64).powi(2) / 4.0 * m as f64;
    if work > 2e10 {
        return Err(SetupError::Invalid(format!(
            "the exact ranges would scan {} tilt intervals over {m} candidate directions; use a coarser grid or the fast method",
            tilts.len().pow(2) / 4
        )));
    }
    Ok(access::ca_ranges_exact(&pairs).map(|r| [r.tilt, centred_window(r.c_start, r.c_len)]))
}

/// A copy of the cone sets holding only `keep` (so the pole search ignores the rest).
fn restrict(vis: &CellSets, keep: &[usize]) -> CellSets {
    let mut out = CellSets::new(keep.len(), vis.cells);
    for (i, &t) in keep.iter().enumerate() {
        out.copy_from(i, vis, t);
    }
    out
}

fn facet_area(m: &TriMesh, t: usize) -> f64 {
    let [a, b, c] = m.corners(t);
    0.5 * (b - a).cross(c - a).length()
}

/// Whether a closed or nearly closed mesh (under 1 % open edges) encloses a
/// negative volume, i.e. its triangles are wound clockwise seen from outside.
pub fn wound_inward(m: &TriMesh) -> bool {
    let e = m.edge_report();
    if e.edges == 0 || e.open * 100 > e.edges {
        return false;
    }
    let c = m.bounds().center();
    let vol: f64 = (0..m.len())
        .map(|t| {
            let [a, b, d] = m.corners(t);
            (a - c).dot((b - c).cross(d - c))
        })
        .sum();
    vol < 0.0
}

/// Facets facing straight down at the lowest Z of the part: the face it stands on.
fn bottom_facets(m: &TriMesh) -> Vec<bool> {
    let b = m.bounds();
    let tol = 1e-6 * b.diagonal().max(1e-9);
    (0..m.len())
        .map(|t| {
            let [p, q, r] = m.corners(t);
            m.facet_normal(t).z < -0.9998 && [p, q, r].iter().all(|v| v.z < b.min.z + tol)
        })
        .collect()
}

/// Z-Y-X Euler angles (degrees) of a rotation: R = Rz(z)·Ry(y)·Rx(x).
pub fn euler_zyx_deg(r: DMat3) -> [f64; 3] {
    let m = |i: usize, j: usize| r.col(j)[i];
    let y = (-m(2, 0)).clamp(-1.0, 1.0).asin();
    let (z, x) = if y.cos().abs() > 1e-9 {
        (m(1, 0).atan2(m(0, 0)), m(2, 1).atan2(m(2, 2)))
    } else {
        ((-m(0, 1)).atan2(m(1, 1)), 0.0)
    };
    [z.to_degrees(), y.to_degrees(), x.to_degrees()]
}

/// The names of a machine's (first, second) rotary axes.
pub fn axis_names(kind: KinKind) -> [&'static str; 2] {
    match kind {
        KinKind::TableAb => ["a", "b"],
        KinKind::TableAc => ["a", "c"],
        _ => ["b", "c"],
    }
}

/// A circular window as (from, to) degrees with its middle in (−180°, 180°].
fn centred_window(start: f64, len: f64) -> (f64, f64) {
    let mid = (start + len / 2.0 + 180.0).rem_euclid(360.0) - 180.0;
    (mid - len / 2.0, mid + len / 2.0)
}

/// What a setup plan says, for JSON.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Summary {
    pub feasible: bool,
    /// Rotation part → table, row by row.
    pub setup: [[f64; 3]; 3],
    pub euler_zyx_deg: [f64; 3],
    /// Ranges of the (first, second) axis, degrees, the setup needs: the
    /// smallest over all setups (scaled like the machine's own), whether or
    /// not this machine has them.
    pub required: Option<[(f64, f64); 2]>,
    /// Out of reach: the ranges the part needs as it lies in the file.
    pub would_do: Option<[(f64, f64); 2]>,
    pub axes: [&'static str; 2],
    pub max_tilt_deg: f64,
    /// The largest share of the machine's ranges a facet needs (≤ 1 when the
    /// machine reaches every facet).
    pub usage: f64,
    /// Facets no rotary range reaches (no direction sees them), with their
    /// centroids, and their area.
    pub unreachable: Vec<(usize, [f64; 3])>,
    pub unreachable_area: f64,
    /// Facets this machine does not reach in the setup, and their area.
    pub out_of_reach: Vec<(usize, [f64; 3])>,
    pub out_of_reach_area: f64,
    pub facets: usize,
    pub ignored: usize,
    pub grid: String,
    pub cells: usize,
    pub flipped: bool,
}

impl SetupPlan {
    pub fn summary(&self, mesh: &TriMesh, machine: &Kinematics) -> Summary {
        let s = self.best.setup;
        let centroid = |t: &usize| {
            let [p, q, r] = mesh.corners(*t);
            (*t, ((p + q + r) / 3.0).to_array())
        };
        Summary {
            feasible: self.feasible,
            setup: [
                s.row(0).to_array(),
                s.row(1).to_array(),
                s.row(2).to_array(),
            ],
            euler_zyx_deg: euler_zyx_deg(s),
            required: self.best.required,
            would_do: self.would_do,
            axes: axis_names(machine.kind),
            max_tilt_deg: self.best.tilt,
            usage: self.best.usage,
            unreachable: self.inaccessible.iter().map(centroid).collect(),
            unreachable_area: self
                .inaccessible
                .iter()
                .map(|&t| facet_area(mesh, t))
                .sum::<f64>()
                + 0.0,
            out_of_reach: self.best.unreachable.iter().map(centroid).collect(),
            out_of_reach_area: self.best.unreachable_area,
            facets: mesh.len(),
            ignored: self.ignored,
            grid: self.grid.name(),
            cells: self.grid.len(),
            flipped: self.flipped,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_angles_of_known_rotations() {
        let e = euler_zyx_deg(DMat3::from_rotation_z(30f64.to_radians()));
        assert!((e[0] - 30.0).abs() < 1e-9 && e[1].abs() < 1e-9 && e[2].abs() < 1e-9);
        let r = DMat3::from_rotation_z(0.3)
            * DMat3::from_rotation_y(-0.2)
            * DMat3::from_rotation_x(0.7);
        let e = euler_zyx_deg(r);
        for (got, want) in e.iter().zip([0.3f64, -0.2, 0.7]) {
            assert!((got - want.to_degrees()).abs() < 1e-9);
        }
    }

    #[test]
    fn a_c_window_is_centred_about_its_middle() {
        // 170°…210° has its middle at 190°, that is −170°.
        assert_eq!(centred_window(170.0, 40.0), (-190.0, -150.0));
        assert_eq!(centred_window(-30.0, 20.0), (-30.0, -10.0));
    }
}

#[cfg(test)]
mod cube_tests {
    use super::*;
    use millplan_models::kinematics::RotaryAxis;

    /// A closed 40 mm cube, facets wound outward.
    fn cube() -> TriMesh {
        let s = 40.0;
        let faces: [(DVec3, [[f64; 3]; 4]); 6] = [
            (
                DVec3::Z,
                [[0.0, 0.0, s], [s, 0.0, s], [s, s, s], [0.0, s, s]],
            ),
            (
                -DVec3::Z,
                [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, s, 0.0], [0.0, s, 0.0]],
            ),
            (
                DVec3::X,
                [[s, 0.0, 0.0], [s, s, 0.0], [s, s, s], [s, 0.0, s]],
            ),
            (
                -DVec3::X,
                [[0.0, 0.0, 0.0], [0.0, s, 0.0], [0.0, s, s], [0.0, 0.0, s]],
            ),
            (
                DVec3::Y,
                [[0.0, s, 0.0], [s, s, 0.0], [s, s, s], [0.0, s, s]],
            ),
            (
                -DVec3::Y,
                [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, 0.0, s], [0.0, 0.0, s]],
            ),
        ];
        let mut soup = Vec::new();
        for (n, q) in faces {
            let [a, b, c, d] = q.map(DVec3::from_array);
            if (b - a).cross(c - a).dot(n) > 0.0 {
                soup.extend([[a, b, c], [a, c, d]]);
            } else {
                soup.extend([[a, c, b], [a, d, c]]);
            }
        }
        TriMesh::from_soup(&soup).0
    }

    fn ca(lo: f64, hi: f64) -> Kinematics {
        let mut k = Kinematics::new(KinKind::TableAc);
        k.first = RotaryAxis {
            min: Some(lo),
            max: Some(hi),
            sign: 1.0,
        };
        k
    }

    #[test]
    fn cube_on_its_corner() {
        // Every face of a closed cube sees its open half-space: a setup needs
        // a tilt reaching each of the six half-spaces. With the pole on a
        // body diagonal the three faces turned away are 90° + 35.26° from it,
        // atan(1/√2) = 35.26° beyond their planes, and no pole does better
        // (each of the six normals is within 125.26° of it at most there).
        let exact = (1.0f64 / 2f64.sqrt()).atan().to_degrees();
        for g in [GridKind::LatLon, GridKind::Icosphere, GridKind::Healpix] {
            let p = SetupParams {
                grid: g,
                ..SetupParams::new()
            };
            for (range, feasible) in [(36.0, true), (34.5, false)] {
                let plan = plan(&mut cube(), &ca(-range, range), &p).expect("plans");
                assert_eq!(plan.feasible, feasible, "{g:?} ±{range}");
                // Feasible or not, the least tilt of any setup: standing on a
                // corner, the three faces below see the table's Z at 35.26°.
                let r = plan.best.required.expect("required");
                assert!(
                    (plan.best.tilt - exact).abs() < 0.5,
                    "{g:?}: {}",
                    plan.best.tilt
                );
                assert!(
                    r[0].0 == 0.0 && (r[0].1 - exact).abs() < 0.5,
                    "{g:?}: {r:?}"
                );
                let pole = plan.best.setup.transpose() * DVec3::Z;
                assert!(
                    (pole.x.abs() - pole.z.abs()).abs() < 0.01
                        && (pole.y.abs() - pole.z.abs()).abs() < 0.01,
                    "on a corner: {pole}"
                );
                assert!(plan.inaccessible.is_empty());
                assert_eq!(plan.best.unreachable.is_empty(), feasible);
            }
        }
    }

    fn ab(l: f64) -> Kinematics {
        let mut k = Kinematics::new(KinKind::TableAb);
        let r = RotaryAxis {
            min: Some(-l),
            max: Some(l),
            sign: 1.0,
        };
        (k.first, k.second) = (r, r);
        k
    }

    #[test]
    fn cube_on_its_bottom_on_an_ab_table() {
        // The cube stands on its bottom face (spins only) and every face must
        // be cut at least 30° off its plane: a wall with outward normal n
        // needs K·n > sin 30°. With K = (sin B, −sin A·cos B, cos A·cos B)
        // and |A|, |B| ≤ L, a wall at azimuth φ gets at most
        // sin L·|cos φ| + sin L·cos L·|sin φ| (the corner of the box: the
        // derivative in B is cos B·|cos φ| − sin L·sin B·|sin φ| > 0 for
        // B ≤ L < 45°). The four walls are at φ = ψ + k·90°; the worst of
        // them needs least L at ψ = 45°, where sin L·(1 + cos L) = √2·sin 30°:
        // L* = 21.486°, against 30° with the walls square to the axes. The
        // top face sees straight up.
        let exact = 21.486_43;
        for g in [GridKind::LatLon, GridKind::Icosphere, GridKind::Healpix] {
            let p = SetupParams {
                grid: g,
                clearance_deg: 30.0,
                ignore_bottom: true,
                ..SetupParams::new()
            };
            for (l, feasible) in [(exact + 0.5, true), (exact - 0.5, false)] {
                let plan = plan(&mut cube(), &ab(l), &p).expect("plans");
                let r = plan.best.required.expect("required");
                assert_eq!(plan.feasible, feasible, "{g:?} ±{l}");
                for (lo, hi) in r {
                    assert!(
                        (lo + exact).abs() < 0.5 && (hi - exact).abs() < 0.5,
                        "{g:?}: {r:?}"
                    );
                }
            }
        }
    }
}
