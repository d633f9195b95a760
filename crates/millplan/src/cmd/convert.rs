//! `millplan convert`: read a program in any supported format, write it in another.

use crate::cmd::{read_options, TargetArg, UnitArg};
use crate::error::CliResult;
use crate::io::Outputs;
use millplan_driver::convert::{self as lib, ConvertRequest};
use millplan_driver::watch::Watch as _;
use millplan_nc::write::krl::KrlMotion;
use millplan_nc::LengthUnit;
use std::path::PathBuf;

/// Convert an NC program (APT/CL, G-code or KUKA KRL) to another dialect.
///
/// Every block of the output means what its source block meant: moves, arcs,
/// feeds and feed modes (G93/G94/G95), spindle, coolant, tool-length and
/// cutter compensation, work offsets and comments are carried over; an axis
/// the source never set is never written; words the source dialect keeps
/// verbatim are copied into the same dialect, and a word another dialect
/// cannot express stops the conversion at its line (--lossy: a comment and a
/// warning instead, exit 3 when the output commands less than the source). Arcs outside the XY/ZX/YZ planes are written as lines; a G-code
/// canned cycle stays a cycle where the target has it and in APT (G81 as CYCLE/DRILL ...); other holes are written as lines. A KRL program (.src) is read with the
/// sub-programs its main calls from beside it (a missing one named with its
/// calling line); KRL to KRL keeps the poses, external axes and speeds as
/// read, in one file; into another dialect the orientation A, B, C becomes
/// a tool axis and an external axis (E1..E6) stops the conversion at its
/// line (--lossy: dropped with a warning). The output is written to a temporary file and
/// renamed, so a failed run leaves nothing behind.
#[derive(clap::Args)]
pub struct Args {
    /// Input program.
    pub input: PathBuf,
    /// Output file (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Target dialect; default: from the output's extension (.nc Fanuc, .mpf
    /// Sinumerik, .h Heidenhain, .ngc LinuxCNC, .apt/.cls APT, .src KRL),
    /// else the input's own.
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    /// Unit of the output program (default: the unit of the source, so that
    /// words copied as written keep their meaning).
    #[arg(long, value_enum)]
    pub out_units: Option<UnitArg>,
    /// Feed (mm/min) for cutting moves programmed before any feed.
    #[arg(long)]
    pub feed: Option<f64>,
    /// Write block numbers (always on for Heidenhain).
    #[arg(long)]
    pub line_numbers: bool,
    /// Write words the target cannot express as comments (a warning each)
    /// instead of refusing the conversion; exit 3 when the output then
    /// commands less than the source.
    #[arg(long)]
    pub lossy: bool,
    /// Machine file (examples/machine.toml): its control's dialect is the
    /// default target and its S-word decimals are used; with a `[kinematics]`
    /// table, rotary angles become tool axes (so five-axis G-code can be
    /// written as APT).
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// With a KRL output: at most this many motions a file. A longer
    /// program becomes a main program (at -o) calling sub-programs of N
    /// motions each, written beside it as NAME_001.src, NAME_002.src, …
    /// (NAME from the output's file name), as a controller loads them. 0:
    /// one file, as without the option.
    #[arg(long, value_name = "N")]
    pub max_points: Option<usize>,
    /// With a KRL output: each point one LIN as read or written (the
    /// default), or each run of approximated LINs one SPLINE block of SPL
    /// points. Refused with any other output, which has no such motions.
    #[arg(long, value_name = "lin|spline")]
    pub krl_motion: Option<KrlMotion>,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    /// Print a machine-readable summary (JSON) on standard output (not with -o -); errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

fn request(a: &Args) -> ConvertRequest {
    ConvertRequest {
        to: a.to.map(Into::into),
        unit: a.out_units.map(LengthUnit::from),
        line_numbers: a.line_numbers,
        lossy: a.lossy,
        max_points: a.max_points,
        motion: a.krl_motion,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    // The reader's findings are said under --json too (the summary lists them).
    let watch = crate::progress::Watch::new(&a.input, a.notes.quiet, false);
    crate::cmd::json_not_on_stdout(a.json, &a.output)?;
    let inputs: Vec<&std::path::Path> = [Some(&*a.input), a.machine.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    let outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], true)?;
    let c = lib::ConvertCommand {
        input: &a.input,
        machine: a.machine.as_deref(),
        output: &a.output,
        convert: request(&a),
        read: read_options(a.units.units, a.feed)?,
    };
    let r = lib::command(&c, &inputs, outputs, &watch)?;
    if a.json {
        outln!("{}", serde_json::to_string(&r.summary).unwrap_or_default());
    } else {
        eprintln!("{}", r.summary.text());
    }
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(crate::error::exit(!r.equivalent))
}
