//! `millplan orient`: lead and tilt per operation by the force model or the
//! machining time (spec process-models §2.4).

use crate::cmd::cut::{load_materials, VariantArg};
use crate::cmd::{arg, print_diagnostics, read_options, target_for, Range, TargetArg, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, read_surface, Outputs};
use millplan_models::leadtilt::{SearchOptions, Variant};
use millplan_plan::leadtilt::{choose_with, Objective, Oriented, Params, Stage, StockInput};
use millplan_plan::machine::Machine;
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::spec::StockSpec;
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Choose lead and tilt per ball-end operation (spec process-models §2.4):
/// a 5° grid over the ranges, then steepest descent from its best node, on
/// F_xy,max of the force model at --fz (--objective fxy) or on the machining
/// time estimated with acceleration, the feed scaled to keep the original
/// F_xy,max (--objective time).
///
/// Lead and tilt are taken in each point's frame of feed f, cross-feed
/// c = n × f and the part's normal n (from the STL at the contact), the
/// ball centre kept where the program has it. The convention is `cut`'s
/// (process-models §0): lead a right-handed turn about c, tilt one about f,
/// R = Rx(tilt)·Ry(lead) by default; a positive lead leans the shank toward
/// the feed (the tip trails), a positive tilt toward −c (right of the feed,
/// seen from the shank). `millplan cut` with the lead and tilt reported
/// (and the same --variant, tool, --flutes, --helix, --fz, --n, --ap,
/// --ae) gives the F_xy,max reported. A candidate is refused when the zero-speed tip would
/// cut (negative lead; zero lead, within 0.01°, unless R·(1 − cos tilt) ≥ --ap), when the
/// shank or holder meets the part at any point, or when the machine's rotary
/// axes cannot reach it. Writes the re-oriented CL (tool axes on every
/// point). Exit 3, nothing written, when no operation can be re-oriented.
///
/// With --stock the forces are evaluated on the engagement of the simulated
/// stock instead of one planar pass of --ap and --ae: the program is run
/// through the stock once as it is (a ball centre kept where the program has
/// it removes the same material at any orientation), and at up to --samples
/// moves per operation that remove material (the heaviest cuts, the rest
/// spread along the operation) the stock before the move is kept around the
/// ball; a candidate's F_xy,max is the largest at those moves, and its tip
/// cuts where, with no lead of the feed against the axis, it lies in that
/// material.
///
/// Before it is written the program is checked: the IR verifier, S and F
/// within the machine, every ball centre where the input put it, with
/// --stock no rapid through material and no shank in it (refused also when
/// the input did it, named as the input's), and no gouge into the part the
/// input did not have (three-axis moves). A check that fails names its line
/// and exits 3 with nothing written, unless --force.
#[derive(clap::Args)]
pub struct Args {
    /// Program with ball-end operations (APT/CL or G-code).
    pub path: PathBuf,
    /// Part surface (STL): the normals at the contacts and the collision
    /// tests.
    #[arg(long)]
    pub stl: PathBuf,
    /// Unit of the STL's numbers (an STL does not say): mm (default) or inch.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    /// Machine file (examples/machine.toml): rotary limits, and the axis
    /// limits of the time estimate (default: a built-in three-axis machine,
    /// no rotary limits).
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Named material (`millplan force materials` lists them).
    #[arg(long)]
    pub material: String,
    /// A TOML file of further materials (same form as the built-in table).
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Lead range LO:HI, degrees (positive: the shank toward the feed).
    #[arg(long, default_value = millplan_driver::command_defaults::orient::LEAD_RANGE, allow_hyphen_values = true)]
    pub lead_range: String,
    /// Tilt range LO:HI, degrees (positive: the shank toward −c, right of
    /// the feed seen from the shank).
    #[arg(long, default_value = millplan_driver::command_defaults::orient::TILT_RANGE, allow_hyphen_values = true)]
    pub tilt_range: String,
    /// What to minimise: fxy (F_xy,max at --fz) or time (with the feed
    /// scaled to the original force level).
    #[arg(long, value_enum, default_value = "fxy")]
    pub objective: ObjectiveArg,
    /// Order of the two turns: tilt-then-lead (process-models §0,
    /// R = Rx(tilt)·Ry(lead), axis (sin L, −cos L·sin T, cos L·cos T);
    /// variant 2 of kinematics-access-tools §2.2) or lead-then-tilt
    /// (R = Ry(lead)·Rx(tilt), axis (sin L·cos T, −sin T, cos L·cos T);
    /// variant 1); same signs either way, and `cut --variant` takes the
    /// same.
    #[arg(long, value_enum, default_value = "tilt-then-lead")]
    pub variant: VariantArg,
    /// Feed per tooth the forces are evaluated at, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::FZ)]
    pub fz: f64,
    /// Spindle speed, 1/min (default: the program's first cutting S word).
    #[arg(long)]
    pub n: Option<f64>,
    /// Number of flutes.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::FLUTES)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::HELIX_DEG)]
    pub helix: f64,
    /// Axial depth of the engagement the forces are evaluated for, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::AP)]
    pub ap: f64,
    /// Stepover of that engagement, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::AE)]
    pub ae: f64,
    /// Initial stock, for the engagement of the simulated stock instead of
    /// --ap/--ae: box:auto or box:auto:MARGIN, box:X0,Y0,Z0,X1,Y1,Z1,
    /// cylinder:auto or cylinder:auto:MARGIN, cylinder:CX,CY,Z0,Z1,D, stl:FILE
    /// or offset:MM (the --stl part grown by MM), as in `millplan simulate`.
    #[arg(long)]
    pub stock: Option<String>,
    /// Dexel size of the stock, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::RESOLUTION)]
    pub resolution: f64,
    /// Most sample moves per operation on the stock.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::SAMPLES)]
    pub samples: usize,
    /// The shank's reach: from the ball centre to the holder's face, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::orient::REACH)]
    pub reach: f64,
    /// Holder as DIAMETER:LENGTH, mm (default: no holder, the shank alone).
    #[arg(long)]
    pub holder: Option<String>,
    /// Output program (the extension or --to names the dialect).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Dialect to write: fanuc, sinumerik, heidenhain, linuxcnc or apt.
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Unit of a program that does not say: mm or inch.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Print a machine-readable summary (JSON) on standard output; errors
    /// too, as JSON on standard error.
    #[arg(long)]
    pub json: bool,
    /// Print no warnings, notes or progress (errors still print).
    #[arg(long, short)]
    pub quiet: bool,
    /// Write the program even when a check before writing refuses it (a
    /// ball centre moved, a rapid or shank in the stock, a new gouge, an S
    /// or F outside the machine); the run then ends with exit 3.
    #[arg(long)]
    pub force: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ObjectiveArg {
    Fxy,
    Time,
}

/// `LO:HI` in degrees, within ±89°.
fn range(flag: &str, s: &str) -> CliResult<(f64, f64)> {
    let bad = || {
        CliError::input(format!(
            "{flag} {s}: give LO:HI in degrees, LO ≤ HI, within ±89"
        ))
    };
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

fn holder(s: Option<&str>) -> CliResult<(f64, f64)> {
    let Some(s) = s else {
        return Ok((0.0, 0.0));
    };
    let bad = || {
        CliError::input(format!(
            "--holder {s}: give DIAMETER:LENGTH in mm, both positive"
        ))
    };
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

/// The inputs checked into the pass's parameters (before any file is read).
fn params(a: &Args) -> CliResult<(Params, f64)> {
    let lead = range("--lead-range", &a.lead_range)?;
    let tilt = range("--tilt-range", &a.tilt_range)?;
    let fz = arg("--fz", a.fz, Range::positive(10.0, "mm"))?;
    let ap = arg("--ap", a.ap, Range::positive(1000.0, "mm"))?;
    let ae = arg("--ae", a.ae, Range::positive(1000.0, "mm"))?;
    let reach = arg("--reach", a.reach, Range::positive(10_000.0, "mm"))?;
    let helix = arg("--helix", a.helix, Range::from(0.0, 60.0, "degrees"))?;
    if a.flutes == 0 || a.flutes > 64 {
        return Err(CliError::input("--flutes: give 1 to 64"));
    }
    let n = match a.n {
        Some(n) => arg("--n", n, Range::positive(crate::cmd::MAX_SPINDLE, "1/min"))?,
        None => 0.0,
    };
    let (holder_radius, holder_length) = holder(a.holder.as_deref())?;
    let materials = load_materials(a.materials.as_deref())?;
    let law = materials
        .get(&a.material)
        .map_err(|e| CliError::input(format!("--material: {e}")))?
        .law;
    Ok((
        Params {
            search: SearchOptions {
                lead,
                tilt,
                ..SearchOptions::default()
            },
            variant: Variant::from(a.variant),
            objective: match a.objective {
                ObjectiveArg::Fxy => Objective::Fxy,
                ObjectiveArg::Time => Objective::Time,
            },
            law,
            flutes: a.flutes,
            helix: helix.to_radians(),
            fz,
            rpm: n,
            ap,
            ae,
            reach,
            holder_radius,
            holder_length,
        },
        n,
    ))
}

/// The checked stock options: the spec, when given.
fn stock_spec(a: &Args) -> CliResult<Option<StockSpec>> {
    arg(
        "--resolution",
        a.resolution,
        Range::from(0.005, 100.0, "mm"),
    )?;
    if a.samples == 0 || a.samples > 4096 {
        return Err(CliError::input("--samples: give 1 to 4096"));
    }
    a.stock
        .as_deref()
        .map(|s| StockSpec::parse(s).map_err(|e| CliError::input(format!("--stock {e}"))))
        .transpose()
}

/// The strokes the stock is cut by: every operation whose cutter has a
/// shape (its flutes up to the tool's height, else the whole tool).
fn program_strokes(p: &millplan_nc::Program, res: f64, rapid: f64) -> Strokes {
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
fn tool_body(op: &millplan_nc::Operation) -> Option<ToolBody> {
    ToolBody::for_operation(op, &BodyOptions::default())
}

/// The re-oriented program against the input: the IR verifier, S and F
/// within the machine, every ball centre where the input put it, rapids and
/// shanks on the initial stock (with --stock). No gouge check against the
/// part: with every ball centre kept (checked) the ball meets the part
/// exactly where the input's did, and the three-axis gouge check cannot
/// see a tilted shank. A refusal ends the run (exit 3) unless --force.
fn check_oriented(
    a: &Args,
    (input, output): (&millplan_nc::Program, &millplan_nc::Program),
    stock: Option<&Stock>,
    machine: &Machine,
) -> CliResult<(Vec<Check>, bool)> {
    let checks = safety::check(&Inputs {
        input,
        output,
        part: None,
        stock,
        tool_body: &tool_body,
        machine: Some(machine),
        tip: TipRule::CentreKept,
        tol: Tolerances::default(),
        loads: None,
    });
    let ok = crate::verdict::enforce(&checks, &a.path, a.force)?;
    Ok((checks, ok))
}

/// The program's first cutting spindle speed (for a run without --n).
fn first_spindle(path: &Path, p: &millplan_nc::Program) -> CliResult<f64> {
    p.moves()
        .find(|m| m.is_cutting() && m.spindle > 0.0)
        .map(|m| m.spindle)
        .ok_or_else(|| {
            CliError::input(format!(
                "{}: the program sets no spindle speed; give --n",
                path.display()
            ))
        })
}

/// The initial stock and the strokes that cut it, for the choice; a note
/// on the moves the stock does not see.
fn stock_input<'a>(
    a: &Args,
    spec: &StockSpec,
    st: &'a Strokes,
    mesh: &millplan_geom::TriMesh,
) -> CliResult<StockInput<'a>> {
    if st.strokes.iter().all(|x| x.rapid) {
        return Err(CliError::input(format!(
            "{}: no cutting move can be simulated for --stock (no operation's tool has a shape, or every move is from or to an unknown position)",
            a.path.display()
        )));
    }
    let unsimulated = st.skipped.total();
    if unsimulated > 0 && !(a.quiet || a.json) {
        eprintln!(
            "{}: note: {unsimulated} moves are not simulated (their tool has no shape, or their position or axis is unknown): the stock does not see them",
            a.path.display()
        );
    }
    let stock = crate::cmd::simulate::initial_stock(
        &a.path,
        a.resolution,
        spec,
        st,
        Some(mesh),
        a.stl_units,
    )?;
    Ok(StockInput {
        stock,
        strokes: st,
        samples: a.samples,
        max_bytes: millplan_plan::leadtilt::MAX_CROP_BYTES,
    })
}

pub fn run(a: Args) -> CliResult<i32> {
    let (mut p, n) = params(&a)?;
    let spec = stock_spec(&a)?;
    let mut inputs: Vec<&Path> = vec![&a.path, &a.stl];
    inputs.extend(a.machine.as_deref());
    if let Some(StockSpec::Stl(b)) = &spec {
        inputs.push(b);
    }
    let mut outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], false)?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let parsed = read_program(&a.path, read_options(a.units, None)?)?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    let target = target_for(a.to, &a.output, parsed.program.source)?;
    if n <= 0.0 {
        p.rpm = first_spindle(&a.path, &parsed.program)?;
    }
    let (mesh, _) = read_surface(&a.stl, a.stl_units)?;
    let st = spec
        .as_ref()
        .map(|_| program_strokes(&parsed.program, a.resolution, machine.rapid));
    let unsimulated = st.as_ref().map_or(0, |s| s.skipped.total());
    let input = match (&spec, &st) {
        (Some(spec), Some(st)) => Some(stock_input(&a, spec, st, &mesh)?),
        _ => None,
    };
    let initial = input.as_ref().map(|i| i.stock.clone());
    let total = parsed.program.operations.len() as u64;
    let strokes_total = st.as_ref().map_or(0, |s| 2 * s.strokes.len()) as u64;
    let sim_bar = crate::progress::count(
        strokes_total,
        "stock",
        "strokes",
        !a.quiet && input.is_some(),
    );
    let bar = crate::progress::count(total, "lead/tilt", "operations", !a.quiet);
    let o = choose_with(
        &parsed.program,
        &mesh,
        &machine,
        &p,
        input,
        &|stage, done, _| match stage {
            Stage::Stock => sim_bar.set_position(done as u64),
            Stage::Operations => {
                sim_bar.finish_and_clear();
                bar.set_position(done as u64)
            }
        },
    )
    .map_err(|e| CliError::input(format!("{}: {e}", a.path.display())))?;
    sim_bar.finish_and_clear();
    bar.finish_and_clear();
    let mut summary = summary_json(&a, &o, p.objective, (spec.is_some(), unsimulated));
    if o.chosen.is_empty() {
        outputs.commit()?;
        report(&a, &summary);
        return Ok(EXIT_FINDINGS);
    }
    let (checks, checked) = check_oriented(
        &a,
        (&parsed.program, &o.program),
        initial.as_ref(),
        &machine,
    )?;
    summary["checks"] = json!(checks);
    crate::cmd::write_program_file(
        &o.program,
        machine.write_options(target),
        &mut outputs,
        &a.output,
        &a.path,
        a.quiet,
    )?;
    outputs.commit()?;
    report(&a, &summary);
    Ok(if checked { EXIT_OK } else { EXIT_FINDINGS })
}

