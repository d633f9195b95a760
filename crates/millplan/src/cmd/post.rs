//! `millplan post`: a five-axis CL file posted through a machine's kinematics.

use crate::cmd::{arg, print_diagnostics, print_json, read_options, Range, TargetArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, Outputs};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back;
use millplan_nc::write::Target;
use millplan_plan::machine::Machine;
use millplan_plan::post::{for_target, post, PostError, PostOptions, PostReport, Posted};
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Post a five-axis CL file (tool-axis vectors) for a machine: rotary angles
/// through its kinematics, chosen over the whole path.
///
/// Per CL point both IK branches and every winding the rotary travel allows
/// are candidates; dynamic programming picks the path of least rotary travel
/// that never changes branch inside a cut (a change across a rapid gets a
/// retract, rotation and approach at the clearance, and is reported). Near
/// the pole the turning axis is held and the orientation deviation reported.
/// Without --tcp the program is in machine coordinates (joint X Y Z and the
/// rotary angles, for a control without TCP) and CL points are inserted
/// wherever the rotaries' motion would take the tip further than --tol from
/// the CL segment. Feeds: G94 converted to what the control applies to the
/// joints' motion, or with --g93 inverse time. A block that would move an
/// axis faster than the machine file's top speed is slowed. An orientation
/// or position out of an axis's travel stops the run (exit 3, nothing
/// written), naming the CL line and the axis. The output is read back and
/// checked before it is written: the IR verifier, S and F within the
/// machine, and every posted tip through the forward kinematics (as written
/// under --tcp) on the CL path within --tol; a check that fails names the
/// CL line and exits 3 with nothing written, unless --force.
#[derive(clap::Args)]
pub struct Args {
    /// Input CL file (APT/CLSF with tool axes) or G-code with tool vectors.
    pub input: PathBuf,
    /// Machine file with `[kinematics]` (examples/machine.toml); its axes'
    /// travel and top speeds and its control's G93 semantics are used.
    #[arg(long)]
    pub machine: PathBuf,
    /// Output dialect; default: the machine's control, else the output's extension.
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Write tool tips under the control's TCP mode (Sinumerik TRAORI,
    /// Heidenhain M128, Fanuc G43.4; LinuxCNC: the machine must run TCP
    /// kinematics) instead of machine coordinates.
    #[arg(long)]
    pub tcp: bool,
    /// Inverse-time feed (G93, F on every feed block) instead of G94.
    #[arg(long)]
    pub g93: bool,
    /// Tolerance, mm: how far the tool tip may leave the CL segment while
    /// the rotaries move, and the chord tolerance of arcs.
    #[arg(long, default_value_t = millplan_driver::command_defaults::post::TOL)]
    pub tol: f64,
    /// Half-angle of the cone about the pole (the tool along the turning
    /// axis) inside which the turning axis is held, degrees (default: the
    /// machine file's `[post] pole_cone`, else 1).
    #[arg(long)]
    pub pole_cone: Option<f64>,
    /// Orientation deviation beyond which a pole block is flagged, degrees
    /// (default: the machine file's `[post] pole_tol`, else 1).
    #[arg(long)]
    pub pole_tol: Option<f64>,
    /// Retract distance along the tool axis of a branch change, mm
    /// (default: the machine file's `[post] clearance`, else 50).
    #[arg(long)]
    pub clearance: Option<f64>,
    /// Output file (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Unit of the source when the file does not say.
    #[arg(long, value_enum)]
    pub units: Option<crate::cmd::UnitArg>,
    /// Do not print reader diagnostics or progress.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print a machine-readable summary (JSON) on standard output (not with -o -); errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
    /// Write the program even when a check before writing refuses it (a
    /// tip off the CL path, an S or F outside the machine); the run then
    /// ends with exit 3.
    #[arg(long)]
    pub force: bool,
    /// Print the wall time of each phase on standard error (they add up to
    /// the whole run).
    #[arg(long)]
    pub timings: bool,
}

/// The post's options: the command line's, else the machine file's `[post]`.
fn options(a: &Args, m: &Machine) -> CliResult<PostOptions> {
    Ok(PostOptions {
        tol: arg("--tol", a.tol, Range::positive(10.0, "mm"))?,
        tcp: a.tcp,
        g93: a.g93,
        pole_cone: arg(
            "--pole-cone",
            a.pole_cone.unwrap_or(m.post.pole_cone),
            Range::from(0.0, 30.0, "degrees"),
        )?,
        pole_tol: arg(
            "--pole-tol",
            a.pole_tol.unwrap_or(m.post.pole_tol),
            Range::from(0.0, 180.0, "degrees"),
        )?,
        clearance: arg(
            "--clearance",
            a.clearance.unwrap_or(m.post.clearance),
            Range::positive(10_000.0, "mm"),
        )?,
    })
}

