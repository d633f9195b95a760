//! `millplan orient`: the request checked into the lead/tilt pass's
//! parameters, the stock the choice runs on, the checks of the re-oriented
//! program, the run (`run_command`) and the summary it prints.

use crate::check::{arg, Range, MAX_SPINDLE};
use millplan_models::force::materials::Materials;
use millplan_models::leadtilt::{SearchOptions, Variant};
use millplan_nc::{Operation, Program};
use millplan_plan::leadtilt::{
    choose_with, Objective, OpChoice, OpSkipped, Oriented, Params, Stage, StockInput,
};
use millplan_plan::machine::Machine;
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_report::html::{failed_checks, worse_words, Evidence, Verdict};
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::stock::path::{strokes, PathOptions, Strokes, Unsimulated};
use millplan_sim::stock::spec::StockSpec;
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use serde::Serialize;
use std::fmt::Write as _;

mod command;
pub use command::{run_command, OrientCommand, OrientRun};

/// The options of `millplan orient` as given.
#[derive(Clone, Debug)]
pub struct OrientRequest {
    /// `LO:HI`, degrees.
    pub lead_range: String,
    pub tilt_range: String,
    pub variant: Variant,
    pub objective: Objective,
    pub fz: f64,
    /// Spindle speed; `None`: the program's first cutting S.
    pub n: Option<f64>,
    pub flutes: usize,
    /// Degrees.
    pub helix: f64,
    pub ap: f64,
    pub ae: f64,
    pub reach: f64,
    /// `DIAMETER:LENGTH`, mm.
    pub holder: Option<String>,
    pub material: String,
    pub stock: Option<String>,
    pub resolution: f64,
    pub samples: usize,
}

/// `LO:HI` in degrees, within ±89°.
fn range(flag: &str, s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("{flag} {s}: give LO:HI in degrees, LO ≤ HI, within ±89");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if !(a.is_finite() && b.is_finite() && a <= b && a >= -89.0 && b <= 89.0) {
        return Err(bad());
    }
    Ok((a, b))
}

/// `DIAMETER:LENGTH` as (radius, length); none given: no holder.
fn holder(s: Option<&str>) -> Result<(f64, f64), String> {
    let Some(s) = s else {
        return Ok((0.0, 0.0));
    };
    let bad = || format!("--holder {s}: give DIAMETER:LENGTH in mm, both positive");
    let (d, l) = s.split_once(':').ok_or_else(bad)?;
    let (d, l): (f64, f64) = (
        d.trim().parse().map_err(|_| bad())?,
        l.trim().parse().map_err(|_| bad())?,
    );
    if !(d.is_finite() && l.is_finite() && d > 0.0 && l > 0.0) {
        return Err(bad());
    }
    Ok((d / 2.0, l))
}

/// The request checked into the pass's parameters (before any program is
/// read); `rpm` is 0 when the program's own speed is to be taken
/// ([`first_spindle`]).
pub fn params(a: &OrientRequest, materials: &Materials) -> Result<Params, String> {
    let lead = range("--lead-range", &a.lead_range)?;
    let tilt = range("--tilt-range", &a.tilt_range)?;
    let fz = arg("--fz", a.fz, Range::positive(10.0, "mm"))?;
    let ap = arg("--ap", a.ap, Range::positive(1000.0, "mm"))?;
    let ae = arg("--ae", a.ae, Range::positive(1000.0, "mm"))?;
    let reach = arg("--reach", a.reach, Range::positive(10_000.0, "mm"))?;
    let helix = arg("--helix", a.helix, Range::from(0.0, 60.0, "degrees"))?;
    if a.flutes == 0 || a.flutes > 64 {
        return Err("--flutes: give 1 to 64".into());
    }
    let rpm = match a.n {
        Some(n) => arg("--n", n, Range::positive(MAX_SPINDLE, "1/min"))?,
        None => 0.0,
    };
    let (holder_radius, holder_length) = holder(a.holder.as_deref())?;
    let law = materials
        .get(&a.material)
        .map_err(|e| format!("--material: {e}"))?
        .law;
    Ok(Params {
        search: SearchOptions {
            lead,
            tilt,
            ..SearchOptions::default()
        },
        variant: a.variant,
        objective: a.objective,
        law,
        flutes: a.flutes,
        helix: helix.to_radians(),
        fz,
        rpm,
        ap,
        ae,
        reach,
        holder_radius,
        holder_length,
    })
}