/// The summary; `stock`: whether the engagement is the stock's, and the
/// moves it does not see.
fn summary_json(
    a: &Args,
    o: &Oriented,
    objective: Objective,
    (stock, unsimulated): (bool, usize),
) -> serde_json::Value {
    json!({
        "objective": objective,
        "operations": o.chosen,
        "skipped": o.skipped,
        "output": (!o.chosen.is_empty()).then(|| a.output.display().to_string()),
        "engagement": if stock { "stock" } else { "planar" },
        "stock": a.stock,
        "resolution_mm": stock.then_some(a.resolution),
        "unsimulated_moves": unsimulated,
    })
}

fn report(a: &Args, s: &serde_json::Value) {
    if a.json {
        crate::cmd::print_json(s.clone());
        return;
    }
    let unit = if s["objective"] == "time" { "s" } else { "N" };
    for c in s["operations"].as_array().into_iter().flatten() {
        let f = |k: &str| c[k].as_f64().unwrap_or(f64::NAN);
        let before = c["objective_before"]
            .as_f64()
            .map_or("(the orientation read is refused)".to_string(), |v| {
                format!("{v:.1} {unit}")
            });
        let source = match c["engagement"].as_str() {
            Some("stock") => format!("on the stock at {} sample moves", c["samples"]),
            _ => "on the planar pass".to_string(),
        };
        outln!(
            "operation {}: lead {:.2}°, tilt {:.2}° (read: {:.2}°, {:.2}°); {} {} → {:.1} {unit} {source}; refused: {} by tip contact, {} by holder collision, {} by rotary limits",
            c["operation"],
            f("lead"),
            f("tilt"),
            f("lead_before"),
            f("tilt_before"),
            s["objective"].as_str().unwrap_or(""),
            before,
            f("objective_after"),
            c["refused"]["tip_contact"],
            c["refused"]["holder_collision"],
            c["refused"]["rotary_limits"],
        );
    }
    for k in s["skipped"].as_array().into_iter().flatten() {
        outln!(
            "operation {}: left as it was: {}",
            k["operation"],
            k["reason"].as_str().unwrap_or("")
        );
    }
    match s["output"].as_str() {
        Some(o) => outln!("wrote {o}"),
        None => outln!("no operation could be re-oriented: nothing written"),
    }
}
