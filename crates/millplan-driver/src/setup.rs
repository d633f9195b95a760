//! `millplan setup`: the machine and the search's parameters from the
//! request, the run (`run_command`), the report's inputs and the typed
//! summary the command prints.

use crate::check::{arg, Range};
use millplan_geom::TriMesh;
pub use millplan_models::kinematics::Kinematics;
use millplan_models::kinematics::{KinKind, RotaryAxis};
use millplan_plan::setup::{GridKind, SetupError, SetupParams, SetupPlan, Summary};
use millplan_report::html::Verdict;
use millplan_sim::access::ToolModel;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

mod command;
pub use command::{run_command, SetupCommand, SetupRun};

/// The machine types `--type` names: A tilting table on C, or A table in a
/// B cradle.
#[derive(Clone, Copy, Debug)]
pub enum MachineType {
    Ca,
    Ab,
}

/// The options of `millplan setup` that shape the search.
#[derive(Clone, Debug)]
pub struct SetupRequest {
    pub grid: GridKind,
    pub cells: usize,
    /// `D,REACH[,HOLDER_D,HOLDER_LENGTH]`; `None`: line of sight.
    pub tool: Option<String>,
    /// Degrees.
    pub clearance: f64,
    pub ignore_bottom: bool,
    pub exact: bool,
}

fn parse_tool(s: &str) -> Result<ToolModel, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--tool `{s}`: expected D,REACH[,HOLDER_D,HOLDER_LENGTH] in mm"))?;
    let ok = v.iter().all(|x| x.is_finite() && *x >= 0.0) && v.first().is_some_and(|d| *d > 0.0);
    match v[..] {
        [d, reach] if ok => Ok(ToolModel {
            radius: d / 2.0,
            reach,
            holder_radius: 0.0,
            holder_length: 0.0,
        }),
        [d, reach, hd, hl] if ok => Ok(ToolModel {
            radius: d / 2.0,
            reach,
            holder_radius: hd / 2.0,
            holder_length: hl,
        }),
        _ => Err(format!(
            "--tool `{s}`: expected D,REACH[,HOLDER_D,HOLDER_LENGTH], D > 0, none negative"
        )),
    }
}

fn parse_range(s: &str, what: &str) -> Result<RotaryAxis, String> {
    if s.trim().eq_ignore_ascii_case("free") {
        return Ok(RotaryAxis::default());
    }
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{what} `{s}`: expected MIN,MAX in degrees or free"))?;
    match v[..] {
        [lo, hi] if lo <= hi && lo.is_finite() && hi.is_finite() => Ok(RotaryAxis {
            min: Some(lo),
            max: Some(hi),
            sign: 1.0,
        }),
        _ => Err(format!("{what} `{s}`: expected MIN,MAX with MIN ≤ MAX")),
    }
}

/// A machine of type `t` with the rotary ranges `range1` and `range2`
/// (`MIN,MAX` in degrees or `free`).
pub fn machine_of_type(t: MachineType, range1: &str, range2: &str) -> Result<Kinematics, String> {
    let mut k = Kinematics::new(match t {
        MachineType::Ca => KinKind::TableAc,
        MachineType::Ab => KinKind::TableAb,
    });
    k.first = parse_range(range1, "--range1")?;
    k.second = parse_range(range2, "--range2")?;
    Ok(k)
}

/// The clearance and the grid's size in their ranges.
pub fn check(a: &SetupRequest) -> Result<(), String> {
    arg(
        "--clearance",
        a.clearance,
        Range::from(0.0, 89.0, "degrees"),
    )?;
    arg("--cells", a.cells as f64, Range::from(8.0, 1e7, "cells"))?;
    Ok(())
}

/// The request checked into the search's parameters (the tool parsed).
pub fn params(a: &SetupRequest) -> Result<SetupParams, String> {
    Ok(SetupParams {
        grid: a.grid,
        cells: a.cells,
        tool: a.tool.as_deref().map(parse_tool).transpose()?,
        clearance_deg: a.clearance,
        ignore_bottom: a.ignore_bottom,
        exact: a.exact,
    })
}

/// The HTML report of `part` (its name), with the mesh's defects and its
/// winding among the warnings.
pub fn report(
    a: &SetupRequest,
    part: String,
    mesh: &TriMesh,
    plan: &SetupPlan,
    machine: &Kinematics,
) -> String {
    millplan_report::setup::setup_report(&inputs(a, part, mesh, plan), mesh, plan, machine)
}

