//! `millplan setup`: can a five-axis machine reach the whole part in one setup,
//! and how should the part be clamped?

use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_surface, write_atomic};
use millplan_geom::bvh::Bvh;
use millplan_geom::{DMat3, DVec3, TriMesh};
use millplan_models::kinematics::{KinKind, Kinematics, RotaryAxis};
use millplan_sim::access::{self, CellSets, Icosphere, LatLon, SphereGrid};
use std::path::PathBuf;

/// Machinability and setup orientation of a part on a five-axis machine
/// (line of sight, after Kang & Suh).
///
/// Every facet gets its visibility cone: the grid directions that leave its
/// outer side by more than --clearance degrees and see no other part of the
/// part (with --tool: along which the ball-end mill, its shank and holder
/// touch nothing but the facet). A setup is feasible when, with the part rotated by it, every facet
/// keeps a direction the machine reaches within its rotary limits. The search
/// tries the part as it lies in the file and the orientation that needs the
/// least tilt (the pole every facet sees most nearly), each spun about the
/// vertical in 15° steps, and keeps the feasible one with the smallest required
/// rotary ranges (or, if none is feasible, the one leaving the least area
/// unreachable).
///
/// Ranges are MIN,MAX in degrees or `free` for an unlimited axis; for `ca`
/// range1 is the tilting A axis and range2 the C table, for `ab` range1 is the
/// A table and range2 the B cradle.
///
/// Exit code 0 when feasible, 3 when not.
#[derive(clap::Args)]
pub struct Args {
    /// Part surface (STL).
    #[arg(long)]
    pub stl: PathBuf,
    /// Machine kinematics (TOML: kind = "table-ac" | "table-bc" | "table-ab" |
    /// "head-bc" | "head-b-table-c", [first] and [second] with min, max, sign).
    #[arg(long, conflicts_with = "kind")]
    pub machine: Option<PathBuf>,
    /// Machine type when no --machine file is given.
    #[arg(long = "type", value_enum, id = "kind")]
    pub kind: Option<TypeArg>,
    /// First rotary range (the tilting axis): MIN,MAX or free.
    #[arg(long, default_value = "free", allow_hyphen_values = true)]
    pub range1: String,
    /// Second rotary range: MIN,MAX or free.
    #[arg(long, default_value = "free", allow_hyphen_values = true)]
    pub range2: String,
    /// Sphere grid of tool directions.
    #[arg(long, value_enum, default_value_t = GridArg::Latlon)]
    pub grid: GridArg,
    /// Approximate number of grid cells (latlon: bands × sectors × 2 with 3 sectors
    /// per 2 bands; icosphere: 20·4^k; healpix: 12·N²).
    #[arg(long, default_value_t = 1200)]
    pub cells: usize,
    /// Tool mode: a ball-end mill D,REACH[,HOLDER_D,HOLDER_LENGTH] in mm (REACH
    /// from the ball centre to the holder). Without it, line of sight.
    #[arg(long, allow_hyphen_values = true)]
    pub tool: Option<String>,
    /// A direction must leave the facet's surface by more than this, degrees.
    #[arg(long, default_value_t = 0.0)]
    pub clearance: f64,
    /// The part stands on its bottom face (the facets facing down at its lowest
    /// Z): leave those out and keep that face on the table (the search then only
    /// spins the part about the vertical).
    #[arg(long)]
    pub ignore_bottom: bool,
    /// Required ranges of a machine with a C axis by the exact window algorithm
    /// (every tilt interval, the smallest C window for each) instead of the fast
    /// nearest-direction method; slow on fine grids and large parts.
    #[arg(long)]
    pub exact: bool,
    /// Write an HTML report: the sphere map of directions and the part coloured by tilt.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the part rotated into the chosen setup (binary STL).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum TypeArg {
    /// Tilting A table carrying a C rotary table.
    Ca,
    /// A table on a B cradle (two tilting axes).
    Ab,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum GridArg {
    /// Latitude-longitude bands and sectors, each split into two triangles.
    Latlon,
    /// Geodesic icosphere, near-uniform cells.
    Icosphere,
    /// HEALPix, equal-area cells on rings of constant latitude.
    Healpix,
}

fn parse_tool(s: &str) -> CliResult<access::ToolModel> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            CliError::input(format!(
                "--tool `{s}`: expected D,REACH[,HOLDER_D,HOLDER_LENGTH] in mm"
            ))
        })?;
    let ok = v.iter().all(|x| x.is_finite() && *x >= 0.0) && v.first().is_some_and(|d| *d > 0.0);
    match v[..] {
        [d, reach] if ok => Ok(access::ToolModel {
            radius: d / 2.0,
            reach,
            holder_radius: 0.0,
            holder_length: 0.0,
        }),
        [d, reach, hd, hl] if ok => Ok(access::ToolModel {
            radius: d / 2.0,
            reach,
            holder_radius: hd / 2.0,
            holder_length: hl,
        }),
        _ => Err(CliError::input(format!(
            "--tool `{s}`: expected D,REACH[,HOLDER_D,HOLDER_LENGTH], D > 0, none negative"
        ))),
    }
}

