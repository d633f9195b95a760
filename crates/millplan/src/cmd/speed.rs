//! `millplan speed`: constant-cutting-speed spindle control for ball-end finishing.

use crate::error::{exit, CliResult};
use clap::ValueEnum;
use millplan_driver::speed::{self as lib, Convention, Cutting, NormalMode, SpeedRequest};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ConventionArg {
    Auto,
    Tip,
    Centre,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum NormalArg {
    Smooth,
    Facet,
    Ball,
}

/// Set the spindle speed per block so the cutting speed stays constant
/// from the working diameter of the ball at each point (docs/usage.md).
///
/// For every cutting point of every ball-end operation millplan finds where the
/// ball touches the part (STL), the surface inclination, the feed direction and
/// which side is already machined, computes the working diameter D_w and sets
/// n = 1000·vc/(π·D_w), within the machine's spindle range and acceleration.
/// By default the feed follows, F = n·z·fz, so the chip load stays constant.
/// Only speeds and feeds change, never positions.
///
/// Exit code 3 (the program is still written) when more than 5 % of the
/// cutting points do not touch the part: the part does not match the program,
/// or the CL points are not what --convention says, and the speeds mean nothing.
///
/// Before it is written the program is checked: the IR verifier, every S
/// within the machine's spindle range, every cutting F above 0 and at most
/// the machine's maximum, every position the input's. A check that fails
/// names its line and exits 3 with nothing written, unless --force.
#[derive(clap::Args)]
pub struct Args {
    /// Toolpath: APT/CL or G-code with a ball-end tool.
    pub path: PathBuf,
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    /// Cutting speed, m/min.
    #[arg(long)]
    pub vc: f64,
    /// Feed per tooth, mm.
    #[arg(long)]
    pub fz: f64,
    /// Number of flutes.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cutting::FLUTES)]
    pub flutes: u32,
    /// Stock thickness along the surface normal (finishing allowance), mm.
    #[arg(long)]
    pub ap: f64,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    #[command(flatten)]
    pub out: crate::cmd::args::ProgramOutput,
    /// Ball diameter (mm) for operations whose tool has no geometry, as in
    /// G-code programs that call tools by number only.
    #[arg(long)]
    pub ball_d: Option<f64>,
    /// Keep the programmed feed instead of F = n·z·fz.
    #[arg(long)]
    pub keep_feed: bool,
    /// Write a new S only when the speed changes by more than this, 1/min.
    #[arg(long, default_value_t = millplan_driver::command_defaults::speed::S_THRESHOLD)]
    pub s_threshold: f64,
    /// Which tool point the CL points are.
    #[arg(long, value_enum, default_value = "auto")]
    pub convention: ConventionArg,
    /// Normals at the contact point.
    #[arg(long, value_enum, default_value = "smooth")]
    pub normals: NormalArg,
    /// Use the paper's nearest-in-centre facet mapping (comparison only).
    #[arg(long)]
    pub nearest_incentre: bool,
    /// Per-point table (CSV).
    #[arg(long)]
    pub table: Option<PathBuf>,
    /// Report (self-contained HTML with SVG plots).
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
}

fn request(a: &Args) -> SpeedRequest {
    SpeedRequest {
        cut: Cutting {
            vc: a.vc,
            fz: a.fz,
            flutes: a.flutes,
            ap: a.ap,
        },
        ball_d: a.ball_d,
        s_threshold: a.s_threshold,
        keep_feed: a.keep_feed,
        convention: match a.convention {
            ConventionArg::Auto => None,
            ConventionArg::Tip => Some(Convention::Tip),
            ConventionArg::Centre => Some(Convention::Centre),
        },
        normals: match a.normals {
            NormalArg::Smooth => NormalMode::Smooth,
            NormalArg::Facet => NormalMode::Facet,
            NormalArg::Ball => NormalMode::Ball,
        },
        nearest_incentre: a.nearest_incentre,
        keep_rows: a.table.is_some() || a.report.is_some(),
    }
}

/// `millplan speed`: the request built from the arguments, the run
/// (`speed::run_command`: the part read beside the program), the summary.
pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.path, a.notes.quiet, a.summary.json);
    let watch = watch.bars_under_json();
    let c = lib::SpeedCommand {
        input: &a.path,
        part: a.part.file(),
        machine: a.machine.machine.as_deref(),
        output: &a.out.output,
        to: a.out.to.map(Into::into),
        table: a.table.as_deref(),
        report: a.report.as_deref(),
        request: request(&a),
        read: a.units.options()?,
        force: a.force.force,
        started: std::time::Instant::now(),
    };
    let r = lib::run_command(&c, &watch)?;
    a.summary.print(&r.report(&c), |r| r.render_text());
    if a.timings.on {
        crate::timings::print(&r.timings, c.started);
    }
    Ok(exit(r.findings()))
}