/// The checked stock options: the spec, when given.
pub fn stock_spec(a: &OrientRequest) -> Result<Option<StockSpec>, String> {
    arg(
        "--resolution",
        a.resolution,
        Range::from(0.005, 100.0, "mm"),
    )?;
    if a.samples == 0 || a.samples > 4096 {
        return Err("--samples: give 1 to 4096".into());
    }
    a.stock
        .as_deref()
        .map(|s| StockSpec::parse(s).map_err(|e| format!("--stock {e}")))
        .transpose()
}

/// The strokes the stock is cut by: every operation whose cutter has a
/// shape (its flutes up to the tool's height, else the whole tool).
pub fn program_strokes(p: &Program, res: f64, rapid: f64) -> Strokes {
    strokes(
        p,
        tool_body,
        &PathOptions {
            chord: res / 4.0,
            rapid_rate: rapid,
        },
    )
}

/// The body of an operation's tool: its cutter, flutes up to the tool's
/// height (else the whole tool cuts).
fn tool_body(op: &Operation) -> Option<ToolBody> {
    ToolBody::for_operation(op, &BodyOptions::default())
}

/// Whether the strokes hold a cutting move the stock can see; the error
/// names `program`.
pub fn simulable(st: &Strokes, program: &str) -> Result<(), String> {
    if st.strokes.iter().all(|x| x.rapid) {
        return Err(format!(
            "{program}: no cutting move can be simulated for --stock (no operation's tool has a shape, or every move is from or to an unknown position)"
        ));
    }
    Ok(())
}

/// The choice's stock input: the initial stock and the strokes that cut it.
pub fn stock_input(stock: Stock, st: &Strokes, samples: usize) -> StockInput<'_> {
    StockInput {
        stock,
        strokes: st,
        samples,
        max_bytes: millplan_plan::leadtilt::MAX_CROP_BYTES,
    }
}

/// The program's first cutting spindle speed (for a run without --n).
pub fn first_spindle(p: &Program) -> Option<f64> {
    p.moves()
        .find(|m| m.is_cutting() && m.spindle > 0.0)
        .map(|m| m.spindle)
}

/// The re-oriented program against the input: the IR verifier, S and F
/// within the machine, every ball centre where the input put it, rapids and
/// shanks on the initial stock (with a stock), and the gouges into `part`
/// (a leaned ball by its distance to the part; the input's own refused too,
/// as `optimise` does: a user trial saw a program gouging 2 mm written as
/// Green because the ball centres were kept).
pub fn check(
    input: &Program,
    output: &Program,
    (stock, part): (Option<&Stock>, &millplan_geom::TriMesh),
    machine: &Machine,
) -> Vec<Check> {
    let part = DropMesh::new(part);
    safety::check(&Inputs {
        input,
        output,
        part: Some(&part),
        stock,
        tool_body: &tool_body,
        machine: Some(machine),
        tip: TipRule::CentreKept,
        tol: Tolerances::default(),
        loads: None,
    })
}

/// What `millplan orient` works on besides its request: the program (its
/// file's name for errors), the part, the machine, an `stl:` stock's blank
/// (read), the memory the stock may take and the output's name.
pub struct OrientInputs<'a> {
    pub name: &'a str,
    pub output: &'a str,
    pub program: &'a Program,
    pub mesh: &'a millplan_geom::TriMesh,
    pub machine: &'a Machine,
    pub blank: Option<&'a millplan_geom::TriMesh>,
    pub memory: u64,
}

