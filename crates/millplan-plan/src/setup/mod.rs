//! Machinability and setup orientation of a part on a five-axis machine
//! (paper 004, after Kang & Suh; spec `kinematics-access-tools.md` §3).
//!
//! Every facet gets its visibility cone: the grid directions that leave its
//! outer side by more than a clearance angle and see no other part of the part
//! (tool mode: along which the ball-end mill, its shank and holder touch
//! nothing but the facet). A setup is feasible when, with the part rotated by
//! it, every facet keeps a direction the machine reaches within its rotary
//! limits. The search tries the part as it lies and the orientation needing
//! least tilt (the pole every facet sees most nearly), each spun about the
//! vertical in 15° steps, and keeps the feasible one with the smallest required
//! rotary ranges (or, if none is feasible, the one leaving the least area out
//! of reach).

use millplan_geom::bvh::Bvh;
use millplan_geom::{DMat3, DVec3, TriMesh};
use millplan_models::kinematics::{KinKind, Kinematics, RotaryAxis};
use millplan_sim::access::{self, CellSets, Healpix, Icosphere, LatLon, SphereGrid, ToolModel};

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
    pub unreachable: Vec<usize>,
    pub unreachable_area: f64,
    /// Required (first, second) ranges in degrees over the facets' best directions.
    pub required: Option<[(f64, f64); 2]>,
    /// The largest angle between the C axis (or the A=B=0 direction) and a
    /// facet's nearest direction, degrees.
    pub tilt: f64,
    /// Per live facet, the reachable cell nearest the vertical, if any.
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
    /// Facets no direction sees.
    pub inaccessible: Vec<usize>,
    /// Facets left out as the bottom face.
    pub ignored: usize,
    /// The mesh was wound inward and was turned outward.
    pub flipped: bool,
    pub best: Candidate,
    /// Out of reach: the ranges the same setup would need with unlimited
    /// rotary axes.
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
    let vis = match &p.tool {
        Some(t) => access::accessibility(mesh, &bvh, grid.as_ref(), p.clearance_deg, t),
        None => access::visibility(mesh, &bvh, grid.as_ref(), p.clearance_deg),
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
    let mut poles = vec![DVec3::Z];
    // A part standing on its bottom face keeps it on the table: spins only.
    if !p.ignore_bottom {
        if let Some((pole, _)) = access::best_pole(&restrict(&vis, &live), grid.as_ref()) {
            poles.push(pole);
        }
    }
    let candidates: Vec<Candidate> = poles
        .iter()
        .flat_map(|&pole| {
            (0..24).map(move |k| {
                DMat3::from_rotation_z((k as f64 * 15.0).to_radians())
                    * access::setup_for_pole(pole)
            })
        })
        .map(|setup| evaluate(setup, machine, grid.as_ref(), &vis, &live, &areas))
        .collect();
    let mut best = choose(candidates, machine)
        .ok_or_else(|| SetupError::Invalid("no setup candidates".into()))?;
    // Out of this machine's reach: report what ranges would do, from the same
    // setup on the same kind of machine with unlimited rotary axes.
    let would_do = if best.unreachable.is_empty() {
        None
    } else {
        let mut free = machine.clone();
        free.first = RotaryAxis {
            min: None,
            max: None,
            sign: machine.first.sign,
        };
        free.second = RotaryAxis {
            min: None,
            max: None,
            sign: machine.second.sign,
        };
        evaluate(best.setup, &free, grid.as_ref(), &vis, &live, &areas).required
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

fn has_c_axis(kind: KinKind) -> bool {
    matches!(
        kind,
        KinKind::TableAc | KinKind::TableBc | KinKind::HeadBc | KinKind::HeadBTableC
    )
}

/// Least unreachable area, then least tilt, then the narrowest ranges on the
/// limited axes, then the smallest turn away from the part as programmed.
fn choose(candidates: Vec<Candidate>, machine: &Kinematics) -> Option<Candidate> {
    let limited = [
        machine.first.min.is_some() || machine.first.max.is_some(),
        machine.second.min.is_some() || machine.second.max.is_some(),
    ];
    let key = |c: &Candidate| {
        let spread = c.required.map_or(f64::INFINITY, |r| {
            (0..2)
                .filter(|&i| limited[i])
                .map(|i| r[i].1 - r[i].0)
                .sum::<f64>()
        });
        let turn = ((c.setup.x_axis.x + c.setup.y_axis.y + c.setup.z_axis.z - 1.0) / 2.0)
            .clamp(-1.0, 1.0)
            .acos();
        [
            c.unreachable_area,
            (c.tilt * 1e3).round(),
            (spread * 1e3).round(),
            turn,
        ]
    };
    candidates.into_iter().min_by(|x, y| {
        let (kx, ky) = (key(x), key(y));
        kx.iter()
            .zip(&ky)
            .map(|(a, b)| a.total_cmp(b))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    })
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

/// Which of two IK branches a facet is cut with: on a machine with a C axis the
/// one with the tilt positive (C turns instead), on an A,B table the one
/// nearest home on both axes.
fn branch_cost(kind: KinKind, (first, second): (f64, f64)) -> f64 {
    match kind {
        KinKind::TableAb => first.abs().max(second.abs()),
        _ => first.abs() + if first < 0.0 { 1e3 } else { 0.0 },
    }
}

/// A circular window as (from, to) degrees with its middle in (−180°, 180°].
fn centred_window(start: f64, len: f64) -> (f64, f64) {
    let mid = (start + len / 2.0 + 180.0).rem_euclid(360.0) - 180.0;
    (mid - len / 2.0, mid + len / 2.0)
}

fn evaluate(
    setup: DMat3,
    machine: &Kinematics,
    grid: &dyn SphereGrid,
    vis: &CellSets,
    live: &[usize],
    areas: &[f64],
) -> Candidate {
    let mask = access::reachable(grid, machine, setup);
    // Per cell, the machine's rotary positions for that direction (the branch
    // nearest zero) when reachable.
    let angles: Vec<Option<(f64, f64)>> = (0..grid.len())
        .map(|c| {
            if mask[c / 64] >> (c % 64) & 1 == 0 {
                return None;
            }
            let d = setup * grid.direction(c);
            machine
                .inverse(DVec3::ZERO, d, 0.0)
                .into_iter()
                .map(|j| (j.first, j.second))
                .min_by(|x, y| {
                    branch_cost(machine.kind, *x).total_cmp(&branch_cost(machine.kind, *y))
                })
        })
        .collect();
    let cos: Vec<f64> = (0..grid.len())
        .map(|c| (setup * grid.direction(c)).z)
        .collect();
    let mut unreachable = Vec::new();
    // Both ranges hold 0, the machine's home position.
    let mut first = (0.0f64, 0.0f64);
    let mut second = Vec::new();
    let mut tilt: f64 = 0.0;
    let mut chosen = Vec::with_capacity(live.len());
    for &t in live {
        // The facet's reachable direction nearest the C axis (least tilt).
        let best = vis
            .cells_of(t)
            .filter(|&c| angles[c].is_some())
            .max_by(|&x, &y| cos[x].total_cmp(&cos[y]));
        chosen.push(best);
        match best {
            None => unreachable.push(t),
            Some(c) => {
                let (f, s) = angles[c].unwrap_or_default();
                first = (first.0.min(f), first.1.max(f));
                second.push(s);
                tilt = tilt.max(cos[c].clamp(-1.0, 1.0).acos().to_degrees());
            }
        }
    }
    let required = if unreachable.is_empty() && !second.is_empty() {
        let s = if has_c_axis(machine.kind) {
            // A rotary C axis: the smallest arc of azimuths that serves every facet.
            let (start, len) = access::min_arc(&second).unwrap_or((0.0, 0.0));
            centred_window(start, len)
        } else {
            second
                .iter()
                .fold((0.0f64, 0.0f64), |r, &s| (r.0.min(s), r.1.max(s)))
        };
        Some([first, s])
    } else {
        None
    };
    // (+ 0.0: the empty float sum is −0.0.)
    let unreachable_area = unreachable.iter().map(|&t| areas[t]).sum::<f64>() + 0.0;
    Candidate {
        setup,
        unreachable,
        unreachable_area,
        required,
        tilt,
        chosen,
        mask,
    }
}

/// What a setup plan says, for JSON.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Summary {
    pub feasible: bool,
    /// Rotation part → table, row by row.
    pub setup: [[f64; 3]; 3],
    pub euler_zyx_deg: [f64; 3],
    /// Required ranges of the (first, second) axis, degrees; `None` when out of reach.
    pub required: Option<[(f64, f64); 2]>,
    pub would_do: Option<[(f64, f64); 2]>,
    pub axes: [&'static str; 2],
    pub max_tilt_deg: f64,
    /// Facets out of reach and no direction sees, with their centroids.
    pub unreachable: Vec<(usize, [f64; 3])>,
    pub unreachable_area: f64,
    pub inaccessible: Vec<(usize, [f64; 3])>,
    pub facets: usize,
    pub ignored: usize,
    pub grid: String,
    pub cells: usize,
    pub flipped: bool,
}

impl SetupPlan {
    pub fn summary(&self, mesh: &TriMesh, machine: &Kinematics) -> Summary {
        let s = self.best.setup;
        let centroid = |t: usize| {
            let [p, q, r] = mesh.corners(t);
            ((p + q + r) / 3.0).to_array()
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
            unreachable: self
                .best
                .unreachable
                .iter()
                .map(|&t| (t, centroid(t)))
                .collect(),
            unreachable_area: self.best.unreachable_area,
            inaccessible: self
                .inaccessible
                .iter()
                .map(|&t| (t, centroid(t)))
                .collect(),
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
