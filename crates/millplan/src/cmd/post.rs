//! `millplan post`: a five-axis CL file posted through a machine's kinematics.

use crate::cmd::{print_json, TargetArg};
use crate::error::CliResult;
use crate::io::Outputs;
use millplan_driver::post::{self as lib, PostRequest};
use millplan_driver::watch::Watch as _;
use std::path::PathBuf;

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
/// axis faster than the machine file's top speed, take less than its
/// control's block cycle (`block_time`) or, in G94, ask the joints for more
/// than the machine's top feed, is slowed. An orientation
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
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    /// Print a machine-readable summary (JSON) on standard output (not with -o -); errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.input, a.notes.quiet, a.json);
    crate::cmd::json_not_on_stdout(a.json, &a.output)?;
    let inputs = [a.input.as_path(), a.machine.as_path()];
    let outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], true)?;
    let c = lib::PostCommand {
        input: &a.input,
        machine: &a.machine,
        output: &a.output,
        to: a.to.map(Into::into),
        post: PostRequest {
            tol: a.tol,
            tcp: a.tcp,
            g93: a.g93,
            pole_cone: a.pole_cone,
            pole_tol: a.pole_tol,
            clearance: a.clearance,
        },
        read: a.units.options()?,
        force: a.force.force,
    };
    let r = lib::command(&c, outputs, &watch)?;
    let s = r.summary(&c);
    if a.json {
        print_json(serde_json::to_value(&s).unwrap_or_default());
    } else if a.output.as_os_str() == "-" {
        eprintln!("{}\n{}", s.wrote(), s.render_text());
    } else {
        eprintln!("{}", s.wrote());
        out!("{}", s.render_text());
    }
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(crate::error::exit(!r.checked))
}
