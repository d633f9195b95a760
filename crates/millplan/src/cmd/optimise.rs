//! `millplan optimise`: the compiler driver — parses, reads the files,
//! builds a `millplan_driver::Job`, runs it and prints.

use crate::cmd::{load_machine, print_diagnostics, TargetArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use crate::timings::{Clock, Table as _};
use millplan_driver::given::{Given, GivenError};
use millplan_driver::passes::{self, ORDER};
use millplan_driver::report::{self, InputNames, Plotted};
use millplan_driver::tools::Library;
use millplan_driver::StockSpec;
use millplan_driver::{Inputs, Job, OptionsRequest, Outcome, Verdict, Written};
use std::path::{Path, PathBuf};

/// Take a CAM program to a verified, better program for one machine, stock,
/// material and part: every pass the inputs allow, the result written,
/// re-read from its own bytes and checked before it is put in place.
///
/// Passes, in order (`--list-passes` prints what each needs and changes): speed (constant
/// cutting speed for ball-end operations; needs --stl), reorder (the order as it will run, kept
/// unless it wins; needs --stl), orient (lead/tilt of five-axis ball-end CL from the forces on the
/// stock, ball centres kept, as `millplan orient --stock` with its defaults and the job's ap,
/// flutes, helix and resolution; needs --stl, --stock, --material), feed (a feed per block from
/// the forces on the stock under the machine's spindle chart and --limit; needs --stock and
/// --material), post (five-axis CL through the machine's kinematics to joint positions, feeds in
/// inverse time when the machine file's `[post]` says `inverse_time = true` or --g93 is given;
/// the posted tips are checked through the forward kinematics). In the default list a pass whose
/// inputs are missing is skipped and says why; one named in --passes is refused instead (exit 2,
/// before any work). A pass the program has nothing for (post on three-axis) is always skipped.
///
/// Defaults (each printed with where it came from): vc from the material's
/// cutting data; the spindle speed of moves without S from vc on the tool's
/// diameter (--spindle gives it); the largest feed per tooth from the
/// material's chip load at each tool's diameter, the smallest 0.01 mm
/// (--limit fz_min=MM,fz_max=MM set them); torque and power from the
/// machine's spindle chart at each block's speed; F_xy (and torque and
/// power when the machine has no chart) no higher than the input's own
/// largest on the stock. --limit fxy=N,torque=N·mm,power=W,stress=MPa,
/// deflection=mm gives a limit instead.
///
/// Checks of what is written, on the program re-read from its bytes:
/// read-back (parses, commands what the optimised program does, IR verifier), machine (S and F
/// within the machine), tip (the tool tip where the input put it; the ball centre after orient),
/// rapids-and-holder (on the stock: refused even when the input had it), loads (under every limit
/// within 0.5 %), gouge (none, the input's own refused too unless within 0.05 mm).
///
/// Exit codes: 0 written; 2 bad input; 3 a check failed (the check and line
/// are named; nothing written unless --force).
#[derive(clap::Args)]
pub struct Args {
    /// Program (APT/CL or G-code).
    #[arg(required_unless_present = "list_passes")]
    pub path: Option<PathBuf>,
    #[command(flatten)]
    pub part: crate::cmd::args::OptionalPart,
    /// Initial stock: box:auto or box:auto:MARGIN, box:X0,Y0,Z0,X1,Y1,Z1,
    /// cylinder:auto or cylinder:auto:MARGIN, cylinder:CX,CY,Z0,Z1,D, stl:FILE or offset:MM
    /// (the --stl part grown by MM), as in `millplan simulate`.
    #[arg(long)]
    pub stock: Option<String>,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    /// Named material (`millplan force materials` lists them).
    #[arg(long)]
    pub material: Option<String>,
    /// A TOML file of further materials.
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Tool library (the SQLite file of `millplan tool`): each tool the
    /// program calls takes its radius and length as measured (R + DR,
    /// L + DL), flutes, helix, stick-out and holder from it; a tool the
    /// library lacks, has locked or has worn out stops the run at the tool
    /// call before any work.
    #[arg(long, value_name = "LIBRARY.db")]
    pub tools: Option<PathBuf>,
    /// Cutter for operations whose tool has no geometry, or to override it:
    /// ball:D, flat:D or bull:D:R.
    #[arg(long)]
    pub tool: Option<String>,
    /// Flutes of every tool (default 2).
    #[arg(long)]
    pub flutes: Option<usize>,
    /// Cutting speed, m/min (default: the material's cutting data).
    #[arg(long)]
    pub vc: Option<f64>,
    /// Spindle speed of cutting moves without S, 1/min (default: from vc
    /// on the tool's diameter).
    #[arg(long)]
    pub spindle: Option<f64>,
    /// Dexel size of the stock, mm (default 0.1).
    #[arg(long)]
    pub resolution: Option<f64>,
    /// Tolerance of the checks, mm (default 0.01; the input's own gouges are reported only to
    /// max(0.05, tol)); also how far the post lets the tool tip stray while the rotaries move.
    #[arg(long)]
    pub tol: Option<f64>,
    /// Post five-axis programs with inverse-time feed (G93) whatever the
    /// machine file says.
    #[arg(long)]
    pub g93: bool,
    /// Passes to run, in this order, comma-separated (default: all the
    /// inputs allow, in the order above). A pass named here that a missing
    /// --stl, --stock, --material or --machine keeps from running stops the
    /// run (exit 2); one the program has nothing for is skipped.
    #[arg(long, value_name = "LIST")]
    pub passes: Option<String>,
    /// Print the pass table (what each pass needs and changes) and stop.
    #[arg(long)]
    pub list_passes: bool,
    /// Output program.
    #[arg(short, long, required_unless_present = "list_passes")]
    pub output: Option<PathBuf>,
    /// Output dialect (default: the machine file's, else the file name's,
    /// else the input's).
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// HTML report: verdict, inputs, passes, before → after, checks, plots.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub robot: crate::cmd::robot::OptimiseRobotArgs,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

fn options(a: &Args) -> OptionsRequest {
    OptionsRequest {
        vc: a.vc,
        spindle: a.spindle,
        tool: a.tool.clone(),
        flutes: a.flutes,
        resolution: a.resolution,
        loads: crate::limits::loads(),
        tol: a.tol,
        memory: Some(crate::limits::get().memory),
        g93: a.g93,
    }
}

fn read_inputs(a: &Args, path: &Path) -> CliResult<Inputs> {
    let parsed = a.units.read(path, quiet(a))?;
    let library = a.tools.as_deref().map(Library::open).transpose()?;
    let machine = a.machine.machine.as_deref().map(|m| load_machine(Some(m)));
    let given = Given {
        program: parsed.program,
        part: a.part.read()?,
        stock: a.stock.as_deref(),
        stl_units: a.part.units.stl_units.map(Into::into),
        limits: crate::limits::get(),
        machine: machine.transpose()?,
        materials: crate::io::read_materials(a.materials.as_deref())?,
        material: a.material.clone(),
        library: library.as_ref(),
        options: options(a),
    };
    Inputs::given(given).map_err(|e| match e {
        GivenError::Option(m) => CliError::input(m),
        GivenError::Tool(e) => {
            CliError::input(format!("{}:{}:1: {}", path.display(), e.line, e.message))
        }
        GivenError::Io(e) => e.into(),
    })
}

/// A job's error after the program's name: a finding exits 3, else 2.
fn job_error(path: &Path, e: millplan_driver::job::JobError) -> CliError {
    let m = e.located(&path.display().to_string());
    if e.refused {
        CliError::findings(m)
    } else {
        CliError::input(m)
    }
}

/// Whether warnings, notes and the bar are left out (`-q`, `--json`).
fn quiet(a: &Args) -> bool {
    a.notes.quiet || a.summary.json
}

fn list_passes(json: bool) {
    let text = || format!("{}\n", passes::table_text());
    crate::cmd::print_summary(json, passes::table, text);
}

/// The passes to run (--passes, else all), once the options refused
/// before any work are checked.
fn checked_order(a: &Args) -> CliResult<Vec<passes::PassName>> {
    a.robot.check()?;
    match &a.passes {
        Some(s) => passes::parse_list(s).map_err(|e| CliError::input(format!("--passes: {e}"))),
        None => Ok(ORDER.to_vec()),
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let (Some(path), Some(output), false) = (a.path.clone(), a.output.clone(), a.list_passes)
    else {
        list_passes(a.summary.json);
        return Ok(EXIT_OK);
    };
    let mut clock = Clock::start();
    let order = checked_order(&a)?;
    let blank = a.stock.as_deref().and_then(StockSpec::file_of);
    let (stl, machine) = (a.part.stl.as_deref(), a.machine.machine.as_deref());
    let (materials, tools) = (a.materials.as_deref(), a.tools.as_deref());
    let inputs = [
        Some(&*path),
        stl,
        machine,
        materials,
        blank.as_deref(),
        tools,
    ];
    let inputs: Vec<&Path> = inputs.into_iter().flatten().collect();
    let outs = [("-o", Some(&*output)), ("--report", a.report.as_deref())];
    let mut outputs = Outputs::plan(&inputs, &outs, false)?;
    clock.lap("arguments and outputs checked");
    let given = read_inputs(&a, &path)?;
    let (to, robot) = (a.to.map(Into::into), a.robot.robot.is_some());
    let wo =
        (given.write_options(to, &output, crate::limits::get(), robot)).map_err(CliError::input)?;
    clock.lap("program, part, machine, materials and tools read");
    let named = a.passes.is_some().then_some(&order[..]);
    let job =
        Job::for_passes(given, named, &mut |n| clock.lap(n)).map_err(|e| job_error(&path, e))?;
    let (outcome, mut w) = passes_and_checks(&a, &job, &order, wo, &path, &mut clock)?;
    let (force, quiet) = (a.force.force, quiet(&a));
    let files = (&inputs[..], &*output);
    crate::cmd::robot::after_optimise(&a.robot, (&job, &outcome), &mut w, files, (force, quiet))?;
    clock.lap("robot placement and compensation (--robot)");
    print_diagnostics(&path, &w.warnings, quiet);
    let refused = w.summary.verdict == Verdict::Refused;
    if !refused || force {
        outputs.write(&output, &w.bytes)?;
    }
    if let Some(r) = &a.report {
        outputs.write(r, page(&a, &job, &outcome, &w, &path, &output).as_bytes())?;
    }
    outputs.commit()?;
    clock.lap("outputs written and renamed into place");
    print_summary(&a, &w, &path, &output, refused && !force);
    clock.end(a.timings.on);
    Ok(crate::error::exit(refused))
}

/// The passes, then the written program's checks, under one bar on a
/// terminal (none with -q or --json).
fn passes_and_checks(
    a: &Args,
    job: &Job,
    order: &[passes::PassName],
    wo: millplan_nc::write::WriteOptions,
    path: &Path,
    clock: &mut Clock,
) -> CliResult<(Outcome, Written)> {
    let bar = crate::progress::Phases::new(!quiet(a));
    let h = |phase: &str, done: usize, total: usize| bar.report(phase, done, total);
    let mut lap = |n: &str, part: Option<f64>| match part {
        Some(t) => clock.part(n, t),
        None => clock.lap(n),
    };
    let ran = job.run_and_finish(order, Some(&h), wo, &mut lap);
    bar.finish();
    say_skipped(a, report::notes_of(&ran));
    ran.map_err(|e| job_error(path, e))
}

/// The skipped passes' notes before an error that stopped the checks.
fn say_skipped(a: &Args, notes: Vec<String>) {
    for n in notes.into_iter().filter(|_| !quiet(a)) {
        eprintln!("{n}");
    }
}

fn page(a: &Args, job: &Job, o: &Outcome, w: &Written, path: &Path, output: &Path) -> String {
    let names = InputNames::of(
        (path, output),
        a.part.stl.as_deref(),
        (a.stock.as_deref(), a.material.as_deref()),
        (a.machine.machine.as_deref(), &job.inputs.machine.name),
    );
    let plotted = Plotted {
        before: &job.inputs.program,
        after: &w.program,
        forces_before: o.forces_before.as_ref(),
        forces_after: w.forces_after.as_ref(),
        machine: &job.inputs.machine,
    };
    report::html(&w.summary, &names, &plotted)
}

fn print_summary(a: &Args, w: &Written, path: &Path, output: &Path, withheld: bool) {
    let s = &w.summary;
    if let Some(line) = report::refusal_line(s, path) {
        eprintln!("{line}");
    }
    let text = || format!("{}\n", report::summary_text(s, output, withheld));
    crate::cmd::print_summary(a.summary.json, || s, text);
}