/// The verdict of the search, as the report's: text and JSON print it.
pub fn verdict(a: &SetupRequest, mesh: &TriMesh, plan: &SetupPlan) -> Verdict {
    millplan_report::setup::setup_verdict(&inputs(a, String::new(), mesh, plan), mesh, plan)
}

/// What the report and the verdict are made from: the part's name, the
/// mode, and the mesh's defects and winding among the warnings.
fn inputs(
    a: &SetupRequest,
    part: String,
    mesh: &TriMesh,
    plan: &SetupPlan,
) -> millplan_report::setup::SetupInputs {
    let mut warnings: Vec<String> = millplan_plan::checks::mesh(mesh)
        .into_iter()
        .map(|d| d.message)
        .collect();
    if plan.flipped {
        warnings.push(
            "the facets were wound inward (negative volume) and were turned outward".to_string(),
        );
    }
    millplan_report::setup::SetupInputs {
        part,
        mode: a
            .tool
            .as_deref()
            .map_or("line of sight".to_string(), |t| format!("tool {t}")),
        clearance_deg: a.clearance,
        warnings,
    }
}

/// A rotary axis's limits: `free`, or `[min, max]`.
#[derive(Serialize)]
#[serde(untagged)]
pub enum Limit {
    Free(&'static str),
    Range([Option<f64>; 2]),
}

/// The machine as the JSON names it: its kind and each axis's limits.
#[derive(Serialize)]
pub struct MachineJson {
    kind: KinKind,
    #[serde(flatten)]
    axes: BTreeMap<&'static str, Limit>,
}

/// A facet by its index and centroid.
#[derive(Serialize)]
pub struct FacetJson {
    facet: usize,
    centroid: [f64; 3],
}

/// What `setup --json` prints.
#[derive(Serialize)]
pub struct Report {
    feasible: bool,
    setup: [[f64; 3]; 3],
    euler_zyx_deg: [f64; 3],
    required: Option<BTreeMap<&'static str, [f64; 2]>>,
    would_do: Option<BTreeMap<&'static str, [f64; 2]>>,
    max_tilt_deg: f64,
    usage: f64,
    machine: MachineJson,
    unreachable: Vec<FacetJson>,
    unreachable_area: f64,
    out_of_reach: Vec<FacetJson>,
    out_of_reach_area: f64,
    facets: usize,
    ignored: usize,
    grid: String,
    cells: usize,
    clearance_deg: f64,
    flipped: bool,
    mode: &'static str,
    seconds: f64,
    /// The verdict by the one rule, as the report's ([`verdict`]).
    verdict: Verdict,
}

fn facets(v: &[(usize, [f64; 3])]) -> Vec<FacetJson> {
    v.iter()
        .map(|&(facet, centroid)| FacetJson { facet, centroid })
        .collect()
}

impl Report {
    /// The summary of a search that took `seconds`.
    pub fn new(
        a: &SetupRequest,
        s: &Summary,
        machine: &Kinematics,
        (seconds, verdict): (f64, Verdict),
    ) -> Report {
        let limit = |ax: &RotaryAxis| match (ax.min, ax.max) {
            (None, None) => Limit::Free("free"),
            (lo, hi) => Limit::Range([lo, hi]),
        };
        let ranges = |r: Option<[(f64, f64); 2]>| {
            r.map(|r| {
                BTreeMap::from([(s.axes[0], [r[0].0, r[0].1]), (s.axes[1], [r[1].0, r[1].1])])
            })
        };
        let axes = BTreeMap::from([
            (s.axes[0], limit(&machine.first)),
            (s.axes[1], limit(&machine.second)),
        ]);
        Report {
            feasible: s.feasible,
            setup: s.setup,
            euler_zyx_deg: s.euler_zyx_deg,
            required: ranges(s.required),
            would_do: ranges(s.would_do),
            max_tilt_deg: s.max_tilt_deg,
            usage: s.usage,
            machine: MachineJson {
                kind: machine.kind,
                axes,
            },
            unreachable: facets(&s.unreachable),
            unreachable_area: s.unreachable_area,
            out_of_reach: facets(&s.out_of_reach),
            out_of_reach_area: s.out_of_reach_area,
            facets: s.facets,
            ignored: s.ignored,
            grid: s.grid.clone(),
            cells: s.cells,
            clearance_deg: a.clearance,
            flipped: s.flipped,
            mode: if a.tool.is_some() {
                "tool"
            } else {
                "line-of-sight"
            },
            seconds,
            verdict,
        }
    }
}

/// The text summary of the search on `part` (its name as printed).
pub fn render_text(
    a: &SetupRequest,
    part: &str,
    (s, v): (&Summary, &Verdict),
    plan: &SetupPlan,
) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "{part}: {} facets, {} grid ({} cells), clearance {}°",
        s.facets, s.grid, s.cells, a.clearance
    );
    let verdict = if s.feasible {
        "feasible in one setup"
    } else {
        "NOT feasible in one setup"
    };
    let _ = writeln!(o, "{verdict}");
    let _ = writeln!(o, "setup rotation (part → table):");
    for r in s.setup {
        let _ = writeln!(o, "  [{:9.6} {:9.6} {:9.6}]", r[0], r[1], r[2]);
    }
    let e = s.euler_zyx_deg;
    let _ = writeln!(o, "  Euler Z-Y-X: {:.3}°, {:.3}°, {:.3}°", e[0], e[1], e[2]);
    let [n0, n1] = s.axes.map(str::to_uppercase);
    if let Some(r) = s.required {
        let _ = writeln!(
            o,
            "required (the least of any setup): {n0} {:.2}..{:.2}°, {n1} {:.2}..{:.2}° (largest tilt {:.2}°, {:.0} % of the machine's ranges)",
            r[0].0, r[0].1, r[1].0, r[1].1, s.max_tilt_deg, 100.0 * s.usage
        );
    }
    if let Some(r) = s.would_do {
        let _ = writeln!(
            o,
            "as it lies in the file it would need {n0} {:.2}..{:.2}°, {n1} {:.2}..{:.2}°",
            r[0].0, r[0].1, r[1].0, r[1].1
        );
    }
    if !s.out_of_reach.is_empty() {
        let _ = writeln!(
            o,
            "{} facets ({:.2} mm²) out of the machine's reach",
            s.out_of_reach.len(),
            s.out_of_reach_area
        );
    }
    if let Some((t, c)) = s.unreachable.first() {
        let _ = writeln!(
            o,
            "{} facets no tool direction can see, no range reaches (the first: facet {t} at {c:?})",
            plan.inaccessible.len()
        );
    }
    o.push_str(&v.text());
    o
}