/// A post error as the command reports it: a check's finding (exit 3) or
/// the input's fault (exit 2), located in the CL file.
fn post_error(path: &Path, e: PostError) -> CliError {
    let message = format!("{}:{e}", path.display());
    let message = if e.line() == 0 {
        format!("{}: {e}", path.display())
    } else {
        message
    };
    if e.is_check() {
        CliError {
            code: EXIT_FINDINGS,
            message: format!("{message}; nothing written"),
        }
    } else {
        CliError::input(message)
    }
}

/// Reads the written program back: it must command what the posted IR does.
fn check_output(
    posted: &millplan_nc::ir::Program,
    out: &[u8],
    target: Target,
    a: &Args,
) -> CliResult<()> {
    let tol = Tolerance {
        position: a.tol.max(Tolerance::default().position),
        ..Tolerance::default()
    };
    let back = read_back(out, target, posted, &tol).map_err(|e| {
        CliError::internal(format!(
            "{}: the posted program does not read back ({e}); not written",
            a.output.display()
        ))
    })?;
    back.equiv.map_err(|m| {
        CliError::internal(format!(
            "{}:{}: the posted program would not command what the post made ({m}); not written",
            a.input.display(),
            m.line_a
        ))
    })?;
    Ok(())
}

/// The posted program against the CL file: the IR verifier, S and F within
/// the machine, and every posted tip (through the machine's forward
/// kinematics, or as written under TCP) on the CL path within --tol.
fn check_posted(
    cl: &millplan_nc::Program,
    posted: &millplan_nc::Program,
    machine: &Machine,
    tol: f64,
) -> Vec<Check> {
    let Some(kin) = machine.kinematics() else {
        return Vec::new();
    };
    safety::check(&Inputs {
        input: cl,
        output: posted,
        part: None,
        stock: None,
        tool_body: &|_| None,
        machine: Some(machine),
        tip: TipRule::MovedBy(kin),
        tol: Tolerances {
            tip: tol,
            ..Tolerances::default()
        },
        loads: None,
    })
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = crate::timings::Clock::start();
    let code = run_timed(&a, &mut clock)?;
    clock.lap("summary printed");
    clock.print(a.timings);
    Ok(code)
}

/// The machine must have kinematics; the output is G-code of `--to`, else
/// the machine file's control, else the output's file name.
fn post_target(a: &Args, machine: &Machine) -> CliResult<millplan_nc::write::Target> {
    if machine.kinematics().is_none() {
        return Err(CliError::input(format!(
            "{}: no [kinematics] table: a five-axis post needs the machine's rotary axes",
            a.machine.display()
        )));
    }
    let target = match a.to.map(Into::into).or(machine.target()) {
        Some(t) => t,
        None => crate::cmd::target_for(None, &a.output, millplan_nc::Dialect::Generated)?,
    };
    if !target.is_gcode() {
        return Err(CliError::input("--to apt: a posted program is G-code"));
    }
    Ok(target)
}

fn run_timed(a: &Args, clock: &mut crate::timings::Clock) -> CliResult<i32> {
    if a.json && a.output.as_os_str() == "-" {
        return Err(CliError::input(
            "--json: not with -o - (the program itself goes to standard output)",
        ));
    }
    let inputs = [a.input.as_path(), a.machine.as_path()];
    let mut outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], true)?;
    let machine = crate::cmd::load_machine(Some(&a.machine))?;
    let o = options(a, &machine)?;
    let target = post_target(a, &machine)?;
    clock.lap("arguments, machine file and outputs checked");
    let parsed = read_program(&a.input, read_options(a.units, None)?)?;
    print_diagnostics(&a.input, &parsed.diagnostics, a.quiet || a.json);
    clock.lap("read CL file");
    let bar = crate::progress::spinner("posting", !a.quiet && !a.json);
    let posted = post(&parsed.program, &machine, &o).map_err(|e| post_error(&a.input, e))?;
    // The posted blocks (timed inside the post) are not needed any more:
    // their memory goes before the written program and its read-back take
    // theirs. The CL program stays for the tip check.
    let Posted {
        mut program,
        report,
        ..
    } = posted;
    clock.lap("post (IK, DP over the path, linearisation, feeds, time estimates)");
    for_target(&mut program, target).map_err(|e| post_error(&a.input, e))?;
    bar.finish_and_clear();
    let mut wo = machine.write_options(target);
    // The post states TCP itself, per operation, when asked for it.
    wo.auto_tcp = false;
    let out = crate::cmd::write_program(&program, wo, &a.input, a.quiet)?;
    clock.lap("G-code written (in memory)");
    check_output(&program, &out, target, a)?;
    clock.lap("written program read back and compared");
    let checks = check_posted(&parsed.program, &program, &machine, o.tol);
    drop(parsed);
    let checked = crate::verdict::enforce(&checks, &a.input, a.force)?;
    clock.lap("checks (IR, machine, tips through the kinematics)");
    outputs.write(&a.output, &out)?;
    outputs.commit()?;
    clock.lap("program staged, synced and renamed into place");
    print_outcome(
        a,
        summary(a, &o, &machine, target.name(), &report),
        &checks,
        &report,
    );
    Ok(if checked { EXIT_OK } else { EXIT_FINDINGS })
}