/// What a run of `millplan orient` made: the summary (without the checks),
/// the re-oriented program and its checks against the input (none when no
/// operation was re-oriented), and the moves the stock did not see.
pub struct Outcome {
    pub summary: Summary,
    pub program: Program,
    pub checks: Vec<Check>,
    /// Whether any operation was re-oriented (else nothing is to be written).
    pub chosen: bool,
    /// The moves the stock did not see, by reason.
    pub unsimulated: Unsimulated,
}

impl Outcome {
    /// The note on moves the stock did not see, for the program `path`
    /// (`None` when every move was simulated).
    pub fn unsimulated_note(&self, path: &str) -> Option<String> {
        let u = &self.unsimulated;
        (u.total() > 0).then(|| format!(
            "{path}: note: {} moves are not simulated (their tool has no shape, or their position or axis is unknown{}): the stock does not see them",
            u.total(),
            u.first()
        ))
    }
}

/// `millplan orient`: the spindle speed from the program where `--n` gave
/// none, with `--stock` the stock and the strokes that cut it, the choice
/// per operation (`progress` hears its stages), the summary and the checks
/// of the re-oriented program.
pub fn command(
    a: &OrientRequest,
    mut p: Params,
    g: &OrientInputs,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<Outcome, String> {
    let spec = stock_spec(a)?;
    if p.rpm <= 0.0 {
        p.rpm = first_spindle(g.program)
            .ok_or_else(|| format!("{}: the program sets no spindle speed; give --n", g.name))?;
    }
    let st = spec
        .as_ref()
        .map(|_| program_strokes(g.program, a.resolution, g.machine.rapid));
    let unsimulated = st.as_ref().map_or_else(Unsimulated::default, |s| s.skipped);
    let input = match (&spec, &st) {
        (Some(spec), Some(st)) => {
            simulable(st, g.name)?;
            let parts = (Some(g.mesh), g.blank);
            // The stock before the program is kept beside the one cut.
            let memory = (g.memory, 2);
            let stock =
                crate::simulate::build_stock(g.name, a.resolution, spec, st, parts, memory)?;
            Some(stock_input(stock, st, a.samples))
        }
        _ => None,
    };
    let initial = input.as_ref().map(|i| i.stock.clone());
    let o = choose_with(g.program, g.mesh, g.machine, &p, input, progress)
        .map_err(|e| format!("{}: {e}", g.name))?;
    let summary = Summary::new(a, &o, g.output, &unsimulated);
    let chosen = !o.chosen.is_empty();
    let checks = if chosen {
        check(g.program, &o.program, (initial.as_ref(), g.mesh), g.machine)
    } else {
        Vec::new()
    };
    Ok(Outcome {
        summary,
        program: o.program,
        checks,
        chosen,
        unsimulated,
    })
}

/// An operation's objective that grew by more than this share counts as
/// worse in the verdict (below it: the search's resolution).
pub const OBJECTIVE_WORSE: f64 = 0.005;

/// What `orient` reports (`--json`).
#[derive(Serialize)]
pub struct Summary {
    pub objective: Objective,
    pub operations: Vec<OpChoice>,
    pub skipped: Vec<OpSkipped>,
    /// The file written; `None` when no operation could be re-oriented.
    pub output: Option<String>,
    /// `stock` or `planar`.
    pub engagement: &'static str,
    pub stock: Option<String>,
    pub resolution_mm: Option<f64>,
    pub unsimulated_moves: usize,
    /// The checks of the written program (absent when nothing is written).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checks: Option<Vec<Check>>,
    /// The verdict by the one rule: red when a check of the written program
    /// failed; amber when nothing was re-oriented, an operation's objective
    /// got worse, a ball-end operation was left as it was or moves are not
    /// simulated; green otherwise.
    pub verdict: Verdict,
}

/// The warnings of a choice: ball-end operations left as they were (the
/// pass applies to them; other tools are not its business) and moves the
/// stock does not see.
fn warnings(o: &Oriented, unsimulated: &Unsimulated) -> Vec<String> {
    let is_ball = |k: usize| {
        o.program
            .operations
            .get(k)
            .and_then(|op| op.tool.as_ref())
            .and_then(|t| t.cutter)
            .is_some_and(|c| c.kind == millplan_nc::CutterKind::Ball)
    };
    let mut w: Vec<String> = o
        .skipped
        .iter()
        .filter(|k| is_ball(k.operation))
        .map(|k| {
            format!(
                "operation {} (a ball-end mill) is left as it was: {}",
                k.operation + 1,
                k.reason
            )
        })
        .collect();
    if unsimulated.total() > 0 {
        w.push(format!(
            "{} moves are not simulated (their tool has no shape, or their position or axis is unknown{}): the stock does not see them",
            unsimulated.total(),
            unsimulated.first()
        ));
    }
    w
}

impl Summary {
    /// The summary of an outcome written to `output`; `unsimulated`: the
    /// moves the stock does not see (with a stock).
    pub fn new(
        a: &OrientRequest,
        o: &Oriented,
        output: &str,
        unsimulated: &Unsimulated,
    ) -> Summary {
        let stock = a.stock.is_some();
        let mut s = Summary {
            objective: a.objective,
            operations: o.chosen.clone(),
            skipped: o.skipped.clone(),
            output: (!o.chosen.is_empty()).then(|| output.to_string()),
            engagement: if stock { "stock" } else { "planar" },
            stock: a.stock.clone(),
            resolution_mm: stock.then_some(a.resolution),
            unsimulated_moves: unsimulated.total(),
            checks: None,
            verdict: Verdict {
                warnings: warnings(o, unsimulated),
                ..Verdict::default()
            },
        };
        s.judge();
        s
    }

    /// The summary with the checks of the written program, judged again.
    pub fn with_checks(mut self, checks: Vec<Check>) -> Summary {
        self.checks = Some(checks);
        self.judge();
        self
    }

    /// The verdict from the checks, what was chosen and the warnings.
    fn judge(&mut self) {
        let (name, unit) = match self.objective {
            Objective::Time => ("time", "s"),
            Objective::Fxy => ("F_xy,max", "N"),
        };
        let worse = self
            .operations
            .iter()
            .filter_map(|c| {
                let b = c.objective_before?;
                (c.objective_after > b * (1.0 + OBJECTIVE_WORSE)).then(|| {
                    worse_words(
                        &format!("operation {} {name}", c.operation + 1),
                        b,
                        c.objective_after,
                        1,
                        unit,
                    )
                })
            })
            .collect();
        let e = Evidence {
            failed: self
                .checks
                .as_deref()
                .map(failed_checks)
                .unwrap_or_default(),
            kept: self.operations.is_empty(),
            worse,
            not_better: None,
        };
        let warnings = std::mem::take(&mut self.verdict.warnings);
        self.verdict = Verdict::of(&e, warnings);
    }

    /// The text report: a line per operation (counted from 1, as `inspect`,
    /// `gouge` and `feed` count them), then what was written and the verdict.
    pub fn render_text(&self) -> String {
        let mut o = String::new();
        let time = self.objective == Objective::Time;
        let (name, unit) = if time { ("time", "s") } else { ("fxy", "N") };
        for c in &self.operations {
            let before = c
                .objective_before
                .map_or("(the orientation read is refused)".to_string(), |v| {
                    format!("{v:.1} {unit}")
                });
            let source = match c.engagement {
                millplan_plan::leadtilt::EngagementSource::Stock => {
                    format!("on the stock at {} sample moves", c.samples)
                }
                _ => "on the planar pass".to_string(),
            };
            let _ = writeln!(
                o,
                "operation {}: lead {:.2}°, tilt {:.2}° (read: {:.2}°, {:.2}°); {name} {before} → {:.1} {unit} {source}; refused: {} by tip contact, {} by holder collision, {} by rotary limits",
                c.operation + 1,
                c.lead,
                c.tilt,
                c.lead_before,
                c.tilt_before,
                c.objective_after,
                c.refused.tip_contact,
                c.refused.holder_collision,
                c.refused.rotary_limits,
            );
        }
        for k in &self.skipped {
            let _ = writeln!(
                o,
                "operation {}: left as it was: {}",
                k.operation + 1,
                k.reason
            );
        }
        match &self.output {
            Some(p) => {
                let _ = writeln!(o, "wrote {p}");
            }
            None => o.push_str("no operation could be re-oriented: nothing written\n"),
        }
        o.push_str(&self.verdict.text());
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command_defaults::orient as d;
    use millplan_geom::{DVec3, TriMesh};
    use millplan_nc::{Cutter, Dialect, Move};

    fn request(n: Option<f64>) -> OrientRequest {
        OrientRequest {
            lead_range: d::LEAD_RANGE.into(),
            tilt_range: d::TILT_RANGE.into(),
            variant: Variant::LeadThenTilt,
            objective: Objective::Fxy,
            fz: d::FZ,
            n,
            flutes: d::FLUTES,
            helix: d::HELIX_DEG,
            ap: d::AP,
            ae: d::AE,
            reach: d::REACH,
            holder: None,
            material: "al7075".into(),
            stock: None,
            resolution: d::RESOLUTION,
            samples: d::SAMPLES,
        }
    }

    /// A flat 100 × 100 mm plate, top at z = 0.
    fn plate() -> TriMesh {
        let v = [
            DVec3::new(-50.0, -50.0, 0.0),
            DVec3::new(50.0, -50.0, 0.0),
            DVec3::new(50.0, 50.0, 0.0),
            DVec3::new(-50.0, 50.0, 0.0),
        ];
        TriMesh::from_soup(&[[v[0], v[1], v[2]], [v[0], v[2], v[3]]]).0
    }

    /// A D10 ball along +X on the plate, vertical, with no spindle speed.
    fn program() -> Program {
        let mut op = Operation {
            start: DVec3::new(-30.0, 0.0, 5.0),
            tool: Some(millplan_nc::Tool {
                number: Some(1),
                name: None,
                cutter: Some(Cutter::ball(10.0)),
                line: 1,
            }),
            ..Operation::default()
        };
        for k in 0..=30 {
            let at = DVec3::new(-30.0 + 2.0 * k as f64, 0.0, 0.0);
            op.moves.push(Move::linear(at, 1000.0));
        }
        let mut p = Program::new(Dialect::Fanuc);
        p.operations.push(op);
        p
    }

    /// On a flat plate the vertical ball cuts with its centre, where the
    /// tip rule (process-models §1.4c) refuses lead 0 and the force model
    /// prefers a forward lean: the command re-orients the operation with a
    /// positive lead, every ball centre kept (its checks pass) and the
    /// output named. Without --n a program with no S is the program's
    /// error.
    #[test]
    fn the_command_leans_the_ball_forward_and_asks_for_a_speed() {
        let materials = Materials::builtin();
        let (mesh, machine, p) = (plate(), Machine::default(), program());
        let g = OrientInputs {
            name: "plate.nc",
            output: "out.nc",
            program: &p,
            mesh: &mesh,
            machine: &machine,
            blank: None,
            memory: 1 << 30,
        };
        let req = request(None);
        let params = super::params(&req, &materials).expect("params");
        let e = command(&req, params, &g, &|_, _, _| {})
            .err()
            .expect("no S");
        assert!(e.starts_with("plate.nc: ") && e.contains("--n"), "{e}");
        let req = request(Some(8000.0));
        let params = super::params(&req, &materials).expect("params");
        let Ok(o) = command(&req, params, &g, &|_, _, _| {}) else {
            panic!("orients")
        };
        assert!(o.chosen);
        assert!(o.summary.operations[0].lead > 1.0);
        assert!(safety::passed(&o.checks), "{:?}", o.checks);
        assert_eq!(o.summary.output.as_deref(), Some("out.nc"));
        assert_eq!(o.unsimulated.total(), 0);
    }
}