fn parse_range(s: &str, what: &str) -> CliResult<RotaryAxis> {
    if s.trim().eq_ignore_ascii_case("free") {
        return Ok(RotaryAxis::default());
    }
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            CliError::input(format!("{what} `{s}`: expected MIN,MAX in degrees or free"))
        })?;
    match v[..] {
        [lo, hi] if lo <= hi && lo.is_finite() && hi.is_finite() => Ok(RotaryAxis {
            min: Some(lo),
            max: Some(hi),
            sign: 1.0,
        }),
        _ => Err(CliError::input(format!(
            "{what} `{s}`: expected MIN,MAX with MIN ≤ MAX"
        ))),
    }
}

/// One candidate setup and what it needs.
struct Candidate {
    setup: DMat3,
    unreachable: Vec<usize>,
    unreachable_area: f64,
    /// Required (first, second) ranges in degrees over the facets' best directions.
    required: Option<[(f64, f64); 2]>,
    /// The largest angle between the C axis (or the A=B=0 direction) and a facet's nearest direction.
    tilt: f64,
    /// Per live facet, the reachable cell nearest the vertical, if any.
    chosen: Vec<Option<usize>>,
    /// The machine's reachable cells.
    mask: Vec<u64>,
}

pub fn run(a: Args) -> CliResult<i32> {
    let machine = match (&a.machine, a.kind) {
        (Some(p), _) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| CliError::input(format!("{}: cannot read: {e}", p.display())))?;
            Kinematics::from_toml(&text)
                .map_err(|e| CliError::input(format!("{}: {e}", p.display())))?
        }
        (None, Some(t)) => {
            let mut k = Kinematics::new(match t {
                TypeArg::Ca => KinKind::TableAc,
                TypeArg::Ab => KinKind::TableAb,
            });
            k.first = parse_range(&a.range1, "--range1")?;
            k.second = parse_range(&a.range2, "--range2")?;
            k
        }
        (None, None) => return Err(CliError::input("give --machine FILE or --type ca|ab")),
    };
    if !(0.0..90.0).contains(&a.clearance) {
        return Err(CliError::input("--clearance must be in [0, 90) degrees"));
    }
    if !(20..=200_000).contains(&a.cells) {
        return Err(CliError::input("--cells must be between 20 and 200000"));
    }
    let grid: Box<dyn SphereGrid> = match a.grid {
        GridArg::Latlon => {
            // cells = 2·b·s with s = 1.5·b.
            let b = ((a.cells as f64 / 3.0).sqrt().round() as usize).max(2);
            Box::new(LatLon {
                bands: b,
                sectors: (b * 3).div_ceil(2),
            })
        }
        GridArg::Healpix => Box::new(access::Healpix {
            nside: ((a.cells as f64 / 12.0).sqrt().round() as usize).max(1),
        }),
        GridArg::Icosphere => {
            let k = ((a.cells as f64 / 20.0).ln() / 4f64.ln()).round().max(0.0) as u32;
            Box::new(Icosphere::new(k))
        }
    };
    let tool = a.tool.as_deref().map(parse_tool).transpose()?;
    let (mut mesh, _) = read_surface(&a.stl)?;
    if mesh.is_empty() {
        return Err(CliError::input(format!(
            "{}: the part has no triangles",
            a.stl.display()
        )));
    }
    // A (nearly) closed part wound inside out would see only its own inside.
    let flipped = wound_inward(&mesh);
    if flipped {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        if !a.quiet && !a.json {
            eprintln!(
                "{}: the facets are wound inward (negative volume); turned outward",
                a.stl.display()
            );
        }
    }
    let bar = crate::progress::spinner(
        "visibility",
        mesh.len() * grid.len() > 20_000_000 && !a.quiet,
    );
    let t0 = std::time::Instant::now();
    let bvh = Bvh::build(&mesh);
    let vis = match &tool {
        Some(t) => access::accessibility(&mesh, &bvh, grid.as_ref(), a.clearance, t),
        None => access::visibility(&mesh, &bvh, grid.as_ref(), a.clearance),
    };
    bar.finish_and_clear();
    let areas: Vec<f64> = (0..mesh.len()).map(|t| facet_area(&mesh, t)).collect();
    let ignored = if a.ignore_bottom {
        bottom_facets(&mesh)
    } else {
        vec![false; mesh.len()]
    };
    let inaccessible: Vec<usize> = (0..mesh.len())
        .filter(|&t| !ignored[t] && areas[t] > 0.0 && vis.count(t) == 0)
        .collect();
    // The facets a setup must serve: with a cone, not ignored, not degenerate.
    let live: Vec<usize> = (0..mesh.len())
        .filter(|&t| !ignored[t] && areas[t] > 0.0 && vis.count(t) > 0)
        .collect();
    let mut poles = vec![DVec3::Z];
    // A part standing on its bottom face keeps it on the table: spins only.
    if !a.ignore_bottom {
        if let Some((p, _)) = access::best_pole(&restrict(&vis, &live), grid.as_ref()) {
            poles.push(p);
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
        .map(|setup| evaluate(setup, &machine, grid.as_ref(), &vis, &live, &areas))
        .collect();
    // Least unreachable area, then least tilt, then the narrowest ranges on the
    // limited axes, then the smallest turn away from the part as programmed.
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
    let best = candidates
        .into_iter()
        .min_by(|x, y| {
            let (kx, ky) = (key(x), key(y));
            kx.iter()
                .zip(&ky)
                .map(|(a, b)| a.total_cmp(b))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .ok_or_else(|| CliError::internal("no setup candidates"))?;
    let mut best = best;
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
    let c_axis = matches!(
        machine.kind,
        KinKind::TableAc | KinKind::TableBc | KinKind::HeadBc | KinKind::HeadBTableC
    );
    if a.exact && c_axis && best.unreachable.is_empty() {
        let pairs: Vec<Vec<(f64, f64)>> = live
            .iter()
            .map(|&t| {
                vis.cells_of(t)
                    .flat_map(|c| machine.inverse(DVec3::ZERO, best.setup * grid.direction(c), 0.0))
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
        // K² interval scans over M pairs: refuse work of hours rather than hang.
        let work = (tilts.len() as f64).powi(2) / 4.0 * m as f64;
        if work > 2e10 {
            return Err(CliError::input(format!(
                "--exact would scan {} tilt intervals over {m} candidate directions; use a coarser --cells or drop --exact",
                tilts.len().pow(2) / 4
            )));
        }
        if let Some(r) = access::ca_ranges_exact(&pairs) {
            best.required = Some([r.tilt, centred_window(r.c_start, r.c_len)]);
        }
    }
    let feasible = best.unreachable.is_empty() && inaccessible.is_empty();
    let secs = t0.elapsed().as_secs_f64();
    if let Some(out) = &a.output {
        let s = best.setup;
        let mut rotated = mesh.clone();
        rotated.map_vertices(|v| s * v);
        let mut bytes = Vec::new();
        millplan_geom::stl::write_binary_stl(&rotated, "millplan setup", &mut bytes);
        write_atomic(out, &bytes, &[a.stl.as_path()])?;
    }
    if let Some(path) = &a.report {
        let html = report(
            &a,
            &mesh,
            grid.as_ref(),
            &vis,
            &live,
            &best,
            inaccessible.len(),
            &machine,
        );
        write_atomic(path, html.as_bytes(), &[a.stl.as_path()])?;
    }
    let rows = |m: DMat3| {
        [
            m.row(0).to_array(),
            m.row(1).to_array(),
            m.row(2).to_array(),
        ]
    };
    let euler = {
        let (z, y, x) = glam_euler_zyx(best.setup);
        [z.to_degrees(), y.to_degrees(), x.to_degrees()]
    };
    let centroid = |t: usize| {
        let [p, q, r] = mesh.corners(t);
        ((p + q + r) / 3.0).to_array()
    };
    let names = match machine.kind {
        KinKind::TableAb => ["a", "b"],
        KinKind::TableAc => ["a", "c"],
        _ => ["b", "c"],
    };
    if a.json {
        let range = |r: Option<(f64, f64)>| match r {
            Some((lo, hi)) => serde_json::json!([lo, hi]),
            None => serde_json::json!("free"),
        };
        let req = best.required.map(
            |r| serde_json::json!({ names[0]: range(Some(r[0])), names[1]: range(Some(r[1])) }),
        );
        let limit = |ax: &RotaryAxis| match (ax.min, ax.max) {
            (None, None) => serde_json::json!("free"),
            (lo, hi) => serde_json::json!([lo, hi]),
        };
        let j = serde_json::json!({
            "feasible": feasible,
            "setup": rows(best.setup),
            "euler_zyx_deg": euler,
            "required": req,
            "would_do": would_do.map(|r| serde_json::json!({ names[0]: [r[0].0, r[0].1], names[1]: [r[1].0, r[1].1] })),
            "max_tilt_deg": best.tilt,
            "machine": { "kind": machine.kind, names[0]: limit(&machine.first), names[1]: limit(&machine.second) },
            "unreachable": best.unreachable.iter().map(|&t| serde_json::json!({"facet": t, "centroid": centroid(t)})).collect::<Vec<_>>(),
            "unreachable_area": best.unreachable_area,
            "inaccessible": inaccessible.iter().map(|&t| serde_json::json!({"facet": t, "centroid": centroid(t)})).collect::<Vec<_>>(),
            "facets": mesh.len(),
            "ignored": ignored.iter().filter(|&&x| x).count(),
            "grid": grid.name(),
            "cells": grid.len(),
            "clearance_deg": a.clearance,
            "flipped": flipped,
            "mode": if tool.is_some() { "tool" } else { "line-of-sight" },
            "seconds": secs,
        });
        println!("{}", serde_json::to_string_pretty(&j).unwrap_or_default());
    } else {
        println!(
            "{}: {} facets, {} grid ({} cells), clearance {}°",
            a.stl.display(),
            mesh.len(),
            grid.name(),
            grid.len(),
            a.clearance
        );
        println!(
            "{}",
            if feasible {
                "feasible in one setup"
            } else {
                "NOT feasible in one setup"
            }
        );
        let m = rows(best.setup);
        println!("setup rotation (part → table):");
        for r in m {
            println!("  [{:9.6} {:9.6} {:9.6}]", r[0], r[1], r[2]);
        }
        println!(
            "  Euler Z-Y-X: {:.3}°, {:.3}°, {:.3}°",
            euler[0], euler[1], euler[2]
        );
        match best.required {
            Some(r) => println!(
                "required: {} {:.2}..{:.2}°, {} {:.2}..{:.2}° (largest tilt {:.2}°)",
                names[0].to_uppercase(),
                r[0].0,
                r[0].1,
                names[1].to_uppercase(),
                r[1].0,
                r[1].1,
                best.tilt
            ),
            None => match would_do {
                Some(r) => println!(
                    "out of reach; ranges that would do in this setup: {} {:.2}..{:.2}°, {} {:.2}..{:.2}°",
                    names[0].to_uppercase(),
                    r[0].0,
                    r[0].1,
                    names[1].to_uppercase(),
                    r[1].0,
                    r[1].1
                ),
                None => println!("required: some facets have no reachable direction"),
            },
        }
        if !best.unreachable.is_empty() {
            println!(
                "{} facets ({:.2} mm²) out of the machine's reach",
                best.unreachable.len(),
                best.unreachable_area
            );
        }
        if !inaccessible.is_empty() {
            println!(
                "{} facets no tool direction can see (the first: facet {} at {:?})",
                inaccessible.len(),
                inaccessible[0],
                centroid(inaccessible[0])
            );
        }
    }
    Ok(if feasible { EXIT_OK } else { EXIT_FINDINGS })
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
fn wound_inward(m: &TriMesh) -> bool {
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

/// Z-Y-X Euler angles (radians) of a rotation: R = Rz(z)·Ry(y)·Rx(x).
fn glam_euler_zyx(r: DMat3) -> (f64, f64, f64) {
    let m = |i: usize, j: usize| r.col(j)[i];
    let y = (-m(2, 0)).clamp(-1.0, 1.0).asin();
    if y.cos().abs() > 1e-9 {
        (m(1, 0).atan2(m(0, 0)), y, m(2, 1).atan2(m(2, 2)))
    } else {
        ((-m(0, 1)).atan2(m(1, 1)), y, 0.0)
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
        let s = match machine.kind {
            // A rotary C axis: the smallest arc of azimuths that serves every facet.
            KinKind::TableAc | KinKind::TableBc | KinKind::HeadBc | KinKind::HeadBTableC => {
                let (start, len) = access::min_arc(&second).unwrap_or((0.0, 0.0));
                centred_window(start, len)
            }
            KinKind::TableAb => second
                .iter()
                .fold((0.0f64, 0.0f64), |r, &s| (r.0.min(s), r.1.max(s))),
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

#[allow(clippy::too_many_arguments)]
fn report(
    a: &Args,
    mesh: &TriMesh,
    grid: &dyn SphereGrid,
    vis: &CellSets,
    live: &[usize],
    best: &Candidate,
    inaccessible: usize,
    machine: &Kinematics,
) -> String {
    let feasible = best.unreachable.is_empty() && inaccessible == 0;
    use millplan_report::svg::{map, sphere_map, DirClass};
    let s = best.setup;
    let mut class: Vec<DirClass> = (0..grid.len())
        .map(|c| {
            if best.mask[c / 64] >> (c % 64) & 1 == 1 {
                DirClass::Reach
            } else {
                DirClass::Out
            }
        })
        .collect();
    for &t in &best.unreachable {
        for c in vis.cells_of(t) {
            class[c] = DirClass::Missing;
        }
    }
    for c in best.chosen.iter().flatten() {
        class[*c] = DirClass::Used;
    }
    let cells: Vec<([f64; 3], DirClass)> = (0..grid.len())
        .map(|c| ((s * grid.direction(c)).to_array(), class[c]))
        .collect();
    let part: Vec<(f64, f64, f64)> = live
        .iter()
        .zip(&best.chosen)
        .filter_map(|(&t, c)| {
            let [p, q, r] = mesh.corners(t);
            let m = s * ((p + q + r) / 3.0);
            c.map(|c| {
                (
                    m.x,
                    m.y,
                    (s * grid.direction(c))
                        .z
                        .clamp(-1.0, 1.0)
                        .acos()
                        .to_degrees(),
                )
            })
        })
        .collect();
    let range = |ax: &RotaryAxis| match (ax.min, ax.max) {
        (None, None) => "free".to_string(),
        (lo, hi) => format!(
            "{} … {}",
            lo.map_or("−∞".into(), |v| format!("{v}°")),
            hi.map_or("∞".into(), |v| format!("{v}°"))
        ),
    };
    let mut rows = vec![
        ("part".to_string(), a.stl.display().to_string()),
        ("facets".to_string(), mesh.len().to_string()),
        (
            "machine".to_string(),
            format!(
                "{:?}: first axis {}, second axis {}",
                machine.kind,
                range(&machine.first),
                range(&machine.second)
            ),
        ),
        (
            "mode".to_string(),
            if a.tool.is_some() {
                format!("tool {}", a.tool.clone().unwrap_or_default())
            } else {
                "line of sight".to_string()
            },
        ),
        (
            "grid".to_string(),
            format!(
                "{} ({} cells), clearance {}°",
                grid.name(),
                grid.len(),
                a.clearance
            ),
        ),
        (
            "feasible in one setup".to_string(),
            if feasible {
                "yes".to_string()
            } else {
                "no".to_string()
            },
        ),
        ("largest tilt".to_string(), format!("{:.2}°", best.tilt)),
        (
            "facets out of reach".to_string(),
            format!(
                "{} ({:.2} mm²)",
                best.unreachable.len(),
                best.unreachable_area
            ),
        ),
        (
            "facets no direction sees".to_string(),
            inaccessible.to_string(),
        ),
    ];
    if let Some(r) = best.required {
        rows.push((
            "required ranges".to_string(),
            format!(
                "first {:.2}° … {:.2}°, second {:.2}° … {:.2}°",
                r[0].0, r[0].1, r[1].0, r[1].1
            ),
        ));
    }
    let m = |i: usize| format!("[{:.6} {:.6} {:.6}]", s.row(i).x, s.row(i).y, s.row(i).z);
    rows.push((
        "setup rotation (part → table)".to_string(),
        format!("{} {} {}", m(0), m(1), m(2)),
    ));
    millplan_report::html::simple_report(
        "Setup and machinability",
        "Tool directions each facet can be reached from, the directions the machine reaches with the part clamped in the chosen setup, and the tilt every facet needs.",
        &rows,
        &[
            ("Tool directions in the table frame (equal-area projection). Dark blue: the direction each facet is cut from; red: directions facets need but the machine cannot reach.".to_string(), sphere_map("Directions", &cells)),
            ("The part in the chosen setup seen from above, coloured by the tilt its facets need (degrees).".to_string(), map("Required tilt", "tilt °", &part)),
        ],
    )
}