/// The kinematics of a machine file (`path` names it in the error), which
/// `setup` needs: the rotary axes.
/// The machine of `setup`: the kinematics of the machine `file` (read, with
/// its path), else a machine of `kind` with the rotary ranges `ranges`.
pub fn kinematics(
    file: Option<(&millplan_plan::machine::Machine, &str)>,
    kind: Option<MachineType>,
    (range1, range2): (&str, &str),
) -> Result<Kinematics, String> {
    match (file, kind) {
        (Some((m, path)), _) => file_kinematics(m, path),
        (None, Some(t)) => machine_of_type(t, range1, range2),
        (None, None) => Err("give --machine FILE or --type ca|ab".into()),
    }
}

pub fn file_kinematics(
    machine: &millplan_plan::machine::Machine,
    path: &str,
) -> Result<Kinematics, String> {
    machine.kinematics().cloned().ok_or_else(|| {
        format!("{path}: the machine file has no [kinematics] table: setup needs the rotary axes")
    })
}

/// Facets times directions above which the search shows its progress.
pub const SHOWN_WORK: usize = 20_000_000;

/// Whether the search over `mesh` with `p` takes long enough to show its
/// progress.
pub fn shows_progress(mesh: &TriMesh, p: &SetupParams) -> bool {
    mesh.len() * p.cells > SHOWN_WORK
}

/// The part turned into the setup found, as binary STL.
pub fn rotated_stl(mesh: &TriMesh, plan: &SetupPlan) -> Vec<u8> {
    let s = plan.best.setup;
    let mut rotated = mesh.clone();
    rotated.map_vertices(|v| s * v);
    let mut bytes = Vec::new();
    millplan_geom::stl::write_binary_stl(&rotated, "millplan setup", &mut bytes);
    bytes
}

/// The warning when the part's facets were wound inward (`None` when not).
pub fn flipped_note(plan: &SetupPlan, stl: &str) -> Option<String> {
    plan.flipped
        .then(|| format!("{stl}: the facets are wound inward (negative volume); turned outward"))
}