/// The summary with its checks, as JSON or text.
fn print_outcome(
    a: &Args,
    mut j: Value,
    checks: &[millplan_plan::safety::Check],
    report: &PostReport,
) {
    j["checks"] = serde_json::to_value(checks).unwrap_or_default();
    if a.json {
        print_json(j);
    } else {
        print_text(a, &j, report);
    }
}

fn summary(a: &Args, o: &PostOptions, machine: &Machine, target: &str, r: &PostReport) -> Value {
    json!({
        "input": a.input.display().to_string(),
        "output": a.output.display().to_string(),
        "machine": machine.name,
        "target": target,
        "mode": if a.tcp { "tcp" } else { "machine" },
        "feed_mode": if a.g93 { "g93" } else { "g94" },
        "tol_mm": a.tol,
        "pole_cone_deg": o.pole_cone,
        "blocks": r.blocks,
        "flips": r.flips.len(),
        "flip_list": r.flips,
        "pole_blocks": r.pole_blocks,
        "pole_flagged": r.pole_flagged,
        "max_orientation_deviation_deg": r.max_orientation_deviation_deg,
        "inserted_points": r.inserted_points,
        "arc_points": r.arc_points,
        "flip_moves": r.flip_moves,
        "slowed_blocks": r.slowed_blocks,
        "null_moves": r.null_moves,
        "g93_blocks": r.g93_blocks,
        "max_tip_error_mm": r.max_tip_error_mm,
        "time_s": r.time_s,
        "nominal_s": r.nominal_s,
        "time_g93_s": r.time_g93_s,
        "time_g94_s": r.time_g94_s,
        "nominal_g93_s": r.nominal_g93_s,
        "nominal_g94_s": r.nominal_g94_s,
        "rotary": r.rotary,
    })
}

fn print_text(a: &Args, j: &Value, r: &PostReport) {
    eprintln!(
        "wrote {} ({} blocks, {}, {}, {})",
        a.output.display(),
        r.blocks,
        j["target"].as_str().unwrap_or(""),
        j["mode"].as_str().unwrap_or(""),
        j["feed_mode"].as_str().unwrap_or("")
    );
    let lim = |v: Option<f64>| v.map_or("unlimited".to_string(), |v| format!("{v:.1}"));
    let rows: Vec<String> = r
        .rotary
        .iter()
        .map(|ax| match (ax.min, ax.max) {
            (Some(lo), Some(hi)) => format!(
                "  {}  used {lo:.3} .. {hi:.3} deg   travel {} .. {}",
                ax.axis,
                lim(ax.limit_min),
                lim(ax.limit_max)
            ),
            _ => format!("  {}  not moved", ax.axis),
        })
        .collect();
    outln!("rotary axes:\n{}", rows.join("\n"));
    outln!(
        "branch flips {} (across rapids), pole blocks {} ({} beyond --pole-tol), max orientation deviation {:.4} deg",
        r.flips.len(),
        r.pole_blocks,
        r.pole_flagged.len(),
        r.max_orientation_deviation_deg
    );
    outln!(
        "points inserted {} (linearisation), {} from arcs; blocks slowed {}",
        r.inserted_points,
        r.arc_points,
        r.slowed_blocks
    );
    outln!(
        "time {:.1} s estimated ({:.1} s nominal); at the CL tip feed (G93) {:.1} s, a plain G94 post {:.1} s",
        r.time_s,
        r.nominal_s,
        r.time_g93_s,
        r.time_g94_s
    );
}
