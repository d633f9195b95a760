//! `millplan raster`: the request checked into the raster's parameters, its
//! size against the limits, the checks of the written raster, the run
//! (`run_command`) and the typed summary.

use crate::check::{arg, raster_spacing, tool_shape, Range, FEED, SPINDLE};
use millplan_geom::limits::{amount, Exceeded};
use millplan_geom::{Aabb, TriMesh};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back;
use millplan_nc::write::Target;
use millplan_nc::{Dialect, Program};
use millplan_plan::machine::Machine;
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_plan::timing::TimeEstimate;
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{GougeParams, GougeReport};
pub use millplan_sim::raster::RasterParams;
use millplan_sim::raster::{estimate, raster};
use millplan_sim::stock::tool::ToolBody;
use serde::Serialize;

mod command;
pub use command::{run_command, RasterCommand, RasterRun};

/// The options of `millplan raster`.
#[derive(Clone, Debug)]
pub struct RasterRequest {
    pub tool: String,
    /// Degrees from +X.
    pub angle: f64,
    pub stepover: f64,
    pub step: f64,
    pub oneway: bool,
    pub boundary: f64,
    /// 0: no refinement.
    pub tol: f64,
    pub clearance: f64,
    pub feed: f64,
    pub spindle: f64,
}

/// Every argument in its physical range: the stepover from a thousandth of
/// the tool's diameter, the step from a micrometre, the clearance above the
/// part.
pub fn params(a: &RasterRequest) -> Result<RasterParams, String> {
    let shape = tool_shape("--tool", &a.tool)?;
    let d = 2.0 * shape.radius();
    arg("--angle", a.angle, Range::from(-360.0, 360.0, "degrees"))?;
    raster_spacing(d, a.stepover, a.step)?;
    if a.tol != 0.0 {
        let r = Range::from(1e-5, 10.0, "mm (or 0: no refinement)");
        arg("--tol", a.tol, r)?;
    }
    arg("--boundary", a.boundary, Range::from(-1e6, 1e6, "mm"))?;
    let above = Range::positive(1e4, "mm above the part");
    arg("--clearance", a.clearance, above)?;
    arg("--feed", a.feed, FEED)?;
    arg("--spindle", a.spindle, SPINDLE)?;
    let mut p = RasterParams::new(shape);
    p.angle_deg = a.angle;
    p.stepover = a.stepover;
    p.step = a.step;
    p.zigzag = !a.oneway;
    p.margin = a.boundary;
    p.tol = (a.tol > 0.0).then_some(a.tol);
    p.clearance = a.clearance;
    p.feed = a.feed;
    p.spindle = a.spindle;
    Ok(p)
}

/// The margin within the part (at most half its narrower side, or nothing
/// is left) and beyond it by at most its size and the tool, and the raster's
/// points within `max_moves`: counted from the grid, before any point is
/// dropped. Returns the points and the bytes they will take.
pub fn check_grid(p: &RasterParams, bounds: &Aabb, max_moves: f64) -> Result<(f64, f64), String> {
    let size = bounds.size();
    let (narrow, wide) = (size.x.min(size.y), size.x.max(size.y));
    let reach = wide + 2.0 * p.shape.radius();
    if !(p.margin < narrow / 2.0 && p.margin >= -reach) {
        return Err(format!(
            "--boundary {}: must be from {} to under {} mm for this part ({} × {} mm in XY, with this tool)",
            p.margin,
            amount(-reach),
            amount(narrow / 2.0),
            amount(size.x),
            amount(size.y)
        ));
    }
    let e = estimate(bounds, p, GougeParams::default().step);
    if !(e.points <= max_moves) {
        let needs = format!(
            "--stepover {} and --step {} over {} × {} mm make {} points",
            p.stepover,
            p.step,
            amount(size.x - 2.0 * p.margin),
            amount(size.y - 2.0 * p.margin),
            amount(e.points.ceil())
        );
        return Err(Exceeded::new("moves", needs, max_moves).to_string());
    }
    Ok((e.points, e.bytes))
}

/// The raster over `mesh`, with the part's drop-cutter tree for its checks.
pub fn generate(mesh: &TriMesh, p: &RasterParams) -> (Program, DropMesh) {
    let part = DropMesh::new(mesh);
    let prog = raster(&part, &mesh.bounds(), p);
    (prog, part)
}

/// The raster checked from its written bytes `out` (so findings name lines
/// of the written program): the read-back, the IR verifier, S and F within
/// the machine, and its gouge check as `millplan gouge` would run it
/// (rapids too). An `Err` is a raster that does not read back (a bug).
pub fn check(
    (prog, out): (&Program, &[u8]),
    target: Target,
    part: &DropMesh,
    machine: &Machine,
    p: &RasterParams,
) -> Result<(Vec<Check>, GougeReport), String> {
    let back = read_back(out, target, prog, &Tolerance::default())
        .map_err(|e| format!("the raster written does not read back ({e}); not written"))?;
    // A generated program: every finding is the raster's own.
    let none = Program::new(Dialect::Generated);
    let shape = p.shape;
    let (mut checks, rep) = safety::check_with_gouges(&Inputs {
        input: &none,
        output: &back.program,
        part: Some(part),
        stock: None,
        tool_body: &|_| Some(ToolBody::new(shape)),
        machine: Some(machine),
        tip: TipRule::Free,
        tol: Tolerances::default(),
        loads: None,
    });
    checks.insert(0, safety::read_back_check(&back));
    Ok((checks, rep.unwrap_or_default()))
}

/// The gouge check's counts.
#[derive(Serialize)]
pub struct GougeJson {
    moves_checked: usize,
    points_checked: usize,
    gouges: usize,
    max_depth_mm: f64,
}

/// What `raster --json` prints.
#[derive(Serialize)]
pub struct Report<'a> {
    output: String,
    moves: usize,
    cutting_mm: f64,
    time_s: f64,
    time_nominal_s: f64,
    gouge_check: GougeJson,
    checks: &'a [Check],
    #[serde(skip)]
    feed: f64,
}

impl<'a> Report<'a> {
    pub fn new(
        output: String,
        (prog, machine, p): (&Program, &Machine, &RasterParams),
        (rep, checks): (&GougeReport, &'a [Check]),
        est: &TimeEstimate,
    ) -> Self {
        let s = millplan_nc::stats::summarize(prog, machine.rapid);
        Report {
            output,
            moves: prog.move_count(),
            cutting_mm: s.cutting_mm,
            time_s: est.total_s,
            time_nominal_s: est.nominal_s,
            gouge_check: GougeJson {
                moves_checked: rep.moves_checked,
                points_checked: rep.points_checked,
                gouges: rep.gouges.len(),
                max_depth_mm: rep.max_depth,
            },
            checks,
            feed: p.feed,
        }
    }

    /// One line: what was written and what the gouge check found.
    pub fn render_text(&self) -> String {
        let g = &self.gouge_check;
        format!(
            "wrote {}: {} moves, {:.0} mm cutting, {:.0} s estimated with acceleration ({:.0} s at {} mm/min); gouge check: {} moves at {} points, {}\n",
            self.output,
            self.moves,
            self.cutting_mm,
            self.time_s,
            self.time_nominal_s,
            self.feed,
            g.moves_checked,
            g.points_checked,
            if g.gouges == 0 { "clean" } else { "gouges" }
        )
    }
}
